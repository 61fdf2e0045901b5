"""Design spaces: a grid or a random sample of designs over named parameters of a base bicycle.

A design is the base with some values changed.  The base is either a set of benchmark parameters
(:class:`bikerider.benchmark.BenchmarkParameters`: the varied names are Meijaard's) or the raw
measurements of a bicycle and a seated rider (an :class:`bikerider.estimate.EstimateResult` of the
rider model: the varied names are the inputs of the estimate chain,
:data:`bikerider.uncertainty.chain.ESTIMATE_INPUTS`: geometry, body masses and inertias, the rider's
measurements), which every design goes through whole (the chain's generated stages, batched).

* :func:`grid`: every combination of the values of each parameter (six parameters at 20 values
  are 6.4e7 designs), in C order (the last parameter varies fastest);
* :func:`random_designs`: ``n`` designs, each parameter drawn uniformly between two bounds or
  normally about a mean;
* :func:`monte_carlo`: ``n`` designs with every base value that has an uncertainty drawn normally
  (a population of measurement errors).

A space never holds its designs: :meth:`DesignSpace.values` makes those of one chunk, so a space
of any size costs nothing.  Random draws come in fixed blocks of :data:`RANDOM_BLOCK` designs,
each from its own seeded stream, so the designs do not depend on the chunk size.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np

from bikerider.benchmark.parameters import BENCHMARK_NAMES, BenchmarkParameters
from bikerider.errors import InputError
from bikerider.uncertainty.chain import ESTIMATE_INPUTS

RANDOM_BLOCK = 65_536
"""Designs drawn from one seeded stream (the chunk size of a run does not change the designs)."""
MAX_DESIGNS = 10**12
"""A larger space is a typing error."""
NORMAL_REACH = 40.0
"""Standard deviations a normal draw may reach: no float64 normal draw goes beyond 40 sigma."""
KINDS = ("benchmark", "measurements")


def measurement_names() -> tuple[str, ...]:
    """The inputs of the estimate chain, in its order (the manifest's list)."""
    return ESTIMATE_INPUTS


@dataclass(frozen=True)
class Axis:
    """One parameter of a grid and its values (SI units)."""

    name: str
    values: np.ndarray


@dataclass(frozen=True)
class Draw:
    """One randomly drawn parameter: ``uniform`` between ``a`` and ``b``, or ``normal`` with mean ``a``
    and standard deviation ``b``."""

    name: str
    distribution: str
    a: float
    b: float


@dataclass(frozen=True)
class DesignSpace:
    """A grid or a random sample of designs over named parameters of a base.

    Attributes
    ----------
    kind : {"benchmark", "measurements"}
        What the names are: benchmark parameters, or raw measurements of the estimate chain.
    base : dict of str to float
        Every input of the evaluation (the 26 benchmark values, or the estimate chain's inputs), SI
        units; NaN for a value that is not determined (``IByy``, ``IHyy``).
    sigmas : dict of str to float
        Standard uncertainties of the base values (the validity of a wheel's inertias allows them).
    axes : tuple of Axis
        Grid axes (empty for a random space).
    draws : tuple of Draw
        Randomly drawn parameters (empty for a grid).
    n_random : int
        Number of random designs.
    seed : int
    name : str
        A name for titles and the store.
    """

    kind: str
    base: dict[str, float]
    sigmas: dict[str, float] = field(default_factory=dict)
    axes: tuple[Axis, ...] = ()
    draws: tuple[Draw, ...] = ()
    n_random: int = 0
    seed: int = 0
    name: str = ""

    @property
    def is_grid(self) -> bool:
        return bool(self.axes)

    @property
    def names(self) -> tuple[str, ...]:
        """The varied parameters."""
        return tuple(a.name for a in self.axes) if self.axes else tuple(d.name for d in self.draws)

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape, or ``(n,)``."""
        return tuple(a.values.size for a in self.axes) if self.axes else (self.n_random,)

    @property
    def size(self) -> int:
        return int(math.prod(self.shape))

    def values(self, start: int, stop: int) -> dict[str, np.ndarray]:
        """The varied values of designs ``start .. stop - 1`` (flat index, C order)."""
        if self.axes:
            index = np.unravel_index(np.arange(start, stop, dtype=np.int64), self.shape)
            return {axis.name: axis.values[i] for axis, i in zip(self.axes, index)}
        out = {d.name: np.empty(stop - start) for d in self.draws}
        for block in range(start // RANDOM_BLOCK, (stop - 1) // RANDOM_BLOCK + 1 if stop > start else 0):
            first = block * RANDOM_BLOCK
            drawn = self._block(block, min(RANDOM_BLOCK, self.n_random - first))
            lo, hi = max(start, first), min(stop, first + RANDOM_BLOCK)
            for name, array in drawn.items():
                out[name][lo - start : hi - start] = array[lo - first : hi - first]
        return out

    def _block(self, block: int, size: int) -> dict[str, np.ndarray]:
        rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(block,)))
        out = {}
        for d in self.draws:
            out[d.name] = rng.uniform(d.a, d.b, size) if d.distribution == "uniform" else rng.normal(d.a, d.b, size)
        return out

    def inputs(self, start: int, stop: int) -> dict[str, np.ndarray]:
        """Every input of designs ``start .. stop - 1``: the base values (scalars) with the varied ones
        (arrays)."""
        out: dict[str, np.ndarray] = {k: np.asarray(v, dtype=float) for k, v in self.base.items()}
        out.update(self.values(start, stop))
        return out

    # -- metadata ---------------------------------------------------------------------------------
    def to_json(self) -> str:
        """The whole space as JSON (stored with the results; resuming checks it is the same)."""
        return json.dumps(
            {
                "kind": self.kind,
                "name": self.name,
                "base": _finite_or_none(self.base),
                "sigmas": self.sigmas,
                "seed": self.seed,
                "n_random": self.n_random,
                "axes": [{"name": a.name, "values": a.values.tolist()} for a in self.axes],
                "draws": [{"name": d.name, "distribution": d.distribution, "a": d.a, "b": d.b} for d in self.draws],
            },
            sort_keys=True,
        )

    @classmethod
    def from_json(cls, text: str) -> DesignSpace:
        data = json.loads(text)
        base = {k: (math.nan if v is None else float(v)) for k, v in data["base"].items()}
        return cls(
            data["kind"],
            base,
            {k: float(v) for k, v in data["sigmas"].items()},
            tuple(Axis(a["name"], np.asarray(a["values"], dtype=float)) for a in data["axes"]),
            tuple(Draw(d["name"], d["distribution"], float(d["a"]), float(d["b"])) for d in data["draws"]),
            int(data["n_random"]),
            int(data["seed"]),
            data["name"],
        )


def _finite_or_none(values: dict[str, float]) -> dict[str, float | None]:
    return {k: (float(v) if math.isfinite(v) else None) for k, v in values.items()}


# -- construction ------------------------------------------------------------------------------------
def _base_of(base) -> tuple[str, dict[str, float], dict[str, float], str]:
    """``(kind, values, sigmas, name)`` of a BenchmarkParameters or an EstimateResult."""
    if isinstance(base, BenchmarkParameters):
        values = {k: (math.nan if base.values[k] is None else float(base.values[k])) for k in BENCHMARK_NAMES}
        return "benchmark", values, {k: float(base.sigmas.get(k, 0.0)) for k in BENCHMARK_NAMES}, base.source or ""
    inputs = getattr(base, "chain_inputs", None)
    if inputs is None:
        raise InputError(
            "base",
            type(base).__name__,
            "benchmark parameters, or the estimate of a bicycle with the rider model (raw measurements)",
        )
    names = measurement_names()
    values = {k: float(inputs[k].value) for k in names}
    sigmas = {k: float(inputs[k].sigma) for k in names}
    return "measurements", values, sigmas, base.parameters.source or ""


def _check_name(kind: str, values: dict[str, float], name: str, option: str) -> None:
    known = BENCHMARK_NAMES if kind == "benchmark" else measurement_names()
    if name not in known:
        what = (
            "one of the benchmark names "
            if kind == "benchmark"
            else "a measurement of the estimate chain (with --measured): "
        )
        raise InputError(option, name, what + ", ".join(known))
    if not math.isfinite(values[name]):
        raise InputError(option, name, f"a base that determines {name}, to vary it")


def grid(base, parameters: dict[str, object], name: str = "") -> DesignSpace:
    """Every combination of the given values of each parameter.

    Parameters
    ----------
    base : BenchmarkParameters or EstimateResult
        What the designs vary (benchmark parameters, or raw measurements through the whole estimate).
    parameters : dict
        Name to a one-dimensional array of values (SI units; angles in radians).
    name : str, optional
        A name for titles and the store (default: the base's source).

    Returns
    -------
    DesignSpace
        Of shape ``(len(values) for each parameter)``, in C order (the last parameter varies fastest).

    Raises
    ------
    InputError
        An unknown name, an empty or non-finite set of values, or more than 1e12 designs.
    """
    kind, values, sigmas, source = _base_of(base)
    if not parameters:
        raise InputError("--vary", "nothing", "at least one parameter to vary")
    axes = []
    for key, raw in parameters.items():
        _check_name(kind, values, key, "--vary")
        array = np.atleast_1d(np.asarray(raw, dtype=float))
        if array.size == 0:
            raise InputError(key, "an empty range", "at least one value (N >= 1)")
        if array.ndim != 1 or not np.all(np.isfinite(array)):
            raise InputError(
                key,
                array.tolist() if array.size < 10 else f"array of shape {array.shape}",
                "a one-dimensional array of finite values",
            )
        axes.append(Axis(key, array))
    space = DesignSpace(kind, values, sigmas, tuple(axes), name=name or source)
    if space.size > MAX_DESIGNS:
        raise InputError("--vary", f"{space.size:.3g} designs", f"at most {MAX_DESIGNS:.0e} designs")
    return space


def random_designs(base, parameters: dict[str, tuple], n: int, seed: int = 0, name: str = "") -> DesignSpace:
    """``n`` designs with each parameter drawn at random.

    Parameters
    ----------
    base : BenchmarkParameters or EstimateResult
        What the designs vary (see :func:`grid`).
    parameters : dict
        Name to ``("uniform", low, high)`` or ``("normal", mean, sigma)``.
    n : int
        Number of designs.
    seed : int
        Seed of the random streams (the same seed gives the same designs).
    name : str, optional
        A name for titles and the store.

    Returns
    -------
    DesignSpace

    Raises
    ------
    InputError
        An unknown name, an empty range, a non-positive sigma or a number of designs out of range.
    """
    kind, values, sigmas, source = _base_of(base)
    n = _check_count(n)
    if not parameters:
        raise InputError("--vary", "nothing", "at least one parameter to draw")
    draws = []
    for key, (distribution, a, b) in parameters.items():
        _check_name(kind, values, key, "--vary")
        draws.append(_draw(key, distribution, a, b))
    return DesignSpace(kind, values, sigmas, draws=tuple(draws), n_random=n, seed=int(seed), name=name or source)


def monte_carlo(base, n: int, seed: int = 0, name: str = "") -> DesignSpace:
    """``n`` designs with every base value that has a standard uncertainty drawn normally about it (a
    population of measurement errors).

    Parameters
    ----------
    base : BenchmarkParameters or EstimateResult
        Values with standard uncertainties (see :func:`grid`).
    n : int
        Number of designs.
    seed : int
        Seed of the random streams.
    name : str, optional
        A name for titles and the store.

    Returns
    -------
    DesignSpace

    Raises
    ------
    InputError
        A base without uncertainties, or a number of designs out of range.
    """
    kind, values, sigmas, source = _base_of(base)
    n = _check_count(n, "--monte-carlo")
    draws = tuple(
        Draw(k, "normal", values[k], sigmas[k]) for k in values if sigmas.get(k, 0.0) > 0 and math.isfinite(values[k])
    )
    if not draws:
        raise InputError("--monte-carlo", "no uncertainties", "a base whose values carry standard uncertainties")
    return DesignSpace(kind, values, sigmas, draws=draws, n_random=n, seed=int(seed), name=name or source)


def _check_count(n, option: str = "--random") -> int:
    if not (isinstance(n, (int, np.integer)) and 1 <= n <= MAX_DESIGNS):
        raise InputError(option, n, f"a whole number of designs between 1 and {MAX_DESIGNS:.0e}")
    return int(n)


def _draw(name: str, distribution: str, a: float, b: float) -> Draw:
    a, b = float(a), float(b)
    if distribution not in ("uniform", "normal"):
        raise InputError(name, distribution, 'a distribution "uniform" (LOW:HIGH) or "normal" (MEAN+/-SIGMA)')
    if not (math.isfinite(a) and math.isfinite(b)):
        raise InputError(name, f"{a:g}, {b:g}", "finite bounds (uniform) or a finite mean and sigma (normal)")
    if distribution == "uniform" and not a < b:
        raise InputError(name, f"{a:g}:{b:g}", "a range LOW:HIGH with LOW < HIGH (an empty range has no designs)")
    if distribution == "uniform" and not math.isfinite(b - a):
        raise InputError(name, f"{a:g}:{b:g}", "a range LOW:HIGH whose width HIGH - LOW is a finite number")
    if distribution == "normal" and not b > 0:
        raise InputError(name, f"{a:g}+/-{b:g}", "a positive standard deviation")
    if distribution == "normal" and not math.isfinite(abs(a) + NORMAL_REACH * b):
        raise InputError(
            name, f"{a:g}+/-{b:g}", f"a mean and sigma whose draws stay finite (|MEAN| + {NORMAL_REACH:g} SIGMA)"
        )
    return Draw(name, distribution, a, b)


__all__ = [
    "Axis",
    "DesignSpace",
    "Draw",
    "KINDS",
    "RANDOM_BLOCK",
    "grid",
    "measurement_names",
    "monte_carlo",
    "random_designs",
]
