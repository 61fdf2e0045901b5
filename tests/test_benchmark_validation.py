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
from bikerider.inertia import TENSOR_RULES, broken_rules, check_inertia_tensor, inertia_problem
from bikerider.io.bicycleparameters import read_benchmark_file
from bikerider.quantity import Quantity

DATA = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
BENCHMARK = DATA / "bicycles" / "Benchmark" / "Parameters" / "BenchmarkBenchmark.txt"


def _eigenvalue_verdict(xx: float, yy: float | None, zz: float, xz: float) -> bool | None:
    """An independent judgment (``eigvalsh`` of the tensor over its largest entry): whether it can
    belong to a body, or ``None`` within round-off of a limit (either answer is right there)."""
    entries = np.array([xx, zz, xz, 0.0 if yy is None else yy])
    if not np.all(np.isfinite(entries)):
        return False
    scale = np.abs(entries).max() or 1.0
    block = np.linalg.eigvalsh(np.array([[xx, xz], [xz, zz]]) / scale)
    if abs(block[0]) < 1e-8:
        return None
    if yy is None or block[0] < 0:
        return bool(block[0] > 0)
    p = np.sort([*block, yy / scale])
    margin = (p[0] + p[1] - p[2]) / p.sum()
    return None if abs(margin) < 1e-8 else bool(margin > 0 and p[0] > 0)


def test_the_inertia_check_agrees_with_eigenvalues_at_every_scale():
    rng = np.random.default_rng(11)
    accepted = refused = 0
    for _ in range(4000):
        scale = 10.0 ** rng.choice([rng.uniform(-3, 3), -170.0, 150.0])
        xx, zz = rng.uniform(0.05, 2.0, 2) * scale
        # the xz block at, near and beyond positive definiteness
        xz = rng.choice([-1, 1]) * math.sqrt(xx * zz) * rng.choice([rng.uniform(0, 1), 1, 1 - 1e-13, 1 + 1e-13])
        # I_yy at, near and far from the triangle limits
        half, radius = (xx + zz) / 2, math.hypot((xx - zz) / 2, xz)
        limit = rng.choice([2 * radius, 2 * half])  # lower and upper bound of a valid I_yy
        yy = rng.choice(
            [None, limit * (1 + rng.normal(0, 1e-12)), limit * (1 + rng.normal(0, 1e-8)), limit * rng.uniform(0.5, 1.5)]
        )
        expected = _eigenvalue_verdict(xx, yy, zz, xz)
        if expected is None:
            continue
        assert (inertia_problem(xx, yy, zz, xz) is None) == expected, (xx, yy, zz, xz)
        accepted += expected
        refused += not expected
    assert accepted > 500 and refused > 200  # both kinds drawn, so the assertion was tested


@pytest.mark.parametrize(
    "xx, yy, zz, xz, valid",
    [
        (math.nan, 1.0, 1.0, 0.0, False),
        (1.0, 1.0, 1.0, math.nan, False),
        (math.inf, 1.0, 1.0, 0.0, False),
        (1.0, math.inf, 1.0, 0.0, True),  # an I_yy that is not finite is not determined: the xz block alone
        (1.0, math.nan, 1.0, 0.0, True),
        (0.0, 1.0, 1.0, 0.0, False),
        (-1.0, None, 1.0, 0.0, False),
        (0.0, 0.0, 0.0, 0.0, False),
        (1.0, 2.0, 1.0, 0.0, True),  # the triangle limit itself: within the slack
        (1.0, None, 1.0, 1.0, False),
        (1e-200, 1.0, 1e-200, 0.0, False),
    ],
)
def test_the_inertia_check_at_its_edges(xx, yy, zz, xz, valid):
    assert (inertia_problem(xx, yy, zz, xz) is None) == valid
    tensor = np.array([[xx, 0.0, xz], [0.0, math.nan if yy is None else yy, 0.0], [xz, 0.0, zz]])
    if valid:
        check_inertia_tensor("I", tensor)
    else:
        with pytest.raises(InputError):
            check_inertia_tensor("I", tensor)


def test_the_batched_inertia_check_breaks_the_rules_the_one_check_names():
    # bikerider.inertia.broken_rules (design spaces) against inertia_problem, tensor by tensor:
    # random tensors at every scale, near the limits, and the edge cases above
    rng = np.random.default_rng(12)
    n = 3000
    scale = 10.0 ** rng.choice([-170.0, 0.0, 150.0], n) * 10.0 ** rng.uniform(-3, 3, n)
    xx, zz = rng.uniform(-0.2, 2.0, (2, n)) * scale
    xz = rng.choice([-1, 1], n) * np.sqrt(np.abs(xx * zz)) * rng.choice([0.5, 1 - 1e-6, 1 + 1e-6], n)
    yy = np.where(rng.random(n) < 0.2, np.nan, (np.abs(xx) + np.abs(zz)) * rng.uniform(-0.2, 1.2, n))
    edges = np.array(
        [
            (math.nan, 1.0, 1.0, 0.0),
            (1.0, math.inf, 1.0, 0.0),
            (0.0, 1.0, 1.0, 0.0),
            (1.0, 2.0, 1.0, 0.0),
            (1.0, math.nan, 1.0, 1.0),
            (0.0, 0.0, 0.0, 0.0),
        ]
    )
    xx, yy, zz, xz = (np.concatenate([a, edges[:, k]]) for k, a in enumerate((xx, yy, zz, xz)))
    got = broken_rules(xx, yy, zz, xz)
    for i in range(xx.size):
        problem = inertia_problem(float(xx[i]), float(yy[i]), float(zz[i]), float(xz[i]))
        assert got[i] == (0 if problem is None else TENSOR_RULES.index(problem[1]) + 1), (xx[i], yy[i], zz[i], xz[i])
    assert len(set(got.tolist())) == len(TENSOR_RULES) + 1  # every rule broken somewhere, and none


def test_the_benchmark_bicycle_passes_the_inertia_check():
    v = read_benchmark_file(BENCHMARK).parameters.values
    for body in ("B", "H"):
        assert inertia_problem(v[f"I{body}xx"], v[f"I{body}yy"], v[f"I{body}zz"], v[f"I{body}xz"]) is None, body
        assert inertia_problem(v[f"I{body}xx"], None, v[f"I{body}zz"], v[f"I{body}xz"]) is None, body


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
