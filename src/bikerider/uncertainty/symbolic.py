"""Closed-form sensitivities as SymPy expressions: the chain rule over the emitted stage expressions.

``derive/sensitivities.py`` emits each stage's expressions (``generated.sensitivities.EXPRESSIONS``,
``srepr`` text); this module parses them, renames each stage's local symbols to the nodes they
stand for, and differentiates.  A derivative ``d y / d x`` is returned as a list of exact steps,
one per intermediate quantity on the way::

    d y/d x   = sum_k  (partial y / partial m_k) * d m_k/d x
    d m_k/d x = ...

with the intermediate *values* (``m_B``, ``x_B``, ``M_phiphi``, ...) kept as symbols.  Where the
whole substitution stays small it is also given in one piece (:attr:`closed_form`).  A speed is a
root of its condition ``F = 0``; its step is the implicit derivative ``-(dF/dx) / (dF/dv)``, with
the characteristic coefficients evaluated at that speed.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import cache

import numpy as np
import sympy as sp

from bikerider.errors import InputError
from bikerider.generated import benchmark_model as gen_model
from bikerider.generated.sensitivities import EXPRESSIONS
from bikerider.uncertainty import names
from bikerider.uncertainty.chain import Chain, with_optional
from bikerider.uncertainty.stages import COEFFICIENTS, ENTRIES

SIMPLIFY_LIMIT = 40
"""Partial derivatives up to this many operations are factored (half as many: ``sympy.simplify``)."""
CLOSED_FORM_LIMIT = 600
"""A closed form is built only when its estimated size stays below this many operations."""


@cache
def _stage_expressions(key: str) -> tuple[tuple[str, ...], tuple[str, ...], tuple[sp.Expr, ...]]:
    inputs, outputs, texts = EXPRESSIONS[key]
    return inputs, outputs, tuple(sp.sympify(t) for t in texts)


@cache
def node_symbol(name: str, positive: bool = False) -> sp.Symbol:
    """The symbol standing for node ``name`` (positive where its stage's symbol is)."""
    return sp.Symbol(name, positive=True) if positive else sp.Symbol(name, real=True)


@cache
def derivative_symbol(node: str, wrt: str) -> sp.Symbol:
    """A symbol printed ``d<node>/d<wrt>`` standing for a total derivative."""
    return sp.Symbol(f"d{node}/d{wrt}")


@dataclass(frozen=True)
class SymbolicStage:
    """A stage with its expressions in node symbols.

    ``solves`` names the node the stage determines implicitly (its one expression is ``F`` with
    ``F = 0`` at that node's value); otherwise each output has an explicit expression.
    """

    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    exprs: dict[str, sp.Expr]
    solves: str | None = None


def _renamed(
    key: str,
    local_inputs: tuple[str, ...],
    nodes_in: tuple[str, ...],
    nodes_out: tuple[str, ...],
    solves: str | None = None,
) -> SymbolicStage:
    inputs, outputs, exprs = _stage_expressions(key)
    if tuple(inputs) != tuple(local_inputs):
        raise RuntimeError(f"stage {key}: generated inputs {inputs} differ from {local_inputs}; run make derive")
    local = {s.name: s for e in exprs for s in e.free_symbols}
    mapping = {}
    for loc, node in zip(local_inputs, nodes_in):
        if loc in local:
            mapping[local[loc]] = node_symbol(node, bool(local[loc].is_positive))
    renamed = [e.xreplace(mapping) for e in exprs]
    if solves is not None:
        return SymbolicStage(nodes_in, (solves,), {solves: renamed[0]}, solves)
    return SymbolicStage(nodes_in, nodes_out, dict(zip(nodes_out, renamed)))


def symbolic_stages(chain: Chain, output: str) -> dict[str, SymbolicStage]:
    """Node -> the symbolic stage producing it, for the stages ``chain`` runs."""
    producers: dict[str, SymbolicStage] = {}
    for stage in chain.stages:
        if stage.symbolic is None or stage.name == "characteristic":
            continue
        s = _renamed(stage.symbolic, stage.args, stage.inputs, stage.outputs)
        producers.update({o: s for o in s.outputs})
    args = EXPRESSIONS["characteristic"][0]  # the matrix entries, g and the speed v
    at_speed = {"v": output}  # a speed's condition is taken at that speed
    if output == "v_capsize":
        producers["v_capsize"] = _renamed(
            "capsize_condition", args, tuple(at_speed.get(a, a) for a in args), (), solves="v_capsize"
        )
    elif output == "v_weave":
        s = _renamed("characteristic", args, tuple(at_speed.get(a, a) for a in args), COEFFICIENTS)
        producers.update({o: s for o in COEFFICIENTS})
        weave_args = EXPRESSIONS["weave_condition"][0]  # the coefficients and v
        producers["v_weave"] = _renamed(
            "weave_condition", weave_args, tuple(at_speed.get(a, a) for a in weave_args), (), solves="v_weave"
        )
    elif output in COEFFICIENTS and "characteristic" in {st.name for st in chain.stages}:
        s = _renamed("characteristic", args, args, COEFFICIENTS)
        producers.update({o: s for o in COEFFICIENTS})
    return producers


def _symbol(name: str, stage: SymbolicStage) -> sp.Symbol:
    for e in stage.exprs.values():
        for s in e.free_symbols:
            if s.name == name:
                return s
    return node_symbol(name)


def _tidy(expr: sp.Expr) -> sp.Expr:
    """The shortest of a few equal forms (``simplify`` only for small expressions)."""
    ops = sp.count_ops(expr)
    candidates = [expr]
    if ops <= 8 * SIMPLIFY_LIMIT:
        candidates.append(sp.factor_terms(expr))
    if ops <= SIMPLIFY_LIMIT:
        candidates.append(sp.factor(sp.cancel(expr)))
    if ops <= SIMPLIFY_LIMIT // 2:
        candidates.append(sp.simplify(expr))
    return min(candidates, key=lambda e: (sp.count_ops(e), candidates.index(e)))


@dataclass
class SensitivityExpression:
    """``d output / d wrt`` as exact chain-rule steps, and in one piece when small.

    Attributes
    ----------
    output, wrt : str
        Node names.
    steps : list of (Symbol, Expr)
        ``d<node>/d<wrt> = expression``, the output's first; expressions use node symbols and the
        derivative symbols of later steps.
    conditions : list of (str, Expr)
        For speeds: the condition ``F`` whose root the speed is.
    closed_form : Expr or None
        Every step substituted into the first (None when that would exceed
        :data:`CLOSED_FORM_LIMIT` operations).
    size : int
        Estimated operations of the closed form.
    """

    output: str
    wrt: str
    steps: list[tuple[sp.Symbol, sp.Expr]]
    conditions: list[tuple[str, sp.Expr]] = field(default_factory=list)
    closed_form: sp.Expr | None = None
    size: int = 0

    @property
    def expression(self) -> sp.Expr:
        """The closed form when available, else the first step (with derivative symbols)."""
        if self.closed_form is not None:
            return self.closed_form
        return self.steps[0][1] if self.steps else sp.Integer(0)

    def evaluate(self, point: Mapping[str, float]) -> float:
        """The derivative's value with node values ``point`` (all the steps' nodes needed)."""
        point = _with_coefficients(point, self.output)
        values: dict[sp.Symbol, sp.Expr] = {}
        for s in {s for _, rhs in self.steps for s in rhs.free_symbols}:
            if s.name in point:
                values[s] = sp.Float(float(point[s.name]), 30)
        for lhs, rhs in reversed(self.steps):
            values[lhs] = sp.N(rhs.xreplace(values), 30)
        if not self.steps:
            return 0.0
        result = values[self.steps[0][0]]
        if result.free_symbols:
            missing = sorted(s.name for s in result.free_symbols)
            raise InputError("point", missing[:5], "values for every node the expression uses")
        return float(result)

    def latex_names(self) -> dict[sp.Symbol, str]:
        """``symbol_names`` for ``sympy.latex``: LaTeX of the nodes and of the derivative symbols."""
        out: dict[sp.Symbol, str] = {}
        for lhs, rhs in self.steps:
            for s in rhs.free_symbols | {lhs}:
                if "/" in s.name:
                    node, wrt = s.name[1:].split("/d", 1)
                    out[s] = rf"\frac{{d {names.latex(node)}}}{{d {names.latex(wrt)}}}"
                else:
                    out[s] = names.latex(s.name)
        for _, F in self.conditions:
            for s in F.free_symbols:
                out.setdefault(s, names.latex(s.name))
        return out


def _with_coefficients(point: Mapping[str, float], output: str) -> Mapping[str, float]:
    """Add the characteristic coefficients at the weave speed, which the weave steps use."""
    if output != "v_weave" or "a0" in point or "v_weave" not in point:
        return point
    coefficients = gen_model.characteristic_coefficients(
        **{k: np.asarray(point[k], dtype=float) for k in ENTRIES}, g=float(point["g"]), v=float(point["v_weave"])
    )
    return {**point, **{name: float(c) for name, c in zip(COEFFICIENTS, coefficients)}}


class _Deriver:
    """Builds the steps of ``d output / d wrt`` over the symbolic stages."""

    def __init__(self, producers: dict[str, SymbolicStage], wrt: str):
        self.producers, self.wrt = producers, wrt
        self.steps: dict[str, sp.Expr] = {}
        self.order: list[str] = []
        self.conditions: list[tuple[str, sp.Expr]] = []
        self._depends: dict[tuple[str, str | None], bool] = {}
        self.zero: set[str] = set()

    def depends(self, node: str, fixed: str | None = None) -> bool:
        key = (node, fixed)
        if key not in self._depends:
            self._depends[key] = False  # guards cycles through an implicitly solved node
            stage = self.producers.get(node)
            if node == self.wrt:
                result = True
            elif node == fixed or stage is None:
                result = False
            else:
                inner = stage.solves if stage.solves else fixed
                result = any(self.depends(i, inner) for i in stage.inputs if i != stage.solves)
            self._depends[key] = result
        return self._depends[key]

    def build(self, node: str, fixed: str | None = None) -> sp.Symbol | sp.Expr:
        """The derivative symbol of ``node`` (its step built on the way), 1 or 0."""
        if node == self.wrt:
            return sp.Integer(1)
        if not self.depends(node, fixed):
            return sp.Integer(0)
        lhs = derivative_symbol(node, self.wrt)
        if node in self.zero:
            return sp.Integer(0)
        if node in self.steps:
            return lhs
        self.steps[node] = sp.Integer(0)  # placeholder while the inputs' steps are built
        stage = self.producers[node]
        expr = stage.exprs[node]
        if stage.solves:
            self.conditions.append((node, expr))
            v = _symbol(node, stage)
            dF_dv = expr.diff(v)
            numerator = sp.Integer(0)
            for i in stage.inputs:
                if i == node:
                    continue
                s = _symbol(i, stage)
                partial = expr.diff(s)
                if partial == 0:
                    continue
                inner = self.producers.get(i)
                if inner is not None and node in inner.inputs and not inner.solves:
                    dF_dv += partial * inner.exprs[i].diff(_symbol(node, inner))
                if self.depends(i, node):
                    numerator += _tidy(_in_outputs(partial, stage)) * self.build(i, node)
            if numerator == 0:
                return self._is_zero(node)
            self.steps[node] = -numerator / _tidy(_in_outputs(dF_dv, stage))
            self.order.append(node)
        else:
            total = sp.Integer(0)
            for i in stage.inputs:
                if i == fixed or not self.depends(i, fixed):
                    continue
                partial = expr.diff(_symbol(i, stage))
                if partial != 0:
                    total += _tidy(_in_outputs(partial, stage)) * self.build(i, fixed)
            if total == 0:
                return self._is_zero(node)
            self.steps[node] = total
            self.order.append(node)
        return lhs

    def _is_zero(self, node: str) -> sp.Integer:
        """Record that ``node`` does not depend on ``wrt`` after all (its partials cancel)."""
        del self.steps[node]
        self.zero.add(node)
        return sp.Integer(0)


def _in_outputs(expr: sp.Expr, stage: SymbolicStage) -> sp.Expr:
    """Write the stage's own small output expressions back as their symbols (e.g. x_B)."""
    if stage.solves is not None:
        return expr
    small = [(name, e) for name, e in stage.exprs.items() if not e.is_Symbol and sp.count_ops(e) <= 30]
    for name, e in sorted(small, key=lambda item: -sp.count_ops(item[1])):  # largest first
        expr = expr.subs(e, node_symbol(name, bool(e.is_positive)))
    return expr


def _closed_form(steps: list[tuple[sp.Symbol, sp.Expr]]) -> tuple[sp.Expr | None, int]:
    sizes: dict[sp.Symbol, int] = {}
    for lhs, rhs in reversed(steps):
        own = int(sp.count_ops(rhs))
        sizes[lhs] = own + sum(sizes.get(s, 0) for s in rhs.free_symbols if s in sizes)
    size = sizes[steps[0][0]] if steps else 0
    if size > CLOSED_FORM_LIMIT:
        return None, size
    done: dict[sp.Symbol, sp.Expr] = {}
    for lhs, rhs in reversed(steps):
        done[lhs] = rhs.xreplace(done)
    expr = done[steps[0][0]]
    return (_tidy(expr) if sp.count_ops(expr) <= 2 * SIMPLIFY_LIMIT else expr), size


def sensitivity_expression(output: str, wrt: str, provided: Iterable[str]) -> SensitivityExpression:
    """``d output / d wrt`` for a chain entered with the nodes ``provided``.

    Parameters
    ----------
    output : str
        Any node (``weave_speed``, ``capsize_speed``, a benchmark name, ``M_phidelta``, ``xBr``...).
    wrt : str
        An input, or an intermediate node (then held as the variable, its own inputs ignored).
    provided : iterable of str
        The input names (e.g. the keys of :func:`bikerider.uncertainty.inputs.paper_inputs`).

    Raises
    ------
    InputError
        Unknown names, or an output the inputs cannot reach.
    """
    provided = with_optional(provided)
    chain = Chain(provided)
    known = set(chain.available) | {"v_weave", "v_capsize"} | set(COEFFICIENTS)
    output = names.check_name(output, known, "OUTPUT")
    wrt = names.check_name(wrt, known, "--wrt")
    chain.require([output] if output not in COEFFICIENTS else ["g"])
    if output in COEFFICIENTS and "v" not in provided:
        raise InputError("v", "missing", "a speed (--speed) for the characteristic coefficients")
    producers = symbolic_stages(chain, output)
    deriver = _Deriver(producers, wrt)
    top = deriver.build(output)
    if top == 1 or top == 0:
        lhs = derivative_symbol(output, wrt)
        return SensitivityExpression(output, wrt, [(lhs, sp.Integer(top))], closed_form=sp.Integer(top))
    # deriver.order is children-first; the steps read parent-first
    steps = [(derivative_symbol(n, wrt), deriver.steps[n]) for n in reversed(deriver.order)]
    closed, size = _closed_form(steps)
    return SensitivityExpression(output, wrt, steps, deriver.conditions, closed, size)
