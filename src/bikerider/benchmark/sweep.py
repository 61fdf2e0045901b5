"""Eigenvalues and stable speed intervals against one benchmark parameter, or two (a stability map).

A sweep varies one or two of the benchmark parameters of a base set over given values, the others
fixed, and evaluates every design in one batch: the canonical matrices (generated, vectorised), the
stable intervals and critical speeds (:func:`bikerider.benchmark.stability.stability_batch`, no scan
over speed) and, on request, the eigenvalues at the given speeds.

Validity.  Every design is checked as :meth:`BenchmarkParameters.with_values` checks it (positive
masses, inertia tensors, wheels, ...).  A design no bicycle can have is kept in the grid, marked
invalid with the reason, and its results are NaN; the sweep never stops on it.  Checks that tie
parameters together are the inertia tensor of each body and the two inertias of each wheel; when
the two swept parameters share one of them every pair of values is checked, otherwise each value of
each axis once (a pair is valid when both of its values are).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from bikerider.benchmark.closed_loop import ClosedLoopModel
from bikerider.benchmark.model import WhippleModel
from bikerider.benchmark.parameters import BENCHMARK_NAMES, BenchmarkParameters
from bikerider.benchmark.rules import TIED
from bikerider.benchmark.stability import KIND_NAMES, OSCILLATORY, REAL, StabilityBatch, stability_batch
from bikerider.engine import arguments
from bikerider.errors import InputError
from bikerider.generated import benchmark_model as gen

_CANONICAL_ARGS = arguments("benchmark_model.canonical_matrices")


@dataclass(frozen=True)
class Sweep:
    """Results of a sweep over a grid of designs (shape ``G``: ``(n1,)`` or ``(n1, n2)``).

    Attributes
    ----------
    base : BenchmarkParameters
        The set the designs vary.
    names : tuple of str
        The swept parameters (benchmark names, SI units).
    values : tuple of numpy.ndarray
        The values of each swept parameter (one array per axis of ``G``).
    speeds : numpy.ndarray, shape (n,)
        Speeds [m/s] at which stability (and eigenvalues) are reported.
    valid : numpy.ndarray of bool, shape G
        Whether the design is a possible bicycle.
    reasons : numpy.ndarray of str, shape G
        Why an invalid design is invalid ("" for a valid one).
    stability : StabilityBatch
        Stable intervals and critical speeds, arrays of shape ``G + ...`` (NaN for invalid designs).
    eigenvalues : numpy.ndarray or None, shape G + (n, 4)
        Eigenvalues in the order weave (+imag), weave, capsize, castor (labels as
        :meth:`WhippleModel.eigenvalues`), when asked for; NaN for invalid designs.
    labels : numpy.ndarray or None, shape G + (n, 4)
        Their mode labels.
    """

    base: BenchmarkParameters
    names: tuple[str, ...]
    values: tuple[np.ndarray, ...]
    speeds: np.ndarray
    valid: np.ndarray
    reasons: np.ndarray
    stability: StabilityBatch
    eigenvalues: np.ndarray | None = None
    labels: np.ndarray | None = field(default=None)
    law: object = None
    """The control law every design is under (``None``: the open loop, self-stability)."""

    @property
    def shape(self) -> tuple[int, ...]:
        return self.valid.shape

    def stable(self) -> np.ndarray:
        """Whether each design is self-stable at each speed, ``G + (n,)`` (False when invalid)."""
        return self.stability.is_stable(self.speeds) & self.valid[..., None]

    def design(self, index) -> dict[str, float]:
        """The swept values of the design at ``index`` (a tuple of grid indices)."""
        index = (index,) if np.ndim(index) == 0 else tuple(index)
        return {name: float(values[i]) for name, values, i in zip(self.names, self.values, index)}

    def design_rows(self) -> list[dict[str, object]]:
        """One record per design: swept values, validity, critical speeds, weave frequency, intervals."""
        s = self.stability
        rows = []
        for index in np.ndindex(self.shape):
            row: dict[str, object] = dict(self.design(index))
            row["valid"] = bool(self.valid[index])
            row["reason"] = str(self.reasons[index])
            for key, array in (
                ("weave_speed", s.weave),
                ("capsize_speed", s.capsize),
                ("weave_frequency", s.weave_frequency),
            ):
                row[key] = _number(array[index])
            row["stable_intervals"] = [
                {
                    "lower": _number(s.lower[index][k]),
                    "upper": _number(s.upper[index][k]),
                    "lower_crossing": KIND_NAMES[int(s.lower_kind[index][k])],
                    "upper_crossing": KIND_NAMES[int(s.upper_kind[index][k])],
                }
                for k in range(s.lower.shape[-1])
                if np.isfinite(s.lower[index][k])
            ]
            rows.append(row)
        return rows

    def speed_rows(self) -> list[dict[str, object]]:
        """One record per design and speed: swept values, speed, stable, and the four eigenvalues
        (when computed) as ``<column>_real``/``<column>_imag`` for the columns of
        :data:`SPEED_COLUMNS` (``weave`` the member with positive imaginary part or the larger real
        root, ``weave2`` the other), and ``modes``: the label of each of the four (``other`` where
        one is none of weave, capsize, castor: its values are still given)."""
        stable = self.stable()
        rows = []
        for index in np.ndindex(self.shape):
            design = self.design(index)
            for k, v in enumerate(self.speeds):
                row: dict[str, object] = {**design, "speed": float(v), "stable": bool(stable[index][k])}
                if self.eigenvalues is not None:
                    ev = self.eigenvalues[index][k]
                    for column, z in zip(SPEED_COLUMNS, ev):
                        row[f"{column}_real"] = _number(z.real)
                        row[f"{column}_imag"] = _number(z.imag)
                    if self.labels is not None:
                        row["modes"] = " ".join(str(x) for x in self.labels[index][k])
                rows.append(row)
        return rows


SPEED_COLUMNS = ("weave", "weave2", "capsize", "castor")
"""Column stems of the eigenvalues in :meth:`Sweep.speed_rows`, in the order of :data:`MODES`."""


def _number(x) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else (None if np.isnan(x) else x)


def _check_axes(base: BenchmarkParameters, axes: dict[str, object]) -> tuple[tuple[str, ...], tuple[np.ndarray, ...]]:
    if not 1 <= len(axes) <= 2:
        raise InputError("parameters", list(axes), "one or two benchmark parameters to vary")
    names, values = [], []
    for name, raw in axes.items():
        if name not in BENCHMARK_NAMES:
            raise InputError(
                name, f"{np.size(raw)} values", f"one of the benchmark names {', '.join(BENCHMARK_NAMES)}", base.source
            )
        if base.values[name] is None:
            raise InputError(
                name, "not determined", f"a base parameter set that determines {name}, to vary it", base.source
            )
        array = np.atleast_1d(np.asarray(raw, dtype=float))
        if array.ndim != 1 or array.size == 0 or not np.all(np.isfinite(array)):
            raise InputError(
                name,
                array.tolist() if array.size < 10 else f"array of shape {array.shape}",
                "a non-empty one-dimensional array of finite values",
            )
        names.append(name)
        values.append(array)
    return tuple(names), tuple(values)


def _validity(base: BenchmarkParameters, names: tuple[str, ...], values: tuple[np.ndarray, ...]):
    """``valid`` and ``reasons`` of shape G (the module docstring's rules)."""

    def check(changes: dict[str, float]) -> str:
        try:
            base.with_values(**changes)
        except InputError as exc:
            return str(InputError(exc.name, exc.value, exc.expected))  # without the source: the row says which
        return ""

    shape = tuple(v.size for v in values)
    reasons = np.full(shape, "", dtype=object)
    linked = len(names) == 2 and any(names[0] in group and names[1] in group for group in TIED)
    if len(names) == 1 or not linked:
        per_axis = [[check({name: float(x)}) for x in axis] for name, axis in zip(names, values)]
        for index in np.ndindex(shape):
            reasons[index] = "; ".join(r for r in (per_axis[a][i] for a, i in enumerate(index)) if r)
    else:
        for index in np.ndindex(shape):
            reasons[index] = check({name: float(axis[i]) for name, axis, i in zip(names, values, index)})
    return reasons == "", reasons


def sweep(
    base: BenchmarkParameters,
    parameters: dict[str, object],
    speeds=(),
    eigenvalues: bool = True,
    method: str = "quartic",
    law=None,
) -> Sweep:
    """Evaluate every design of a grid over one or two benchmark parameters.

    Parameters
    ----------
    base : BenchmarkParameters
        The parameters not varied.
    parameters : dict
        One or two benchmark names to arrays of values (SI units; ``lam`` in radians).  Two names
        give the grid of every pair (a stability map).
    speeds : array_like, shape (n,)
        Speeds [m/s] at which to report stability (and eigenvalues).
    eigenvalues : bool
        Also compute the eigenvalues at ``speeds`` (``G x n`` quartics).
    method : {"quartic", "eigvals"}
        How (:meth:`WhippleModel.eigenvalues`).
    law : ControlLaw, dict or sequence of 4 float, optional
        A control law on the steer torque (:mod:`bikerider.benchmark.closed_loop`): every design
        under it, its closed-loop stable intervals (one design at a time, exact per piece of the
        law) and eigenvalues.

    Returns
    -------
    Sweep

    Raises
    ------
    InputError
        An unknown or undetermined parameter, or empty or non-finite values.  Designs no bicycle
        can have do not raise: they are marked invalid.
    """
    names, values = _check_axes(base, parameters)
    speeds = np.atleast_1d(np.asarray(speeds, dtype=float))
    if speeds.ndim != 1 or not np.all(np.isfinite(speeds)):
        raise InputError("speeds", speeds.tolist(), "a one-dimensional array of finite speeds [m/s]")
    valid, reasons = _validity(base, names, values)
    grids = np.meshgrid(*values, indexing="ij")
    arguments = {}
    for key in _CANONICAL_ARGS:
        value = np.full(valid.shape, float(base.values[key]))  # type: ignore[arg-type]
        if key in names:
            value = np.where(valid, grids[names.index(key)], value)  # invalid designs: the base values
        arguments[key] = value
    model = WhippleModel(*gen.canonical_matrices(**arguments), g=float(base.values["g"]))  # type: ignore[arg-type]
    system = None if law is None else ClosedLoopModel(model, law)
    result = stability_batch(model.entries(), model.g) if system is None else _closed_loop_batch(system)
    result = StabilityBatch(
        *(
            np.where(_expand(valid, a), a, np.nan if a.dtype.kind == "f" else 0)
            for a in (getattr(result, f.name) for f in fields(StabilityBatch))
        )
    )
    ev = labels = None
    if eigenvalues and speeds.size:
        modal = model.eigenvalues(speeds, method=method) if system is None else system.eigenvalues(speeds)
        ev = np.where(valid[..., None, None], modal.values, np.nan)
        labels = modal.labels
    return Sweep(
        base, names, values, speeds, valid, reasons, result, ev, labels, None if system is None else system.law
    )


def _closed_loop_batch(system: ClosedLoopModel) -> StabilityBatch:
    """The closed-loop stability of every design, in the arrays of :class:`StabilityBatch`."""
    shape = system.batch_shape
    lower, upper = np.full(shape + (3,), np.nan), np.full(shape + (3,), np.nan)
    lower_kind, upper_kind = np.zeros(shape + (3,), dtype=int), np.zeros(shape + (3,), dtype=int)
    weave, capsize, frequency = np.full(shape, np.nan), np.full(shape, np.nan), np.full(shape, np.nan)
    kinds = {None: 0, "real": REAL, "oscillatory": OSCILLATORY}
    for index, one in zip(np.ndindex(shape), system._bicycles()):
        result = one.stability()
        for k, interval in enumerate(result.intervals[:3]):
            lower[index + (k,)], upper[index + (k,)] = interval.lower, interval.upper
            lower_kind[index + (k,)] = kinds[getattr(interval.lower_crossing, "kind", None)]
            upper_kind[index + (k,)] = kinds[getattr(interval.upper_crossing, "kind", None)]
        for array, value in ((weave, result.weave), (capsize, result.capsize), (frequency, result.weave_frequency)):
            array[index] = np.nan if value is None else value
    return StabilityBatch(lower, upper, lower_kind, upper_kind, weave, capsize, frequency)


def _expand(valid: np.ndarray, array: np.ndarray) -> np.ndarray:
    return valid.reshape(valid.shape + (1,) * (array.ndim - valid.ndim))


def stability_map(base: BenchmarkParameters, x: tuple[str, object], y: tuple[str, object], speeds=()) -> Sweep:
    """Stable intervals over the grid of two parameters, without eigenvalues.

    Parameters
    ----------
    base : BenchmarkParameters
        The parameters not varied.
    x, y : tuple of (str, array_like)
        Two different benchmark names and their values (SI units; ``lam`` in radians).
    speeds : array_like, shape (n,)
        Speeds [m/s] at which :meth:`Sweep.stable` gives stability.

    Returns
    -------
    Sweep
        Of grid shape ``(len(x values), len(y values))``.

    Raises
    ------
    InputError
        The same name twice, or the errors of :func:`sweep`.
    """
    if x[0] == y[0]:
        raise InputError("parameters", [x[0], y[0]], "two different benchmark parameters")
    return sweep(base, {x[0]: x[1], y[0]: y[1]}, speeds, eigenvalues=False)


__all__ = ["Sweep", "stability_map", "sweep"]
