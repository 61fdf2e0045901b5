"""Steer-torque multisine records: the runs ``gap --next`` recommends, read back as frequency responses.

A :class:`MultisineRecord` is one run at one speed under one control law: the applied steer torque
and the measured response (roll rate, and where logged steer angle, steer rate, roll angle) at the
recorded instants, which may jitter, miss samples or hold missing values.

:func:`fit_multisine` repairs the record as a logger left it (:func:`repair_multisine`, each repair
said, as for decays in :mod:`bikerider.gap.measured.repair`) and estimates its frequency response
``H(w_k)`` from steer torque to each response signal at the multisine's lines ``w_k``:

* **Lines**: those the manifest declares, or found in the torque itself: the frequencies where the
  torque's periodogram, on the record's own grid ``1 / duration``, holds at least
  :data:`LINE_SHARE` of the strongest line's power.
* **Estimate at the recorded instants**: every signal ``y`` (the torque too) is fitted by linear
  least squares as ``c0 + c1 t + sum_k (a_k cos w_k t + b_k sin w_k t)`` at the instants it was
  recorded (no resampling, so jitter and gaps need no interpolation); ``Y_k = a_k - i b_k`` and
  ``H_k = Y_k / U_k``.  The offset and drift absorb a sensor bias and a slow drift.
* **Standard error from the noise**: the residual variance of the fit of ``y`` (degrees of freedom
  the samples less the coefficients) times ``(X^T X)^-1`` gives the covariance of ``a_k, b_k``;
  divided by ``|U_k|`` it is that of ``H_k``'s real and imaginary parts (the torque is the
  controller's command, taken as known; its own residual is reported).  The residual holds the
  sensor noise and whatever no linear response at the lines explains (friction's harmonics, a rig's
  disturbances), so a nonlinear run has wider errors, honestly.
* **Transient**: the record must be the periodic steady state; ``settle`` seconds at the start are
  left out (the manifest says how many).  A run shorter than one period of its lowest line, or with
  fewer than :data:`MIN_SAMPLES_PER_COEFFICIENT` samples per fitted coefficient, is left out.

The diagnosis compares each candidate's ``H(w_k)`` of its closed loop at the record's speed and law
with these values (:mod:`bikerider.gap.inference.frequency_response`), like with like: a linear
model's periodic steady state at a line is exactly ``H(w_k)`` times the torque's line.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np

from bikerider.gap.measured.control import ControlLaw
from bikerider.gap.measured.records import SIGNAL_UNITS, SIGNALS, record_summary
from bikerider.gap.measured.repair import Repair, _clipped, _clock, _monotonic

LOG = logging.getLogger(__name__)

LINE_SHARE = 0.01
"""A line found in the torque holds at least this share of the strongest line's power."""
MAX_LINES = 64
"""Most lines of one multisine."""
MIN_SAMPLES_PER_COEFFICIENT = 4
"""Fewest samples per fitted coefficient (two per line, offset and drift)."""
MIN_EXPLAINED = 0.9
"""Least share of the torque's variance the lines must explain (a multisine is its lines)."""
GAP_STEPS = 1.5
"""An interval longer than this many median steps is a gap (samples missing), reported."""


@dataclass
class MultisineRecord:
    """One steer-torque multisine run.

    Attributes
    ----------
    name : str
        ``file`` or ``file[start:end]``.
    source : str
        Where the run was declared (``manifest:line``).
    time : ndarray
        Recorded instants from the first sample [s] (may jitter; NaN where a stamp is missing).
    torque : ndarray
        The applied steer torque [N m] (benchmark sign convention).
    signals : dict
        Response signal name (:data:`bikerider.gap.measured.records.SIGNALS`) to samples.
    speed, speed_sigma : float
        [m/s]
    group : str
    law : ControlLaw
    controller_speed : float
    outputs : tuple of str
        The response signals compared (those of them the record holds).
    lines : tuple of float or None
        The multisine's frequencies [Hz] as declared; ``None``: found in the torque.
    settle : float
        Seconds at the start left out (transient).
    problem : str or None
        Why the run cannot be used, found while it was read.
    speed_measured : bool
    repairs : list of str
    window : tuple of int or None
    """

    name: str
    source: str
    time: np.ndarray
    torque: np.ndarray
    signals: dict[str, np.ndarray]
    speed: float
    speed_sigma: float
    group: str
    law: ControlLaw
    controller_speed: float
    outputs: tuple[str, ...] = ("roll_rate", "steer_angle")
    lines: tuple[float, ...] | None = None
    settle: float = 0.0
    problem: str | None = None
    speed_measured: bool = False
    repairs: list[str] = field(default_factory=list)
    window: tuple[int, int] | None = None

    kind = "multisine"

    @property
    def gains(self) -> np.ndarray:
        """The control gains at the controller's speed ``[k_phi, k_phid, k_delta, k_deltad]``."""
        return self.law(self.controller_speed)

    @property
    def duration(self) -> float:
        t = np.asarray(self.time, float)
        t = t[np.isfinite(t)]
        return float(t.max() - t.min()) if t.size else 0.0


@dataclass
class MultisineFit:
    """A multisine record and its frequency response.

    Attributes
    ----------
    record : MultisineRecord
        As repaired.
    lines : ndarray
        [Hz]
    response : dict
        Output signal to ``H`` at the lines ``(K,)`` complex (signal unit per N m).
    sigma : dict
        Output signal to the standard error ``(K,)`` of each of ``H``'s real and imaginary parts.
    torque_amplitude : ndarray
        ``|U_k|`` [N m].
    reason : str or None
        Why the record is left out.
    notes : list of str
    """

    record: MultisineRecord
    lines: np.ndarray = field(default_factory=lambda: np.zeros(0))
    response: dict[str, np.ndarray] = field(default_factory=dict)
    sigma: dict[str, np.ndarray] = field(default_factory=dict)
    torque_amplitude: np.ndarray = field(default_factory=lambda: np.zeros(0))
    reason: str | None = None
    notes: list[str] = field(default_factory=list)
    torque_coefficients: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """The torque's least-squares fit ``c0, c1, a_1..a_K, b_1..b_K`` (:func:`design`): the input a model is
    simulated with (:func:`bikerider.gap.inference.frequency_response.predict_frf_friction`)."""

    def torque_at(self, time) -> np.ndarray:
        """The torque's fit (its lines, offset and drift) at any instants [N m]."""
        return design(np.asarray(time, float), self.lines, self.record.time) @ self.torque_coefficients

    def estimate(self, y: np.ndarray) -> np.ndarray:
        """``H_k`` of samples ``y`` at the record's instants, as the record's own were estimated."""
        X = design(self.record.time, self.lines)
        coef = np.linalg.lstsq(X, y, rcond=None)[0]
        K = self.lines.size
        U = self.torque_coefficients[2 : 2 + K] - 1j * self.torque_coefficients[2 + K :]
        return (coef[2 : 2 + K] - 1j * coef[2 + K :]) / U

    @property
    def used(self) -> bool:
        return self.reason is None and bool(self.response)

    def summary(self) -> dict:
        """Plain values for reports and JSON."""
        r = self.record
        out = {**record_summary(r, self.used, self.reason), "kind": "multisine"}
        if self.used:
            out["lines"] = [float(x) for x in self.lines]
            out["signals"] = list(self.response)
            out["frf"] = {
                name: {
                    "real": [float(x) for x in h.real],
                    "imag": [float(x) for x in h.imag],
                    "sigma": [float(x) for x in self.sigma[name]],
                }
                for name, h in self.response.items()
            }
        return out


def repair_multisine(record: MultisineRecord) -> tuple[MultisineRecord, list[str], str | None]:
    """``(record, actions, problem)``: the run as the estimate uses it and what was done to it.

    Stamps without a value are dropped, a clock reset undone, repeated or non-increasing stamps
    dropped (as for decays); samples where the torque or a compared output is missing are dropped
    (another signal with missing values is set aside); clipped outputs are dropped (a saturated gyro);
    non-uniform instants (jitter) and gaps are reported, never interpolated: the lines are fitted at the
    instants recorded.  The input record is not changed.
    """
    rep = Repair()  # repair.py's helpers say what they did in it
    actions = rep.actions
    t = np.asarray(record.time, float)
    torque = np.asarray(record.torque, float)
    signals = {k: np.asarray(v, float) for k, v in record.signals.items()}
    if t.size == 0:
        return record, actions, "the record holds no samples"
    keep = np.isfinite(t)
    if not keep.all():
        actions.append(f"{int((~keep).sum())} samples without a time stamp dropped")
    t, torque, signals = t[keep], torque[keep], {k: v[keep] for k, v in signals.items()}
    if t.size < 3:
        return record, actions, "fewer than three samples with a time stamp"

    t = _clock(t, rep)
    both = dict(signals, _torque=torque)
    t, both = _monotonic(t, both, rep)
    torque = both.pop("_torque")
    signals = both
    outputs = [o for o in record.outputs if o in signals]
    missing = ~np.isfinite(torque)
    if missing.any():
        actions.append(f"{int(missing.sum())} missing torque samples dropped (first at {t[np.argmax(missing)]:.3f} s)")
    for name in outputs:
        bad = ~np.isfinite(signals[name])
        if bad.any():
            actions.append(f"{int(bad.sum())} missing {name} samples dropped (first at {t[np.argmax(bad)]:.3f} s)")
            missing |= bad
    for name in [k for k in signals if k not in outputs]:
        if not np.all(np.isfinite(signals[name][~missing])):
            actions.append(f"{name} has missing values: not used for this record")
            del signals[name]
    clipped = np.zeros(t.size, bool)
    for name in outputs:
        run = _clipped(signals[name], ~missing)
        if run.any():
            actions.append(f"{int(run.sum())} clipped {name} samples dropped (at {signals[name][run][0]:.4g})")
            clipped |= run
    keep = ~(missing | clipped)
    t, torque, signals = t[keep], torque[keep], {k: v[keep] for k, v in signals.items()}
    if t.size < 3:
        return record, actions, f"{t.size} usable samples left after the repairs ({'; '.join(actions)})"
    steps = np.diff(t)
    median = float(np.median(steps))
    gaps = steps > GAP_STEPS * median
    if gaps.any():
        actions.append(
            f"{int(gaps.sum())} gap{'s' if gaps.sum() > 1 else ''} in the samples (up to {float(steps.max()):.3g} s): "
            "the lines are fitted at the instants recorded, nothing interpolated"
        )
    elif not np.allclose(steps, steps[0], rtol=1e-6, atol=0):
        actions.append(
            f"time stamps not uniform (steps {1e3 * float(steps.min()):.2f}-{1e3 * float(steps.max()):.2f} ms): "
            "the lines are fitted at the instants recorded, nothing resampled"
        )
    out = replace(record, time=t - t[0], torque=torque, signals=signals, repairs=list(record.repairs) + actions)
    return out, actions, None


def find_lines(time: np.ndarray, torque: np.ndarray) -> np.ndarray:
    """The multisine's lines [Hz] in a torque record: the frequencies on the grid ``1 / duration`` whose
    least-squares periodogram holds at least :data:`LINE_SHARE` of the strongest one's power."""
    duration = float(time[-1] - time[0]) + float(np.median(np.diff(time)))
    f0 = 1.0 / duration
    nyquist = 0.5 / float(np.median(np.diff(time)))
    grid = f0 * np.arange(1, int(nyquist / f0))
    if grid.size == 0:
        return grid
    u = torque - torque.mean()
    if not np.any(u):  # a constant torque has no line
        return grid[:0]
    w = 2 * math.pi * grid
    power = np.empty(grid.size)
    for start in range(0, grid.size, 256):  # chunks bound the memory of the (samples x frequencies) products
        ph = np.outer(time, w[start : start + 256])
        power[start : start + 256] = (u @ np.cos(ph)) ** 2 + (u @ np.sin(ph)) ** 2
    return grid[power >= LINE_SHARE * power.max()]


def design(time: np.ndarray, lines: np.ndarray, reference: np.ndarray | None = None) -> np.ndarray:
    """Columns ``1, t - mean(reference), cos(2 pi f_k t)..., sin(2 pi f_k t)...`` at ``time`` (``reference``:
    the record's instants, whose mean centres the drift; ``time`` itself by default)."""
    w = 2 * math.pi * np.asarray(lines, float)
    ph = np.outer(time, w)
    centre = float(np.mean(time if reference is None else reference))
    return np.hstack([np.ones((time.size, 1)), time[:, None] - centre, np.cos(ph), np.sin(ph)])


def fit_multisine(record: MultisineRecord) -> MultisineFit:
    """Repair one multisine record and estimate its frequency response (module docstring); a record that
    cannot be used gets its reason, never an exception."""
    if record.problem:
        return MultisineFit(record, reason=record.problem)
    repaired, actions, problem = repair_multisine(record)
    if problem:
        return MultisineFit(replace(record, repairs=list(record.repairs) + actions), reason=problem)
    r = repaired
    t = r.time
    if r.settle > 0:
        keep = t >= r.settle
        if np.count_nonzero(keep) < 3:
            return MultisineFit(r, reason=f"nothing left after the {r.settle:g} s settling time ({r.duration:.3g} s)")
        t = t[keep]
        r = replace(r, time=t, torque=r.torque[keep], signals={k: v[keep] for k, v in r.signals.items()})
    outputs = [o for o in r.outputs if o in r.signals]
    if not outputs:
        return MultisineFit(r, reason="none of the signals " + ", ".join(r.outputs) + " is in the record")
    lines = np.asarray(r.lines, float) if r.lines else find_lines(t, r.torque)
    span = float(t[-1] - t[0])
    if lines.size == 0:
        return MultisineFit(r, reason="no line found in the steer torque (is the torque column right?)")
    if lines.size > MAX_LINES:
        return MultisineFit(
            r, reason=f"{lines.size} lines found in the torque: expected a multisine of at most {MAX_LINES}"
        )
    if span * lines.min() < 1.0:
        return MultisineFit(
            r,
            reason=f"{span:.3g} s of steady response: shorter than one period of the lowest line "
            f"({lines.min():.3g} Hz)",
        )
    X = design(t, lines)
    n, m = X.shape
    if n < MIN_SAMPLES_PER_COEFFICIENT * m:
        return MultisineFit(
            r, reason=f"{n} samples for {lines.size} lines: expected at least {MIN_SAMPLES_PER_COEFFICIENT * m}"
        )
    K = lines.size
    XtX_inv = np.linalg.pinv(X.T @ X)
    coef_u = XtX_inv @ (X.T @ r.torque)
    U = coef_u[2 : 2 + K] - 1j * coef_u[2 + K :]
    fit = MultisineFit(r, lines=lines, torque_amplitude=np.abs(U), torque_coefficients=coef_u)
    weak = np.abs(U) < 1e-3 * np.abs(U).max()
    if weak.any():
        return MultisineFit(
            r, reason=f"the torque has no power at {', '.join(f'{x:.3g}' for x in lines[weak][:3])} Hz: check the lines"
        )
    resid_u = r.torque - X @ coef_u
    explained = 1.0 - float(np.var(resid_u)) / max(float(np.var(r.torque)), 1e-300)
    if explained < MIN_EXPLAINED:
        return MultisineFit(
            r,
            reason=f"the lines {', '.join(f'{x:.3g}' for x in lines[:4])}{' ...' if K > 4 else ''} Hz explain "
            f"{100 * max(explained, 0):.0f} % of the steer torque's variance (expected {100 * MIN_EXPLAINED:.0f} % "
            "or more): check the lines, or leave them out to find them in the torque",
        )
    fit.notes.append(f"torque: {K} lines, residual RMS {float(np.sqrt(np.mean(resid_u**2))):.2g} N m")
    var_re = np.diag(XtX_inv)[2 : 2 + K]
    var_im = np.diag(XtX_inv)[2 + K :]
    for name in outputs:
        y = r.signals[name]
        coef = XtX_inv @ (X.T @ y)
        resid = y - X @ coef
        s2 = float(resid @ resid) / max(n - m, 1)
        Y = coef[2 : 2 + K] - 1j * coef[2 + K :]
        H = Y / U
        # the larger of the cosine and sine coefficients' variances, over |U|: each part of H
        fit.response[name] = H
        fit.sigma[name] = np.sqrt(s2 * np.maximum(var_re, var_im)) / np.abs(U)
        if not np.all(np.isfinite(H)) or not np.all(fit.sigma[name] > 0):
            return MultisineFit(r, reason=f"{name}: no finite frequency response (a constant signal?)")
    return fit


def fit_multisines(records: list[MultisineRecord]) -> list[MultisineFit]:
    """:func:`fit_multisine` of every record; logs one line per record left out."""
    fits = [fit_multisine(r) for r in records]
    for f in fits:
        if not f.used:
            LOG.info("%s left out: %s", f.record.name, f.reason)
    return fits


@dataclass
class FrequencyResponseData:
    """The frequency-response observations of the multisine records used: one row per line and signal.

    Attributes
    ----------
    speed, speed_sigma : ndarray
    gains : ndarray ``(R, 4)``
    omega : ndarray
        [rad/s]
    signal : list of str
        The response signal (``roll_rate``, ``steer_angle``, ...).
    value : ndarray complex
    sigma : ndarray
        Standard error of each of the real and imaginary parts.
    group, source : list of str
    record : ndarray of int
        The multisine record (index into the fits given) of each row.
    speed_sensor : ndarray of bool
        The row's speed is a sensor's reading (a ``speed_sensor`` candidate rescales it).
    """

    speed: np.ndarray
    speed_sigma: np.ndarray
    gains: np.ndarray
    omega: np.ndarray
    signal: list[str]
    value: np.ndarray
    sigma: np.ndarray
    group: list[str]
    source: list[str]
    record: np.ndarray
    speed_sensor: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))

    def __post_init__(self):
        if self.speed_sensor.size != self.value.size:
            self.speed_sensor = np.zeros(self.value.size, bool)

    def __len__(self) -> int:
        return int(self.value.size)

    @classmethod
    def empty(cls) -> FrequencyResponseData:
        return cls(
            np.zeros(0),
            np.zeros(0),
            np.zeros((0, 4)),
            np.zeros(0),
            [],
            np.zeros(0, complex),
            np.zeros(0),
            [],
            [],
            np.zeros(0, int),
        )

    @classmethod
    def of(cls, fits: list[MultisineFit]) -> FrequencyResponseData:
        """Rows of the fits used (in order: record, signal, line)."""
        rows: dict[str, list] = {
            k: []
            for k in (
                "speed",
                "ss",
                "gains",
                "omega",
                "signal",
                "value",
                "sigma",
                "group",
                "source",
                "record",
                "sensor",
            )
        }
        for k, f in enumerate(fits):
            if not f.used:
                continue
            r = f.record
            for name, H in f.response.items():
                for j in range(H.size):
                    rows["speed"].append(r.speed)
                    rows["ss"].append(r.speed_sigma)
                    rows["gains"].append(r.gains)
                    rows["omega"].append(2 * math.pi * f.lines[j])
                    rows["signal"].append(name)
                    rows["value"].append(H[j])
                    rows["sigma"].append(f.sigma[name][j])
                    rows["group"].append(r.group)
                    rows["source"].append(f"{r.name} {name} {f.lines[j]:.3g} Hz")
                    rows["record"].append(k)
                    rows["sensor"].append(bool(r.speed_measured))
        if not rows["speed"]:
            return cls.empty()
        return cls(
            np.array(rows["speed"], float),
            np.array(rows["ss"], float),
            np.array(rows["gains"], float).reshape(-1, 4),
            np.array(rows["omega"], float),
            rows["signal"],
            np.array(rows["value"], complex),
            np.array(rows["sigma"], float),
            rows["group"],
            rows["source"],
            np.array(rows["record"], int),
            np.array(rows["sensor"], bool),
        )

    def subset(self, keep: np.ndarray) -> FrequencyResponseData:
        keep = np.asarray(keep, int)
        return FrequencyResponseData(
            self.speed[keep],
            self.speed_sigma[keep],
            self.gains[keep],
            self.omega[keep],
            [self.signal[k] for k in keep],
            self.value[keep],
            self.sigma[keep],
            [self.group[k] for k in keep],
            [self.source[k] for k in keep],
            self.record[keep],
            self.speed_sensor[keep],
        )


OUTPUT_UNITS = {name: f"{SIGNAL_UNITS[name]} per N m" for name in SIGNALS}
"""Units of a frequency response to each signal."""
