"""Weave and capsize speeds for a whole batch at once, and their implicit gradients.

The speeds are the positive roots of quadratics in ``u = v^2`` (``generated.benchmark_model.
critical_speed_polynomials``), solved here with NumPy over any batch shape - no loop over
samples.  The rules are those of :meth:`bikerider.benchmark.WhippleModel.critical_speeds`:
capsize is the smallest positive root of ``det(g K0 + u K2)``; weave is the smallest positive
root of the third Hurwitz determinant at which ``omega^2 = a1/a3 > 0``.  Where there is no such
root the speed is NaN.

The gradient with respect to the matrix entries and ``g`` is the implicit derivative
``dv/dp = -(dF/dp)/(dF/dv)`` emitted by ``derive/sensitivities.py``.
"""
from __future__ import annotations

import numpy as np

from bikerider.generated import benchmark_model as gen_model
from bikerider.generated import sensitivities as gen
from bikerider.uncertainty.stages import Stage

_ENTRIES = tuple(f"{m}_{a}{b}" for m in ("M", "C1", "K0", "K2") for a in ("phi", "delta") for b in ("phi", "delta"))
_ZERO = 1e-14
"""Coefficients below this fraction of the largest are zero (as ``WhippleModel`` treats them)."""
_IMAG = 1e-9
"""A root whose imaginary part is below this fraction of ``max(1, |real part|)`` is real."""


def quadratic_roots(c2: np.ndarray, c1: np.ndarray, c0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two real roots of ``c2 u^2 + c1 u + c0`` (ascending), NaN where they are not real.

    Scale-aware: the coefficients are divided by the largest of them first; a leading
    coefficient below ``1e-14`` of it makes the polynomial linear (one root, the other NaN).
    """
    c2, c1, c0 = np.broadcast_arrays(*(np.asarray(c, dtype=float) for c in (c2, c1, c0)))
    scale = np.maximum(np.maximum(np.abs(c2), np.abs(c1)), np.abs(c0))
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(scale > 0, scale, np.nan)
        a, b, c = c2 / scale, c1 / scale, c0 / scale
        quadratic = np.abs(a) > _ZERO
        a_safe = np.where(quadratic, a, 1.0)
        disc = b * b - 4 * a_safe * c
        root_disc = np.sqrt(np.abs(disc))
        # A slightly negative discriminant from rounding is a double root (imaginary part tiny).
        real_pair = (disc >= 0) | (root_disc / (2 * np.abs(a_safe)) <= _IMAG * np.maximum(1.0, np.abs(b / (2 * a_safe))))
        root_disc = np.where(disc >= 0, root_disc, 0.0)
        q = -0.5 * (b + np.where(b >= 0, 1.0, -1.0) * root_disc)
        r1 = q / a_safe
        r2 = np.where(q != 0, c / np.where(q != 0, q, 1.0), r1)
        low, high = np.minimum(r1, r2), np.maximum(r1, r2)
        low = np.where(quadratic & real_pair, low, np.nan)
        high = np.where(quadratic & real_pair, high, np.nan)
        linear = ~quadratic & (np.abs(b) > _ZERO)
        linear_root = -c / np.where(linear, b, 1.0)
        low = np.where(linear, linear_root, low)
        high = np.where(linear, np.nan, high)
    return low, high


def _smallest_positive(roots: tuple[np.ndarray, np.ndarray], accept: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    low, high = roots
    with np.errstate(invalid="ignore"):
        ok_low = (low > 0) & accept[0]
        ok_high = (high > 0) & accept[1]
    return np.where(ok_low, low, np.where(ok_high, high, np.nan))


def critical_speeds_from_entries(entries: dict[str, np.ndarray], g) -> dict[str, np.ndarray]:
    """``{"v_weave", "v_capsize", "weave_frequency"}`` for a batch of matrices (NaN: none)."""
    capsize_c, weave_c, a1_c, a3_c = gen_model.critical_speed_polynomials(**entries, g=g)
    capsize_u = _smallest_positive(quadratic_roots(capsize_c[..., 0], capsize_c[..., 1], capsize_c[..., 2]),
                                   (True, True))  # type: ignore[arg-type]
    roots = quadratic_roots(weave_c[..., 0], weave_c[..., 1], weave_c[..., 2])
    with np.errstate(invalid="ignore", divide="ignore"):
        omega2 = [(a1_c[..., 0] * u + a1_c[..., 1]) / (a3_c[..., 0] * u + a3_c[..., 1]) for u in roots]
        accept = tuple(np.isfinite(w) & (w > 0) for w in omega2)
        weave_u = _smallest_positive(roots, accept)  # type: ignore[arg-type]
        omega2_at = np.where(weave_u == roots[0], omega2[0], omega2[1])
        return {
            "v_weave": np.sqrt(weave_u),
            "v_capsize": np.sqrt(capsize_u),
            "weave_frequency": np.where(np.isfinite(weave_u), np.sqrt(np.abs(omega2_at)), np.nan),
        }


def _value(kw: dict[str, np.ndarray]) -> list[np.ndarray]:
    entries = {k: kw[k] for k in _ENTRIES}
    out = critical_speeds_from_entries(entries, kw["g"])
    return [out["v_weave"], out["v_capsize"]]


def speed_gradients(kw: dict[str, np.ndarray], v_weave: np.ndarray, v_capsize: np.ndarray) -> np.ndarray:
    """``(..., 2, 17)``: d[v_weave, v_capsize]/d[matrix entries, g] (NaN rows where no speed)."""
    entries = {k: kw[k] for k in _ENTRIES}
    with np.errstate(invalid="ignore", divide="ignore"):
        weave = gen.weave_speed_gradient(**entries, g=kw["g"], v=v_weave)
        capsize = gen.capsize_speed_gradient(**entries, g=kw["g"], v=v_capsize)
    return np.stack([weave, capsize], axis=-2)


def _jacobian(kw: dict[str, np.ndarray]) -> np.ndarray:
    v_weave, v_capsize = _value(kw)
    return speed_gradients(kw, v_weave, v_capsize)


def speed_stage() -> Stage:
    """The critical speeds as a stage of the chain: matrix entries and g to both speeds."""
    inputs = _ENTRIES + ("g",)
    return Stage("critical_speeds", inputs, ("v_weave", "v_capsize"), inputs, _value, _jacobian, None)
