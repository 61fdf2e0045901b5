"""Every speed interval in which the Whipple model is self-stable, from its characteristic polynomial.

The eigenvalues at speed ``v`` are the roots of ``a4 s^4 + a3 s^3 + a2 s^2 + a1 s + a0`` (``a4 = det
M > 0``).  By the Lienard-Chipart form of the Routh-Hurwitz criterion all of them have negative real
parts exactly when ``a0 > 0``, ``a1 > 0``, ``a3 > 0`` and the third Hurwitz determinant
``H3 = a3 a2 a1 - a4 a1^2 - a0 a3^2 > 0`` (then ``a2 > 0`` follows).  As functions of ``u = v^2``
(``v > 0``) these are the polynomials of the generated ``critical_speed_polynomials``:
``a0(u)``, ``a1/v``, ``a3/v`` and ``W(u) = H3 / v^2``, each of degree two at most.

Method.  A stable interval can only begin or end where ``a0`` or ``W`` changes sign: where ``a1`` or
``a3`` would vanish inside a region with ``a0 > 0``, ``W`` is already negative (``W = -a0 a3^2 / v^2``
at ``a1 = 0``, ``W = -a4 a1^2 / v^2`` at ``a3 = 0``).  So the positive real roots of ``a0(u)`` and
``W(u)`` (at most four) cut ``v > 0`` into at most five pieces on which every condition keeps its
sign; one evaluation per piece says whether the model is stable on it.  Nothing is scanned.

Crossings.  At a sign change of ``a0`` a real eigenvalue crosses zero (``s = -a0/a1`` near it,
so it moves left as speed rises, a *stabilising* crossing, when ``a0`` rises and ``a1 > 0`` or
falls and ``a1 < 0``).  At a sign change of ``W`` with ``omega^2 = a1/a3 > 0`` a complex pair
crosses the imaginary axis at ``+/- i omega``; by Orlando's formula ``H3 = a4^3 prod_{i<j}(s_i + s_j)``
the pair moves left as speed rises when ``W`` rises and ``a3 > 0`` or falls and ``a3 < 0``.  A sign
change of ``W`` with ``a1/a3 < 0`` is a pair ``+/- sigma`` of real roots summing to zero, not a
crossing.  A double root (the polynomial touches zero) is not a crossing either.

Weave and capsize speeds (what :meth:`bikerider.benchmark.WhippleModel.critical_speeds` returns).

* With a stable interval: the *first* (lowest-speed) interval defines them.  ``weave`` is its lower
  end when a complex pair crosses into the left half-plane there (the usual case); ``capsize`` is its
  upper end when a real eigenvalue crosses zero there.  A bound of the other kind gives ``None``
  for that speed (the interval says which crossing bounds it); an interval without an upper end
  (stable at every higher speed) gives ``capsize = None`` and ``stable_range = (weave, inf)``.
  Further stable intervals (none among 7000 random bicycles within +/-50-90 % of the benchmark;
  about one in 700 sets of entry-wise perturbed matrices) are listed by :func:`stability` and in
  ``CriticalSpeeds.stable_intervals``.
* Without one: ``weave`` is the lowest speed at which a complex pair crosses into the left half
  plane and ``capsize`` the lowest at which a real eigenvalue crosses into the right half-plane
  (each mode's own change of stability; the bicycle is never self-stable).  ``None`` where there is
  no such crossing.

The scalar path (:func:`stability`, plain floats, a few microseconds) and the batched path
(:func:`stability_batch`, NumPy over any batch shape) implement the same rules; the tests hold them
equal on thousands of random bicycles and compare both with a dense eigenvalue scan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from bikerider.benchmark.roots import positive_real_roots, quadratic_roots
from bikerider.generated import benchmark_model as gen

MAX_INTERVALS = 3
"""At most four sign changes give at most three stable intervals."""
_DOUBLE = 1e-9
"""Two roots of one polynomial closer than this (relative) are a double root: a touch, not a crossing."""
REAL, OSCILLATORY = 1, 2
"""Kinds of crossing in the batched arrays (0: none)."""
KIND_NAMES = {0: None, REAL: "real", OSCILLATORY: "oscillatory"}


@dataclass(frozen=True)
class Crossing:
    """An eigenvalue crossing the imaginary axis as the speed rises.

    Attributes
    ----------
    speed : float
        Where it happens [m/s].
    kind : {"real", "oscillatory"}
        ``"real"``: a real eigenvalue crosses zero (capsize-like); ``"oscillatory"``: a complex pair
        crosses at ``+/- i frequency`` (weave-like).
    stabilising : bool
        Whether the eigenvalue(s) move into the left half-plane as the speed rises.
    frequency : float
        Angular frequency of an oscillatory crossing [rad/s]; 0 for a real one.
    """

    speed: float
    kind: str
    stabilising: bool
    frequency: float


@dataclass(frozen=True)
class StableInterval:
    """A maximal speed interval in which every eigenvalue has a negative real part.

    ``upper`` is ``inf`` when the model stays stable at every higher speed.  ``lower_crossing`` and
    ``upper_crossing`` are the crossings that bound it (``None`` for ``lower = 0`` or ``upper = inf``).
    """

    lower: float
    upper: float
    lower_crossing: Crossing | None
    upper_crossing: Crossing | None

    def __iter__(self):  # ``lower, upper = interval``
        return iter((self.lower, self.upper))


@dataclass(frozen=True)
class Stability:
    """Stable intervals and crossings of one model, and the weave and capsize speeds they define."""

    intervals: tuple[StableInterval, ...]
    crossings: tuple[Crossing, ...]
    weave: float | None
    capsize: float | None
    weave_frequency: float | None

    def is_stable(self, speeds) -> np.ndarray:
        """Whether the model is stable at each speed (interval ends are not stable)."""
        v = np.asarray(speeds, dtype=float)
        out = np.zeros(v.shape, dtype=bool)
        for interval in self.intervals:
            out |= (v > interval.lower) & (v < interval.upper)
        return out


# -- scalar path -----------------------------------------------------------------------------------
def _simple_roots(c: tuple[float, ...]) -> list[float]:
    """Positive roots of a quadratic in ``u`` where it changes sign (a double root is dropped)."""
    roots = positive_real_roots(*c) if len(c) == 3 else positive_real_roots(0.0, *c)
    if len(roots) == 2 and roots[1] - roots[0] <= _DOUBLE * roots[1]:
        return []
    return roots


def _poly(c: tuple[float, ...], u: float) -> float:
    """``c`` (highest power first, two or three coefficients) at ``u``."""
    if len(c) == 3:
        return (c[0] * u + c[1]) * u + c[2]
    return c[0] * u + c[1]


def stability(entries: dict[str, float], g: float) -> Stability:
    """Stable intervals, crossings and critical speeds of one model (the module docstring's rules).

    Parameters
    ----------
    entries : dict
        The sixteen matrix entries ``M_phiphi ... K2_deltadelta`` as floats
        (:func:`bikerider.benchmark.model.matrix_entries`).
    g : float
        Acceleration due to gravity [m/s^2].

    Raises
    ------
    OverflowError, ValueError
        From the generated polynomials when entries are too large for floating point; the caller
        (``WhippleModel.critical_speeds``) turns that into an :class:`InputError`.
    """
    a0, w, a1, a3 = gen.critical_speed_polynomials_scalar(**entries, g=g)
    if not all(map(math.isfinite, a0 + w + a1 + a3)):
        raise ValueError("critical-speed polynomials are not finite")
    cuts = sorted([(u, REAL) for u in _simple_roots(a0)] + [(u, OSCILLATORY) for u in _simple_roots(w)])
    edges = [0.0] + [u for u, _ in cuts] + [math.inf]
    stable, signs = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        u = 0.5 * (lo + hi) if hi != math.inf else 2.0 * lo + 1.0
        v0, vw = _poly(a0, u), _poly(w, u)
        signs.append((v0, vw))
        stable.append(v0 > 0 and vw > 0 and _poly(a1, u) > 0 and _poly(a3, u) > 0)
    crossings: list[Crossing | None] = []
    for k, (u, kind) in enumerate(cuts):
        before, after = signs[k][kind - 1], signs[k + 1][kind - 1]
        crossing = None
        if (before > 0) != (after > 0):
            rising = after > before
            if kind == REAL:
                crossing = Crossing(math.sqrt(u), "real", rising == (_poly(a1, u) > 0), 0.0)
            else:
                a1_u, a3_u = _poly(a1, u), _poly(a3, u)
                if a3_u != 0 and a1_u / a3_u > 0:
                    crossing = Crossing(math.sqrt(u), "oscillatory", rising == (a3_u > 0), math.sqrt(a1_u / a3_u))
        crossings.append(crossing)
    intervals = []
    k = 0
    while k < len(stable):
        if not stable[k]:
            k += 1
            continue
        j = k
        while j + 1 < len(stable) and stable[j + 1]:
            j += 1
        upper = edges[j + 1]
        intervals.append(
            StableInterval(
                math.sqrt(edges[k]),
                math.sqrt(upper) if upper != math.inf else math.inf,
                crossings[k - 1] if k > 0 else None,
                crossings[j] if j < len(cuts) else None,
            )
        )
        k = j + 1
    events = tuple(c for c in crossings if c is not None)
    weave, capsize, frequency = _critical(intervals, events)
    return Stability(tuple(intervals), events, weave, capsize, frequency)


def _critical(intervals: list[StableInterval], crossings: tuple[Crossing, ...]):
    """Weave speed, capsize speed and weave frequency by the rules of the module docstring."""
    if intervals:
        first = intervals[0]
        low, high = first.lower_crossing, first.upper_crossing
        weave = low if low is not None and low.kind == "oscillatory" else None
        capsize = high.speed if high is not None and high.kind == "real" else None
    else:
        weave = next((c for c in crossings if c.kind == "oscillatory" and c.stabilising), None)
        capsize = next((c.speed for c in crossings if c.kind == "real" and not c.stabilising), None)
    return (weave.speed if weave else None), capsize, (weave.frequency if weave else None)


# -- batched path ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class StabilityBatch:
    """:func:`stability` for a batch of models, as arrays of the batch shape ``S``.

    Attributes
    ----------
    lower, upper : numpy.ndarray, shape S + (3,)
        Ends of the stable intervals [m/s], lowest first, NaN-padded; ``upper`` is ``inf`` for an
        interval without an upper end.
    lower_kind, upper_kind : numpy.ndarray of int, shape S + (3,)
        The crossing at each end: 1 real, 2 oscillatory, 0 none (``v = 0``, ``inf`` or padding).
    weave, capsize, weave_frequency : numpy.ndarray, shape S
        The critical speeds [m/s] and the weave frequency [rad/s] (NaN: none), by the rules of the
        module docstring.
    """

    lower: np.ndarray
    upper: np.ndarray
    lower_kind: np.ndarray
    upper_kind: np.ndarray
    weave: np.ndarray
    capsize: np.ndarray
    weave_frequency: np.ndarray

    @property
    def n_intervals(self) -> np.ndarray:
        """Number of stable intervals of each model."""
        return np.isfinite(self.lower).sum(axis=-1)

    def is_stable(self, speeds) -> np.ndarray:
        """Stability at each speed, shape ``S + speeds.shape`` (interval ends are not stable)."""
        v = np.asarray(speeds, dtype=float)
        out = np.zeros(self.lower.shape[:-1] + v.shape, dtype=bool)
        pad = (...,) + (None,) * v.ndim
        for k in range(self.lower.shape[-1]):
            out |= (v > self.lower[..., k][pad]) & (v < self.upper[..., k][pad])  # NaN compares False
        return out


def _sign_changes(values: np.ndarray) -> np.ndarray:
    """``values`` (..., 5): whether the sign differs between consecutive pieces, (..., 4)."""
    positive = values > 0
    return positive[..., 1:] != positive[..., :-1]


def stability_batch(entries: dict[str, np.ndarray], g) -> StabilityBatch:
    """:func:`stability` for a batch: matrix entries (and ``g``) of any common broadcast shape.

    Parameters
    ----------
    entries : dict
        The sixteen matrix entries as arrays (:func:`bikerider.benchmark.model.matrix_entries`).
    g : float or array_like
        Acceleration due to gravity [m/s^2].

    Returns
    -------
    StabilityBatch
        NaN where a polynomial is not finite (entries beyond floating point) as for no interval.

    Notes
    -----
    A batch of more than :data:`CHUNK` models is evaluated :data:`CHUNK` at a time (the generated
    polynomials keep about 200 temporaries per model alive): the memory beyond the results does not
    grow with the batch.
    """
    arrays = {k: np.asarray(v, dtype=float) for k, v in entries.items()}
    g_array = np.asarray(g, dtype=float)
    shape = np.broadcast_shapes(g_array.shape, *(a.shape for a in arrays.values()))
    size = int(np.prod(shape))
    if size <= CHUNK:
        return _stability_batch(arrays, g_array)
    flat = {k: np.broadcast_to(a, shape).reshape(size) for k, a in arrays.items()}
    g_flat = np.broadcast_to(g_array, shape).reshape(size)
    parts = [
        _stability_batch({k: a[i : i + CHUNK] for k, a in flat.items()}, g_flat[i : i + CHUNK])
        for i in range(0, size, CHUNK)
    ]
    return StabilityBatch(
        *(
            np.concatenate([getattr(p, f.name) for p in parts]).reshape(shape + getattr(parts[0], f.name).shape[1:])
            for f in fields(StabilityBatch)
        )
    )


CHUNK = 8192
"""Models :func:`stability_batch` evaluates at once."""


def _stability_batch(entries: dict[str, np.ndarray], g) -> StabilityBatch:
    """:func:`stability_batch` of one chunk."""
    with np.errstate(all="ignore"):
        a0c, wc, a1c, a3c = gen.critical_speed_polynomials(**entries, g=g)
    shape = a0c.shape[:-1]
    roots = []
    for c in (a0c, wc):
        low, high = quadratic_roots(c[..., 0], c[..., 1], c[..., 2])
        double = np.abs(high - low) <= _DOUBLE * np.abs(high)
        for r in (low, high):
            roots.append(np.where((r > 0) & ~double, r, np.inf))
    cuts = np.stack(roots, axis=-1)  # (..., 4): a0 roots then W roots
    kinds = np.broadcast_to(np.array([REAL, REAL, OSCILLATORY, OSCILLATORY]), cuts.shape)
    order = np.argsort(cuts, axis=-1, kind="stable")
    cuts = np.take_along_axis(cuts, order, axis=-1)
    kinds = np.where(np.isfinite(cuts), np.take_along_axis(kinds, order, axis=-1), 0)
    edges = np.concatenate([np.zeros(shape + (1,)), cuts, np.full(shape + (1,), np.inf)], axis=-1)
    lo, hi = edges[..., :-1], edges[..., 1:]
    with np.errstate(all="ignore"):
        test = np.where(np.isfinite(hi), 0.5 * (lo + hi), 2.0 * lo + 1.0)  # a point inside each piece
        test = np.where(np.isfinite(test), test, np.nan)

        def at(c, u):
            out = np.zeros_like(u)
            for k in range(c.shape[-1]):
                out = out * u + c[..., k, None]
            return out

        v0, vw, v1, v3 = at(a0c, test), at(wc, test), at(a1c, test), at(a3c, test)
        stable = (v0 > 0) & (vw > 0) & (v1 > 0) & (v3 > 0)  # (..., 5); NaN pieces are not stable
        # crossings at each cut
        a1_cut, a3_cut = at(a1c, cuts), at(a3c, cuts)
        rising0, rising_w = v0[..., 1:] > v0[..., :-1], vw[..., 1:] > vw[..., :-1]
        real = (kinds == REAL) & _sign_changes(v0)
        omega2 = a1_cut / a3_cut
        oscillatory = (kinds == OSCILLATORY) & _sign_changes(vw) & (omega2 > 0)
        stabilising = np.where(kinds == REAL, rising0 == (a1_cut > 0), rising_w == (a3_cut > 0))
        crossing_kind = np.where(real, REAL, np.where(oscillatory, OSCILLATORY, 0))
    # stable intervals: runs of stable pieces
    previous = np.concatenate([np.zeros(shape + (1,), bool), stable[..., :-1]], axis=-1)
    following = np.concatenate([stable[..., 1:], np.zeros(shape + (1,), bool)], axis=-1)
    starts, ends = stable & ~previous, stable & ~following
    lower = np.full(shape + (MAX_INTERVALS,), np.nan)
    upper = np.full(shape + (MAX_INTERVALS,), np.nan)
    lower_kind = np.zeros(shape + (MAX_INTERVALS,), dtype=int)
    upper_kind = np.zeros(shape + (MAX_INTERVALS,), dtype=int)
    cut_kind = np.concatenate([np.zeros(shape + (1,), int), crossing_kind, np.zeros(shape + (1,), int)], axis=-1)
    start_rank = np.cumsum(starts, axis=-1) - 1
    end_rank = np.cumsum(ends, axis=-1) - 1
    for j in range(5):
        for k in range(MAX_INTERVALS):
            s = starts[..., j] & (start_rank[..., j] == k)
            lower[..., k] = np.where(s, lo[..., j], lower[..., k])
            lower_kind[..., k] = np.where(s, cut_kind[..., j], lower_kind[..., k])
            e = ends[..., j] & (end_rank[..., j] == k)
            upper[..., k] = np.where(e, hi[..., j], upper[..., k])
            upper_kind[..., k] = np.where(e, cut_kind[..., j + 1], upper_kind[..., k])
    lower, upper = np.sqrt(lower), np.sqrt(upper)
    # critical speeds
    has = np.isfinite(lower[..., 0])
    speeds_at_cuts = np.sqrt(cuts)
    first_osc = _first(speeds_at_cuts, (crossing_kind == OSCILLATORY) & stabilising)
    first_real = _first(speeds_at_cuts, (crossing_kind == REAL) & ~stabilising)
    weave = np.where(has, np.where(lower_kind[..., 0] == OSCILLATORY, lower[..., 0], np.nan), first_osc)
    capsize = np.where(has, np.where(upper_kind[..., 0] == REAL, upper[..., 0], np.nan), first_real)
    with np.errstate(all="ignore"):
        u = weave * weave
        frequency = np.sqrt(at(a1c, u[..., None])[..., 0] / at(a3c, u[..., None])[..., 0])
    frequency = np.where(np.isfinite(weave), frequency, np.nan)
    return StabilityBatch(lower, upper, lower_kind, upper_kind, weave, capsize, frequency)


def _first(speeds: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The lowest of ``speeds`` (..., k, ascending) where ``mask``; NaN where none."""
    any_ = mask.any(axis=-1)
    index = np.argmax(mask, axis=-1)
    return np.where(any_, np.take_along_axis(speeds, index[..., None], axis=-1)[..., 0], np.nan)


__all__ = ["Crossing", "StableInterval", "Stability", "StabilityBatch", "stability", "stability_batch"]
