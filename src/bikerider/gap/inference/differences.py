"""Forward-difference Jacobians of residuals evaluated for many parameter vectors in one batched call.

The gap's fits (:mod:`bikerider.gap.inference.problem`, :mod:`bikerider.gap.inference.timedomain`)
evaluate their residuals for a stack of parameter vectors at once; a Jacobian is then one call on the
point and the point moved by each step, a step taken backwards where forwards would cross the upper
bound.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def forward_jacobian(
    residuals_batch: Callable[[np.ndarray], np.ndarray], x: np.ndarray, steps: np.ndarray, upper: np.ndarray
) -> np.ndarray:
    """``d r / d x`` at ``x`` by one-sided differences of ``steps``, ``(n_residuals, n_parameters)``.

    Parameters
    ----------
    residuals_batch : callable
        ``(k, n_parameters) -> (k, n_residuals)``: the residuals of each row of parameter values.
    x : ndarray
        The point, ``(n_parameters,)``.
    steps : ndarray
        Each parameter's step (positive), ``(n_parameters,)``; taken backwards where ``x + step``
        would pass ``upper``.
    upper : ndarray
        The parameters' upper bounds.
    """
    h = steps * np.where(x + steps <= upper, 1.0, -1.0)
    R = residuals_batch(np.vstack([x, x + np.diag(h)]))
    return ((R[1:] - R[0]) / h[:, None]).T
