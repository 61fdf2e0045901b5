"""Stages: named inputs to named outputs, with a value and a Jacobian.

A *node* is a named quantity of a chain (a measurement, a reduced value, a matrix entry, a speed).
A :class:`Stage` turns input nodes into output nodes.  :class:`GeneratedStage` is a stage kind of
the manifest (``generated/manifest.py``, written by ``make derive``) bound to node names: its value
and Jacobian are generated functions, so nothing here restates a formula or an argument list.
Other stages compute what has no closed form: a root (``bikerider.uncertainty.speeds``), a least
squares over more rows than unknowns (:mod:`bikerider.engine.least_squares`), or any callable
differentiated numerically (:class:`DifferencedStage`).

Every stage takes and returns arrays that broadcast over leading batch dimensions.  A generated
stage given plain floats calls the generated functions' plain-float twins where there are any (one
bicycle at a time is then not dominated by NumPy's per-call overhead).
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping
from functools import cache

import numpy as np

from bikerider.generated.manifest import FUNCTIONS, STAGES

Arrays = dict[str, np.ndarray]


@cache
def generated_function(name: str, scalar: bool = False) -> Callable:
    """The generated function ``"module.function"`` of the manifest (``scalar``: its float twin)."""
    module, function = name.split(".")
    # The manifest names the function; its module is imported on first use (a chain that never
    # reaches the rider does not pay for importing the rider's large modules).
    return getattr(
        importlib.import_module(f"bikerider.generated.{module}"), f"{function}_scalar" if scalar else function
    )


class _Functions(dict):
    """``(name, scalar) -> function``, resolved on first use."""

    def __missing__(self, key: tuple[str, bool]) -> Callable:
        self[key] = generated_function(*key)
        return self[key]


def arguments(function: str) -> tuple[str, ...]:
    """The arguments of the generated function ``"module.function"``, in order (from the manifest)."""
    return FUNCTIONS[function]["args"]


class Stage:
    """One step of a chain.

    Attributes
    ----------
    name : str
        Names the stage in messages and tests.
    inputs, outputs : tuple of str
        Node names, in the order of the Jacobian's columns and rows.
    args : tuple of str
        The keyword each input is passed under (aligned with ``inputs``).
    checks : tuple of str
        Node names of quantities computed for the runtime's checks, not differentiated.
    """

    name: str
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    args: tuple[str, ...]
    checks: tuple[str, ...] = ()
    symbolic: str | None = None
    """Key of the stage's expressions in ``generated.sensitivities.STAGE_EXPRESSIONS``, if any."""

    def kwargs(self, nodes: Mapping[str, object]) -> dict[str, object]:
        """The stage's keyword arguments from node values."""
        return {arg: nodes[name] for arg, name in zip(self.args, self.inputs)}

    def value(self, kw: Mapping[str, object]) -> list:
        """The outputs, aligned with :attr:`outputs`."""
        return self.evaluate(kw)[0]

    def evaluate(self, kw: Mapping[str, object]) -> tuple[list, list]:
        """``(outputs, checks)``, aligned with :attr:`outputs` and :attr:`checks`."""
        raise NotImplementedError

    def jacobian(self, kw: Mapping[str, object]) -> np.ndarray:
        """``(..., len(outputs), len(inputs))``."""
        raise NotImplementedError

    def evaluate_with_jacobian(self, kw: Mapping[str, object]) -> tuple[list, list, np.ndarray]:
        """``(outputs, checks, jacobian)`` in one call (a stage may share work between them)."""
        outputs, checks = self.evaluate(kw)
        return outputs, checks, self.jacobian(kw)

    sparsity: np.ndarray | None = None
    """Flat indices into ``(len(outputs), len(inputs))`` of the Jacobian entries that are not
    identically zero, when :meth:`evaluate_point` can give the Jacobian as those entries alone."""

    def evaluate_point(self, kw: Mapping[str, object]) -> tuple[list, list, object, bool]:
        """:meth:`evaluate_with_jacobian` at one point: ``(outputs, checks, jacobian, sparse)``.

        With ``sparse`` the Jacobian is the flat sequence of its entries at :attr:`sparsity` (every
        other entry is zero), else the whole ``(len(outputs), len(inputs))`` array.  One bicycle's
        chain then writes a stage's Jacobian where it is needed without building the matrix.
        """
        outputs, checks, jacobian = self.evaluate_with_jacobian(kw)
        return outputs, checks, jacobian, False


def _floats(kw: Mapping[str, object]) -> bool:
    """Whether every argument is a plain number (not an array)."""
    for x in kw.values():
        if type(x) is not float and type(x) is not int:
            return False
    return True


def _pick(value: object, index: tuple[int, ...], batched: bool):
    if not index:
        return value
    if batched:
        return value[(..., *index)]  # type: ignore[index]
    for i in index:  # nested tuples of a plain-float twin
        value = value[i]  # type: ignore[index]
    return value


class GeneratedStage(Stage):
    """A stage kind of the manifest bound to node names.

    Parameters
    ----------
    kind : str
        A key of the manifest's ``STAGES``.
    name : str, optional
        The stage's name (default: the kind).
    inputs : mapping of str to str, optional
        The node bound to each of the kind's inputs; an input not named is its own node.
    outputs : mapping of str to str, optional
        The node each of the kind's outputs is written to; one not named is its own node.
    checks : mapping of str to str, optional
        The node each of the kind's checks is written to; by default ``"<name>.<check>"``.
    """

    def __init__(
        self,
        kind: str,
        name: str | None = None,
        inputs: Mapping[str, str] | None = None,
        outputs: Mapping[str, str] | None = None,
        checks: Mapping[str, str] | None = None,
    ):
        entry = STAGES[kind]
        self.kind = self.symbolic = kind
        self.name = name or kind
        for given, known, what in (
            (inputs, entry["inputs"], "input"),
            (outputs, entry["outputs"], "output"),
            (checks, tuple(c[0] for c in entry["checks"]), "check"),
        ):
            unknown = set(given or ()) - set(known)
            if unknown:  # a binding the manifest does not know: the derivation changed
                raise ValueError(f"stage {self.name}: {kind} has no {what} {sorted(unknown)[0]}")
        inputs, outputs, checks = dict(inputs or {}), dict(outputs or {}), dict(checks or {})
        self.args = entry["inputs"]
        self.inputs = tuple(inputs.get(a, a) for a in self.args)
        self.outputs = tuple(outputs.get(o, o) for o in entry["outputs"])
        self.checks = tuple(checks.get(c, f"{self.name}.{c}") for c, _, _ in entry["checks"])
        self._value, self._jacobian = entry["value"], entry["jacobian"]
        names = [o[0] for o in FUNCTIONS[self._value]["outputs"]]
        self._picks = [(names.index(o), index) for o, index in entry["picks"]]
        self._check_picks = [(names.index(o), index) for _, o, index in entry["checks"]]
        self._scalar = FUNCTIONS[self._value]["scalar"] and FUNCTIONS[self._jacobian]["scalar"]
        self._single = len(FUNCTIONS[self._value]["outputs"]) == 1
        self._functions = _Functions()
        # A stage emitted by derive.codegen.stage_functions returns its outputs as one vector (and its
        # checks as another): one bicycle's floats then need no picking.
        jacobian = FUNCTIONS[self._jacobian]
        self._shape = jacobian["outputs"][-1][1]
        self._combined = [o[0] for o in jacobian["outputs"][:-1]] == names  # the values come with it
        self._nonzero = np.array(jacobian.get("nonzero", {}).get("jacobian", ()), dtype=int)
        if self._scalar:  # the float twin returns the entries at these indices
            self.sparsity = self._nonzero
        vector = [("values", (i,)) for i in range(len(self.outputs))]
        self._vector = list(entry["picks"]) == vector and all(
            o == "checks" and index == (i,) for i, (_, o, index) in enumerate(entry["checks"])
        )

    def _call(self, function: str, kw: Mapping[str, object], scalar: bool) -> tuple[object, bool]:
        """``(result, batched)``: the float twin on floats, else the NumPy function."""
        if scalar:
            try:
                return self._functions[function, True](**kw), False
            except (ValueError, ZeroDivisionError, OverflowError):
                pass  # outside a function's domain: NumPy gives NaN or inf where plain floats raise
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return self._functions[function, False](**kw), True

    def _values(self, kw: Mapping[str, object], scalar: bool) -> tuple[list, list]:
        result, batched = self._call(self._value, kw, scalar)
        if self._single:
            result = (result,)
        outputs = [_pick(result[i], index, batched) for i, index in self._picks]  # type: ignore[index]
        checks = [_pick(result[i], index, batched) for i, index in self._check_picks]  # type: ignore[index]
        return outputs, checks

    def evaluate(self, kw: Mapping[str, object]) -> tuple[list, list]:
        return self._values(kw, self._scalar and _floats(kw))

    def jacobian(self, kw: Mapping[str, object]) -> np.ndarray:
        result, batched = self._call(self._jacobian, kw, self._scalar and _floats(kw))
        return self._matrix(result[-1] if self._combined else result, batched)

    def _matrix(self, result: object, batched: bool) -> np.ndarray:
        """The Jacobian as an array (the float twins return its entries that are not zero)."""
        if batched:
            return np.asarray(result, dtype=float)
        matrix = np.zeros(self._shape)
        matrix.flat[self._nonzero] = result
        return matrix

    def evaluate_with_jacobian(self, kw: Mapping[str, object]) -> tuple[list, list, np.ndarray]:
        outputs, checks, jacobian, sparse = self.evaluate_point(kw)
        return outputs, checks, self._matrix(jacobian, False) if sparse else jacobian

    def evaluate_point(self, kw: Mapping[str, object]) -> tuple[list, list, object, bool]:
        scalar = self._scalar and _floats(kw)
        if scalar:  # one bicycle: the float twins, the Jacobian's entries as they come
            functions = self._functions
            try:
                if self._vector and self._combined:  # values, checks and Jacobian from one function, no picking
                    *values, jacobian = functions[self._jacobian, True](**kw)
                    return list(values[0]), list(values[1]) if len(values) > 1 else [], jacobian, True
                result = functions[self._value, True](**kw)
                jacobian = functions[self._jacobian, True](**kw)
            except (ValueError, ZeroDivisionError, OverflowError):
                pass  # outside a function's domain: the NumPy functions below give NaN or inf
            else:
                if self._single:
                    result = (result,)
                outputs = [_pick(result[i], index, False) for i, index in self._picks]
                checks = [_pick(result[i], index, False) for i, index in self._check_picks]
                return outputs, checks, jacobian[-1] if self._combined else jacobian, True
        outputs, checks = self._values(kw, scalar)
        result, batched = self._call(self._jacobian, kw, scalar)
        jacobian = result[-1] if self._combined else result  # type: ignore[index]
        return outputs, checks, np.asarray(jacobian, dtype=float) if batched else jacobian, not batched


class DifferencedStage(Stage):
    """A callable of named inputs, its Jacobian by central differences.

    For what has no generated Jacobian (a fit's prediction, a simulation).  The step of each input
    is given (e.g. one standard uncertainty: a secant over +-1 sigma) or relative,
    ``relative_step * max(|x|, 1e-2)``.

    Parameters
    ----------
    name : str
    function : callable
        ``function(values) -> outputs``, an array (or a sequence of numbers) aligned with
        ``outputs``; ``values`` a dict of the inputs by name.  With ``batched``, every input arrives
        as an array whose first axis runs over the points ``[nominal, up_1, down_1, up_2, down_2,
        ...]`` (followed by ``extra_dims`` axes of length one, to broadcast against the caller's own
        trailing dimensions), and the outputs carry that axis first: ``(points, ...)``.
    inputs, outputs : sequence of str
    steps : mapping of str to float, optional
    """

    def __init__(
        self,
        name: str,
        function: Callable[[dict], object],
        inputs,
        outputs,
        steps: Mapping[str, float] | None = None,
        relative_step: float = 1e-6,
        batched: bool = False,
        extra_dims: int = 0,
    ):
        self.name, self.function = name, function
        self.inputs = self.args = tuple(inputs)
        self.outputs = tuple(outputs)
        self.steps, self.relative_step = dict(steps or {}), relative_step
        self.batched, self.extra_dims = batched, extra_dims

    def evaluate(self, kw: Mapping[str, object]) -> tuple[list, list]:
        return list(self.function(dict(kw))), []  # type: ignore[arg-type]

    def step(self, name: str, value: float) -> float:
        return self.steps.get(name, self.relative_step * max(abs(value), 1e-2))

    def jacobian(self, kw: Mapping[str, object]) -> np.ndarray:
        """``(n_out..., len(inputs))`` at one point (floats or 0-d arrays)."""
        nominal = {k: float(v) for k, v in kw.items()}  # type: ignore[arg-type]
        steps = np.array([self.step(k, nominal[k]) for k in self.inputs])
        if self.batched:
            n = len(self.inputs)
            points = {k: np.full(2 * n + 1, v) for k, v in nominal.items()}
            for j, k in enumerate(self.inputs):
                points[k][2 * j + 1] += steps[j]
                points[k][2 * j + 2] -= steps[j]
            shape = (-1,) + (1,) * self.extra_dims
            table = np.asarray(self.function({k: v.reshape(shape) for k, v in points.items()}), dtype=float)
            up, down = table[1::2], table[2::2]
            slopes = (up - down) / steps.reshape((-1,) + (1,) * (up.ndim - 1))
            return np.moveaxis(slopes / 2, 0, -1)
        columns = []
        for k, h in zip(self.inputs, steps):
            up = np.asarray(self.function({**nominal, k: nominal[k] + h}), dtype=float)
            down = np.asarray(self.function({**nominal, k: nominal[k] - h}), dtype=float)
            columns.append((up - down) / (2 * h))
        return np.stack(columns, axis=-1)


def finite(value: object) -> bool:
    """Whether a float or 0-d array is finite."""
    return math.isfinite(float(value))  # type: ignore[arg-type]
