"""The statistics of the diagnosis: RMS errors, the gap's shrinkage, the paired bootstrap that breaks
ties, the jackknife's quantile, and the count and the table of a fit's values.

Pure functions of arrays and fits (no state), shared by the steps of :mod:`bikerider.gap.diagnosis.result`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import stdtrit  # Student's t quantile (scipy.stats.t.ppf's own function, without its import)

from bikerider.gap.candidates.effects import EFFECT_NAMES, EFFECTS, PARAMETERS
from bikerider.gap.distributions import chi2
from bikerider.gap.inference.problem import EffectFit, GapProblem

ALPHA = 0.01
"""Significance level of the gap tests."""

TIE_RELATIVE = 0.05
"""Held-out errors closer than this fraction of the better one are a tie."""

SAME_ERROR = 1e-9
"""Held-out errors that agree within this fraction are the same number to the fits' tolerance (their
least-squares refits stop at a relative 1e-10 of the cost, :data:`bikerider.gap.inference.indirect.LM_TOLERANCE`):
:func:`by_error` orders them by rule, not by their last digits, so a change of rounding does not reorder
the ranking (SBW: steer_stiffness and steer_inertia agree to 1e-11)."""

TIE_P = 0.05
"""One-sided p-value a better held-out error must reach to break a tie."""

N_BOOTSTRAP = 2000
"""Resamples of the paired bootstrap in :func:`significantly_better`."""

BOOTSTRAP_BLOCK = 1_000_000
"""Resampled points drawn at a time by :func:`significantly_better` (bounds its memory)."""


NOISE_FLOOR_LEVEL = 0.05
"""Held-out residuals are at the noise floor when noise alone would give a larger sum of squares with
at least this probability (:func:`at_noise_floor`)."""


def noise_floor_rms(n: int) -> float:
    """The largest RMS of ``n`` normalised residuals that noise alone reaches with probability
    ``1 - NOISE_FLOOR_LEVEL``: ``sqrt(chi2_95(n) / n)`` (1.17 for 50 points, 1.05 for 500)."""
    return math.sqrt(chi2.ppf(1.0 - NOISE_FLOOR_LEVEL, n) / n) if n > 0 else math.nan


def at_noise_floor(rms_error: float, n: int) -> bool:
    """Whether ``n`` held-out residuals of RMS ``rms_error`` (in units of their noise) are consistent
    with the noise alone: ``n rms^2`` within the chi-square's upper 95 % point with ``n`` degrees of
    freedom.  A bare ``rms <= 1`` would call pure noise "above the floor" half the time."""
    if not (n > 0 and math.isfinite(rms_error)):
        return False
    return bool(rms_error <= noise_floor_rms(n))


def rms(z: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(z)))) if z.size else math.nan


def gap_shrink(z_before: np.ndarray, z_after: np.ndarray) -> float | None:
    """``(G_before - G_after) / G_before`` with ``G = mean(z^2) - 1``; ``None`` when ``G_before <= 0``."""
    g_before = float(np.mean(np.square(z_before))) - 1.0
    g_after = float(np.mean(np.square(z_after))) - 1.0
    if not g_before > 0:
        return None
    return (g_before - max(g_after, 0.0)) / g_before


def significantly_better(z_better: np.ndarray, z_worse: np.ndarray) -> tuple[bool, float]:
    """Whether held-out residuals ``z_better`` beat ``z_worse``; returns (significant, p).

    Paired bootstrap over the held-out points (:data:`N_BOOTSTRAP` resamples, fixed seed): ``p`` is
    the fraction of resamples in which the RMS of ``z_better`` is not below that of ``z_worse``.
    Significant when ``p <`` :data:`TIE_P` and the RMS error is lower by more than
    :data:`TIE_RELATIVE`.  Points of one fold share a fit, so the test is optimistic about
    independence; it is a screening rule, not an exact test.
    """
    a, b = np.square(z_better), np.square(z_worse)
    n = a.size
    if n < 3:
        return False, 1.0
    rng = np.random.default_rng(0)
    rows = max(1, BOOTSTRAP_BLOCK // n)  # resamples drawn at a time: memory bounded for any n
    not_better = 0
    for done in range(0, N_BOOTSTRAP, rows):
        index = rng.integers(0, n, size=(min(rows, N_BOOTSTRAP - done), n))
        not_better += int(np.sum(a[index].sum(axis=1) >= b[index].sum(axis=1)))
    p = not_better / N_BOOTSTRAP
    return p < TIE_P and rms(z_better) < (1 - TIE_RELATIVE) * rms(z_worse), p


def by_error(results: list, problem: GapProblem) -> list:
    """Cross-validations sorted by held-out error, deterministically where errors agree within
    :data:`SAME_ERROR` (relative, chained between neighbours): fewer fitted parameters first, then the
    registry's order of the effects (:data:`bikerider.gap.candidates.effects.EFFECT_NAMES`)."""
    ordered = sorted(results, key=lambda r: r.error_after)
    out: list = []
    group: list = []
    for r in ordered:
        if group and not abs(r.error_after - group[-1].error_after) <= SAME_ERROR * abs(group[-1].error_after):
            out += sorted(group, key=lambda g: _rule(problem, g.effects))
            group = []
        group.append(r)
    return out + sorted(group, key=lambda g: _rule(problem, g.effects))


def _rule(problem: GapProblem, effects: tuple[str, ...]) -> tuple:
    return (_n_params(problem, effects), [EFFECT_NAMES.index(e) for e in effects])


def _n_params(problem: GapProblem, effects: tuple[str, ...]) -> int:
    n = 0
    for e in effects:
        n += len(problem.free) if e == PARAMETERS else len(EFFECTS[e].parameters)
    return n


def _named_values(fit: EffectFit | None) -> dict:
    if fit is None:
        return {}
    return {
        name: {"value": float(v), "stderr": float(s), "ci95": [float(lo), float(hi)], "unit": u}
        for name, v, s, lo, hi, u in zip(fit.names, fit.values, fit.stderr, fit.ci_low, fit.ci_high, fit.units)
    }


def _minima(fit: EffectFit | None) -> list[dict]:
    """The other local minima of a fit's chi-square found (:meth:`GapProblem.fit_apparent`), lowest first:
    ``{values: {name: value}, chi2, chi2_fit, within}``, ``within`` when it lies within the 95 %
    profile-likelihood threshold of the fit's chi-square (the 95 % intervals then hold it)."""
    if fit is None:
        return []
    return [
        {
            "values": {name: float(v) for name, v in zip(fit.names, values)},
            "chi2": float(chi2),
            "chi2_fit": float(fit.chi2),
            "within": k < fit.minima_within,  # those within the threshold come first
        }
        for k, (values, chi2) in enumerate(fit.minima)
    ]


def jackknife_quantile(folds: int) -> float:
    """The 97.5 % point of Student's t with ``folds - 1`` degrees of freedom: a jackknife over ``folds``
    fits estimates a standard error with that many, so the normal 1.96 would make its 95 % intervals too
    narrow (4.30 for three folds, 2.26 for ten)."""
    return float(stdtrit(max(folds - 1, 1), 0.975))


def interval_quantile(gradient, covariance, jackknife_covariance, folds: int) -> float:
    """The 97.5 % point of Student's t for the 95 % interval of ``gradient @ values`` when its variance
    is a jackknife's share over ``folds`` fits plus a share known from the model (the benchmark
    parameters'): Welch-Satterthwaite degrees of freedom ``(folds - 1) (v / v_jackknife)^2`` (the
    jackknife's alone gives :func:`jackknife_quantile`; a known share alone, the normal 1.96)."""
    g = np.asarray(gradient, float)
    total = float(g @ np.asarray(covariance, float) @ g)
    if jackknife_covariance is None:
        return 1.96
    return variance_quantile(total, float(g @ np.asarray(jackknife_covariance, float) @ g), folds)


def variance_quantile(total: float, spread: float, folds: int) -> float:
    """:func:`interval_quantile` for one value whose variance ``total`` holds a jackknife's share ``spread``
    over ``folds`` fits (the rest known)."""
    if not (np.isfinite(total) and np.isfinite(spread)) or spread <= 0 or total <= 0:
        return 1.96 if spread <= 0 else jackknife_quantile(folds)
    dof = max(folds - 1, 1) * (total / spread) ** 2
    return float(stdtrit(min(dof, 1e6), 0.975))
