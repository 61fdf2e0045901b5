"""The closed-loop harness (validation.loop): its pieces checked against what they stand for."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import bikerider
from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.plan.sweeps import Sweep, lines_for, response
from bikerider.io.gap_model import load_model
from validation import cases as V
from validation import loop as L

BP = Path(bikerider.__file__).parent / "data" / "bicycleparameters"


def test_run_by_run_evidence_is_the_joint_marginal_likelihood():
    """The Kalman steps of a linearised rival add up to the log density of all runs at once under the
    rival's prior (the runs share its uncertain values, so they are not independent)."""
    rng = np.random.default_rng(1)
    p, n_exp = 3, 4
    mean = [rng.standard_normal(2) for _ in range(n_exp)]
    jac = [rng.standard_normal((2, p)) for _ in range(n_exp)]
    A = rng.standard_normal((p, p))
    prior = A @ A.T + 0.1 * np.eye(p)
    rival = L.LinearRival(mean, jac, prior)
    chosen = [0, 2, 2, 3, 1]
    ys, Rs = [], []
    for e in chosen:
        y, R = rng.standard_normal(2), np.diag(rng.uniform(0.1, 0.5, 2))
        rival.update(e, y, R)
        ys.append(y)
        Rs.append(R)
    mu = np.concatenate([mean[e] for e in chosen])
    J = np.concatenate([jac[e] for e in chosen])
    S = J @ prior @ J.T
    for k, R in enumerate(Rs):
        S[2 * k : 2 * k + 2, 2 * k : 2 * k + 2] += R
    r = np.concatenate(ys) - mu
    expected = -0.5 * (r @ np.linalg.solve(S, r) + np.linalg.slogdet(S)[1] + r.size * np.log(2 * np.pi))
    assert rival.log_evidence == pytest.approx(expected, rel=1e-10)


def test_lack_of_fit_downweights_a_run_every_rival_misses():
    rivals = [L.LinearRival([np.zeros(2)], [np.zeros((2, 1))], np.eye(1)) for _ in range(2)]
    R = np.eye(2) * 0.01
    assert L.lack_of_fit(rivals, 0, np.array([0.05, -0.05]), R) == 1.0
    assert L.lack_of_fit(rivals, 0, np.array([1.0, 1.0]), R) == pytest.approx(100.0)


def test_even_order_takes_the_laws_in_turn_and_spreads_the_speeds():
    points = [SimpleNamespace(law=law, speed=v) for law in ("a", "b") for v in np.linspace(3, 9, 12)]
    order = L._even_order(SimpleNamespace(points=points), 8)
    assert [points[e].law for e in order] == ["a", "b"] * 4
    speeds = sorted(points[e].speed for e in order if points[e].law == "a")
    assert speeds[0] < 5 and speeds[-1] > 7 and len(set(speeds)) == 4


def test_figure_of_merit_counts_unresolved_as_more_than_any():
    med, p90 = L.figure_of_merit([2, 3, None, 4, None])
    assert med == 4 and p90 == np.inf


def test_truth_multisine_reads_the_frequency_response(monkeypatch):
    """The truth's multisine run, with no effect, the nominal values and no sensor noise, gives the nominal
    model's frequency response (two independent implementations: Meijaard's Appendix A by hand and the
    candidates' model), up to what a settling time of five of the capsize's time constants leaves of the
    start."""
    monkeypatch.setattr(L, "GYRO_NOISE", 0.0)
    monkeypatch.setattr(L, "STEER_NOISE", 0.0)
    model = load_model(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt")
    rng = np.random.default_rng(3)
    simulator = V.TruthSimulator(model, V.TRUTHS["null"], rng)
    simulator.values = {k: float(model.parameters.values[k]) for k in simulator.values}
    speed, gains = 6.0, np.zeros(4)  # uncontrolled: every mode decays there (the capsize at -0.08/s)
    nominal = EffectModel(dict(model.parameters.values), model.geometry)
    ss = nominal.state_space([speed])
    A, b = ss.closed_loop(gains[None, :])[0], ss.B[0, :, 1]
    weave = np.linalg.eigvals(A)
    hz = float(weave.imag.max()) / (2 * np.pi)
    for output, index in (("roll_rate", ss.output_states[2]), ("steer_angle", ss.output_states[1])):
        sweep = Sweep(speed, "control", output, 0.5, 10.0, lines_for(hz, 10.0))
        H = L.multisine_run(simulator, speed, gains, sweep, rng, settle=60.0)
        expected = response(A, b, index, sweep.omegas)
        assert np.max(np.abs(H - expected)) < 0.02 * np.max(np.abs(expected)), (output, H, expected)
