"""The noise of a new decay's signals: each signal's sample noise and the data's noise as functions of speed.

Sample noise comes from the records (:func:`signal_noise`, :func:`fit_residual`), is given, or is assumed
(:data:`ASSUMED_NOISE`).  The data's noise at a speed is the median per speed of the data, linear between
those speeds (:func:`over_speed`): continuous in speed, where the nearest speed's value jumps half-way
between two.
"""

from __future__ import annotations

import math

import numpy as np

from bikerider.errors import FitError, InputError
from bikerider.gap.measured.extraction import weave_eigenvalue
from bikerider.gap.measured.records import SIGNALS
from bikerider.gap.parallel import map_forked

MAX_NOISE = 10.0
"""Largest sample noise of a signal (rad, rad/s): noise beyond ten radians (per second) would drown
any lateral motion of a bicycle; a larger value is a unit slip (and overflows the planned covariances)."""
ASSUMED_NOISE = {
    "roll_rate": 0.01,
    "roll_angle": 0.002,
    "steer_angle": 2 * math.pi / 8192 / math.sqrt(12),
    "steer_rate": 0.02,
}
"""Sample noise assumed for a signal the data's records do not hold (rad, rad/s): a MEMS gyro, an IMU's
angle, a 13-bit steer encoder's quantisation, its rate."""
MIN_REPLICATES = 3
"""Fewest records at one speed whose fits of a signal give that signal's run-to-run scatter."""
SAME_SPEED = 0.03
"""Records (or rows) whose speeds differ by less than this fraction are taken at one speed."""


def sample_noise(diagnosis, given: dict | None) -> tuple[dict[str, float], dict[str, str], dict[str, list]]:
    """Sample noise of each signal (given, from the data's records, or assumed), where it came from, and
    every record's fit of each signal as ``(speed, fit)`` pairs (for :func:`signal_scatter`)."""
    values: dict[str, float] = {}
    source: dict[str, str] = {}
    signal_fits: dict[str, list] = {}
    d = diagnosis
    if d.record_rows:
        held = {
            name: [d.records[k].record for k in d.record_rows if name in d.records[k].record.signals]
            for name in SIGNALS
        }
        # every record's fit of every signal: the diagnosis's own where it fitted the signal (the same
        # call), the others fitted one per core
        scatter = {n: [x for x in (signal_noise(r.signals[n]) for r in held[n]) if x > 0] for n in SIGNALS}
        own = {(id(d.records[k].record), n): f for k in d.record_rows for n, f in d.records[k].fits.items()}
        todo = [(n, r) for n in SIGNALS if scatter[n] for r in held[n] if (id(r), n) not in own]
        fitted = map_forked(lambda item: record_fit(item[1].time, item[1].signals[item[0]]), todo)
        own.update({(id(r), n): f for (n, r), f in zip(todo, fitted)})
        for name in SIGNALS:
            if not scatter[name]:
                continue
            fits = [(r.speed, own[(id(r), name)]) for r in held[name]]
            signal_fits[name] = [(v, f) for v, f in fits if f is not None]
            left = [f.residual_rms for _, f in signal_fits[name]]
            values[name] = max(float(np.median(scatter[name])), float(np.median(left)) if left else 0.0)
            source[name] = (
                f"the data's records: the larger of their sample-to-sample scatter ({np.median(scatter[name]):.2g}) "
                "and what their own fits leave ("
                + (f"{np.median(left):.2g}, RMS residual over {len(left)} records" if left else "no fit")
                + ")"
            )
        for name in SIGNALS:
            if name not in values:
                values[name], source[name] = ASSUMED_NOISE[name], "assumed (the data hold no such signal)"
    for name, value in (given or {}).items():
        if name not in SIGNALS:
            raise InputError("noise signal", name, "one of " + ", ".join(SIGNALS))
        if not (isinstance(value, int | float) and math.isfinite(value) and 0 < value <= MAX_NOISE):
            raise InputError(
                f"noise of {name}", value, f"a positive standard deviation of at most {MAX_NOISE:g} (rad or rad/s)"
            )
        values[name], source[name] = float(value), "given"
    return values, source, signal_fits


def signal_scatter(diagnosis, signal_fits: dict[str, list], signal: str):
    """Run-to-run variance (real, imaginary) of the records' own fits of ``signal``, beyond their fits'
    standard errors, as a function of speed: per speed of the data with :data:`MIN_REPLICATES` fits or
    more, linearly between those speeds; ``None`` for a signal the diagnosis fits (its data uncertainty
    holds it) or without such a speed."""
    d = diagnosis
    fitted = {name for k in d.record_rows for name in d.records[k].record.fit_signals}
    fits = signal_fits.get(signal, [])
    if signal in fitted or not fits:
        return None
    speeds = np.array([v for v, _ in fits])
    groups = [g for g in speed_groups(speeds) if g.size >= MIN_REPLICATES]
    if not groups:
        return None
    centre, real, imag = [], [], []
    for g in groups:
        z = np.array([fits[k][1].eigenvalue for k in g])
        own_r = float(np.median([fits[k][1].real_sigma ** 2 for k in g]))
        own_i = float(np.median([fits[k][1].imag_sigma ** 2 for k in g]))
        centre.append(float(np.median(speeds[g])))
        real.append(max(float(np.var(z.real, ddof=1)) - own_r, 0.0))
        imag.append(max(float(np.var(z.imag, ddof=1)) - own_i, 0.0))
    return lambda speed: (float(np.interp(speed, centre, real)), float(np.interp(speed, centre, imag)))


def run_scatter(problem, records: bool):
    """The data's run-to-run variance (real, imaginary) of the weave eigenvalue as a function of speed (per
    speed of the data, linearly between them: :func:`over_speed`): with ``records``, their scatter beyond
    their fits' own standard errors; from tables, the rows' whole uncertainty (which of it is scatter
    from run to run the table does not say)."""
    p = problem
    eig = p.eigen
    first = np.cumsum([0] + [2 if m == "weave" else 1 for m in eig.mode])
    weave = np.array([r for r in range(len(eig)) if eig.mode[r] == "weave"])
    speeds = eig.speed[weave]
    real = np.array([p.var_data[first[r]] for r in weave])
    imag = np.array([p.var_data[first[r] + 1] for r in weave])
    if records:  # beyond each row's own standard error, per speed
        real = real - over_groups(speeds, eig.real_sigma[weave] ** 2)
        imag = imag - over_groups(speeds, eig.imag_sigma[weave] ** 2)
    real, imag = over_speed(speeds, real), over_speed(speeds, imag)
    return lambda speed: (max(real(speed), 0.0), max(imag(speed), 0.0))


def record_fit(time, samples):
    """The record fit of one signal of a record (``None`` when it cannot fit it).

    Its RMS residual bounds the signal's noise from below where the samples' scatter does not: a
    signal smoothed before it was logged (an IMU's fused roll angle) scatters less from sample to
    sample than its error, and a decay departs from the fit's two-mode function by more than the
    sensor's noise; both show in what the fit leaves, which a new decay's fit will meet too.  Its
    eigenvalues, over the records of one speed, give the signal's own run-to-run scatter.
    """
    try:
        return weave_eigenvalue(time, samples)
    except FitError:
        return None


def fit_residual(time, samples) -> float | None:
    """The RMS residual of :func:`record_fit` (``None`` when it cannot fit the signal)."""
    fit = record_fit(time, samples)
    return None if fit is None else float(fit.residual_rms)


def signal_noise(samples) -> float:
    """A signal's sample noise: the robust (median absolute deviation) scatter of its second differences
    over sqrt(6), which a decay's own curvature hardly touches at a lab's sampling rates; for a quantised
    signal at least its step over sqrt(12)."""
    y = np.asarray(samples, dtype=float)
    y = y[np.isfinite(y)]
    if y.size < 4:
        return 0.0
    second = np.diff(y, 2)
    mad = 1.4826 * float(np.median(np.abs(second - np.median(second)))) / math.sqrt(6)
    steps = np.abs(np.diff(y))
    steps = steps[steps > 0]
    quantum = float(steps.min()) / math.sqrt(12) if steps.size else 0.0
    return max(mad, quantum)


def speed_groups(speeds) -> list[np.ndarray]:
    """Indices of ``speeds`` grouped by speed (sorted; a group ends where the next speed is more than
    :data:`SAME_SPEED` of it above the group's last)."""
    speeds = np.asarray(speeds, float)
    order = np.argsort(speeds, kind="stable")
    groups: list[list[int]] = []
    for k in order:
        if groups and speeds[k] - speeds[groups[-1][-1]] <= SAME_SPEED * speeds[k] + 1e-9:
            groups[-1].append(int(k))
        else:
            groups.append([int(k)])
    return [np.array(g) for g in groups]


def over_speed(speeds, values, least: int = 1):
    """The medians of ``values`` per speed group (:func:`speed_groups`) as a function of speed, linear between
    the groups' median speeds (the nearest group's beyond them): continuous in speed, where the value of
    the nearest group jumps half-way between two.  Groups of fewer than ``least`` values are skipped
    (``None`` when none is left)."""
    speeds, values = np.asarray(speeds, float), np.asarray(values, float)
    groups = [g for g in speed_groups(speeds) if g.size >= least]
    if not groups:
        return None
    centre = np.array([np.median(speeds[g]) for g in groups])
    level = np.array([np.median(values[g]) for g in groups])
    return lambda at: float(np.interp(at, centre, level))


def over_groups(speeds, values) -> np.ndarray:
    """Each value replaced by the median of its speed group (:func:`speed_groups`)."""
    values = np.asarray(values, float)
    out = np.empty_like(values)
    for g in speed_groups(speeds):
        out[g] = np.median(values[g])
    return out
