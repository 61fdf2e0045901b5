"""First-order propagation of standard uncertainties through a function of named values.

The function maps a dict of input floats to a dict of output floats.  Its Jacobian is taken by
central differences, one input at a time, over the inputs that carry an uncertainty; inputs are
treated as independent.  Because the whole chain is differentiated at once, outputs that share an
input (every inertia shares the pendulum stiffness, every centre of mass the steer axis tilt) get
their uncertainty from one derivative of the chain rather than from stacked independent steps.

The ``2 k + 1`` points (the nominal one and a step up and down in each of the ``k`` inputs with an
uncertainty) are evaluated either one at a time, or, for a function written with NumPy that
accepts arrays (``vectorized=True``), all in one call with every input a 1-D array of the points.
The second is what makes the raw-measurement reduction fast: one pass of array operations instead
of ``2 k + 1`` passes of scalar ones.  Both go through the same central-difference code below.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np

from bikerider.quantity import Quantity

#: Step of the central difference, relative to ``max(|x|, sigma)`` of each input.
RELATIVE_STEP = 1e-6


def perturbed_points(inputs: Mapping[str, Quantity]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The points at which :func:`propagate` evaluates the function.

    Returns
    -------
    points : ndarray, shape (n_inputs, 2 k + 1)
        Column 0 holds the nominal values; columns ``2 j + 1`` and ``2 j + 2`` the nominal values
        with the ``j``-th uncertain input stepped up and down.
    varied : ndarray of int, shape (k,)
        Index (in ``inputs`` order) of each input with a positive uncertainty.
    steps : ndarray, shape (k,)
        The step of each of those inputs: :data:`RELATIVE_STEP` ``* max(|x|, sigma)``.
    sigmas : ndarray, shape (k,)
        The standard uncertainty of each of those inputs.
    """
    quantities = inputs.values()
    nominal = np.array([q.value for q in quantities], dtype=float)
    sigma = np.array([q.sigma for q in quantities], dtype=float)
    varied = np.flatnonzero(sigma > 0)
    sigma = sigma[varied]
    steps = RELATIVE_STEP * np.maximum(np.abs(nominal[varied]), sigma)
    k = len(varied)
    points = np.repeat(nominal[:, None], 2 * k + 1, axis=1)
    columns = np.arange(k)
    points[varied, 2 * columns + 1] += steps
    points[varied, 2 * columns + 2] -= steps
    return points, varied, steps, sigma


def propagate(function: Callable[[dict], dict],
              inputs: Mapping[str, Quantity], *, vectorized: bool = False) -> dict[str, Quantity]:
    """Evaluate ``function`` at the input values and attach first-order standard uncertainties.

    Parameters
    ----------
    function : callable
        ``function(values) -> outputs``; dicts of name to float.  Must not raise for inputs within
        a millionth of their uncertainty of the nominal values.  With ``vectorized`` every input
        is a 1-D array of the ``2 k + 1`` points of :func:`perturbed_points`, the first one the
        nominal point, and every output must be an array of that length (or a scalar, the same
        at every point).
    inputs : mapping of str to Quantity
    vectorized : bool
        Evaluate all points in one call (see above) instead of one call per point.

    Returns
    -------
    dict of str to Quantity
        Every output with ``sigma = sqrt(sum_i (d out / d in_i * sigma_i)^2)``.  An output that is
        NaN at the nominal point (not determined by these inputs) keeps sigma 0.
    """
    names = list(inputs)
    points, _, steps, sigma = perturbed_points(inputs)
    n_points = points.shape[1]
    if vectorized:
        outputs = function(dict(zip(names, points)))
        keys = list(outputs)
        try:  # every output an array over the points: one copy
            table = np.array(list(outputs.values()), dtype=float).reshape(len(keys), n_points)
        except ValueError:  # some are scalars (the same at every point)
            table = np.empty((len(keys), n_points))
            for row, key in zip(table, keys):
                row[...] = outputs[key]
    else:
        evaluations = [function(dict(zip(names, column))) for column in points.T.tolist()]
        keys = list(evaluations[0])
        table = np.array([[float(e[key]) for key in keys] for e in evaluations]).T.reshape(len(keys), n_points)
    centre = table[:, 0].tolist()
    with np.errstate(over="ignore", invalid="ignore"):
        slopes = (table[:, 1::2] - table[:, 2::2]) / (2 * steps)
        terms = slopes * sigma
        variance = np.where(np.isfinite(slopes), terms * terms, 0.0).sum(axis=1)
        sigmas = np.sqrt(variance).tolist()
    return {key: Quantity(value, sigma_ if math.isfinite(value) else 0.0)
            for key, value, sigma_ in zip(keys, centre, sigmas)}


__all__ = ["RELATIVE_STEP", "perturbed_points", "propagate"]
