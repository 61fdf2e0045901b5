"""Issue 21, parts 3 and 4: priors, not walls; the equivalent of friction the records cannot split; the
calibration study's trials and report (a few trials only)."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from gap_support import BP, DATA

from bikerider.errors import InputError
from bikerider.gap.candidates.effects import EFFECTS, Prior, prior_from_range
from bikerider.gap.diagnosis.fits import with_parameter_uncertainty
from bikerider.gap.diagnosis.priors import Priors, steer_rate_amplitudes
from bikerider.gap.diagnosis.result import diagnose
from bikerider.gap.inference.problem import EffectFit
from bikerider.gap.inference.timedomain import describing_gain
from bikerider.io.gap_data import read_eigenvalues
from bikerider.io.gap_model import load_model

ROOT = Path(__file__).resolve().parents[3]


# -- priors ------------------------------------------------------------------------------------------
def test_every_candidate_parameter_has_a_prior_with_a_source():
    for effect in EFFECTS.values():
        for p in effect.parameters:
            prior = p.the_prior()
            assert prior.source and prior.kind in ("lognormal", "halfcauchy", "normal")
            lo, hi = prior.interval()
            assert lo < hi and lo >= p.bounds[0] - 1e-12, p.name


def test_the_log_prior_ratio_is_zero_at_the_mode_and_falls_off_either_side():
    lognormal = Prior("lognormal", 0.3, 3.0, "test")
    assert lognormal.log_ratio(0.3) == 0.0
    assert lognormal.log_ratio(0.1) < 0 and lognormal.log_ratio(0.9) < 0
    assert lognormal.log_ratio(0.1) == pytest.approx(lognormal.log_ratio(0.9))  # symmetric in ln x
    assert lognormal.log_ratio(0.9) == pytest.approx(-0.5)  # one geometric sd: -1/2 nat
    cauchy = Prior("halfcauchy", 0.0, 0.1, "test")
    assert cauchy.log_ratio(0.0) == 0.0 and cauchy.log_ratio(0.1) == pytest.approx(-math.log(2))
    assert cauchy.log_ratio(10.0) > -10  # heavy tails: a hundred scales costs under 10 nats
    made = prior_from_range(0.05, 0.3, "range")
    lo, hi = made.interval()
    assert lo == pytest.approx(0.05) and hi == pytest.approx(0.3)


def test_prior_draws_stay_in_the_interval_asked_for():
    rng = np.random.default_rng(0)
    prior = Prior("halfcauchy", 0.0, 0.1, "test")
    x = [prior.sample(rng, 0.8) for _ in range(200)]
    assert max(x) <= prior.interval(0.8)[1] and min(x) >= 0


# -- selection with priors -----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def table_diagnosis():
    model = load_model(
        BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt", BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
    )
    return diagnose(
        model, read_eigenvalues(DATA / "gap_examples" / "eigenvalues.csv"), effects=("steer_damping", "steer_inertia")
    )


def test_a_precise_value_above_the_usual_range_is_selected_and_flagged(table_diagnosis):
    # before: c_steer = 1.08 [0.88, 1.27] ranked first, and "Selected: nothing" (a fixed plausible 0.05-0.5)
    d = table_diagnosis
    assert d.verdict == "structural" and d.ranking[0]["effect"] == "steer_damping"
    assert d.selected == ["steer_damping"]
    (flag,) = d.selection["flags"]
    assert "above the usual 0.05-0.5 N m s/rad" in flag and "the data determine it" in flag and ": check " in flag
    assert "reaches the usual range" not in flag  # its interval [0.88, 1.27] lies above 0.5 too
    assert d.selection["log_prior"] < 0 and d.selection["log_odds_vs_nominal"] > 0
    from bikerider.gap.text import summary_text

    text = summary_text(d.as_dict())
    assert "Selected: steer_damping" in text and "flag: c_steer = " in text


def _fit(values, low, high, names=("c_steer",), effects=("steer_damping",)):
    n = len(values)
    return EffectFit(
        effects=effects,
        names=list(names),
        units=["N m s/rad"] * n,
        values=np.array(values, float),
        stderr=(np.array(high) - np.array(low)) / 3.92,
        ci_low=np.array(low, float),
        ci_high=np.array(high, float),
        config={},
        shift={},
        chi2=0.0,
        prior_chi2=0.0,
        n=10,
        success=True,
        lower=np.zeros(n),
        upper=np.full(n, 20.0),
    )


def test_an_interval_overlapping_the_usual_range_does_not_make_a_value_usual(table_diagnosis):
    # before: c = 0.62 [0.42, 0.82] was called plausible because its interval reaches 0.5
    ok, (check,) = table_diagnosis.priors.plausibility(_fit([0.62], [0.42], [0.82]))
    assert not ok and not check["in_range"] and check["usable"]
    assert check["flag"].startswith("c_steer = 0.62 N m s/rad") and "above the usual" in check["flag"]
    assert check["log_prior"] == pytest.approx(Prior("lognormal", 0.3, 3.0, "").log_ratio(0.62))
    ok, (check,) = table_diagnosis.priors.plausibility(_fit([0.3], [0.2], [0.4]))
    assert ok and check["flag"] is None


def test_a_bicycles_own_range_becomes_its_prior(table_diagnosis):
    own = Priors({"I_steer": (0.0, 0.1, "a steer motor's rotor")}, np.zeros(0))
    prior = own.prior_of("I_steer")
    assert prior.kind == "halfcauchy" and "steer motor" in prior.source
    assert table_diagnosis.priors.prior_of("I_steer").kind == "lognormal"


def test_a_candidate_at_the_noise_floor_is_always_selected():
    # before: steer damping well above 0.5 N m s/rad ranked first at the noise floor with "Selected: nothing"
    from validation import cases as V

    model = load_model(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt")
    truth = V.Truth("viscous", ("steer_damping",), {"c_steer": 1.2}, "viscous 1.2 N m s/rad")
    rng = np.random.default_rng(3)
    simulator = V.TruthSimulator(model, truth, rng)
    data, _ = V.measure(simulator, V.CALIBRATION_RIDERLESS, rng)
    d = diagnose(model, data)
    out = d.as_dict()
    first = out["ranking"][0]
    assert out["verdict"] == "structural" and first["effect"] == "steer_damping"
    assert first["heldout_error_after"] < 1.5
    assert first["parameters"]["c_steer"]["ci95"][0] > 0.5  # precisely above the usual range
    assert "steer_damping" in out["selected"]
    assert any("above the usual" in f for f in out["selection"]["flags"])


# -- friction's equivalent -------------------------------------------------------------------------------
def _friction_diagnosis(amplitudes):
    t = np.arange(0.0, 2.0, 0.01)
    records = [
        SimpleNamespace(record=SimpleNamespace(signals={"steer_rate": a * np.sin(2 * np.pi * 2 * t)}), estimate=None)
        for a in amplitudes
    ]
    return Priors({}, steer_rate_amplitudes(records, {k: k for k in range(len(amplitudes))}))


def _friction_fit(T, c, cov):
    fit = _fit([T, c], [0, 0], [1, 1], names=("T_coulomb", "c_viscous"), effects=("steer_friction",))
    fit.covariance = np.array(cov)
    fit.stderr = np.sqrt(np.diag(fit.covariance))
    return fit


def test_decays_of_one_amplitude_report_the_equivalent_not_the_split():
    d = _friction_diagnosis([0.5, 0.52, 0.55, 0.48, 0.5])
    fit = _friction_fit(0.02, 0.29, [[1e-4, -5e-4], [-5e-4, 3e-3]])
    eq = d.friction_equivalent(fit)
    a = eq["amplitude"]
    assert a == pytest.approx(0.5, rel=0.02)  # sqrt(2) RMS of a sine is its amplitude
    # the fit's own law's describing function at 10 corners: within 2 % of a sharp corner's 4 / (pi A)
    gain = float(describing_gain(a))
    assert 0.98 * 4 / (math.pi * a) < gain < 4 / (math.pi * a)
    assert eq["c_equivalent"] == pytest.approx(0.29 + gain * 0.02)
    g = np.array([gain, 1.0])
    assert eq["stderr"] == pytest.approx(math.sqrt(g @ fit.covariance @ g))  # no corners refitted: the fit's own
    assert not eq["separable"] and "cannot tell Coulomb from viscous" in eq["note"]


def test_decays_of_many_amplitudes_carry_the_split():
    d = _friction_diagnosis([0.2, 0.4, 0.8, 1.2, 1.6])
    eq = d.friction_equivalent(_friction_fit(0.08, 0.0, [[1e-4, 0.0], [0.0, 1e-4]]))
    assert eq["separable"] and eq["amplitude_spread"] >= 2
    assert d.friction_equivalent(_fit([0.3], [0.2], [0.4])) is None  # no friction in the fit


# -- the calibration study -----------------------------------------------------------------------------
@pytest.mark.slow
def test_a_few_calibration_trials_and_their_report(tmp_path):
    import json

    from validation import cases as V

    models = {"riderless": load_model(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt")}
    effect = next(e for e in V.CALIBRATION_EFFECTS if e.name == "steer_coulomb")
    trial = V.run_trial(models, effect, 0)  # even seed: riderless; the diagnosis gets the records
    assert trial.method == "records" and not trial.rider
    assert 0 < trial.truth["T_coulomb"] <= Prior("halfcauchy", 0, 0.1, "").interval(0.8)[1]
    c_eq = trial.reference["c_steer"]
    # the truth's own law at its drawn corner, below a sharp corner's 4 T / (pi A)
    eps = trial.truth["eps_coulomb"]
    assert eps == V.draw_corner(0)
    assert c_eq == pytest.approx(trial.truth["T_coulomb"] * describing_gain(trial.amplitude, eps))
    assert c_eq < 4 * trial.truth["T_coulomb"] / (math.pi * trial.amplitude)
    assert "c_steer" in trial.fitted
    # the candidate's fit to all the data, for analysis offline: its chi-square over its observations and
    # the local minima its search found (from records)
    assert trial.fit_chi2 >= 0 and trial.fit_n >= trial.n_measured > 0
    assert trial.minima == 1 + len(trial.other_minima) and 0 <= trial.minima_within <= len(trial.other_minima)
    # from records Coulomb friction has its own candidate, scored against the truth's level
    assert trial.reference["T_coulomb"] == trial.truth["T_coulomb"] and "T_coulomb" in trial.fitted
    before = V.run_trial(models, effect, 0, "tables")  # the same runs as a table of eigenvalues
    assert before.method == "tables" and before.truth == trial.truth and before.amplitude == trial.amplitude
    assert before.first == "steer_damping" and "T_coulomb" not in before.fitted
    assert before.minima == 1 and not before.other_minima  # a table's fit is not searched for other minima
    results = tmp_path / "trials.jsonl"
    results.write_text(json.dumps(trial.as_dict()) + "\n" + json.dumps(before.as_dict()) + "\n")
    doc = tmp_path / "doc.md"
    doc.write_text("# head\n")
    sys.path.insert(0, str(ROOT / "docs" / "scripts"))
    try:
        from gap_calibration_report import write_report
    finally:
        sys.path.pop(0)
    write_report(results, doc, 200)
    text = doc.read_text()
    assert text.startswith("# head") and "## 4. Calibration" in text
    assert "Fewer than the 200 trials per effect" in text and "| steer_coulomb | c_steer | 1 |" in text
    assert "Records against tables, on the same 1 trials" in text and "| steer_coulomb | T_coulomb | 1 |" in text
    write_report(results, doc, 200)  # rewritten in place, not appended
    assert doc.read_text().count("## 4. Calibration") == 1


def test_docs_list_every_prior_as_the_registry_has_it():
    text = (ROOT / "docs" / "gap.md").read_text(encoding="utf-8")
    for effect in EFFECTS.values():
        for p in effect.parameters:
            prior = p.the_prior()
            assert f"| `{p.name}` |" in text and prior.describe(p.unit) in text and prior.source in text, p.name


def test_records_of_a_strong_damper_select_it_at_the_noise_floor_and_flag_it():
    # the case from records: a steer damping far above the usual range (a rider's hands, a
    # motor's back-EMF) explains the held-out records to the noise floor; a fixed plausible range made
    # that "Selected: nothing"
    from dataclasses import replace

    from bikerider.gap.measured.records import fit_records
    from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
    from validation import cases as V

    model = load_model(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt")
    model = replace(model, plausible=dict(V.STEER_MOTOR))
    truth = V.Truth("viscous", ("steer_damping",), {"c_steer": 1.2}, "viscous 1.2 N m s/rad")
    rng = np.random.default_rng(5)
    records = fit_records(V.measure_records(V.TruthSimulator(model, truth, rng), V.QUICK_RECORDS, rng))
    effects = ("parameters", "steer_damping", "steer_inertia", "steer_friction")
    out = diagnose(model, EigenvalueData.empty(), CanonicalData.empty(), effects, records).as_dict()
    first = out["ranking"][0]
    assert first["effect"] == "steer_damping" and first["data_error_after"] < 1.0  # at the noise floor
    c = first["parameters"]["c_steer"]
    assert c["ci95"][0] <= 1.2 <= c["ci95"][1]
    assert "steer_damping" in out["selected"]
    assert any(f.startswith("c_steer = ") and "above the usual" in f for f in out["selection"]["flags"])


def test_the_noise_floor_is_consistency_with_noise_not_an_rms_below_one():
    """A held-out RMS of pure noise exceeds 1 about half the time: the floor is the chi-square's upper
    95 % point (the validation's tyre-slip case, seed 15, reached RMS 1.02 on 12 values and was left
    unselected under a bare ``rms <= 1``)."""
    from scipy.stats import chi2

    from bikerider.gap.diagnosis.statistics import at_noise_floor

    assert at_noise_floor(1.02, 12)
    limit = math.sqrt(chi2.ppf(0.95, 12) / 12)  # about 1.32
    assert at_noise_floor(limit * 0.999, 12) and not at_noise_floor(limit * 1.001, 12)
    assert not at_noise_floor(2.0, 12) and not at_noise_floor(math.nan, 12) and not at_noise_floor(0.5, 0)
    # calibrated: pure noise is called "at the floor" in about 95 % of draws, whatever n
    rng = np.random.default_rng(1)
    for n in (3, 12, 200):
        z = rng.standard_normal((4000, n))
        share = np.mean([at_noise_floor(float(np.sqrt(np.mean(row**2))), n) for row in z])
        assert 0.94 <= share <= 0.96, (n, share)


def test_calibration_records_and_tables_of_one_seed_hold_the_same_runs_and_fits():
    # the record method gives the diagnosis what a lab keeps (the noisy runs); the table method the
    # eigenvalues fitted from the very same runs, so the before/after comparison is on identical data
    from bikerider.gap.measured.records import fit_records
    from validation import cases as V

    model = load_model(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt")
    truth = V.Truth("viscous", ("steer_damping",), {"c_steer": 0.4}, "viscous 0.4 N m s/rad")
    rng = np.random.default_rng(2)
    records: list = []
    data, _ = V.measure(V.TruthSimulator(model, truth, rng), V.CALIBRATION_RIDERLESS, rng, None, records)
    used = [f for f in records if f.used]
    assert len(records) == 9 and len(used) == len(data) >= 4
    np.testing.assert_array_equal(data.value.real, [f.estimate.eigenvalue.real for f in used])
    assert [f.record.group for f in used] == list(data.group)
    np.testing.assert_array_equal([f.record.speed for f in used], data.speed)
    # the fits measure() made are those a lab's fit_records makes of the same records
    again = fit_records([f.record for f in records])
    assert [f.used for f in again] == [f.used for f in records]
    for a, b in zip(again, records):
        if a.used:
            assert a.estimate.eigenvalue == b.estimate.eigenvalue and a.estimate.real_sigma == b.estimate.real_sigma
    assert used[0].record.law.is_zero and not used[-1].record.law.is_zero  # the controlled session's law


def test_calibration_jobs_go_round_the_effects_and_resume(tmp_path):
    from validation import cases as V

    sys.path.insert(0, str(ROOT / "docs" / "scripts"))
    try:
        from gap_calibration import jobs
    finally:
        sys.path.pop(0)
    order = jobs(3, 1, 1, 1000)
    n = len(V.CALIBRATION_EFFECTS)
    assert order[: n + 1] == [(e.name, 1000, "records") for e in V.CALIBRATION_EFFECTS] + [
        (V.CALIBRATION_FRICTION.name, 1000, "records")
    ]
    assert order[n + 1 : 2 * n + 1] == [(e.name, 1000, "tables") for e in V.CALIBRATION_EFFECTS]
    assert len(order) == 3 * (n + 1) + n and len(set(order)) == len(order)


def _sandwich_problem(direct_slope: float, apparent_slope: float, records: bool) -> SimpleNamespace:
    """A problem that predicts 4 observations linearly in one size: the weave eigenvalues with
    ``direct_slope``, the records' apparent eigenvalues (indirect inference) with ``apparent_slope``."""

    def predict_batch(lay, X, indirect=True):
        slope = apparent_slope if (indirect and records) else direct_slope
        return slope * np.asarray(X, float)[:, :1] * np.ones((1, 4))

    return SimpleNamespace(
        free=["w"],
        obs=[0, 1, 2, 3],
        layout=lambda effects: None,
        predict_batch=predict_batch,
        var_total=np.full(4, 0.04),
        var_data=np.full(4, 0.04),
        jacobian=np.zeros((4, 1)),
        records=SimpleNamespace() if records else None,
        record_obs=np.array([[0, 1], [2, 3]]) if records else np.zeros((0, 2), int),
    )


def test_intervals_from_records_use_the_apparent_eigenvalues_slopes():
    # the fit weighs the records' residuals by the weave's slopes; where a short record's fitted eigenvalue
    # moves less with the size than the weave does, the records carry less about it: a wider interval
    fit = _fit([5.0], [4.9], [5.1])
    tables = with_parameter_uncertainty(_sandwich_problem(0.4, 0.1, records=False), fit)
    same = with_parameter_uncertainty(_sandwich_problem(0.4, 0.4, records=True), fit)
    flat = with_parameter_uncertainty(_sandwich_problem(0.4, 0.1, records=True), fit)
    expected = 0.2 / (0.4 * math.sqrt(4))  # one size, four rows of standard error 0.2, slope 0.4
    assert tables.stderr[0] == pytest.approx(expected) and same.stderr[0] == pytest.approx(expected)
    assert flat.stderr[0] == pytest.approx(4 * expected)  # the bread (A^T A_i)^-1 with A_i a quarter of A
    assert flat.ci_high[0] - flat.ci_low[0] == pytest.approx(2 * 1.96 * 4 * expected)


@pytest.mark.slow
def test_a_calibration_trial_whose_records_are_all_left_out_is_scored_not_lost(monkeypatch):
    from validation import cases as V

    def no_record_used(*args, **kwargs):
        raise InputError("records", "0 of 9 used", "at least one record whose weave the fit finds")

    monkeypatch.setattr("bikerider.gap.diagnosis.result.diagnose", no_record_used)  # run_trial imports it late
    models = {"riderless": load_model(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt")}
    effect = next(e for e in V.CALIBRATION_EFFECTS if e.name == "steer_damping")
    trial = V.run_trial(models, effect, 0)
    assert trial.verdict == "no record used" and trial.n_measured == 0 and trial.method == "records"
    assert trial.reference == {k: trial.truth[k] for k in effect.sizes} and not trial.fitted


def test_a_record_the_amplitudes_cannot_batch_is_skipped_not_fatal():
    # a record whose clock still jitters keeps no inferred steer-rate amplitude (NaN) and stops nothing; the
    # others keep their places; without being asked to skip, the batching names the record
    from bikerider.errors import FitError
    from bikerider.gap.inference.timedomain import make_batches

    t = np.arange(0.0, 2.0, 0.01)
    jitter = t + np.where(np.arange(t.size) % 2, 0.002, 0.0)
    records = [
        SimpleNamespace(name=name, time=time, signals={"roll_rate": np.sin(7 * time)})
        for name, time in (("a", t), ("jitter", jitter), ("b", t))
    ]
    batches = make_batches(records, skip_nonuniform=True)
    assert [idx for idx, _ in batches] == [[0, 2]]
    with pytest.raises(FitError, match="jitter: the time-domain fit needs uniformly sampled records"):
        make_batches(records)
    assert Priors({}, np.array([0.5, np.nan])).steer_rate_amplitude() == 0.5
