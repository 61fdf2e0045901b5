"""The Measured-file reduction (generated stages, exact Jacobians) against an independent oracle.

``bikerider.bicycle.raw_measurements`` runs the generated stages of ``derive/measured_reduction.py``
through the uncertainty engine; ``tests/measured_oracle.py`` is the same chain written by hand with
NumPy, its uncertainties by central differences.  Agreement on the shipped files and on perturbed
copies of them checks both.  Values agree to rounding; uncertainties to the central differences'
truncation error (relative step 1e-6, so about 1e-8 of a sigma; held to 1e-6).
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import measured_oracle as oracle
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bikerider.bicycle import raw_measurements as rm
from bikerider.engine import Chain
from bikerider.errors import FitError, InputError
from bikerider.io.name_value_file import read_name_value_file
from bikerider.quantity import Quantity

DATA = Path(str(resources.files("bikerider") / "data" / "bicycleparameters" / "bicycles"))
STANDARD = ("Browser", "Browserins", "Fisher", "Yellow")
"""The shipped files in the template's layout (Fisher without seating measurements)."""


def _values(name: str) -> dict[str, Quantity]:
    return read_name_value_file(DATA / name / "RawData" / f"{name}Measured.txt").as_dict()


def _reduced(values: dict[str, Quantity], com_method: str = "least_squares") -> dict[str, Quantity]:
    """Every finite output of the reduction's chain."""
    reduced, _ = rm.reduce_values(values, rm.detect_layout(values), com_method=com_method)
    return {k: q for k, q in reduced.items() if math.isfinite(q.value)}


def _assert_same(reduced: dict[str, Quantity], reference: dict[str, Quantity]) -> None:
    assert set(reduced) == set(reference)
    for key, q in reduced.items():
        assert q.value == pytest.approx(reference[key].value, rel=1e-12, abs=1e-15), key
        assert q.sigma == pytest.approx(reference[key].sigma, rel=1e-6, abs=1e-15), key


@pytest.mark.parametrize("name", STANDARD)
def test_shipped_standard_files_agree_with_the_oracle(name):
    values = _values(name)
    reduction = rm.reduce_measured(values)
    reduced = _reduced(values)
    assert ("l_s" in reduced) == reduction.layout.seating
    _assert_same(reduced, oracle.reduce(values, reduction.layout))
    oracle_lines: dict = {}
    oracle.evaluate_measured({k: q.value for k, q in values.items()}, reduction.layout, lines=oracle_lines)
    for body, fit in reduction.lines.items():
        np.testing.assert_allclose(fit.point, oracle_lines[body].point, rtol=1e-12)
        np.testing.assert_allclose(fit.distances, oracle_lines[body].distances, rtol=1e-9, atol=1e-15)
        assert fit.rms == pytest.approx(oracle_lines[body].rms, rel=1e-9)


@pytest.mark.parametrize("seed", range(6))
def test_perturbed_files_agree_with_the_oracle(seed):
    """Every value moved by up to two of its sigmas (or 1 %), and every sigma scaled: a different
    point of the chain and different weights in every uncertainty."""
    rng = np.random.default_rng(seed)
    values = {}
    for key, q in _values("Browser").items():
        spread = 2 * q.sigma if q.sigma > 0 else 0.01 * abs(q.value)
        sigma = q.sigma * rng.uniform(0.2, 5) if q.sigma > 0 else (0.0 if key in ("nF", "nR") else 0.001 * abs(q.value))
        values[key] = Quantity(q.value + spread * rng.uniform(-1, 1) if key not in ("nF", "nR") else q.value, sigma)
    _assert_same(_reduced(values), oracle.reduce(values, rm.detect_layout(values)))


@pytest.mark.parametrize("name", ["Browser", "Rigid"])
@pytest.mark.parametrize("method", ["least_squares", "pairwise_mean"])
def test_every_layout_and_centre_of_mass_method_agrees_with_the_oracle(name, method):
    """Rigid: heights-and-diameters geometry, handlebar and fork apart, five orientations (the
    numeric least-squares stage) and three (the closed form)."""
    values = _values(name)
    _assert_same(_reduced(values, method), oracle.reduce(values, rm.detect_layout(values), method))


REJECTED = {
    # a hanging distance 0.1 m off: the rear frame's lines miss their common point
    "lines that do not meet": (lambda v: {"aB1": Quantity(v["aB1"].value + 0.1, 0.003)}, FitError, "rear frame"),
    # orientation 2 the same axis and line as orientation 1, seen from the other side
    "coincident orientations": (
        lambda v: {"alphaH2": Quantity(v["alphaH1"].value - 180.0, 0.2), "aH2": Quantity(-v["aH1"].value, 0.003)},
        InputError,
        "Eq. 6 is singular",
    ),
}


@pytest.mark.parametrize("case", sorted(REJECTED))
def test_a_rejected_file_gets_its_error(case):
    changes, error, message = REJECTED[case]
    values = _values("Browser")
    values.update(changes(values))
    with pytest.raises(error, match=message):
        rm.reduce_measured(values, source="Browser")
    with pytest.raises(error):
        oracle.reduce(values, rm.detect_layout(values))


def test_grips_out_of_reach_leave_the_seating_out():
    values = _values("Browser")
    values["LhbF"] = Quantity(0.2, 0.0)  # shorter than half the handlebar width
    reduction = rm.reduce_measured(values, source="Browser")
    assert any("seating measurements not usable" in note for note in reduction.notes)
    assert "l_s" not in reduction.bodies.values


@pytest.mark.parametrize("name", ["Browser", "Rigid"])
@pytest.mark.parametrize("shape", [(4,), (2, 3)])
def test_the_stages_broadcast_over_batches(name, shape):
    """The reduction's stages evaluated on batches of points equal them point by point (each point
    perturbs different inputs, so mixing points up anywhere would show)."""
    values = _values(name)
    layout = rm.detect_layout(values)
    inputs = rm.measured_inputs(values, layout)
    stages = rm._stages(rm._layout_key(layout, "least_squares"))
    chain = Chain(stages, inputs)
    rng = np.random.default_rng(3)
    batch = {
        k: q.value * (1 + 1e-4 * rng.uniform(-1, 1, shape)) if math.isfinite(q.value) else q.value
        for k, q in inputs.items()
    }
    together = chain.evaluate(batch)
    outputs = [o for stage in chain.stages for o in stage.outputs]
    for index in np.ndindex(*shape):
        alone = chain.evaluate({k: float(v[index]) if np.ndim(v) else v for k, v in batch.items()})
        for key in outputs:
            got = np.broadcast_to(together[key], shape)[index]
            if math.isnan(alone[key]):
                assert math.isnan(got), key
            else:
                assert got == pytest.approx(alone[key], rel=1e-12, abs=1e-15), (key, index)


_HANGING = [f"{kind}{body}{i}" for body in "BH" for kind in ("alpha", "a", "Tt") for i in (1, 2, 3)]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    moves=st.dictionaries(
        st.sampled_from(_HANGING + ["gamma", "TcB1", "TcH1", "TcR1", "LhbF", "whb", "TtP1"]),
        st.floats(-0.5, 0.5),
        min_size=1,
        max_size=4,
    ),
)
def test_the_reduction_decides_what_the_oracle_decides(moves):
    """Hanging angles, distances and periods moved far (up to 50 %, angles up to 90 degrees): where the
    oracle raises, the reduction raises the same kind of error; where it answers, the two agree."""
    values = _values("Browser")
    for name, move in moves.items():
        q = values[name]
        shifted = q.value + 180 * move if name.startswith("alpha") or name == "gamma" else q.value * (1 + move)
        values[name] = Quantity(shifted, q.sigma)
    try:
        rm._check_values(values, str, {})  # values out of any plausible range: refused before the chain
    except InputError:
        return
    try:
        reference = oracle.reduce(values, rm.detect_layout(values))
    except (InputError, FitError) as exc:
        with pytest.raises(type(exc)):
            _reduced(values)
        return
    _assert_same(_reduced(values), reference)
