"""The next single run of ``--next`` (``bikerider.gap.plan.sequential``) is the closed loop's first
Jensen-Renyi choice (``validation.loop``), and multisines predicted to lean too far are left out
(``bikerider.gap.plan.sweeps.peak_roll``)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from gap_support import BP
from scipy.integrate import solve_ivp

from bikerider.gap.plan import criteria as C
from bikerider.gap.plan import sequential
from bikerider.gap.plan.ranking import plan_next
from bikerider.gap.plan.sweeps import MAX_ROLL, Sweep, line_amplitude, lines_for, peak_roll
from bikerider.gap.text import next_text
from bikerider.io.gap_model import load_model
from validation import loop as L


@pytest.fixture(scope="module")
def tie():
    """A closed-loop case (``validation.loop``): tyre slip hidden, passive arms its rival, the Davis bicycle
    with rider, six decays near 6.5 m/s; the first of a few seeds the diagnosis ties, planned as the loop plans."""
    models = {
        "rider": load_model(
            BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt", BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
        )
    }
    scenario = next(s for s in L.SCENARIOS if s.label == "tyre_slip vs passive_arms (rider)")
    for seed in (7004, 7016, 7028, 7040):
        case = L.run_loop_case(models, scenario, seed, strategies=(), keep=True)
        if case["status"] == "loop":
            return case["_objects"]["runs"].plan
    raise AssertionError("none of the seeds gave a tie")


class _Chosen(Exception):
    pass


class _FirstRun:
    """The loop's truth runs, stopped at the first run a strategy asks for (which experiment it chose)."""

    shared = False

    def get(self, e, k):
        raise _Chosen(e)


def test_the_next_run_is_the_loops_first_jensen_renyi_choice(tie):
    plan = tie
    assert plan.sweeps and plan.points, "the tie's plan must hold decays and multisines"
    rivals = [L.linearise(plan, r) for r in plan.rivals]
    with pytest.raises(_Chosen) as chosen:
        L.run_strategy("plan:jensen_renyi", plan, rivals, _FirstRun(), truth_index=0, seed=0)
    assert plan.next_run["index"] == chosen.value.args[0]
    assert plan.experiments[plan.next_run["index"]].describe(1) == plan.next_run["text"]
    # and it is where the divergence is largest, above the experiments the loop scores lower
    loop = L._scores(plan, rivals, np.full(2, 0.5), "jensen_renyi", L._groups(plan))
    mine = sequential.scores(plan)
    assert mine == pytest.approx(loop, rel=1e-6, abs=1e-9)
    assert plan.next_run["divergence"] == pytest.approx(mine.max())
    assert 0 < plan.next_run["divergence"] <= math.log(2) + 1e-12 == pytest.approx(plan.next_run["bound"] + 1e-12)


def test_the_next_run_follows_the_rivals_weights(tie):
    """A rival already unlikely weighs little: the divergence falls (to nothing with one rival left)."""
    even = sequential.scores(tie)
    lopsided = sequential.scores(tie, weights=[0.95, 0.05])
    assert lopsided.max() < even.max()
    assert np.max(np.abs(sequential.scores(tie, weights=[1.0, 0.0]))) < 1e-9
    group = sequential.observations(tie)[0]
    index, means, own, noise = group
    assert even[index] == pytest.approx(C.jensen_renyi(means, own, noise))


def test_the_next_run_in_json_and_text(tie):
    out = json.loads(json.dumps(tie.as_dict()))
    nxt = out["next_run"]
    assert nxt["criterion"] == "jensen_renyi" and nxt["weights"] == {r.name: 0.5 for r in tie.rivals}
    assert nxt["rank"] is not None and 0 <= nxt["resolution_probability"] <= 1
    text = next_text(out)
    assert "Next run, one at a time: " + nxt["text"] in text and "run --next again" in text


def test_peak_roll_is_the_linear_loops_largest_lean():
    """Against the closed loop integrated in time (LSODA) from rest under the same multisine."""
    rng = np.random.default_rng(4)
    n = 4
    A = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [9.5, -3.0, -0.4, -0.9], [6.0, -25.0, 3.0, -3.5]])
    b = np.array([0.0, 0.0, -0.8, 6.0])
    lines = lines_for(0.8, 10.0)
    sweep = Sweep(5.0, "none", "roll_rate", 0.5, 10.0, lines)
    K = len(lines)
    phases = -math.pi * np.arange(1, K + 1) * np.arange(K) / K
    a = line_amplitude(lines, 0.5, 10.0)
    w = 2 * math.pi * np.asarray(lines)
    for shift in (-0.3, 0.05):  # a damped loop, and one whose slowest mode grows slower than the run
        A_s = A + shift * np.eye(n)
        settle = 7.0
        peak = peak_roll(A_s[None], b[None], 0, [sweep], [settle])[0]
        sol = solve_ivp(
            lambda t, x, A_s=A_s: A_s @ x + b * a * np.sum(np.cos(w * t + phases)),
            (0, settle + 10.0),
            np.zeros(n),
            max_step=0.005,
            rtol=1e-9,
            atol=1e-12,
        )
        assert peak == pytest.approx(np.max(np.abs(sol.y[0])), rel=0.03)
    assert rng is not None


def test_a_multisine_that_leans_too_far_is_left_out(tie):
    """With a larger torque more runs lean past the limit: those are left out with the reason, the others keep
    a predicted lean within it."""
    plan = plan_next(tie.diagnosis, rivals=[r.name for r in tie.rivals], repeats=10, torque=1.5)
    before = [x for x in tie.left_out if "would likely be lost" in x["reason"]]
    lost = [x for x in plan.left_out if "would likely be lost" in x["reason"]]
    assert len(lost) > len(before) and all("rad during its" in x["reason"] for x in lost)
    assert plan.sweep_roll.shape == (2, len(plan.sweeps)) and np.all(plan.sweep_roll <= MAX_ROLL)
    point = plan.as_dict()["points"][len(plan.points)]
    assert point["settle"] >= 5.0 and set(point["peak_roll"]) == {r.name for r in plan.rivals}
