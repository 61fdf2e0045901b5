"""Runs spread over several experiments: the evidence of independent runs adds up (issue 25).

A tie that no experiment repeated breaks may still break when runs at several speeds, laws or signals
are combined: the runs at one speed pin a rival's fitted values, those at another then part the rivals.
Two rivals fitted to the same tie often predict the same at every experiment (both at the nominal
model, say), so the difference of their means alone sees nothing: what tells them apart is that their
own uncertainty moves their predictions differently across experiments.  The measure here is therefore
the expected log Bayes factor of the runs, ``KL(p_T || p_O)`` between the two rivals' predictive
distributions of the runs' means (rival ``T`` true, ``O`` the other), each rival's fitted values
integrated over their Gaussian uncertainty, one set shared by every experiment (factor ``U_e`` of
experiment ``e``, the values in units of their standard deviation).  The runs are independent: ``n_e``
runs of experiment ``e`` have the covariance ``D_e = Y_e + Sigma_e / n_e`` (``Y_e`` a systematic part more
runs of that experiment do not average away: the true rival's misfit, a friction law's form; taken
independent between experiments and the same under both rivals).  With ``V_e = [U_T,e, U_O,e]``, every term
of the divergence is a function of the sums ``a = sum delta^T D^-1 delta``, ``b = sum V^T D^-1 delta`` and
``G = sum V^T D^-1 V`` (Woodbury's identity and the matrix determinant lemma, :func:`divergence`): the
experiments' contributions add.  ``d_T^2 = 2 KL`` then stands for the plan's ``d^2`` (for equal covariances
it is ``delta^T S^-1 delta``) in its resolution probability ``Phi(d / 2 - ln(odds) / d)``.

More runs never lower the divergence (it is that of a function of more data), so a greedy allocation
(one run at a time to the experiment that raises the worst pair's resolution probability most, its
logarithm, so that the first runs are told apart too, over at most :data:`MAX_DISTINCT` experiments,
a plan a researcher can follow) is the allocation used; it stops at the target probability or at the
budget.  Taking the log Bayes factor Gaussian with mean ``KL`` and variance ``2 KL``
is exact when the rivals differ in their means alone; where they differ in how their own uncertainty
moves them, its tail is heavier (a true value that happens to sit where the rivals agree tells nothing),
so once that approximation reaches the target the probability is checked by simulating the runs' means
under each rival and counting the exact log Bayes factors (:func:`simulated_probability`,
:data:`DRAWS` draws, a fixed seed); when it falls short, the allocation goes on to the budget and is
simulated again there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.special import log_ndtr, logsumexp

MAX_DISTINCT = 3
"""Experiments a combination spreads its runs over, at most (a plan a researcher can follow)."""
DRAWS = 2000
"""Simulated outcomes per rival taken true in :func:`simulated_probability` (standard error 0.005 at 0.95)."""


@dataclass
class Hypothesis:
    """One pair's rival ``T`` taken true: its weight in the pair's probability, the log odds the runs must
    give, and per group of experiments of one observation size ``m`` the arrays ``(delta (n, m), true (n, m,
    q_T), other (n, m, q_O), noise (n, m, m), systematic (n, m, m))``: the rivals' difference of means, the true
    rival's and the other's own-uncertainty factors, one run's noise and the systematic part; the groups in
    the order of the experiments' global index, ``q_T`` and ``q_O`` the same in every group."""

    pair: int
    weight: float
    need: float
    groups: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=list)


@dataclass(frozen=True)
class Allocation:
    """Runs per experiment (``counts``, by global index), the worst pair's resolution probability after
    them, and the probability after each run the greedy allocation added (``path``; the Gaussian
    approximation's, or the simulated one where the approximation reached the target)."""

    counts: np.ndarray
    probability: float
    path: tuple[float, ...]

    @property
    def runs(self) -> int:
        return int(self.counts.sum())


def _contribution(group, counts: np.ndarray):
    """``(a (n,), b (n, q), G (n, q, q))`` of ``counts (n,)`` runs of each experiment of a group (zero where
    none), ``q = q_T + q_O``."""
    delta, true, other, noise, systematic = group
    n = np.maximum(counts, 1.0)
    D = systematic + noise / n[:, None, None]
    size = np.trace(D, axis1=-2, axis2=-1)[:, None, None]
    D = D + (1e-12 * size + 1e-300) * np.eye(D.shape[-1])
    V = np.concatenate([true, other], axis=-1)
    x = np.linalg.solve(D, np.concatenate([delta[..., None], V], axis=-1))  # (n, m, 1 + q)
    a = np.einsum("nm,nm->n", delta, x[..., 0])
    b = np.einsum("nmq,nm->nq", V, x[..., 0])
    G = np.einsum("nmq,nmr->nqr", V, x[..., 1:])
    on = (counts > 0).astype(float)
    return a * on, b * on[:, None], G * on[:, None, None]


def _q(h: Hypothesis) -> tuple[int, int]:
    return h.groups[0][1].shape[-1], h.groups[0][2].shape[-1]


def _all(h: Hypothesis, counts: np.ndarray):
    parts, start = [], 0
    for group in h.groups:
        n = len(group[0])
        parts.append(_contribution(group, counts[start : start + n]))
        start += n
    return tuple(np.concatenate([p[i] for p in parts]) for i in range(3))


def divergence(a, b, G, q_true: int) -> np.ndarray:
    """``2 KL(p_T || p_O)`` from the sums ``a``, ``b (..., q)``, ``G (..., q, q)`` (module docstring), batched
    over leading axes: ``tr(S_O^-1 S_T) - M + ln det S_O / det S_T + delta^T S_O^-1 delta`` with
    ``S = D + U U^T``, each term through the sums alone."""
    k = q_true
    q = b.shape[-1]
    H_tt, H_oo, H_to = G[..., :k, :k], G[..., k:, k:], G[..., :k, k:]
    b_o = b[..., k:]
    eye_o = np.eye(q - k)
    B = np.linalg.inv(eye_o + H_oo) if q > k else np.zeros(G.shape[:-2] + (0, 0))
    mean = a - np.einsum("...i,...ij,...j->...", b_o, B, b_o)
    trace = np.trace(H_tt, axis1=-2, axis2=-1) - np.einsum("...ij,...jk,...ik->...", H_to, B, H_to)
    trace = trace - np.einsum("...ij,...ji->...", H_oo, B)
    logdet = np.linalg.slogdet(eye_o + H_oo)[1] - np.linalg.slogdet(np.eye(k) + H_tt)[1]
    return np.maximum(mean + trace + logdet, 0.0)


def _log_probability(hypotheses: list[Hypothesis], d2: list[np.ndarray], pairs: int) -> np.ndarray:
    """The worst pair's log resolution probability (``log sum_T w_T Phi(d_T / 2 - need_T / d_T)``)."""
    out = None
    for k in range(pairs):
        terms = []
        for h, x in zip(hypotheses, d2):
            if h.pair != k or h.weight <= 0:
                continue
            d = np.sqrt(np.maximum(x, 1e-300))
            terms.append(math.log(h.weight) + log_ndtr(d / 2 - h.need / d))
        value = logsumexp(np.array(terms), axis=0)
        out = value if out is None else np.minimum(out, value)
    return out


def probability(hypotheses: list[Hypothesis], counts) -> float:
    """The worst pair's resolution probability of the runs ``counts`` (per experiment, global index)."""
    counts = np.asarray(counts, float)
    d2 = [divergence(*(np.sum(c, axis=0) for c in _all(h, counts)), _q(h)[0]) for h in hypotheses]
    pairs = 1 + max(h.pair for h in hypotheses)
    return float(np.exp(_log_probability(hypotheses, [np.atleast_1d(x) for x in d2], pairs))[0])


def _stacked(group, counts: np.ndarray):
    """The chosen experiments of a group stacked: difference of means, factors and the runs' covariance blocks."""
    delta, true, other, noise, systematic = group
    on = np.flatnonzero(counts > 0)
    D = systematic[on] + noise[on] / counts[on][:, None, None]
    return delta[on].reshape(-1), true[on].reshape(-1, true.shape[-1]), other[on].reshape(-1, other.shape[-1]), D


def simulated_probability(hypotheses: list[Hypothesis], counts, draws: int = DRAWS, seed: int = 0) -> float:
    """The worst pair's resolution probability of the runs ``counts``, by simulation: under each rival taken
    true, its fitted values and the runs' noise drawn (the runs' means, stacked over the experiments), the
    exact log Bayes factor against the other rival's predictive distribution counted against ``need``."""
    return float(simulated_pairs(hypotheses, counts, draws, seed).min())


def simulated_pairs(hypotheses: list[Hypothesis], counts, draws: int = DRAWS, seed: int = 0) -> np.ndarray:
    """Every pair's resolution probability of the runs ``counts`` by simulation, ``(pairs,)``
    (:func:`simulated_probability` is the smallest)."""
    counts = np.asarray(counts, float)
    rng = np.random.default_rng(seed)
    pairs = 1 + max(h.pair for h in hypotheses)
    chance = np.zeros(pairs)
    for h in hypotheses:
        parts, start = [], 0
        for group in h.groups:
            n = len(group[0])
            if np.any(counts[start : start + n] > 0):
                parts.append(_stacked(group, counts[start : start + n]))
            start += n
        if not parts or h.weight <= 0:
            continue
        delta = np.concatenate([p[0] for p in parts])
        Ut = np.concatenate([p[1] for p in parts])
        Uo = np.concatenate([p[2] for p in parts])
        M = delta.size
        D = np.zeros((M, M))
        at = 0
        for p in parts:
            for block in p[3]:
                k = block.shape[-1]
                D[at : at + k, at : at + k] = block
                at += k
        z = rng.standard_normal((M, draws))
        llr = _log_bayes_factors(delta, Ut @ Ut.T, Uo @ Uo.T, D, z)
        chance[h.pair] += h.weight * float(np.mean(llr >= h.need))
    return chance


def _log_bayes_factors(
    delta: np.ndarray, Ct: np.ndarray, Co: np.ndarray, D: np.ndarray, z: np.ndarray, endless: np.ndarray | None = None
) -> np.ndarray:
    """Simulated log Bayes factors ``(..., draws)`` of a true rival against the other from the runs' mean.

    The runs' mean less the true rival's prediction is ``Lt z`` (``z (M, draws)`` standard normal, ``Lt`` the
    Cholesky factor of the true rival's predictive covariance ``D + Ct``: the runs' covariance ``D`` and its
    own ``Ct``); the other predicts ``delta`` less, with ``D + Co``.  The log Bayes factor is half the
    difference of the two Mahalanobis squares plus the log ratio of the determinants; ``|Lt^-1 Lt z|^2`` is
    ``|z|^2``.  ``D`` gets a jitter of ``1e-12`` of its mean diagonal, and where ``endless`` (runs without end:
    no noise left, the rivals' own covariances may be singular) ``1e-9`` of the rivals' own.  Leading
    dimensions ``...`` of ``delta (..., M)`` and the ``(..., M, M)`` matrices broadcast (the experiments)."""
    M = delta.shape[-1]
    eye = np.eye(M)
    size = np.trace(D, axis1=-2, axis2=-1)[..., None, None]
    D = D + (1e-12 * size / M + 1e-300) * eye
    if endless is not None and np.any(endless):
        own = np.trace(Ct + Co, axis1=-2, axis2=-1)[..., None, None]
        D = D + np.where(np.asarray(endless)[..., None, None], 1e-9 * own / M, 0.0) * eye
    Lt, Lo = np.linalg.cholesky(D + Ct), np.linalg.cholesky(D + Co)
    inv = np.linalg.inv(Lo)
    # |Lo^-1 (Lt z + delta)|^2, as one product over the leading dimensions: (Lo^-1 Lt) z + Lo^-1 delta
    w = (inv @ Lt).reshape(-1, M) @ z
    w = w.reshape(Lt.shape[:-1] + (z.shape[-1],)) + inv @ delta[..., None]
    qo = np.sum(w * w, axis=-2)
    logdet = 2 * (
        np.sum(np.log(np.diagonal(Lo, axis1=-2, axis2=-1)), axis=-1)
        - np.sum(np.log(np.diagonal(Lt, axis1=-2, axis2=-1)), axis=-1)
    )
    return 0.5 * (qo - np.sum(z * z, axis=0) + logdet[..., None])


def repeated_probability(
    hypotheses: list[Hypothesis], repeats, draws: int = DRAWS, seed: int = 0, only: np.ndarray | None = None
) -> np.ndarray:
    """Every pair's resolution probability of ``repeats`` runs of each experiment alone, by simulation,
    ``(pairs, experiments)``: for experiment ``e`` what :func:`simulated_pairs` gives for ``counts`` holding
    ``repeats[e]`` at ``e`` and none elsewhere, the same draws (the seed's stream, hypothesis after hypothesis),
    batched over the experiments.

    Parameters
    ----------
    hypotheses : list of Hypothesis
        Every pair's rivals, each taken true (:func:`bikerider.gap.plan.discrimination.hypotheses`).
    repeats : float or array_like
        Runs of each experiment (global index; one number for all), ``math.inf`` for endless runs (the limit
        the rivals' own uncertainty and the systematic part set).
    draws, seed : int
        Simulated outcomes per rival taken true, and the seed: every experiment is simulated with the same
        standard normal draws (common random numbers), so the probability is the same on every call and moves
        smoothly with an experiment's speed, as its covariances do.
    only : array_like of bool, optional
        The experiments to simulate (global index); the others are left at 0 (the same draws: an experiment's
        value does not depend on which others are simulated).

    Returns
    -------
    ndarray
        ``(pairs, experiments)``: with each rival of a pair taken true (its weight), the share of outcomes whose
        exact log Bayes factor, the true rival's predictive density of the runs' mean against the other's, reaches
        the hypothesis's ``need``.
    """
    n_exp = sum(len(g[0]) for g in hypotheses[0].groups)
    pairs = 1 + max(h.pair for h in hypotheses)
    reps = np.broadcast_to(np.asarray(repeats, float), (n_exp,))
    wanted = np.ones(n_exp, bool) if only is None else np.broadcast_to(np.asarray(only, bool), (n_exp,))
    chance = np.zeros((pairs, n_exp))
    start = 0
    for g in range(len(hypotheses[0].groups)):
        rng = np.random.default_rng(seed)  # the stream simulated_probability draws for one experiment of group g
        n = len(hypotheses[0].groups[g][0])
        chosen = np.flatnonzero(wanted[start : start + n])  # within the group
        for h in hypotheses:
            if h.weight <= 0 or not chosen.size:
                continue
            delta, true, other, noise, systematic = h.groups[g]
            M = delta.shape[-1]
            z = rng.standard_normal((M, draws))
            step = max(1, 2_000_000 // (M * draws))
            for lo in range(0, chosen.size, step):
                e = chosen[lo : lo + step]
                k = reps[start + e]
                D = systematic[e] + noise[e] / k[:, None, None]
                Ct = true[e] @ np.swapaxes(true[e], -1, -2)
                Co = other[e] @ np.swapaxes(other[e], -1, -2)
                llr = _log_bayes_factors(delta[e], Ct, Co, D, z, endless=~np.isfinite(k))
                chance[h.pair, start + e] += h.weight * np.mean(llr >= h.need, axis=1)
        start += n
    return chance


def _one(h: Hypothesis, e: int, count: float):
    """``(a, b, G)`` of ``count`` runs of experiment ``e`` (global index) alone."""
    start = 0
    for group in h.groups:
        n = len(group[0])
        if e < start + n:
            k = e - start
            a, b, G = _contribution(tuple(x[k : k + 1] for x in group), np.array([float(count)]))
            return a[0], b[0], G[0]
        start += n
    raise IndexError(e)


def allocate(
    hypotheses: list[Hypothesis],
    budget: int,
    target: float,
    allowed=None,
    draws: int = DRAWS,
    distinct: int = MAX_DISTINCT,
) -> Allocation:
    """The greedy allocation of at most ``budget`` runs (module docstring) over at most ``distinct``
    experiments (a plan a researcher can follow), stopping once the worst pair's resolution probability
    reaches ``target``; ``allowed`` (boolean per experiment) excludes experiments.  Where the Gaussian
    approximation first reaches ``target``, and again at the budget's end, the probability is simulated
    (``draws`` per rival taken true) and the allocation goes on while it falls short."""
    n_exp = sum(len(g[0]) for g in hypotheses[0].groups)
    pairs = 1 + max(h.pair for h in hypotheses)
    counts = np.zeros(n_exp)
    ok = np.ones(n_exp, bool) if allowed is None else np.asarray(allowed, bool).copy()
    if not ok.any():
        return Allocation(counts, 0.0, ())
    q = [sum(_q(h)) for h in hypotheses]
    totals = [(0.0, np.zeros(k), np.zeros((k, k))) for k in q]
    now = [[np.zeros(n_exp), np.zeros((n_exp, k)), np.zeros((n_exp, k, k))] for k in q]
    nxt = [list(_all(h, np.ones(n_exp))) for h in hypotheses]  # each experiment's contribution at one run more
    path: list[float] = []
    checked = False
    for _ in range(int(budget)):
        d2 = []
        for h, (a0, g0, H0), cur, new in zip(hypotheses, totals, now, nxt):
            d2.append(divergence(a0 + new[0] - cur[0], g0 + new[1] - cur[1], H0 + new[2] - cur[2], _q(h)[0]))
        score = np.where(ok, _log_probability(hypotheses, d2, pairs), -np.inf)
        e = int(np.argmax(score))
        counts[e] += 1
        for i, h in enumerate(hypotheses):
            a0, g0, H0 = totals[i]
            cur, new = now[i], nxt[i]
            totals[i] = (a0 + new[0][e] - cur[0][e], g0 + new[1][e] - cur[1][e], H0 + new[2][e] - cur[2][e])
            for j in range(3):
                cur[j][e] = new[j][e]
            for j, x in enumerate(_one(h, e, counts[e] + 1)):
                new[j][e] = x
        if np.count_nonzero(counts) >= distinct:
            ok &= counts > 0
        path.append(float(np.exp(score[e])))
        # the simulation where the approximation first reaches the target, then only at the budget's end
        if path[-1] >= target and (not checked or counts.sum() >= budget):
            checked = True
            path[-1] = min(path[-1], simulated_probability(hypotheses, counts, draws))
            if path[-1] >= target:
                break
    return Allocation(counts, path[-1] if path else 0.0, tuple(path))
