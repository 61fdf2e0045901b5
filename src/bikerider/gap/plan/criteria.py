"""Criteria for the next experiment that tells rival models apart (model discrimination).

Every criterion here is a function of what the rivals predict for the next run's observation at one
candidate experiment, and nothing else: rival ``i``'s predicted mean ``mu_i`` (a vector of ``m`` real
numbers, e.g. the real and imaginary part of a weave eigenvalue, or of a frequency response at its
lines), the covariance ``W_i`` of that prediction (from the uncertainty of the rival's fitted values),
the covariance ``Sigma`` of one run's measurement noise, and the rivals' current probabilities ``pi_i``.
The larger a criterion, the better the experiment is expected to discriminate.  All functions take
arrays with a leading experiment axis, so that a whole grid of experiments is scored at once:

* ``means (R, n, m)``: ``R`` rivals, ``n`` experiments, ``m`` observed numbers;
* ``own (R, n, m, m)``: each rival's prediction covariance ``W_i``;
* ``noise (n, m, m)``: one run's noise ``Sigma``;
* ``weights (R,)``: the rivals' probabilities (they need not sum to one; they are normalised).

The predictive distribution of the observation under rival ``i`` is taken Gaussian,
``N(mu_i, S_i)`` with ``S_i = W_i + Sigma``.

References
----------
.. [1] Hunter, W. G. and Reiner, A. M. (1965). Designs for discriminating between two rival models.
   Technometrics 7(3), 307-323.
.. [2] Box, G. E. P. and Hill, W. J. (1967). Discrimination among mechanistic models.
   Technometrics 9(1), 57-71.
.. [3] Buzzi-Ferraris, G. and Forzatti, P. (1984). Sequential experimental design for model
   discrimination in the case of multiple responses. Chemical Engineering Science 39(1), 81-85.
.. [4] Olofsson, S., Hebing, L., Niedenfuehr, S., Deisenroth, M. P. and Misener, R. (2019). GPdoemd:
   a Python package for design of experiments for model discrimination. Computers and Chemical
   Engineering 125, 54-70 (the Jensen-Renyi divergence of Gaussian mixtures as a design criterion).
"""

from __future__ import annotations

import math

import numpy as np

CRITERIA = ("hunter_reiner", "box_hill", "buzzi_ferraris", "jensen_renyi")
"""The criteria of this module by name (see :func:`score`)."""


def _check(means: np.ndarray, own: np.ndarray | None, noise: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    means = np.asarray(means, dtype=float)
    if means.ndim != 3 or means.shape[0] < 2:
        raise ValueError(
            f"means: expected an array (rivals >= 2, experiments, observed numbers), got shape {means.shape}"
        )
    R, n, m = means.shape
    noise = np.asarray(noise, dtype=float)
    if noise.shape != (n, m, m):
        raise ValueError(f"noise: expected shape {(n, m, m)} (one run's covariance per experiment), got {noise.shape}")
    own = np.zeros((R, n, m, m)) if own is None else np.asarray(own, dtype=float)
    if own.shape != (R, n, m, m):
        raise ValueError(f"own: expected shape {(R, n, m, m)} (each rival's prediction covariance), got {own.shape}")
    if not (np.all(np.isfinite(means)) and np.all(np.isfinite(own)) and np.all(np.isfinite(noise))):
        raise ValueError("means, own and noise must be finite (an experiment a rival cannot predict is left out first)")
    return means, own, noise


def _weights(weights, R: int) -> np.ndarray:
    if weights is None:
        return np.full(R, 1.0 / R)
    w = np.asarray(weights, dtype=float).ravel()
    if w.shape != (R,) or np.any(w < 0) or not np.isfinite(w).all() or w.sum() <= 0:
        raise ValueError(f"weights: expected {R} non-negative rival probabilities, got {w.tolist()}")
    return w / w.sum()


def _pairs(R: int) -> list[tuple[int, int]]:
    return [(i, j) for i in range(R) for j in range(i + 1, R)]


def _quadratic(delta: np.ndarray, S: np.ndarray) -> np.ndarray:
    """``delta^T S^-1 delta`` per experiment for ``delta (n, m)``, ``S (n, m, m)``."""
    return np.sum(delta * np.linalg.solve(S, delta[..., None])[..., 0], axis=-1)


def hunter_reiner(means, own=None, noise=None, weights=None) -> np.ndarray:
    """Hunter and Reiner (1965): the squared distance between the rivals' predicted means.

    ``sum_{i<j} (mu_i - mu_j)^T Sigma^-1 (mu_i - mu_j)``, the original criterion for one response and two
    rivals (``(y_1 - y_2)^2``) weighted by the noise so that observed numbers of different units and
    accuracy add up, and summed over the pairs when there are more than two rivals.  It ignores the
    rivals' own uncertainty and probabilities (``own`` and ``weights`` are accepted and not used).

    Returns
    -------
    numpy.ndarray
        ``(n,)``, one value per experiment.
    """
    means, own, noise = _check(means, own, noise)
    return sum(_quadratic(means[i] - means[j], noise) for i, j in _pairs(len(means)))


def symmetric_divergence(mu_i, S_i, mu_j, S_j) -> np.ndarray:
    """The symmetric Kullback-Leibler divergence ``KL(i||j) + KL(j||i)`` of two Gaussians, per experiment:
    ``(tr(S_j^-1 S_i + S_i^-1 S_j) - 2 m) / 2 + delta^T (S_i^-1 + S_j^-1) delta / 2``."""
    m = mu_i.shape[-1]
    delta = mu_i - mu_j
    trace = np.trace(np.linalg.solve(S_j, S_i), axis1=-2, axis2=-1) + np.trace(
        np.linalg.solve(S_i, S_j), axis1=-2, axis2=-1
    )
    return (trace - 2 * m) / 2 + (_quadratic(delta, S_i) + _quadratic(delta, S_j)) / 2


def box_hill(means, own=None, noise=None, weights=None) -> np.ndarray:
    """Box and Hill (1967): the upper bound on the expected gain of information about which rival is true.

    ``D = sum_{i<j} pi_i pi_j J_ij`` with ``J_ij`` the symmetric Kullback-Leibler divergence of the rivals'
    predictive distributions ``N(mu_i, W_i + Sigma)`` (:func:`symmetric_divergence`).  For one response it is
    Box and Hill's
    ``1/2 sum_{i<j} pi_i pi_j [(s_i^2 - s_j^2)^2 / ((s^2 + s_i^2)(s^2 + s_j^2))
    + (y_i - y_j)^2 (1 / (s^2 + s_i^2) + 1 / (s^2 + s_j^2))]``; for several responses the same divergence
    with covariance matrices.  Rivals already unlikely weigh little; a difference the rivals' own
    uncertainty covers counts little.

    Returns
    -------
    numpy.ndarray
        ``(n,)``.
    """
    means, own, noise = _check(means, own, noise)
    w = _weights(weights, len(means))
    S = own + noise[None]
    return sum(w[i] * w[j] * symmetric_divergence(means[i], S[i], means[j], S[j]) for i, j in _pairs(len(means)))


def buzzi_ferraris(means, own=None, noise=None, weights=None) -> np.ndarray:
    """Buzzi-Ferraris and Forzatti (1984): the rivals' differences against what noise and their own
    uncertainty explain.

    ``T = sum_{i<j} (mu_i - mu_j)^T V_ij^-1 (mu_i - mu_j)`` with ``V_ij = 2 Sigma + W_i + W_j``, the covariance
    of the difference of two observations, one from each rival.  Its expected value is about ``m`` (the
    number of observed numbers) per pair when the rivals cannot be told apart at that experiment, so an
    experiment with ``T`` well above ``m`` per pair discriminates and one below does not (their stopping
    rule; see :func:`buzzi_ferraris_ratio`).  ``weights`` are not used (the original sums the pairs alike).

    Returns
    -------
    numpy.ndarray
        ``(n,)``.
    """
    means, own, noise = _check(means, own, noise)
    return sum(_quadratic(means[i] - means[j], 2 * noise + own[i] + own[j]) for i, j in _pairs(len(means)))


def buzzi_ferraris_ratio(means, own=None, noise=None, weights=None) -> np.ndarray:
    """:func:`buzzi_ferraris` over the pairs times the number of observed numbers: below 1 at every
    experiment, the rivals cannot be told apart by one more run (Buzzi-Ferraris and Forzatti's rule)."""
    means, own, noise = _check(means, own, noise)
    R, _, m = means.shape
    return buzzi_ferraris(means, own, noise) / (m * len(_pairs(R)))


def _log_gauss_overlap(mu_i, S_i, mu_j, S_j) -> np.ndarray:
    """``log integral N(x; mu_i, S_i) N(x; mu_j, S_j) dx = log N(mu_i; mu_j, S_i + S_j)`` per experiment."""
    S = S_i + S_j
    m = mu_i.shape[-1]
    _, logdet = np.linalg.slogdet(S)
    return -0.5 * (m * math.log(2 * math.pi) + logdet + _quadratic(mu_i - mu_j, S))


def jensen_renyi(means, own=None, noise=None, weights=None) -> np.ndarray:
    """The Jensen-Renyi divergence (quadratic Renyi entropy) of the rivals' predictive distributions.

    ``JR = H_2(sum_i pi_i N_i) - sum_i pi_i H_2(N_i)``, ``H_2(p) = -log integral p^2``, which has a closed form
    for Gaussians (``integral N_i N_j = N(mu_i; mu_j, S_i + S_j)``; ``H_2(N_i) = log det(4 pi S_i) / 2``), for
    any number of rivals, weighted by their probabilities (Olofsson et al. 2019).  Zero when the rivals
    predict the same distribution; for rivals of equal spread and even weights it grows towards
    ``log R`` as their predictions stop overlapping.

    Returns
    -------
    numpy.ndarray
        ``(n,)``.
    """
    means, own, noise = _check(means, own, noise)
    R = len(means)
    w = _weights(weights, R)
    S = own + noise[None]
    logs = np.array(
        [
            math.log(w[i] * w[j]) + _log_gauss_overlap(means[i], S[i], means[j], S[j])
            if w[i] * w[j] > 0
            else np.full(means.shape[1], -np.inf)
            for i in range(R)
            for j in range(R)
        ]
    )
    top = np.max(logs, axis=0)
    mixture = -(top + np.log(np.sum(np.exp(logs - top), axis=0)))
    m = means.shape[-1]
    own_entropy = np.array([0.5 * (m * math.log(4 * math.pi) + np.linalg.slogdet(S[i])[1]) for i in range(R)])
    return mixture - np.tensordot(w, own_entropy, axes=1)


_BY_NAME = {
    "hunter_reiner": hunter_reiner,
    "box_hill": box_hill,
    "buzzi_ferraris": buzzi_ferraris,
    "jensen_renyi": jensen_renyi,
}


def score(name: str, means, own=None, noise=None, weights=None) -> np.ndarray:
    """The criterion ``name`` (one of :data:`CRITERIA`) for every experiment, ``(n,)``."""
    try:
        function = _BY_NAME[name]
    except KeyError:
        raise ValueError(f"criterion {name!r}: expected one of {', '.join(CRITERIA)}") from None
    return function(means, own, noise, weights)
