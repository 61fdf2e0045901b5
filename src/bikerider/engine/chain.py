"""A chain of stages: which run for the nodes given, their values and their Jacobian.

:meth:`Chain.gradients` is forward-mode differentiation: each stage's Jacobian multiplies the
stacked gradients of its inputs, so ``d node / d input`` is exact wherever the stages' Jacobians
are (generated ones are).  Values broadcast over any batch shape; plain floats stay floats, which
lets generated stages use their plain-float twins for one bicycle.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from bikerider.engine.stage import Stage
from bikerider.errors import InputError


class Rows(Mapping):
    """Gradients at one point: the rows of one matrix by node name; :attr:`matrix` and
    :attr:`index` give them whole (for products over many rows at once).

    ``plan``, when given, is the :class:`_PointPlan` the matrix was computed by: it knows which
    entries of a row can be finite and not zero (:meth:`entries`).  ``entries``, when given
    instead of ``matrix``, are the stages' Jacobian entries one after another (a plan whose
    stages read only given nodes, :attr:`_PointPlan.direct`): the matrix is then built from them
    only when asked for, and :meth:`entries` gathers from them directly."""

    def __init__(
        self,
        index: dict[str, int],
        matrix: np.ndarray | None,
        plan: _PointPlan | None = None,
        entries: tuple[float, ...] | None = None,
    ):
        self.index, self.plan = index, plan
        self._matrix, self._entries = matrix, entries

    @property
    def matrix(self) -> np.ndarray:
        """``(len(index), len(wrt))``: every row."""
        if self._matrix is None:
            self._matrix = self.plan.matrix_of(self._entries)  # type: ignore[union-attr]
        return self._matrix

    def entries(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray, list[int]] | None:
        """``(values, columns, ends)``: the entries of the rows of ``names`` that can be finite and
        not zero, row after row (``ends``: where each row ends), and their columns; every other
        entry of these rows is zero or not finite.  ``None`` without a plan."""
        if self.plan is None:
            return None
        positions, columns, ends, sources = self.plan.entries(tuple(names))
        if self._matrix is None:
            return np.fromiter(self._entries, float, len(self._entries))[sources], columns, ends
        return self._matrix.reshape(-1)[positions], columns, ends

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
        self._plans: dict[tuple, _PointPlan] = {}

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
        """:meth:`gradients` at one point: the gradients are the rows of one matrix ``G``, each stage
        one product of its Jacobian with the rows of its inputs (no per-node arrays; the rows each
        stage reads and writes are worked out once for a set of names, see :class:`_PointPlan`).

        A stage that reads only given nodes, and gives its Jacobian as the entries that are not
        identically zero (a generated stage's float twin), has its entries written straight into
        ``G``: its inputs' rows hold one 1 each (or nothing), so the product is those entries, put
        in place.  Where an entry is not finite the product is taken, so that it spreads as it
        does through a product (``inf * 0`` is NaN).  When every stage is such a stage
        (:attr:`_PointPlan.direct`) and every entry is finite, the entries are kept as they come
        and :class:`Rows` gathers from them (the same numbers, no matrix until one is asked for).
        """
        plan = self._point_plan(tuple(values), tuple(wrt))
        if plan.direct:  # every stage reads given nodes only: its entries are the gradients
            nodes = dict(values)
            entries: tuple = ()
            with np.errstate(invalid="ignore", divide="ignore"):
                for stage, *_ in plan.steps:
                    values_out, checks, J, sparse = stage.evaluate_point(stage.kwargs(nodes))
                    nodes.update(zip(stage.outputs, values_out))
                    if checks:
                        nodes.update(zip(stage.checks, checks))
                    # a finite sum has no entry that is not (one that overflows goes the long way too)
                    if not (sparse and math.isfinite(sum(J))):
                        break  # to the matrix below, which spreads what is not finite
                    entries += tuple(J)
                else:
                    return nodes, Rows(plan.rows, None, plan, (*entries, 1.0))
        G = np.zeros(plan.shape)
        flat = G.reshape(-1)  # a view: writes by flat index land in G
        flat[plan.seeds] = 1.0
        nodes = dict(values)
        with np.errstate(invalid="ignore", divide="ignore"):
            for stage, inputs, outputs, selected, targets in plan.steps:
                values_out, checks, J, sparse = stage.evaluate_point(stage.kwargs(nodes))
                nodes.update(zip(stage.outputs, values_out))
                if checks:
                    nodes.update(zip(stage.checks, checks))
                if sparse:
                    entries = np.array(J, dtype=float)
                    if targets is not None and np.isfinite(entries).all():
                        flat[targets] = entries[selected]
                        continue
                    J = np.zeros((len(stage.outputs), len(stage.inputs)))
                    J.flat[stage.sparsity] = entries
                G[outputs] = J @ G[inputs]
        return nodes, Rows(plan.rows, G, plan)

    def _point_plan(self, names: tuple[str, ...], wrt: tuple[str, ...]) -> _PointPlan:
        key = (names, wrt)
        plan = self._plans.get(key)
        if plan is None:
            plan = self._plans[key] = _PointPlan(self.stages, names, wrt)
        return plan


class _PointPlan:
    """The rows of the gradient matrix for one set of given names and ``wrt``, worked out once.

    Attributes
    ----------
    rows : dict of str to int
        The row of each given and computed node.
    shape : tuple of int
        ``(len(rows), len(wrt))``.
    seeds : ndarray
        Flat indices of the 1s of the ``wrt`` nodes' rows.
    steps : list of tuple
        Per stage ``(stage, input rows, output rows, selected, targets)``: for a stage that reads
        only given nodes (each once) and can give its Jacobian's entries that are not identically
        zero (:attr:`Stage.sparsity`), ``selected`` are those of the entries whose input is in
        ``wrt`` and ``targets`` their flat indices in the gradient matrix; else both are ``None``.
    pattern : list of set of int
        Per row the columns whose entry can be finite and not zero: a ``wrt`` node's own column; a
        stage output's, those of the inputs its Jacobian entry is not identically zero for (every
        input where the stage gives no :attr:`Stage.sparsity`).  Any other entry is zero or not
        finite: a product with a zero Jacobian entry is zero (or NaN from ``0 * inf``), and so is
        a product with a zero gradient entry.
    direct : bool
        Whether every stage has its ``targets`` (reads only given nodes): the gradient matrix is
        then the seeds and the stages' entries, nothing else, and :meth:`Chain.gradients` keeps
        the entries as they come (:class:`Rows` builds the matrix only when asked for it).
    """

    def __init__(self, stages: Sequence[Stage], names: tuple[str, ...], wrt: tuple[str, ...]):
        self.rows = {name: i for i, name in enumerate(names)}
        for stage in stages:
            for name in stage.outputs:
                self.rows[name] = len(self.rows)
        n = len(wrt)
        self.shape = (len(self.rows), n)
        self.seeds = np.array([self.rows[name] * n + k for k, name in enumerate(wrt)], dtype=int)
        column = {name: k for k, name in enumerate(wrt)}
        given = set(names)
        written = set(wrt)  # rows that are not zero before their stage runs
        self.steps = []
        self.pattern: list[set[int]] = [set() for _ in self.rows]
        for k, name in enumerate(wrt):
            self.pattern[self.rows[name]] = {k}
        self._entries: dict[tuple[str, ...], tuple] = {}
        for stage in stages:
            self._add_pattern(stage)
            inputs = np.array([self.rows[name] for name in stage.inputs], dtype=int)
            outputs = np.array([self.rows[name] for name in stage.outputs], dtype=int)
            selected = targets = None
            sparsity = stage.sparsity
            if (
                sparsity is not None
                and given.issuperset(stage.inputs)
                and len(set(stage.inputs)) == len(stage.inputs)
                and written.isdisjoint(stage.outputs)
            ):
                row, col = np.divmod(sparsity, len(stage.inputs))
                wrt_column = np.array([column.get(stage.inputs[j], -1) for j in col.tolist()], dtype=int)
                keep = wrt_column >= 0
                selected = np.flatnonzero(keep)
                targets = outputs[row[keep]] * n + wrt_column[keep]
            written.update(stage.outputs)
            self.steps.append((stage, inputs, outputs, selected, targets))
        self.direct = bool(self.steps) and all(step[4] is not None for step in self.steps)
        # Where each written entry of the matrix is in the stages' entries one after another and
        # a final 1 (the seeds): what a direct plan's Rows gathers from.
        self._source: dict[int, int] = {}
        offset = 0
        self._targets, self._selected = [], []
        for stage, _, _, selected, targets in self.steps:
            if targets is not None:
                self._source.update(zip(targets.tolist(), (offset + selected).tolist()))
                self._targets += targets.tolist()
                self._selected += (offset + selected).tolist()
            offset += len(stage.sparsity) if stage.sparsity is not None else 0
        self._source.update(dict.fromkeys(self.seeds.tolist(), offset))

    def matrix_of(self, entries: tuple[float, ...]) -> np.ndarray:
        """The gradient matrix of a direct plan from its stages' entries one after another."""
        G = np.zeros(self.shape)
        flat = G.reshape(-1)
        flat[self.seeds] = 1.0
        flat[self._targets] = np.fromiter(entries, float, len(entries))[self._selected]
        return G

    def _add_pattern(self, stage: Stage) -> None:
        """The pattern of the rows ``stage`` writes (from its inputs' and its Jacobian's)."""
        n_in = len(stage.inputs)
        if stage.sparsity is None:
            structure: list = [range(n_in)] * len(stage.outputs)
        else:
            structure = [[] for _ in stage.outputs]
            for flat in stage.sparsity.tolist():
                structure[flat // n_in].append(flat % n_in)
        for name, inputs in zip(stage.outputs, structure):
            columns: set[int] = set()
            for j in inputs:
                columns |= self.pattern[self.rows[stage.inputs[j]]]
            self.pattern[self.rows[name]] = columns

    def entries(self, names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, list[int], np.ndarray | None]:
        """``(positions, columns, ends, sources)``: :meth:`Rows.entries` as flat indices into the
        matrix, and for a direct plan where each is in the stages' entries (else ``None``)."""
        found = self._entries.get(names)
        if found is None:
            n = self.shape[1]
            positions: list[int] = []
            columns: list[int] = []
            ends = []
            for name in names:
                row = self.rows[name]
                pattern = sorted(self.pattern[row])
                positions += [row * n + k for k in pattern]
                columns += pattern
                ends.append(len(positions))
            sources = np.array([self._source[p] for p in positions], dtype=int) if self.direct else None
            found = (np.array(positions, dtype=int), np.array(columns, dtype=int), ends, sources)
            self._entries[names] = found
        return found
