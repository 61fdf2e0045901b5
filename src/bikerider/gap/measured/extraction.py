"""The weave eigenvalue of a free decay (a record), from a rate or angle signal.

A bicycle's free response after a perturbation holds every mode: the weave oscillation, the fast
castor decay and the slow capsize drift.  :func:`fit_damped_oscillation` fits one damped
oscillation plus an offset (and a linear drift); when the capsize eigenvalue is not small the
drift is a poor stand-in for ``exp(lambda_c t)`` and the fitted weave eigenvalue is biased by many
of its own standard errors (simulations of the Davis bicycle at 6.5-7.5 m/s: 3-15 sigma).

:func:`weave_eigenvalue` therefore fits, besides :func:`fit_damped_oscillation` (with drift),
one more mode::

    y = offset + exp(-sigma t) (A sin(omega t) + B cos(omega t)) + C exp(lambda_c t)

by Levenberg-Marquardt, started from a least-squares scan over frequency, decay and
``lambda_c`` (the FFT peak can be the slow mode's leakage) and from the plain fit.  The two-mode fit
is kept when it converges to a distinct real mode within :data:`EXTRA_MODE_RANGE` (without a plain fit
to fall back on, a fit whose mode runs outside is refitted with the mode held inside), spans at least
:data:`MIN_CYCLES` of a cycle (below one cycle only when the decay is clear, :data:`CLEAR_DECAY`),
shows an oscillation five standard errors above zero (ten to replace a plain fit that succeeded) and
(if the plain fit succeeded) lowers the residual sum of squares significantly (F-test at 1 %);
otherwise the plain fit stands.  A fit that
explains less than :data:`MIN_R2` of the record is refused.  Standard errors are from
``s^2 (J^T J)^-1``, scaled up by ``sqrt((1 + rho) / (1 - rho))`` with ``rho`` the lag-one
autocorrelation of the residuals: a fit that misses part of the signal leaves correlated
residuals, and the white-noise errors would then be too small (simulated free responses at high
speed, where the weave dies within a cycle, showed frequency errors of 4-12 white-noise standard
errors).  When a fast-growing capsize mode (a fall) swamps the record, the plain fit often fails and
the two-mode fit alone finds the weave.  Records should start after the perturbation.

Every refusal is a :class:`~bikerider.errors.FitError` whose message says why; the records of an
experiment turn it into the record's reason for being left out (:mod:`bikerider.gap.measured.records`).
A model's own response over a record is fitted the same way, batched, by
:mod:`bikerider.gap.inference.indirect` (indirect inference).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from bikerider.errors import FitError
from bikerider.fitting.damped_oscillation import MIN_SAMPLES, fit_damped_oscillation
from bikerider.gap.distributions import f as f_dist


@dataclass(frozen=True)
class WeaveEstimate:
    """A fitted weave eigenvalue and how well the record supports it.

    Attributes
    ----------
    eigenvalue : complex
        ``-sigma + i omega`` [1/s].
    real_sigma, imag_sigma : float
        Standard errors of its real and imaginary parts [1/s].
    extra_mode : float or None
        The real eigenvalue of the extra exponential when the two-mode refinement was kept.
    residual_rms : float
    r2 : float
        Coefficient of determination of the fitted model over the record.
    cycles : float
        Weave cycles the record spans at the fitted frequency.
    kind : str
        ``two-mode`` or ``plain`` (the model that was kept).
    params : tuple of float
        Parameters of the kept model (see :meth:`evaluate`).
    t0 : float
        Time of the first sample [s].
    """

    eigenvalue: complex
    real_sigma: float
    imag_sigma: float
    extra_mode: float | None
    residual_rms: float
    r2: float = math.nan
    cycles: float = math.nan
    kind: str = "two-mode"
    params: tuple[float, ...] = ()
    t0: float = 0.0

    def evaluate(self, time) -> np.ndarray:
        """The fitted curve at ``time`` [s]."""
        tau = np.asarray(time, dtype=float) - self.t0
        p = np.asarray(self.params, dtype=float)
        if self.kind == "two-mode":
            return _two_mode(p, tau)
        omega, sigma, offset, a, b, drift = p
        return offset + drift * tau + np.exp(-sigma * tau) * (a * np.sin(omega * tau) + b * np.cos(omega * tau))


def _two_mode(p: np.ndarray, tau: np.ndarray) -> np.ndarray:
    omega, sigma, a, b, offset, c, lam = p
    return offset + np.exp(-sigma * tau) * (a * np.sin(omega * tau) + b * np.cos(omega * tau)) + c * np.exp(lam * tau)


SCAN_OMEGAS = np.geomspace(1.0, 15.0, 32)
"""Angular frequencies scanned for the starting value [rad/s] (the weave lies in 1-15 rad/s)."""
SCAN_DECAYS = np.linspace(-1.0, 4.0, 8)
"""Decay rates scanned for the starting value [1/s]."""
SCAN_MODES = (-3.0, -1.5, -0.7, -0.3, -0.1, 0.1, 0.3, 0.6, 1.0, 1.5)
"""Real eigenvalues of the extra (capsize) mode scanned for the starting value [1/s]."""
EXTRA_MODE_RANGE = (-6.0, 2.0)
"""Real eigenvalues accepted for the extra mode [1/s]: a bicycle's capsize mode lies well inside;
outside it the exponential merely fits the noise at one end of the record.  A fit whose extra mode
runs outside (and no plain fit to fall back on) is refitted with the mode held inside the range, as
a person would fit the record (and as :mod:`bikerider.gap.inference.indirect` fits every model's response),
rather than left out."""
PLAIN_START_MODES = (-1.5, -0.3, 0.3)
"""Extra-mode eigenvalues tried when the two-mode fit starts from the plain fit [1/s]."""
MIN_AMPLITUDE_SIGNIFICANCE = 5.0
"""A two-mode fit found without a plain fit must show an oscillation this many standard errors
(inflated for correlated residuals) above zero for the record to be used.  Five standard errors is
what a person fitting the record would accept: the chance of such an amplitude from noise alone is
below one in a million, and the other rules (half a cycle, a clear decay below one cycle, r^2 of
0.5) still stand.  (It was ten, which left out an SBW record whose oscillation is plain to the eye
at 9 standard errors.)"""
REFINE_AMPLITUDE_SIGNIFICANCE = 10.0
"""A two-mode fit replaces a plain fit that succeeded only when its oscillation is this many standard
errors above zero (the rule of :mod:`bikerider.fitting.damped_oscillation`): the refinement must be
clearly determined to be preferred."""


_GRID = (SCAN_OMEGAS.size, SCAN_DECAYS.size, len(SCAN_MODES))
"""The scan's grid: frequencies, decays, extra modes (:func:`scan_grid` flattens it in this order)."""
SCAN_CHUNK = 2048
"""Samples per block when :func:`scan_grid` accumulates its normal equations (bounds its memory)."""


def scan_start(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Start ``[omega, sigma, A, B, offset, C, lambda_c]`` of the two-mode fit from a grid scan.

    For each (frequency, decay, extra-mode) grid point the model is linear in its amplitudes; the
    point with the smallest residual is the start.  Unlike the FFT peak this is not taken in by
    the slow capsize mode's leakage (:func:`scan_grid`).
    """
    rss, coef = scan_grid(t, y)
    k = int(np.argmin(rss))
    return _grid_point(k, coef[k])


SCAN_VALLEYS = 4
"""Starts :func:`scan_valleys` gives."""


def scan_valleys(t: np.ndarray, y: np.ndarray) -> list[np.ndarray]:
    """:data:`SCAN_VALLEYS` starts of the two-mode fit in the valleys of its grid scan (grid points as
    :func:`scan_start`'s): the best with a decaying extra mode and the best with a growing one (where the signal
    is no sum of modes, Coulomb friction, the fit can settle with its extra mode either way), then the best of
    the other frequencies where the scan's residual is lower than at both neighbouring ones, the lowest first
    (a signal holding two oscillations has a valley at each); the deepest repeated where there are fewer."""
    rss, coef = scan_grid(t, y)
    shape = _GRID
    modes = np.broadcast_to(np.asarray(SCAN_MODES), shape).ravel()
    picks = [int(np.flatnonzero(side)[np.argmin(rss[side])]) for side in (modes < 0, modes > 0)]
    per = rss.reshape(shape[0], -1)
    best = np.argmin(per, axis=1)
    profile = per[np.arange(shape[0]), best]
    padded = np.concatenate([[np.inf], profile, [np.inf]])
    low = np.flatnonzero((padded[1:-1] < padded[:-2]) & (padded[1:-1] <= padded[2:]))
    taken = {np.unravel_index(k, shape)[0] for k in picks}
    for w in low[np.argsort(profile[low], kind="stable")]:
        if len(picks) == SCAN_VALLEYS:
            break
        if w not in taken:
            picks.append(int(w * per.shape[1] + best[w]))
    picks += [picks[0]] * (SCAN_VALLEYS - len(picks))
    return [_grid_point(k, coef[k]) for k in picks]


def _grid_point(k: int, coef: np.ndarray) -> np.ndarray:
    w, d, l_ = np.unravel_index(k, _GRID)
    a, b, offset, c = coef
    return np.array([SCAN_OMEGAS[w], SCAN_DECAYS[d], a, b, offset, c, SCAN_MODES[l_]])


def scan_grid(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The grid scan of the two-mode model: its residual sum of squares at every (frequency, decay, extra-mode)
    point of :data:`SCAN_OMEGAS`, :data:`SCAN_DECAYS`, :data:`SCAN_MODES` (flattened in that order) and the
    amplitudes ``(A, B, offset, C)`` solved there.

    The normal equations of every grid point are sums over the samples of products of the three
    one-dimensional families of basis functions (oscillation, decay, extra mode); they are accumulated over
    blocks of :data:`SCAN_CHUNK` samples, so the memory stays bounded however long the record (the grid's
    basis functions are never stored for every sample at once).
    """
    W, D, L = _GRID
    modes = np.asarray(SCAN_MODES)
    gram = np.zeros((W, D, L, 4, 4))
    rhs = np.zeros((W, D, L, 4))
    yy = 0.0
    tau_all = t - t[0]
    for lo in range(0, tau_all.size, SCAN_CHUNK):
        tau, yc = tau_all[lo : lo + SCAN_CHUNK], y[lo : lo + SCAN_CHUNK]
        decay = np.exp(-SCAN_DECAYS[:, None] * tau)  # (D, c)
        sin, cos = np.sin(SCAN_OMEGAS[:, None] * tau), np.cos(SCAN_OMEGAS[:, None] * tau)  # (W, c)
        extra = np.exp(modes[:, None] * tau)  # (L, c)
        decay2 = decay**2
        osc_s = sin[:, None, :] * decay[None, :, :]  # (W, D, c)
        osc_c = cos[:, None, :] * decay[None, :, :]
        ss, sc, cc = (sin * sin) @ decay2.T, (sin * cos) @ decay2.T, (cos * cos) @ decay2.T  # (W, D)
        s1, c1 = sin @ decay.T, cos @ decay.T
        se, ce = osc_s @ extra.T, osc_c @ extra.T  # (W, D, L)
        e1, ee = extra.sum(axis=1), np.einsum("lc,lc->l", extra, extra)  # (L,)
        for (i, j), value in {
            (0, 0): ss[:, :, None],
            (0, 1): sc[:, :, None],
            (1, 1): cc[:, :, None],
            (0, 2): s1[:, :, None],
            (1, 2): c1[:, :, None],
            (2, 2): float(tau.size),
            (0, 3): se,
            (1, 3): ce,
            (2, 3): e1,
            (3, 3): ee,
        }.items():
            gram[..., i, j] += value
        rhs[..., 0] += (osc_s @ yc)[:, :, None]
        rhs[..., 1] += (osc_c @ yc)[:, :, None]
        rhs[..., 2] += float(yc.sum())
        rhs[..., 3] += extra @ yc
        yy += float(yc @ yc)
    upper = np.triu_indices(4, 1)
    gram[..., upper[1], upper[0]] = gram[..., upper[0], upper[1]]  # symmetric
    gram = gram.reshape(-1, 4, 4) + 1e-9 * np.eye(4)
    rhs = rhs.reshape(-1, 4)
    coef = np.linalg.solve(gram, rhs[..., None])[..., 0]
    rss = yy - np.einsum("gk,gk->g", coef, rhs)  # residual of the least-squares solution
    return rss, coef


def _correlation_inflation(residual: np.ndarray) -> float:
    """Factor for standard errors when residuals are serially correlated (AR(1) effective samples).

    A model that misses part of the signal leaves correlated residuals; treating them as white
    noise makes the standard errors too small.  With lag-one autocorrelation ``rho > 0`` the
    effective number of samples is ``n (1 - rho) / (1 + rho)``, so the errors grow by
    ``sqrt((1 + rho) / (1 - rho))``.
    """
    r = residual - np.mean(residual)
    denominator = float(r @ r)
    if denominator <= 0 or r.size < 3:
        return 1.0
    rho = float(r[1:] @ r[:-1]) / denominator
    rho = min(max(rho, 0.0), 0.99)
    return math.sqrt((1 + rho) / (1 - rho))


def _two_mode_jacobian(p: np.ndarray, tau: np.ndarray) -> np.ndarray:
    omega, sigma, a, b, _, c, lam = p
    decay = np.exp(-sigma * tau)
    s, co = np.sin(omega * tau), np.cos(omega * tau)
    grow = np.exp(lam * tau)
    return np.column_stack(
        [
            decay * tau * (a * co - b * s),
            -tau * decay * (a * s + b * co),
            decay * s,
            decay * co,
            np.ones_like(tau),
            grow,
            c * tau * grow,
        ]
    )


def _two_mode_problem(tau: np.ndarray, y: np.ndarray):
    """``(residuals, jacobian)`` of the two-mode model against ``y`` for :func:`least_squares`: the same
    values as :func:`_two_mode` ``- y`` and :func:`_two_mode_jacobian`, the exponentials, sine and
    cosine worked out once per parameter vector (the optimiser asks for the Jacobian at the point
    whose residuals it has just evaluated)."""
    last: dict = {}

    def terms(p: np.ndarray) -> tuple:
        key = p.tobytes()
        if last.get("key") != key:
            omega, sigma, lam = p[0], p[1], p[6]
            decay = np.exp(-sigma * tau)
            last["key"], last["terms"] = key, (decay, np.sin(omega * tau), np.cos(omega * tau), np.exp(lam * tau))
        return last["terms"]

    def residuals(p: np.ndarray) -> np.ndarray:
        _, _, a, b, offset, c, _ = p
        decay, s, co, grow = terms(p)
        return offset + decay * (a * s + b * co) + c * grow - y

    def jacobian(p: np.ndarray) -> np.ndarray:
        _, _, a, b, _, c, _ = p
        decay, s, co, grow = terms(p)
        J = np.empty((tau.size, 7))
        J[:, 0] = decay * tau * (a * co - b * s)
        J[:, 1] = -tau * decay * (a * s + b * co)
        J[:, 2] = decay * s
        J[:, 3] = decay * co
        J[:, 4] = 1.0
        J[:, 5] = grow
        J[:, 6] = c * tau * grow
        return J

    return residuals, jacobian


MIN_CYCLES = 0.5
"""Fewest weave cycles a record must span: half a cycle, when the decay is clear (see
:data:`CLEAR_DECAY`); a record of a full cycle or more needs no clear decay."""
CLEAR_DECAY = (5.0, 0.5)
"""A record shorter than one cycle is accepted when its decay rate is this many standard errors
above zero and the oscillation's envelope falls to this fraction (or less) over the record."""
MIN_R2 = 0.5
"""Least coefficient of determination of the fitted model: below it the record is mostly something
else (a disturbance, a second perturbation) and the fit is refused."""


def nyquist_frequency(span, samples):
    """The Nyquist frequency ``pi / dt`` [rad/s] of ``samples`` over ``span`` seconds (``dt`` the mean
    step; infinite without a span), for numbers or arrays: a fitted frequency above it is an alias of a
    slower one, never a weave (the record fit and its indirect-inference refits of a model's response
    both refuse it)."""
    span, samples = np.asarray(span, dtype=float), np.asarray(samples, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(span > 0, np.pi * (samples - 1) / np.where(span > 0, span, 1.0), np.inf)
    return float(out) if out.ndim == 0 else out


def weave_eigenvalue(time, signal, *, min_cycles: float = MIN_CYCLES) -> WeaveEstimate:
    """Fit the weave eigenvalue to a rate (or angle) signal (see the module docstring).

    Trial parameters of the fits may overflow ``exp`` on the way; such steps are rejected by the
    optimisers, so floating-point warnings are silenced here rather than shown to the user.

    Parameters
    ----------
    time, signal : array_like
        The free decay (after the perturbation).
    min_cycles : float
        Fewest cycles accepted when the decay is clear (records of a full cycle or more are
        always accepted if the oscillation is significant).

    Raises
    ------
    bikerider.errors.FitError
        When no damped oscillation can be fitted; the message says why (too few samples, no
        oscillation above the noise, too short a record, a poor fit).
    """
    with np.errstate(all="ignore"):
        return _weave_eigenvalue(time, signal, min_cycles)


def _weave_eigenvalue(time, signal, min_cycles: float) -> WeaveEstimate:
    t = np.asarray(time, dtype=float)
    y = np.asarray(signal, dtype=float)
    if t.shape != y.shape or t.ndim != 1:
        raise FitError(f"time and signal must be one-dimensional and of equal length (shapes {t.shape}, {y.shape})")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        bad = int(np.flatnonzero(~(np.isfinite(t) & np.isfinite(y)))[0])
        raise FitError(f"the record has missing or non-finite values (first at sample {bad + 1})")
    if t.size < MIN_SAMPLES:
        raise FitError(f"too few samples to fit a damped oscillation: {t.size}, need at least {MIN_SAMPLES}")
    if np.any(np.diff(t) <= 0):
        raise FitError("time is not strictly increasing")
    start = scan_start(t, y)
    base, refusal = None, None
    try:
        base = fit_damped_oscillation(t, y, drift=True, guess_frequency=float(start[0]))
    except FitError as exc:
        refusal = exc
        try:
            base = fit_damped_oscillation(t, y, drift=True)
        except FitError:
            pass
    tau = t - t[0]
    n = t.size
    nyquist = nyquist_frequency(float(tau[-1]), n)
    if base is not None and base.omega_d >= nyquist:  # the plain fit's bound lets it reach twice that
        refusal = FitError(
            f"no oscillation found: the fitted frequency {base.omega_d:.3g} rad/s lies above the samples' Nyquist "
            f"frequency {nyquist:.3g} rad/s (an alias, not a weave)"
        )
        base = None
    starts = [start]
    if base is not None:
        starts += [
            np.array([base.omega_d, base.sigma, base.A, base.B, base.offset, 0.0, lam0]) for lam0 in PLAIN_START_MODES
        ]
    total = float(np.sum((y - np.mean(y)) ** 2))
    best = None
    residuals, jacobian = _two_mode_problem(tau, y)
    for p0 in starts:
        try:
            with np.errstate(all="ignore"):
                res = least_squares(
                    residuals,
                    p0,
                    jac=jacobian,
                    method="lm",
                    max_nfev=200,
                )
        except (ValueError, np.linalg.LinAlgError):
            continue
        if np.all(np.isfinite(res.x)) and np.isfinite(res.cost) and (best is None or res.cost < best.cost):
            best = res
    plain = None
    if base is not None:
        k = _correlation_inflation(base.evaluate(t) - y)
        plain = WeaveEstimate(
            base.eigenvalue,
            k * base.sigma_se,
            k * base.omega_d_se,
            None,
            base.residual_rms,
            r2=1 - n * base.residual_rms**2 / total if total > 0 else math.nan,
            cycles=base.omega_d * tau[-1] / (2 * math.pi),
            kind="plain",
            params=(base.omega_d, base.sigma, base.offset, base.A, base.B, base.drift or 0.0),
            t0=float(t[0]),
        )
    significance = MIN_AMPLITUDE_SIGNIFICANCE if plain is None else REFINE_AMPLITUDE_SIGNIFICANCE
    two, why = _accept_two_mode(best, n, tau, total, min_cycles, significance)
    if two is None and plain is None and best is not None and "extra real mode" in (why or ""):
        two, why = _accept_two_mode(_bounded(best.x, tau, y), n, tau, total, min_cycles, significance)
    if two is None:
        if plain is None:
            raise FitError(why or str(refusal))
        return _checked(plain)
    estimate, rss = two
    estimate = WeaveEstimate(
        estimate.eigenvalue,
        estimate.real_sigma,
        estimate.imag_sigma,
        estimate.extra_mode,
        estimate.residual_rms,
        estimate.r2,
        estimate.cycles,
        "two-mode",
        estimate.params,
        float(t[0]),
    )
    if plain is None:
        return _checked(estimate)
    rss_base = base.residual_rms**2 * n
    dof = n - 7
    if rss >= rss_base or f_dist.sf((rss_base - rss) / (rss / dof), 1, dof) >= 0.01:
        return _checked(plain)
    return _checked(estimate)


def _bounded(x0: np.ndarray, tau: np.ndarray, y: np.ndarray):
    """The two-mode fit with its extra mode held inside :data:`EXTRA_MODE_RANGE` (``None`` if it fails)."""
    margin = 1e-6
    lower = np.full(7, -np.inf)
    upper = np.full(7, np.inf)
    lower[6], upper[6] = EXTRA_MODE_RANGE[0] + margin, EXTRA_MODE_RANGE[1] - margin
    start = np.array(x0, dtype=float)
    start[6] = min(max(start[6], lower[6] + margin), upper[6] - margin)
    residuals, jacobian = _two_mode_problem(tau, y)
    try:
        with np.errstate(all="ignore"):
            res = least_squares(
                residuals,
                start,
                jac=jacobian,
                bounds=(lower, upper),
                method="trf",
                max_nfev=200,
            )
    except (ValueError, np.linalg.LinAlgError):
        return None
    return res if np.all(np.isfinite(res.x)) and np.isfinite(res.cost) else None


def _checked(estimate: WeaveEstimate) -> WeaveEstimate:
    if not estimate.r2 >= MIN_R2:
        raise FitError(
            f"poor fit: the damped oscillation explains r^2 = {estimate.r2:.2f} of the record "
            f"(need {MIN_R2:g}); the record holds something else (a disturbance, another perturbation)"
        )
    return estimate


def _accept_two_mode(
    res, n: int, tau: np.ndarray, total: float, min_cycles: float, significance: float = MIN_AMPLITUDE_SIGNIFICANCE
):
    """``((estimate, rss), None)`` or ``(None, reason)`` when the two-mode fit is not a weave."""
    if res is None or n <= 7:
        return None, "no oscillation found: the fit did not converge"
    omega, sigma, a, b, _, c, lam = res.x
    rss = 2 * res.cost
    if not (omega > 0 and abs(lam + sigma) > 0.05 * max(abs(sigma), 0.1) and c != 0):
        return None, "no oscillation found: the fitted modes are not a damped oscillation and a distinct real mode"
    span = float(tau[-1] - tau[0])
    nyquist = nyquist_frequency(span, n)
    if omega >= nyquist:
        return None, (
            f"no oscillation found: the fitted frequency {omega:.3g} rad/s lies above the samples' Nyquist "
            f"frequency {nyquist:.3g} rad/s (an alias, not a weave)"
        )
    if not EXTRA_MODE_RANGE[0] < lam < EXTRA_MODE_RANGE[1]:
        return None, (
            f"no oscillation found: the extra real mode ({lam:.3g} 1/s) lies outside "
            f"{EXTRA_MODE_RANGE[0]:g} to {EXTRA_MODE_RANGE[1]:g} 1/s"
        )
    cycles = omega * span / (2 * math.pi)
    s2 = rss / (n - 7)
    try:
        cov = np.linalg.pinv(res.jac.T @ res.jac) * s2
    except np.linalg.LinAlgError:
        return None, "no oscillation found: the fit's parameters are not determined"
    real_sigma, imag_sigma = math.sqrt(max(cov[1, 1], 0.0)), math.sqrt(max(cov[0, 0], 0.0))
    amplitude = math.hypot(a, b)
    if amplitude > 0:
        grad = np.array([a / amplitude, b / amplitude])
        amp_se = math.sqrt(max(grad @ cov[2:4, 2:4] @ grad, 0.0))
    else:
        amp_se = math.inf
    if not (
        amplitude > significance * amp_se
        and real_sigma > 0
        and imag_sigma > 0
        and math.isfinite(real_sigma)
        and math.isfinite(imag_sigma)
    ):
        return None, (
            f"no oscillation found: the fitted amplitude {amplitude:.3g} is not "
            f"{significance:g} times its standard error {amp_se:.3g}"
        )
    if cycles < min_cycles:
        return None, (
            f"the record ({span:.3g} s) holds {cycles:.2f} cycles of the fitted oscillation; "
            f"need at least {min_cycles:g}"
        )
    if cycles < 1:
        significance, fraction = CLEAR_DECAY
        clear = sigma > significance * real_sigma and math.exp(-sigma * span) <= fraction
        if not clear:
            return None, (
                f"the record ({span:.3g} s) holds {cycles:.2f} cycles and its decay is not clear "
                f"(decay rate {sigma:.3g} +/- {real_sigma:.2g} 1/s, envelope falls to "
                f"{math.exp(-sigma * span):.0%}); a record shorter than a cycle needs a decay rate "
                f"{significance:g} standard errors above zero and an envelope falling to "
                f"{fraction:.0%} or less"
            )
    k = _correlation_inflation(res.fun)
    r2 = 1 - rss / total if total > 0 else math.nan
    estimate = WeaveEstimate(
        complex(-sigma, omega),
        k * real_sigma,
        k * imag_sigma,
        float(lam),
        math.sqrt(rss / n),
        r2=r2,
        cycles=cycles,
        kind="two-mode",
        params=tuple(float(x) for x in res.x),
    )
    return (estimate, rss), None
