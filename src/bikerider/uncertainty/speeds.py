"""The weave and capsize speeds as a stage of the estimate chain.

The value is the stable-interval analysis of :mod:`bikerider.benchmark.stability` (the rules of
:meth:`bikerider.benchmark.WhippleModel.critical_speeds`: the crossings, with their direction, that
bound the first self-stable interval; NaN where there is no such speed), for one bicycle in plain
floats or for any batch shape at once; the Jacobian is the implicit derivative
``dv/dp = -(dF/dp)/(dF/dv)`` at the root, emitted by ``derive/sensitivities.py``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from bikerider.benchmark.roots import quadratic_roots  # noqa: F401 (importable here, where it was)
from bikerider.benchmark.stability import stability, stability_batch
from bikerider.engine import Stage, arguments, generated_function
from bikerider.generated.manifest import MATRIX_ENTRIES

SPEEDS = ("v_weave", "v_capsize")


def critical_speeds_from_entries(entries: Mapping[str, np.ndarray], g) -> dict[str, np.ndarray]:
    """``{"v_weave", "v_capsize", "weave_frequency"}`` for a batch of matrices (NaN: none), by the
    rules of :mod:`bikerider.benchmark.stability` (the crossings that bound the first stable interval).

    One bicycle's entries (0-d) take the plain-float path, ten times faster than NumPy on 0-d arrays
    (the same rules; the tests hold the two paths equal)."""
    if np.ndim(g) == 0 and all(np.ndim(v) == 0 for v in entries.values()):
        try:
            one = stability({k: float(v) for k, v in entries.items()}, float(g))
        except (OverflowError, ValueError):  # polynomials beyond floating point: no speed, as in a batch
            return {"v_weave": np.nan, "v_capsize": np.nan, "weave_frequency": np.nan}
        return {
            "v_weave": _nan(one.weave),
            "v_capsize": _nan(one.capsize),
            "weave_frequency": _nan(one.weave_frequency),
        }
    result = stability_batch(entries, g)
    return {"v_weave": result.weave, "v_capsize": result.capsize, "weave_frequency": result.weave_frequency}


def _nan(x: float | None) -> float:
    return np.nan if x is None else x


class CriticalSpeedsStage(Stage):
    """Matrix entries and ``g`` to the weave and capsize speeds."""

    name = "critical_speeds"
    outputs = SPEEDS

    def __init__(self):
        self.inputs = self.args = arguments("benchmark_model.critical_speed_polynomials")
        self._gradients = [
            generated_function(f"sensitivities.{speed.removeprefix('v_')}_speed_gradient") for speed in SPEEDS
        ]

    def evaluate(self, kw: Mapping[str, object]) -> tuple[list, list]:
        entries = {k: np.asarray(kw[k], dtype=float) for k in MATRIX_ENTRIES}
        speeds = critical_speeds_from_entries(entries, np.asarray(kw["g"], dtype=float))
        return [speeds[name] for name in SPEEDS], []

    def jacobian(self, kw: Mapping[str, object]) -> np.ndarray:
        """``(..., 2, 17)``: d[v_weave, v_capsize]/d[matrix entries, g] (NaN rows where no speed)."""
        speeds, _ = self.evaluate(kw)
        with np.errstate(invalid="ignore", divide="ignore"):
            rows = [gradient(**kw, v=speed) for gradient, speed in zip(self._gradients, speeds)]
        return np.stack(rows, axis=-2)
