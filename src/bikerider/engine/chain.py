"""A chain of stages: which run for the nodes given, their values and their Jacobian.

:meth:`Chain.gradients` is forward-mode differentiation: each stage's Jacobian multiplies the
stacked gradients of its inputs, so ``d node / d input`` is exact wherever the stages' Jacobians
are (generated ones are).  Values broadcast over any batch shape; plain floats stay floats, which
lets generated stages use their plain-float twins for one bicycle.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from bikerider.engine.stage import Stage
from bikerider.errors import InputError


class Rows(Mapping):
    """Gradients at one point: the rows of one matrix by node name; :attr:`matrix` and
    :attr:`index` give them whole (for products over many rows at once)."""

    def __init__(self, index: dict[str, int], matrix: np.ndarray):
        self.index, self.matrix = index, matrix

    def __getitem__(self, name: str) -> np.ndarray:
        return self.matrix[self.index[name]]

    def __iter__(self):
        return iter(self.index)

    def __len__(self) -> int:
        return len(self.index)


_NUMBERS = {float, int}


def _is_point(value: object) -> bool:
    """Whether a node's value is one number (a float, or a 0-d array), not a batch."""
    return type(value) is float or getattr(value, "ndim", 0) == 0


class Chain:
    """The stages that run when the nodes ``provided`` are given, in order.

    Parameters
    ----------
    stages : iterable of Stage
        Every stage the chain may run, in an order where each stage's inputs come from earlier ones
        or from the caller.
    provided : iterable of str
        Names of the nodes the caller gives values for.  A stage runs when all its inputs are
        available.

    Raises
    ------
    InputError
        A node given together with every measurement it is computed from (ambiguous).
    """

    def __init__(self, stages: Iterable[Stage], provided: Iterable[str]):
        self.provided = tuple(provided)
        available = set(self.provided)
        self.stages: list[Stage] = []
        for stage in stages:
            if not all(name in available for name in stage.inputs):
                continue
            given = [name for name in stage.outputs if name in available]
            if given:
                raw = [n for n in stage.inputs if n not in ("g", "k_t") and n in self.provided][:3]
                raise InputError(
                    given[0],
                    "given",
                    f"either {given[0]} or the measurements it is computed from ({', '.join(raw)}, ...), not both",
                )
            self.stages.append(stage)
            available.update(stage.outputs)
        self.available = available
        """The nodes given and computed (the stages' checks are computed too, but not listed)."""
        self._plans: dict[tuple, tuple] = {}

    def require(self, names: Sequence[str]) -> None:
        """Raise :class:`InputError` naming the first of ``names`` the inputs cannot give."""
        for name in names:
            if name not in self.available:
                raise InputError(
                    name,
                    "not computable from the inputs given",
                    "the measurements it depends on (see bikerider sensitivity --help)",
                )

    def evaluate(self, values: Mapping[str, object]) -> dict:
        """Value of every available node (checks included); arrays broadcast against each other."""
        nodes = dict(values)
        with np.errstate(invalid="ignore", divide="ignore"):
            for stage in self.stages:
                outputs, checks = stage.evaluate(stage.kwargs(nodes))
                nodes.update(zip(stage.outputs, outputs))
                nodes.update(zip(stage.checks, checks))
        return nodes

    def gradients(self, values: Mapping[str, object], wrt: Sequence[str]) -> tuple[dict, dict[str, np.ndarray]]:
        """Node values and ``d node / d wrt`` as arrays ``(..., len(wrt))`` for every output node.

        Forward mode: each stage's Jacobian multiplies the stacked gradients of its inputs.  A
        node not in ``wrt`` and not computed (a constant) has gradient zero.
        """
        if set(map(type, values.values())) <= _NUMBERS or all(_is_point(v) for v in values.values()):
            return self._point_gradients(values, wrt)
        nodes = dict(values)
        n = len(wrt)
        eye, zero = np.eye(n), np.zeros(n)
        index = {name: i for i, name in enumerate(wrt)}
        grads: dict[str, np.ndarray] = {name: eye[index[name]] if name in index else zero for name in nodes}
        with np.errstate(invalid="ignore", divide="ignore"):
            for stage in self.stages:
                outputs, checks, J = stage.evaluate_with_jacobian(stage.kwargs(nodes))
                nodes.update(zip(stage.outputs, outputs))
                nodes.update(zip(stage.checks, checks))
                inputs = [grads[name] for name in stage.inputs]
                if J.ndim == 2 and all(g.ndim == 1 for g in inputs):  # one point: no broadcasting needed
                    out = J @ np.array(inputs)
                else:
                    G = np.stack(np.broadcast_arrays(*inputs), axis=-2)
                    batch = np.broadcast_shapes(J.shape[:-2], G.shape[:-2])
                    out = np.broadcast_to(J, batch + J.shape[-2:]) @ np.broadcast_to(G, batch + G.shape[-2:])
                for k, name in enumerate(stage.outputs):
                    grads[name] = out[..., k, :]
        return nodes, grads

    def _point_gradients(self, values: Mapping[str, object], wrt: Sequence[str]) -> tuple[dict, dict[str, np.ndarray]]:
        """:meth:`gradients` at one point: the gradients are the rows of one matrix, each stage one
        product of its Jacobian with the rows of its inputs (no per-node arrays; the rows each stage
        reads and writes are worked out once for a set of names)."""
        rows, plan, seeds = self._plan(tuple(values), tuple(wrt))
        G = np.zeros((len(rows), len(wrt)))
        G[seeds, np.arange(len(wrt))] = 1.0
        nodes = dict(values)
        with np.errstate(invalid="ignore", divide="ignore"):
            for stage, inputs, outputs in plan:
                values_out, checks, J = stage.evaluate_with_jacobian(stage.kwargs(nodes))
                nodes.update(zip(stage.outputs, values_out))
                nodes.update(zip(stage.checks, checks))
                G[outputs] = J @ G[inputs]
        return nodes, Rows(rows, G)

    def _plan(self, names: tuple[str, ...], wrt: tuple[str, ...]):
        key = (names, wrt)
        if key not in self._plans:
            row = {name: i for i, name in enumerate(names)}
            for stage in self.stages:
                for name in stage.outputs:
                    row[name] = len(row)
            plan = [
                (stage, np.array([row[n] for n in stage.inputs]), np.array([row[n] for n in stage.outputs]))
                for stage in self.stages
            ]
            self._plans[key] = (row, plan, np.array([row[n] for n in wrt], dtype=int))
        return self._plans[key]
