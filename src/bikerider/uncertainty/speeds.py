"""The weave and capsize speeds as a stage of the estimate chain.

The value is the root solve of :func:`bikerider.benchmark.roots.critical_speeds` (the rules of
:meth:`bikerider.benchmark.WhippleModel.critical_speeds`, for any batch shape); the Jacobian is the
implicit derivative ``dv/dp = -(dF/dp)/(dF/dv)`` at the root, emitted by ``derive/sensitivities.py``.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from bikerider.benchmark.roots import critical_speeds
from bikerider.engine import Stage, arguments, generated_function
from bikerider.generated.manifest import MATRIX_ENTRIES

SPEEDS = ("v_weave", "v_capsize")


def critical_speeds_from_entries(entries: Mapping[str, np.ndarray], g) -> dict[str, np.ndarray]:
    """``{"v_weave", "v_capsize", "weave_frequency"}`` for a batch of matrices (NaN: none)."""
    polynomials = generated_function("benchmark_model.critical_speed_polynomials")(**entries, g=g)
    weave, capsize, frequency = critical_speeds(*polynomials)
    return {"v_weave": weave, "v_capsize": capsize, "weave_frequency": frequency}


class CriticalSpeedsStage(Stage):
    """Matrix entries and ``g`` to the weave and capsize speeds."""

    name = "critical_speeds"
    outputs = SPEEDS

    def __init__(self):
        self.inputs = self.args = arguments("benchmark_model.critical_speed_polynomials")
        self._gradients = [generated_function(f"sensitivities.{speed.removeprefix('v_')}_speed_gradient")
                           for speed in SPEEDS]

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
