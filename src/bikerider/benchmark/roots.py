"""Polynomial roots: the one quadratic solver of bikerider, for one polynomial or a batch.

:func:`monic_quadratic_roots` solves ``y^2 + b y + c`` by the cancellation-free formula (complex
pairs included), for any batch shape; the quartic solver (:mod:`bikerider.benchmark.quartic`) uses it
for its two quadratic factors, and :func:`quadratic_roots` (scale-aware, real roots only) for the
polynomials in ``u = v^2`` whose roots bound the stable speed intervals
(:mod:`bikerider.benchmark.stability`).  :func:`polynomial_positive_real_roots` takes a polynomial
of any degree (the discriminant of the characteristic quartic).

One bicycle and a batch of a hundred thousand go through the same code: written once over a
namespace ``xp`` of the few functions it needs, NumPy for arrays and :class:`_Floats` for one
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
    abs, sqrt, copysign = abs, math.sqrt, math.copysign

    @staticmethod
    def where(condition, a, b):
        return a if condition else b

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


def positive_real_roots(c2: float, c1: float, c0: float) -> list[float]:
    """The positive real roots of one ``c2 u^2 + c1 u + c0`` in plain floats, ascending
    (:func:`quadratic_roots`' rules: a double root appears twice)."""
    return [u for u in quadratic_roots(float(c2), float(c1), float(c0)) if u > 0]


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
    roots = np.roots(c[nonzero[0] :])
    real = roots[np.abs(roots.imag) <= IMAGINARY * np.maximum(1.0, np.abs(roots.real))].real
    return np.sort(real[real > 0])


__all__ = [
    "IMAGINARY",
    "ZERO",
    "monic_quadratic_roots",
    "polynomial_positive_real_roots",
    "positive_real_roots",
    "quadratic_roots",
]
