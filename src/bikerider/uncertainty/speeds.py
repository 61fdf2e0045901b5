"""Weave and capsize speeds for a whole batch at once, and their implicit gradients.

The speeds are positive roots of quadratics in ``u = v^2`` (``generated.benchmark_model.
critical_speed_polynomials``), found with NumPy over any batch shape - no loop over samples - by
:func:`bikerider.benchmark.stability.stability_batch`, with the rules of
:meth:`bikerider.benchmark.WhippleModel.critical_speeds` (the crossings, with their direction, that
bound the first self-stable interval).  Where there is no such speed it is NaN.

The gradient with respect to the matrix entries and ``g`` is the implicit derivative
``dv/dp = -(dF/dp)/(dF/dv)`` emitted by ``derive/sensitivities.py``.
"""
from __future__ import annotations

import numpy as np

from bikerider.benchmark.stability import quadratic_roots, stability_batch  # noqa: F401 (re-export)
from bikerider.generated import sensitivities as gen
from bikerider.uncertainty.stages import Stage

_ENTRIES = tuple(f"{m}_{a}{b}" for m in ("M", "C1", "K0", "K2") for a in ("phi", "delta") for b in ("phi", "delta"))


def critical_speeds_from_entries(entries: dict[str, np.ndarray], g) -> dict[str, np.ndarray]:
    """``{"v_weave", "v_capsize", "weave_frequency"}`` for a batch of matrices (NaN: none), by the
    rules of :mod:`bikerider.benchmark.stability` (the crossings that bound the first stable interval)."""
    result = stability_batch(entries, g)
    return {"v_weave": result.weave, "v_capsize": result.capsize, "weave_frequency": result.weave_frequency}


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
