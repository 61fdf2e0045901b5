"""The weave eigenvalue of a perturbation run, from a rate signal.

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
is kept when it converges to a distinct real mode within :data:`EXTRA_MODE_RANGE`, holds a full cycle, shows an oscillation ten
standard errors above zero and (if the plain fit succeeded) lowers the residual sum of squares
significantly (F-test at 1 %); otherwise the plain fit stands.  Standard errors are scaled up by
``sqrt((1 + rho) / (1 - rho))`` with ``rho`` the lag-one autocorrelation of the residuals: a fit
that misses part of the signal leaves correlated residuals, and the white-noise errors would then
be too small (simulated free responses at high speed, where the weave dies within a cycle, showed
frequency errors of 4-12 white-noise standard errors).  When a fast-growing capsize mode
(a fall) swamps the record, the plain fit often fails and the two-mode fit alone finds the weave.  Standard errors are from ``s^2 (J^T J)^-1``.  Records should
start after the perturbation (and after the castor transient, a few tenths of a second).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class WeaveEstimate:
    """A fitted weave eigenvalue.

    Attributes
    ----------
    eigenvalue : complex
        ``-sigma + i omega`` [1/s].
    real_sigma, imag_sigma : float
        Standard errors of its real and imaginary parts [1/s].
    extra_mode : float or None
        The real eigenvalue of the extra exponential when the two-mode refinement was kept.
    residual_rms : float
    """

    eigenvalue: complex
    real_sigma: float
    imag_sigma: float
    extra_mode: float | None
    residual_rms: float


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
outside it the exponential merely fits the noise at one end of the record."""
PLAIN_START_MODES = (-1.5, -0.3, 0.3)
"""Extra-mode eigenvalues tried when the two-mode fit starts from the plain fit [1/s]."""
MIN_AMPLITUDE_SIGNIFICANCE = 10.0
"""A two-mode fit found without a plain fit must show an oscillation this many standard errors
above zero (the rule of :mod:`bikerider.fitting.damped_oscillation`)."""


def _scan_start(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Start ``[omega, sigma, A, B, offset, C, lambda_c]`` of the two-mode fit from a grid scan.

    For each (frequency, decay, extra-mode) grid point the model is linear in its amplitudes; the
    point with the smallest residual is the start.  Unlike the FFT peak this is not taken in by
    the slow capsize mode's leakage.  The normal equations are assembled from products of the
    three one-dimensional families of basis functions.
    """
    tau = t - t[0]
    decay = np.exp(-SCAN_DECAYS[:, None] * tau)  # (D, n)
    sin, cos = np.sin(SCAN_OMEGAS[:, None] * tau), np.cos(SCAN_OMEGAS[:, None] * tau)  # (W, n)
    extra = np.exp(np.asarray(SCAN_MODES)[:, None] * tau)  # (L, n)
    osc_s = decay[None, :, :] * sin[:, None, :]  # (W, D, n)
    osc_c = decay[None, :, :] * cos[:, None, :]
    W, D, L, n = SCAN_OMEGAS.size, SCAN_DECAYS.size, len(SCAN_MODES), tau.size
    basis = np.empty((W, D, L, 4, n))
    basis[..., 0, :] = osc_s[:, :, None, :]
    basis[..., 1, :] = osc_c[:, :, None, :]
    basis[..., 2, :] = 1.0
    basis[..., 3, :] = extra[None, None, :, :]
    basis = basis.reshape(-1, 4, n)
    gram = basis @ np.swapaxes(basis, 1, 2) + 1e-9 * np.eye(4)
    rhs = basis @ y
    coef = np.linalg.solve(gram, rhs[..., None])[..., 0]
    rss = y @ y - np.einsum("gk,gk->g", coef, rhs)  # residual of the least-squares solution
    k = int(np.argmin(rss))
    w, d, l_ = np.unravel_index(k, (W, D, L))
    a, b, offset, c = coef[k]
    return np.array([SCAN_OMEGAS[w], SCAN_DECAYS[d], a, b, offset, c, SCAN_MODES[l_]])


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


def weave_eigenvalue(time, signal) -> WeaveEstimate:
    """Fit the weave eigenvalue to a rate signal (see the module docstring).

    Trial parameters of the fits may overflow ``exp`` on the way; such steps are rejected by the
    optimisers, so floating-point warnings are silenced here rather than shown to the user.

    Raises
    ------
    bikerider.errors.FitError
        When neither fit finds an oscillation (the message is the plain fit's reason).
    """
    with np.errstate(all="ignore"):
        return _weave_eigenvalue(time, signal)


def _weave_eigenvalue(time, signal) -> WeaveEstimate:
    from scipy.optimize import least_squares
    from scipy.stats import f as f_dist

    from bikerider.errors import FitError
    from bikerider.fitting.damped_oscillation import fit_damped_oscillation

    t = np.asarray(time, dtype=float)
    y = np.asarray(signal, dtype=float)
    usable = t.size >= 20 and np.all(np.isfinite(t)) and np.all(np.isfinite(y)) and np.all(np.diff(t) > 0)
    start = _scan_start(t, y) if usable else None
    base, refusal = None, None
    try:
        base = fit_damped_oscillation(t, y, drift=True, guess_frequency=None if start is None else float(start[0]))
    except FitError as exc:
        refusal = exc
        try:
            base = fit_damped_oscillation(t, y, drift=True)
        except FitError:
            pass
    if start is None:
        if base is None:
            raise refusal  # type: ignore[misc]
        k = _correlation_inflation(base.evaluate(t) - y)
        return WeaveEstimate(base.eigenvalue, k * base.sigma_se, k * base.omega_d_se, None, base.residual_rms)
    tau = t - t[0]
    n = t.size
    starts = [start]
    if base is not None:
        starts += [
            np.array([base.omega_d, base.sigma, base.A, base.B, base.offset, 0.0, lam0]) for lam0 in PLAIN_START_MODES
        ]
    best = None
    for p0 in starts:
        try:
            with np.errstate(all="ignore"):
                res = least_squares(
                    lambda p: _two_mode(p, tau) - y,
                    p0,
                    jac=lambda p: _two_mode_jacobian(p, tau),
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
        plain = WeaveEstimate(base.eigenvalue, k * base.sigma_se, k * base.omega_d_se, None, base.residual_rms)
    two = _accept_two_mode(best, n, tau)
    if two is None:
        if plain is None:
            raise refusal  # type: ignore[misc]
        return plain
    estimate, rss = two
    if plain is None:
        return estimate
    rss_base = base.residual_rms**2 * n
    dof = n - 7
    if rss >= rss_base or f_dist.sf((rss_base - rss) / (rss / dof), 1, dof) >= 0.01:
        return plain
    return estimate


def _accept_two_mode(res, n: int, tau: np.ndarray):
    """The two-mode estimate and its residual sum of squares, or ``None`` if it is not a weave."""
    if res is None or n <= 7:
        return None
    omega, sigma, a, b, _, c, lam = res.x
    rss = 2 * res.cost
    if not (omega > 0 and abs(lam + sigma) > 0.05 * max(abs(sigma), 0.1) and c != 0):
        return None
    if not EXTRA_MODE_RANGE[0] < lam < EXTRA_MODE_RANGE[1]:
        return None  # not a capsize mode: an exponential fitted to the record's ends
    if omega * (tau[-1] - tau[0]) < 2 * math.pi:  # less than one cycle in the record
        return None
    s2 = rss / (n - 7)
    try:
        cov = np.linalg.pinv(res.jac.T @ res.jac) * s2
    except np.linalg.LinAlgError:
        return None
    real_sigma, imag_sigma = math.sqrt(max(cov[1, 1], 0.0)), math.sqrt(max(cov[0, 0], 0.0))
    amplitude = math.hypot(a, b)
    if amplitude > 0:
        grad = np.array([a / amplitude, b / amplitude])
        amp_se = math.sqrt(max(grad @ cov[2:4, 2:4] @ grad, 0.0))
    else:
        amp_se = math.inf
    if not (
        amplitude > MIN_AMPLITUDE_SIGNIFICANCE * amp_se
        and real_sigma > 0
        and imag_sigma > 0
        and math.isfinite(real_sigma)
        and math.isfinite(imag_sigma)
    ):
        return None
    k = _correlation_inflation(res.fun)
    return WeaveEstimate(complex(-sigma, omega), k * real_sigma, k * imag_sigma, float(lam), math.sqrt(rss / n)), rss
