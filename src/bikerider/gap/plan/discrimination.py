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
from bikerider.gap.plan.allocation import MAX_DISTINCT, Hypothesis, allocate

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


def rank(plan) -> list[dict]:
    """Every experiment of ``plan`` (a :class:`bikerider.gap.plan.ranking.NextExperiment`, unranked), best
    first: by its smallest resolution probability over the pairs at the plan's number of runs, then by its
    smallest ``d``; with the runs each needs for 95 % and the limit of endless runs."""
    counts = np.arange(1, MAX_REPEATS + 1)
    d_all = np.stack([plan.separation(float(k)) for k in counts])  # (repeats, pairs, 2, points)
    prob_all = resolution_probability(d_all).mean(axis=2)  # (repeats, pairs, points)
    worst = prob_all.min(axis=1)  # (repeats, points)
    at = plan.repeats - 1
    limit = plan.probability(math.inf).min(axis=0)
    order = np.lexsort((-d_all[at].min(axis=(0, 1)), -worst[at]))
    ranked = []
    for m in order:
        e = plan.experiments[m]
        enough = np.flatnonzero(worst[:, m] >= 0.95)
        ranked.append(
            {
                "experiment": e,
                "text": e.describe(plan.repeats),
                "text_for_95": e.describe(int(counts[enough[0]])) if enough.size else None,
                "resolution_probability": float(worst[at, m]),
                "decays_for_95": int(counts[enough[0]]) if enough.size else None,
                "limit": float(limit[m]),
                "pairs": [
                    {
                        "rivals": [plan.rivals[i].name, plan.rivals[j].name],
                        "separation": [float(d_all[at, k, 0, m]), float(d_all[at, k, 1, m])],
                        "expected_log_likelihood_ratio": [
                            float(d_all[at, k, 0, m] ** 2 / 2),
                            float(d_all[at, k, 1, m] ** 2 / 2),
                        ],
                        "resolution_probability": float(prob_all[at, k, m]),
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
    if plan.own_factor is None or plan.sweep_factor is None:
        return None
    hypotheses = []
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
            hypotheses.append(h)
    found = allocate(hypotheses, budget, target)
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
