"""The closed-form reduction of standard-layout Measured files against the general (numerical) route.

``bikerider.bicycle.closed_form_reduction`` evaluates a generated function with exact derivatives;
the general route evaluates the NumPy chain of ``raw_measurements`` at the ``2 k + 1`` points of a
central-difference Jacobian.  Both implement the same chain independently (one derived in SymPy,
one written by hand), so agreement on the shipped files and on perturbed copies of them checks
both.  Values agree to rounding; uncertainties to the central differences' truncation error
(relative step 1e-6, so about 1e-8 of a sigma; held to 1e-6).
"""
from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bikerider.bicycle import raw_measurements as rm
from bikerider.bicycle.closed_form_reduction import is_standard_layout, reduce_standard_layout
from bikerider.bicycle.hanging_lines import DEFAULT_LINE_TOLERANCE
from bikerider.bicycle.propagation import propagate
from bikerider.errors import FitError, InputError
from bikerider.generated import measured_reduction as gen
from bikerider.io.name_value_file import read_name_value_file
from bikerider.quantity import Quantity

DATA = Path(str(resources.files("bikerider") / "data" / "bicycleparameters" / "bicycles"))
STANDARD = ("Browser", "Browserins", "Fisher", "Yellow")
"""The shipped files in the template's layout (Fisher without seating measurements)."""


def _values(name: str) -> dict[str, Quantity]:
    return read_name_value_file(DATA / name / "RawData" / f"{name}Measured.txt").as_dict()


def _general(values: dict[str, Quantity]) -> dict[str, Quantity]:
    """The general route: the batched numerical Jacobian of ``evaluate_measured``, finite outputs."""
    layout = rm.detect_layout(values)
    used = {k: q for k, q in values.items() if k not in rm._KNOWN_EXTRAS}
    result = propagate(lambda x: rm.evaluate_measured(x, layout, check=True), used, vectorized=True)
    return {k: q for k, q in result.items() if math.isfinite(q.value)}


def _assert_same(closed: dict[str, Quantity], general: dict[str, Quantity]) -> None:
    assert list(closed) == list(general)
    for key, q in closed.items():
        assert q.value == pytest.approx(general[key].value, rel=1e-12, abs=1e-15), key
        assert q.sigma == pytest.approx(general[key].sigma, rel=1e-6, abs=1e-15), key


@pytest.mark.parametrize("name", STANDARD)
def test_shipped_standard_files_agree_with_the_general_route(name):
    values = _values(name)
    layout = rm.detect_layout(values)
    assert is_standard_layout(layout)
    closed, lines = reduce_standard_layout(values, layout, DEFAULT_LINE_TOLERANCE)
    _assert_same(closed, _general(values))
    assert ("l_s" in closed) == layout.seating
    general_lines: dict = {}
    rm.evaluate_measured({k: q.value for k, q in values.items()}, layout, lines=general_lines)
    for body, fit in lines.items():
        np.testing.assert_allclose(fit.point, general_lines[body].point, rtol=1e-12)
        np.testing.assert_allclose(fit.distances, general_lines[body].distances, rtol=1e-9, atol=1e-15)
        assert fit.rms == pytest.approx(general_lines[body].rms, rel=1e-9)


@pytest.mark.parametrize("seed", range(6))
def test_perturbed_files_agree_with_the_general_route(seed):
    """Every value moved by up to two of its sigmas (or 1 %), and every sigma scaled: a different
    point of the chain and different weights in every uncertainty."""
    rng = np.random.default_rng(seed)
    values = {}
    for key, q in _values("Browser").items():
        spread = 2 * q.sigma if q.sigma > 0 else 0.01 * abs(q.value)
        sigma = q.sigma * rng.uniform(0.2, 5) if q.sigma > 0 else (0.0 if key in ("nF", "nR") else 0.001 * abs(q.value))
        values[key] = Quantity(q.value + spread * rng.uniform(-1, 1) if key not in ("nF", "nR") else q.value, sigma)
    layout = rm.detect_layout(values)
    closed = reduce_standard_layout(values, layout, DEFAULT_LINE_TOLERANCE)
    assert closed is not None
    _assert_same(closed[0], _general(values))


def test_reduce_measured_takes_the_closed_form_for_the_template_layout(monkeypatch):
    data = read_name_value_file(DATA / "Browser" / "RawData" / "BrowserMeasured.txt")
    calls = []
    monkeypatch.setattr(rm, "propagate", lambda *a, **k: calls.append(a) or propagate(*a, **k))
    rm.reduce_measured(data, source=data)
    assert calls == []  # no numerical Jacobian
    rm.reduce_measured(data, source=data, com_method="pairwise_mean")
    assert len(calls) == 1  # BicycleParameters' centre-of-mass method: the general route


def test_other_layouts_take_the_general_route():
    values = _values("Rigid")  # heights geometry, fork and handlebar apart, five orientations
    layout = rm.detect_layout(values)
    assert not is_standard_layout(layout)
    assert reduce_standard_layout(values, layout, DEFAULT_LINE_TOLERANCE) is None


REJECTED = {
    # a hanging distance 0.1 m off: the rear frame's lines miss their common point
    "lines that do not meet": (lambda v: {"aB1": Quantity(v["aB1"].value + 0.1, 0.003)}, FitError, "rear frame"),
    # orientation 2 the same axis and line as orientation 1, seen from the other side
    "coincident orientations": (lambda v: {"alphaH2": Quantity(v["alphaH1"].value - 180.0, 0.2),
                                           "aH2": Quantity(-v["aH1"].value, 0.003)}, InputError, "Eq. 6 is singular"),
}


@pytest.mark.parametrize("case", sorted(REJECTED))
def test_a_rejected_file_gets_the_general_routes_error(case):
    changes, error, message = REJECTED[case]
    values = _values("Browser")
    values.update(changes(values))
    layout = rm.detect_layout(values)
    assert reduce_standard_layout(values, layout, DEFAULT_LINE_TOLERANCE) is None
    with pytest.raises(error, match=message):
        rm.reduce_measured(values, source="Browser")


def test_grips_out_of_reach_leave_the_seating_to_the_general_route():
    values = _values("Browser")
    values["LhbF"] = Quantity(0.2, 0.0)  # shorter than half the handlebar width
    layout = rm.detect_layout(values)
    assert reduce_standard_layout(values, layout, DEFAULT_LINE_TOLERANCE) is None
    reduction = rm.reduce_measured(values, source="Browser")
    assert any("seating measurements not usable" in note for note in reduction.notes)
    assert "l_s" not in reduction.bodies.values


def test_generated_function_broadcasts_over_batches():
    """The NumPy twin of the scalar function, over two batch shapes, equals it point by point."""
    values = _values("Browser")
    layout = rm.detect_layout(values)
    assert layout.seating
    names = {"mBf": "mB", "lam_ht": "gamma", "l_cs": "lcs", "h_bb": "hbb", "l_sp": "lsp", "l_st": "lst",
             "lam_st": "lamst"}
    args, sigmas = [], []
    for name in gen.ARGS:
        q = values[names.get(name, name)]
        scale = math.pi / 180 if name == "lam_ht" or name.startswith("alpha") else 1.0
        args.append(q.value * scale)
        sigmas.append(q.sigma * scale)
    rng = np.random.default_rng(3)
    for shape in ((4,), (2, 3)):
        batch = [a * (1 + 1e-3 * rng.uniform(-1, 1, shape)) for a in args]
        arrays = gen.standard_layout(*batch, *sigmas)
        for out in arrays:
            assert out.shape[:-1] == shape
        for index in np.ndindex(*shape):
            scalar = gen.standard_layout_scalar(*(float(b[index]) for b in batch), *sigmas)
            for array, expected in zip(arrays, scalar):
                np.testing.assert_allclose(array[index], expected, rtol=1e-12, atol=1e-15)


_HANGING = [f"{kind}{body}{i}" for body in "BH" for kind in ("alpha", "a", "Tt") for i in (1, 2, 3)]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    moves=st.dictionaries(st.sampled_from(_HANGING + ["gamma", "TcB1", "TcH1", "TcR1", "LhbF", "whb", "TtP1"]),
                          st.floats(-0.5, 0.5), min_size=1, max_size=4),
)
def test_the_closed_form_decides_only_what_the_general_route_accepts(moves):
    """Hanging angles, distances and periods moved far (up to 50 %, angles up to 90 degrees): where the
    general route raises, the closed form declines; where the closed form answers, the general route
    agrees with it."""
    values = _values("Browser")
    for name, move in moves.items():
        q = values[name]
        shifted = q.value + 180 * move if name.startswith("alpha") or name == "gamma" else q.value * (1 + move)
        values[name] = Quantity(shifted, q.sigma)
    layout = rm.detect_layout(values)
    closed = reduce_standard_layout(values, layout, DEFAULT_LINE_TOLERANCE)
    try:
        general = _general(values)
    except (InputError, FitError):
        assert closed is None
        return
    if closed is not None:
        _assert_same(closed[0], general)
