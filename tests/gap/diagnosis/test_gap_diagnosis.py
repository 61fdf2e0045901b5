"""The diagnosis on synthetic data whose answer is known, and the predictor's building blocks."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import bikerider
from bikerider.errors import InputError
from bikerider.gap.candidates.effect_model import BENCH_ARGS, EffectModel
from bikerider.gap.diagnosis.result import diagnose
from bikerider.gap.diagnosis.statistics import gap_shrink, significantly_better
from bikerider.gap.inference.predict import Predictor
from bikerider.gap.inference.problem import GapProblem
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
from bikerider.io.gap_data import read_canonical
from bikerider.io.gap_model import load_model

DATA = Path(bikerider.__file__).parent / "data"
BP = DATA / "bicycleparameters"
EMPTY = CanonicalData([], np.empty(0), np.empty(0), [], {}, [])


def _nominal(model):
    return {k: float(model.parameters.values[k]) for k in BENCH_ARGS + ("g",)}


def _synthetic(model, effects, seed, sigma=0.04, n_per_group=5):
    """Weave eigenvalues of a truth with Gaussian noise: 3 groups, the third under control."""
    rng = np.random.default_rng(seed)
    truth = EffectModel(_nominal(model), model.geometry, effects)
    rows = {"speed": [], "value": [], "group": [], "gains": []}
    for group, lo, hi, gains in (
        ("a", 5.5, 9.0, (0, 0, 0, 0)),
        ("b", 5.7, 9.2, (0, 0, 0, 0)),
        ("c", 4.0, 7.5, (0, 5.0, -2.0, -0.5)),
    ):
        speeds = np.linspace(lo, hi, n_per_group)
        reference = Predictor(
            EigenvalueData(
                speeds,
                np.zeros(speeds.size, complex),
                np.ones(speeds.size),
                np.ones(speeds.size),
                np.zeros(speeds.size),
                ["weave"] * speeds.size,
                [group] * speeds.size,
                np.tile(gains, (speeds.size, 1)),
                ["x"] * speeds.size,
            ),
            EMPTY,
            _nominal(model),
            model.geometry,
        )
        weave = reference.eigenvalues(truth)
        rows["speed"] += list(speeds)
        rows["value"] += list(weave + sigma * (rng.standard_normal(weave.size) + 1j * rng.standard_normal(weave.size)))
        rows["group"] += [group] * speeds.size
        rows["gains"] += [gains] * speeds.size
    n = len(rows["speed"])
    return EigenvalueData(
        np.array(rows["speed"]),
        np.array(rows["value"]),
        np.full(n, sigma),
        np.full(n, sigma),
        np.zeros(n),
        ["weave"] * n,
        rows["group"],
        np.array(rows["gains"], float),
        [f"synthetic:{k}" for k in range(n)],
    )


def test_hidden_steer_damping_is_found_ranked_and_shrinks_the_gap(davis):
    data = _synthetic(davis, {"steer_damping": {"c_steer": 0.4}}, seed=1)
    result = diagnose(davis, data, EMPTY).as_dict()
    assert result["verdict"] == "structural"
    assert result["ranking"][0]["effect"] == "steer_damping"
    fitted = result["ranking"][0]["parameters"]["c_steer"]
    assert fitted["ci95"][0] <= 0.4 <= fitted["ci95"][1]
    assert result["ranking"][0]["plausible"]
    assert result["selected"][0] == "steer_damping"
    assert result["how_far"]["heldout_error_after"] < 1.5 < result["how_far"]["heldout_error_before"]
    assert result["how_far"]["shrink"] > 0.9
    # JSON contract
    for key in ("verdict", "gap", "ranking", "selected"):
        assert key in result
    for key in ("effect", "parameters", "heldout_error_before", "heldout_error_after", "shrink", "plausible"):
        assert key in result["ranking"][0]
    assert {c["mode"] for c in result["gap"]["map"]} == {"weave"}
    assert any(c["significant"] for c in result["gap"]["map"])


def test_no_effect_gives_no_structural_verdict(davis):
    data = _synthetic(davis, {}, seed=2)
    result = diagnose(davis, data, EMPTY).as_dict()
    assert result["verdict"] in ("none", "parameters")
    assert "steer_damping" not in result["selected"]


def test_one_point_gets_a_gap_map_but_no_ranking(davis):
    data = _synthetic(davis, {}, seed=3)
    one = EigenvalueData(
        data.speed[:1],
        data.value[:1],
        data.real_sigma[:1],
        data.imag_sigma[:1],
        data.speed_sigma[:1],
        data.mode[:1],
        data.group[:1],
        data.gains[:1],
        data.source[:1],
    )
    result = diagnose(davis, one, EMPTY).as_dict()
    assert result["ranking"] == [] and len(result["gap"]["map"]) == 2
    assert any("fewer than two folds" in n for n in result["notes"])


def test_observations_without_any_uncertainty_are_refused(davis):
    riderless = load_model(DATA / "gap" / "kooijman2008_bicycle.toml")
    no_sigma = type(riderless)(
        riderless.parameters.__class__.from_mapping(
            {k: v for k, v in riderless.parameters.values.items()}, "no sigmas"
        ),
        riderless.geometry,
        None,
        "test",
    )
    data = EigenvalueData(
        np.array([5.0]),
        np.array([complex(-1, 5)]),
        np.array([np.nan]),
        np.array([np.nan]),
        np.zeros(1),
        ["weave"],
        ["g"],
        np.zeros((1, 4)),
        ["f.csv:2"],
    )
    with pytest.raises(InputError, match="f.csv:2"):
        GapProblem(no_sigma, data, EMPTY)


def test_predicted_identification_of_the_whipple_model_is_itself(davis):
    can = read_canonical(DATA / "gap" / "moore2012_canonical_id.csv", ["J-P"])
    nominal = _nominal(davis)
    predictor = Predictor(EigenvalueData.concatenate([]), can, nominal, davis.geometry)
    from bikerider.benchmark import WhippleModel

    w = WhippleModel.from_parameters(davis.parameters)
    mats = {"M": w.M, "C1": w.C1, "K0": w.K0, "K2": w.K2}
    idx = {"phi": 0, "delta": 1}
    expected = []
    for entry in can.entry:
        name, coords = entry.split("_")
        row = "phi" if coords.startswith("phi") else "delta"
        expected.append(mats[name][idx[row], idx[coords[len(row) :]]])
    np.testing.assert_allclose(predictor.predict(EffectModel(nominal, davis.geometry)), expected, rtol=1e-9, atol=1e-12)
    # Moore (2012) back-computed Whipple values for J-P (canonical_id_coefficients.csv): our model agrees
    # to 0.3 %, so the rider and bicycle files are the ones he used.
    moore = {
        "M_phidelta": 2.43973,
        "C1_phidelta": 44.63596,
        "K0_phidelta": -2.48295,
        "M_deltadelta": 0.22437,
        "C1_deltaphi": -0.31448,
        "C1_deltadelta": 1.46183,
        "K0_deltadelta": -0.77462,
        "K2_deltadelta": 2.29263,
    }
    for entry, value in zip(can.entry, expected):
        assert value == pytest.approx(moore[entry], rel=3e-3)


def test_identification_sees_steer_damping_in_c1_deltadelta_only(davis):
    can = read_canonical(DATA / "gap" / "moore2012_canonical_id.csv", ["J-P"])
    nominal = _nominal(davis)
    predictor = Predictor(EigenvalueData.concatenate([]), can, nominal, davis.geometry)
    base = predictor.predict(EffectModel(nominal, davis.geometry))
    damped = predictor.predict(EffectModel(nominal, davis.geometry, {"steer_damping": {"c_steer": 1.0}}))
    changed = {e for e, a, b in zip(can.entry, base, damped) if abs(a - b) > 1e-9}
    assert changed == {"C1_deltadelta"}
    k = can.entry.index("C1_deltadelta")
    # least squares of c s against v C1 s over the speeds gives c * sum(v) / sum(v^2)
    v = np.linspace(1.5, 9.0, 5)
    assert damped[k] - base[k] == pytest.approx(v.sum() / (v**2).sum(), rel=1e-9)


def test_shrink_and_significance_helpers():
    z = np.array([3.0, -4.0, 5.0, 2.0, -3.0, 4.0])
    assert gap_shrink(z, z / 10) == pytest.approx(1.0)
    assert gap_shrink(z, z) == pytest.approx(0.0)
    assert gap_shrink(z / 10, z / 20) is None  # no gap above the noise floor
    assert significantly_better(z / 3, z)[0]
    assert not significantly_better(z, z)[0]
    assert not significantly_better(z * 0.99, z)[0]  # better by less than TIE_RELATIVE
