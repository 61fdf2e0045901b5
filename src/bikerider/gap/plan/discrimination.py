"""Discrimination between rivals: the expected log-likelihood ratio of new runs, the odds it gives, and the
ranking of experiments by them (the measure of :mod:`bikerider.gap.plan.ranking`'s module docstring).

Pure functions of arrays: the rivals' predictions, their own covariance and the runs' noise in, the
separations, probabilities and the ranked list out.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtr

from bikerider.gap.inference.problem import EffectFit
from bikerider.gap.plan.allocation import MAX_DISTINCT, Hypothesis, allocate, repeated_probability

STATED = {"decay": "combined", "sweep": "gaussian"}
"""The resolution probability ``--next`` states for runs of one experiment, per kind of experiment:
``"combined"``, the plan's measure of runs combined, both rivals' predictive distributions simulated
(:func:`combined_probability`), or ``"gaussian"``, the approximation :func:`gaussian_probability` (the rivals'
difference of means weighed by the true rival's covariance).  The closed loop (docs/gap_validation.md part 5,
*Honest odds with both rivals' distributions*), scoring the probability of ``k`` runs at ``k`` runs: for decays
the combined measure's Brier score 0.142 against the approximation's 0.193 with the parameters' error shared by
the runs as the diagnosis counts it (43.6 stated at 10 runs for 43 of 89 ties resolved; the approximation 30.1),
0.179 against 0.174 with it counted per run; for multisines 0.265 against 0.162 and 0.312 against 0.152 (the
friction and passive-arms rivals' multisines, whose runs often no rival describes, stated 0.88 and resolved
0.39-0.49), so multisines keep the approximation."""
DEFAULT_REPEATS = 10
MAX_REPEATS = 100
ODDS = 19.0
"""Odds a resolution needs: 95 % posterior probability from even prior odds."""


def separation(plan, repeats: float) -> np.ndarray:
    """``d`` of every pair of ``plan`` at every experiment for ``repeats`` runs each, ``(n_pairs, 2, n_points)``:
    with the pair's first rival true, and with its second (``math.inf`` repeats: the limit the true
    rival's own uncertainty sets)."""
    out = []
    for i, j in plan.pairs:
        both = []
        for true in (i, j):
            misfit = plan.rivals[true].misfit
            decays = distance(
                split_last(plan.mean[i] - plan.mean[j]),
                plan.own_cov[true],
                plan.data_cov + plan.model_cov,
                misfit,
                repeats,
                kick_noise(plan, true),
            )
            sweeps = distance(
                split_last_k(plan.sweep_mean[i] - plan.sweep_mean[j]),
                plan.sweep_own[true],
                plan.sweep_data + plan.sweep_model,
                misfit,
                repeats,
            )
            both.append(np.concatenate([decays, sweeps]))
        out.append(both)
    return np.array(out)


def split_last(z: np.ndarray) -> np.ndarray:
    """Complex ``(...)`` to real ``(..., 2)``: real and imaginary part."""
    return np.stack([z.real, z.imag], axis=-1)


def split_last_k(z: np.ndarray) -> np.ndarray:
    """Complex ``(..., K)`` to real ``(..., 2 K)``: real parts, then imaginary parts."""
    z = np.asarray(z)
    return np.concatenate([z.real, z.imag], axis=-1)


def kick_noise(plan, true: int) -> np.ndarray | float:
    """One decay's variance from the kick's unknown initial steer rate with rival ``true`` true, ``(n, 2, 2)``
    (the plan's ``kick_cov``; 0 for a plan without it)."""
    kick = getattr(plan, "kick_cov", None)
    return 0.0 if kick is None else kick[true]


def form_noise(plan, true: int) -> np.ndarray | float:
    """A friction rival's spread over the corner of its friction law with rival ``true`` true, ``(n, 2, 2)``
    (the plan's ``form_cov``, part of its ``own_cov``; systematic; 0 for a plan without it)."""
    form = getattr(plan, "form_cov", None)
    return 0.0 if form is None else form[true]


def distance(delta, own, noise, misfit: float, repeats: float, kick=0.0) -> np.ndarray:
    """``d`` per experiment: ``delta (n, m)`` the rivals' difference, ``own (n, m, m)`` the true rival's own
    covariance, ``noise (n, m, m)`` one run's (data plus parameters), ``misfit`` the true rival's, ``kick``
    one run's variance of the true rival's prediction from the kick (:func:`kick_noise`)."""
    if not len(delta):
        return np.zeros(0)
    # the true rival's own uncertainty, and its misfit on held-out data (systematic: more runs do not
    # average it away), then the runs' noise, the parameters' and the kick's, per run
    S = own + misfit * noise
    if math.isfinite(repeats):
        S = S + (noise + kick) / repeats
    # a difference no uncertainty covers (a rival of one fitted value, endless runs): resolved
    size = np.trace(S, axis1=-2, axis2=-1)[..., None, None]
    S = S + (1e-9 * size + 1e-30) * np.eye(S.shape[-1])
    x = np.linalg.solve(S, delta[..., None])[..., 0]
    return np.sqrt(np.maximum(np.sum(delta * x, axis=-1), 0.0))


def secants(fit: EffectFit, predict) -> tuple[np.ndarray, np.ndarray]:
    """Slopes ``(m, p)`` of ``predict(X (P, p)) -> (P, m)`` in a rival's fitted values, and the values'
    covariance they carry.

    The fit's covariance, each value's spread at most that of a value anywhere in its range; slopes by
    secants over +-1 standard deviation kept inside the search bounds (a tyre's relaxation length or an
    inertia stepped below zero would be no model at all), so not by the engine's central differences.
    """
    X, width, cov = secant_points(fit)
    return secant_slopes(predict(X), width), cov


def secant_points(fit: EffectFit) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ``2 p`` fitted-value vectors of :func:`_secants` (each value up, then down), the secants'
    widths and the values' covariance."""
    span = (fit.upper - fit.lower) / math.sqrt(12)
    cov = bounded_covariance(fit, span)
    sigma = np.sqrt(np.diag(cov))
    h = np.where(sigma > 0, sigma, 1e-6 * np.maximum(span, 1.0))
    up = np.minimum(fit.values + h, fit.upper)
    down = np.maximum(fit.values - h, fit.lower)
    X = np.repeat(fit.values[None, :], 2 * fit.values.size, axis=0)
    for j in range(fit.values.size):
        X[2 * j, j], X[2 * j + 1, j] = up[j], down[j]
    width = np.where(up > down, up - down, np.inf)
    return X, width, cov


def secant_slopes(pred: np.ndarray, width: np.ndarray) -> np.ndarray:
    """Slopes ``(m, p)`` from the predictions ``(2 p, m)`` at :func:`_secant_points`."""
    return ((pred[0::2] - pred[1::2]) / width[:, None]).T


def bounded_covariance(fit: EffectFit, span: np.ndarray) -> np.ndarray:
    """The fitted values' covariance (or their standard errors' squares), each value's standard deviation
    capped at ``span`` (the spread of a value anywhere in its search range), correlations kept.

    A friction fit's share from the law's corner (``fit.corner_covariance``) is left out: the plan predicts a
    friction rival at each corner itself (:func:`bikerider.gap.plan.decays.smoothing_nodes`, the multisines'
    friction form), and counting the corner's move of the fitted values as well would count it twice."""
    stderr = np.where(np.isfinite(fit.stderr), fit.stderr, np.inf)
    cov = fit.covariance
    if cov is not None and fit.corner_covariance is not None and fit.corner_covariance.shape == cov.shape:
        cov = cov - fit.corner_covariance
    if cov is None or cov.shape != (stderr.size, stderr.size) or not np.all(np.isfinite(cov)):
        cov = np.diag(np.where(np.isfinite(stderr), stderr, 0.0) ** 2)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    target = np.minimum(np.where(np.isfinite(stderr), sd, np.inf), span)
    scale = np.where(sd > 0, target / np.where(sd > 0, sd, 1.0), 0.0)
    out = cov * scale[:, None] * scale[None, :]
    fill = ~np.isfinite(stderr) | (sd == 0) & (stderr > 0)
    out[fill, :], out[:, fill] = 0.0, 0.0
    out[fill, fill] = span[fill] ** 2
    return out


def resolution_probability(d: np.ndarray) -> np.ndarray:
    """``Phi(d / 2 - ln(ODDS) / d)``: the new data favour the true rival by :data:`ODDS` to 1 or more."""
    d = np.asarray(d, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(d > 0, d / 2 - math.log(ODDS) / np.where(d > 0, d, 1.0), -np.inf)
    return ndtr(z)


def gaussian_probability(plan, repeats: float) -> np.ndarray:
    """The Gaussian approximation ``Phi(d / 2 - ln(ODDS) / d)`` of every pair's resolution probability at every
    experiment, ``(n_pairs, n_points)`` (the mean over which rival is true), ``d`` of :func:`separation`: the
    rivals' difference of means weighed by the true rival's covariance alone.  Fast, and what :func:`rank`
    orders the experiments by; the probability the plan states is :func:`stated_probability`."""
    return resolution_probability(separation(plan, repeats)).mean(axis=1)


def stated_probability(plan, repeats: float, found: list[Hypothesis] | None = None) -> np.ndarray:
    """The probability the plan states that ``repeats`` runs of one experiment favour the true rival by
    :data:`ODDS` to 1 or more, for every pair at every experiment, ``(n_pairs, n_points)``: by :data:`STATED`
    for the experiment's kind, :func:`combined_probability` (decays) or :func:`gaussian_probability`
    (multisines); ``found``: the plan's :func:`hypotheses`, when already built."""
    out = gaussian_probability(plan, repeats)
    combined = _combined_columns(plan)
    if combined.any():
        out = np.where(combined[None, :], combined_probability(plan, repeats, found, only=combined), out)
    return out


def _combined_columns(plan) -> np.ndarray:
    """Which experiments of ``plan`` state the combined measure (:data:`STATED`), ``(n_points,)`` booleans."""
    return np.array([STATED.get(e.kind) == "combined" for e in plan.experiments], dtype=bool)


def combined_probability(
    plan, repeats: float, found: list[Hypothesis] | None = None, only: np.ndarray | None = None
) -> np.ndarray:
    """The probability that ``repeats`` runs of one experiment favour the true rival by :data:`ODDS` to 1 or
    more by the plan's measure of runs combined, for every pair at every experiment, ``(n_pairs, n_points)``.

    The plan's own measure of runs combined (:func:`combine`), for ``repeats`` runs of each experiment alone:
    under each rival of a pair taken true (even prior odds), the runs' mean drawn from the true rival's
    predictive distribution (its fitted values' uncertainty, the runs' noise and the kick's spread over
    ``repeats``, its held-out misfit systematic), the exact log Bayes factor of the true rival's predictive
    density against the other rival's counted against ``ln(ODDS)``
    (:func:`~bikerider.gap.plan.allocation.repeated_probability`: :data:`~bikerider.gap.plan.allocation.DRAWS`
    draws per rival, a fixed seed, the same draws at every experiment, so the same value on every call and
    smooth in speed).

    Both rivals' distributions count, not their means alone: a rival much vaguer than the other puts little
    density where the sharp one predicts, so a run near the sharp rival's prediction favours it even when the
    two means coincide.  The Gaussian ``d`` of :func:`separation` weighs the difference of means by the true
    rival's covariance only and cannot see this: in the closed loop's seed 7050 (``steer_inertia`` against
    ``passive_arms``, means apart by (0.004, 0.018) 1/s, own standard deviations (0.014, 0.012) against (0.15,
    0.20)) it gave one decay 0.006 while one decay took the posterior to 0.984 (this measure: 0.79); over the
    loop's stored ties it was underconfident below 0.6 (0.12 stated, 0.32-0.44 resolved at ``k`` runs).
    ``--next`` states this measure for decays, not for multisines (:data:`STATED`: the same loop found it far
    overconfident there).

    Parameters
    ----------
    plan : bikerider.gap.plan.ranking.NextExperiment
        A plan with its rivals' own-uncertainty factors (else the Gaussian approximation,
        :func:`gaussian_probability`, is returned).
    repeats : float
        Runs of each experiment; ``math.inf`` for the limit of endless runs.
    found : list of Hypothesis, optional
        The plan's :func:`hypotheses`, when already built (else built here).
    only : ndarray of bool, optional
        The experiments to simulate (``(n_points,)``; the others 0): those that state this measure.

    Returns
    -------
    ndarray
        ``(n_pairs, n_points)``, the experiments in the order of ``plan.experiments``.
    """
    found = hypotheses(plan) if found is None else found
    if not found or not found[0].groups:
        return gaussian_probability(plan, repeats)
    return repeated_probability(found, repeats, only=only)


def runs_for(plan, target: float = 0.95, found: list[Hypothesis] | None = None) -> np.ndarray:
    """The fewest runs of each experiment alone (at most :data:`MAX_REPEATS`) whose :func:`stated_probability`,
    the smallest over the pairs, reaches ``target``, ``(n_points,)``; 0 where :data:`MAX_REPEATS` do not.

    The Gaussian approximation at every count; the combined measure by bisection over the number of runs (the
    probability rises with the runs; the returned count reaches the target and one run fewer does not).
    ``found``: the plan's :func:`hypotheses`, when already built."""
    each = np.stack([gaussian_probability(plan, float(k)).min(axis=0) for k in range(1, MAX_REPEATS + 1)])
    reached = each >= target
    gaussian = np.where(reached.any(axis=0), np.argmax(reached, axis=0) + 1, 0)
    combined = _combined_columns(plan)
    if combined.any() and found is None:
        found = hypotheses(plan)
    n = len(plan.experiments)
    if not combined.any() or not found or not found[0].groups:
        return gaussian

    def worst(k):
        return repeated_probability(found, k, only=combined).min(axis=0)

    hi = np.full(n, MAX_REPEATS)
    ok = worst(hi.astype(float)) >= target
    lo = np.zeros(n, int)  # probability below target (none at no runs)
    while np.any(ok & (hi - lo > 1)):
        mid = np.where(ok & (hi - lo > 1), (lo + hi) // 2, hi)
        up = worst(mid.astype(float)) >= target
        move = ok & (hi - lo > 1)
        hi = np.where(move & up, mid, hi)
        lo = np.where(move & ~up, mid, lo)
    return np.where(combined, np.where(ok, hi, 0), gaussian)


def rank(plan) -> list[dict]:
    """Every experiment of ``plan`` (a :class:`bikerider.gap.plan.ranking.NextExperiment`, unranked), best
    first, with the probability it states (:func:`stated_probability`) at the plan's number of runs, the runs
    each needs for 95 % (:func:`runs_for`) and the limit of endless runs.

    Ordered by the Gaussian approximation (:func:`gaussian_probability`: its smallest over the pairs at the
    plan's number of runs, then the smallest ``d``); the probabilities stated for decays are simulated
    (:data:`STATED`), so a list ordered by the approximation may state a higher probability below a lower one."""
    d_at = plan.separation(float(plan.repeats))  # (pairs, 2, points)
    gauss = resolution_probability(d_at).mean(axis=1).min(axis=0)
    found = hypotheses(plan) if _combined_columns(plan).any() else None  # built once for the three below
    stated = stated_probability(plan, float(plan.repeats), found)  # (pairs, points)
    worst = stated.min(axis=0)
    limit = stated_probability(plan, math.inf, found).min(axis=0)
    need = runs_for(plan, found=found)
    order = np.lexsort((-d_at.min(axis=(0, 1)), -gauss))
    ranked = []
    for m in order:
        e = plan.experiments[m]
        ranked.append(
            {
                "experiment": e,
                "text": e.describe(plan.repeats),
                "text_for_95": e.describe(int(need[m])) if need[m] else None,
                "resolution_probability": float(worst[m]),
                "decays_for_95": int(need[m]) if need[m] else None,
                "limit": float(limit[m]),
                "pairs": [
                    {
                        "rivals": [plan.rivals[i].name, plan.rivals[j].name],
                        "separation": [float(d_at[k, 0, m]), float(d_at[k, 1, m])],
                        "expected_log_likelihood_ratio": [
                            float(d_at[k, 0, m] ** 2 / 2),
                            float(d_at[k, 1, m] ** 2 / 2),
                        ],
                        "resolution_probability": float(stated[k, m]),
                    }
                    for k, (i, j) in enumerate(plan.pairs)
                ],
            }
        )
    return ranked


def combine(plan, budget: int = MAX_REPEATS, target: float = 0.95) -> dict | None:
    """Runs spread over the experiments of ``plan`` (:mod:`bikerider.gap.plan.allocation`): the greedy
    allocation of at most ``budget`` runs until the worst pair's resolution probability reaches ``target``.

    Every pair, each of its rivals true with even odds, the odds :data:`ODDS`; per experiment the rivals'
    difference of means, their own uncertainty's factors (one set of fitted values for every experiment),
    one run's noise (data plus the nominal parameters', and the true rival's spread over the kick's unknown
    initial steer rate) and, systematic, the true rival's misfit on held-out
    data times that noise (and for a friction rival's multisines the friction law's form).  ``None`` when the
    plan holds no factors (made otherwise than by :func:`~bikerider.gap.plan.ranking.plan_next`).

    Returns
    -------
    dict or None
        ``runs`` (the total), ``probability``, ``reached`` (``probability >= target``), ``budget``, ``distinct``
        (the most experiments a combination spreads over),
        ``experiments`` (each with ``runs``, ``kind``, ``speed``, ``law``, ``signal``, ``text``) and ``text``
        (the combination in words, e.g. ``"5 decays at 3.00 m/s under none and 5 decays at 6.00 m/s under
        none"``).
    """
    found = hypotheses(plan)
    if found is None:
        return None
    found = allocate(found, budget, target)
    experiments = plan.experiments
    chosen = [(int(m), int(found.counts[m])) for m in np.argsort(-found.counts, kind="stable") if found.counts[m] > 0]
    return {
        "runs": found.runs,
        "probability": found.probability,
        "reached": found.probability >= target,
        "budget": int(budget),
        "distinct": MAX_DISTINCT,
        "experiments": [
            {
                "runs": n,
                "kind": experiments[m].kind,
                "speed": experiments[m].speed,
                "law": experiments[m].law,
                "signal": experiments[m].signal,
                "text": experiments[m].describe(n),
            }
            for m, n in chosen
        ],
        "text": " and ".join(experiments[m].describe(n) for m, n in chosen),
    }


def hypotheses(plan) -> list[Hypothesis] | None:
    """Every pair of ``plan``, each of its rivals taken true, as :mod:`bikerider.gap.plan.allocation` takes them
    (:class:`~bikerider.gap.plan.allocation.Hypothesis`): weight 1/2 (even prior odds), the log odds
    ``ln(ODDS)`` the runs must give, and per group (the decays, the multisines) the rivals' difference of means,
    the true rival's and the other's own-uncertainty factors, one run's noise (data plus the nominal
    parameters', and the true rival's spread over the kick's initial steer rate) and, systematic, the true
    rival's misfit on held-out data times that noise (and a friction rival's form of its friction law).
    ``None`` when the plan holds no factors (made otherwise than by :func:`~bikerider.gap.plan.ranking.plan_next`).
    """
    if getattr(plan, "own_factor", None) is None or getattr(plan, "sweep_factor", None) is None:
        return None
    out = []
    for k, (i, j) in enumerate(plan.pairs):
        for true, other in ((i, j), (j, i)):
            misfit = plan.rivals[true].misfit
            h = Hypothesis(k, 0.5, math.log(ODDS))
            if len(plan.points):
                noise = plan.data_cov + plan.model_cov
                h.groups.append(
                    (
                        split_last(plan.mean[true] - plan.mean[other]),
                        plan.own_factor[true],
                        plan.own_factor[other],
                        noise + kick_noise(plan, true),
                        misfit * noise + form_noise(plan, true),
                    )
                )
            if len(plan.sweeps):
                noise = plan.sweep_data + plan.sweep_model
                h.groups.append(
                    (
                        split_last_k(plan.sweep_mean[true] - plan.sweep_mean[other]),
                        plan.sweep_factor[true],
                        plan.sweep_factor[other],
                        noise,
                        misfit * noise + plan.sweep_form[true],
                    )
                )
            out.append(h)
    return out


def item_dict(item: dict) -> dict:
    """A ranked item, JSON-ready."""
    e = item["experiment"]
    return {
        "kind": e.kind,
        "text": item["text"],
        "text_for_95": item["text_for_95"],
        "speed": e.speed,
        "law": e.law,
        "signal": e.signal,
        "push": e.push,
        **({"torque": e.torque, "run_time": e.run_time, "lines": list(e.lines)} if e.kind == "sweep" else {}),
        "resolution_probability": item["resolution_probability"],
        "decays_for_95": item["decays_for_95"],
        "limit": item["limit"],
        "pairs": item["pairs"],
    }
