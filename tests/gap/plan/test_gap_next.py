"""What to measure next (``bikerider gap --next``): the plan's numbers, its records path, the command, and
the blind check against runs spread evenly (``validation.plan_cases``)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from gap_support import BP, DATA, decay_record, nominal, riderless_model

from bikerider.cli import main
from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.diagnosis.result import diagnose
from bikerider.gap.measured.records import fit_records
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
from bikerider.gap.plan.ranking import ODDS, fit_residual, plan_next, resolution_probability, signal_noise
from bikerider.io.gap_model import load_model


@pytest.fixture(scope="module")
def riderless():
    return riderless_model()


_nominal = nominal


def _weave(model, effects, speed, gains=(0.0, 0.0, 0.0, 0.0)):
    """The weave eigenvalue: the Whipple bicycle's oscillating one, or the one nearest it with more modes."""
    gains = np.asarray(gains, float)
    ev = EffectModel(_nominal(model), model.geometry, {}).eigenvalues([speed], gains)[0]
    reference = ev[np.argmax(ev.imag)]
    ev = EffectModel(_nominal(model), model.geometry, effects).eigenvalues([speed], gains)[0]
    ev = ev[ev.imag > 0]
    return ev[np.argmin(np.abs(ev - reference))]


def _table(model, effects, speeds, groups, sigma=0.03, seed=0):
    """Weave eigenvalues of a linear model at ``speeds`` with noise ``sigma``, one group per entry of ``groups``."""
    rng = np.random.default_rng(seed)
    values = np.array([_weave(model, effects, v) for v in speeds])
    values = values + sigma * (rng.standard_normal(len(speeds)) + 1j * rng.standard_normal(len(speeds)))
    n = len(speeds)
    return EigenvalueData(
        np.array(speeds, float),
        values,
        np.full(n, sigma),
        np.full(n, sigma),
        np.zeros(n),
        ["weave"] * n,
        list(groups),
        np.zeros((n, 4)),
        [f"row {k}" for k in range(n)],
    )


TRUTH = {"steer_damping": {"c_steer": 0.3}}
RIVALS = ["steer_damping", "tyre_slip"]


@pytest.fixture(scope="module")
def table_plan(riderless):
    # a lab that ran at 6 m/s only: steer damping and tyre slip both fit its weave
    speeds = [6.0] * 9
    data = _table(riderless, TRUTH, speeds, ["a"] * 3 + ["b"] * 3 + ["c"] * 3)
    diagnosis = diagnose(riderless, data, CanonicalData.empty(), effects=tuple(RIVALS))
    return diagnosis, plan_next(diagnosis, rivals=RIVALS, speeds=np.linspace(3.0, 9.0, 13), repeats=5)


def test_the_probability_of_a_resolution():
    # Phi(d/2 - ln 19 / d): 1/2 where the expected log-likelihood ratio d^2/2 is ln 19, 0 without a difference
    assert resolution_probability(0.0) == 0.0
    assert resolution_probability(math.sqrt(2 * math.log(ODDS))) == pytest.approx(0.5)
    d = np.linspace(0.1, 8, 50)
    assert np.all(np.diff(resolution_probability(d)) > 0) and resolution_probability(8.0) > 0.99


def test_a_smoothed_signal_takes_its_noise_from_the_fit_residual():
    # A weave decay measured with white noise: the second differences' scatter finds the noise and the
    # record fit leaves about as much.  The same decay logged smoothed, with the slow drift of a fused
    # angle: its samples scatter far less than its error, and only the fit's residual shows that error.
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 2.5, 0.01)
    clean = 0.5 * np.exp(-1.5 * t) * np.sin(6.0 * t)
    noisy = clean + 0.01 * rng.standard_normal(t.size)
    assert signal_noise(noisy) == pytest.approx(0.01, rel=0.25)
    assert fit_residual(t, noisy) == pytest.approx(0.01, rel=0.25)
    drift = np.cumsum(0.004 * rng.standard_normal(t.size))
    smoothed = np.convolve(clean + drift, np.ones(5) / 5, mode="same")
    error = np.std((smoothed - clean)[5:-5])
    assert signal_noise(smoothed[5:-5]) < 0.2 * error
    assert fit_residual(t[5:-5], smoothed[5:-5]) > 5 * signal_noise(smoothed[5:-5])


def test_each_rival_predicts_its_own_weave(riderless, table_plan):
    diagnosis, plan = table_plan
    for k, name in enumerate(RIVALS):
        effects = {name: diagnosis.fit_of((name,)).config[name]}  # fitted and fixed values
        for m, e in enumerate(plan.points):
            assert plan.mean[k, m] == pytest.approx(_weave(riderless, effects, e.speed, plan.laws[e.law](e.speed)))


def test_the_plan_ranks_by_its_resolution_probability(table_plan):
    _, plan = table_plan
    best = plan.plan[0]
    m = plan.points.index(best["experiment"])
    d = plan.separation(plan.repeats)  # (pairs, which rival is true, points)
    # the probability stated is the plan's measure of runs combined (both rivals' distributions, simulated);
    # the order is its Gaussian approximation's
    assert best["resolution_probability"] == pytest.approx(float(plan.probability(plan.repeats)[:, m].min()))
    gaussian = [
        float(resolution_probability(d[:, :, plan.experiments.index(item["experiment"])]).mean(axis=1).min())
        for item in plan.plan
    ]
    assert gaussian == sorted(gaussian, reverse=True)
    # more decays separate more, towards the limit the true rival's own uncertainty sets
    assert np.all(plan.separation(plan.repeats + 5) >= d) and np.all(plan.separation(math.inf) >= d)
    n95 = best["decays_for_95"]
    assert n95 is not None
    assert plan.probability(n95)[:, m].min() >= 0.95
    assert n95 == 1 or plan.probability(n95 - 1)[:, m].min() < 0.95
    # the rivals agree where the data are and part away from them: the plan goes where they disagree
    assert abs(best["experiment"].speed - 6.0) > 1.0


def test_following_the_plan_resolves_the_tie(riderless, table_plan):
    diagnosis, plan = table_plan
    first = diagnosis.ranking[0]
    assert first["tied_with"], "the narrow data must leave the rivals tied"
    best = plan.plan[0]["experiment"]
    speeds = [6.0] * 9
    groups = ["a"] * 3 + ["b"] * 3 + ["c"] * 3

    def rediagnose(new_speeds):
        rows = _table(riderless, TRUTH, speeds + new_speeds, groups + ["new"] * len(new_speeds), seed=1)
        return diagnose(riderless, rows, CanonicalData.empty(), effects=tuple(RIVALS)).ranking[0]

    planned = rediagnose([best.speed] * plan.repeats)
    assert planned["effect"] == "steer_damping" and not planned["tied_with"]
    same = rediagnose([6.0] * plan.repeats)  # more of the same protocol
    assert same["tied_with"]


def test_the_numbers_in_json(table_plan):
    _, plan = table_plan
    out = json.loads(json.dumps(plan.as_dict()))
    assert [r["effects"] for r in out["rivals"]] == [["steer_damping"], ["tyre_slip"]]
    assert out["pairs"] == [["steer_damping", "tyre_slip"]]
    item = out["plan"][0]
    for key in ("text", "speed", "law", "signal", "resolution_probability", "decays_for_95", "limit", "pairs"):
        assert key in item
    pair = item["pairs"][0]
    assert pair["expected_log_likelihood_ratio"] == pytest.approx([x**2 / 2 for x in pair["separation"]])
    assert {"no control"} <= set(out["best_per_law"])
    assert len(out["points"]) == len(plan.points) and "data_sigma" in out["points"][0]
    assert "expected log-likelihood ratio" in out["measure"]


def test_bad_rivals_are_a_clear_error(table_plan):
    from bikerider.errors import InputError

    diagnosis, _ = table_plan
    with pytest.raises(InputError, match="rival = 'wobble'"):
        plan_next(diagnosis, rivals=["steer_damping", "wobble"])
    with pytest.raises(InputError, match="repeats"):
        plan_next(diagnosis, rivals=RIVALS, repeats=0)


def _record(model, speed, group, effects, seed, duration=1.8):
    initial = {"phid": 0.6, "deltad": 0.4, "delta": 0.03}
    return decay_record(model, speed, group, effects, seed=seed, duration=duration, steer_noise=2e-4, initial=initial)


@pytest.mark.slow
def test_records_are_planned_by_indirect_inference(riderless):
    # records under the SIL law: every experiment is a template decay fitted as a record, predicted by each
    # rival's own response; signals the records hold give their noise, the others are assumed
    records = [_record(riderless, v, f"{v} m/s", TRUTH, seed=k) for v in (3.0, 3.5, 4.0) for k in range(3)]
    d = diagnose(
        riderless, EigenvalueData.empty(), CanonicalData.empty(), effects=tuple(RIVALS), records=fit_records(records)
    )
    plan = plan_next(d, rivals=RIVALS, speeds=[2.0, 3.0, 4.0, 5.0, 6.0], repeats=10)
    out = plan.as_dict()
    assert out["noise"]["signals"]["roll_rate"]["value"] == pytest.approx(0.01, rel=0.2)
    assert "the data's records" in out["noise"]["signals"]["steer_angle"]["source"]
    assert "assumed" in out["noise"]["signals"]["steer_rate"]["source"]
    assert set(out["best_per_signal"]) <= {
        "roll_rate",
        "roll_angle",
        "steer_angle",
        "steer_rate",
        "frf_roll_rate",
        "frf_steer_angle",
    }
    assert {e.law for e in plan.points} <= {"sil", "sil x0.5", "sil x1.5", "no control"}
    # the riderless bicycle without control falls at these speeds: no decay the record fit accepts there
    assert not [e for e in plan.points if e.law == "no control" and e.speed <= 4.0]
    slow = [x for x in out["left_out"] if "decays at 2.00 m/s under no control" in x["experiment"]]
    assert len(slow) == 4 and all("no weave" in x["reason"] for x in slow)
    # nor a steady response to a steer-torque multisine
    (sweep,) = [x for x in out["left_out"] if x["experiment"] == "multisines at 2.00 m/s under no control"]
    assert "unstable" in sweep["reason"]
    # each template is predicted like a record: the nominal model that made it predicts its fit within the
    # fit's standard errors (the template carries the signals' noise, the model's response none)
    e = plan.points[0]
    template = plan.templates[e].estimate
    nominal = plan.simulator.subset([0]).apparent(_nominal(riderless), {})[0, 0]
    assert abs(nominal.real - template.eigenvalue.real) < 2 * template.real_sigma
    assert abs(nominal.imag - template.eigenvalue.imag) < 2 * template.imag_sigma


@pytest.mark.slow
def test_the_command_plans_the_next_experiment(tmp_path, capsys):
    args = ["gap", "--model", str(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt"), "--rider"]
    args += [str(BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt"), "--data"]
    args += [str(DATA / "gap_examples" / "eigenvalues.csv"), "--effects", "steer_damping,passive_arms,steer_inertia"]
    assert main(args + ["--next", "--next-speeds", "4:9:6", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["next"]["plan"] and out["next"]["repeats"] == 10
    assert main(args + ["--next", "--next-speeds", "4:9:6", "--report", str(tmp_path / "rep")]) == 0
    text = capsys.readouterr().out
    assert "Next experiment: to tell" in text and "Recommendation:" in text
    assert (tmp_path / "rep" / "next.png").stat().st_size > 10_000
    assert "## Next experiment" in (tmp_path / "rep" / "report.md").read_text()


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--next", "--next-speeds", "5:3"], "--next-speeds = '5:3'"),
        (["--next-between", "steer_damping,steer_inertia"], "--next as well"),
        (["--next", "--next-noise", "gyro=0.1"], "noise signal = 'gyro'"),
    ],
)
def test_bad_next_options_exit_2(capsys, extra, message):
    args = ["gap", "--model", str(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt"), "--data"]
    args += [str(DATA / "gap_examples" / "eigenvalues.csv"), "--effects", "steer_damping,steer_inertia"]
    assert main(args + extra) == 2
    assert message in capsys.readouterr().err


@pytest.mark.slow
def test_blind_check_follows_the_plan_with_an_independent_simulation():
    # rider lean hidden, measured between 6 and 7.2 m/s only: rider lean ties with tyre slip; ten runs
    # where the plan says (by the hand-typed Meijaard model, LSODA, noise and the record fit) resolve it
    from validation.plan_cases import run_next_case

    model = load_model(
        BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt", BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
    )
    case = run_next_case(model, "rider_lean", 501)
    assert case.tie and set(case.rivals) == {"rider_lean", "tyre_slip"}
    assert "no control" in case.planned and case.resolved_planned
    assert case.first_planned == "rider_lean"
