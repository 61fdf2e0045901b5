"""First-order propagation of standard uncertainties through a chain.

``sigma_y^2 = sum_j (dy/dx_j)^2 sigma_j^2`` over the independent inputs ``x_j`` that carry an
uncertainty, with ``dy/dx_j`` from :meth:`Chain.gradients` (exact where the stages' Jacobians are).
Outputs that share an input (every inertia shares the pendulum stiffness, every centre of mass the
steer axis tilt) get their uncertainty from one derivative of the whole chain rather than from
stacked independent steps.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from bikerider.engine.chain import Chain, Rows
from bikerider.engine.stage import Stage
from bikerider.quantity import Quantity


@dataclass(frozen=True)
class FirstOrder:
    """Values and first-order derivatives of a chain at one point.

    Attributes
    ----------
    nodes : dict
        The value of every node (inputs, outputs and checks).
    gradients : dict of str to ndarray
        ``d node / d wrt`` for every input and output node, shape ``(len(wrt),)``.
    wrt : tuple of str
        The inputs differentiated (by default those with a positive uncertainty).
    sigmas : ndarray
        Their standard uncertainties.
    """

    nodes: dict
    gradients: dict[str, np.ndarray]
    wrt: tuple[str, ...]
    sigmas: np.ndarray

    def jacobian(self, names: Sequence[str]) -> np.ndarray:
        """``(len(names), len(wrt))``: the derivatives of ``names``."""
        if isinstance(self.gradients, Rows):  # one point: the rows of one matrix
            return self.gradients.matrix[[self.gradients.index[n] for n in names]]
        rows = [self.gradients[n] for n in names]
        try:
            return np.array(rows, dtype=float).reshape(len(rows), len(self.wrt))
        except ValueError:  # rows of other shapes: a batch of one point
            return np.array([np.broadcast_to(row, (len(self.wrt),)) for row in rows], dtype=float)

    def sigma(self, name: str, skip_nonfinite: bool = True) -> float:
        """First-order standard uncertainty of ``name`` (0 for a node no uncertain input reaches).

        ``skip_nonfinite``: a derivative that is not finite contributes nothing (a slope at a
        value the inputs do not determine); otherwise the sigma is NaN.
        """
        grad = self.gradients.get(name)
        if grad is None or not len(self.wrt):
            return 0.0
        return _root_sum_squares(np.asarray(grad, dtype=float).reshape(1, -1), self.sigmas, skip_nonfinite)[0]

    def quantity(self, name: str) -> Quantity:
        """``name`` with its sigma; a value that is not finite (not determined) keeps sigma 0."""
        return self.quantities([name])[name]

    def quantities(self, names: Sequence[str]) -> dict[str, Quantity]:
        """:meth:`quantity` of each of ``names``, at once."""
        entries = self.gradients.entries(names) if isinstance(self.gradients, Rows) else None
        if not len(self.wrt):
            sigmas = [0.0] * len(names)
        elif entries is not None:  # one point: only the entries that can count
            sigmas = _root_sum_squares_of_entries(*entries, self.sigmas)
        else:
            sigmas = _root_sum_squares(self.jacobian(names), self.sigmas)
        nodes = self.nodes
        out = {}
        for name, sigma in zip(names, sigmas):
            value = float(nodes[name])
            out[name] = Quantity(value, sigma if value - value == 0 else 0.0)  # not finite: not determined
        return out


def _root_sum_squares(jacobian: np.ndarray, sigmas: np.ndarray, skip_nonfinite: bool = True) -> list[float]:
    """``sqrt(sum_j (J_ij sigma_j)^2)`` of each row ``i``; a term that is not finite contributes nothing
    (``skip_nonfinite``) or makes the row's sigma inf or NaN."""
    used = sigmas > 0
    terms = jacobian * sigmas if used.all() else jacobian[:, used] * sigmas[used]
    with np.errstate(invalid="ignore", over="ignore"):
        squares = terms * terms  # t * t: inf rather than OverflowError
    if skip_nonfinite:
        squares[~np.isfinite(squares)] = 0.0  # a slope at a value the inputs do not determine
    # fsum: correctly rounded, so the sigmas do not depend on the order of the inputs (a fit
    # weighted by them, as gap's, moves by more than the last digit when they change by one ulp).
    # Only the terms that are not zero are summed (a Jacobian is mostly zeros; zeros add nothing).
    nonzero = squares != 0
    terms_by_row = squares[nonzero].tolist()
    ends = np.cumsum(nonzero.sum(axis=1)).tolist()
    fsum, sqrt = math.fsum, math.sqrt
    return [sqrt(fsum(terms_by_row[start:end])) for start, end in zip([0, *ends], ends)]


def _root_sum_squares_of_entries(
    values: np.ndarray, columns: np.ndarray, ends: list[int], sigmas: np.ndarray
) -> list[float]:
    """:func:`_root_sum_squares` (skipping terms that are not finite) of rows given by the entries
    that can be finite and not zero (:meth:`Rows.entries`): the same terms, so the same sums."""
    with np.errstate(invalid="ignore", over="ignore"):
        terms = values * sigmas[columns]
        squares = (terms * terms).tolist()
    fsum, sqrt, isfinite = math.fsum, math.sqrt, math.isfinite
    try:  # the common case, every row's sum finite, in C loops
        totals = list(map(fsum, map(squares.__getitem__, map(slice, [0, *ends[:-1]], ends))))
    except OverflowError:
        pass
    else:
        if isfinite(sum(totals)):  # (sums of squares: a finite total has no sum that is not)
            return list(map(sqrt, totals))
    out = []
    start = 0
    for end in ends:
        row = squares[start:end]
        start = end
        try:
            total = fsum(row)
        except OverflowError:
            total = math.inf
        if not isfinite(total):  # a term that is not finite contributes nothing
            total = fsum([t for t in row if isfinite(t)])
        out.append(sqrt(total))
    return out


@functools.lru_cache(maxsize=256)
def _chain(stages: tuple[Stage, ...], names: frozenset[str]) -> Chain:
    """The chain of the same stages for the same input names, built once (one bicycle after another)."""
    return Chain(stages, names)


def first_order(
    stages: Iterable[Stage],
    quantities: Mapping[str, Quantity],
    chain: Chain | None = None,
    wrt: Sequence[str] | None = None,
) -> FirstOrder:
    """Evaluate the stages at the quantities' values and differentiate with respect to ``wrt``
    (default: every input with a positive uncertainty).  Floats stay floats (plain-float twins
    for one bicycle); arrays give a batch.  ``chain``: the stages already selected for these
    inputs (:class:`Chain`), when the caller has them."""
    chain = chain or _chain(tuple(stages), frozenset(quantities))
    values, uncertain, spread = {}, [], []
    for name, q in quantities.items():
        if type(q) is Quantity:
            values[name] = q.value
            sigma = q.sigma
        else:  # a plain number or an array: no uncertainty
            values[name] = getattr(q, "value", q)
            sigma = getattr(q, "sigma", 0.0)
        if sigma > 0:
            uncertain.append(name)
            spread.append(sigma)
    if wrt is None:
        wrt = tuple(uncertain)
    else:
        wrt = tuple(wrt)
        spread = [getattr(quantities[name], "sigma", 0.0) for name in wrt]
    nodes, gradients = chain.gradients(values, wrt)
    sigmas = np.array(spread, dtype=float)
    return FirstOrder(nodes, gradients, wrt, sigmas)


def propagate(
    stages: Iterable[Stage], quantities: Mapping[str, Quantity], outputs: Sequence[str] | None = None
) -> dict[str, Quantity]:
    """Every output of the stages (or those named) with its first-order standard uncertainty."""
    stages = list(stages)
    result = first_order(stages, quantities)
    names = outputs if outputs is not None else [o for stage in stages for o in stage.outputs]
    return result.quantities(names)
