"""Summaries of a design-space run, read chunk by chunk (a store larger than memory is fine).

* :func:`summarize`: for each varied parameter, against its values (a grid's axis values, or
  :data:`BINS` equal bins of a random parameter's range): the number of valid designs, the
  fraction of them that is self-stable somewhere in a speed range, the quartiles of the weave
  speed and the capsize speed (from histograms in steps of :data:`SPEED_BIN`), and the mean of
  those speeds and of the width of the first stable interval; with these, the *first-order
  sensitivity index* of each output to each parameter, ``S_i = Var(E[y | x_i]) / Var(y)`` (the share
  of the output's variance over the design space that the parameter explains alone; Sobol's main
  effect, exact on a full grid, a binned estimate for a random sample).  The speeds enter the means
  and indices where they lie in the speed range (a few designs with a weave speed of 100 m/s would
  otherwise decide every variance);
* :func:`design_slice`: a two-dimensional slice of a grid (the other parameters fixed), as arrays;
* :func:`closest_to_weave_speed`: the valid design whose weave speed is closest to a target.

"Self-stable" means: a stable interval that overlaps the speed range (by default the run's map
speeds, else 0-10 m/s).  The stable interval of the sensitivities is the first one: the weave speed
where it begins one, the capsize speed where it ends one (designs that are never self-stable have
weave and capsize speeds of their own, the modes' changes of stability, which are left out here);
its width counts only intervals with an upper end.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bikerider.design.store import DesignStore
from bikerider.errors import InputError

BINS = 20
"""Bins of a randomly drawn parameter."""
SPEED_BIN = 0.02
"""Width [m/s] of the speed histograms the quartiles come from."""
OUTPUTS = ("weave_speed", "capsize_speed", "width")
"""Outputs whose sensitivity is reported."""


@dataclass(frozen=True)
class ParameterSummary:
    """Outputs of the designs at each value (bin) of one parameter.

    Attributes
    ----------
    name : str
    values : numpy.ndarray, shape (k,)
        Axis values, or bin centres.
    edges : numpy.ndarray or None
        Bin edges (random designs), shape (k + 1,).
    count, valid, stable : numpy.ndarray of int, shape (k,)
        Designs, valid designs, self-stable designs.
    mean, std, n : dict of str to numpy.ndarray
        Per output of :data:`OUTPUTS`: mean and standard deviation over the designs where it lies in
        the speed range, and their number.
    quartiles : dict of str to numpy.ndarray
        Weave and capsize speed: 25, 50 and 75 % quantiles at each value, shape (k, 3), over the
        designs that have the speed in the speed range.
    sensitivity : dict of str to float
        First-order sensitivity index of each output to this parameter.
    """

    name: str
    values: np.ndarray
    edges: np.ndarray | None
    count: np.ndarray
    valid: np.ndarray
    stable: np.ndarray
    mean: dict[str, np.ndarray]
    std: dict[str, np.ndarray]
    n: dict[str, np.ndarray]
    sensitivity: dict[str, float]
    quartiles: dict[str, np.ndarray]

    @property
    def stable_fraction(self) -> np.ndarray:
        """Self-stable designs over valid designs at each value (NaN where none is valid)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.valid > 0, self.stable / np.maximum(self.valid, 1), np.nan)


@dataclass(frozen=True)
class Summary:
    """:func:`summarize`'s result."""

    speed_range: tuple[float, float]
    designs: int
    valid: int
    stable: int
    reasons: dict[str, int]
    parameters: tuple[ParameterSummary, ...]
    overall: dict[str, tuple[float, float, int]]
    """Per output: mean, standard deviation and number of designs where it exists."""

    def as_dict(self) -> dict:
        """JSON-ready."""

        def clean(a):
            return [None if not np.isfinite(x) else float(x) for x in np.asarray(a, dtype=float)]

        return {
            "speed_range": list(self.speed_range),
            "designs": self.designs,
            "valid": self.valid,
            "self_stable": self.stable,
            "invalid_reasons": self.reasons,
            "overall": {k: {"mean": _num(m), "std": _num(s), "n": n} for k, (m, s, n) in self.overall.items()},
            "parameters": [
                {
                    "name": p.name,
                    "values": clean(p.values),
                    "valid": p.valid.tolist(),
                    "self_stable_fraction": clean(p.stable_fraction),
                    **{f"mean_{k}": clean(p.mean[k]) for k in OUTPUTS},
                    "sensitivity": {k: _num(v) for k, v in p.sensitivity.items()},
                }
                for p in self.parameters
            ],
        }


def _num(x) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None


def speed_range_of(store: DesignStore, speed_range=None) -> tuple[float, float]:
    """The speed range of "self-stable": given, else the run's map speeds, else 0-10 m/s."""
    if speed_range is not None:
        lo, hi = (float(x) for x in speed_range)
        if not (0 <= lo < hi):
            raise InputError("--speed-range", f"{lo:g}:{hi:g}", "LOW:HIGH speeds [m/s] with 0 <= LOW < HIGH")
        return lo, hi
    v = store.spec.speeds
    return (float(v.min()), float(v.max())) if v.size > 1 else (0.0, 10.0)


def _stable_in(lower: np.ndarray, upper: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """A stable interval overlapping (lo, hi)."""
    with np.errstate(invalid="ignore"):
        return np.any((lower < hi) & (upper > lo), axis=-1)


def _bin_index(store: DesignStore) -> list[tuple[str, np.ndarray, np.ndarray | None]]:
    """``(name, values or centres, edges)`` of each varied parameter."""
    space = store.spec.space
    if space.is_grid:
        return [(a.name, a.values, None) for a in space.axes]
    out = []
    for d in space.draws:
        lo, hi = (d.a, d.b) if d.distribution == "uniform" else (d.a - 4 * d.b, d.a + 4 * d.b)
        edges = np.linspace(lo, hi, BINS + 1)
        out.append((d.name, 0.5 * (edges[1:] + edges[:-1]), edges))
    return out


def summarize(store: DesignStore, speed_range=None, progress: Callable[[int], None] | None = None) -> Summary:
    """Self-stable fractions, conditional means and sensitivity indices (the module docstring).

    One pass over the finished chunks of ``store``; ``progress(n)`` is called after each chunk of
    ``n`` designs (a progress bar's ``update``).
    """
    lo, hi = speed_range_of(store, speed_range)
    axes = _bin_index(store)
    space = store.spec.space
    k_sizes = [values.size for _, values, _ in axes]
    n_hist = int(np.ceil((hi - lo) / SPEED_BIN))
    acc = {
        name: {
            "count": np.zeros(k, np.int64),
            "valid": np.zeros(k, np.int64),
            "stable": np.zeros(k, np.int64),
            **{f"{o}_{m}": np.zeros(k) for o in OUTPUTS for m in ("n", "sum", "sq")},
            **{f"{o}_hist": np.zeros((k, n_hist), np.int64) for o in OUTPUTS[:2]},
        }
        for (name, _, _), k in zip(axes, k_sizes)
    }
    total = {o: np.zeros(3) for o in OUTPUTS}
    designs = valid_total = stable_total = 0
    reasons: dict[str, int] = {}
    fields = ("valid", "reason", "lower", "upper", "weave_speed", "capsize_speed")
    for start, stop, chunk in store.chunks(fields):
        valid = chunk["valid"]
        stable = _stable_in(chunk["lower"], chunk["upper"], lo, hi) & valid
        with np.errstate(invalid="ignore"):
            width = chunk["upper"][:, 0] - chunk["lower"][:, 0]
        first_lower, first_upper = chunk["lower"][:, 0], chunk["upper"][:, 0]
        outputs = {  # the ends of the first stable interval (a design without one has none)
            "weave_speed": np.where(chunk["weave_speed"] == first_lower, first_lower, np.nan),
            "capsize_speed": np.where(chunk["capsize_speed"] == first_upper, first_upper, np.nan),
            "width": np.where(np.isfinite(width), width, np.nan),
        }
        with np.errstate(invalid="ignore"):
            outputs = {
                o: np.where((y >= lo) & (y <= hi) if o != "width" else (y <= hi - lo), y, np.nan)
                for o, y in outputs.items()
            }
        bins = (
            {
                o: np.clip(np.nan_to_num((outputs[o] - lo) / SPEED_BIN).astype(np.int64), 0, n_hist - 1)
                for o in OUTPUTS[:2]
            }
            if n_hist
            else {}
        )
        designs += stop - start
        valid_total += int(valid.sum())
        stable_total += int(stable.sum())
        codes, counts = np.unique(chunk["reason"][~valid], return_counts=True)
        for text, count in zip(store.reason_texts(codes), counts):
            reasons[text] = reasons.get(text, 0) + int(count)
        for o, y in outputs.items():
            good = np.isfinite(y)
            total[o] += (good.sum(), y[good].sum(), (y[good] ** 2).sum())
        if space.is_grid:
            index = np.unravel_index(np.arange(start, stop, dtype=np.int64), space.shape)
        else:
            drawn = store.varied_values(start, stop)
            index = [
                np.clip(np.searchsorted(edges, drawn[name], side="right") - 1, 0, BINS - 1) for name, _, edges in axes
            ]
            inside = [(drawn[name] >= edges[0]) & (drawn[name] <= edges[-1]) for name, _, edges in axes]
        for a, (name, _, _) in enumerate(axes):
            i = index[a]
            keep = slice(None) if space.is_grid else inside[a]
            k = k_sizes[a]
            acc[name]["count"] += np.bincount(i[keep], minlength=k)
            acc[name]["valid"] += np.bincount(i[keep], weights=valid[keep], minlength=k).astype(np.int64)
            acc[name]["stable"] += np.bincount(i[keep], weights=stable[keep], minlength=k).astype(np.int64)
            for o, y in outputs.items():
                good = np.isfinite(y)
                if not space.is_grid:
                    good &= inside[a]
                acc[name][f"{o}_n"] += np.bincount(i[good], minlength=k)
                acc[name][f"{o}_sum"] += np.bincount(i[good], weights=y[good], minlength=k)
                acc[name][f"{o}_sq"] += np.bincount(i[good], weights=y[good] ** 2, minlength=k)
                if o in bins:
                    flat = i[good] * n_hist + bins[o][good]
                    acc[name][f"{o}_hist"] += np.bincount(flat, minlength=k * n_hist).reshape(k, n_hist)
        if progress is not None:
            progress(stop - start)
    overall = {}
    for o, (n, s, sq) in total.items():
        mean = s / n if n else np.nan
        var = max(sq / n - mean * mean, 0.0) if n else np.nan
        overall[o] = (mean, float(np.sqrt(var)) if n else np.nan, int(n))
    parameters = []
    for name, values, edges in axes:
        a = acc[name]
        mean, std, count = {}, {}, {}
        sensitivity = {}
        for o in OUTPUTS:
            n = a[f"{o}_n"]
            with np.errstate(invalid="ignore", divide="ignore"):
                m = np.where(n > 0, a[f"{o}_sum"] / n, np.nan)
                var = np.where(n > 0, np.maximum(a[f"{o}_sq"] / n - m * m, 0.0), np.nan)
            mean[o], std[o], count[o] = m, np.sqrt(var), n
            grand, spread, total_n = overall[o]
            present = n > 0
            if total_n and spread > 0 and present.any():
                between = np.sum(n[present] * (m[present] - grand) ** 2) / total_n
                sensitivity[o] = float(between / spread**2)
            else:
                sensitivity[o] = np.nan
        quartiles = {o: _quartiles(a[f"{o}_hist"], lo) for o in OUTPUTS[:2]}
        parameters.append(
            ParameterSummary(
                name,
                np.asarray(values, float),
                edges,
                a["count"],
                a["valid"],
                a["stable"],
                mean,
                std,
                count,
                sensitivity,
                quartiles,
            )
        )
    return Summary((lo, hi), designs, valid_total, stable_total, reasons, tuple(parameters), overall)


def _quartiles(hist: np.ndarray, lo: float) -> np.ndarray:
    """25/50/75 % quantiles (k, 3) from histograms (k, bins) of width :data:`SPEED_BIN` from ``lo``
    (linear within a bin); NaN where a row is empty."""
    out = np.full((hist.shape[0], 3), np.nan)
    for row in range(hist.shape[0]):
        total = hist[row].sum()
        if total == 0:
            continue
        cumulative = np.cumsum(hist[row])
        for j, q in enumerate((0.25, 0.5, 0.75)):
            b = int(np.searchsorted(cumulative, q * total))
            before = cumulative[b - 1] if b else 0
            out[row, j] = lo + SPEED_BIN * (b + (q * total - before) / max(hist[row, b], 1))
    return out


@dataclass(frozen=True)
class DesignSlice:
    """Outputs over two parameters of a grid, the others fixed (arrays of shape ``(nx, ny)``)."""

    x: tuple[str, np.ndarray]
    y: tuple[str, np.ndarray]
    fixed: dict[str, float]
    valid: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    weave_speed: np.ndarray
    capsize_speed: np.ndarray
    stable_fraction: np.ndarray
    """Fraction of the map speeds at which the design is self-stable."""
    base: dict[str, float]


def design_slice(store: DesignStore, x: str, y: str, fixed: dict[str, float] | None = None) -> DesignSlice:
    """The slice of a grid over parameters ``x`` and ``y``, every other parameter at the axis value
    nearest the given one (default: nearest the base value, else the middle of its axis).

    Raises
    ------
    InputError
        A random space (no grid to slice), an unknown or repeated parameter.
    """
    space = store.spec.space
    if not space.is_grid:
        raise InputError("--slice", f"{x}, {y}", "a grid design space (a random one has no slices)")
    names = [a.name for a in space.axes]
    for name in (x, y):
        if name not in names:
            raise InputError("--slice", name, f"one of the varied parameters {', '.join(names)}")
    if x == y:
        raise InputError("--slice", f"{x}, {y}", "two different parameters")
    fixed = dict(fixed or {})
    grids, chosen = [], {}
    for axis in space.axes:
        if axis.name in (x, y):
            grids.append(np.arange(axis.values.size))
            continue
        target = fixed.get(axis.name, space.base.get(axis.name, np.nan))
        k = int(np.nanargmin(np.abs(axis.values - target))) if np.isfinite(target) else axis.values.size // 2
        chosen[axis.name] = float(axis.values[k])
        grids.append(np.array([k]))
    mesh = np.meshgrid(*grids, indexing="ij")
    flat = np.ravel_multi_index([m.ravel() for m in mesh], space.shape)
    ix, iy = names.index(x), names.index(y)
    shape = (space.axes[ix].values.size, space.axes[iy].values.size)
    transpose = ix > iy

    def take(name: str) -> np.ndarray:
        values = store.take(name, flat)
        values = (
            values.reshape((shape[1], shape[0]) + values.shape[1:])
            if transpose
            else values.reshape(shape + values.shape[1:])
        )
        return np.swapaxes(values, 0, 1) if transpose else values

    stable = np.unpackbits(take("stable"), axis=-1, count=store.spec.speeds.size, bitorder="little")
    fraction = stable.mean(axis=-1) if store.spec.speeds.size else np.full(shape, np.nan)
    lower, upper = take("lower"), take("upper")
    return DesignSlice(
        (x, space.axes[ix].values),
        (y, space.axes[iy].values),
        chosen,
        take("valid"),
        lower,
        upper,
        take("weave_speed"),
        take("capsize_speed"),
        fraction,
        dict(space.base),
    )


@dataclass(frozen=True)
class ClosestDesign:
    """The valid design whose weave speed is nearest a target."""

    index: int
    values: dict[str, float]
    weave_speed: float
    capsize_speed: float
    stable_intervals: list[tuple[float, float]]


def closest_to_weave_speed(
    store: DesignStore, target: float, self_stable: bool = True, progress: Callable[[int], None] | None = None
) -> ClosestDesign | None:
    """The design whose weave speed is nearest ``target`` [m/s] (with ``self_stable``, among designs
    whose weave speed begins a stable interval); None when no design has a weave speed.
    ``progress(n)`` after each chunk of ``n`` designs."""
    if not (np.isfinite(target) and target > 0):
        raise InputError("--target-weave-speed", target, "a positive speed [m/s]")
    best, best_gap = -1, np.inf
    for start, stop, chunk in store.chunks(("weave_speed", "lower")):
        if progress is not None:
            progress(stop - start)
        w = chunk["weave_speed"]
        ok = np.isfinite(w)
        if self_stable:
            ok &= w == chunk["lower"][:, 0]
        if not ok.any():
            continue
        gap = np.where(ok, np.abs(w - target), np.inf)
        k = int(np.argmin(gap))
        if gap[k] < best_gap:
            best, best_gap = start + k, float(gap[k])
    if best < 0:
        return None
    values = {k: float(v[0]) for k, v in store.varied_values(best, best + 1).items()}
    lower, upper = store.read("lower", best, best + 1)[0], store.read("upper", best, best + 1)[0]
    intervals = [(float(a), float(b)) for a, b in zip(lower, upper) if np.isfinite(a)]
    return ClosestDesign(
        best,
        values,
        float(store.read("weave_speed", best, best + 1)[0]),
        float(store.read("capsize_speed", best, best + 1)[0]),
        intervals,
    )


__all__ = [
    "BINS",
    "ClosestDesign",
    "DesignSlice",
    "ParameterSummary",
    "Summary",
    "closest_to_weave_speed",
    "design_slice",
    "summarize",
]
