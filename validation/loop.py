"""The closed measure-diagnose-plan loop against a hidden truth (issue 25): does following the plan
need fewer runs than spreading them evenly?

One *case*: a hidden effect with sizes drawn over its prior (:func:`validation.cases.draw_truth`), on the
bicycle with or without rider, measured by a narrow protocol (:data:`NARROW`: six runs near one speed in
two sessions, one under a stabilising control) and simulated by the independent truth
(:class:`validation.cases.TruthSimulator`: Meijaard's Appendix A typed in by hand, nonlinear effects,
Coulomb friction in time, LSODA, noise, the weave fitted from the noisy roll rate).  The diagnosis is
given the hidden effect's candidate and a rival that often stands in for it (:data:`SCENARIOS`); a case
counts when the diagnosis ties them.  Then ``bikerider gap --next`` (:class:`NextExperiment`, public
attributes only) plans once, which gives the experiments (decays at speeds under control laws, and
steer-torque multisines), each rival's predictions and the noise of one run; and the loop runs.

The inner loop must be cheap, so each rival is *linearised* at its fit to the tie's data: its
predictions of every experiment and their slopes in its fitted values, by secants through the same public model code the diagnosis
uses (:class:`bikerider.gap.inference.predict.Predictor` for decays,
:meth:`bikerider.gap.candidates.effect_model.EffectModel.state_space` for multisines).  The rival's
values then have a Gaussian prior (its fit's covariance, each value's spread capped at that of a value
anywhere in its search range), every new run updates it exactly as a refit of the linearised model would (a Kalman step), and
the rival's log evidence grows by the predictive density of the run (a run every rival misses beyond its
noise is down-weighted first, :func:`lack_of_fit`).  The nominal parameters' uncertainty is counted per
run, as the plan and the diagnosis count it.  Posterior model probabilities start even at the tie.  A strategy stops when the hidden effect's probability reaches
:data:`DECIDED` (*resolved*), when the rival's does (*wrong*), when it has spent :data:`N_MAX` runs
(*undecided*), or, for the plan, when it declares the tie unbreakable (no allocation of the runs
left over the experiments, the evidence of their runs adding up, promises a resolution with probability
:data:`HOPELESS` or more; :func:`best_chance`).  The first run that every rival misses beyond chance
(:data:`NEITHER_P`) is noted (``neither``): a decision after it is between two models the data reject,
which the diagnosis, run on the new records with every candidate, would say.

One new run per step is simulated by the truth: a decay (a random kick, 6 s, the weave fitted from the
noisy roll rate) or a multisine (:func:`multisine_run`: a Schroeder multisine of steer torque added to
the control law, the motor's total torque saturating at :data:`MOTOR_LIMIT`, the truth's own Coulomb
friction, a settling time, then one period of roll rate or steer angle with sensor noise, read as the
frequency response at the lines).  The same experiment's k-th run is the same simulated run for every
strategy (common random numbers).

Strategies: ``plan:<criterion>`` (the next run where the criterion of
:mod:`bikerider.gap.plan.criteria` is largest, with the rivals' predictions and probabilities as the loop
has updated them; ``plan:jensen_renyi``'s first run is the next run ``--next`` names,
:mod:`bikerider.gap.plan.sequential`), ``even`` (decays under the laws in turn at speeds spread evenly over the feasible
range, a van der Corput order), ``random`` (any feasible experiment), ``repeat:decay`` and
``repeat:sweep`` (the plan's best decay, or best multisine, repeated: what ``--next`` recommends,
whose predicted resolution probability after ``k`` runs is stored for the reliability diagrams, ``predicted``,
the probability the plan states, beside its Gaussian approximation, ``predicted_gaussian``; these two run on
past their decision to :data:`N_MAX` runs and store the hidden effect's probability after every run,
``posterior``, so that the plan's probability of ``k`` runs is scored at ``k`` runs).

The records mode (``run_loop_case(..., records=True)``, :data:`RECORD_SCENARIOS`: the friction pairs): the
tie's data are records (:data:`RECORD_NARROW`, the truth's noisy roll rate of each kicked run, fitted by the
record fit), the friction truths' candidate is the steer friction fitted in time (:data:`RECORD_CANDIDATES`),
nonlinear, so the plan also plans each decay at other pushes (:data:`bikerider.gap.plan.ranking.PUSHES`).  The
rivals' predictions are the plan's own (templates at each push, indirect inference, the friction simulated in
time), linear through the plan's secants (:func:`from_plan`); a decay run is the truth's kick, drawn as the
data's, times the experiment's push, read by the record fit (:func:`validation.cases.measure` with records,
``Protocol.push``).  The even spread decays at the data's push.  Beside the loop each case stores the next run
``--next`` names and the one the table loop's plan names on the same runs (their fits as a table).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.stats import chi2 as chi2_dist

from bikerider.errors import FitError, InputError
from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.diagnosis.result import diagnose
from bikerider.gap.inference.predict import Predictor
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
from bikerider.gap.plan import allocation as A
from bikerider.gap.plan import criteria as C
from bikerider.gap.plan.discrimination import gaussian_probability
from bikerider.gap.plan.ranking import ASSUMED_NOISE, NextExperiment, NoExperiment, plan_next, planned_rows
from bikerider.gap.plan.sweeps import line_amplitude, response, split
from validation.cases import CONTROL, CalibrationEffect, Protocol, Session, TruthSimulator, draw_truth, measure

N_MAX = 20
"""Runs a strategy may spend after the tie."""
DECIDED = 0.95
"""Posterior probability of one rival that decides the tie."""
HOPELESS = 0.05
"""The plan declares a tie unbreakable when no allocation of the runs left over the experiments (greedy,
:func:`bikerider.gap.plan.allocation.allocate`) resolves it with at least this probability (the plan's own
measure, ``Phi(d / 2 - ln(odds) / d)``, with ``d`` of the runs combined)."""
NEITHER_P = 1e-3
"""A run whose best rival's chi-square (its own uncertainty and the run's noise, :func:`misfit`) exceeds this
upper quantile of the chi-square distribution with as many degrees of freedom as the run has numbers is one no
rival describes: in the tables-mode multisines of a friction truth (its rival the viscous damping that acts
as the friction at the decays' amplitude), chi-square 75 to 16000 on 18 numbers."""
MOTOR_LIMIT = 2.0
"""Largest steer torque the steer motor gives (control plus multisine) [N m]."""
GYRO_NOISE = 0.01
"""Roll-rate noise of a multisine run [rad/s] (as the decays')."""
STEER_NOISE = ASSUMED_NOISE["steer_angle"]
"""Steer-angle noise of a multisine run [rad] (a 13-bit encoder's quantisation)."""
RATE = 100.0
"""Sampling rate of a multisine run [Hz]."""

NARROW = {
    "rider": Protocol((Session("day1", (6.0, 6.5, 7.0)), Session("day2-controlled", (6.0, 6.5, 7.0), CONTROL))),
    "riderless": Protocol((Session("day1", (5.0, 5.5, 6.0)), Session("day2-controlled", (4.5, 5.0, 5.5), CONTROL))),
}
"""The tie's data: six runs near one speed in two sessions, one under a stabilising control."""

RECORD_NARROW = {
    "rider": Protocol(
        (
            Session("day1", (6.0, 6.5, 7.0)),
            Session("day2", (6.0, 6.5, 7.0)),
            Session("day3-controlled", (6.0, 6.5, 7.0), CONTROL),
        )
    ),
    "riderless": Protocol(
        (
            Session("day1", (5.0, 5.5, 6.0)),
            Session("day2", (5.0, 5.5, 6.0)),
            Session("day3-controlled", (4.5, 5.0, 5.5), CONTROL),
        )
    ),
}
"""The records mode's tie data: nine runs near one speed in three sessions (one under the stabilising control), as
part 4's trials have three sessions: the steer friction fitted in time gets its covariance from the jackknife
over the held-out sessions, which needs three or more and sees the scatter between sessions (with two, as
:data:`NARROW`, it had no standard errors when this study was run, and the plan took each value's spread as its whole
search range; the fallback since, the fit's own covariance, does not see that scatter)."""


@dataclass(frozen=True)
class Scenario:
    """A hidden effect (sizes over its prior), the candidate standing for it, its rival, the bicycle."""

    effect: CalibrationEffect
    rival: str
    rider: bool

    @property
    def label(self) -> str:
        return f"{self.effect.name} vs {self.rival} ({'rider' if self.rider else 'riderless'})"


def _effect(name: str, candidate: str, sizes: tuple[str, ...], fixed: dict | None = None) -> CalibrationEffect:
    return CalibrationEffect(name, candidate, sizes, fixed or {})


LEAN = _effect("rider_lean", "rider_lean", ("k_lean", "c_lean"))
TYRES = _effect("tyre_slip", "tyre_slip", ("c_alpha", "sigma_t", "t_p"), {"c_gamma": 0.8, "mu": 1.0})
INERTIA = _effect("steer_inertia", "steer_inertia", ("I_steer",))
ARMS = _effect("passive_arms", "passive_arms", ("m_arm", "k_arm", "c_arm"))
DAMPING = _effect("steer_damping", "steer_damping", ("c_steer",))
FRICTION = _effect("steer_friction", "steer_damping", ("c_steer", "T_coulomb"))
COULOMB = _effect("steer_coulomb", "steer_damping", ("T_coulomb",))
STIFFNESS = _effect("steer_stiffness", "steer_stiffness", ("k_steer",))

SCENARIOS: tuple[Scenario, ...] = (
    Scenario(LEAN, "tyre_slip", True),
    Scenario(TYRES, "rider_lean", True),
    Scenario(INERTIA, "passive_arms", True),
    Scenario(ARMS, "steer_inertia", True),
    Scenario(TYRES, "passive_arms", True),
    Scenario(FRICTION, "passive_arms", True),
    Scenario(DAMPING, "steer_inertia", False),
    Scenario(INERTIA, "steer_damping", False),
    Scenario(COULOMB, "steer_inertia", False),
    Scenario(TYRES, "steer_inertia", False),
    Scenario(STIFFNESS, "steer_inertia", False),
    Scenario(FRICTION, "tyre_slip", False),
)
"""Hidden effect and the rival that often ties with it (the ties of part 3 and the usual confusions)."""

STRATEGIES = tuple(f"plan:{c}" for c in C.CRITERIA) + ("even", "random", "repeat:decay", "repeat:sweep")

RECORD_CANDIDATES = {"steer_friction": "steer_friction", "steer_coulomb": "steer_friction"}
"""The records mode: the candidate standing for a friction truth, the steer friction fitted in time (viscous and
Coulomb; nonlinear, so the plan plans pushes for it), where tables have only the viscous ``steer_damping``."""
RECORD_SCENARIOS: tuple[Scenario, ...] = tuple(s for s in SCENARIOS if s.effect.name in RECORD_CANDIDATES)
"""The friction pairs the records mode runs (Coulomb friction makes a decay depend on its push)."""
RECORD_SIGNALS = ("roll_rate",)
"""The signal the records mode's decays are fitted from (the tie's records log the roll rate only)."""
RECORD_STRATEGIES = ("plan:jensen_renyi", "even")
"""The records mode's strategies: the next run ``--next`` names, and the even spread (at the data's push)."""


# -- the truth's multisine run --------------------------------------------------------------------------
def multisine_run(simulator: TruthSimulator, speed: float, gains, sweep, rng: np.random.Generator, settle: float):
    """One steer-torque multisine run of the truth: the frequency response at the sweep's lines
    (``(K,)`` complex), or ``None`` when the bicycle falls.

    The torque ``sum_k a cos(w_k t + phi_k)`` (Schroeder phases, peak ``sweep.torque``) adds to the control
    law's; the motor saturates their sum at :data:`MOTOR_LIMIT`.  The truth's passive torques (its Coulomb
    friction too) act as in its decays.  After ``settle`` seconds one period (``sweep.run_time``) is
    recorded at :data:`RATE` with sensor noise; the response is the DFT at the lines over the torque's.
    """
    zero = np.zeros(4)
    f0, n, idx = simulator.rhs(speed, zero)
    f1, _, _ = simulator.rhs(speed, np.array([1.0, 0.0, 0.0, 0.0]))
    x = np.zeros(n)
    x[idx[0]] = 1.0
    b = f1(0.0, x) - f0(0.0, x)  # what one newton metre of steer torque does (the torque enters linearly)
    gains = np.asarray(gains, float)
    lines = np.asarray(sweep.lines, float)
    K = lines.size
    omegas = 2 * math.pi * lines
    phases = -math.pi * np.arange(1, K + 1) * np.arange(K) / K
    a = line_amplitude(lines, sweep.torque, sweep.run_time)

    def f(t, s):
        u = a * float(np.sum(np.cos(omegas * t + phases)))
        control = gains @ np.array([s[idx[0]], s[idx[2]], s[idx[1]], s[idx[3]]])
        return f0(t, s) + b * min(max(control + u, -MOTOR_LIMIT), MOTOR_LIMIT)

    def fall(_, s):
        return abs(s[idx[0]]) - 0.5

    fall.terminal = True
    end = settle + sweep.run_time
    times = settle + np.arange(int(round(sweep.run_time * RATE))) / RATE
    sol = solve_ivp(f, (0.0, end), np.zeros(n), t_eval=times, method="LSODA", rtol=1e-6, atol=1e-8, events=fall)
    if sol.status != 0 or sol.t.size != times.size:
        return None
    if sweep.output == "roll_rate":
        y = sol.y[idx[2]] + GYRO_NOISE * rng.standard_normal(times.size)
    else:
        y = sol.y[idx[1]] + STEER_NOISE * rng.standard_normal(times.size)
    Y = 2.0 / times.size * np.exp(-1j * np.outer(omegas, times)) @ y
    return Y / (a * np.exp(1j * phases))


# -- the rivals, linearised -------------------------------------------------------------------------------
class LinearRival:
    """A rival's predictions of every experiment, linear in its fitted values ``z``, with a Gaussian prior on
    ``z`` that the runs update, and the log evidence of the runs so far."""

    def __init__(
        self,
        mean: list[np.ndarray],
        jac: list[np.ndarray],
        prior: np.ndarray,
        own: int | None = None,
        extra: list[np.ndarray | None] | None = None,
    ):
        self.mean, self.jac = mean, jac
        self.extra = extra
        """Per experiment, a covariance added to the prediction's that no run shrinks (``None``: none): the
        friction law's form of a nonlinear rival's multisine, as the plan counts it, and a decay's spread over
        the kick's unknown initial steer rate (:func:`from_plan`)."""
        self.a = np.zeros(prior.shape[0])
        self.P = prior.copy()
        self.log_evidence = 0.0
        self.own = prior.shape[0] if own is None else own
        """How many of ``z`` are the rival's own fitted values (the rest: shared nominal-parameter shifts)."""

    def predict(self, e: int, own_only: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Mean and covariance of the rival's prediction of experiment ``e`` (``own_only``: the covariance from
        its own values alone, which the runs shrink; the shared shifts' part they do not)."""
        J = self.jac[e]
        fixed = 0.0 if self.extra is None or self.extra[e] is None else self.extra[e]
        if own_only:
            k = self.own
            return self.mean[e] + J @ self.a, J[:, :k] @ self.P[:k, :k] @ J[:, :k].T
        return self.mean[e] + J @ self.a, J @ self.P @ J.T + fixed

    def update(self, e: int, y: np.ndarray, R: np.ndarray) -> None:
        mu, W = self.predict(e)
        S = W + R
        r = y - mu
        sol = np.linalg.solve(S, r)
        _, logdet = np.linalg.slogdet(S)
        self.log_evidence += -0.5 * (r @ sol + logdet + r.size * math.log(2 * math.pi))
        J = self.jac[e]
        gain = np.linalg.solve(S, J @ self.P).T  # P J^T S^-1
        self.a = self.a + gain @ r
        self.P = self.P - gain @ J @ self.P
        self.P = (self.P + self.P.T) / 2


def _rows(plan: NextExperiment) -> EigenvalueData:
    return planned_rows(plan.points, plan.laws)


def _predictions(plan: NextExperiment, effects: tuple[str, ...], X: np.ndarray, shared: bool = False) -> np.ndarray:
    """Every experiment's prediction ``(P, n_points * 2 + n_sweeps * 2K)`` for values ``X (P, p + q)`` (with
    ``shared``, the last ``q`` the nominal parameters' shifts in units of their uncertainty)."""
    p = plan.problem
    values, config, _ = p.configure(p.layout(tuple(effects) + (("parameters",) if shared else ())), X)
    model = EffectModel(values, p.geometry, config)
    P = X.shape[0]
    parts = []
    if plan.points:
        ev = Predictor(_rows(plan), CanonicalData.empty(), p.nominal, p.geometry).eigenvalues(model)
        ev = np.broadcast_to(ev, (P, len(plan.points)))
        parts.append(np.stack([ev.real, np.abs(ev.imag)], axis=-1).reshape(P, -1))
    if plan.sweeps:
        speeds = np.array([s.speed for s in plan.sweeps])
        gains = np.array([plan.laws[s.law](s.speed) for s in plan.sweeps]).reshape(len(speeds), 4)
        ss = model.state_space(speeds)
        A = np.broadcast_to(ss.closed_loop(gains), (P, len(speeds)) + ss.A.shape[-2:])
        b = np.broadcast_to(ss.B[..., :, 1], (P, len(speeds), ss.A.shape[-1]))
        omegas = np.array([s.omegas for s in plan.sweeps])
        roll = response(A, b, ss.output_states[2], omegas[None])
        steer = response(A, b, ss.output_states[1], omegas[None])
        is_roll = np.array([s.output == "roll_rate" for s in plan.sweeps])
        H = np.where(is_roll[None, :, None], roll, steer)
        parts.append(split(H).reshape(P, -1))
    return np.concatenate(parts, axis=-1)


def _unpack(plan: NextExperiment, flat: np.ndarray) -> list[np.ndarray]:
    """A flat prediction ``(..., total)`` per experiment: decays ``(..., 2)``, sweeps ``(..., 2K)``."""
    out = [flat[..., 2 * m : 2 * m + 2] for m in range(len(plan.points))]
    start = 2 * len(plan.points)
    for m, s in enumerate(plan.sweeps):
        K = len(s.lines)
        block = flat[..., start + 2 * K * m : start + 2 * K * (m + 1)]
        out.append(block)
    return out


def linearise(plan: NextExperiment, rival, shared: bool = False) -> LinearRival:
    """A rival of the plan, linearised at its fit (module docstring); with ``shared``, also in the nominal
    parameters' shifts (standard normal prior, one set for all runs: the truth's parameter error is the same
    in every run) instead of counting their uncertainty per run."""
    fit = rival.fit
    q = len(plan.problem.free) if shared else 0
    k = fit.values.size
    span = (np.asarray(fit.upper) - np.asarray(fit.lower)) / math.sqrt(12)
    cov = fit.covariance if fit.covariance is not None and np.all(np.isfinite(fit.covariance)) else None
    if cov is None or cov.shape != (k, k):
        stderr = np.where(np.isfinite(fit.stderr), fit.stderr, span)
        cov = np.diag(stderr**2)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    cap = np.where(sd > span, span / np.where(sd > 0, sd, 1.0), 1.0)
    cov = cov * cap[:, None] * cap[None, :]
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    h = np.where(sd > 0, sd, 1e-6 * np.maximum(span, 1.0))
    z0 = np.concatenate([fit.values, np.zeros(q)])
    X = [z0]
    for j in range(k + q):
        up, down = z0.copy(), z0.copy()
        if j < k:
            up[j] = min(z0[j] + h[j], fit.upper[j])
            down[j] = max(z0[j] - h[j], fit.lower[j])
        else:
            up[j], down[j] = 1.0, -1.0
        X += [up, down]
    X = np.array(X)
    pred = _predictions(plan, rival.effects, X, shared)
    width = X[1::2] - X[2::2]
    width = np.diagonal(width)
    slopes = ((pred[1::2] - pred[2::2]) / np.where(width > 0, width, np.inf)[:, None]).T  # (total, k + q)
    prior = np.zeros((k + q, k + q))
    prior[:k, :k] = cov
    prior[k:, k:] = np.eye(q)
    return LinearRival(_unpack(plan, pred[0]), [J.T for J in _unpack(plan, slopes.T)], prior, own=k)


def from_plan(plan: NextExperiment, k: int) -> LinearRival:
    """Rival ``k`` of a plan as the plan predicts it (the records mode): its predicted decays (the eigenvalue the
    record fit finds in its response over each experiment's template, at the experiment's push, by indirect
    inference; a nonlinear rival's response simulated in time with its friction) and multisines, linear in its
    fitted values through the plan's own secants: ``z ~ N(0, I)`` whitened by the fit's covariance, the plan's
    factor ``F`` (``own_cov = F F^T``) the slopes.  A nonlinear rival's multisines carry the friction law's form
    (``sweep_form``, part of the plan's ``sweep_own``) as a covariance no run shrinks, added to every run's; its
    decays the spread over the kick's unknown initial steer rate (``kick_cov``), added to every run's too (each
    run has a kick of its own), and a friction rival's spread over the corner of its friction law (``form_cov``,
    part of the plan's ``own_cov``), as the multisines' form.

    The predictions are the plan's own, not recomputed: the records' templates and indirect inference live
    in the plan (:class:`bikerider.gap.plan.ranking.NextExperiment`), as the table loop's eigenvalues live in the
    public :class:`~bikerider.gap.inference.predict.Predictor` it linearises through (:func:`linearise`).
    """
    q = plan.own_factor[k].shape[-1] if plan.points else plan.sweep_factor[k].shape[-1]
    mean: list[np.ndarray] = []
    jac: list[np.ndarray] = []
    extra: list[np.ndarray | None] = []
    flip = np.array([[1.0, -1.0], [-1.0, 1.0]])
    for m in range(len(plan.points)):
        z = complex(plan.mean[k, m])
        F = np.array(plan.own_factor[k][m], float).reshape(2, q)
        kick = None if plan.kick_cov is None else np.array(plan.kick_cov[k, m], float)
        form = getattr(plan, "form_cov", None)
        if form is not None:  # the friction law's corner: in own_cov, not in the secants' factor F
            kick = np.array(form[k, m], float) if kick is None else kick + form[k, m]
        if z.imag < 0:  # the loop reads the frequency as |imag| (as the table loop)
            F[1] = -F[1]
            kick = None if kick is None else kick * flip
        mean.append(np.array([z.real, abs(z.imag)]))
        jac.append(F)
        extra.append(kick)
    for m in range(len(plan.sweeps)):
        mean.append(split(plan.sweep_mean[k, m]))
        jac.append(np.array(plan.sweep_factor[k][m], float).reshape(-1, q))
        extra.append(np.array(plan.sweep_form[k, m], float))
    return LinearRival(mean, jac, np.eye(q), extra=extra)


# -- the loop ---------------------------------------------------------------------------------------
class TruthRuns:
    """The truth's runs, the k-th run of an experiment the same for every strategy."""

    def __init__(
        self, simulator: TruthSimulator, plan: NextExperiment, seed: int, shared: bool = False, records: bool = False
    ):
        self.simulator, self.plan, self.seed, self.shared = simulator, plan, seed, shared
        self.records = records
        """Decays are records: the truth's kicks scaled by the experiment's push, read by the record fit."""
        self.cache: dict[tuple[int, int], tuple[np.ndarray, np.ndarray] | None] = {}
        self.rows: dict[tuple[int, int], EigenvalueData] = {}  # the decays as the diagnosis reads them
        self.record_fits: dict[tuple[int, int], object] = {}  # with records, each decay's RecordFit
        self.seconds = {"decay": 0.0, "sweep": 0.0}
        self.count = {"decay": 0, "sweep": 0}

    def get(self, e: int, k: int):
        key = (e, k)
        if key not in self.cache:
            rng = np.random.default_rng([self.seed, e, k, 77])
            if self.records and e < len(self.plan.points):  # the pushes of one speed and law share their draws
                x = self.plan.points[e]
                law = list(self.plan.laws).index(x.law)
                rng = np.random.default_rng([self.seed, int(round(x.speed * 100)), law, k, 78])
            start = time.perf_counter()
            plan = self.plan
            if e < len(plan.points):
                x = plan.points[e]
                gains = tuple(float(g) for g in plan.laws[x.law](x.speed))
                # with records, the truth's kick scaled by the experiment's push and the run read by the
                # diagnosis's own record fit (measure's records path, fit_record); a table's decay has no push
                push = x.push if self.records else 1.0
                protocol = Protocol((Session("loop", (x.speed,), gains),), speed_jitter=0.0, push=push)
                fits: list | None = [] if self.records else None
                data, _ = measure(self.simulator, protocol, rng, None, fits)
                out = None
                if len(data):
                    self.rows[key] = data
                    if fits:
                        self.record_fits[key] = fits[0]
                    y = np.array([data.value[0].real, abs(data.value[0].imag)])
                    R = np.diag([data.real_sigma[0] ** 2, data.imag_sigma[0] ** 2])
                    if self.records:  # the plan's one-run noise with this run's own standard errors in place of
                        # the template's: the data's scatter from run to run beyond their fits' (as the diagnosis
                        # weighs a record by its cell's replicate scatter; Coulomb friction makes each kick decay
                        # its own way)
                        t = plan.templates[x].estimate
                        R = R + plan.data_cov[e] - np.diag([t.real_sigma**2, t.imag_sigma**2])
                    out = (y, R if self.shared else R + plan.model_cov[e])
                kind = "decay"
            else:
                m = e - len(plan.points)
                s = plan.sweeps[m]
                gains = plan.laws[s.law](s.speed)
                # the plan's settling time: until the slowest transient of the nominal loop and of every rival's
                # has died (sweeps.settle_time)
                H = multisine_run(self.simulator, s.speed, gains, s, rng, float(plan.sweep_settle[m]))
                R = plan.sweep_data[m] if self.shared else plan.sweep_data[m] + plan.sweep_model[m]
                out = None if H is None else (split(H), R)
                kind = "sweep"
            self.cache[key] = out
            self.seconds[kind] += time.perf_counter() - start
            self.count[kind] += 1
        return self.cache[key]


def _van_der_corput(k: int) -> float:
    x, denom = 0.0, 1.0
    while k:
        denom *= 2
        x += (k % 2) / denom
        k //= 2
    return x


def _even_order(plan: NextExperiment, n: int) -> list[int]:
    """Decays under the laws in turn at speeds spread evenly; with pushes planned (records), at the data's push
    (the researcher without a plan pushes as before)."""
    standard = [i for i, e in enumerate(plan.points) if getattr(e, "push", 1.0) == 1.0] or list(range(len(plan.points)))
    laws = list(dict.fromkeys(plan.points[i].law for i in standard))
    order = []
    for k in range(n):
        law = laws[k % len(laws)]
        idx = sorted((i for i in standard if plan.points[i].law == law), key=lambda i: plan.points[i].speed)
        j = k // len(laws)
        frac = _van_der_corput(j + 1)  # 1/2, 1/4, 3/4, 1/8, ...: every new run between those before
        order.append(idx[min(int(frac * len(idx)), len(idx) - 1)])
    return order


def _noise(plan: NextExperiment, e: int, shared: bool = False) -> np.ndarray:
    """One run's noise the plan expects (with the nominal parameters' uncertainty unless it is ``shared``)."""
    if e < len(plan.points):
        return plan.data_cov[e] + (0 if shared else plan.model_cov[e])
    m = e - len(plan.points)
    return plan.sweep_data[m] + (0 if shared else plan.sweep_model[m])


def _kick(rival: LinearRival, plan: NextExperiment, e: int) -> np.ndarray | float:
    """A decay's per-run spread over the kick's initial steer rate under ``rival`` (:func:`from_plan`), else 0."""
    if e >= len(plan.points) or rival.extra is None or rival.extra[e] is None:
        return 0.0
    return rival.extra[e]


def _groups(plan: NextExperiment) -> list[list[int]]:
    """Experiments with observations of the same size (decays; multisines), to score together."""
    decays = list(range(len(plan.points)))
    sweeps = list(range(len(plan.points), len(plan.points) + len(plan.sweeps)))
    return [g for g in (decays, sweeps) if g]


def _posterior(rivals: list[LinearRival]) -> np.ndarray:
    le = np.array([r.log_evidence for r in rivals])
    w = np.exp(le - le.max())
    return w / w.sum()


def _scores(plan, rivals, weights, criterion, groups, shared=False) -> np.ndarray:
    out = np.full(len(plan.points) + len(plan.sweeps), -np.inf)
    for g in groups:
        preds = [[r.predict(e) for e in g] for r in rivals]
        means = np.array([[m for m, _ in row] for row in preds])
        own = np.array([[W for _, W in row] for row in preds])
        noise = np.array([_noise(plan, e, shared) for e in g])
        out[g] = C.score(criterion, means, own, noise, weights)
    return out


def best_chance(plan, rivals, weights, runs_left: int, groups, shared=False) -> float:
    """The plan's resolution probability of the runs left spread over the experiments (a greedy allocation,
    :func:`bikerider.gap.plan.allocation.allocate`: the expected log Bayes factor of the runs combined, each
    rival's own values integrated over their uncertainty as the loop's evidence does), from the rivals as the loop has
    updated them (the odds needed from the current ones), stopping as soon as it reaches :data:`HOPELESS`;
    the shared shifts' uncertainty, common to both rivals' predictions, is left out, as the plan counts it
    per run.  Rivals fitted to the same predictions (both at the nominal model) differ in how their own
    uncertainty moves their predictions across experiments, which the old rule (one experiment repeated,
    the means' difference alone) could not see."""
    factors = []
    for r in rivals:
        k = r.own
        vals, vecs = np.linalg.eigh((r.P[:k, :k] + r.P[:k, :k].T) / 2)
        L = vecs * np.sqrt(np.clip(vals, 0.0, None))
        factors.append([np.array([r.jac[e][:, :k] @ L for e in g]) for g in groups])
    hypotheses = []
    for t in (0, 1):
        need = math.log(DECIDED / (1 - DECIDED)) + math.log(max(weights[1 - t], 1e-300) / max(weights[t], 1e-300))
        h = A.Hypothesis(0, float(weights[t]), need)
        for j, g in enumerate(groups):
            delta = np.array([rivals[t].predict(e)[0] - rivals[1 - t].predict(e)[0] for e in g])
            # a decay's spread over the kick's initial steer rate is per run, with the true rival's noise
            noise = np.array([_noise(plan, e) + _kick(rivals[t], plan, e) for e in g])
            h.groups.append((delta, factors[t][j], factors[1 - t][j], noise, np.zeros_like(noise)))
        hypotheses.append(h)
    return A.allocate(hypotheses, runs_left, HOPELESS, draws=400).probability


def misfit(rivals: list[LinearRival], e: int, y: np.ndarray, R: np.ndarray) -> float:
    """The best rival's chi-square of a run: its residual against the rival's prediction weighed by the run's
    noise ``R`` and the rival's own uncertainty."""
    chi2 = []
    for r in rivals:
        mu, W = r.predict(e)
        res = y - mu
        chi2.append(float(res @ np.linalg.solve(W + R, res)))
    return min(chi2)


def lack_of_fit(chi2: float, numbers: int) -> float:
    """How far the best rival misses a run beyond its noise and its own uncertainty, chi-square per
    observed number, at least 1 (a Birge ratio): a run that every rival misses alike (the truth is none of
    them there: parameter error, a rider's geometry, friction) is down-weighted by it, as the diagnosis
    scales its errors by the lack of fit, instead of handing the tie to the rival whose own uncertainty
    happens to be wider.  ``chi2`` is the best rival's (:func:`misfit`), ``numbers`` the run's."""
    return max(1.0, chi2 / numbers)


def _learn(rivals: list, e: int, obs) -> float | None:
    """Every rival updated with a run ``obs`` ``(y, R)`` of experiment ``e``, its noise ``R`` inflated by the
    rivals' lack of fit to it (:func:`lack_of_fit`); returns that misfit's chi-square (:func:`misfit`), or
    ``None`` where the run gave nothing (the bicycle fell, no weave fitted)."""
    if obs is None:
        return None
    y, R = obs
    chi2 = misfit(rivals, e, y, R)
    R = R * lack_of_fit(chi2, y.size)
    for r in rivals:
        r.update(e, y, R)
    return chi2


def run_strategy(name: str, plan, rivals_at_tie, runs: TruthRuns, truth_index: int, seed: int, repeat=None) -> dict:
    """One strategy's loop (module docstring): its runs, the hidden effect's probability after each."""
    rivals = [LinearRival(r.mean, r.jac, r.P, r.own, r.extra) for r in rivals_at_tie]
    shared = runs.shared
    groups = _groups(plan)
    n_exp = len(plan.points) + len(plan.sweeps)
    rng = np.random.default_rng([seed, 991])
    even = _even_order(plan, 4 * N_MAX) if name == "even" else None
    used: dict[int, int] = {}
    failed: set[int] = set()  # experiments whose run fell or gave no weave: not tried again (but by repeat:)
    chosen, trajectory, posterior = [], [], []
    cursor = 0
    status, lost = "undecided", 0
    neither = None  # the first run no rival describes (NEITHER_P)
    for step in range(N_MAX):
        if status != "undecided":  # a repeat strategy runs on after its decision (``posterior``)
            _learn(rivals, repeat, runs.get(repeat, used.get(repeat, 0)))
            used[repeat] = used.get(repeat, 0) + 1
            posterior.append(round(float(_posterior(rivals)[truth_index]), 5))
            continue
        weights = _posterior(rivals)
        if name.startswith("plan:"):
            if best_chance(plan, rivals, weights, N_MAX - step, groups, shared) < HOPELESS:
                status = "unbreakable"
                break
            scores = _scores(plan, rivals, weights, name.split(":", 1)[1], groups, shared)
            scores[list(failed)] = -np.inf
            e = int(np.argmax(scores))
        elif name == "even":
            while even[cursor % len(even)] in failed and len(failed) < len(plan.points):
                cursor += 1
            e = even[cursor % len(even)]
            cursor += 1
        elif name == "random":
            left = [i for i in range(n_exp) if i not in failed]
            e = int(left[rng.integers(len(left))])
        else:
            e = repeat
        k = used.get(e, 0)
        used[e] = k + 1
        obs = runs.get(e, k)
        chosen.append(e)
        chi2 = _learn(rivals, e, obs)
        if chi2 is None:  # the bicycle fell or no weave was fitted: a run spent, nothing learnt
            lost += 1
            failed.add(e)
        elif neither is None and chi2 > float(chi2_dist.ppf(1.0 - NEITHER_P, obs[0].size)):
            neither = {"run": len(chosen), "chi2": round(chi2, 2), "numbers": int(obs[0].size)}
        pi = _posterior(rivals)
        trajectory.append(round(float(pi[truth_index]), 5))
        if pi[truth_index] >= DECIDED:
            status = "resolved"
        elif pi[1 - truth_index] >= DECIDED:
            status = "wrong"
        if status != "undecided":
            if repeat is None:
                break
            posterior = list(trajectory)
    out = {
        "status": status,
        "runs": len(chosen),
        "chosen": chosen,
        "truth_probability": trajectory,
        "lost": lost,
        "neither": neither,
    }
    if repeat is not None:  # the hidden effect's probability after each of N_MAX runs, on past a decision
        out["posterior"] = posterior if status != "undecided" else list(trajectory)
    return out


def run_loop_case(
    models: dict,
    scenario: Scenario,
    seed: int,
    strategies=None,
    keep: bool = False,
    shared: bool = False,
    records: bool = False,
) -> dict:
    """One case (module docstring), JSON-ready (with ``keep``, also the objects under ``_objects``; ``shared``:
    the nominal parameters' uncertainty shared by all runs, :func:`linearise`; ``records``: the records mode,
    :data:`RECORD_SCENARIOS`).  ``strategies`` default to :data:`STRATEGIES` (:data:`RECORD_STRATEGIES` with
    records)."""
    if records and shared:
        raise ValueError("the records mode counts the nominal parameters' uncertainty per run (shared=False)")
    if strategies is None:
        strategies = RECORD_STRATEGIES if records else STRATEGIES
    start = time.perf_counter()
    rng = np.random.default_rng(seed)
    model = models["rider" if scenario.rider else "riderless"]
    truth = draw_truth(scenario.effect, rng)
    simulator = TruthSimulator(model, truth, rng)
    fits: list | None = [] if records else None  # the same runs either way (measure's draws do not depend on it)
    protocols = RECORD_NARROW if records else NARROW
    data, _ = measure(simulator, protocols["rider" if scenario.rider else "riderless"], rng, None, fits)
    candidate = RECORD_CANDIDATES.get(scenario.effect.name, scenario.effect.candidate) if records else None
    candidate = candidate or scenario.effect.candidate
    out = {
        "shared": shared,
        "data": "records" if records else "tables",
        "scenario": scenario.label,
        "truth": scenario.effect.name,
        "candidate": candidate,
        "rival": scenario.rival,
        "rider": scenario.rider,
        "seed": seed,
        "sizes": {k: float(v) for k, v in truth.values.items()},
        "n_data": len(data),
    }
    if len(data) < 4:
        return {**out, "tie": False, "status": "too few runs", "seconds": time.perf_counter() - start}
    rivals = (candidate, scenario.rival)
    try:
        if records:
            diagnosis = diagnose(model, EigenvalueData.empty(), CanonicalData.empty(), records=fits, effects=rivals)
        else:
            diagnosis = diagnose(model, data, CanonicalData.empty(), effects=rivals)
    except (FitError, InputError) as exc:
        return {**out, "tie": False, "status": f"diagnosis failed: {exc}", "seconds": time.perf_counter() - start}
    first = diagnosis.ranking[0] if diagnosis.ranking else None
    out["first"] = first["effect"] if first else None
    out["tie"] = bool(first and first["tied_with"])
    if not out["tie"]:
        out["status"] = "no tie"
        out["seconds"] = time.perf_counter() - start
        return out
    t_diag = time.perf_counter()
    try:
        signals = RECORD_SIGNALS if records else None
        plan = plan_next(diagnosis, rivals=list(rivals), repeats=10, sweeps=True, signals=signals)
    except (NoExperiment, InputError, FitError) as exc:
        return {**out, "status": f"no plan: {exc}", "seconds": time.perf_counter() - start}
    t_plan = time.perf_counter()
    if records:
        lin = [from_plan(plan, k) for k in range(len(plan.rivals))]
    else:
        lin = [linearise(plan, r, shared) for r in plan.rivals]
    names = [r.name for r in plan.rivals]
    truth_index = names.index(candidate)
    if records:
        out.update(_record_extras(models, scenario, plan, data, lin))
    # the linearised rivals reproduce the plan's own predictions at the fit
    check = []
    for k, r in enumerate(lin):
        if plan.points:
            mine = np.array([r.mean[m] for m in range(len(plan.points))])
            theirs = np.stack([plan.mean[k].real, np.abs(plan.mean[k].imag)], axis=-1)
            check.append(float(np.max(np.abs(mine - theirs))))
        if plan.sweeps:
            mine = np.array([r.mean[len(plan.points) + m] for m in range(len(plan.sweeps))])
            check.append(float(np.max(np.abs(mine - split(plan.sweep_mean[k])))))
    n_points = len(plan.points)
    best = {"decay": None, "sweep": None}
    for item in plan.plan:
        kind = item["experiment"].kind
        if best[kind] is None:
            best[kind] = plan.experiments.index(item["experiment"])
    predicted, gaussian = {}, {}
    for kind, m in best.items():
        if m is not None:
            predicted[kind] = [round(float(plan.probability(float(k)).min(axis=0)[m]), 5) for k in range(1, N_MAX + 1)]
            gaussian[kind] = [
                round(float(gaussian_probability(plan, float(k)).min(axis=0)[m]), 5) for k in range(1, N_MAX + 1)
            ]
    out.update(
        status="loop",
        experiments={"decays": n_points, "sweeps": len(plan.sweeps)},
        plan_top=plan.plan[0]["text"],
        plan_top_probability=plan.plan[0]["resolution_probability"],
        best={k: (None if m is None else plan.experiments[m].describe()) for k, m in best.items()},
        predicted=predicted,
        predicted_gaussian=gaussian,
        linearisation_error=max(check) if check else None,
        sweeps_left_out_lean=sum("would likely be lost" in x["reason"] for x in plan.left_out),
        truth_index=truth_index,
    )
    runs = TruthRuns(simulator, plan, seed, shared, records)
    results = {}
    for name in strategies:
        if name.startswith("repeat:"):
            m = best[name.split(":", 1)[1]]
            if m is None:
                continue
            results[name] = run_strategy(name, plan, lin, runs, truth_index, seed, repeat=m)
        else:
            results[name] = run_strategy(name, plan, lin, runs, truth_index, seed)
    out["strategies"] = results
    jr = results.get("plan:jensen_renyi")
    if jr and jr["chosen"] and plan.next_run is not None:  # the loop's first choice is the next run --next names
        out["first_is_next_run"] = jr["chosen"][0] == plan.next_run["index"]
    out["truth_runs"] = {"count": runs.count, "seconds": {k: round(v, 3) for k, v in runs.seconds.items()}}
    out["seconds_setup"] = {"diagnosis": round(t_diag - start, 3), "plan": round(t_plan - t_diag, 3)}
    out["seconds"] = time.perf_counter() - start
    if keep:
        out["_objects"] = {"model": model, "data": data, "runs": runs, "rivals": rivals, "plan": plan, "linear": lin}
    return out


def _first(plan: NextExperiment) -> dict | None:
    """The next run ``--next`` names for ``plan`` (its kind, speed, law and push), JSON-ready."""
    x = plan.next_run
    if x is None:
        return None
    return {"kind": x["kind"], "speed": x["speed"], "law": x["law"], "push": x["push"], "text": x["text"]}


def _record_extras(models: dict, scenario: Scenario, plan: NextExperiment, data: EigenvalueData, lin) -> dict:
    """What the records mode stores beside the loop: each planned decay's push, the plan's covariances as the
    linearised rivals give them back (``own_cov_error``, relative), the next run ``--next`` names and the one
    the table loop's plan names on the same runs (their fitted eigenvalues as a table, the table loop's
    candidate and rival: :func:`run_loop_case` without records)."""
    worst = 0.0
    for k, r in enumerate(lin):
        for m in range(len(plan.points)):
            mine = r.predict(m)[1]
            theirs = np.array(plan.own_cov[k, m]) + (0.0 if plan.kick_cov is None else plan.kick_cov[k, m])
            if plan.mean[k, m].imag < 0:
                theirs = theirs * np.array([[1, -1], [-1, 1]])
            worst = max(worst, float(np.max(np.abs(mine - theirs)) / max(np.max(np.abs(theirs)), 1e-300)))
        for m in range(len(plan.sweeps)):
            mine = r.predict(len(plan.points) + m)[1]
            theirs = np.array(plan.sweep_own[k, m])
            worst = max(worst, float(np.max(np.abs(mine - theirs)) / max(np.max(np.abs(theirs)), 1e-300)))
    out = {"pushes": [float(e.push) for e in plan.points], "own_cov_error": worst, "first": _first(plan)}
    model = models["rider" if scenario.rider else "riderless"]
    try:
        table = diagnose(model, data, CanonicalData.empty(), effects=(scenario.effect.candidate, scenario.rival))
        other = plan_next(table, rivals=[scenario.effect.candidate, scenario.rival], repeats=10, sweeps=True)
        out["table_first"] = _first(other)
        out["table_tie"] = bool(table.ranking and table.ranking[0]["tied_with"])
    except (NoExperiment, InputError, FitError) as exc:
        out["table_first"] = None
        out["table_error"] = str(exc)
    return out


def diagnosis_check(models: dict, scenario: Scenario, seed: int, strategy: str = "even") -> dict:
    """The case again (the same runs), and the diagnosis itself on the tie's data plus the decays the
    strategy took: does the diagnosis (its priors, its held-out tie rule) decide as the loop did?
    Multisines the strategy took are left out (the diagnosis reads no frequency responses)."""
    out = run_loop_case(models, scenario, seed, strategies=(strategy,), keep=True)
    if "_objects" not in out:
        return {"scenario": scenario.label, "seed": seed, "status": out["status"]}
    o = out.pop("_objects")
    s = out["strategies"][strategy]
    seen: dict[int, int] = {}
    rows = []
    for e in s["chosen"]:
        k = seen.get(e, 0)
        seen[e] = k + 1
        if (e, k) in o["runs"].rows:
            rows.append(o["runs"].rows[(e, k)])
    check = {"scenario": scenario.label, "seed": seed, "strategy": strategy, "loop": s["status"], "runs": s["runs"]}
    check["decays_used"] = len(rows)
    if not rows:
        return check
    data = EigenvalueData.concatenate([o["data"], *rows])
    d = diagnose(o["model"], data, CanonicalData.empty(), effects=o["rivals"])
    first = d.ranking[0] if d.ranking else None
    check["diagnosis_first"] = first["effect"] if first else None
    check["diagnosis_tied"] = list(first["tied_with"]) if first else []
    check["hidden"] = scenario.effect.candidate
    return check


def figure_of_merit(runs: list[int | None]) -> tuple[float, float]:
    """Median and 90th percentile of the runs needed (``None``: not resolved within :data:`N_MAX`,
    counted as more than it)."""
    x = np.array([math.inf if r is None else r for r in runs], float)
    if not x.size:
        return math.nan, math.nan
    return float(np.quantile(x, 0.5, method="inverted_cdf")), float(np.quantile(x, 0.9, method="inverted_cdf"))


def push_check(models: dict, scenario: Scenario, seed: int, groups: int = 4) -> dict:
    """A records case again (the same runs) and, at up to ``groups`` speeds and laws where the plan holds a decay
    at every push, the truth's first run at each push against the rivals' predictions of it: does the plan
    foresee how the truth's decay moves with the push?  JSON-ready: per run the push, the truth's observation,
    its weight and each rival's predictive mean and standard deviations (real part, frequency)."""
    case = run_loop_case(models, scenario, seed, strategies=(), keep=True, records=True)
    out = {"scenario": scenario.label, "seed": seed, "status": case["status"], "sizes": case["sizes"]}
    if "_objects" not in case:
        return out
    o = case.pop("_objects")
    plan, lin, runs = o["plan"], o["linear"], o["runs"]
    names = [r.name for r in plan.rivals]
    by_group: dict[tuple[float, str], dict[float, int]] = {}
    for m, x in enumerate(plan.points):
        by_group.setdefault((x.speed, x.law), {})[x.push] = m
    full = [g for g, d in by_group.items() if len(d) == len({e.push for e in plan.points})]
    pick = (
        [full[int(j)] for j in np.unique(np.linspace(0, len(full) - 1, min(groups, len(full))).round())] if full else []
    )
    rows = []
    for speed, law in pick:
        for push, m in sorted(by_group[(speed, law)].items()):
            obs = runs.get(m, 0)
            row = {"speed": speed, "law": law, "push": push, "lost": obs is None}
            if obs is not None:
                y, R = obs
                row["y"] = [float(v) for v in y]
                row["sd"] = [float(v) for v in np.sqrt(np.diag(R))]
                row["rivals"] = {}
                for name, r in zip(names, lin):
                    mu, W = r.predict(m)
                    row["rivals"][name] = {
                        "mean": [float(v) for v in mu],
                        "sd": [float(v) for v in np.sqrt(np.diag(W))],
                    }
            rows.append(row)
    out.update(candidate=case["candidate"], rivals=names, runs=rows)
    return out
