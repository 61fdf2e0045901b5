"""Steer-torque multisine runs simulated by a truth independent of the candidates' code.

The truth is the Whipple bicycle typed in from Meijaard et al. (2007) Appendix A
(:func:`validation.cases.meijaard_matrices`, not the generated models the candidates use) with a
viscous steer damper and Coulomb steer friction (``tanh(deltad / 0.02)``), under a control law
``T = k_phi phi + k_phid phid + k_delta delta + k_deltad deltad``, driven by a Schroeder-phased steer
torque multisine ``a sum_k cos(2 pi f_k t + phi_k)``, integrated in time by
:func:`scipy.integrate.solve_ivp` (RK45, tight tolerances) from rest ``lead`` seconds before the record
starts, so that the record is the periodic steady state.  The samples are taken at the logger's
instants (optionally jittered, dropped, with missing cells), with white noise on each signal.

:func:`multisine_log` gives the columns of one run; :func:`write_log` writes them as a log the
diagnosis reads (``bikerider.io.multisine``).  ``docs/scripts/gap_multisine_example.py`` and the tests
use them.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from validation.cases import meijaard_matrices

NOISE = {"roll_rate": 0.01, "steer_angle": 0.002, "steer_rate": 0.02, "roll_angle": 0.002}
"""White noise of each logged signal (rad/s, rad), as a MEMS gyro and an encoder give."""


def schroeder_phases(n: int) -> np.ndarray:
    """Schroeder's low-crest-factor phases ``-pi k (k - 1) / n``."""
    k = np.arange(1, n + 1)
    return -math.pi * k * (k - 1) / n


def multisine_log(
    values: dict[str, float],
    speed: float,
    gains,
    lines,
    peak: float,
    run_time: float,
    *,
    c_steer: float = 0.0,
    coulomb: float = 0.0,
    sample_rate: float = 100.0,
    lead: float = 20.0,
    rng: np.random.Generator | None = None,
    noise: dict[str, float] | None = None,
    jitter: float = 0.0,
    with_roll_angle: bool = False,
    corner: float = 0.02,
) -> dict[str, np.ndarray]:
    """One run's log columns: ``time, steer_torque, roll_rate, steer_angle, steer_rate, speed`` (and
    ``roll_angle`` with ``with_roll_angle``).

    Parameters
    ----------
    values : dict
        Benchmark parameters (Meijaard et al. 2007 names) and ``g``.
    gains : array_like
        ``[k_phi, k_phid, k_delta, k_deltad]`` of the control law at this speed.
    lines : array_like
        The multisine's frequencies [Hz] (multiples of ``1 / run_time``).
    peak : float
        The torque's peak over a period [N m].
    jitter : float
        Standard deviation of the time stamps' error, as a fraction of a step.
    corner : float
        The friction's ``tanh(deltad / corner)`` [rad/s] (0.02: sharper than the candidate's 0.05).
    """
    rng = rng if rng is not None else np.random.default_rng(0)
    noise = NOISE if noise is None else noise
    M, C1, K0, K2 = meijaard_matrices(values)
    g = values["g"]
    K = g * K0 + speed**2 * K2
    C = speed * C1
    Minv = np.linalg.inv(M)
    k_phi, k_phid, k_delta, k_deltad = np.asarray(gains, float)
    lines = np.asarray(lines, float)
    phases = schroeder_phases(lines.size)
    w = 2 * math.pi * lines
    t_fine = np.linspace(0.0, run_time, 20000, endpoint=False)
    shape = np.cos(w[None, :] * t_fine[:, None] + phases).sum(axis=1)
    a = peak / float(np.max(np.abs(shape)))

    def torque(t):
        return a * np.sum(np.cos(w * t + phases))

    def rhs(t, x):
        phi, delta, phid, deltad = x
        steer = (
            torque(t)
            + k_phi * phi
            + k_phid * phid
            + k_delta * delta
            + k_deltad * deltad
            - c_steer * deltad
            - coulomb * math.tanh(deltad / corner)
        )
        q, qd = x[:2], x[2:]
        qdd = Minv @ (np.array([0.0, steer]) - C @ qd - K @ q)
        return np.concatenate([qd, qdd])

    n = int(round(run_time * sample_rate))
    stamps = np.arange(n) / sample_rate
    instants = stamps + jitter / sample_rate * rng.standard_normal(n) if jitter else stamps
    instants = np.clip(instants, 0.0, None)
    sol = solve_ivp(
        rhs,
        (-lead, float(instants.max()) + 1e-9),
        np.zeros(4),
        t_eval=np.sort(instants),
        rtol=1e-8,
        atol=1e-10,
        max_step=0.5 / max(float(lines.max()), 1.0) / 8,
    )
    if not sol.success:
        raise RuntimeError(f"the truth's simulation failed: {sol.message}")
    order = np.argsort(np.argsort(instants))
    x = sol.y[:, order]
    out = {
        "time": instants,
        "steer_torque": np.array([torque(t) for t in instants]),
        "roll_rate": x[2] + noise.get("roll_rate", 0.0) * rng.standard_normal(n),
        "steer_angle": x[1] + noise.get("steer_angle", 0.0) * rng.standard_normal(n),
        "steer_rate": x[3] + noise.get("steer_rate", 0.0) * rng.standard_normal(n),
        "speed": speed + 0.02 * rng.standard_normal(n),
    }
    if with_roll_angle:
        out["roll_angle"] = x[0] + noise.get("roll_angle", 0.0) * rng.standard_normal(n)
    return out


def write_log(path: str | Path, columns: dict[str, np.ndarray], digits: int = 6) -> None:
    """Write log columns as a comma-separated log with a header line (empty cells where NaN)."""
    names = list(columns)
    rows = [",".join(names)]
    data = np.column_stack([np.asarray(columns[k], float) for k in names])
    for row in data:
        rows.append(",".join("" if not math.isfinite(x) else f"{x:.{digits}g}" for x in row))
    Path(path).write_text("\n".join(rows) + "\n")


def damage(columns: dict[str, np.ndarray], rng: np.random.Generator, *, jitter=0.05, drop=0.05, gap=("roll_rate", 3)):
    """A copy of a run's log as a careless logger writes it: stamps jittered by ``jitter`` of a step,
    a fraction ``drop`` of the rows dropped, and ``gap[1]`` consecutive missing cells of ``gap[0]``."""
    out = {k: np.array(v, float) for k, v in columns.items()}
    t = out["time"]
    step = float(np.median(np.diff(t)))
    out["time"] = t + jitter * step * rng.uniform(-1, 1, t.size)
    keep = rng.random(t.size) >= drop
    out = {k: v[keep] for k, v in out.items()}
    name, length = gap
    at = int(rng.integers(10, out[name].size - length - 10))
    out[name][at : at + length] = np.nan
    return out


def decay_log(
    values: dict[str, float],
    speed: float,
    gains,
    duration: float,
    *,
    kick: float = 0.5,
    c_steer: float = 0.0,
    sample_rate: float = 100.0,
    rng: np.random.Generator | None = None,
    noise: dict[str, float] | None = None,
) -> dict[str, np.ndarray]:
    """A free decay after a roll-rate kick ``kick`` [rad/s] by the same truth (no torque): the columns
    ``time, steer_torque (0), roll_rate, steer_angle, steer_rate, speed``."""
    rng = rng if rng is not None else np.random.default_rng(0)
    noise = NOISE if noise is None else noise
    M, C1, K0, K2 = meijaard_matrices(values)
    K = values["g"] * K0 + speed**2 * K2
    C = speed * C1
    Minv = np.linalg.inv(M)
    k = np.asarray(gains, float)

    def rhs(t, x):
        steer = k @ np.array([x[0], x[2], x[1], x[3]]) - c_steer * x[3]
        return np.concatenate([x[2:], Minv @ (np.array([0.0, steer]) - C @ x[2:] - K @ x[:2])])

    n = int(round(duration * sample_rate))
    t = np.arange(n) / sample_rate
    sol = solve_ivp(rhs, (0.0, float(t[-1]) + 1e-9), np.array([0.0, 0.0, kick, 0.0]), t_eval=t, rtol=1e-8, atol=1e-10)
    return {
        "time": t,
        "steer_torque": np.zeros(n),
        "roll_rate": sol.y[2] + noise.get("roll_rate", 0.0) * rng.standard_normal(n),
        "steer_angle": sol.y[1] + noise.get("steer_angle", 0.0) * rng.standard_normal(n),
        "steer_rate": sol.y[3] + noise.get("steer_rate", 0.0) * rng.standard_normal(n),
        "speed": speed + 0.02 * rng.standard_normal(n),
    }
