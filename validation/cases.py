"""Validation of the gap diagnosis with the effect withheld.

"Measured" data are generated from a richer truth with an implementation that shares nothing with
the candidate models but the benchmark parameters' meaning, and the diagnosis runs on them blind
(it sees only the nominal model file and the measured eigenvalues):

* the truth's equations are assembled here by hand: the Whipple matrices from Meijaard et al.
  (2007) Appendix A (``generated.benchmark_model``, not the Lagrangian of the candidates), an upper
  body coupled through hand-derived Newton-Euler terms, arm masses moved from the rear body to the
  handlebar with the parallel-axis theorem, added steer inertia as a change of the front frame's
  inertia tensor; the tyre truth uses the contact kinematics of the tyre model but its own tyre law
  (saturating, ``F = mu N tanh(c_alpha alpha / mu)``) with relaxation in time;
* the effects are nonlinear where nature is: Coulomb steer friction beside viscous, cubic springs,
  the gravity moment of the leaning upper body as ``sin(theta)``, saturating tyres;
* every run is a time-domain simulation (:func:`scipy.integrate.solve_ivp`) of a perturbation
  (random roll-rate and steer-rate kick), with gyro noise on the roll rate and noise on the speed
  reading, and the weave eigenvalue is extracted from the noisy roll rate by
  :func:`bikerider.gap.measured.extraction.weave_eigenvalue`, as from a real run;
* the truth's benchmark parameters differ from the nominal ones by a random draw within their
  stated uncertainty, and the rider's geometry differs from the diagnosis's default (upper body
  45 % of the rider's mass instead of 50 %, hip axis 5 cm lower, grips 8 cm higher and 2 cm wider).

The shrinkage the diagnosis predicts (held-out, on the data it has) is compared with the shrinkage
the selected effects achieve on a fresh data set from the same truth (new kicks, noise, speeds).

The calibration study (:func:`run_trial`, :func:`run_friction_trial`; ``docs/scripts/gap_calibration.py``)
repeats short trials per candidate effect with the sizes drawn over the candidate's prior
(:data:`CALIBRATION_EFFECTS`), gives the diagnosis the noisy runs as records (or, for the comparison, the
eigenvalues fitted from them: :data:`CALIBRATION_METHODS`) and scores identification, the fitted sizes'
95 % intervals and bias.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np

from bikerider.errors import FitError, InputError
from bikerider.gap.candidates.effect_model import BENCH_ARGS
from bikerider.gap.candidates.nominal import GapModelInput
from bikerider.gap.inference.problem import POSITIVE
from bikerider.gap.measured.control import ControlLaw, GainSchedule
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData

LOG = logging.getLogger(__name__)


@dataclass(frozen=True)
class Truth:
    """A hidden truth: which effects, with which values (truth-side names, SI)."""

    name: str
    effects: tuple[str, ...]
    values: dict[str, float]
    description: str


TRUTHS: dict[str, Truth] = {
    t.name: t
    for t in (
        Truth("null", (), {}, "parameter error within the stated uncertainty only"),
        Truth(
            "steer_damping",
            ("steer_damping",),
            {"c_steer": 0.3, "T_coulomb": 0.05},
            "viscous 0.3 N m s/rad and Coulomb 0.05 N m steer friction",
        ),
        Truth(
            "steer_inertia",
            ("steer_inertia",),
            {"I_steer": 0.2},
            "0.2 kg m^2 about the steer axis added to the front frame's inertia tensor",
        ),
        Truth(
            "steer_stiffness",
            ("steer_stiffness",),
            {"k_steer": 6.0, "k3_steer": 20.0},
            "steer spring 6 N m/rad plus 20 N m/rad^3 cubic",
        ),
        Truth(
            "passive_arms",
            ("passive_arms",),
            {"m_arm": 2.5, "k_arm": 4.0, "c_arm": 1.5},
            "2.5 kg of arms at the grips, 4 N m/rad and 1.5 N m s/rad about the steer axis",
        ),
        Truth(
            "rider_lean",
            ("rider_lean",),
            {"k_lean": 128.0, "c_lean": 50.0, "k3_lean": 200.0},
            "upper body leaning on 128 N m/rad (+200 N m/rad^3) and 50 N m s/rad (Moore 2012 values)",
        ),
        Truth(
            "tyre_slip",
            ("tyre_slip",),
            {"c_alpha": 13.0, "c_gamma": 0.8, "sigma_t": 0.2, "t_p": 0.02, "mu": 1.0},
            "tyres 13/rad cornering, 0.8/rad camber, 0.2 m relaxation, 20 mm pneumatic trail, saturating at mu = 1",
        ),
        Truth(
            "steer_damping+tyre_slip",
            ("steer_damping", "tyre_slip"),
            {
                "c_steer": 0.3,
                "T_coulomb": 0.05,
                "c_alpha": 13.0,
                "c_gamma": 0.8,
                "sigma_t": 0.2,
                "t_p": 0.02,
                "mu": 1.0,
            },
            "the steer friction and the tyres above together",
        ),
        Truth(
            "rider_lean+steer_damping",
            ("rider_lean", "steer_damping"),
            {"k_lean": 128.0, "c_lean": 50.0, "k3_lean": 200.0, "c_steer": 0.3, "T_coulomb": 0.05},
            "the leaning upper body and the steer friction above together",
        ),
        Truth(
            "strong_steer_damping",
            ("steer_damping",),
            {"c_steer": 0.5, "T_coulomb": 0.1},
            "viscous 0.5 N m s/rad and Coulomb 0.1 N m steer friction",
        ),
    )
}

TRUTH_GEOMETRY = {"upper_mass_fraction": 0.45, "hip_shift": 0.05, "grip_rise": 0.08, "grip_widen": 0.02}
"""How the truth's rider differs from the diagnosis's default geometry (see the module docstring): one
fixed rider for parts 1-3 and the loop.  The calibration draws a rider per trial instead
(:data:`GEOMETRY_DRAW_LIMIT`)."""
GEOMETRY_DRAW_LIMIT = 2.5
"""The calibration's riders: the default geometry moved by a standard normal draw of each of its stated
sources of uncertainty (``RiderGeometry.uncertainty``, as the benchmark parameters are drawn from theirs),
each draw truncated at this many sigmas so that every rider is possible (the inertia's share moves
30 % a sigma)."""


@dataclass(frozen=True)
class Session:
    """One group of runs: speeds [m/s] and the known control gains."""

    group: str
    speeds: tuple[float, ...]
    gains: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Protocol:
    """How the runs are made and measured."""

    sessions: tuple[Session, ...]
    duration: float = 6.0
    rate: float = 100.0
    start: float = 0.3
    gyro_noise: float = 0.01
    speed_noise: float = 0.03
    speed_jitter: float = 0.1
    push: float = 1.0
    """The kicks' size relative to the usual (a push experiment of the closed loop, :mod:`validation.loop`)."""


CONTROL = (0.0, 5.0, -2.0, -0.5)
"""Known stabilising control of the low-speed session (k_phi, k_phid, k_delta, k_deltad)."""

FULL = Protocol(
    (
        Session("day1", (5.5, 6.2, 6.9, 7.6, 8.3, 9.0)),
        Session("day2", (5.7, 6.4, 7.1, 7.8, 8.5, 9.2)),
        Session("day3-controlled", (4.0, 4.7, 5.4, 6.1, 6.8, 7.5), CONTROL),
    )
)
"""The documented protocol: three sessions of six runs (18 measured weave eigenvalues)."""

QUICK = Protocol(
    (
        Session("day1", (5.5, 6.7, 7.9, 9.0)),
        Session("day2", (5.8, 7.0, 8.2, 9.2)),
        Session("day3-controlled", (4.0, 5.2, 6.4, 7.5), CONTROL),
    )
)
"""A reduced protocol for the unit test: three sessions of four runs."""


# ---------------------------------------------------------------------------------------------
# The truth's equations, assembled independently of the candidate models.
# ---------------------------------------------------------------------------------------------
class TruthSimulator:
    """Time-domain simulation of a hidden truth.

    Parameters
    ----------
    model : GapModelInput
        The nominal model (the truth perturbs it).
    truth : Truth
    rng : numpy.random.Generator
        Draws the parameter error.
    geometry_rng : numpy.random.Generator, optional
        Draws the rider's geometry from its stated uncertainty (:func:`_drawn_geometry`); without it the
        rider is the fixed one of :data:`TRUTH_GEOMETRY`.
    """

    def __init__(
        self,
        model: GapModelInput,
        truth: Truth,
        rng: np.random.Generator,
        geometry_rng: np.random.Generator | None = None,
    ):
        self.truth = truth
        values, sigmas = model.parameters.values, model.parameters.sigmas
        self.values = {k: float(values[k]) for k in BENCH_ARGS + ("g",)}  # type: ignore[arg-type]
        for k in BENCH_ARGS:
            if sigmas.get(k, 0.0) > 0:
                nominal = self.values[k]
                self.values[k] += sigmas[k] * float(rng.standard_normal())
                if k in POSITIVE and nominal > 0:  # a mass or inertia stays physical (at least 10 % of nominal)
                    self.values[k] = max(self.values[k], 0.1 * nominal)
        self.geometry = _truth_geometry(model) if geometry_rng is None else _drawn_geometry(model, geometry_rng)
        self.g = self.values["g"]

    # -- ingredients ---------------------------------------------------------------------------
    def _benchmark_values(self) -> dict[str, float]:
        v = dict(self.values)
        t = self.truth.values
        if "I_steer" in t:
            lam = v["lam"]
            s, c = math.sin(lam), math.cos(lam)
            v["IHxx"] += t["I_steer"] * s * s
            v["IHzz"] += t["I_steer"] * c * c
            v["IHxz"] += t["I_steer"] * s * c
        if "m_arm" in t:
            v = _move_arms(v, t["m_arm"], self.geometry["grips"])
        return v

    def canonical(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        return meijaard_matrices(self._benchmark_values())

    def _lean_terms(self, speed: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Hand-derived coupling of an upper body leaning about a longitudinal hip axis.

        Newton-Euler with the yaw rate ``psi' = (c delta' + v delta) cos(lam) / w`` of the rolling
        bicycle: the upper body's lateral acceleration ``v psi' + x psi'' - z phi'' + h theta''``
        and roll acceleration ``phi'' + theta''`` give its equation and its reactions on the roll
        and (through the front contact force, factor ``c cos(lam) / w``) steer equations.
        """
        v = self.values
        u = self.geometry["upper"]
        m, x, z, Ixx, Ixz = u["m_u"], u["x_u"], u["z_u"], u["IUxx"], u["IUxz"]
        h = u["z_lean"] - z  # height of the upper body's centre above the hip axis
        nu1 = v["c"] * math.cos(v["lam"]) / v["w"]
        nu0 = math.cos(v["lam"]) / v["w"]
        M = np.zeros((3, 3))
        C = np.zeros((3, 3))
        K = np.zeros((3, 3))
        M[0, 2] = M[2, 0] = Ixx - m * z * h
        M[2, 2] = Ixx + m * h * h
        M[1, 2] = M[2, 1] = nu1 * (Ixz + m * x * h)
        C[2, 1] = speed * (m * h * (nu1 + x * nu0) + Ixz * nu0)
        K[2, 1] = speed**2 * m * h * nu0
        K[0, 2] = -self.g * m * h
        return M, C, K

    # -- right-hand sides -------------------------------------------------------------------------
    def rhs(self, speed: float, gains) -> tuple[callable, int, tuple[int, int, int, int]]:
        """``(f(t, x), n_states, (phi, delta, phid, deltad) indices)`` for one speed."""
        t = self.truth.values
        gains = np.asarray(gains, dtype=float)
        c_s, T_c = t.get("c_steer", 0.0), t.get("T_coulomb", 0.0)
        eps = t.get("eps_coulomb", FRICTION_CORNER)
        k_s, k3_s = t.get("k_steer", 0.0), t.get("k3_steer", 0.0)
        k_a, c_a = t.get("k_arm", 0.0), t.get("c_arm", 0.0)

        def steer_torque(phi, delta, phid, deltad):
            control = gains @ np.array([phi, phid, delta, deltad])
            passive = -(c_s + c_a) * deltad - T_c * math.tanh(deltad / eps) - (k_s + k_a) * delta - k3_s * delta**3
            return control + passive

        if "tyre_slip" in self.truth.effects:
            return self._tyre_rhs(speed, steer_torque)
        M2, C1, K0, K2 = self.canonical()
        lean = "rider_lean" in self.truth.effects
        n = 3 if lean else 2
        M = np.zeros((n, n))
        C = np.zeros((n, n))
        K = np.zeros((n, n))
        M[:2, :2], C[:2, :2], K[:2, :2] = M2, speed * C1, self.g * K0 + speed**2 * K2
        if lean:
            Ml, Cl, Kl = self._lean_terms(speed)
            M += Ml
            C += Cl
            K += Kl
            m_u, h = self.geometry["upper"]["m_u"], self.geometry["upper"]["z_lean"] - self.geometry["upper"]["z_u"]
            k_l, c_l, k3_l = t["k_lean"], t["c_lean"], t.get("k3_lean", 0.0)
        Minv = np.linalg.inv(M)

        def f(_, x):
            q, qd = x[:n], x[n:]
            forces = -C @ qd - K @ q
            forces[1] += steer_torque(q[0], q[1], qd[0], qd[1])
            if lean:
                theta = q[2]
                # K[2, :] holds no gravity: the upper body's gravity moment and spring enter in full
                forces[2] += self.g * m_u * h * math.sin(q[0] + theta)
                forces[2] += -k_l * theta - k3_l * theta**3 - c_l * qd[2]
            return np.concatenate([qd, Minv @ forces])

        return f, 2 * n, (0, 1, n, n + 1)

    def _tyre_rhs(self, speed: float, steer_torque):
        from bikerider.generated import gap_effects as gen

        t = self.truth.values
        v = dict(self._benchmark_values())
        upper = {"m_u": 0.0, "x_u": 0.0, "z_u": -1.0, "IUxx": 0.0, "IUxz": 0.0, "IUzz": 0.0, "z_lean": -0.5}
        bench = {k: v[k] for k in BENCH_ARGS}
        zero = {
            "k_lean": 1.0,
            "c_lean": 0.0,
            "I_steer": 0.0,
            "c_steer": 0.0,
            "k_steer": 0.0,
            "m_arm": 0.0,
            "k_arm": 0.0,
            "c_arm": 0.0,
            **{k: 0.3 for k in ("x_grip", "z_grip", "b_grip")},
        }
        E, A, _ = gen.tyre_slip_descriptor(
            **bench,
            **upper,
            **zero,
            c_alpha=t["c_alpha"],
            c_gamma=t["c_gamma"],
            sigma_t=t["sigma_t"],
            t_p=t["t_p"],
            g=self.g,
            v=speed,
        )
        slip, loads = gen.tyre_slip_contacts(**bench, **upper, g=self.g, v=speed)
        keep = [0, 1, 3, 4, 5, 6, 8, 9]
        E, A, slip = E[np.ix_(keep, keep)], A[np.ix_(keep, keep)], slip[:, keep]
        mech = slice(0, 6)
        Einv = np.linalg.inv(E[mech, mech])
        A_mech = A[mech, :]
        mu, c_alpha, sigma = t["mu"], t["c_alpha"], t["sigma_t"]

        def f(_, x):
            rhs = A_mech @ x
            rhs[5] += steer_torque(x[0], x[1], x[4], x[5])  # the steer equation
            xd = np.empty_like(x)
            xd[mech] = Einv @ rhs
            alpha = -(slip @ x) / speed
            target = mu * loads * np.tanh(c_alpha * alpha / mu)
            xd[6:] = speed / sigma * (target - x[6:])
            return xd

        return f, 8, (0, 1, 4, 5)

    def run(self, speed: float, gains, kick: tuple[float, float], duration: float, rate: float):
        """Simulate a kick ``(phid, deltad)`` at ``speed``; return sample times and roll rate."""
        t, states = self.states(speed, gains, {"phid": kick[0], "deltad": kick[1]}, duration, rate)
        return t, states["phid"]

    def states(self, speed: float, gains, initial: dict[str, float], duration: float, rate: float):
        """Simulate from an initial state (``phi, delta, phid, deltad``); sample times and those four
        signals (the run stops if the bicycle falls past 0.5 rad)."""
        from scipy.integrate import solve_ivp

        f, n, idx = self.rhs(speed, gains)
        x0 = np.zeros(n)
        for k, name in enumerate(("phi", "delta", "phid", "deltad")):
            x0[idx[k]] = initial.get(name, 0.0)
        times = np.arange(0.0, duration, 1.0 / rate)

        def fall(_, x):
            return abs(x[idx[0]]) - 0.5

        fall.terminal = True
        sol = solve_ivp(f, (0.0, duration), x0, t_eval=times, method="LSODA", rtol=1e-6, atol=1e-8, events=fall)
        return sol.t, {name: sol.y[idx[k]] for k, name in enumerate(("phi", "delta", "phid", "deltad"))}


def meijaard_matrices(v: dict[str, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``M, C1, K0, K2`` of the Whipple bicycle, typed in from Meijaard et al. (2007) Appendix A.

    Written out by hand (no generated code), so the truth shares nothing with the candidates but the
    meaning of the 23 parameters; ``tests/gap/test_gap_validation.py`` holds it to the generated
    benchmark model.  ``K0`` is per unit ``g``; the equations are
    ``M q'' + v C1 q' + (g K0 + v^2 K2) q = f`` with ``q = [roll, steer]``.
    """
    w, c, lam, rR, rF = v["w"], v["c"], v["lam"], v["rR"], v["rF"]
    mR, mB, mH, mF = v["mR"], v["mB"], v["mH"], v["mF"]
    xB, zB, xH, zH = v["xB"], v["zB"], v["xH"], v["zH"]
    sl, cl = math.sin(lam), math.cos(lam)
    mT = mR + mB + mH + mF
    xT = (xB * mB + xH * mH + w * mF) / mT
    zT = (-rR * mR + zB * mB + zH * mH - rF * mF) / mT
    ITxx = v["IRxx"] + v["IBxx"] + v["IHxx"] + v["IFxx"] + mR * rR**2 + mB * zB**2 + mH * zH**2 + mF * rF**2
    ITxz = v["IBxz"] + v["IHxz"] - mB * xB * zB - mH * xH * zH + mF * w * rF
    ITzz = v["IRxx"] + v["IBzz"] + v["IHzz"] + v["IFxx"] + mB * xB**2 + mH * xH**2 + mF * w**2
    mA = mH + mF
    xA = (xH * mH + w * mF) / mA
    zA = (zH * mH - rF * mF) / mA
    IAxx = v["IHxx"] + v["IFxx"] + mH * (zH - zA) ** 2 + mF * (rF + zA) ** 2
    IAxz = v["IHxz"] - mH * (xH - xA) * (zH - zA) + mF * (w - xA) * (rF + zA)
    IAzz = v["IHzz"] + v["IFxx"] + mH * (xH - xA) ** 2 + mF * (w - xA) ** 2
    uA = (xA - w - c) * cl - zA * sl
    IAll = mA * uA**2 + IAxx * sl**2 + 2 * IAxz * sl * cl + IAzz * cl**2
    IAlx = -mA * uA * zA + IAxx * sl + IAxz * cl
    IAlz = mA * uA * xA + IAxz * sl + IAzz * cl
    mu = c / w * cl
    SR, SF = v["IRyy"] / rR, v["IFyy"] / rF
    ST = SR + SF
    SA = mA * uA + mu * mT * xT
    M = np.array([[ITxx, IAlx + mu * ITxz], [IAlx + mu * ITxz, IAll + 2 * mu * IAlz + mu**2 * ITzz]])
    K0 = np.array([[mT * zT, -SA], [-SA, -SA * sl]])
    K2 = np.array([[0.0, (ST - mT * zT) / w * cl], [0.0, (SA + SF * sl) / w * cl]])
    C1 = np.array(
        [
            [0.0, mu * ST + SF * cl + ITxz / w * cl - mu * mT * zT],
            [-(mu * ST + SF * cl), IAlz / w * cl + mu * (SA + ITzz / w * cl)],
        ]
    )
    return M, C1, K0, K2


def _truth_geometry(model: GapModelInput) -> dict:
    """The truth's rider: the default geometry moved as :data:`TRUTH_GEOMETRY` says."""
    grips = dict(model.geometry.grips)
    grips["z_grip"] -= TRUTH_GEOMETRY["grip_rise"]
    grips["b_grip"] += TRUTH_GEOMETRY["grip_widen"]
    upper = None
    if model.geometry.upper_body is not None:
        upper = dict(model.geometry.upper_body)
        if model.rider is not None:
            scale = TRUTH_GEOMETRY["upper_mass_fraction"] * model.rider["mass"] / upper["m_u"]
            for key in ("m_u", "IUxx", "IUxz", "IUzz"):
                upper[key] *= scale
        upper["z_lean"] += TRUTH_GEOMETRY["hip_shift"]
    return {"grips": grips, "upper": upper}


def _drawn_geometry(model: GapModelInput, rng: np.random.Generator) -> dict:
    """A rider drawn from the geometry's stated uncertainty (:data:`GEOMETRY_DRAW_LIMIT`): each source of
    ``model.geometry.uncertainty``, in its stated order, moves the values it names by a truncated standard
    normal draw times their shift per sigma."""
    grips = dict(model.geometry.grips)
    upper = dict(model.geometry.upper_body) if model.geometry.upper_body is not None else None
    for shift in model.geometry.uncertainty.values():
        z = float(np.clip(rng.standard_normal(), -GEOMETRY_DRAW_LIMIT, GEOMETRY_DRAW_LIMIT))
        for key, per_sigma in shift.items():
            if key in grips:
                grips[key] += z * per_sigma
            elif upper is not None and key in upper:
                upper[key] += z * per_sigma
    return {"grips": grips, "upper": upper}


def _move_arms(v: dict[str, float], m_arm: float, grips: dict[str, float]) -> dict[str, float]:
    """Move two point masses ``m_arm / 2`` at the grips from the rear body to the front frame."""
    out = dict(v)
    xg, zg, bg = grips["x_grip"], grips["z_grip"], grips["b_grip"]

    def combine(m, x, z, Ixx, Ixz, Izz, dm, sign):
        m2 = m + sign * dm
        x2 = (m * x + sign * dm * xg) / m2
        z2 = (m * z + sign * dm * zg) / m2
        # inertia about the new centre: parallel-axis theorem for both bodies, two symmetric points
        Ixx2 = Ixx + m * (z - z2) ** 2 + sign * dm * ((zg - z2) ** 2 + bg**2)
        Izz2 = Izz + m * (x - x2) ** 2 + sign * dm * ((xg - x2) ** 2 + bg**2)
        Ixz2 = Ixz - m * (x - x2) * (z - z2) - sign * dm * (xg - x2) * (zg - z2)
        return m2, x2, z2, Ixx2, Ixz2, Izz2

    out["mB"], out["xB"], out["zB"], out["IBxx"], out["IBxz"], out["IBzz"] = combine(
        v["mB"], v["xB"], v["zB"], v["IBxx"], v["IBxz"], v["IBzz"], m_arm, -1
    )
    out["mH"], out["xH"], out["zH"], out["IHxx"], out["IHxz"], out["IHzz"] = combine(
        v["mH"], v["xH"], v["zH"], v["IHxx"], v["IHxz"], v["IHzz"], m_arm, +1
    )
    return out


# ---------------------------------------------------------------------------------------------
# Measuring, diagnosing, scoring
# ---------------------------------------------------------------------------------------------
def measure(
    simulator: TruthSimulator,
    protocol: Protocol,
    rng: np.random.Generator,
    amplitudes: list[float] | None = None,
    records: list | None = None,
) -> tuple[EigenvalueData, list[str]]:
    """Run every session of the protocol and extract the weave eigenvalues as from real runs.

    ``amplitudes``, when given, receives each fitted run's steer-rate amplitude (``sqrt(2)`` times its
    RMS over the fitted window, as :func:`bikerider.gap.diagnosis.priors.steer_rate_amplitudes`).
    ``records``, when given, receives every run as the record a lab keeps, fitted
    (:class:`bikerider.gap.measured.records.RecordFit` from :func:`bikerider.gap.measured.records.fit_record`:
    the noisy roll rate over the fitted window, the speed reading, the session as its group, the session's
    control law), and the table's rows are those records' fits, so tables and records of one seed hold the
    same runs and the same fits (each run fitted once); the random draws are the same with or without it.
    """
    from dataclasses import replace

    from bikerider.gap.measured.extraction import weave_eigenvalue
    from bikerider.gap.measured.records import Record, fit_record

    rows = {k: [] for k in ("speed", "value", "rs", "is", "group", "gains")}
    notes = []
    for session in protocol.sessions:
        law = ControlLaw.constant(session.gains)
        for nominal_speed in session.speeds:
            speed = nominal_speed + protocol.speed_jitter * float(rng.uniform(-1, 1))
            kick = (float(rng.choice([-1, 1]) * rng.uniform(0.2, 0.4)), float(rng.uniform(-0.8, 0.8)))
            kick = (protocol.push * kick[0], protocol.push * kick[1])  # the same draws at any push
            t, states = simulator.states(
                speed, session.gains, {"phid": kick[0], "deltad": kick[1]}, protocol.duration, protocol.rate
            )
            roll_rate = states["phid"]
            y = roll_rate + protocol.gyro_noise * rng.standard_normal(roll_rate.size)
            keep = t >= protocol.start
            if records is not None:
                # the speed reading is drawn below, for fitted runs only (the same draws as without records)
                record = Record(
                    f"{session.group} run {len(records) + 1}",
                    "simulated",
                    t[keep] - t[keep][0],
                    {"roll_rate": y[keep]},
                    speed,
                    protocol.speed_noise,
                    session.group,
                    law,
                    speed,
                )
                fit = fit_record(record)
                records.append(fit)
                if not fit.used:
                    notes.append(f"{session.group} {speed:.2f} m/s: no weave fitted ({fit.reason})")
                    continue
                est = fit.estimate
            else:
                try:
                    est = weave_eigenvalue(t[keep], y[keep])
                except FitError as exc:
                    notes.append(f"{session.group} {speed:.2f} m/s: no weave fitted ({exc})")
                    continue
            if amplitudes is not None:
                amplitudes.append(math.sqrt(2) * float(np.std(states["deltad"][keep])))
            reading = speed + protocol.speed_noise * float(rng.standard_normal())
            if records is not None:
                records[-1] = replace(
                    records[-1], record=replace(records[-1].record, speed=reading, controller_speed=reading)
                )
            rows["speed"].append(reading)
            rows["value"].append(complex(est.eigenvalue.real, abs(est.eigenvalue.imag)))
            rows["rs"].append(est.real_sigma)
            rows["is"].append(est.imag_sigma)
            rows["group"].append(session.group)
            rows["gains"].append(session.gains)
    n = len(rows["speed"])
    data = EigenvalueData(
        np.array(rows["speed"]),
        np.array(rows["value"], complex),
        np.array(rows["rs"]),
        np.array(rows["is"]),
        np.full(n, protocol.speed_noise),
        ["weave"] * n,
        rows["group"],
        np.array(rows["gains"], float).reshape(n, 4),
        [f"simulated run {k + 1}" for k in range(n)],
    )
    return data, notes


@dataclass
class CaseResult:
    """One blind diagnosis of one hidden truth."""

    truth: str
    hidden: tuple[str, ...]
    seed: int
    verdict: str
    ranking: list[str]
    ties_with_first: list[str]
    selected: list[str]
    predicted_shrink: float | None
    actual_shrink: float | None
    n_measured: int
    seconds: float
    notes: list[str] = field(default_factory=list)
    first_parameters: dict[str, float] = field(default_factory=dict)
    """Fitted values of the first-ranked effect (structural parameters only)."""
    data_errors: tuple[float, float] | None = None
    """The selection's held-out RMS error over the data's own noise, before and after (record cases)."""

    @property
    def top(self) -> str:
        """The predicted label: the first-ranked effect for a structural verdict, else the verdict."""
        if self.verdict != "structural" or not self.ranking:
            return self.verdict
        return self.ranking[0]

    @property
    def correct(self) -> bool:
        """Null: no structural verdict.  Effect: structural verdict and a hidden effect ranked first."""
        if not self.hidden:
            return self.verdict != "structural"
        return self.verdict == "structural" and bool(self.ranking) and self.ranking[0] in self.hidden


def run_case(model: GapModelInput, truth_name: str, seed: int, protocol: Protocol = FULL) -> CaseResult:
    """Generate data from one truth, diagnose it blind, and score the predicted shrinkage."""
    from bikerider.gap.diagnosis.result import diagnose
    from bikerider.gap.diagnosis.statistics import gap_shrink
    from bikerider.gap.inference.problem import GapProblem

    start = time.perf_counter()
    truth = TRUTHS[truth_name]
    rng = np.random.default_rng(seed)
    simulator = TruthSimulator(model, truth, rng)
    data, notes = measure(simulator, protocol, rng)
    empty = CanonicalData([], np.empty(0), np.empty(0), [], {}, [])
    diagnosis = diagnose(model, data, empty)
    result = diagnosis.as_dict()
    predicted = actual = None
    if diagnosis.selected and result["how_far"] is not None:
        predicted = result["how_far"]["shrink"]
        fresh, _ = measure(simulator, protocol, np.random.default_rng(seed + 10_000))
        test = GapProblem(model, fresh, empty)
        fitted = diagnosis.problem.fitted_model(diagnosis.selected_fit)
        z_before = test.z(test.baseline)
        z_after = test.z(test.predictor.predict(fitted))
        actual = gap_shrink(z_before, z_after)
    return _case_result(
        truth_name, truth.effects, seed, diagnosis, result, predicted, actual, len(data), start, notes + result["notes"]
    )


def _case_result(
    truth_name: str,
    hidden: tuple[str, ...],
    seed: int,
    diagnosis,
    result: dict,
    predicted: float | None,
    actual: float | None,
    n_measured: int,
    start: float,
    notes: list[str],
    first: dict[str, float] | None = None,
    errors: tuple[float, float] | None = None,
) -> CaseResult:
    """A case's score from its diagnosis (``result`` its ``as_dict()``); ``first`` defaults to the structural
    values of the first-ranked effect."""
    ranking = result["ranking"]
    if first is None:
        first = (
            {k: v["value"] for k, v in ranking[0]["parameters"].items() if not k.startswith("parameters.")}
            if ranking
            else {}
        )
    return CaseResult(
        truth_name,
        hidden,
        seed,
        result["verdict"],
        [r["effect"] for r in ranking],
        ranking[0]["tied_with"] if ranking else [],
        list(diagnosis.selected),
        predicted,
        actual,
        n_measured,
        time.perf_counter() - start,
        notes,
        first,
        errors,
    )


@dataclass
class SuiteResult:
    """Scores over many cases."""

    cases: list[CaseResult]

    @property
    def effect_cases(self) -> list[CaseResult]:
        return [c for c in self.cases if c.hidden]

    @property
    def null_cases(self) -> list[CaseResult]:
        return [c for c in self.cases if not c.hidden]

    @property
    def first_rate(self) -> tuple[int, int]:
        """(hidden effect ranked first with a structural verdict, effect cases)."""
        cases = self.effect_cases
        return sum(c.correct for c in cases), len(cases)

    @property
    def false_alarms(self) -> tuple[int, int]:
        """(null cases with a structural verdict, null cases)."""
        cases = self.null_cases
        return sum(c.verdict == "structural" for c in cases), len(cases)

    @property
    def shrink_errors(self) -> np.ndarray:
        """Predicted minus actual shrinkage, for every case with a selection."""
        return np.array(
            [
                c.predicted_shrink - c.actual_shrink
                for c in self.cases
                if c.predicted_shrink is not None and c.actual_shrink is not None
            ]
        )

    def confusion(self) -> tuple[list[str], list[str], np.ndarray]:
        """Rows: truths; columns: predicted labels (first-ranked effect, or the verdict)."""
        rows = list(dict.fromkeys(c.truth for c in self.cases))
        cols = list(dict.fromkeys(["none", "parameters"] + [c.top for c in self.cases]))
        table = np.zeros((len(rows), len(cols)), int)
        for c in self.cases:
            table[rows.index(c.truth), cols.index(c.top)] += 1
        return rows, cols, table


def run_suite(model: GapModelInput, cases: list[tuple[str, int]], protocol: Protocol = FULL) -> SuiteResult:
    """Run :func:`run_case` for every ``(truth, seed)``."""
    results = []
    for truth, seed in cases:
        result = run_case(model, truth, seed, protocol)
        LOG.info(
            "%s seed %d: verdict %s, first %s (%.1f s)", truth, seed, result.verdict, result.ranking[:1], result.seconds
        )
        results.append(result)
    return SuiteResult(results)


FULL_CASES = [
    (name, 100 + k)
    for k, name in enumerate(
        [
            "steer_damping",
            "steer_inertia",
            "steer_stiffness",
            "passive_arms",
            "rider_lean",
            "tyre_slip",
            "steer_damping+tyre_slip",
            "rider_lean+steer_damping",
            "strong_steer_damping",
            "passive_arms",
        ]
    )
] + [("null", 200 + k) for k in range(10)]
"""The documented case set: ten effect cases and ten null cases."""


# ---------------------------------------------------------------------------------------------
# Records of the steer-by-wire kind: short, strongly damped, under a speed-scheduled control
# ---------------------------------------------------------------------------------------------
SIL = ControlLaw(
    "sil",
    {"k_phid": GainSchedule.make_ramp(2.0, 6.5, "below"), "k_phi": GainSchedule.make_ramp(0.7, 6.5, "above")},
    "steer into lean of the SBW experiment: 2 (6.5 - v) phid below 6.5 m/s, 0.7 (v - 6.5) phi above",
)
"""The speed-scheduled control of the record cases, evaluated at the recorded speed (as the SBW's)."""

RECORD_TRUTHS: dict[str, Truth] = {
    t.name: t
    for t in (
        Truth("sbw_null", (), {}, "parameter error within the stated uncertainty only"),
        Truth(
            "sbw_friction",
            ("steer_friction",),
            {"T_coulomb": 0.12, "c_steer": 0.05},
            "Coulomb 0.12 N m and viscous 0.05 N m s/rad steer friction (smoothed by tanh(deltad / 0.02))",
        ),
        Truth(
            "sbw_inertia+damping",
            ("steer_inertia", "steer_damping"),
            {"I_steer": 0.03, "c_steer": 0.3},
            "0.03 kg m^2 of steer inertia (a motor's rotor) and 0.3 N m s/rad viscous damping, together",
        ),
        Truth(
            "sbw_speed+friction",
            ("speed_sensor", "steer_friction"),
            {"speed_scale": 1.04, "T_coulomb": 0.1, "c_steer": 0.05},
            "a speed sensor reading 4 % high (the controller uses it) and Coulomb 0.1 N m with viscous "
            "0.05 N m s/rad steer friction, together",
        ),
    )
}
"""Hidden truths of the record cases (the candidate each stands for in ``effects``)."""


@dataclass(frozen=True)
class RecordProtocol:
    """Short free-decay records of a riderless bicycle under :data:`SIL` (the SBW experiment's kind).

    Attributes
    ----------
    speeds : tuple of float
        Set speeds [m/s]; each is a group.
    per_speed : int
        Records per speed.
    duration : tuple of float
        Range of record lengths [s] (drawn uniformly).
    rate : float
        Samples per second (no time column).
    gyro_noise : float
        Roll-rate noise [rad/s].
    encoder_step : float
        Quantisation of the steer angle [rad] (a 13-bit encoder).
    speed_noise : float
        Noise of each speed sample [m/s].
    speed_jitter : float
        Spread of a record's true speed about the set speed [m/s].
    """

    speeds: tuple[float, ...] = (2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0)
    per_speed: int = 4
    duration: tuple[float, float] = (1.2, 2.5)
    rate: float = 100.0
    gyro_noise: float = 0.015
    encoder_step: float = 2 * math.pi / 8192
    speed_noise: float = 0.02
    speed_jitter: float = 0.05


RECORDS = RecordProtocol()
"""The documented record protocol: seven speeds of four records (28 records)."""
QUICK_RECORDS = RecordProtocol(speeds=(2.5, 3.5, 4.5), per_speed=4)
"""A reduced record protocol for the unit test."""


def measure_records(simulator: TruthSimulator, protocol: RecordProtocol, rng: np.random.Generator):
    """Records of every speed: the truth simulated from a random post-push state, noisy and quantised."""
    from bikerider.gap.measured.records import Record

    scale = simulator.truth.values.get("speed_scale", 1.0)
    records = []
    for set_speed in protocol.speeds:
        for k in range(protocol.per_speed):
            true_speed = set_speed + protocol.speed_jitter * float(rng.uniform(-1, 1))
            recorded = true_speed * scale
            initial = {
                "phid": float(rng.choice([-1, 1]) * rng.uniform(0.4, 0.9)),
                "deltad": float(rng.uniform(-1.0, 1.0)),
                "delta": float(rng.uniform(-0.08, 0.08)),
                "phi": float(rng.uniform(-0.03, 0.03)),
            }
            duration = float(rng.uniform(*protocol.duration))
            t, states = simulator.states(true_speed, SIL(recorded), initial, duration, protocol.rate)
            roll_rate = states["phid"] + protocol.gyro_noise * rng.standard_normal(t.size)
            steer = np.round(states["delta"] / protocol.encoder_step) * protocol.encoder_step
            speed_column = recorded + protocol.speed_noise * rng.standard_normal(t.size)
            name = f"sim_{set_speed:.1f}mps[{k}]"
            records.append(
                Record(
                    name,
                    "simulated",
                    t - t[0],
                    {"roll_rate": roll_rate, "steer_angle": steer},
                    float(np.mean(speed_column)),
                    float(np.std(speed_column)),
                    f"{set_speed:.1f} m/s",
                    SIL,
                    float(np.mean(speed_column)),
                    None,
                    None,
                    ("roll_rate",),
                    True,
                )
            )
    return records


STEER_MOTOR = {
    "I_steer": (
        0.0,
        0.1,
        "a steer motor's rotor through its gearbox (a steer-by-wire conversion, as the "
        "SBW bicycle's [plausible] table)",
    )
}
"""What the record cases' bicycle states as plausible: it is steer-by-wire, like the SBW bicycle."""


def run_record_case(model: GapModelInput, truth_name: str, seed: int, protocol: RecordProtocol = RECORDS) -> CaseResult:
    """Simulate records from a hidden truth, diagnose them blind from the records, score on fresh records.

    The diagnosis sees ``model`` with :data:`STEER_MOTOR` as its ``[plausible]`` table.
    """
    from dataclasses import replace

    model = replace(model, plausible={**STEER_MOTOR, **model.plausible})
    from bikerider.gap.diagnosis.result import diagnose
    from bikerider.gap.diagnosis.statistics import gap_shrink
    from bikerider.gap.measured.records import fit_records

    start = time.perf_counter()
    truth = RECORD_TRUTHS[truth_name]
    rng = np.random.default_rng(seed)
    simulator = TruthSimulator(model, truth, rng)
    fits = fit_records(measure_records(simulator, protocol, rng))
    diagnosis = diagnose(model, EigenvalueData.empty(), CanonicalData.empty(), records=fits)
    result = diagnosis.as_dict()
    predicted = actual = None
    if diagnosis.selected and result["how_far"] is not None:
        predicted = result["how_far"]["data_shrink"]
        fresh = fit_records(measure_records(simulator, protocol, np.random.default_rng(seed + 10_000)))
        check = diagnose(model, EigenvalueData.empty(), CanonicalData.empty(), effects=(), records=fresh)
        p = check.problem
        if "steer_friction" in diagnosis.selected:
            after = check.fits.time_domain_predict(diagnosis.selected_fit, np.ones(len(p.obs), bool))
        else:
            after = p.predict_batch(p.layout(diagnosis.selected_fit.effects), diagnosis.selected_fit.values[None, :])[0]
        sigma = np.sqrt(p.var_data)
        actual = gap_shrink((p.baseline - p.y) / sigma, (after - p.y) / sigma)
    first = None  # the first-ranked effect's values, unless an effect is selected
    if diagnosis.selected_fit is not None:
        first = {
            k: float(v)
            for k, v in zip(diagnosis.selected_fit.names, diagnosis.selected_fit.values)
            if not k.startswith("parameters.")
        }
    notes = [f"{r['record']}: {r['reason']}" for r in result["records"]["reasons"]] if result["records"] else []
    how = result["how_far"] or {}
    errors = (
        (how["data_error_before"], how["data_error_after"])
        if how.get("data_error_before") is not None and how.get("data_error_after") is not None
        else None
    )
    return _case_result(
        truth_name,
        truth.effects,
        seed,
        diagnosis,
        result,
        predicted,
        actual,
        len(diagnosis.record_rows),
        start,
        notes,
        first,
        errors,
    )


RECORD_CASES = [
    ("sbw_friction", 300),
    ("sbw_friction", 301),
    ("sbw_inertia+damping", 302),
    ("sbw_inertia+damping", 303),
    ("sbw_speed+friction", 304),
    ("sbw_speed+friction", 305),
    ("sbw_null", 306),
    ("sbw_null", 307),
]
"""The documented record cases: three truths of two seeds and two null cases."""


# ---------------------------------------------------------------------------------------------
# Calibration: many short trials per candidate effect, sizes drawn over its prior
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class CalibrationEffect:
    """A hidden effect of the calibration study and the candidate that stands for it.

    Attributes
    ----------
    name : str
        The truth's label.
    candidate : str
        The candidate whose fitted sizes are scored (its intervals' coverage, its bias).
    sizes : tuple of str
        The truth's parameters drawn from the candidate's priors (same names as the candidate's).
    fixed : dict
        Truth values held fixed.
    rider : str
        ``"riderless"``, ``"rider"`` or ``"both"`` (alternating trials).
    """

    name: str
    candidate: str
    sizes: tuple[str, ...]
    fixed: dict[str, float] = field(default_factory=dict)
    rider: str = "both"


CALIBRATION_EFFECTS: tuple[CalibrationEffect, ...] = (
    CalibrationEffect("steer_damping", "steer_damping", ("c_steer",)),
    CalibrationEffect("steer_coulomb", "steer_damping", ("T_coulomb",)),
    CalibrationEffect("steer_inertia", "steer_inertia", ("I_steer",)),
    CalibrationEffect("steer_stiffness", "steer_stiffness", ("k_steer",)),
    CalibrationEffect("passive_arms", "passive_arms", ("m_arm", "k_arm", "c_arm"), rider="rider"),
    CalibrationEffect("rider_lean", "rider_lean", ("k_lean", "c_lean"), rider="rider"),
    CalibrationEffect("tyre_slip", "tyre_slip", ("c_alpha", "sigma_t", "t_p"), {"c_gamma": 0.8, "mu": 1.0}),
)
"""The calibrated effects.  ``steer_coulomb`` is pure Coulomb steer friction simulated nonlinearly in time,
which a table of eigenvalues can only size as a viscous damping: its size is scored against the
describing-function equivalent of the truth's law at the runs' median steer-rate amplitude ``A``
(:func:`truth_equivalent`; ``4 T / (pi A)`` for a sharp corner), the corner drawn by :func:`draw_corner`."""

FRICTION_CORNER = 0.02
"""The truth's Coulomb friction corner ``eps`` of ``T tanh(deltad / eps)`` [rad/s] unless a truth draws its own
(``eps_coulomb``: :func:`draw_corner`)."""


def draw_corner(seed: int) -> float:
    """A calibration truth's friction corner ``eps`` [rad/s], drawn log-uniform over the corner's range the fits
    assume (:func:`bikerider.gap.inference.timedomain.corner_nodes`: 0.02-0.125 rad/s), from a stream of its own
    (the sizes, bicycle and runs of a seed stay those drawn before the corner was)."""
    from bikerider.gap.inference.timedomain import CORNER_FACTOR, SMOOTHING

    low, high = math.log(SMOOTHING / CORNER_FACTOR), math.log(SMOOTHING * CORNER_FACTOR)
    return float(math.exp(np.random.default_rng((seed, 25)).uniform(low, high)))


def truth_equivalent(truth: Truth, amplitude: float | None) -> float:
    """The truth's friction as the viscous damping it equals at steer-rate amplitude ``amplitude``: its own law's
    describing function (:func:`bikerider.gap.inference.timedomain.describing_gain` at its corner; ``4 T /
    (pi A)`` for a sharp one) plus its viscous part; NaN without an amplitude."""
    from bikerider.gap.inference.timedomain import describing_gain

    if not amplitude:
        return math.nan
    v = truth.values
    eps = v.get("eps_coulomb", FRICTION_CORNER)
    return float(v.get("c_steer", 0.0) + v.get("T_coulomb", 0.0) * describing_gain(amplitude, eps))


CALIBRATION_DRAW = {"halfcauchy": 0.8}
"""Probability of the prior's interval the sizes are drawn from (0.95 unless named here: a half-Cauchy's
95 % reaches 12.7 times its scale, beyond any bicycle; its 80 % reaches 3.1 times)."""

CALIBRATION_RIDER = Protocol(
    (
        Session("day1", (5.5, 7.0, 8.5)),
        Session("day2", (6.0, 7.5, 9.0)),
        Session("day3-controlled", (4.5, 6.0, 7.5), CONTROL),
    ),
    duration=3.0,
)
"""Short runs of a bicycle with rider: three sessions of three 3-s runs (one session under control)."""
CALIBRATION_RIDERLESS = Protocol(
    (
        Session("day1", (3.0, 4.5, 6.0)),
        Session("day2", (3.5, 5.0, 6.5)),
        Session("day3-controlled", (2.5, 3.5, 4.5), CONTROL),
    ),
    duration=3.0,
)
"""Short runs of the riderless bicycle: three sessions of three 3-s runs (one session under control)."""


def draw_truth(effect: CalibrationEffect, rng: np.random.Generator) -> Truth:
    """A truth whose sizes are drawn over the candidate's priors (:data:`CALIBRATION_DRAW`)."""
    from bikerider.gap.candidates.effects import EFFECTS

    priors = {p.name: p.the_prior() for e in EFFECTS.values() for p in e.parameters}
    if effect.name == "steer_coulomb":
        priors["T_coulomb"] = next(p for p in EFFECTS["steer_friction"].parameters if p.name == "T_coulomb").the_prior()
    values = dict(effect.fixed)
    for name in effect.sizes:
        prior = priors[name]
        values[name] = prior.sample(rng, CALIBRATION_DRAW.get(prior.kind, 0.95))
    effects = ("steer_damping",) if effect.name == "steer_coulomb" else (effect.candidate,)
    text = ", ".join(f"{k} {v:.3g}" for k, v in values.items())
    return Truth(effect.name, effects, values, text)


@dataclass
class Trial:
    """One calibration trial: what was hidden, what the diagnosis found, the candidate's fitted sizes."""

    effect: str
    candidate: str
    seed: int
    rider: bool
    truth: dict[str, float]
    verdict: str
    first: str | None
    tied_with_first: list[str]
    selected: list[str]
    fitted: dict[str, dict]
    """The candidate's own fit to all the data: ``{name: {value, ci95}}``."""
    reference: dict[str, float]
    """What each fitted size is scored against (the truth's value, or its equivalent)."""
    predicted_shrink: float | None
    achieved_shrink: float | None
    n_measured: int
    seconds: float
    amplitude: float | None = None
    method: str = "tables"
    """How the runs reached the diagnosis (:data:`CALIBRATION_METHODS`; record trials: ``records``)."""
    fit_chi2: float | None = None
    """The candidate's fit to all the data: its chi-square, over ``fit_n`` observations."""
    fit_n: int | None = None
    minima: int | None = None
    """Local minima of that fit's chi-square found (the fit's own counted; see
    :meth:`bikerider.gap.inference.problem.GapProblem.fit_apparent`), ``minima_within`` of the others within
    the 95 % profile-likelihood threshold (held by the intervals), each of the others in ``other_minima``
    (``{values: {name: value}, chi2}``)."""
    minima_within: int | None = None
    other_minima: list[dict] = field(default_factory=list)
    truth_geometry: dict | None = None
    """The truth's rider geometry (``{grips, upper}``, benchmark frame) where it was drawn."""

    def as_dict(self) -> dict:
        return dict(self.__dict__)


CALIBRATION_METHODS = ("records", "tables")
"""How a trial's runs reach the diagnosis.  ``records``: the noisy roll-rate records themselves, each predicted
by every model through the same fit applied to its own simulated response (indirect inference,
:mod:`bikerider.gap.inference.indirect`), so the fit's bias on short runs is the same on both sides;
``tables``: the weave eigenvalues fitted from the runs, compared with each model's weave eigenvalue (the
method before issue 21, kept for the before/after comparison on the same seeds)."""


def run_trial(models: dict[str, GapModelInput], effect: CalibrationEffect, seed: int, method: str = "records") -> Trial:
    """One trial: draw the sizes and the bicycle, measure short noisy runs, diagnose blind, score.

    ``models`` holds ``"riderless"`` and ``"rider"`` nominal models; with ``effect.rider == "both"`` even
    seeds are riderless.  ``method`` (:data:`CALIBRATION_METHODS`) says whether the diagnosis gets the
    records or a table of the eigenvalues fitted from them; the runs of one seed are the same either way.
    """
    from bikerider.gap.diagnosis.result import diagnose
    from bikerider.gap.diagnosis.statistics import gap_shrink
    from bikerider.gap.inference.problem import GapProblem

    if method not in CALIBRATION_METHODS:
        raise ValueError(f"calibration method {method!r}: expected one of {', '.join(CALIBRATION_METHODS)}")
    start = time.perf_counter()
    rng = np.random.default_rng(seed)
    rider = effect.rider == "rider" or (effect.rider == "both" and seed % 2 == 1)
    model = models["rider" if rider else "riderless"]
    protocol = CALIBRATION_RIDER if rider else CALIBRATION_RIDERLESS
    truth = draw_truth(effect, rng)
    if effect.name == "steer_coulomb":  # the friction's corner drawn over the range the fits assume
        truth = Truth(truth.name, truth.effects, {**truth.values, "eps_coulomb": draw_corner(seed)}, truth.description)
    # the rider drawn from a stream of its own, so the sizes, bicycle and runs of a seed stay those of the
    # studies before the geometry was drawn (their stored trials compare on the same seeds)
    simulator = TruthSimulator(model, truth, rng, geometry_rng=np.random.default_rng((seed, 21)))
    amplitudes: list[float] = []
    records: list = []
    data, _ = measure(simulator, protocol, rng, amplitudes, records)
    empty = CanonicalData.empty()
    amplitude = float(np.median(amplitudes)) if amplitudes else None
    reference = {k: truth.values[k] for k in effect.sizes}
    if effect.name == "steer_coulomb":
        reference = {"c_steer": truth_equivalent(truth, amplitude)}

    def undiagnosed(verdict: str, n_measured: int) -> Trial:
        """The trial when no diagnosis could be made (``verdict`` says why)."""
        return Trial(
            effect.name,
            effect.candidate,
            seed,
            rider,
            truth.values,
            verdict,
            None,
            [],
            [],
            {},
            reference,
            None,
            None,
            n_measured,
            time.perf_counter() - start,
            amplitude,
            method,
        )

    if len(data) < 4:
        return undiagnosed("too few runs", len(data))
    if method == "records":
        try:
            diagnosis = diagnose(model, EigenvalueData.empty(), empty, records=records)
        except InputError:  # every record left out: the model predicts no weave the fit finds in any
            return undiagnosed("no record used", 0)
        n_measured = len(diagnosis.record_rows)
    else:
        diagnosis = diagnose(model, data, empty)
        n_measured = len(data)
    result = diagnosis.as_dict()
    fit = diagnosis.fit_of((effect.candidate,)) if effect.candidate in diagnosis.candidates else None
    fitted = {}
    if fit is not None:
        for k, name in enumerate(fit.names):
            fitted[name] = {"value": float(fit.values[k]), "ci95": [float(fit.ci_low[k]), float(fit.ci_high[k])]}
    if effect.name == "steer_coulomb" and "steer_friction" in diagnosis.candidates:
        # from records, Coulomb friction also has a candidate of its own (fitted in the time domain): its
        # Coulomb level is scored against the truth's, the viscous part it adds against 0
        friction = diagnosis.fit_of(("steer_friction",))
        for k, name in enumerate(friction.names):
            value = [float(friction.ci_low[k]), float(friction.ci_high[k])]
            fitted[name] = {"value": float(friction.values[k]), "ci95": value}
        reference["T_coulomb"] = truth.values["T_coulomb"]
        reference["c_viscous"] = 0.0
        equivalent = _friction_equivalent(diagnosis, friction, amplitude)
        if equivalent is not None:
            # whether the diagnosis itself, from the amplitudes it infers (the records hold no steer),
            # says the records carry the split
            judged = diagnosis.priors.friction_equivalent(friction)
            if judged is not None:
                equivalent.update(separable=judged["separable"], amplitude_spread=judged["amplitude_spread"])
            fitted["c_equivalent"] = equivalent
            reference["c_equivalent"] = reference["c_steer"]
    predicted = achieved = None
    if diagnosis.selected and result["how_far"] is not None:
        predicted = result["how_far"]["shrink"]
        fresh_records: list = []
        fresh, _ = measure(simulator, protocol, np.random.default_rng(seed + 1_000_000), None, fresh_records)
        if len(fresh) and method == "records":
            achieved = _achieved_on_records(model, diagnosis, fresh_records)
        elif len(fresh):
            test = GapProblem(model, fresh, empty)
            fitted_model = diagnosis.problem.fitted_model(diagnosis.selected_fit)
            achieved = gap_shrink(test.z(test.baseline), test.z(test.predictor.predict(fitted_model)))
    ranking = result["ranking"]
    trial = Trial(
        effect.name,
        effect.candidate,
        seed,
        rider,
        truth.values,
        result["verdict"],
        ranking[0]["effect"] if ranking else None,
        list(ranking[0]["tied_with"]) if ranking else [],
        list(diagnosis.selected),
        fitted,
        reference,
        predicted,
        achieved,
        n_measured,
        time.perf_counter() - start,
        amplitude,
        method,
    )
    if rider:
        trial.truth_geometry = {
            part: None if values is None else {k: float(v) for k, v in values.items()}
            for part, values in simulator.geometry.items()
        }
    if fit is not None:
        trial.fit_chi2, trial.fit_n = float(fit.chi2), int(fit.n)
        trial.minima, trial.minima_within = 1 + len(fit.minima), int(fit.minima_within)
        trial.other_minima = [
            {"values": dict(zip(fit.names, map(float, values))), "chi2": float(chi2)} for values, chi2 in fit.minima
        ]
    return trial


def _friction_equivalent(diagnosis, fit, amplitude: float | None) -> dict | None:
    """The steer-friction fit as the viscous damping it equals at the runs' median steer-rate amplitude
    with its 95 % interval (:func:`bikerider.gap.diagnosis.priors.equivalent_damping`, as
    :meth:`bikerider.gap.diagnosis.priors.Priors.friction_equivalent` reports it for records with a steer
    signal; these hold the roll rate only, so the amplitude is the truth's, the one the reference uses)."""
    from bikerider.gap.diagnosis.priors import equivalent_damping

    if not amplitude or fit.covariance is None or not np.all(np.isfinite(fit.covariance)):
        return None
    value, _, interval = equivalent_damping(fit, amplitude, len(diagnosis.folds))
    return {"value": value, "ci95": list(interval)}


def _achieved_on_records(model: GapModelInput, diagnosis, records: list) -> float | None:
    """The shrinkage the selection achieves on fresh records (fitted, as :func:`measure` gives them): each predicted by indirect inference (or in the
    time domain for steer friction), against the nominal model, residuals over the data and parameters'
    standard uncertainty as in the held-out shrinkage it is compared with."""
    from bikerider.gap.diagnosis.compare import time_domain_ready
    from bikerider.gap.diagnosis.result import diagnose
    from bikerider.gap.diagnosis.statistics import gap_shrink

    try:
        check = diagnose(model, EigenvalueData.empty(), CanonicalData.empty(), effects=(), records=records)
    except InputError:
        return None
    p = check.problem
    if "steer_friction" in diagnosis.selected:
        if not time_domain_ready(check, p):  # the diagnosis holds the records and their rows as compared
            return None
        after = check.fits.time_domain_predict(diagnosis.selected_fit, np.ones(len(p.obs), bool))
    else:
        after = p.predict_batch(p.layout(diagnosis.selected_fit.effects), diagnosis.selected_fit.values[None, :])[0]
    if not np.all(np.isfinite(after)):
        return None
    return gap_shrink(p.z(p.baseline), p.z(after))


CALIBRATION_FRICTION = CalibrationEffect("steer_friction_records", "steer_friction", ("T_coulomb",), rider="riderless")
"""Pure Coulomb steer friction diagnosed from records (fitted in the time domain), riderless under :data:`SIL`."""
CALIBRATION_RECORDS = RecordProtocol(speeds=(2.5, 3.5, 4.5), per_speed=3)
"""Short records of the friction trials: three speeds of three records, 1.2-2.5 s each."""


def run_friction_trial(model: GapModelInput, seed: int, protocol: RecordProtocol = CALIBRATION_RECORDS) -> Trial:
    """A record trial: pure Coulomb friction drawn over its prior, simulated in time, diagnosed from records.

    The fitted split (``T_coulomb``, ``c_viscous``) is scored against the truth (``c_viscous`` 0), and the
    equivalent viscous damping (:meth:`bikerider.gap.diagnosis.priors.Priors.friction_equivalent`) against
    the truth's own (:func:`truth_equivalent`) at the same median amplitude ``A``.  The truth's friction corner
    is drawn over the range the fits assume (:func:`draw_corner`).
    """
    from dataclasses import replace

    from bikerider.gap.candidates.effects import EFFECTS
    from bikerider.gap.diagnosis.result import diagnose
    from bikerider.gap.measured.records import fit_records

    start = time.perf_counter()
    model = replace(model, plausible={**STEER_MOTOR, **model.plausible})
    rng = np.random.default_rng(seed)
    effect = CALIBRATION_FRICTION
    prior = next(p for p in EFFECTS["steer_friction"].parameters if p.name == "T_coulomb").the_prior()
    T = prior.sample(rng, CALIBRATION_DRAW.get(prior.kind, 0.95))
    eps = draw_corner(seed)
    truth = Truth(effect.name, ("steer_friction",), {"T_coulomb": T, "eps_coulomb": eps}, f"T_coulomb {T:.3g}")
    simulator = TruthSimulator(model, truth, rng)
    fits = fit_records(measure_records(simulator, protocol, rng))
    diagnosis = diagnose(model, EigenvalueData.empty(), CanonicalData.empty(), records=fits)
    result = diagnosis.as_dict()
    fitted: dict[str, dict] = {}
    reference = {"T_coulomb": T, "c_viscous": 0.0}
    amplitude = None
    if "steer_friction" in diagnosis.candidates:
        fit = diagnosis.fit_of(("steer_friction",))
        for k, name in enumerate(fit.names):
            fitted[name] = {"value": float(fit.values[k]), "ci95": [float(fit.ci_low[k]), float(fit.ci_high[k])]}
        eq = diagnosis.priors.friction_equivalent(fit)
        if eq is not None:
            amplitude = eq["amplitude"]
            fitted["c_equivalent"] = {"value": eq["c_equivalent"], "ci95": eq["ci95"], "separable": eq["separable"]}
            reference["c_equivalent"] = truth_equivalent(truth, amplitude)
    ranking = result["ranking"]
    how = result["how_far"] or {}
    return Trial(
        effect.name,
        effect.candidate,
        seed,
        False,
        truth.values,
        result["verdict"],
        ranking[0]["effect"] if ranking else None,
        list(ranking[0]["tied_with"]) if ranking else [],
        list(diagnosis.selected),
        fitted,
        reference,
        how.get("data_shrink"),
        None,
        len(diagnosis.record_rows),
        time.perf_counter() - start,
        amplitude,
        "records",
    )
