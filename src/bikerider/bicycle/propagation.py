"""First-order propagation of standard uncertainties through a function of named values.

The function maps a dict of input floats to a dict of output floats.  Its Jacobian is taken by
central differences, one input at a time, over the inputs that carry an uncertainty; inputs are
treated as independent.  Because the whole chain is differentiated at once, outputs that share an
input (every inertia shares the pendulum stiffness, every centre of mass the steer axis tilt) get
their uncertainty from one derivative of the chain rather than from stacked independent steps.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping

from bikerider.quantity import Quantity

#: Step of the central difference, relative to ``max(|x|, sigma)`` of each input.
RELATIVE_STEP = 1e-6


def propagate(function: Callable[[dict[str, float]], dict[str, float]],
              inputs: Mapping[str, Quantity]) -> dict[str, Quantity]:
    """Evaluate ``function`` at the input values and attach first-order standard uncertainties.

    Parameters
    ----------
    function : callable
        ``function(values) -> outputs``; dicts of name to float.  Must not raise for inputs within
        a millionth of their uncertainty of the nominal values.
    inputs : mapping of str to Quantity

    Returns
    -------
    dict of str to Quantity
        Every output with ``sigma = sqrt(sum_i (d out / d in_i * sigma_i)^2)``.  An output that is
        NaN at the nominal point (not determined by these inputs) keeps sigma 0.
    """
    nominal = {name: q.value for name, q in inputs.items()}
    centre = function(dict(nominal))
    variance = dict.fromkeys(centre, 0.0)
    for name, q in inputs.items():
        if q.sigma <= 0:
            continue
        step = RELATIVE_STEP * max(abs(q.value), q.sigma)
        up = function({**nominal, name: q.value + step})
        down = function({**nominal, name: q.value - step})
        for key in centre:
            slope = (up[key] - down[key]) / (2 * step)
            if math.isfinite(slope):
                term = slope * q.sigma  # float products overflow to inf; ** 2 would raise OverflowError
                variance[key] += term * term
    return {key: Quantity(value, math.sqrt(variance[key]) if math.isfinite(value) else 0.0)
            for key, value in centre.items()}
