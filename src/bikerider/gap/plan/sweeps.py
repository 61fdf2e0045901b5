"""Steer-torque frequency responses as experiments of the next-experiment plan.

Experiment.  At one speed under one control law (as for decays), the steer is driven by a multisine
torque ``T(t) = a sum_k cos(w_k t + phi_k)`` of :data:`N_LINES` lines with Schroeder phases, scaled so
that its peak is the planned torque; after the transient has settled, ``run_time`` seconds (a whole
number of the multisine's periods) of the response are recorded at the sampling rate ``fs`` and the
frequency response ``H(w_k)`` from steer torque to the roll rate (or the steer angle) is read at each
line by the discrete Fourier transform.  The roll rate is what every lab logs with a gyro and what the
whole bicycle, weave and all, shapes; the steer angle is the steer's own response, which steer
inertia, damping and friction act on first.  Both are offered; the plan ranks them.

Lines.  Log-spaced from a quarter to four times the nominal model's weave frequency at that speed and
law (two octaves either side), rounded to multiples of ``1 / run_time`` (distinct, at least one): the
rivals part at the weave resonance (damping sets its height and width) and on its flanks (stiffness
below it, inertia above it).

Prediction.  A linear rival's closed loop ``x' = A x + b T`` (``A`` from
:meth:`~bikerider.gap.candidates.effect_model.EffectModel.state_space` and ``closed_loop`` with the law's gains, ``b``
its steer-torque column) predicts ``H(w) = c (i w I - A)^-1 b``.  A rival with steer Coulomb friction
``T_c sign(delta')`` is not linear: its runs are simulated in time from the friction-free loop's periodic
response over one settling period and the recorded one, and read by the DFT as a record is
(:func:`simulated_response`); the same runs give its largest lean.  A describing function (the friction as
the viscous damping of the same dissipation, Booton 1954) was used here before: where the torque cannot
move the steer it locks the steer, and a locked steer makes the bicycle fall as an inverted pendulum
(SBW's loop at 0.25 N m grows as ``e^(3.7 t)``), so every SBW multisine was left out as leaning too far,
where 54 of the 68 simulated runs stay within :data:`MAX_ROLL` (median 0.04 rad).  The friction-free loop judges whether a friction rival's
run has a steady state (friction only takes energy out of the steer).

Noise per run.  Output samples ``y_n = sum_k Re(H_k a e^(i (w_k t_n + phi_k))) + e_n``, ``e_n`` white
of standard deviation ``sigma_y`` (the signal's sample noise of the plan), ``N = fs run_time`` samples,
the torque known: the DFT estimate ``H_k = (2 / N) sum_n y_n e^(-i w_k t_n) / (a e^(i phi_k))`` has
independent real and imaginary errors of variance ``2 sigma_y^2 / (N a^2)`` at each line, independent
between lines (orthogonal bins of white noise).  A run's speed scatters as the data's did (the
records' speed uncertainty): ``J_v J_v^T sigma_v^2`` with ``J_v`` the nominal response's slope in
speed, also per run.  The bicycle itself varies from run to run as the data's weave eigenvalue did
(:func:`weave_shift`: the response's slopes in the weave eigenvalue times the data's run-to-run
variance), and a real run departs from any linear response at each line by a share ``rho`` of it
(variance ``(rho |H_k|)^2 / 2`` on each part; ``rho`` from the records' fits, ``sqrt(1 - r^2)``):
neither shrinks with a larger torque (:meth:`bikerider.gap.plan.ranking._Planner._predict_sweeps`).

What a run records (:data:`RECORD`), so that it can be read back as the plan reads it: time-stamped samples
of the steer torque actually applied and of the response at the plan's sampling rate or faster, over
the settling period and the recorded one; the speed; the control law and its gains; and the multisine
(lines, phases, peak), so that ``H(w_k)`` is the response's DFT line over the applied torque's.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from bikerider.benchmark.simulation import discretise
from bikerider.gap.inference.timedomain import SMOOTHING

N_LINES = 9
"""Lines of the multisine."""
LINE_SPAN = (0.25, 4.0)
"""The lines span these factors times the nominal weave frequency."""
DEFAULT_TORQUE = 0.5
"""Peak steer torque of a planned multisine [N m]."""
MAX_TORQUE = 50.0
MIN_TORQUE = 1e-3
"""Smallest peak torque planned [N m]: a thousandth of a newton metre is below any steer actuator's
resolution, and much smaller torques make the predicted responses underflow."""
DEFAULT_RUN_TIME = 10.0
"""Recorded steady-state length of one run [s]."""
RUN_TIME_RANGE = (2.0, 600.0)
DEFAULT_SAMPLE_RATE = 100.0
"""Sampling rate [Hz] assumed without records."""
FRF_SIGNALS = {"roll_rate": "frf_roll_rate", "steer_angle": "frf_steer_angle"}
"""Output signal measured to the name the plan's rows carry."""
SIMULATION_STEP = 2e-3
"""Longest step [s] of a multisine run simulated with friction (shorter where the friction's slope at zero
steer rate would make its explicit term stiff)."""
STICK_STEP = 1e-3
"""Longest step [s] of a run simulated with stick-slip friction."""
STICK_RATE = 1e-3
"""Steer rate [rad/s] below which the stick-slip rule may hold the steer still."""
MAX_ROLL = 0.2
"""Largest lean [rad] a planned multisine run may reach under any rival (:func:`peak_roll`, about 11 degrees):
the linear models hold there (``sin phi`` within 0.7 % of ``phi``), with room below a fall (a closed-loop
check's truth fell at 0.5 rad) for the rivals' error, friction and a motor's torque limit.  A run predicted to
lean further is likely lost and is left out of the plan."""
SETTLE_RANGE = (5.0, 60.0)
"""Shortest and longest settling time [s] of a planned run before its recorded period (:func:`settle_time`).  A run
settles until every rival's transient has died (the plan takes the longest over the nominal loop and every
rival's), not only the nominal model's: a rival with a heavily damped steer has a slow real mode, and a truth
like it read after the nominal model's 11 s still carries its transient (a loop check's seed 7206: chi^2 96
on 18 degrees of freedom against 1.5 after 37 s).  The longest, 60 s, bounds a run a lab would still make."""
SETTLE_PERIODS = 1
"""Periods of the multisine a simulated run settles for before the one read."""
RECORD = (
    "per run: time-stamped samples (at the plan's sampling rate or faster) of the steer torque actually applied "
    "(torque sensor, or motor current times its torque constant) and of the response (roll rate from a gyro, or "
    "steer angle from the encoder; both where logged), over one settling period and the recorded run; the "
    "speed (and its scatter); the control law and its gains; the multisine's lines [Hz], phases and peak torque. "
    "The frequency response at each line is the response's DFT over the applied torque's, on the recorded period"
)
"""What a researcher records of each planned multisine run (the plan's JSON says it under ``sweeps.record``)."""


@dataclass(frozen=True)
class Sweep:
    """One kind of steer-torque run: its frequency response from steer torque to ``output``.

    Attributes
    ----------
    speed : float
        [m/s]
    law : str
    output : str
        ``roll_rate`` or ``steer_angle``.
    torque : float
        Peak torque of the multisine [N m].
    run_time : float
        Recorded length of one run [s].
    lines : tuple of float
        The multisine's frequencies [Hz].
    """

    speed: float
    law: str
    output: str
    torque: float
    run_time: float
    lines: tuple[float, ...]

    kind = "sweep"
    push = None

    @property
    def signal(self) -> str:
        return FRF_SIGNALS[self.output]

    @property
    def omegas(self) -> np.ndarray:
        return 2 * math.pi * np.asarray(self.lines)

    def describe(self, repeats: int | None = None) -> str:
        what = (
            "steer-torque multisines" if repeats is None else f"{repeats} steer-torque multisine" + "s" * (repeats != 1)
        )
        return (
            f"{what} of {self.torque:g} N m, {self.run_time:g} s, at {self.speed:.2f} m/s under {self.law}, "
            f"{self.output.replace('_', ' ')} response {self.lines[0]:.2g}-{self.lines[-1]:.2g} Hz"
        )


def lines_for(weave_hz: float, run_time: float) -> tuple[float, ...]:
    """:data:`N_LINES` frequencies [Hz] around ``weave_hz`` on the multisine's grid ``1 / run_time``."""
    f0 = 1.0 / run_time
    wanted = weave_hz * np.geomspace(LINE_SPAN[0], LINE_SPAN[1], N_LINES)
    k = np.maximum(np.round(wanted / f0).astype(int), 1)
    for j in range(1, k.size):
        k[j] = max(k[j], k[j - 1] + 1)
    return tuple(float(x) for x in k * f0)


def line_amplitude(lines, peak: float, run_time: float) -> float:
    """Amplitude ``a`` of each line of a Schroeder-phased multisine over ``lines`` [Hz] (multiples of
    ``1 / run_time``) whose peak over its period ``run_time`` is ``peak``."""
    return _line_amplitude(tuple(float(x) for x in np.ravel(lines)), float(peak), float(run_time))


@functools.lru_cache(maxsize=4096)
def _line_amplitude(lines: tuple[float, ...], peak: float, run_time: float) -> float:
    """:func:`line_amplitude`, kept per multisine (a plan asks for the same ones many times)."""
    lines = np.asarray(lines, float)
    K = lines.size
    phases = -math.pi * np.arange(1, K + 1) * np.arange(K) / K
    t = np.linspace(0.0, run_time, 20000, endpoint=False)
    shape = np.cos(2 * math.pi * lines[None, :] * t[:, None] + phases[None, :]).sum(axis=1)
    return peak / float(np.max(np.abs(shape)))


def response(A: np.ndarray, b: np.ndarray, index: int, omegas: np.ndarray) -> np.ndarray:
    """``H(w) = e_index^T (i w I - A)^-1 b`` for ``A (..., n, n)``, ``b (..., n)``, ``omegas (..., K)``: ``(..., K)``."""
    n = A.shape[-1]
    s = 1j * np.asarray(omegas)[..., None, None]
    M = s * np.eye(n) - A[..., None, :, :]
    x = np.linalg.solve(M, np.broadcast_to(b[..., None, :, None], M.shape[:-1] + (1,)).astype(complex))
    return x[..., index, 0]


def weave_shift(A: np.ndarray, b: np.ndarray, index: int, omegas: np.ndarray) -> np.ndarray | None:
    """Slopes ``(2K, 2)`` of the response ``e_index^T (i w I - A)^-1 b`` at ``omegas (K,)`` (real parts,
    then imaginary parts) in the real and imaginary part of the weave eigenvalue, its modal residue held:
    how a run's response moves when the bicycle's weave moves from run to run (``None`` without a weave).

    With ``A = V diag(lambda) V^-1``, ``H(w) = sum_j r_j / (i w - lambda_j)``, ``r_j = (e^T V)_j (V^-1 b)_j``;
    moving the weave pair ``lambda, conj(lambda)`` by ``delta, conj(delta)`` moves ``H`` by
    ``g delta + g' conj(delta)``, ``g = r / (i w - lambda)^2``, ``g'`` the same for the conjugate.
    """
    lam, V = np.linalg.eig(A)
    upper = np.flatnonzero(lam.imag > 1e-9)
    if not upper.size:
        return None
    w = upper[np.argmax(lam.imag[upper])]
    c = np.conj(lam[w])
    pair = np.argmin(np.abs(lam - c))
    r = V[index, :] * np.linalg.solve(V, b.astype(complex))
    s = 1j * np.asarray(omegas)
    g = r[w] / (s - lam[w]) ** 2
    g_conj = r[pair] / (s - lam[pair]) ** 2
    d_real = g + g_conj  # delta = 1
    d_imag = 1j * g - 1j * g_conj  # delta = i
    return np.stack([split(d_real), split(d_imag)], axis=-1)


def settle_time(eigenvalues) -> float:
    """Settling time [s] before a run's recorded period: three time constants of the slowest mode of the closed
    loop with ``eigenvalues`` (its decay rate counted as at least 1e-3 1/s, and at most 10 1/s), from
    :data:`SETTLE_RANGE` ``[0]`` to ``[1]`` seconds (a growing mode gets the longest)."""
    slowest = max(float(np.max(np.real(eigenvalues))), -10.0)
    lo, hi = SETTLE_RANGE
    return min(hi, max(lo, 3.0 / max(-slowest, 1e-3)))


def peak_roll(A: np.ndarray, b: np.ndarray, roll_index: int, sweeps, settle) -> np.ndarray:
    """The largest roll angle ``|phi|`` [rad] of each run, ``(..., s)``: the linear closed loop ``x' = A x + b T``
    (``A (..., s, n, n)``, ``b (..., s, n)``) from rest, driven by each sweep's multisine (Schroeder phases, its
    peak torque) over its settling time ``settle (s,)`` and its recorded period.

    Exact for the linear loop: ``x(t) = x_p(t) - e^(A t) x_p(0)`` with ``x_p`` the periodic response
    (``(i w_k I - A)^-1 b`` at every line), read on a grid of at least ten points per period of the highest
    line.  A mode that grows (a capsize slower than the run) makes the second term grow over the whole run.
    """
    A, b = np.asarray(A, float), np.asarray(b, float)
    batch, n = A.shape[:-2], A.shape[-1]
    s = len(sweeps)
    run_time = float(sweeps[0].run_time)
    top = max(max(x.lines) for x in sweeps)
    steps = int(math.ceil(run_time * 10.0 * top))  # per period
    h = run_time / steps
    settle = np.asarray(settle, float).reshape(s)
    horizon = settle + run_time
    K = len(sweeps[0].lines)
    phases = -math.pi * np.arange(1, K + 1) * np.arange(K) / K
    omegas = np.array([x.omegas for x in sweeps])  # (s, K)
    amplitude = np.array([line_amplitude(x.lines, x.torque, x.run_time) for x in sweeps])
    # the periodic response's lines, complex state amplitudes (..., s, K, n)
    M = 1j * omegas[..., None, None] * np.eye(n) - A[..., None, :, :]
    rhs = np.broadcast_to(b[..., None, :, None], M.shape[:-1] + (1,)).astype(complex)
    X = np.linalg.solve(M, rhs)[..., 0] * (amplitude[:, None] * np.exp(1j * phases))[:, :, None]
    t = np.arange(steps) * h
    periodic = np.einsum("...sk,skt->...st", X[..., roll_index], np.exp(1j * omegas[:, :, None] * t)).real
    start = X.sum(axis=-2).real  # x_p(0), (..., s, n)
    # e^(A t) x_p(0) on the roll angle, by the modes of A: sum_j V_roll,j c_j e^(lambda_j t), c = V^-1 x_p(0)
    lam, V = np.linalg.eig(A)
    c = np.linalg.solve(V, start.astype(complex)[..., None])[..., 0]
    weight = V[..., roll_index, :] * c  # (..., s, n)
    peak = np.zeros(batch)
    total = int(math.ceil(float(horizon.max()) / h)) + 1
    chunk = steps
    with np.errstate(over="ignore", invalid="ignore"):
        for first in range(0, total, chunk):
            j = np.arange(first, min(first + chunk, total))
            free = np.einsum("...sn,...snt->...st", weight, np.exp(lam[..., None] * (j * h))).real
            roll = np.abs(periodic[..., j % steps] - free)
            roll = np.where(j * h <= horizon[:, None], roll, 0.0)
            peak = np.maximum(peak, np.max(roll, axis=-1))
    return peak


def noise_covariance(sweep: Sweep, sigma_y: float, sample_rate: float) -> np.ndarray:
    """Per run ``(2K, 2K)``: the DFT estimate's variance ``2 sigma_y^2 / (N a^2)`` on each real and
    imaginary part (module docstring)."""
    a = line_amplitude(sweep.lines, sweep.torque, sweep.run_time)
    N = sample_rate * sweep.run_time
    return np.eye(2 * len(sweep.lines)) * 2 * sigma_y**2 / (N * a**2)


def run_stand_in(sweep: Sweep, gains: np.ndarray, speed_measured: bool):
    """What :func:`bikerider.gap.inference.timedomain.systems` reads of a record, for a sweep."""
    return SimpleNamespace(speed=sweep.speed, speed_measured=speed_measured, gains=np.asarray(gains, float))


def split(z: np.ndarray) -> np.ndarray:
    """Complex ``(..., K)`` to real ``(..., 2 K)``: real parts, then imaginary parts."""
    z = np.asarray(z)
    return np.concatenate([z.real, z.imag], axis=-1)


def simulated_response(
    A,
    b,
    friction,
    rate_index: int,
    outputs: tuple[int, int],
    sweeps: list[Sweep],
    stick: bool = False,
    roll_index: int | None = None,
):
    """Frequency responses ``(P, s, 2, K)`` (roll rate, steer angle) of runs simulated in time with steer
    Coulomb friction: ``A (P, s, n, n)``, ``b (P, s, n)``, ``friction (P,)``, the ``s`` sweeps alike in
    run time and number of lines (module docstring, "Prediction").  The friction as the diagnosis fits
    it, ``T_c tanh(delta' / eps)``, or with ``stick`` by Karnopp's stick-slip rule (the steer held still
    while the torque that takes is at most ``T_c``).  With ``roll_index`` (the roll angle's state) also
    the largest ``|phi|`` [rad] of each run over the settling period and the recorded one, ``(P, s)``: a
    run that grows (the steer held by friction while the bicycle falls) shows it there."""
    A, b = np.asarray(A, float), np.asarray(b, float)
    P, s, n = A.shape[0], A.shape[1], A.shape[-1]
    friction = np.broadcast_to(np.asarray(friction, float).reshape(-1), (P,))
    run_time = float(sweeps[0].run_time)
    slope = float(np.max(friction)) / SMOOTHING * float(np.max(np.abs(b[..., rate_index])))
    h = min(SIMULATION_STEP, 0.5 / slope) if slope > 0 else SIMULATION_STEP
    if stick:
        h = min(h, STICK_STEP)
    per_period = math.ceil(run_time / h)
    h = run_time / per_period
    Phi, Gamma, _ = discretise(A, b[..., None], h, hold="zoh")  # the one zero-order hold
    phi = np.ascontiguousarray(np.moveaxis(Phi.reshape(P * s, n, n), 0, -1))  # (n, n, P s)
    gamma = np.ascontiguousarray(Gamma[..., 0].reshape(P * s, n).T)  # (n, P s)
    minus_T = -np.repeat(friction, s)
    lines = np.array([x.lines for x in sweeps])  # (s, K)
    omegas = 2 * math.pi * lines
    K = lines.shape[1]
    phases = -math.pi * np.arange(1, K + 1) * np.arange(K) / K
    amplitude = np.array([line_amplitude(x.lines, x.torque, x.run_time) for x in sweeps])
    # from the linear loop's periodic response (a slow mode would take longer than the run to settle)
    start = np.einsum("sk,psk->psk", amplitude[:, None] * np.exp(1j * phases)[None, :], np.ones((P, s, K)))
    steady = np.linalg.solve(
        1j * omegas[None, :, :, None, None] * np.eye(n) - A[:, :, None],
        np.broadcast_to(b[:, :, None, :, None], (P, s, K, n, 1)).astype(complex),
    )[..., 0]
    x = np.ascontiguousarray(np.einsum("psk,pskn->psn", start, steady).real.reshape(P * s, n).T)
    y = np.zeros((2, K, P * s), complex)
    u = np.zeros((K, s), complex)
    rotate = np.exp(-1j * omegas.T * h)  # (K, s)
    rows = list(outputs)
    peak = np.abs(x[roll_index]) if roll_index is not None else None
    for k in range(per_period * (SETTLE_PERIODS + 1)):
        t = k * h
        torque = amplitude * np.cos(omegas * t + phases).sum(axis=1)  # (s,), read at the samples
        # held over the step at its value half-way (the zero-order hold's half-step lag undone)
        drive = np.tile(amplitude * np.cos(omegas * (t + h / 2) + phases).sum(axis=1), P)
        if stick:
            free = np.einsum("ijb,jb->ib", phi, x)
            g, rate = gamma[rate_index], x[rate_index]
            hold = -free[rate_index] / g - drive  # the friction torque that stops the steer within the step
            can = np.abs(hold) <= -minus_T
            slow = np.abs(rate) < STICK_RATE
            moving = np.where(slow, np.sign(free[rate_index] + g * drive), np.sign(rate))
            friction_torque = np.where(slow & can, hold, minus_T * moving)
            turns = ~slow & can & ((free[rate_index] + g * (drive + friction_torque)) * rate < 0)
            friction_torque = np.where(turns, hold, friction_torque)
        else:
            friction_torque = minus_T * np.tanh(x[rate_index] / SMOOTHING)
        drive = drive + friction_torque
        if k >= per_period * SETTLE_PERIODS:
            if k == per_period * SETTLE_PERIODS:
                basis = np.ones((K, s), complex)
            y += x[rows][:, None, :] * np.tile(basis, (1, P))[None]
            u += torque[None, :] * basis
            basis = basis * rotate
        x = np.einsum("ijb,jb->ib", phi, x) + gamma * drive
        if peak is not None:
            peak = np.fmax(peak, np.abs(x[roll_index]))
    H = np.moveaxis((y / np.tile(u, (1, P))[None]).reshape(2, K, P, s), (2, 3), (0, 1))
    if peak is None:
        return H
    return H, np.where(np.all(np.isfinite(x), axis=0), peak, np.inf).reshape(P, s)
