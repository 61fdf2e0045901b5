"""Records as labs write them: time stamps, gaps and saturation repaired on purpose, each said.

A data logger's record is seldom a clean uniform series.  :func:`repair_record` takes a
:class:`~bikerider.gap.measured.records.Record` as it was read and returns the record the fits and the
models compare with, and what was done to it (:class:`Repair`), or why it cannot be used:

* **Time stamps that are not finite** (an empty time cell): the sample is dropped.
* **A clock reset** (a stamp more than :data:`RESET_STEPS` median steps before the previous one):
  the later stamps are shifted so that the clock continues at the median step.
* **Duplicate or non-increasing stamps** (a repeated row, a sample logged out of order): the sample
  is dropped (the first of a repeated stamp is kept).
* **Missing values** (NaN, empty cells) in a signal the fits use (the roll rate, the fitted signals,
  the steer angle): the sample is dropped.  Another signal with missing values is set aside (not
  used by this record), said.
* **Clipped (saturated) samples** of the roll rate and the fitted signals (a rate gyro saturates;
  an angle encoder's quantised steps sit still at every peak, so it is not searched): a run of samples
  at exactly the record's largest or smallest value, two or more entered and left by steps larger
  than the signal's median step (a smooth peak arrives flat, a sensor's rail is hit at speed), or
  three or more in a signal that otherwise seldom repeats a value (under 5 % of its steps), is
  dropped.
* **A constant sensor bias** needs no repair: every fit of a record (its own and each model's
  initial-state fit) has a constant offset per signal.
* **Non-uniform time** (jitter, the gaps the drops above leave, a clock that runs otherwise than
  the nominal rate): the batched simulators of the models (:mod:`bikerider.gap.inference.indirect`,
  :mod:`bikerider.gap.inference.timedomain`) step by one matrix exponential of a uniform step, so the record
  is resampled onto a uniform grid at the logger's step (the median over its whole log, else over the
  record; rounded to three significant digits), by
  linear interpolation between neighbouring samples.  The error of linear interpolation over an
  interval ``H`` is at most ``H^2 / 8 max|y''|`` (the maximum over that interval); ``y''`` is taken from the record's own fit on
  the recorded instants (a preliminary fit of the damped oscillation, :func:`bikerider.gap.
  extraction.weave_eigenvalue`, which takes any increasing time), evaluated on a fine grid.  A gap
  (an interval over 1.5 median steps) is bridged only when that bound is at most the fit's residual RMS (interpolation then adds less
  than the record's own misfit); the record is cut at a longer gap, keeping its longest part.  The
  bound is reported with the repair.

Only the roll rate's, the fitted signals' and the steer angle's samples decide what is dropped; the
record then holds the same instants for every signal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from bikerider.errors import FitError
from bikerider.gap.measured.extraction import weave_eigenvalue

RESET_STEPS = 10.0
"""A stamp this many median steps (or more) before the previous one is a clock reset; a smaller step
back is a sample out of order (dropped)."""
UNIFORM_RTOL = 1e-6
"""Steps that agree within this fraction are uniform (as :mod:`bikerider.gap.inference.indirect` requires)."""
MIN_CLIP_RUN = 2
"""Fewest samples at the extreme that count as clipping."""
GAP_STEPS = 1.5
"""An interval longer than this many median steps is a gap (samples missing); shorter ones are jitter."""
MIN_FLAT_RUN = 3
"""A run this long at the extreme is clipping whatever its steps, in a signal that seldom repeats a value."""
MAX_REPEATS = 0.05
"""Fraction of repeated consecutive values (away from the extremes) below which a signal is continuous."""
FINE = 8
"""Points per sampling step where the preliminary fit's second derivative is evaluated."""


@dataclass
class Repair:
    """What was done to a record.

    Attributes
    ----------
    actions : list of str
        One line per repair (what, how many, where).
    resampled : bool
        The record was put on a uniform grid by linear interpolation.
    step : float
        The uniform sampling step of the repaired record [s].
    bound : dict
        Per resampled signal, the bound on the interpolation error (the signal's units).
    problem : str or None
        Why the record cannot be used after all.
    raw : tuple of ndarray or None
        The recorded instants (a clock reset undone) and roll rate, on the repaired record's time axis.
    """

    actions: list[str] = field(default_factory=list)
    resampled: bool = False
    step: float = math.nan
    bound: dict[str, float] = field(default_factory=dict)
    problem: str | None = None
    raw: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def repaired(self) -> bool:
        return bool(self.actions)


def essential(record) -> tuple[str, ...]:
    """The signals whose samples decide which instants a record keeps."""
    names = ("roll_rate",) + tuple(record.fit_signals) + ("steer_angle",)
    return tuple(n for n in dict.fromkeys(names) if n in record.signals)


def repair_record(record):
    """``(record, repair)``: the record as the fits use it, and what was done (module docstring).

    The input record is not changed.  A record that needs nothing comes back as it is.  When the
    repair leaves too little, ``repair.problem`` says why (the record is then left out).
    """
    rep = Repair()
    t = np.asarray(record.time, dtype=float)
    signals = {k: np.asarray(v, dtype=float) for k, v in record.signals.items()}
    n0 = t.size
    if n0 == 0:
        rep.problem = "the record holds no samples"
        return record, rep
    keep = np.isfinite(t)
    if not keep.all():
        rep.actions.append(f"{int((~keep).sum())} samples without a time stamp dropped")
    t, signals = t[keep], {k: v[keep] for k, v in signals.items()}
    if t.size < 2:
        rep.problem = "fewer than two samples with a time stamp"
        return record, rep
    t = _clock(t, rep)
    shown = (t.copy(), signals["roll_rate"].copy()) if "roll_rate" in signals else None
    t, signals = _monotonic(t, signals, rep)
    names = essential(record)
    missing = np.zeros(t.size, bool)
    for name in names:
        bad = ~np.isfinite(signals[name])
        if bad.any():
            rep.actions.append(
                f"{int(bad.sum())} missing {name} samples dropped (first at {t[int(np.flatnonzero(bad)[0])]:.3f} s)"
            )
            missing |= bad
    for name in [k for k in signals if k not in names]:
        if not np.all(np.isfinite(signals[name][~missing])):
            rep.actions.append(f"{name} has missing values: not used for this record")
            del signals[name]
    clipped = np.zeros(t.size, bool)
    for name in [n for n in names if n == "roll_rate" or n in record.fit_signals]:  # a rate gyro saturates
        run = _clipped(signals[name], ~missing)
        if run.any():
            rep.actions.append(
                f"{int(run.sum())} clipped {name} samples dropped (at {signals[name][run][0]:.4g}, "
                f"the record's {'largest' if signals[name][run][0] > np.nanmedian(signals[name]) else 'smallest'} value)"
            )
            clipped |= run
    keep = ~(missing | clipped)
    t, signals = t[keep], {k: v[keep] for k, v in signals.items()}
    if t.size < 3:
        rep.problem = f"{t.size} usable samples left after the repairs ({'; '.join(rep.actions)})"
        return record, rep
    steps = np.diff(t)
    median = float(np.median(steps))
    uniform = np.allclose(steps, steps[0], rtol=UNIFORM_RTOL, atol=0)
    if uniform and not rep.actions:
        return record, rep
    if not uniform:
        hint = getattr(record, "step", None)  # the logger's step over its whole log, where known
        nominal = hint if hint and 0.5 * median < hint < 2 * median else median
        t, signals = _resample(t, signals, nominal, names, rep)
        if rep.problem:
            return record, rep
    else:
        rep.step = float(steps[0])
    if shown is not None:  # the samples as recorded, on the repaired record's time axis
        rep.raw = (shown[0] - t[0], shown[1])
    out = replace(record, time=t - t[0], signals=signals)
    return out, rep


def _clock(t: np.ndarray, rep: Repair) -> np.ndarray:
    """Stamps with every clock reset undone (the clock continues at the median forward step)."""
    steps = np.diff(t)
    forward = steps[steps > 0]
    if forward.size == 0:
        return t
    median = float(np.median(forward))
    resets = np.flatnonzero(steps <= -RESET_STEPS * median)
    if resets.size == 0:
        return t
    t = t.copy()
    for k in resets:
        shift = t[k] + median - t[k + 1]
        t[k + 1 :] += shift
        rep.actions.append(
            f"clock reset after sample {k + 1} ({-steps[k]:.3g} s back): later stamps shifted by {shift:.3g} s"
        )
    return t


def _monotonic(t: np.ndarray, signals: dict, rep: Repair) -> tuple[np.ndarray, dict]:
    """Drop samples whose stamp does not increase on the last one kept."""
    keep = np.ones(t.size, bool)
    last = t[0]
    for k in range(1, t.size):
        if t[k] <= last:
            keep[k] = False
        else:
            last = t[k]
    if keep.all():
        return t, signals
    same = int(np.count_nonzero(~keep[1:] & (np.diff(t) == 0)))
    rep.actions.append(
        f"{int((~keep).sum())} samples with a duplicate or non-increasing stamp dropped ({same} repeated stamps)"
    )
    return t[keep], {k: v[keep] for k, v in signals.items()}


def _clipped(y: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Samples of flat runs at the record's extreme that are entered and left steeply (saturation)."""
    out = np.zeros(y.size, bool)
    v = np.where(valid, y, np.nan)
    if np.count_nonzero(valid) < 5:
        return out
    d = np.abs(np.diff(v))
    typical = float(np.nanmedian(d[d > 0])) if np.any(d > 0) else 0.0
    if typical <= 0:
        return out
    # how often the signal repeats a value away from its extremes: rarely for a continuous reading
    # (a gyro logged to several digits), often for a quantised one (an encoder at rest)
    inner = (v[1:] != np.nanmax(v)) & (v[1:] != np.nanmin(v)) & np.isfinite(d)
    repeats = float(np.mean(d[inner] == 0)) if np.any(inner) else 1.0
    for extreme in (np.nanmax(v), np.nanmin(v)):
        at = np.flatnonzero(v == extreme)
        if at.size < MIN_CLIP_RUN:
            continue
        for run in np.split(at, np.flatnonzero(np.diff(at) > 1) + 1):
            if run.size < MIN_CLIP_RUN:
                continue
            lo, hi = int(run[0]), int(run[-1])
            entry = abs(v[lo] - v[lo - 1]) if lo >= 1 else math.inf
            leave = abs(v[hi + 1] - v[hi]) if hi + 1 < v.size else math.inf
            entry = entry if math.isfinite(entry) else math.inf
            leave = leave if math.isfinite(leave) else math.inf
            steep = min(entry, leave) > typical and not (math.isinf(entry) and math.isinf(leave))
            flat = run.size >= MIN_FLAT_RUN and repeats < MAX_REPEATS
            if steep or flat:
                out[run] = True
    return out


def _round_step(step: float) -> float:
    """A sampling step rounded to three significant digits (records of one logger share a grid)."""
    if step <= 0 or not math.isfinite(step):
        return step
    digits = 2 - int(math.floor(math.log10(step)))
    return round(step, digits)


def _resample(t: np.ndarray, signals: dict, median: float, names: tuple[str, ...], rep: Repair):
    """The record on a uniform grid, gaps bridged where the interpolation error is bounded (module docstring)."""
    gaps = np.diff(t)
    try:  # the record's own fit on its recorded instants bounds the signal's curvature
        fit = weave_eigenvalue(t, signals["roll_rate"])
    except FitError as exc:
        rep.problem = f"{'; '.join(rep.actions) + '; ' if rep.actions else ''}not uniformly sampled, and {exc}"
        return t, signals
    bound = gaps**2 / 8 * _curvature(fit, t)  # per interval: H^2 / 8 max|y''| over it
    floor = max(fit.residual_rms, 1e-12)
    too_long = (gaps > GAP_STEPS * median) & (bound > floor)  # a gap, and too long to bridge
    if too_long.any():
        # keep the longest stretch between gaps too long to bridge
        cuts = np.flatnonzero(too_long)
        edges = np.concatenate([[0], cuts + 1, [t.size]])
        spans = [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]
        a, b = max(spans, key=lambda s: t[s[1] - 1] - t[s[0]])
        longest = float(gaps[cuts].max())
        rep.actions.append(
            f"cut at {cuts.size} gap{'s' if cuts.size > 1 else ''} too long to interpolate (up to {longest:.3g} s: "
            f"error bound up to {float(bound[cuts].max()):.2g} above the fit's residual {floor:.2g}); "
            f"kept {t[a]:.3f}-{t[b - 1]:.3f} s"
        )
        t, signals = t[a:b], {k: v[a:b] for k, v in signals.items()}
        gaps, bound = np.diff(t), bound[a : b - 1]
        if t.size < 3:
            rep.problem = "; ".join(rep.actions) + ": too few samples left"
            return t, signals
        if np.allclose(gaps, gaps[0], rtol=UNIFORM_RTOL, atol=0):  # what is left is uniform
            rep.step = float(gaps[0])
            return t, signals
    step = _round_step(median)
    grid = t[0] + step * np.arange(int(math.floor((t[-1] - t[0]) / step + 1e-9)) + 1)
    out = {k: np.interp(grid, t, v) for k, v in signals.items()}
    worst = float(bound.max()) if bound.size else 0.0
    rep.resampled, rep.step = True, step
    rep.bound = {"roll_rate": worst}
    spread = (float(gaps.min()), float(gaps.max()))
    rep.actions.append(
        f"time stamps not uniform (steps {1e3 * spread[0]:.2f}-{1e3 * spread[1]:.2f} ms): resampled to "
        f"{1e3 * step:.4g} ms by linear interpolation, roll-rate error at most {worst:.2g} rad/s "
        f"(fit residual {floor:.2g})"
    )
    return grid, out


def _curvature(fit, t: np.ndarray) -> np.ndarray:
    """Largest ``|y''|`` of the fitted curve over each interval between samples (a fine grid of
    :data:`FINE` points per interval)."""
    u = np.linspace(0.0, 1.0, FINE + 1)
    fine = (t[:-1, None] + np.diff(t)[:, None] * u).ravel()  # (n - 1) intervals, FINE + 1 points each
    h = 1e-3 * float(np.median(np.diff(t)))
    second = (fit.evaluate(fine + h) - 2 * fit.evaluate(fine) + fit.evaluate(fine - h)) / h**2
    return np.max(np.abs(second).reshape(t.size - 1, FINE + 1), axis=1)


TAGS = (
    ("clock reset", "clock reset"),
    ("without a time stamp", "stamps missing"),
    ("non-increasing stamp", "duplicate stamps"),
    ("missing", "missing values"),
    ("clipped", "clipped"),
    ("cut at", "cut at a gap"),
    ("resampled", "resampled"),
)
"""Short names of the repairs (for figures), from the text of each action."""


def repair_tags(actions: list[str]) -> list[str]:
    """Short names of a record's repairs, in the order of :data:`TAGS`, for a figure's label."""
    return [tag for key, tag in TAGS if any(key in a for a in actions)]
