"""Polynomial roots: the one quadratic solver, and the critical speeds it gives.

:func:`monic_quadratic_roots` solves ``y^2 + b y + c`` by the cancellation-free formula (complex
pairs included), for any batch shape; the quartic solver (:mod:`bikerider.benchmark.quartic`) uses it
for its two quadratic factors and :func:`quadratic_roots` for the real roots of the critical-speed
polynomials.

Critical speeds (:func:`critical_speeds`) are the positive roots of quadratics in ``u = v^2``, the
generated ``benchmark_model.critical_speed_polynomials``: capsize is the smallest positive root of
``det(g K0 + u K2)``; weave is the smallest positive root of the third Hurwitz determinant at which
the crossing frequency ``omega^2 = a1/a3`` is positive.  Where there is no such root the speed is
NaN.  One bicycle and a batch of a hundred thousand go through the same code: written once over
a namespace ``xp`` of the few functions it needs, NumPy for arrays and :class:`_Floats` for one
bicycle's plain floats (NumPy's per-call overhead on 0-d arrays would cost ten times the
arithmetic; the results are the same bit for bit).
"""
from __future__ import annotations

import math

import numpy as np

ZERO = 1e-14
"""Polynomial coefficients below this fraction of the largest are zero."""
IMAGINARY = 1e-9
"""A complex root pair with imaginary part below ``IMAGINARY * max(1, |real part|)`` is a double
real root (round-off can split a double root into such a pair)."""


class _Floats:
    """The few NumPy functions the solvers use, on plain floats (the operations and their order
    are NumPy's, so one bicycle gets the batch's results bit for bit, without NumPy's per-call
    overhead on 0-d arrays)."""

    nan = math.nan
    abs, sqrt, copysign, isfinite = abs, math.sqrt, math.copysign, math.isfinite

    @staticmethod
    def where(condition, a, b):
        return a if condition else b

    @staticmethod
    def divide(a, b):  # as numpy.divide: inf (signed) or NaN rather than ZeroDivisionError
        if b != 0:
            return a / b
        return math.nan if a != a or a == 0 else math.copysign(math.inf, a) * math.copysign(1.0, b)

    @staticmethod
    def maximum(a, b):  # NaN-propagating, as numpy.maximum
        return a if a >= b or a != a else b

    @staticmethod
    def minimum(a, b):
        return a if a <= b or a != a else b


def _backend(*values):
    """``(namespace, values)``: plain floats with :class:`_Floats`, anything else as float arrays with NumPy."""
    if all(type(v) is float or type(v) is int for v in values):
        return _Floats, tuple(float(v) for v in values)
    return np, tuple(np.asarray(v, dtype=float) for v in values)


def monic_quadratic_roots(b, c, xp=np) -> tuple:
    """Roots of ``y^2 + b y + c`` (real ``b``, ``c``) as ``(re1, im1, re2, im2)``, cancellation-free.

    ``xp``: NumPy (arrays of any batch shape) or :class:`_Floats` (plain floats).
    """
    disc = b * b - 4 * c
    root = xp.sqrt(xp.abs(disc))
    real = disc >= 0
    t = -(b + xp.copysign(root, b)) / 2
    other = xp.where(t != 0, c / xp.where(t != 0, t, 1.0), 0.0)
    half_b = -b / 2
    im = xp.where(real, 0.0, root / 2)
    return xp.where(real, t, half_b), im, xp.where(real, other, half_b), -im


def quadratic_roots(c2, c1, c0) -> tuple:
    """The real roots of ``c2 u^2 + c1 u + c0`` (ascending), NaN where they are not real.

    Scale-aware: a leading coefficient below :data:`ZERO` times the largest makes the polynomial
    linear (one root, the other NaN); a complex pair within :data:`IMAGINARY` of the real axis is
    a double real root.  Plain floats give floats, anything else arrays of the broadcast shape.
    """
    xp, (c2, c1, c0) = _backend(c2, c1, c0)
    if xp is np:
        c2, c1, c0 = np.broadcast_arrays(c2, c1, c0)
        with np.errstate(invalid="ignore", divide="ignore"):
            return _quadratic_roots(c2, c1, c0, np)
    return _quadratic_roots(c2, c1, c0, xp)


def _quadratic_roots(c2, c1, c0, xp) -> tuple:
    scale = xp.maximum(xp.maximum(xp.abs(c2), xp.abs(c1)), xp.abs(c0))
    scale = xp.where(scale > 0, scale, xp.nan)
    a, b, c = c2 / scale, c1 / scale, c0 / scale
    quadratic = xp.abs(a) > ZERO
    a_safe = xp.where(quadratic, a, 1.0)
    re1, im1, re2, _ = monic_quadratic_roots(b / a_safe, c / a_safe, xp)
    keep = quadratic & (im1 <= IMAGINARY * xp.maximum(1.0, xp.abs(re1)))  # a real pair
    low = xp.where(keep, xp.minimum(re1, re2), xp.nan)
    high = xp.where(keep, xp.maximum(re1, re2), xp.nan)
    linear = (quadratic ^ True) & (xp.abs(b) > ZERO)
    low = xp.where(linear, -c / xp.where(linear, b, 1.0), low)
    high = xp.where(linear, xp.nan, high)
    return low, high


def _smallest_positive(low, high, xp, accept_low=True, accept_high=True):
    return xp.where((low > 0) & accept_low, low, xp.where((high > 0) & accept_high, high, xp.nan))


def critical_speeds(capsize, weave, a1_over_v, a3_over_v) -> tuple:
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
    v_weave, v_capsize, weave_frequency : float or ndarray
        [m/s, m/s, rad/s]; NaN where there is none at positive speed.  Floats for one bicycle's
        coefficients given as sequences of numbers (the generated plain-float twin's), arrays
        otherwise.
    """
    polynomials = (capsize, weave, a1_over_v, a3_over_v)
    if all(isinstance(p, (tuple, list)) and all(type(c) is float or type(c) is int for c in p) for p in polynomials):
        return _critical_speeds(*([float(c) for c in p] for p in polynomials), _Floats)
    # coefficient first, then the batch: unpacking gives one array per coefficient
    capsize, weave, a1, a3 = (np.moveaxis(np.asarray(p, dtype=float), -1, 0) for p in polynomials)
    with np.errstate(invalid="ignore", divide="ignore"):
        return _critical_speeds(capsize, weave, a1, a3, np)


def _critical_speeds(capsize, weave, a1, a3, xp) -> tuple:
    capsize_u = _smallest_positive(*_quadratic_roots(*capsize, xp), xp)
    roots = _quadratic_roots(*weave, xp)
    omega2 = [xp.divide(a1[0] * u + a1[1], a3[0] * u + a3[1]) for u in roots]
    accept = [xp.isfinite(w) & (w > 0) for w in omega2]
    weave_u = _smallest_positive(*roots, xp, *accept)
    omega2_at = xp.where(weave_u == roots[0], omega2[0], omega2[1])
    frequency = xp.where(xp.isfinite(weave_u), xp.sqrt(xp.abs(omega2_at)), xp.nan)
    return xp.sqrt(weave_u), xp.sqrt(capsize_u), frequency  # NaN or positive: the roots of real speeds


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
