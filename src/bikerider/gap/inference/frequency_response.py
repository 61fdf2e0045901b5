"""Every model's prediction of a multisine record's frequency response, like with like.

A multisine record's value at a line ``w`` is the periodic steady-state response of the signal to the
steer torque's line (:mod:`bikerider.gap.measured.multisine`).  For a linear closed loop ``x' = A x
+ b T`` (``A`` from :meth:`~bikerider.gap.candidates.effect_model.EffectModel.state_space` and
``closed_loop`` with the record's gains at the controller's speed, ``b`` the steer-torque column) it
is exactly ``H(w) = e^T (i w I - A)^-1 b`` with ``e`` picking the signal (roll angle, steer angle,
roll rate or steer rate), whatever the model's modes: no extraction bias, no initial state.  A model
whose loop has a growing mode has no steady state; its prediction is still ``H(w)`` (what a
periodic response would be), and the diagnosis leaves out records where the nominal model's loop
grows (:func:`unstable_records`).

A model with steer Coulomb friction is not linear: its prediction is the record's run simulated in
time at the recorded instants and read by the same DFT (:func:`predict_frf_friction`, as the plan
predicts a planned run: :func:`bikerider.gap.plan.sweeps.simulated_response`); the random-input
describing function it replaced is kept for comparison (:func:`predict_frf_describing`).
"""

from __future__ import annotations

import math

import numpy as np

from bikerider.benchmark.simulation import discretise
from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.inference.timedomain import SMOOTHING, systems
from bikerider.gap.measured.multisine import FrequencyResponseData

SIGNAL_STATE = {"roll_angle": 0, "steer_angle": 1, "roll_rate": 2, "steer_rate": 3}
"""Signal name to its place among the state space's outputs ``(phi, delta, phid, deltad)``."""


def predict_frf(model: EffectModel, frf: FrequencyResponseData, speed_scale=None) -> np.ndarray:
    """Predicted real and imaginary parts ``(..., 2 R)`` (each row's real part, then its imaginary part,
    interleaved as the observations are) of the rows of ``frf`` under a (batched) model.

    ``speed_scale`` multiplies the speed the bicycle ran at (one number, or one per row); the gains
    stay those of the controller's reading.
    """
    speeds = frf.speed if speed_scale is None else frf.speed * np.asarray(speed_scale, float)
    ss = model.state_space(np.asarray(speeds, float))
    A = ss.closed_loop(frf.gains)  # (..., R, n, n)
    b = ss.B[..., :, 1]  # (..., R, n)
    n = A.shape[-1]
    M = 1j * frf.omega[:, None, None] * np.eye(n) - A
    x = np.linalg.solve(M, b[..., None].astype(complex))[..., 0]  # (..., R, n)
    index = np.array([ss.output_states[SIGNAL_STATE[s]] for s in frf.signal], int)
    H = np.take_along_axis(x, np.broadcast_to(index[:, None], x.shape[:-1] + (1,)), axis=-1)[..., 0]
    out = np.empty(H.shape[:-1] + (2 * H.shape[-1],))
    out[..., 0::2] = H.real
    out[..., 1::2] = H.imag
    return out


def predict_frf_scaled(values: dict, geometry, config: dict, frf: FrequencyResponseData, scales) -> np.ndarray:
    """Predictions ``(P, 2 R)`` for ``P`` parameter vectors, each with its own speed scale (a ``speed_sensor``
    candidate): the scale multiplies the speed of the rows a sensor read (``frf.speed_sensor``); the gains
    stay those of the controller's reading.  ``values`` and ``config`` hold scalars or ``(P, 1)`` arrays, as
    :meth:`bikerider.gap.inference.problem.GapProblem.configure` gives them; every (vector, row) pair is one
    model of a single flattened call."""
    scales = np.ravel(np.asarray(scales, float))
    P, R = scales.size, len(frf)

    def flat(v):
        return np.repeat(np.broadcast_to(np.asarray(v, float).reshape(-1, 1)[:, :1], (P, 1))[:, 0], R)

    model = EffectModel(
        {k: flat(v) for k, v in values.items()},
        geometry,
        {e: {k: flat(v) for k, v in c.items()} for e, c in config.items()},
    )
    speeds = (np.where(frf.speed_sensor[None, :], scales[:, None], 1.0) * frf.speed[None, :]).ravel()
    ss = model.state_space(speeds)
    A = ss.closed_loop(np.tile(frf.gains, (P, 1)))  # (P R, n, n)
    b = ss.B[..., :, 1]
    n = A.shape[-1]
    M = 1j * np.tile(frf.omega, P)[:, None, None] * np.eye(n) - A
    x = np.linalg.solve(M, b[..., None].astype(complex))[..., 0]  # (P R, n)
    index = np.tile(np.array([ss.output_states[SIGNAL_STATE[s]] for s in frf.signal], int), P)
    H = x[np.arange(P * R), index].reshape(P, R)
    out = np.empty((P, 2 * R))
    out[:, 0::2] = H.real
    out[:, 1::2] = H.imag
    return out


def with_speed_uncertainty(frf: FrequencyResponseData, model: EffectModel) -> np.ndarray:
    """Each row's standard error with the speed's uncertainty added: the nominal response's slope in
    speed (central difference over the speed's own scatter, at least 1 mm/s) times that scatter, the
    larger of its real and imaginary parts, added in quadrature."""
    if not len(frf) or not np.any(frf.speed_sigma > 0):
        return frf.sigma.copy()
    h = np.minimum(np.maximum(frf.speed_sigma, 1e-3), 0.5 * frf.speed)
    up = predict_frf(model, frf, 1 + h / frf.speed)
    down = predict_frf(model, frf, 1 - h / frf.speed)
    slope = (up - down) / 2 / np.repeat(h, 2) * np.repeat(frf.speed_sigma, 2)
    per_row = np.maximum(np.abs(slope[0::2]), np.abs(slope[1::2]))
    return np.sqrt(frf.sigma**2 + per_row**2)


def unstable_records(frf: FrequencyResponseData, model: EffectModel, durations: dict[int, float]) -> set[int]:
    """Records (``frf.record`` values) where the model's closed loop has a mode growing e-fold within the
    record's duration (``durations``: record to seconds), as the plan leaves such runs out: a multisine
    there has no steady response to compare (a slower capsize is taken as held by a rider or a catch)."""
    ss = model.state_space(frf.speed)
    ev = np.linalg.eigvals(ss.closed_loop(frf.gains))
    rate = np.max(ev.real, axis=-1)
    return {int(r) for r, g in zip(frf.record, np.ravel(rate)) if g * max(durations.get(int(r), 1.0), 1e-9) > 1.0}


def multisine_rows(fits: list, model: EffectModel) -> tuple[FrequencyResponseData, dict[int, str]]:
    """The observations of the multisine fits used, and the reason of each fit left out here.

    Rows of records where the nominal model's loop grows e-fold within the run are left out (no steady
    response to compare); the others' standard errors get the speed's uncertainty
    (:func:`with_speed_uncertainty`).
    """
    frf = FrequencyResponseData.of(fits)
    reasons: dict[int, str] = {}
    if not len(frf):
        return frf, reasons
    durations = {k: f.record.duration for k, f in enumerate(fits)}
    for k in sorted(unstable_records(frf, model, durations)):
        reasons[k] = (
            "the model's closed loop has a mode growing e-fold within the run at this speed and law: "
            "no steady response to compare the multisine with"
        )
    keep = np.array([k for k in range(len(frf)) if int(frf.record[k]) not in reasons], int)
    frf = frf.subset(keep)
    if len(frf):
        frf.sigma = with_speed_uncertainty(frf, model)
    return frf, reasons


def predict_frf_friction(frf: FrequencyResponseData, fits: list, nominal: dict, geometry, layout, theta) -> np.ndarray:
    """Predicted real and imaginary parts ``(2 R,)`` of the rows of ``frf`` under a time-domain candidate
    (steer friction, alone or with a linear effect; :class:`bikerider.gap.inference.timedomain.Layout` and
    its values ``theta``), like with like: the candidate's closed loop, friction and all, is simulated
    with the record's own torque (its fit at the lines, :meth:`MultisineFit.torque_at`) from rest
    :data:`LEAD` periods of the lowest line before the record, so that it reaches its periodic steady
    state, and its response at the record's instants is estimated at the lines exactly as the record's
    was (:meth:`MultisineFit.estimate`): the harmonics friction makes and its amplitude dependence are
    in the prediction, not approximated (a describing function missed the SBW-like runs by several
    standard errors)."""
    out = np.full(2 * len(frf), np.nan)
    for k in sorted({int(r) for r in frf.record}):
        rows = np.flatnonzero(frf.record == k)
        f = fits[k]
        A, b, outputs, friction = systems(nominal, geometry, [f.record], layout, np.atleast_2d(theta))
        responses = simulate_torque(A[0, 0], b[0, 0], float(np.ravel(friction)[0]), outputs, f)
        estimates = {name: f.estimate(y) for name, y in responses.items()}
        for j in rows:
            line = int(np.argmin(np.abs(2 * np.pi * f.lines - frf.omega[j])))
            H = estimates[frf.signal[j]][line]
            out[2 * j], out[2 * j + 1] = H.real, H.imag
    return out


LEAD = 3.0
"""Periods of the lowest line simulated before the record (at least 10 s): the transient from rest dies out."""
MAX_STEP = 0.005
"""Longest step of the friction simulation [s]; shorter where friction's slope at zero steer rate is stiff."""


def simulate_torque(A: np.ndarray, b: np.ndarray, friction: float, outputs, fit) -> dict[str, np.ndarray]:
    """The closed loop ``x' = A x + b (T(t) - friction tanh(deltad / eps))`` driven by the record's torque
    ``T`` (:meth:`MultisineFit.torque_at`), from rest, by an exponential integrator (the linear part exact
    over each step, the torque and the friction held); each compared signal at the record's instants
    (linear interpolation between steps of at most :data:`MAX_STEP`)."""
    record = fit.record
    t_rec = np.asarray(record.time, float)
    lead = max(LEAD / float(np.min(fit.lines)), 10.0)
    rate_gain = abs(float(b[outputs[3]]))  # steer acceleration per N m
    stiff = friction / SMOOTHING * rate_gain
    h = min(MAX_STEP, 0.5 / stiff) if stiff > 0 else MAX_STEP
    n = int(np.ceil((lead + t_rec[-1] - t_rec[0]) / h)) + 1
    grid = t_rec[0] - lead + h * np.arange(n)
    m = A.shape[0]
    Phi, gamma, _ = discretise(A, b[:, None], h, hold="zoh")  # the one zero-order hold
    Gamma = gamma[:, 0]
    torque = fit.torque_at(grid + 0.5 * h)  # held over each step at its middle
    x = np.zeros(m)
    states = np.empty((n, m))
    rate = outputs[3]
    for i in range(n):
        states[i] = x
        x = Phi @ x + Gamma * (torque[i] - friction * np.tanh(x[rate] / SMOOTHING))
    return {name: np.interp(t_rec, grid, states[:, outputs[SIGNAL_STATE[name]]]) for name in fit.response}


def predict_frf_describing(
    frf: FrequencyResponseData, fits: list, nominal: dict, geometry, layout, theta
) -> np.ndarray:
    """What :func:`predict_frf_friction` replaced, kept for comparison: the Coulomb friction replaced by its random-input describing function
    (:func:`describing_function_loop`) at the record's torque, the amplitude the root mean square of its
    lines' measured amplitudes; ``(2 R,)`` as :func:`predict_frf`."""
    out = np.full(2 * len(frf), np.nan)
    for k in sorted({int(r) for r in frf.record}):
        f = fits[k]
        A, b, outputs, friction = systems(nominal, geometry, [f.record], layout, np.atleast_2d(theta))
        amplitude = float(np.sqrt(np.mean(np.asarray(f.torque_amplitude, float) ** 2)))
        omegas = 2 * np.pi * np.asarray(f.lines, float)
        loop = describing_function_loop(A[0, 0], b[0, 0], float(np.ravel(friction)[0]), outputs[3], omegas, amplitude)
        for j in np.flatnonzero(frf.record == k):
            H = _response(loop, b[0, 0], outputs[SIGNAL_STATE[frf.signal[j]]], frf.omega[j])
            out[2 * j], out[2 * j + 1] = H.real, H.imag
    return out


def _response(A: np.ndarray, b: np.ndarray, index: int, omega: float) -> complex:
    """``e_index^T (i w I - A)^-1 b`` of one system."""
    return complex(np.linalg.solve(1j * omega * np.eye(A.shape[0]) - A, b.astype(complex))[index])


STICK = 1e4
"""Largest equivalent damping of the friction [N m s/rad] (the steer sticks)."""


def describing_function_loop(
    A: np.ndarray, b: np.ndarray, friction: float, rate: int, omegas: np.ndarray, amplitude: float
) -> np.ndarray:
    """``A - c b e_rate^T`` with Coulomb friction ``friction`` replaced by the viscous damping ``c`` its
    random-input describing function gives (Booton 1954): ``c s = sqrt(2 / pi) friction`` with ``s`` the
    steer rate's standard deviation under the multisine's lines ``omegas`` of ``amplitude`` each,
    ``s^2 = sum_k amplitude^2 |H_rate(w_k)|^2 / 2`` of the loop with ``c`` itself (``c s`` grows with
    ``c``: bisection on ``log c``; :data:`STICK` where the torque cannot move the steer)."""
    if friction <= 0:
        return A
    e = np.zeros(A.shape[0])
    e[rate] = 1.0

    def loop(c):
        return A - c * np.outer(b, e)

    def c_times_sd(c):
        H = np.array([_response(loop(c), b, rate, w) for w in omegas])
        return c * amplitude * float(np.sqrt(np.sum(np.abs(H) ** 2) / 2))

    target = math.sqrt(2 / math.pi) * friction
    lo, hi = -8.0, math.log10(STICK)
    if c_times_sd(10.0**hi) <= target:
        return loop(STICK)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if c_times_sd(10.0**mid) > target else (mid, hi)
    return loop(10.0 ** (0.5 * (lo + hi)))
