"""Roots of the characteristic polynomial without a matrix eigensolver.

The Whipple model's eigenvalues at speed ``v`` are the roots of the quartic
``a4 s^4 + a3 s^3 + a2 s^2 + a1 s + a0`` whose coefficients the generated
``benchmark_model.characteristic_coefficients`` gives for any batch of speeds.  This module solves
that quartic in closed form for a whole batch at once.  (The weave and capsize speeds come from the
generated plain-float ``critical_speed_polynomials_scalar``; see ``WhippleModel.critical_speeds``.)

:func:`quartic_roots`
    Ferrari's method (resolvent cubic, factor into two quadratics, each solved by the stable
    quadratic formula), vectorised over any leading shape, then Newton steps on the original
    polynomial.  A Newton step is taken only if it lowers the residual and moves the root by less
    than half the distance to its nearest neighbour, so two roots never collapse onto one.
:func:`eigenvalues_from_polynomial`
    The same result as :meth:`bikerider.benchmark.WhippleModel.eigenvalues` (values and mode
    labels, the rules of :func:`bikerider.benchmark.mode_labels.label_modes`), without ``eigvals``.
Accuracy.  For simple roots the result agrees with ``numpy.linalg.eigvals`` of the state matrix to
about ``1e-13`` relative to ``max(1, |root|)`` (the tests hold it to ``1e-10`` over random quartics
and the benchmark bicycle at 1000 speeds).  A root of multiplicity two is ill-conditioned for any
floating-point method: a relative perturbation ``eps`` of the coefficients moves it by about
``sqrt(eps)``, i.e. ``1e-8`` relative.  At the speed ``v_d`` where the two real weave eigenvalues
merge, this solver and ``eigvals`` therefore each place the two roots within about ``1e-8`` of the
true double root (and may disagree on whether the pair is real or complex by that much), while
the pair's mean is accurate to ``1e-12``; the tests check exactly these bounds.
"""

from __future__ import annotations

import numpy as np

from bikerider.benchmark.mode_labels import ModalEigenvalues, check_speeds, label_modes
from bikerider.benchmark.roots import monic_quadratic_roots
from bikerider.errors import InputError

NEWTON_STEPS = 2
"""Newton steps on the original polynomial after the closed form."""
_BACKWARD = 1e-14
"""Roots whose residual is below this fraction of ``sum |b_k| |z|^k`` (a few rounding units) are
not polished: Newton cannot improve them."""


# -- quartic -------------------------------------------------------------------------------------
def _check_coefficients(coefficients) -> np.ndarray:
    try:
        c = np.asarray(coefficients, dtype=float)
    except (TypeError, ValueError):
        raise InputError("coefficients", coefficients, "real numbers, shape (..., 5)") from None
    if c.ndim == 0 or c.shape[-1] != 5:
        raise InputError("coefficients", c.shape, "an array of shape (..., 5): [a4, a3, a2, a1, a0]")
    bad = ~np.isfinite(c)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise InputError(f"coefficients[{', '.join(map(str, index))}]", float(c[index]), "a finite number")
    zero = c[..., 0] == 0
    if zero.any():
        index = tuple(int(i) for i in np.argwhere(zero)[0]) if zero.ndim else ()
        raise InputError(
            f"coefficients[{', '.join(map(str, index + (0,)))}]",
            0.0,
            "a nonzero leading coefficient a4 (a polynomial of degree four)",
        )
    return c


def _largest_real_cubic_root(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Largest real root of ``t^3 + A t^2 + B t + C`` (closed form, then one guarded Newton step)."""
    A3 = A / 3
    P = B - A * A3
    Q = (2 * A3 * A3 - B) * A3 + C
    half_q = Q / 2
    third_p = P / 3
    D = half_q * half_q + third_p * third_p * third_p
    # one real root (D > 0): Cardano with the cancellation-free sign
    u = np.cbrt(-half_q - np.copysign(np.sqrt(np.maximum(D, 0.0)), Q))
    one_real = np.where(u != 0, u - third_p / u, 0.0)
    # three real roots (D <= 0): the largest, trigonometric form
    rho = np.sqrt(np.maximum(-third_p, 0.0))
    cos3 = np.clip(-half_q / (rho * rho * rho), -1.0, 1.0)
    three_real = 2 * rho * np.cos(np.arccos(np.where(rho > 0, cos3, 1.0)) / 3)
    t = np.where(D > 0, one_real, three_real) - A3
    f = ((t + A) * t + B) * t + C
    df = (3 * t + 2 * A) * t + B
    new = t - f / df
    f_new = ((new + A) * new + B) * new + C
    return np.where(np.abs(f_new) < np.abs(f), new, t)


def _small_real_root(z: np.ndarray, size: np.ndarray, b0: np.ndarray) -> np.ndarray:
    """Recompute a lone small real root from Vieta's product ``z1 z2 z3 z4 = b0``.

    The depressed form loses the relative accuracy of a root much smaller than the others (the
    capsize eigenvalue near the capsize speed); the product of the other three does not.
    ``size`` is ``|z|``; it is updated in place for the recomputed roots.
    """
    k = size.argmin(axis=0)
    cols = np.arange(z.shape[1])
    smallest_size = size[k, cols]
    size[k, cols] = np.inf
    next_size = size.min(axis=0)
    size[k, cols] = smallest_size
    candidate = (z.imag[k, cols] == 0) & (smallest_size < 0.1 * next_size)
    if not candidate.any():
        return z
    j = np.flatnonzero(candidate)
    kj = k[j]
    # the product of the other three roots (never divided by the inaccurate small one)
    others = np.ones(len(j), dtype=complex)
    for i in range(4):
        others *= np.where(kj == i, 1.0, z[i, j])
    ok = others.real != 0
    j, kj = j[ok], kj[ok]
    better = b0[j] / others.real[ok]
    z = z.copy()
    z[kj, j] = better
    size[kj, j] = np.abs(better)
    return z


def _horner(z: np.ndarray, b3, b2, b1, b0) -> np.ndarray:
    return (((z + b3) * z + b2) * z + b1) * z + b0


def _polish(z: np.ndarray, a: np.ndarray, b3, b2, b1, b0) -> np.ndarray:
    """Guarded Newton steps on the scaled monic quartic; ``z`` is ``(4, n)``, coefficients ``(n,)``.

    Only the columns holding a root whose backward error exceeds :data:`_BACKWARD` are polished.
    A step is taken only where it lowers the residual and moves the root by less than half the
    distance to its nearest neighbour.  ``a`` is ``|z|``.
    """
    bound = (((a + np.abs(b3)) * a + np.abs(b2)) * a + np.abs(b1)) * a + np.abs(b0)
    p = _horner(z, b3, b2, b1, b0)
    bound *= _BACKWARD
    rough = (np.abs(p) > bound).any(axis=0)
    if not rough.any():
        return z
    cols = np.flatnonzero(rough)
    w, p = z[:, cols], p[:, cols]
    c3, c2, c1, c0 = b3[cols], b2[cols], b1[cols], b0[cols]
    gap = np.full(w.shape, np.inf)
    for i in range(4):
        for j in range(i + 1, 4):
            d = np.abs(w[i] - w[j])
            np.minimum(gap[i], d, out=gap[i])
            np.minimum(gap[j], d, out=gap[j])
    residual = np.abs(p)
    for _ in range(NEWTON_STEPS):
        dp = ((4 * w + 3 * c3) * w + 2 * c2) * w + c1
        step = p / dp
        new = w - step
        p_new = _horner(new, c3, c2, c1, c0)
        new_residual = np.abs(p_new)
        ok = (new_residual < residual) & (np.abs(step) < 0.5 * gap)
        if not ok.any():
            break
        w = np.where(ok, new, w)
        p = np.where(ok, p_new, p)
        residual = np.where(ok, new_residual, residual)
    z = z.copy()
    z[:, cols] = w
    return z


def quartic_roots(coefficients) -> np.ndarray:
    """The four complex roots of real quartics, for any batch shape.

    Parameters
    ----------
    coefficients : array_like, shape (..., 5)
        ``[a4, a3, a2, a1, a0]`` of ``a4 x^4 + a3 x^3 + a2 x^2 + a1 x + a0``, highest power first
        (the layout of ``characteristic_coefficients``), ``a4 != 0``.

    Returns
    -------
    numpy.ndarray, shape (..., 4), complex
        The roots, sorted by real part then imaginary part.  Complex roots of real quartics come
        in conjugate pairs.

    Raises
    ------
    InputError
        A last dimension other than 5, a non-finite coefficient or a zero leading coefficient
        (named by its index).
    """
    return np.sort(_roots(_check_coefficients(coefficients)), axis=-1)


def _roots(c: np.ndarray) -> np.ndarray:
    """Unsorted roots of checked coefficients ``(..., 5)``."""
    with np.errstate(all="ignore"):  # divisions by zero are masked by np.where
        return _factored_roots(c.reshape(-1, 5)).T.reshape(c.shape[:-1] + (4,))


def _factored_roots(c: np.ndarray) -> np.ndarray:
    """Roots ``(4, n)`` of coefficients ``(n, 5)`` in the order of the two quadratic factors:
    rows 0-1 and rows 2-3 are each a conjugate pair (row 0 / row 2 with either sign of the
    imaginary part) or two real roots."""
    flat = c.T
    monic = flat[1:] / flat[0]
    # Scale x = sigma z so that the roots are of order one (a Fujiwara-type bound).
    a = np.abs(monic)
    sigma = np.maximum(np.maximum(a[0], np.sqrt(a[1])), np.maximum(np.cbrt(a[2]), np.sqrt(np.sqrt(a[3]))))
    sigma = np.where(sigma > 0, sigma, 1.0)
    inv = 1.0 / sigma
    inv2 = inv * inv
    b3, b2, b1, b0 = monic[0] * inv, monic[1] * inv2, monic[2] * inv2 * inv, monic[3] * inv2 * inv2
    # Depressed quartic y^4 + p y^2 + q y + r, z = y - b3/4.
    e = b3 / 4
    e2 = e * e
    p = b2 - 6 * e2
    q = b1 - 2 * b2 * e + 8 * e2 * e
    r = b0 - b1 * e + b2 * e2 - 3 * e2 * e2
    # Resolvent cubic: (y^2 + m)^2 - (s y - h)^2 with s^2 = 2m - p, h = q / (2s), h^2 = m^2 - r.
    m = _largest_real_cubic_root(-p / 2, -r, p * r / 2 - q * q / 8)
    s2 = np.maximum(2 * m - p, 0.0)
    s = np.sqrt(s2)
    # h from q / (2s) or from h^2 = m^2 - r (>= 0 for the largest m), whichever cancels less.
    h2 = np.maximum(m * m - r, 0.0)
    h = np.where(s2 >= h2, q / (2 * s), np.copysign(np.sqrt(h2), q))
    h = np.where(np.isfinite(h), h, 0.0)
    re1, im1, re2, im2 = monic_quadratic_roots(np.stack([-s, s]), np.stack([m + h, m - h]))
    z = np.empty((4,) + s.shape, dtype=complex)
    z.real[0::2], z.real[1::2] = re1 - e, re2 - e  # rows 0-1: first factor, 2-3: second
    z.imag[0::2], z.imag[1::2] = im1, im2
    size = np.abs(z)
    z = _small_real_root(z, size, b0)
    z = _polish(z, size, b3, b2, b1, b0)
    return z * sigma


# -- eigenvalues ---------------------------------------------------------------------------------
def eigenvalues_from_polynomial(model, speeds) -> ModalEigenvalues:
    """Eigenvalues of ``model`` at each speed, from the characteristic polynomial.

    Parameters
    ----------
    model : bikerider.benchmark.WhippleModel
        Anything with ``characteristic_coefficients(speeds)`` (one bicycle or a batch).
    speeds : array_like, shape (n,)
        Speeds [m/s].

    Returns
    -------
    ModalEigenvalues
        As :meth:`WhippleModel.eigenvalues` returns (see the module docstring for the accuracy),
        named as :meth:`WhippleModel.eigenvalues` names them (by continuation,
        :mod:`bikerider.benchmark.mode_names`); values of shape
        ``batch_shape + (n, 4)``.

    Raises
    ------
    InputError
        Speeds that are not a one-dimensional array of finite numbers.
    """
    speeds = check_speeds(speeds)
    coefficients = _check_coefficients(model.characteristic_coefficients(speeds))
    with np.errstate(all="ignore"):  # divisions by zero are masked by np.where
        roots = _factored_roots(coefficients.reshape(-1, 5))
    n = speeds.size
    if hasattr(model, "name_modes"):  # a WhippleModel: names by continuation in speed
        values, labels = model.name_modes(speeds, roots.T.reshape(-1, n, 4))
    else:
        values, labels = label_modes(roots.T)
    shape = coefficients.shape[:-1] + (4,)
    return ModalEigenvalues(speeds, values.reshape(shape), labels.reshape(shape))


__all__ = ["eigenvalues_from_polynomial", "quartic_roots"]
