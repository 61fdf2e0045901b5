"""Free-decay records as an experiment writes them, their fits, and the eigenvalues they give.

A :class:`Record` is one free decay cut from a log: the samples of the state signals it holds
(roll rate, and where logged roll angle, steer angle, steer rate), the speed the bicycle ran at,
its group (the unit the diagnosis holds out: a file, a session) and the control law acting. The
readers (:mod:`bikerider.io.experiment`) cut records from logs with a manifest; records that are
found wanting while they are read (a window with missing values, a speed that cannot be read) keep
the reason in :attr:`Record.problem` and are left out, never stopping the diagnosis.

:func:`fit_records` fits each record's weave eigenvalue (:func:`bikerider.gap.measured.extraction.
weave_eigenvalue`: a damped oscillation with the slow capsize mode, half a cycle and more when
the decay is clear) to the roll rate and, where asked, to other signals, combined when they agree.
A record that cannot be fitted is left out with the fit's reason.  Every fit carries its quality:
r^2, the cycles it spans, standard errors.

:func:`detect_windows` is the automatic alternative to an experimenter's list of windows.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np

from bikerider import progress
from bikerider.errors import FitError
from bikerider.gap.measured.control import ControlLaw
from bikerider.gap.measured.extraction import WeaveEstimate, weave_eigenvalue
from bikerider.gap.measured.repair import repair_record
from bikerider.gap.measured.tables import EigenvalueData
from bikerider.gap.parallel import MIN_RECORDS, map_forked

LOG = logging.getLogger(__name__)

SIGNALS = ("roll_rate", "roll_angle", "steer_angle", "steer_rate")
"""State signals a record may hold (rad, rad/s; benchmark sign convention)."""
SIGNAL_UNITS = {"roll_rate": "rad/s", "roll_angle": "rad", "steer_angle": "rad", "steer_rate": "rad/s"}
MAX_RECORD_SAMPLES = 100_000
"""Most samples of one record: a free decay lasts seconds (a weave's time constant is about one),
and 100,000 samples are 100 s even at 1 kHz.  A longer record holds more than one decay (and its fit
would take minutes): cut the decay out, or give the log with a manifest of windows."""
AGREEMENT = 3.0
"""Fits of one record to two signals are combined when they agree within this many combined
standard errors; otherwise the first (the roll rate) stands alone."""


@dataclass
class Record:
    """One free decay.

    Attributes
    ----------
    name : str
        ``file[start:end]`` (sample window) or the file.
    source : str
        Where the record was defined (``manifest:line``, or the file).
    time : ndarray
        Sample times from the window's first sample [s].
    signals : dict
        Signal name (:data:`SIGNALS`) to samples.
    speed, speed_sigma : float
        The speed the bicycle ran at and its scatter over the record [m/s].
    group : str
    law : ControlLaw
    controller_speed : float
        The speed the control law is evaluated at (the controller's own reading) [m/s].
    window : tuple of int or None
        Sample indices ``(start, end)`` in the log.
    problem : str or None
        Why the record cannot be used, found while it was read.
    fit_signals : tuple of str
        The signals its eigenvalue is fitted to, in order of preference.
    speed_measured : bool
        The speed is a sensor's reading during the record (a speed column), not a set value.
    repairs : list of str
        What :func:`bikerider.gap.measured.repair.repair_record` did to the record as read (empty: nothing).
    raw : tuple of ndarray or None
        The recorded instants and roll rate before a repair (for figures); ``None`` when not repaired.
    step : float or None
        The logger's sampling step [s] (the median over its whole log, where the log has a time
        column): the grid a record with uneven stamps is resampled onto.
    """

    name: str
    source: str
    time: np.ndarray
    signals: dict[str, np.ndarray]
    speed: float
    speed_sigma: float
    group: str
    law: ControlLaw
    controller_speed: float
    window: tuple[int, int] | None = None
    problem: str | None = None
    fit_signals: tuple[str, ...] = ("roll_rate",)
    speed_measured: bool = False
    repairs: list[str] = field(default_factory=list)
    raw: tuple[np.ndarray, np.ndarray] | None = None
    step: float | None = None

    @property
    def gains(self) -> np.ndarray:
        """The control gains at the controller's speed ``[k_phi, k_phid, k_delta, k_deltad]``."""
        return self.law(self.controller_speed)

    @property
    def duration(self) -> float:
        return float(self.time[-1] - self.time[0]) if self.time.size else 0.0


def record_summary(r, used: bool, reason: str | None) -> dict:
    """What every record's summary starts with (a decay's :class:`Record` or a multisine run's): its
    name, source, group, law, speeds, duration, whether it was used (or why not) and its repairs."""
    return {
        "record": r.name,
        "source": r.source,
        "group": r.group,
        "law": r.law.name,
        "speed": r.speed,
        "speed_sigma": r.speed_sigma,
        "controller_speed": r.controller_speed,
        "duration": r.duration,
        "used": used,
        "reason": reason,
        "repairs": list(r.repairs),
    }


@dataclass
class RecordFit:
    """A record and what its fit gave.

    Attributes
    ----------
    record : Record
    estimate : WeaveEstimate or None
        The weave eigenvalue (signals combined where they agree); ``None`` when left out.
    fits : dict
        The fit of each signal that could be fitted.
    reason : str or None
        Why the record is left out.
    notes : list of str
    """

    record: Record
    estimate: WeaveEstimate | None
    fits: dict[str, WeaveEstimate] = field(default_factory=dict)
    reason: str | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def used(self) -> bool:
        return self.estimate is not None

    def summary(self) -> dict:
        """Plain values for reports and JSON."""
        out = record_summary(self.record, self.used, self.reason)
        if self.estimate is not None:
            e = self.estimate
            out.update(
                {
                    "real": e.eigenvalue.real,
                    "imag": e.eigenvalue.imag,
                    "real_sigma": e.real_sigma,
                    "imag_sigma": e.imag_sigma,
                    "r2": e.r2,
                    "cycles": e.cycles,
                    "model": e.kind,
                    "signals": list(self.fits),
                }
            )
        return out


def fit_record(record: Record) -> RecordFit:
    """Repair one record as read (:func:`bikerider.gap.measured.repair.repair_record`: time stamps, gaps,
    clipping) and fit its weave eigenvalue; a failure becomes the record's reason, never an exception."""
    if record.problem:
        return RecordFit(record, None, reason=record.problem)
    repaired, repair = repair_record(record)
    if repair.repaired:
        raw = repair.raw or (np.asarray(record.time, float), np.asarray(record.signals.get("roll_rate", []), float))
        repaired = replace(repaired, repairs=list(repair.actions), raw=raw)
    if repair.problem:
        return RecordFit(repaired, None, reason=repair.problem)
    record = repaired
    fits: dict[str, WeaveEstimate] = {}
    reasons: dict[str, str] = {}
    for name in record.fit_signals:
        if name not in record.signals:
            continue
        try:
            fits[name] = weave_eigenvalue(record.time, record.signals[name])
        except FitError as exc:
            reasons[name] = str(exc)
    if not fits:
        if not reasons:
            return RecordFit(
                record, None, reason="none of the signals " + ", ".join(record.fit_signals) + " is in the record"
            )
        reason = "; ".join(f"{k}: {v}" for k, v in reasons.items())
        if record.repairs:  # say what the record was by then
            reason += " (after the repairs: " + "; ".join(record.repairs) + ")"
        return RecordFit(record, None, reason=reason)
    estimate, note = combine_fits(fits)
    out = RecordFit(record, estimate, fits)
    if note:
        out.notes.append(note)
    for name, why in reasons.items():
        out.notes.append(f"{name} not fitted ({why}); the other signals alone")
    return out


def fit_records(records: list[Record]) -> list[RecordFit]:
    """Fit every record (see :func:`fit_record`); logs one line per record left out."""
    if records:
        progress.begin("fitting records", len(records), "records")
    # independent fits, one per core (the same results); each keeps the caller's record object, unless
    # the fit holds the record as repaired (its samples then differ from the caller's)
    fits = [
        fit if fit.record.repairs else replace(fit, record=record)
        for record, fit in zip(records, map_forked(fit_record, records, min_items=MIN_RECORDS))
    ]
    progress.advance(len(records))
    for record, fit in zip(records, fits):
        if not fit.used:
            LOG.info("%s left out: %s", record.name, fit.reason)
    return fits


def combine_fits(fits: dict[str, WeaveEstimate]) -> tuple[WeaveEstimate, str | None]:
    """Inverse-variance mean of the signals' fits when they agree (:data:`AGREEMENT`); else the first."""
    names = list(fits)
    first = fits[names[0]]
    if len(names) == 1:
        return first, None
    values = [fits[n].eigenvalue for n in names]
    rs = np.array([max(fits[n].real_sigma, 1e-12) for n in names])
    is_ = np.array([max(fits[n].imag_sigma, 1e-12) for n in names])
    d_r = max(abs(v.real - values[0].real) / math.hypot(rs[0], s) for v, s in zip(values[1:], rs[1:]))
    d_i = max(abs(v.imag - values[0].imag) / math.hypot(is_[0], s) for v, s in zip(values[1:], is_[1:]))
    if d_r < AGREEMENT and d_i < AGREEMENT:
        wr, wi = 1 / rs**2, 1 / is_**2
        real = float(np.sum(wr * [v.real for v in values]) / wr.sum())
        imag = float(np.sum(wi * [v.imag for v in values]) / wi.sum())
        combined = WeaveEstimate(
            complex(real, imag),
            float(1 / math.sqrt(wr.sum())),
            float(1 / math.sqrt(wi.sum())),
            first.extra_mode,
            first.residual_rms,
            first.r2,
            first.cycles,
            first.kind,
            first.params,
            first.t0,
        )
        return combined, None
    return first, (f"{' and '.join(names)} fits disagree ({d_r:.1f}, {d_i:.1f} standard errors); {names[0]} alone")


def eigenvalues_of(fits: list[RecordFit]) -> EigenvalueData:
    """One weave row per record used: speed, eigenvalue, standard errors, group, the law's gains."""
    used = [f for f in fits if f.used]
    if not used:
        return EigenvalueData.empty()
    laws = {f.record.law.name: f.record.law for f in used}
    return EigenvalueData(
        np.array([f.record.speed for f in used]),
        np.array([f.estimate.eigenvalue for f in used]),
        np.array([f.estimate.real_sigma for f in used]),
        np.array([f.estimate.imag_sigma for f in used]),
        np.array([f.record.speed_sigma for f in used]),
        ["weave"] * len(used),
        [f.record.group for f in used],
        np.array([f.record.gains for f in used]),
        [f.record.name for f in used],
        [f.record.law.name for f in used],
        laws,
        ["record"] * len(used),
        np.array([f.record.speed_measured for f in used], bool),
    )


# ---------------------------------------------------------------------------------------------
# Automatic detection of free decays
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DetectorSettings:
    """Settings of :func:`detect_windows` (defaults suit 1-3 s weave decays after lateral pulses).

    Attributes
    ----------
    threshold : float
        A perturbation is a roll rate above this many robust noise levels (and above
        ``min_rate``).
    min_rate : float
        Least peak roll rate of a perturbation [rad/s].
    gap : float
        Excursions closer than this belong to one perturbation's response [s].
    max_duration : float
        Longest record [s].
    min_duration : float
        Shortest record [s].
    margin : float
        Time left out before the next perturbation [s].
    """

    threshold: float = 8.0
    min_rate: float = 0.2
    gap: float = 1.0
    max_duration: float = 3.5
    min_duration: float = 0.8
    margin: float = 0.1


def detect_windows(roll_rate, rate: float, settings: DetectorSettings = DetectorSettings()) -> list[tuple[int, int]]:
    """Free decays in a roll-rate log: ``[(start, end), ...]`` sample windows.

    Method: the noise level is the robust (median absolute deviation) scatter of the
    sample-to-sample differences divided by sqrt(2); a perturbation is a run of samples whose roll
    rate exceeds ``threshold`` times that level (and ``min_rate``), runs closer than ``gap``
    being one perturbation's response.  A record starts at the largest roll-rate peak of the
    response's first ``gap`` (the end of the push, where the experimenters of the SBW data start
    theirs) and ends ``margin`` before the next perturbation starts, after at most
    ``max_duration``; shorter than ``min_duration`` it is dropped.  Samples that are not finite
    end a record and are never inside one.
    """
    y = np.asarray(roll_rate, dtype=float)
    n = y.size
    finite = np.isfinite(y)
    if n < 3 or not np.any(finite):
        return []
    d = np.diff(np.where(finite, y, 0.0))
    d = d[finite[1:] & finite[:-1]]
    noise = 1.4826 * float(np.median(np.abs(d - np.median(d)))) / math.sqrt(2) if d.size else 0.0
    level = max(settings.threshold * noise, settings.min_rate)
    above = finite & (np.abs(np.where(finite, y, 0.0)) > level)
    idx = np.flatnonzero(above)
    if idx.size == 0:
        return []
    gap = max(1, int(round(settings.gap * rate)))  # at least one sample: a slow log (0.5 Hz) has gaps too
    events = [[int(idx[0]), int(idx[0])]]
    for k in idx[1:]:
        if k - events[-1][1] <= gap:
            events[-1][1] = int(k)
        else:
            events.append([int(k), int(k)])
    windows = []
    for j, (onset, _) in enumerate(events):
        head = slice(onset, min(onset + gap, n))
        start = onset + int(np.argmax(np.abs(np.where(finite[head], y[head], 0.0))))
        stop = events[j + 1][0] - int(round(settings.margin * rate)) if j + 1 < len(events) else n
        stop = min(stop, start + int(round(settings.max_duration * rate)), n)
        bad = np.flatnonzero(~finite[start:stop])
        if bad.size:
            stop = start + int(bad[0])
        if stop - start >= settings.min_duration * rate:
            windows.append((start, stop))
    return windows
