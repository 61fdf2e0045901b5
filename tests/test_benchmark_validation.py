"""Validation of the benchmark parameters: the closed-form tensor screen and the messages it must not change.

``BenchmarkParameters.validate`` first tries to show in plain floats that a rear body's or
handlebar's inertia tensor passes ``check_inertia_tensor``; only when it cannot does the full check
run (and raise with its own message).  The screen must never accept a tensor the full check refuses.
"""
from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from bikerider.benchmark.parameters import BENCHMARK_NAMES, BenchmarkParameters
from bikerider.errors import InputError
from bikerider.inertia import check_inertia_tensor, clearly_valid_plane_symmetric
from bikerider.io.bicycleparameters import read_benchmark_file
from bikerider.quantity import Quantity

DATA = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
BENCHMARK = DATA / "bicycles" / "Benchmark" / "Parameters" / "BenchmarkBenchmark.txt"


def _full_check_passes(xx: float, yy: float | None, zz: float, xz: float) -> bool:
    tensor = np.array([[xx, 0.0, xz], [0.0, math.nan if yy is None else yy, 0.0], [xz, 0.0, zz]])
    try:
        check_inertia_tensor("I", tensor)
    except InputError:
        return False
    return True


def test_the_screen_never_accepts_a_tensor_the_full_check_refuses():
    rng = np.random.default_rng(11)
    accepted = refused_by_both = 0
    for _ in range(4000):
        scale = 10.0 ** rng.choice([rng.uniform(-3, 3), -170.0, 150.0])
        xx, zz = rng.uniform(0.05, 2.0, 2) * scale
        # the xz block at, near and beyond positive definiteness
        xz = rng.choice([-1, 1]) * math.sqrt(xx * zz) * rng.choice([rng.uniform(0, 1), 1, 1 - 1e-13, 1 + 1e-13])
        # I_yy at, near (within and beyond the full check's slack) and far from the triangle limits
        half, radius = (xx + zz) / 2, math.hypot((xx - zz) / 2, xz)
        limit = rng.choice([2 * radius, 2 * half])  # lower and upper bound of a valid I_yy
        yy = rng.choice([None, limit * (1 + rng.normal(0, 1e-12)), limit * (1 + rng.normal(0, 1e-8)),
                         limit * rng.uniform(0.5, 1.5)])
        verdict = clearly_valid_plane_symmetric(xx, yy, zz, xz)
        passes = _full_check_passes(xx, yy, zz, xz)
        assert passes or not verdict, (xx, yy, zz, xz)
        accepted += verdict
        refused_by_both += not passes
    assert accepted > 1000 and refused_by_both > 500  # both kinds drawn, so the assertion was tested


@pytest.mark.parametrize(
    "xx, yy, zz, xz",
    [
        (math.nan, 1.0, 1.0, 0.0), (1.0, 1.0, 1.0, math.nan), (math.inf, 1.0, 1.0, 0.0),
        (1.0, math.inf, 1.0, 0.0), (1.0, math.nan, 1.0, 0.0), (0.0, 1.0, 1.0, 0.0), (-1.0, None, 1.0, 0.0),
        (0.0, 0.0, 0.0, 0.0), (1.0, 2.0, 1.0, 0.0),  # the triangle limit itself: the full check decides
        (1.0, None, 1.0, 1.0), (1e-200, 1.0, 1e-200, 0.0),
    ],
)
def test_the_screen_leaves_edge_cases_to_the_full_check(xx, yy, zz, xz):
    assert not clearly_valid_plane_symmetric(xx, yy, zz, xz)


def test_the_screen_accepts_the_benchmark_bicycle():
    v = read_benchmark_file(BENCHMARK).parameters.values
    for body in ("B", "H"):
        assert clearly_valid_plane_symmetric(v[f"I{body}xx"], v[f"I{body}yy"], v[f"I{body}zz"], v[f"I{body}xz"]), body
        assert clearly_valid_plane_symmetric(v[f"I{body}xx"], None, v[f"I{body}zz"], v[f"I{body}xz"]), body


def _mapping(**changes) -> dict:
    params = read_benchmark_file(BENCHMARK).parameters
    mapping = {name: Quantity(params.values[name], params.sigmas[name]) for name in BENCHMARK_NAMES}
    mapping.update(changes)
    return {name: q for name, q in mapping.items() if q is not ...}


@pytest.mark.parametrize(
    "changes, name, fragment",
    [
        ({"zz_top": 1.0, "IBq": 2.0}, "IBq", "one of the benchmark names w, c, lam"),
        ({"w": ...}, "w", "w = missing: expected a value (all 25 benchmark parameters are needed)"),
        ({"c": math.nan}, "c", "c = nan: expected a finite number"),
        ({"mB": Quantity(-1.0, 0.1)}, "mB", "mB = -1: expected a positive value"),
        ({"IBxz": 6.0}, "IB (IBxx, IByy, IBzz, IBxz)", "positive moments with Ixx*Izz > Ixz^2"),
        ({"IHyy": 3.0}, "IH (IHxx, IHyy, IHzz, IHxz)", "each principal moment at most the sum of the other two"),
        ({"IByy": 0.0}, "IB (IBxx, IByy, IBzz, IBxz)", "positive principal moments of inertia"),
    ],
)
def test_from_mapping_errors_name_the_value_and_what_was_expected(changes, name, fragment):
    with pytest.raises(InputError) as info:
        BenchmarkParameters.from_mapping(_mapping(**changes), source="test")
    assert info.value.name == name
    assert fragment in str(info.value)


def test_from_mapping_takes_numbers_and_quantities_and_fills_gravity_and_the_optional_moments():
    mapping = _mapping(g=..., IByy=None, IHyy=..., w=1.02, c=Quantity(0.08, 0.001))
    params = BenchmarkParameters.from_mapping(mapping)
    assert (params.values["g"], params.sigmas["g"]) == (9.81, 0.0)
    assert params.values["IByy"] is None and params.values["IHyy"] is None
    assert (params.values["w"], params.sigmas["w"]) == (1.02, 0.0)
    assert (params.values["c"], params.sigmas["c"]) == (0.08, 0.001)
    assert list(params.values) == list(BENCHMARK_NAMES)
