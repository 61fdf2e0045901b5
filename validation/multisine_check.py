"""Are the plan's odds for steer-torque multisines honest?  Runs simulated in time against the plan's noise model.

The plan (:mod:`bikerider.gap.plan.sweeps`) predicts a multisine run's frequency response by a linear
closed loop, steer Coulomb friction replaced by its random-input describing function, and states the
noise of a run's response at each line.  Here the same runs are simulated in time, by code of its own:

* the rival's closed loop ``x' = A x + b (T_motor + T_f)`` (its fitted values, the law's gains), held
  constant over steps of :data:`STEP` (exact zero-order-hold transition of the linear part);
* steer Coulomb friction ``T_f`` by Karnopp's stick-slip rule: while the steer rate is below
  :data:`STICK_RATE`, the friction holds the steer still if the torque that takes is at most ``T_c``,
  else it opposes the motion with ``T_c`` (no smoothing, no describing function);
* the motor's torque saturated at ``limit`` (the planned multisine's peak clipped: a motor whose
  torque is short of the plan's), the applied torque the one the frequency response is read against;
* the run started from the linear loop's periodic response (a slow capsize mode would take longer than
  a run to settle), the first :data:`SETTLE` periods left to settle, the next one recorded at the plan's sampling rate,
  and ``H_k`` read at each line by the discrete Fourier transform (output line over applied-torque
  line).

For each planned multisine and each rival as the truth the check reports the *bias* of the truth's
own prediction (the simulated response less the plan's predicted one, in the plan's standard
deviations of the mean of the planned runs: ``b^T S^-1 b``), and the separation the runs achieve
against each other rival: with the truth's response ``H``, the expected log-likelihood ratio of the
plan's two Gaussian predictions is ``((H - mu_B)^T S^-1 (H - mu_B) - (H - mu_A)^T S^-1 (H - mu_A)) / 2``,
``d_achieved^2`` twice that (the plan predicts ``d^2 = (mu_A - mu_B)^T S^-1 (mu_A - mu_B)``), and the
achieved resolution probability ``Phi(d_achieved^2 / (2 d) - ln(19) / d)``.  A linear truth's runs
have no bias (the plan's response is exact); friction's harmonics and the motor's saturation are what
the plan's linear prediction can miss.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm
from scipy.special import ndtr

from bikerider.gap.inference.timedomain import Layout, systems
from bikerider.gap.plan.discrimination import ODDS, distance
from bikerider.gap.plan.sweeps import line_amplitude, run_stand_in, split

STEP = 1e-3
"""Integration step [s] (the transition of the linear part is exact over it; the friction is held)."""
STICK_RATE = 1e-3
"""Steer rate [rad/s] below which Karnopp's rule may stick the steer."""
SETTLE = 1
"""Periods of the multisine left to settle before the recorded one."""


@dataclass
class RunCheck:
    """One planned multisine with one rival as the truth."""

    sweep: str
    truth: str
    limit: float
    bias: float
    """``b^T S^-1 b`` of the truth's own prediction (about 0 when the plan predicts the runs; 2K would be one
    standard deviation per part of every line)."""
    d_planned: dict
    d_achieved: dict
    p_planned: float
    p_achieved: float


def multisine(lines, peak: float, run_time: float, t: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """The plan's Schroeder-phased multisine at times ``t``, its line amplitude and phases."""
    lines = np.asarray(lines, float)
    K = lines.size
    phases = -math.pi * np.arange(1, K + 1) * np.arange(K) / K
    a = line_amplitude(lines, peak, run_time)
    torque = a * np.cos(2 * math.pi * lines[None, :] * t[:, None] + phases[None, :]).sum(axis=1)
    return torque, a, phases


def simulate(A, b, rate: int, friction: float, torque: np.ndarray, start=None) -> np.ndarray:
    """States ``(N, n)`` at the steps of ``torque (N,)`` from ``start`` (default rest; Karnopp friction; each step's
    torque the mean of its ends, held over it)."""
    n = A.shape[0]
    aug = np.zeros((n + 1, n + 1))
    aug[:n, :n], aug[:n, n] = A, b
    E = expm(aug * STEP)
    Phi, Gamma = E[:n, :n], E[:n, n]
    x = np.zeros(n) if start is None else np.asarray(start, float)
    out = np.empty((torque.size, n))
    held = (torque + np.append(torque[1:], torque[-1])) / 2
    for k, T in enumerate(held):
        out[k] = x
        free = Phi @ x
        if friction > 0:
            if abs(x[rate]) < STICK_RATE:
                hold = -free[rate] / Gamma[rate] - T  # the friction torque that keeps the steer still
                Tf = hold if abs(hold) <= friction else -friction * math.copysign(1.0, free[rate] + Gamma[rate] * T)
            else:
                Tf = -friction * math.copysign(1.0, x[rate])
                after = free[rate] + Gamma[rate] * (T + Tf)
                if after * x[rate] < 0:  # the rate would reverse within the step: stop it there if friction can
                    hold = -free[rate] / Gamma[rate] - T
                    if abs(hold) <= friction:
                        Tf = hold
            x = free + Gamma * (T + Tf)
        else:
            x = free + Gamma * T
    return out


def periodic_start(A, b, omegas, a: float, phases) -> np.ndarray:
    """The state at ``t = 0`` of the linear loop's periodic response to the multisine (its slow modes settled)."""
    n = A.shape[0]
    x = np.zeros(n)
    for w, phase in zip(omegas, phases):
        x += (a * np.exp(1j * phase) * np.linalg.solve(1j * w * np.eye(n) - A, b.astype(complex))).real
    return x


def measured_response(plan, sweep, rival, limit: float | None = None) -> np.ndarray:
    """The frequency response ``(K,)`` a run of ``sweep`` reads with ``rival`` as the truth (noise-free)."""
    p = plan.problem
    if rival.nonlinear:  # the linear part and the Coulomb friction of the time-domain candidate
        gains = plan.laws[sweep.law](sweep.speed)
        run = run_stand_in(sweep, gains, plan._speed_measured())
        A, b, outputs, friction = systems(
            p.nominal, p.geometry, [run], Layout.of(rival.effects), rival.fit.values[None]
        )
        A, b, T_c = A[0, 0], b[0, 0], float(np.ravel(friction)[0])
    else:  # a linear rival's closed loop as the plan builds it
        A, b, outputs = plan._sweep_systems(rival.effects, rival.fit.values[None])
        m = plan.sweeps.index(sweep)
        A, b, T_c = A[0, m], b[0, m], 0.0
    fs = plan._sample_rate(sweep.speed)
    every = max(1, round(1.0 / (fs * STEP)))
    t = np.arange(round((SETTLE + 1) * sweep.run_time / STEP)) * STEP
    torque, a, phases = multisine(sweep.lines, sweep.torque, sweep.run_time, t)
    if limit is not None:
        torque = np.clip(torque, -limit, limit)
    states = simulate(A, b, outputs[3], T_c, torque, periodic_start(A, b, sweep.omegas, a, phases))
    start = round(SETTLE * sweep.run_time / STEP)
    index = outputs[2] if sweep.output == "roll_rate" else outputs[1]
    y = states[start::every, index]
    u = torque[start::every]
    tt = t[start::every] - t[start]
    w = sweep.omegas
    basis = np.exp(-1j * w[None, :] * tt[:, None])
    return (y @ basis) / (u @ basis)


def check(plan, items: int = 8, limit_share: float | None = None) -> list[RunCheck]:
    """:class:`RunCheck` of the plan's first ``items`` multisines, every rival as the truth in turn; the motor
    limited to ``limit_share`` of the planned peak (``None``: no limit)."""
    sweeps = [item["experiment"] for item in plan.plan if item["experiment"].kind == "sweep"][:items]
    out = []
    n = plan.repeats
    for sweep in sweeps:
        m = plan.sweeps.index(sweep)
        limit = None if limit_share is None else limit_share * sweep.torque
        noise = plan.sweep_data[m] + plan.sweep_model[m]
        for t, truth in enumerate(plan.rivals):
            H = split(measured_response(plan, sweep, truth, limit))
            own = plan.sweep_own[t, m]
            S = own + truth.misfit * noise + noise / n
            mu_t = split(plan.sweep_mean[t, m])
            bias = H - mu_t
            chi_bias = float(bias @ np.linalg.solve(S, bias))
            planned, achieved, p_plan, p_ach = {}, {}, [], []
            for o, other in enumerate(plan.rivals):
                if o == t:
                    continue
                mu_o = split(plan.sweep_mean[o, m])
                d = float(distance((mu_t - mu_o)[None], own[None], noise[None], truth.misfit, n)[0])
                far = H - mu_o
                d2 = float(far @ np.linalg.solve(S, far)) - chi_bias
                planned[other.name], achieved[other.name] = d, math.copysign(math.sqrt(abs(d2)), d2)
                p_plan.append(_probability(d * d, d))
                p_ach.append(_probability(d2, d))
            out.append(
                RunCheck(
                    sweep.describe(n),
                    truth.name,
                    sweep.torque if limit is None else limit,
                    chi_bias,
                    planned,
                    achieved,
                    min(p_plan),
                    min(p_ach),
                )
            )
    return out


def _probability(d2: float, d: float) -> float:
    """``P(log-likelihood ratio >= ln ODDS)``: mean ``d2 / 2``, standard deviation ``d``."""
    if d <= 0:
        return 0.0
    return float(ndtr(d2 / (2 * d) - math.log(ODDS) / d))
