"""Fit a damped oscillation to a sampled signal; combine the periods of repeated trials.

Model (times measured from the first sample, ``t' = t - t[0]``)::

    y(t) = offset [+ drift t'] + exp(-sigma t') (A sin(omega_d t') + B cos(omega_d t'))

``omega_d`` is the damped angular frequency and ``sigma`` the decay rate: the eigenvalues of the
underlying second-order system are ``s = -sigma +/- i omega_d``, its natural frequency
``omega_n = sqrt(omega_d^2 + sigma^2)`` and damping ratio ``zeta = sigma / omega_n`` (so
``exp(-sigma t) = exp(-zeta omega_n t)``).  ``sigma`` may come out negative (a growing
oscillation); the fit does not force a sign.

Method.  The initial frequency is the peak of the zero-padded FFT of the detrended signal (refined
by a parabola through the peak and its neighbours), or ``guess_frequency``; the initial decay rate
comes from a straight-line fit to the logarithm of the Hilbert envelope; offset, drift and the
``A``, ``B`` amplitudes start from the linear least-squares solution at those values.  Then
``scipy.optimize.least_squares`` refines all parameters.  Standard errors are the square roots of
the diagonal of ``s^2 (J^T J)^-1`` with ``J`` the Jacobian at the solution and ``s^2`` the residual
variance (residual sum of squares over ``n - p``).

A fit is refused (:class:`~bikerider.errors.FitError`) when the time samples are not finite and
strictly increasing, there are fewer than :data:`MIN_SAMPLES` samples, the record holds less than
one cycle, the optimiser does not converge, the Jacobian is singular, or the oscillation amplitude
is less than :data:`MIN_AMPLITUDE_SIGNIFICANCE` times its standard error (no oscillation in the
noise).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bikerider.errors import FitError
from bikerider.fitting import PERIOD_TRIAL_TOLERANCE

MIN_SAMPLES = 20
"""Fewest samples a fit accepts."""

MIN_CYCLES = 1.0
"""Fewest oscillation cycles the record must span (at the initial frequency)."""

MIN_AMPLITUDE_SIGNIFICANCE = 10.0
"""The fitted amplitude must exceed this many of its standard errors."""


@dataclass(frozen=True)
class DampedOscillationFit:
    """Result of :func:`fit_damped_oscillation`.

    Attributes
    ----------
    omega_d : float
        Damped angular frequency [rad/s].
    sigma : float
        Decay rate [1/s] (minus the real part of the eigenvalue).
    offset, A, B : float
        Constant offset and the sine and cosine amplitudes at the first sample [signal units].
    drift : float or None
        Linear drift [signal units/s], ``None`` when not fitted.
    covariance : ndarray
        Covariance of ``(omega_d, sigma, offset, A, B[, drift])``.
    residual_rms : float
        Root-mean-square residual [signal units].
    t0 : float
        Time of the first sample [s] (the model's time origin).
    n_samples : int
    """

    omega_d: float
    sigma: float
    offset: float
    A: float
    B: float
    drift: float | None
    covariance: np.ndarray
    residual_rms: float
    t0: float
    n_samples: int

    # -- standard errors ----------------------------------------------------------------------
    def _se(self, index: int) -> float:
        return float(math.sqrt(max(self.covariance[index, index], 0.0)))

    @property
    def omega_d_se(self) -> float:
        """Standard error of ``omega_d`` [rad/s]."""
        return self._se(0)

    @property
    def sigma_se(self) -> float:
        """Standard error of ``sigma`` [1/s]."""
        return self._se(1)

    @property
    def offset_se(self) -> float:
        return self._se(2)

    # -- derived quantities -------------------------------------------------------------------
    @property
    def period(self) -> float:
        """Damped period ``2 pi / omega_d`` [s]."""
        return 2 * math.pi / self.omega_d

    @property
    def period_se(self) -> float:
        """Standard error of the period [s]."""
        return 2 * math.pi / self.omega_d**2 * self.omega_d_se

    @property
    def frequency(self) -> float:
        """Damped angular frequency ``omega_d`` [rad/s] (same as :attr:`omega_d`)."""
        return self.omega_d

    @property
    def omega_n(self) -> float:
        """Natural frequency ``sqrt(omega_d^2 + sigma^2)`` [rad/s]."""
        return math.hypot(self.omega_d, self.sigma)

    @property
    def zeta(self) -> float:
        """Damping ratio ``sigma / omega_n``."""
        return self.sigma / self.omega_n

    @property
    def zeta_se(self) -> float:
        """Standard error of the damping ratio (delta method with the omega_d, sigma covariance)."""
        wn3 = self.omega_n**3
        grad = np.array([-self.sigma * self.omega_d / wn3, self.omega_d**2 / wn3])
        return float(math.sqrt(max(grad @ self.covariance[:2, :2] @ grad, 0.0)))

    @property
    def amplitude(self) -> float:
        """Oscillation amplitude ``hypot(A, B)`` at the first sample [signal units]."""
        return math.hypot(self.A, self.B)

    @property
    def amplitude_se(self) -> float:
        """Standard error of :attr:`amplitude`."""
        amp = self.amplitude
        if amp == 0:
            return math.inf
        grad = np.array([self.A / amp, self.B / amp])
        return float(math.sqrt(max(grad @ self.covariance[3:5, 3:5] @ grad, 0.0)))

    @property
    def eigenvalue(self) -> complex:
        """The eigenvalue ``-sigma + i omega_d`` [1/s]."""
        return complex(-self.sigma, self.omega_d)

    def evaluate(self, time) -> np.ndarray:
        """The fitted model at ``time`` [s]."""
        return _model(self._vector(), np.asarray(time, dtype=float) - self.t0, self.drift is not None)

    def _vector(self) -> np.ndarray:
        values = [self.omega_d, self.sigma, self.offset, self.A, self.B]
        if self.drift is not None:
            values.append(self.drift)
        return np.array(values)

    def as_dict(self) -> dict[str, float | None]:
        """Plain numbers, for JSON output."""
        return {
            "period": self.period,
            "period_se": self.period_se,
            "omega_d": self.omega_d,
            "omega_d_se": self.omega_d_se,
            "decay_rate": self.sigma,  # the model's sigma; "sigma" in bikerider's JSON is an uncertainty
            "decay_rate_se": self.sigma_se,
            "zeta": self.zeta,
            "zeta_se": self.zeta_se,
            "amplitude": self.amplitude,
            "amplitude_se": self.amplitude_se,
            "offset": self.offset,
            "drift": self.drift,
            "residual_rms": self.residual_rms,
            "n_samples": self.n_samples,
        }


def _model(p: np.ndarray, t: np.ndarray, drift: bool) -> np.ndarray:
    omega, sigma, offset, a, b = p[:5]
    y = offset + np.exp(-sigma * t) * (a * np.sin(omega * t) + b * np.cos(omega * t))
    return y + p[5] * t if drift else y


def _jacobian(p: np.ndarray, t: np.ndarray, drift: bool) -> np.ndarray:
    omega, sigma, _, a, b = p[:5]
    decay = np.exp(-sigma * t)
    s, c = np.sin(omega * t), np.cos(omega * t)
    osc = a * s + b * c
    columns = [
        decay * t * (a * c - b * s),  # d/d omega
        -t * decay * osc,  # d/d sigma
        np.ones_like(t),  # d/d offset
        decay * s,  # d/d A
        decay * c,  # d/d B
    ]
    if drift:
        columns.append(t)
    return np.column_stack(columns)


#: Largest magnitude of a time or signal value the fit accepts (its squares must stay finite).
MAX_MAGNITUDE = 1e100


def _check_samples(time: np.ndarray, signal: np.ndarray) -> None:
    if time.ndim != 1 or signal.ndim != 1 or time.shape != signal.shape:
        raise FitError(
            f"time and signal must be one-dimensional and of equal length (got shapes {time.shape} and {signal.shape})"
        )
    if time.size < MIN_SAMPLES:
        raise FitError(f"too few samples to fit a damped oscillation: {time.size}, need at least {MIN_SAMPLES}")
    if not np.all(np.isfinite(time)):
        raise FitError(f"time has {np.count_nonzero(~np.isfinite(time))} non-finite values")
    if not np.all(np.isfinite(signal)):
        bad = int(np.flatnonzero(~np.isfinite(signal))[0])
        raise FitError(f"signal has non-finite values (first at sample {bad + 1}, t = {time[bad]:g} s)")
    for name, values in (("time", time), ("signal", signal)):
        largest = float(np.abs(values).max())
        if largest > MAX_MAGNITUDE:  # squares in the fit would overflow
            raise FitError(
                f"{name} has values up to {largest:.3g}: too large to fit (at most {MAX_MAGNITUDE:g}; "
                "rescale it or check the column)"
            )
    steps = np.diff(time)
    if np.any(steps <= 0):
        bad = int(np.flatnonzero(steps <= 0)[0])
        raise FitError(
            f"time is not strictly increasing: sample {bad + 2} (t = {time[bad + 1]:g} s) does not "
            f"come after sample {bad + 1} (t = {time[bad]:g} s)"
        )


def _fft_frequency(t: np.ndarray, y: np.ndarray) -> float:
    """Angular frequency of the largest spectral peak (above DC) of the detrended signal."""
    n = t.size
    dt = (t[-1] - t[0]) / (n - 1)
    uniform = np.linspace(t[0], t[-1], n)
    resampled = np.interp(uniform, t, y)
    detrended = resampled - np.polyval(np.polyfit(uniform - uniform[0], resampled, 1), uniform - uniform[0])
    window = np.hanning(n)
    size = 1 << int(math.ceil(math.log2(8 * n)))
    spectrum = np.abs(np.fft.rfft(detrended * window, size))
    freqs = np.fft.rfftfreq(size, dt)
    # skip the DC lobe: the Hann window's main lobe is two bins of the unpadded transform wide
    start = max(1, int(math.ceil(2 * size / n)))
    if start >= spectrum.size - 1:
        return math.nan
    k = start + int(np.argmax(spectrum[start:-1]))
    left, mid, right = spectrum[k - 1], spectrum[k], spectrum[k + 1]
    denominator = left - 2 * mid + right
    shift = 0.5 * (left - right) / denominator if denominator != 0 else 0.0
    return 2 * math.pi * (freqs[k] + shift * (freqs[1] - freqs[0]))


def _decay_guess(t: np.ndarray, y: np.ndarray, omega: float) -> float:
    """Decay rate from a line through the log of the Hilbert envelope (0 when unclear)."""
    centred = y - np.mean(y)
    envelope = np.abs(_analytic(centred))
    # drop a quarter cycle at each end, where the envelope of a finite record is unreliable
    edge = np.searchsorted(t - t[0], 0.25 * 2 * math.pi / omega)
    core = slice(edge, max(edge + 2, t.size - edge))
    tt, env = t[core] - t[0], envelope[core]
    keep = env > 0
    if np.count_nonzero(keep) < 3:
        return 0.0
    slope = np.polyfit(tt[keep], np.log(env[keep]), 1)[0]
    return float(-slope) if math.isfinite(slope) else 0.0


def _analytic(x: np.ndarray) -> np.ndarray:
    """The analytic signal of ``x`` (its Hilbert transform as the imaginary part), computed as
    ``scipy.signal.hilbert`` computes it (the same numbers), without importing ``scipy.signal``: that
    import (``scipy.stats`` with it) takes about half a second, in every worker process that fits records."""
    # here, not at the top: the module loads without SciPy (scipy.fft, not numpy.fft: the transform
    # scipy.signal.hilbert uses)
    from scipy import fft

    n = x.size
    spectrum = fft.fft(x, n)
    if n % 2 == 0:
        spectrum[1 : n // 2] *= 2.0
        spectrum[n // 2 + 1 : n] = 0.0
    else:
        spectrum[1 : (n + 1) // 2] *= 2.0
        spectrum[(n + 1) // 2 : n] = 0.0
    return fft.ifft(spectrum)


def _linear_start(t: np.ndarray, y: np.ndarray, omega: float, sigma: float, drift: bool) -> np.ndarray:
    decay = np.exp(-sigma * t)
    columns = [np.ones_like(t), decay * np.sin(omega * t), decay * np.cos(omega * t)]
    if drift:
        columns.append(t)
    coef, *_ = np.linalg.lstsq(np.column_stack(columns), y, rcond=None)
    start = [omega, sigma, coef[0], coef[1], coef[2]]
    if drift:
        start.append(coef[3])
    return np.array(start)


def fit_damped_oscillation(
    time, signal, *, guess_frequency: float | None = None, drift: bool = False
) -> DampedOscillationFit:
    """Fit ``offset [+ drift t] + exp(-sigma t)(A sin(omega_d t) + B cos(omega_d t))`` to a signal.

    Parameters
    ----------
    time : array_like, shape (n,)
        Sample times [s], strictly increasing (need not be uniform).
    signal : array_like, shape (n,)
        The measured signal (e.g. an angular rate).
    guess_frequency : float, optional
        Initial damped angular frequency [rad/s]; by default the FFT peak.
    drift : bool
        Also fit a linear drift (a slowly wandering rate gyro).

    Returns
    -------
    DampedOscillationFit

    Raises
    ------
    FitError
        See the module docstring.
    """
    from scipy.optimize import least_squares

    t_abs = np.asarray(time, dtype=float)
    y = np.asarray(signal, dtype=float)
    _check_samples(t_abs, y)
    t = t_abs - t_abs[0]
    span = float(t[-1])
    if guess_frequency is not None:
        if not (math.isfinite(guess_frequency) and guess_frequency > 0):
            raise FitError(f"guess_frequency = {guess_frequency!r}: expected a positive angular frequency in rad/s")
        omega0 = float(guess_frequency)
    else:
        omega0 = _fft_frequency(t, y)
        if not math.isfinite(omega0) or omega0 <= 0:
            raise FitError("no oscillation found: the spectrum has no peak above zero frequency")
    cycles = omega0 * span / (2 * math.pi)
    if cycles < MIN_CYCLES:
        raise FitError(
            f"the record ({span:.4g} s) holds {cycles:.2f} cycles at the signal's dominant frequency "
            f"{omega0 / (2 * math.pi):.4g} Hz; need at least {MIN_CYCLES:g} full cycle to fit a period"
        )
    nyquist = math.pi * (t.size - 1) / span
    sigma0 = _decay_guess(t, y, omega0)
    sigma0 = float(np.clip(sigma0, -omega0, omega0))
    start = _linear_start(t, y, omega0, sigma0, drift)
    # bounds keep the frequency positive and below the Nyquist frequency of the mean sampling step
    lower = np.full(start.size, -np.inf)
    upper = np.full(start.size, np.inf)
    lower[0], upper[0] = 1e-9 * omega0, 2 * nyquist
    start[0] = float(np.clip(start[0], lower[0] * 10, upper[0] * 0.99))
    result = least_squares(
        lambda p: _model(p, t, drift) - y,
        start,
        jac=lambda p: _jacobian(p, t, drift),
        bounds=(lower, upper),
        method="trf",
        x_scale="jac",
        max_nfev=2000,
    )
    if not result.success or not np.all(np.isfinite(result.x)):
        raise FitError(f"the damped oscillation fit did not converge ({result.message})")
    p = result.x
    residual = result.fun
    dof = t.size - p.size
    s2 = float(residual @ residual) / dof
    jac = _jacobian(p, t, drift)
    try:
        u, singular, vt = np.linalg.svd(jac, full_matrices=False)
    except np.linalg.LinAlgError:
        raise FitError("the fit's Jacobian could not be decomposed: no standard errors") from None
    if singular[-1] <= singular[0] * 1e-12:
        raise FitError(
            "the fit's parameters are not determined by the data (singular Jacobian): "
            "is there an oscillation in the record?"
        )
    covariance = (vt.T / singular**2) @ vt * s2
    fit = DampedOscillationFit(
        omega_d=float(p[0]),
        sigma=float(p[1]),
        offset=float(p[2]),
        A=float(p[3]),
        B=float(p[4]),
        drift=float(p[5]) if drift else None,
        covariance=covariance,
        residual_rms=float(math.sqrt(np.mean(residual**2))),
        t0=float(t_abs[0]),
        n_samples=int(t.size),
    )
    if not fit.amplitude > MIN_AMPLITUDE_SIGNIFICANCE * fit.amplitude_se:
        raise FitError(
            f"no oscillation found: the fitted amplitude {fit.amplitude:.3g} is not {MIN_AMPLITUDE_SIGNIFICANCE:g} "
            f"times its standard error {fit.amplitude_se:.3g} (noise rms {fit.residual_rms:.3g})"
        )
    if fit.omega_d * span / (2 * math.pi) < MIN_CYCLES:
        raise FitError(f"the fitted period {fit.period:.4g} s is longer than the record ({span:.4g} s)")
    return fit


@dataclass(frozen=True)
class PeriodEstimate:
    """The period of repeated trials.

    Attributes
    ----------
    period : float
        Mean of the trials' periods [s].
    sigma : float
        Standard uncertainty of the mean: ``sqrt(mean(se_i^2) / n + s^2 / n)``, the fits' own
        standard errors and the scatter between trials (``s``, sample standard deviation; 0 for
        one trial) combined.
    periods, standard_errors : tuple of float
        Each trial's period and its standard error.
    """

    period: float
    sigma: float
    periods: tuple[float, ...]
    standard_errors: tuple[float, ...]

    @property
    def n_trials(self) -> int:
        return len(self.periods)

    @property
    def scatter(self) -> float:
        """Sample standard deviation of the trials' periods (0 for one trial) [s]."""
        n = len(self.periods)
        if n < 2:
            return 0.0
        mean = self.period
        return math.sqrt(sum((p - mean) ** 2 for p in self.periods) / (n - 1))


def period_from_trials(fits: Sequence[DampedOscillationFit], names: Sequence[str] | None = None) -> PeriodEstimate:
    """Combine the periods of repeated trials (see :class:`PeriodEstimate` for the uncertainty).

    Raises
    ------
    FitError
        No trials, or a trial more than :data:`bikerider.fitting.PERIOD_TRIAL_TOLERANCE` (relative)
        from the median period: it is another oscillation, not a repeat (named in the message).
    """
    if not fits:
        raise FitError("no trials to combine")
    periods = [f.period for f in fits]
    errors = [f.period_se for f in fits]
    median = float(np.median(periods))
    labels = list(names) if names is not None else [f"trial {i + 1}" for i in range(len(fits))]
    for label, period in zip(labels, periods):
        if abs(period - median) > PERIOD_TRIAL_TOLERANCE * median:
            shown = ", ".join(f"{p:.6g}" for p in periods)
            raise FitError(
                f"{label}: period {period:.6g} s is {abs(period - median) / median:.1%} from the trials' median "
                f"{median:.6g} s (periods {shown} s); repeats must agree within {PERIOD_TRIAL_TOLERANCE:.0%} -- "
                "is it a trial of another orientation or body?"
            )
    n = len(periods)
    mean = math.fsum(periods) / n
    scatter2 = math.fsum((p - mean) ** 2 for p in periods) / (n - 1) if n > 1 else 0.0
    sigma = math.sqrt(math.fsum(e**2 for e in errors) / n**2 + scatter2 / n)
    return PeriodEstimate(mean, sigma, tuple(periods), tuple(errors))
