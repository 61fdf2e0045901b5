"""Numerical edges: limbs at the limit of reach, the speed where the weave pair is born, bicycles
without critical speeds, nearly singular mass matrices, speeds too large for floating point."""

from __future__ import annotations

import itertools
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from bikerider.generated import benchmark_model as gen
from bikerider.generated import rider_model as gen_rider
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mode_reference import reference
from strategies import benchmark_mappings, factor, meijaard_values, paper_inputs, run_cli

from bikerider.benchmark import BenchmarkParameters, WhippleModel
from bikerider.engine import arguments
from bikerider.errors import InputError, ReachError
from bikerider.estimate import estimate
from bikerider.quantity import Quantity
from bikerider.rider.model import model_arguments, seat_rider


def _model(**changes) -> WhippleModel:
    return WhippleModel.from_parameters(BenchmarkParameters.from_mapping({**meijaard_values(), **changes}, "bench"))


# ------------------------------------------------------------------------------------------
# Limbs at the limit of reach
# ------------------------------------------------------------------------------------------
def _reach(bicycle, rider) -> np.ndarray:
    args = model_arguments(bicycle, rider)
    return np.asarray(gen_rider.limb_reach(**{k: args[k] for k in arguments("rider_model.limb_reach")}))


def _with(rider, **lengths):
    return replace(rider, values={**rider.values, **{k: Quantity(v) for k, v in lengths.items()}})


def _distance_to_line(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    d = (b - a) / np.linalg.norm(b - a)
    offset = point - a
    return float(np.linalg.norm(offset - (offset @ d) * d))


LIMBS = {  # limb: (distal length, proximal length, reach index, distal end, joint, proximal end), 0-based points
    "leg": ("l_ll", "l_ul", 0, 4, 13, 12),  # pedal axis 5, knee 14, hip 13
    "arm": ("l_la", "l_ua", 2, 18, 22, 20),  # hand 19, elbow 23, shoulder 21
}


@pytest.mark.parametrize("limb", ["leg", "arm"])
@pytest.mark.parametrize("share", [0.35, 0.5, 0.62])
def test_an_exactly_straight_limb_puts_the_joint_on_the_line(limb, share):
    bicycle, rider = paper_inputs()
    distal, proximal, k, a, joint, b = LIMBS[limb]
    span = float(_reach(bicycle, rider)[k])
    straight = _with(rider, **{distal: share * span, proximal: span - share * span})
    model = seat_rider(bicycle, straight)
    p = model.grid_points
    assert np.all(np.isfinite(p[[4, 12, 13, 18, 20, 22]])) and np.all(np.isfinite(model.inertia))
    # The joint lies on the line through the limb's ends (to 1e-7 of the span, see rider.model) ...
    assert _distance_to_line(p[joint], p[a], p[b]) < 1e-7 * span
    # ... at its segment lengths from each end.
    assert np.linalg.norm(p[joint] - p[a]) == pytest.approx(share * span, rel=1e-9)
    assert np.linalg.norm(p[joint] - p[b]) == pytest.approx(span - share * span, rel=1e-9)
    # The whole estimate runs on it: finite parameters, no NaN from the closure inside the chain.
    result = estimate(bicycle, straight)
    assert all(v is None or math.isfinite(v) for v in result.parameters.values.values())


@pytest.mark.parametrize("limb", ["leg", "arm"])
def test_a_limb_a_nanometre_too_short_is_a_reach_error(limb):
    bicycle, rider = paper_inputs()
    distal, proximal, k, *_ = LIMBS[limb]
    span = float(_reach(bicycle, rider)[k])
    short = _with(rider, **{distal: 0.5 * span, proximal: 0.5 * span - 1e-9})
    with pytest.raises(ReachError, match=r"too short to reach"):
        seat_rider(bicycle, short)


@pytest.mark.parametrize("limb", ["leg", "arm"])
def test_a_folded_limb_is_a_reach_error_not_a_nan(limb):
    bicycle, rider = paper_inputs()
    distal, proximal, k, *_ = LIMBS[limb]
    span = float(_reach(bicycle, rider)[k])
    folded = _with(rider, **{distal: 0.2, proximal: 0.2 + span})  # |difference| exactly the span
    with pytest.raises(ReachError, match="cannot close"):
        seat_rider(bicycle, folded)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(factor(0.25, 0.75), st.sampled_from(["leg", "arm"]))
def test_straight_limbs_close_for_any_split_of_the_length(share, limb):
    """Exactly straight for many splits of the span between the two segments: never a NaN."""
    bicycle, rider = paper_inputs()
    distal, proximal, k, a, joint, b = LIMBS[limb]
    span = float(_reach(bicycle, rider)[k])
    model = seat_rider(bicycle, _with(rider, **{distal: share * span, proximal: span - share * span}))
    assert np.all(np.isfinite(model.grid_points[joint])) and np.all(np.isfinite(model.inertia))
    p = model.grid_points
    assert _distance_to_line(p[joint], p[a], p[b]) < 1e-7 * span


# ------------------------------------------------------------------------------------------
# The speed v_d at which the weave pair is born
# ------------------------------------------------------------------------------------------
def _discriminant_from_roots(model: WhippleModel, speed: float) -> float:
    """a4^6 prod_{i<j} (r_i - r_j)^2 over the characteristic roots: the discriminant, computed
    independently of the generated polynomial."""
    a4 = float(np.linalg.det(model.M))
    roots = np.linalg.eigvals(model.state_matrix(np.array([speed])))[0]
    product = np.prod([(x - y) ** 2 for x, y in itertools.combinations(roots, 2)])
    return float((a4**6 * product).real)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(benchmark_mappings())
def test_the_discriminant_polynomial_is_the_discriminant(mapping):
    model = WhippleModel.from_parameters(BenchmarkParameters.from_mapping(mapping, "bench"))
    coefficients = gen.discriminant_polynomial(**model._entries(), g=model.g)
    for speed in (0.0, 0.7, 2.0, 5.0, 9.0):
        expected = _discriminant_from_roots(model, speed)
        got = float(np.polyval(coefficients, speed**2))
        scale = float(np.abs(coefficients).max()) * max(1.0, speed**12)
        assert got == pytest.approx(expected, rel=1e-6, abs=1e-9 * scale), speed


def test_weave_birth_speed_of_the_benchmark(meijaard2007):
    table = meijaard2007["speeds_table2a"]["v_d"]
    model = _model()
    v_d = model.weave_birth_speed()
    assert v_d == pytest.approx(table["value"], abs=1e-10)  # Meijaard et al. 2007 Table 2a: 0.68428307889246
    # The double root there: the mean of the merging pair (a double root is only good to sqrt(eps)
    # apart, but the pair's mean is accurate); Table 2a: lambda = 3.7829040512932.
    pair = model.eigenvalues([v_d]).mode("weave")[0], model.eigenvalues([v_d]).values[0, 1]
    assert float(np.mean(pair).real) == pytest.approx(table["lambda"], abs=1e-10)


def test_mode_labels_are_continuous_through_the_weave_birth():
    model = _model()
    v_d = model.weave_birth_speed()
    jumps = {}
    for eps in (1e-4, 1e-6, 1e-8):
        eig = model.eigenvalues([v_d * (1 - eps), v_d * (1 + eps)])
        assert list(eig.labels[0]) == list(eig.labels[1]) == ["weave", "weave", "capsize", "castor"]
        below, above = eig.values
        assert np.all(below.imag == 0) and above[0].imag > 0  # real pair below, complex pair above
        jumps[eps] = np.abs(above - below)
    # Weave: the two branches of a square root meet, the jump shrinks like sqrt(eps);
    # capsize and castor are smooth there, the jump shrinks like eps.
    assert jumps[1e-6][0] / jumps[1e-8][0] == pytest.approx(10, rel=0.01)
    assert jumps[1e-6][2] / jumps[1e-8][2] == pytest.approx(100, rel=0.01)
    assert jumps[1e-6][3] / jumps[1e-8][3] == pytest.approx(100, rel=0.01)
    assert jumps[1e-8][0] < 1e-3


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(benchmark_mappings())
def test_weave_birth_speed_on_random_bicycles(mapping):
    """Against eigenvalues tracked by continuity down from 12 m/s (tests/mode_reference.py): v_d
    lies in the first grid step, in the speeds where the branches' names are certain, where the
    two weave branches turn from both real into a complex pair.  (The two largest real roots are
    not always the ones that merge: on 55 of 433 random bicycles they are not, docs/dynamics.md.)"""
    model = WhippleModel.from_parameters(BenchmarkParameters.from_mapping(mapping, "bench"))
    ref = reference(model, n=2401)
    v_d = model.weave_birth_speed()
    if ref is None or (v_d is not None and v_d > ref.speeds[-1]):
        return
    pair = ref.tracked[:, list(ref.weave)]
    real = np.all(np.abs(pair.imag) < 1e-9, axis=1)
    births = np.flatnonzero(real[:-1] & ~real[1:] & ref.unambiguous[:-1])
    if not births.size:
        assert v_d is None or v_d <= ref.speeds[np.argmax(ref.unambiguous)] + 1e-9, v_d
        return
    k = births[0]
    assert v_d is not None and ref.speeds[k] - 1e-9 <= v_d <= ref.speeds[k + 1] + 1e-9
    weave_speed = model.critical_speeds().weave
    if weave_speed is not None and weave_speed > ref.speeds[k + 1] and ref.unambiguous[0]:
        assert v_d < weave_speed  # the pair is born before it can cross into stability


# ------------------------------------------------------------------------------------------
# Bicycles without critical speeds
# ------------------------------------------------------------------------------------------
def test_no_weave_and_no_capsize_speed_give_none_and_json_null(tmp_path):
    model = _model(c=-0.08)  # negative trail: never self-stable
    speeds = model.critical_speeds()
    assert speeds.weave is None and speeds.capsize is None and speeds.weave_frequency is None
    assert speeds.stable_range is None and model.weave_birth_speed() is None
    path = tmp_path / "negative_trail.toml"
    path.write_text("\n".join(f"{k} = {v!r}" for k, v in {**meijaard_values(), "c": -0.08}.items()) + "\n")
    code, out, err = run_cli(["benchmark", str(path), "--json"])
    assert code == 0, err
    assert json.loads(out)["speeds"] == {"weave": None, "capsize": None, "stable_intervals": []}
    code, out, err = run_cli(["benchmark", str(path)])
    assert "Weave speed   none at positive speed" in out and "No self-stable speed range" in out


def test_vertical_steer_axis_has_a_real_crossing_that_stabilises_not_a_capsize_speed():
    # With a vertical steer axis a real eigenvalue crosses zero (at 3.52 m/s), but from the right
    # half-plane into the left: that is no capsize speed (where the capsize mode turns unstable).
    # The weave pair stays unstable, so there is no weave speed and no stable range either.
    model = _model(lam=0.0)
    speeds = model.critical_speeds()
    assert speeds.weave is None and speeds.capsize is None and speeds.stable_range is None
    (crossing,) = model.stability().crossings
    assert crossing.kind == "real" and crossing.stabilising
    below, above = model.eigenvalues([crossing.speed * 0.999, crossing.speed * 1.001]).values
    assert np.sum(below.real > 0) == np.sum(above.real > 0) + 1


# ------------------------------------------------------------------------------------------
# Mass matrices that are singular or nearly so; speeds beyond floating point
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("m22", [1.0, 1.0 + 1e-14, 1.0 - 1e-3])
def test_singular_or_indefinite_mass_matrix(m22):
    M = np.array([[1.0, 1.0], [1.0, m22]])
    with pytest.raises(InputError, match=r"M = .*positive definite mass matrix"):
        WhippleModel(M, np.zeros((2, 2)), -np.eye(2), np.zeros((2, 2)))


def test_nearly_singular_mass_matrix_from_parameters_names_the_file(tmp_path):
    # A weightless front assembly on zero trail: the steer row of M all but vanishes.  Masses below
    # a milligram are refused first (bikerider.benchmark.rules.SMALLEST), naming the file.
    tiny = dict(c=0.0, mH=1e-12, mF=1e-12, IHxx=1e-15, IHyy=1e-15, IHzz=1e-15, IHxz=0.0, IFxx=1e-15, IFyy=1.5e-15)
    with pytest.raises(InputError, match=r"bench: mH = 1e-12: expected at least 1e-06 kg"):
        _model(**tiny)
    # At a milligram, beside the heaviest rear body the limits allow, M is singular to rounding:
    # the model refuses it, and so does every reader of a benchmark file (issue 12: `sensitivity
    # --inputs` builds no model and gave sensitivities of a singular bicycle without a word).
    light = dict(tiny, mH=1e-6, mF=1e-6, IHxx=1e-20, IHyy=1e-20, IHzz=1e-20, IFxx=1e-20, IFyy=1e-20)
    heavy = dict(mB=1000.0, zB=-5.0, IBxx=1e4, IByy=1e4, IBzz=1e4, IBxz=0.0)
    with pytest.raises(InputError, match=r"^bench: M = .*positive definite"):
        _model(**light, **heavy)
    path = tmp_path / "SingularBenchmark.txt"
    path.write_text("".join(f"{k} = {v!r}\n" for k, v in {**meijaard_values(), **light, **heavy}.items()))
    for argv in (["benchmark", str(path)], ["sensitivity", "weave_speed", "--inputs", str(path)]):
        code, _, err = run_cli(argv)
        assert code == 2 and f"{path}: M = " in err and "positive definite mass matrix" in err, err


def test_speeds_too_large_for_floating_point():
    model = _model()
    with pytest.raises(InputError, match=r"speeds = 1e\+200"):
        model.eigenvalues([1.0, 1e200])
    code, _, err = run_cli(
        [
            "benchmark",
            str(__import__("pathlib").Path(__file__).parent / "data" / "BenchmarkBenchmark.txt"),
            "--speeds",
            "0:1e300:3",
        ]
    )
    assert code == 2 and "speeds" in err and "Traceback" not in err
