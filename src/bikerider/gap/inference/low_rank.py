"""Chi-square of residuals whose covariance is a diagonal plus a low-rank part, in linear time.

The gap test of :mod:`bikerider.gap.diagnosis.result` weighs the residuals ``r`` (measured minus model) by
their combined covariance ``C = D + J J^T``: ``D`` diagonal (the data's variances), ``J`` the
model's slopes per standard uncertainty of each of its ``p`` free parameters (``n x p``, ``p``
about 25).  Forming ``C`` costs ``n^2`` memory and solving with it ``n^3`` time; instead
:func:`low_rank_chi2` uses that ``r^T C^-1 r`` is the minimum over parameter shifts ``a`` (in
standard uncertainties) of

    (r - J a)^T D^-1 (r - J a) + a^T a,

a least-squares problem of ``n + p`` rows and ``p`` unknowns (``O(n p^2)``).

Observations taken as exact (``D_i = 0``, rows without a stated or estimated uncertainty) make
``C`` singular when there are more of them than ``J`` has rank: they then constrain ``J a = r``
exactly.  The statistic is the same minimum under that constraint, ``r^T C^+ r`` on the support
of the Gaussian, with degrees of freedom the rank of ``C`` (the uncertain observations plus the
rank of ``J`` on the exact ones); it is infinite when no shift reproduces the exact observations.
"""

from __future__ import annotations

import math

import numpy as np

EXACT_TOLERANCE = 1e-9
"""Relative residual below which the exact observations count as reproduced (rounding, not a gap)."""


def low_rank_chi2(residual: np.ndarray, variance: np.ndarray, factor: np.ndarray) -> tuple[float, int]:
    """``r^T (D + J J^T)^+ r`` and the rank of ``D + J J^T`` (see the module docstring).

    Parameters
    ----------
    residual : ndarray, shape (n,)
        ``r``.
    variance : ndarray, shape (n,)
        The diagonal of ``D`` (>= 0; zero for exact observations).
    factor : ndarray, shape (n, p)
        ``J``.

    Returns
    -------
    chi2 : float
        The statistic; ``inf`` when the residuals lie outside the covariance's support.
    dof : int
        Degrees of freedom: the rank of the covariance.
    """
    r = np.asarray(residual, dtype=float)
    v = np.asarray(variance, dtype=float)
    J = np.asarray(factor, dtype=float).reshape(r.size, -1)
    p = J.shape[1]
    exact = ~(v > 0)
    a0 = np.zeros(p)
    null = np.eye(p)  # shifts free to move after the exact observations are met
    rank_exact = 0
    if np.any(exact):
        rz, jz = r[exact], J[exact]
        if p:
            u, s, vt = np.linalg.svd(jz, full_matrices=False)
            rank_exact = int(np.sum(s > s[0] * 1e-12)) if s.size and s[0] > 0 else 0
            a0 = vt[:rank_exact].T @ ((u[:, :rank_exact].T @ rz) / s[:rank_exact])
            basis, _ = np.linalg.qr(vt[:rank_exact].T, mode="complete")  # (p, p): row space, then its complement
            null = basis[:, rank_exact:]
        miss = rz - jz @ a0
        scale = max(float(np.linalg.norm(rz)), float(np.linalg.norm(jz)), math.ulp(1.0))
        if float(np.linalg.norm(miss)) > EXACT_TOLERANCE * scale:
            return math.inf, int(np.sum(~exact)) + rank_exact
    weight = 1.0 / np.sqrt(v[~exact])
    target = (r[~exact] - J[~exact] @ a0) * weight
    design = (J[~exact] @ null) * weight[:, None]
    k = null.shape[1]
    stacked = np.vstack([design, np.eye(k)])
    rhs = np.concatenate([target, np.zeros(k)])
    if k:
        b, *_ = np.linalg.lstsq(stacked, rhs, rcond=None)
        rest = rhs - stacked @ b
    else:
        rest = rhs
    return float(a0 @ a0 + rest @ rest), int(np.sum(~exact)) + rank_exact
