"""Runs spread over experiments (issue 25): a tie no experiment repeated breaks, but runs combined do."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bikerider.gap.plan import allocation as A
from bikerider.gap.plan.decays import Experiment
from bikerider.gap.plan.discrimination import combine, distance, resolution_probability
from bikerider.gap.text import next_text

SIGMA = 0.05  # one run's noise of each number [1/s]


def _two_speed_plan(misfit: float = 0.0):
    """Rival A predicts the weave's decay rate 0.3 1/s faster than rival B at 3 and at 6 m/s.  Each has one
    fitted value of standard deviation 1 that moves its decay rate by 0.1 1/s: A's the same way at both
    speeds, B's in opposite ways.  At either speed alone the rivals' predictions differ by three of their
    own standard deviations, whichever runs (the same covariance for both: the odds of 19 to 1 are out of
    reach); at both speeds, how the two decay rates move together tells them apart."""
    points = (Experiment(3.0, "none"), Experiment(6.0, "none"))
    u = np.array([0.1, 0.0])
    factor_a = np.stack([u, u])[..., None]  # (points, 2, 1)
    factor_b = np.stack([u, -u])[..., None]
    noise = np.stack([np.eye(2) * SIGMA**2] * 2)
    mean_b = np.full(2, -1.0 + 3.0j)
    return SimpleNamespace(
        pairs=((0, 1),),
        rivals=(SimpleNamespace(misfit=misfit, name="a"), SimpleNamespace(misfit=misfit, name="b")),
        points=points,
        sweeps=(),
        experiments=list(points),
        mean=np.stack([mean_b - 0.3, mean_b]),
        own_cov=np.stack([np.einsum("nak,nbk->nab", f, f) for f in (factor_a, factor_b)]),
        own_factor=(factor_a, factor_b),
        sweep_factor=(np.zeros((0, 0, 1)), np.zeros((0, 0, 1))),
        data_cov=noise,
        model_cov=np.zeros_like(noise),
        sweep_mean=np.zeros((2, 0, 0), complex),
        sweep_data=np.zeros((0, 0, 0)),
        sweep_model=np.zeros((0, 0, 0)),
        sweep_form=np.zeros((2, 0, 0, 0)),
    )


def test_one_speed_repeated_never_tells_the_rivals_apart_both_speeds_do():
    plan = _two_speed_plan()
    # the plan's own measure of one experiment repeated 100 times: with B true, its own uncertainty covers the
    # difference, so the pair's probability (even odds over which is true) stays far below 95 %
    delta = np.array([[-0.3, 0.0]])
    for m in range(2):
        chance = [
            float(
                resolution_probability(distance(delta, plan.own_cov[t, m : m + 1], plan.data_cov[m : m + 1], 0, 100))[0]
            )
            for t in (0, 1)
        ]
        assert np.mean(chance) < 0.8
    found = combine(plan, budget=100)
    # not unbreakable: runs at both speeds reach the odds, and the recommendation names both speeds
    assert found["reached"] and found["probability"] >= 0.95
    speeds = sorted(e["speed"] for e in found["experiments"])
    assert speeds == [3.0, 6.0]
    assert all(e["runs"] >= 1 for e in found["experiments"]) and found["runs"] <= 100
    assert "at 3.00 m/s" in found["text"] and "at 6.00 m/s" in found["text"]


def test_the_combination_reaches_the_odds_only_with_both_speeds():
    plan = _two_speed_plan()
    found = combine(plan, budget=100)
    hyp = _hypotheses(plan)
    n = found["runs"]
    for alone in ([n, 0], [0, n], [100, 0], [0, 100]):
        assert A.probability(hyp, alone) < 0.8 and A.simulated_probability(hyp, alone) < 0.8
    counts = [e["runs"] for e in sorted(found["experiments"], key=lambda e: e["speed"])]
    assert A.simulated_probability(hyp, counts, seed=1) >= 0.95


def _hypotheses(plan):
    out = []
    for true, other in ((0, 1), (1, 0)):
        h = A.Hypothesis(0, 0.5, math.log(19.0))
        noise = plan.data_cov
        delta = (plan.mean[true] - plan.mean[other]).real[:, None] * np.array([1.0, 0.0])
        h.groups.append((delta, plan.own_factor[true], plan.own_factor[other], noise, np.zeros_like(noise)))
        out.append(h)
    return out


def test_the_divergence_is_the_gaussians_kullback_leibler_divergence():
    rng = np.random.default_rng(3)
    m, n = 2, 3
    delta = rng.normal(size=(n, m))
    ut, uo = rng.normal(size=(n, m, 2)), rng.normal(size=(n, m, 1))
    noise = np.stack([np.diag(rng.uniform(0.5, 1.5, m)) for _ in range(n)])
    h = A.Hypothesis(0, 1.0, 0.0, [(delta, ut, uo, noise, np.zeros_like(noise))])
    counts = np.array([1.0, 2.0, 4.0])
    a, b, G = (np.sum(x, axis=0) for x in A._all(h, counts))
    got = float(A.divergence(a, b, G, 2))
    # stacked, directly
    D = np.zeros((n * m, n * m))
    for e in range(n):
        D[e * m : (e + 1) * m, e * m : (e + 1) * m] = noise[e] / counts[e]
    UT, UO = ut.reshape(n * m, 2), uo.reshape(n * m, 1)
    St, So = D + UT @ UT.T, D + UO @ UO.T
    d = delta.ravel()
    want = (
        np.trace(np.linalg.solve(So, St))
        - n * m
        + np.linalg.slogdet(So)[1]
        - np.linalg.slogdet(St)[1]
        + d @ np.linalg.solve(So, d)
    )
    assert got == pytest.approx(want, rel=1e-9)


def test_a_hopeless_tie_stays_unbreakable_and_the_text_says_so():
    plan = _two_speed_plan()
    # the rivals predict the same with the same uncertainty: nothing, at any speed or spread, tells them apart
    plan.own_factor = (plan.own_factor[1], plan.own_factor[1])
    plan.mean = np.stack([plan.mean[1], plan.mean[1]])
    found = combine(plan, budget=100)
    assert not found["reached"] and found["probability"] < 0.05
    result = {
        "rivals": [{"effects": ["a"]}, {"effects": ["b"]}],
        "rivals_rule": "named",
        "measure": "m",
        "noise": {"note": "n", "signals": {}},
        "plan": [
            {
                "text": "10 decays at 3.00 m/s under none",
                "text_for_95": None,
                "decays_for_95": None,
                "resolution_probability": 0.0,
                "limit": 0.0,
                "pairs": [],
            }
        ],
        "best_per_law": {},
        "left_out": [],
        "max_repeats": 100,
        "combined": found,
    }
    assert "unbreakable" in next_text(result)
    result["combined"] = combine(_two_speed_plan(), budget=100)
    text = next_text(result)
    assert "runs combined do" in text and "3.00 m/s" in text and "6.00 m/s" in text
