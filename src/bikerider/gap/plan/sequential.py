"""The next single run: the experiment where the rivals' predictions of one run overlap least.

The ranked plan (:func:`~bikerider.gap.plan.discrimination.rank`) answers how many runs of one experiment
resolve the tie, and with what probability.  A researcher who records one run, adds it to the data and
plans again (the closed loop of issue 25) asks another question after every run: which single run next.
In the closed loop against hidden truths (``validation.loop``, docs/gap_validation.md part 5) the criterion
that answered it best, by the runs needed to resolve a tie, was the Jensen-Renyi divergence
(:func:`~bikerider.gap.plan.criteria.jensen_renyi`) of the rivals' predictive distributions of the run's
observation: rival ``i`` predicts ``N(mu_i, W_i + Sigma)``, ``mu_i`` its predicted weave eigenvalue (real
part and frequency) or frequency response (real parts, then imaginary parts at the lines), ``W_i`` its own
uncertainty (its fitted values' covariance through the secants), ``Sigma`` one run's noise and the nominal
parameters' uncertainty, as the plan counts them per run; the rivals weighted evenly (a tie: the
diagnosis leaves them even, as the plan's resolution probability does).

This module computes that choice from a :class:`~bikerider.gap.plan.ranking.NextExperiment` alone, in the
loop's order and with its tie-break (the first experiment of the largest divergence, decays before
multisines), so that ``--next`` names the run the loop's ``plan:jensen_renyi`` strategy takes first
(``tests/gap/plan/test_gap_next_run.py`` checks it against ``validation.loop``).
"""

from __future__ import annotations

import math

import numpy as np

from bikerider.gap.plan import criteria as C
from bikerider.gap.plan.sweeps import split

NEXT_CRITERION = "jensen_renyi"
"""The criterion the next single run follows (the closed loop's best, docs/gap_validation.md part 5)."""


def observations(plan) -> list[tuple[list[int], np.ndarray, np.ndarray, np.ndarray]]:
    """The rivals' predictive distributions of one run, per group of experiments with observations of one
    size (the decays; the multisines): the experiments' indices in ``plan.experiments``, the means
    ``(R, n, m)``, the rivals' own covariances ``(R, n, m, m)`` (a decay's with the rival's spread over the
    kick's initial steer rate) and one run's noise ``(n, m, m)``."""
    out = []
    n_points = len(plan.points)
    if n_points:
        means = np.stack([plan.mean.real, np.abs(plan.mean.imag)], axis=-1)
        # a rival's spread over the kick's unknown initial steer rate is its own, per run (kick_cov)
        own = plan.own_cov if plan.kick_cov is None else plan.own_cov + plan.kick_cov
        out.append((list(range(n_points)), means, own, plan.data_cov + plan.model_cov))
    if plan.sweeps:
        index = list(range(n_points, n_points + len(plan.sweeps)))
        out.append((index, split(plan.sweep_mean), plan.sweep_own, plan.sweep_data + plan.sweep_model))
    return out


def scores(plan, criterion: str = NEXT_CRITERION, weights=None) -> np.ndarray:
    """The criterion ``criterion`` (:data:`~bikerider.gap.plan.criteria.CRITERIA`) of one run at every
    experiment of ``plan``, ``(n_experiments,)`` in the order of ``plan.experiments`` (``weights``: the
    rivals' probabilities, even by default)."""
    out = np.full(len(plan.points) + len(plan.sweeps), -np.inf)
    for index, means, own, noise in observations(plan):
        out[index] = C.score(criterion, means, own, noise, weights)
    return out


def next_run(plan, weights=None) -> dict | None:
    """The next single run (module docstring), JSON-ready, or ``None`` when no experiment can be scored.

    Returns
    -------
    dict
        ``index`` (in ``plan.experiments``), ``kind``, ``text``, ``speed``, ``law``, ``signal``, ``push`` (and a
        multisine's ``torque``, ``run_time``, ``lines``), ``criterion``, ``divergence`` [nats] and its
        ``bound`` ``ln R`` (the rivals' predictions of one run apart), the ``weights``, the experiment's
        ``rank`` and ``resolution_probability`` of one run in the ranked plan, and ``instruction``.
    """
    s = scores(plan, NEXT_CRITERION, weights)
    if not s.size or not np.any(np.isfinite(s)):
        return None
    best = int(np.argmax(s))
    e = plan.experiments[best]
    R = len(plan.rivals)
    w = np.full(R, 1.0 / R) if weights is None else np.asarray(weights, float) / np.sum(weights)
    rank = next((k for k, item in enumerate(plan.plan, start=1) if item["experiment"] == e), None)
    single = float(plan.probability(1.0).min(axis=0)[best])
    return {
        "index": best,
        "kind": e.kind,
        "text": e.describe(1),
        "speed": e.speed,
        "law": e.law,
        "signal": e.signal,
        "push": e.push,
        **({"torque": e.torque, "run_time": e.run_time, "lines": list(e.lines)} if e.kind == "sweep" else {}),
        "criterion": NEXT_CRITERION,
        "divergence": float(s[best]),
        "bound": math.log(R),
        "weights": {r.name: float(x) for r, x in zip(plan.rivals, w)},
        "rank": rank,
        "resolution_probability": single,
        "instruction": (
            "record this one run, add it to the data (a manifest entry), and run --next again: the diagnosis, "
            "the rivals' fits and this choice update after every run"
        ),
    }
