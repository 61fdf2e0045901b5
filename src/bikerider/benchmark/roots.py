"""Polynomial roots: the one quadratic solver, and the critical speeds it gives.

:func:`monic_quadratic_roots` solves ``y^2 + b y + c`` by the cancellation-free formula (complex
pairs included), for any batch shape; the quartic solver (:mod:`bikerider.benchmark.quartic`) uses it
for its two quadratic factors and :func:`quadratic_roots` for the real roots of the critical-speed
polynomials.

Critical speeds (:func:`critical_speeds`) are the positive roots of quadratics in ``u = v^2``, the
generated ``benchmark_model.critical_speed_polynomials``: capsize is the smallest positive root of
``det(g K0 + u K2)``; weave is the smallest positive root of the third Hurwitz determinant at which
the crossing frequency ``omega^2 = a1/a3`` is positive.  Where there is no such root the speed is
NaN.  One bicycle and a batch of a hundred thousand go through the same code.
"""
from __future__ import annotations

import numpy as np

ZERO = 1e-14
"""Polynomial coefficients below this fraction of the largest are zero."""
IMAGINARY = 1e-9
"""A complex root pair with imaginary part below ``IMAGINARY * max(1, |real part|)`` is a double
real root (round-off can split a double root into such a pair)."""


def monic_quadratic_roots(b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, ...]:
    """Roots of ``y^2 + b y + c`` (real ``b``, ``c``) as ``(re1, im1, re2, im2)``, cancellation-free."""
    disc = b * b - 4 * c
    root = np.sqrt(np.abs(disc))
    real = disc >= 0
    t = -(b + np.copysign(root, b)) / 2
    other = np.where(t != 0, c / np.where(t != 0, t, 1.0), 0.0)
    half_b = -b / 2
    im = np.where(real, 0.0, root / 2)
    return np.where(real, t, half_b), im, np.where(real, other, half_b), -im


def quadratic_roots(c2, c1, c0) -> tuple[np.ndarray, np.ndarray]:
    """The real roots of ``c2 u^2 + c1 u + c0`` (ascending), NaN where they are not real.

    Scale-aware: a leading coefficient below :data:`ZERO` times the largest makes the polynomial
    linear (one root, the other NaN); a complex pair within :data:`IMAGINARY` of the real axis is
    a double real root.
    """
    c2, c1, c0 = np.broadcast_arrays(*(np.asarray(c, dtype=float) for c in (c2, c1, c0)))
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.maximum(np.maximum(np.abs(c2), np.abs(c1)), np.abs(c0))
        scale = np.where(scale > 0, scale, np.nan)
        a, b, c = c2 / scale, c1 / scale, c0 / scale
        quadratic = np.abs(a) > ZERO
        a_safe = np.where(quadratic, a, 1.0)
        re1, im1, re2, _ = monic_quadratic_roots(b / a_safe, c / a_safe)
        real_pair = im1 <= IMAGINARY * np.maximum(1.0, np.abs(re1))
        keep = quadratic & real_pair
        low = np.where(keep, np.minimum(re1, re2), np.nan)
        high = np.where(keep, np.maximum(re1, re2), np.nan)
        linear = ~quadratic & (np.abs(b) > ZERO)
        low = np.where(linear, -c / np.where(linear, b, 1.0), low)
        high = np.where(linear, np.nan, high)
    return low, high


def _smallest_positive(low, high, accept_low=True, accept_high=True) -> np.ndarray:
    with np.errstate(invalid="ignore"):
        return np.where((low > 0) & accept_low, low, np.where((high > 0) & accept_high, high, np.nan))


def critical_speeds(capsize, weave, a1_over_v, a3_over_v) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(v_weave, v_capsize, weave_frequency)`` from the critical-speed polynomials in ``u = v^2``.

    Parameters
    ----------
    capsize, weave : array_like, shape (..., 3)
        Coefficients of ``det(g K0 + u K2)`` and of the third Hurwitz determinant over ``v^2``,
        highest power first.
    a1_over_v, a3_over_v : array_like, shape (..., 2)
        ``a1/v`` and ``a3/v`` in ``u``: their ratio is the squared crossing frequency.

    Returns
    -------
    v_weave, v_capsize, weave_frequency : ndarray
        [m/s, m/s, rad/s]; NaN where there is none at positive speed.
    """
    capsize, weave = np.asarray(capsize, dtype=float), np.asarray(weave, dtype=float)
    a1, a3 = np.asarray(a1_over_v, dtype=float), np.asarray(a3_over_v, dtype=float)
    capsize_u = _smallest_positive(*quadratic_roots(capsize[..., 0], capsize[..., 1], capsize[..., 2]))
    roots = quadratic_roots(weave[..., 0], weave[..., 1], weave[..., 2])
    with np.errstate(invalid="ignore", divide="ignore"):
        omega2 = [(a1[..., 0] * u + a1[..., 1]) / (a3[..., 0] * u + a3[..., 1]) for u in roots]
        accept = [np.isfinite(w) & (w > 0) for w in omega2]
        weave_u = _smallest_positive(*roots, *accept)
        omega2_at = np.where(weave_u == roots[0], omega2[0], omega2[1])
        frequency = np.where(np.isfinite(weave_u), np.sqrt(np.abs(omega2_at)), np.nan)
        return np.sqrt(weave_u), np.sqrt(capsize_u), frequency


def polynomial_positive_real_roots(coefficients: np.ndarray) -> np.ndarray:
    """Sorted positive real roots of a polynomial of any degree (highest power first), with the
    tolerances :data:`ZERO` and :data:`IMAGINARY` (``numpy.roots``: companion-matrix eigenvalues)."""
    c = np.asarray(coefficients, dtype=float)
    scale = np.abs(c).max()
    if scale == 0:
        return np.empty(0)
    c = c / scale
    nonzero = np.flatnonzero(np.abs(c) > ZERO)
    if nonzero.size == 0:
        return np.empty(0)
    roots = np.roots(c[nonzero[0]:])
    real = roots[np.abs(roots.imag) <= IMAGINARY * np.maximum(1.0, np.abs(roots.real))].real
    return np.sort(real[real > 0])


__all__ = ["IMAGINARY", "ZERO", "critical_speeds", "monic_quadratic_roots", "polynomial_positive_real_roots",
           "quadratic_roots"]
