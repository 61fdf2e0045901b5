"""What to measure next: the experiment that best tells apart the candidates a diagnosis left standing.

Rivals.  By default the first-ranked candidate of a diagnosis and every (single) candidate tied with
it; when none is tied, the runners-up that also beat the nominal model on the held-out folds (at most
:data:`MAX_RIVALS` in all).  Any candidates (or pairs) fitted to all the data may be named instead.
The measure below is then for every pair of a tie (or of named rivals), or for the first against each
runner-up.

Experiments.  A new measurement is a number of free decays at one speed under one control law: a
law of the data, the same controller with its gains scaled (:data:`GAIN_FACTORS`), or no control;
with records, the signal the decay's eigenvalue is fitted to (roll rate, steer angle, steer rate,
roll angle) and the size of the push (:data:`PUSHES`, relative to the data's: friction makes the
decay depend on it).  What each decay gives is what the diagnosis compares: its weave eigenvalue.

Predictions.  Each rival predicts a decay as the diagnosis predicts a record.  For tables of
eigenvalues: the rival's weave eigenvalue at that speed and law.  With records: a *template* decay
is simulated with the nominal model from the push of the nearest-speed record of the data (its first
samples, scaled), with each signal's noise (the larger of its records' sample-to-sample scatter,
:func:`signal_noise`, and what their own fits leave, :func:`fit_residual`), and fitted as a record is fitted
(the record fit's two-mode function, started from the nominal model's eigenvalues, judged by the record
fit's acceptance rules); every rival predicts it by indirect inference (the same
fit applied to the rival's own response over the template, :mod:`bikerider.gap.inference.indirect`).  A friction
rival's response is simulated from the template's own kick and refitted as a new record's fit would find it,
from the record fit's scan as well, over the fit's valleys (their spread a variance of one run:
:meth:`~bikerider.gap.inference.indirect.RecordSimulator.time_domain_runs`).  A template the record fit cannot fit, or whose fit
the nominal model's own response bends by more than 20 %, is not a measurement the diagnosis could
use, and is left out of the plan with its reason.

Uncertainties (2x2, real and imaginary part): the data's noise per decay ``D`` (tables: the data's
standard uncertainty at the nearest speed, scaled by ``(decay rate / decay rate there)^(3/2)``, as a
fitted decay rate's and frequency's standard errors grow on a faster decay; records: the template
fit's standard errors plus the data's run-to-run scatter beyond their own standard errors at the
nearest speed, of the experiment's own signal where the diagnosis did not fit that signal: the
scatter of its records' own fits of it, :data:`MIN_REPLICATES` or more at that speed); the nominal parameters' uncertainty ``V`` carried through (central differences of one
standard deviation by :class:`bikerider.engine.DifferencedStage`; with records from the roll-rate,
standard-push template of each speed and law), counted per decay as the diagnosis counts it (it
weights each row by data plus parameter variance and takes rows as independent); and each rival's
own uncertainty ``C``: its fitted values' covariance (each value's spread capped at that of a value
anywhere in its search range) through secants over one standard deviation inside the search bounds.
With records that log no steer, the kick's unknown initial steer rate: each rival's prediction is its mean
over templates from three steer rates (:func:`~bikerider.gap.plan.decays.kick_steer_rates`) and their spread
``K_T`` a per-run variance of rival ``T``'s prediction (``kick_cov``, with a friction rival's spread over the record
fit's valleys), added to ``D + V`` wherever rival ``T`` is true.
A friction rival's decays likewise over the corner of its friction law, which the data do not decide: the
mean over its friction smoothed at three ``eps`` (:func:`~bikerider.gap.plan.decays.smoothing_nodes`), each
taken as a move from the decay at the data's push, and their spread ``F_T`` (``form_cov``) part of its own
uncertainty ``C_T`` (systematic: every run of one bicycle has the same friction law).
A rival that misses held-out data by more than the uncertainties (held-out RMS error ``e`` above one)
would miss new data alike: its misfit ``(e^2 - 1) (D + V)`` is added, systematic.  ``n`` decays' mean
then has, with rival ``T`` true, the covariance ``S_T = C_T + (e_T^2 - 1)^+ (D + V) + (D + V + K_T) / n``.
The plan assumes one of the rivals is the truth; the misfit term keeps it from promising a resolution
between two rivals that both miss the data by more than they differ.

Discrimination.  The expected log-likelihood ratio of the new decays between two rivals ``A`` and
``B``: with ``T`` true and the statistic weighted by ``S_T``, the log-likelihood ratio is Gaussian with
mean ``d_T^2 / 2`` and variance ``d_T^2``, ``d_T^2 = (mu_A - mu_B)^T S_T^-1 (mu_A - mu_B)`` (the
Kullback-Leibler divergence; Box and Hill 1967, Hunter and Reiner 1965).  It measures what the
question is, whether new data favour one structure over the other, where the Fisher information of
the effects' parameters measures how precisely one candidate's own values would be pinned down: tied
candidates may each be well determined and still predict the same thing at the measured speeds.  The
probability that the new decays favour the true rival by odds of :data:`ODDS` to 1 or more (95 %
posterior probability from even odds) is then ``Phi(d_T / 2 - ln(ODDS) / d_T)``; averaged over which of the
two is true (even prior odds) it is the pair's *resolution probability*.  Experiments are ranked by
their smallest resolution probability over the pairs of rivals (all pairs of a tie; the first against
each runner-up otherwise) at the given number of decays, then by the smallest ``d``; each states the
decays it needs for 95 % (at most :data:`MAX_REPEATS`), and the limit the rivals' own uncertainty
sets with endless decays.  Experiments where a rival's weave grows (no free decay to record) are left
out.

``d_T`` weighs the difference of means by the true rival's covariance alone, so it cannot see a rival much
vaguer than the other, told apart by a run near the sharp rival's prediction even where their means coincide
(the closed loop's seed 7050: 0.006 for one decay, the loop's posterior 0.984 after it).  The plan's
measure of runs combined (:mod:`bikerider.gap.plan.allocation`) compares both rivals' predictive
distributions; for the runs of one experiment it is
:func:`~bikerider.gap.plan.discrimination.combined_probability` (the runs' mean simulated under each rival
taken true, the exact log Bayes factor counted, a fixed seed: the same value on every call).  Which of the two
an experiment states, with the runs it needs for 95 % and its limit, is
:data:`~bikerider.gap.plan.discrimination.STATED`: the combined measure for decays, the approximation for
multisines, as the closed loop, scoring the probability of ``k`` runs at ``k`` runs, found them better
calibrated (docs/gap_validation.md part 5); the order stays the approximation's.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from bikerider.engine import DifferencedStage
from bikerider.errors import InputError
from bikerider.gap.blas_threads import single_blas_thread
from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.inference.indirect import RecordSimulator, comparable
from bikerider.gap.inference.predict import Predictor
from bikerider.gap.inference.timedomain import SMOOTHING, Layout, systems
from bikerider.gap.measured.control import NO_CONTROL, ControlLaw
from bikerider.gap.measured.records import SIGNALS, RecordFit, eigenvalues_of
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
from bikerider.gap.parallel import map_forked, workers
from bikerider.gap.plan import discrimination, sequential
from bikerider.gap.plan.allocation import DRAWS
from bikerider.gap.plan.decays import (
    KICK_NODES,
    Experiment,
    fit_templates,
    kick_steer_rates,
    smoothing_nodes,
    template_records,
)
from bikerider.gap.plan.discrimination import (  # noqa: F401  (ODDS, MAX_REPEATS, resolution_probability: the plan's face)
    DEFAULT_REPEATS,
    MAX_REPEATS,
    ODDS,
    combine,
    item_dict,
    rank,
    resolution_probability,
    secant_points,
    secant_slopes,
    secants,
    separation,
    stated_probability,
)
from bikerider.gap.plan.noise import (  # noqa: F401  (fit_residual, signal_noise, ...: the plan's face)
    ASSUMED_NOISE,
    MAX_NOISE,
    fit_residual,
    over_speed,
    run_scatter,
    sample_noise,
    signal_noise,
    signal_scatter,
    speed_groups,
)
from bikerider.gap.plan.rivals import MAX_RIVALS, NoExperiment, Rival, choose_rivals  # noqa: F401
from bikerider.gap.plan.sweeps import (
    DEFAULT_RUN_TIME,
    DEFAULT_SAMPLE_RATE,
    DEFAULT_TORQUE,
    FRF_SIGNALS,
    MAX_ROLL,
    MAX_TORQUE,
    RECORD,
    RUN_TIME_RANGE,
    Sweep,
    lines_for,
    noise_covariance,
    peak_roll,
    response,
    run_stand_in,
    settle_time,
    simulated_response,
    split,
    weave_shift,
)

if TYPE_CHECKING:  # annotations only: the diagnosis sits above the plan's floor
    from bikerider.gap.diagnosis.result import Diagnosis
    from bikerider.gap.inference.problem import GapProblem

LOG = logging.getLogger(__name__)

GAIN_FACTORS = (0.5, 1.5)
"""Gains of each control law of the data tried scaled by these factors (a different gain of the
same controller)."""
PUSHES = (0.5, 1.0, 2.0)
"""Push sizes tried with records when a rival is nonlinear (its decay depends on the push)."""
N_SPEEDS = 12
"""Speeds of the default grid."""
SPEED_SPAN = (0.6, 1.25)
"""The default grid spans these factors times the slowest and the fastest speed of the data."""
MIN_DECAY = 0.3
"""Smallest decay rate [1/s] the noise of a table's decays is scaled with (slower decays, and growing
ones, are cut by the record's length rather than by their decay)."""
ASSUMED_DISTORTION = 0.1
"""Share of a run's frequency response a linear model misses at each line (friction's harmonics, the
treadmill's or rider's disturbances), assumed when the data hold no records to measure it."""


class _Models:
    """What a plan and its steps build the rivals' systems from (the diagnosis, its problem, the laws and the
    planned multisines)."""

    def _configured(self, effects, X, values=None):
        """The model's values, effect configuration and speed scale for fitted-value vectors ``X (P, p)`` of
        ``effects`` (or the nominal model with benchmark values ``values``, a batch), and the batch size ``P``."""
        p = self.problem
        if values is None:
            values, config, scale = p.configure(p.layout(tuple(effects)), np.atleast_2d(X))
        else:
            values = {**p.nominal, **{k: np.asarray(v, float).reshape(-1, 1) for k, v in values.items()}}
            config, scale = {}, None
        P = max([np.shape(v)[0] for v in values.values() if np.ndim(v) > 0] + [np.atleast_2d(X).shape[0]])
        return values, config, scale, P

    def _sample_rate(self, speed: float) -> float:
        """The sampling rate [Hz] of the nearest-speed record (without records, :data:`DEFAULT_SAMPLE_RATE`)."""
        if not self.records:
            return DEFAULT_SAMPLE_RATE
        d = self.diagnosis
        used = [d.records[k].record for k in d.record_rows]
        near = used[int(np.argmin([abs(r.speed - speed) for r in used]))]
        return 1.0 / float(near.time[1] - near.time[0])

    def _sweep_systems(self, effects, X, values=None, nonlinear=False, speeds=None):
        """Closed loops ``A (P, s, n, n)``, steer-torque columns ``b (P, s, n)`` and output states of every
        sweep for a rival's fitted-value vectors ``X (P, p)`` (or the nominal model with benchmark values
        ``values``, a batch); with ``nonlinear``, a friction rival's loop without its Coulomb friction (its runs
        are simulated in time: :meth:`_Planner._sweep_simulated`)."""

        p = self.problem
        sweeps = self.sweeps
        speeds = np.array([s.speed for s in sweeps]) if speeds is None else np.asarray(speeds, float)
        gains = np.array([self.laws[s.law](s.speed) for s in sweeps]).reshape(len(sweeps), 4)
        measured = self._speed_measured()
        if nonlinear:
            runs = [
                run_stand_in(Sweep(v, s.law, s.output, s.torque, s.run_time, s.lines), g, measured)
                for v, s, g in zip(speeds, sweeps, gains)
            ]
            A, b, outputs, _ = systems(p.nominal, p.geometry, runs, Layout.of(tuple(effects)), np.atleast_2d(X))
            return A, b, outputs
        values, config, scale, P = self._configured(effects, X, values)
        if scale is None or not measured:
            ss = EffectModel(values, p.geometry, config).state_space(speeds)
            A, b, outputs = ss.closed_loop(gains), ss.B[..., :, 1], ss.output_states
        else:  # a speed sensor's scale per vector: one model per vector

            def row(x, i):
                return np.asarray(x)[i] if np.ndim(x) > 0 and np.shape(x)[0] == P else x

            parts = []
            for i in range(P):
                model = EffectModel(
                    {k: row(v, i) for k, v in values.items()},
                    p.geometry,
                    {e: {k: row(v, i) for k, v in c.items()} for e, c in config.items()},
                )
                ss = model.state_space(float(np.ravel(scale)[i]) * speeds)
                parts.append((ss.closed_loop(gains).reshape((len(sweeps),) + ss.A.shape[-2:]), ss.B[..., :, 1]))
            A = np.array([a for a, _ in parts])
            b = np.array([np.reshape(x, A.shape[1:-1]) for _, x in parts])
            outputs = ss.output_states
        n = A.shape[-1]
        return np.broadcast_to(A, (P, len(sweeps), n, n)), np.broadcast_to(b, (P, len(sweeps), n)), outputs

    def _speed_measured(self) -> bool:
        """Whether the planned runs' speed is read by the sensor a ``speed_sensor`` rival rescales (as the data's)."""
        if self.records:
            d = self.diagnosis
            return any(d.records[k].record.speed_measured for k in d.record_rows)
        return bool(np.any(self.problem.eigen.speed_sensor))


class _Planner(_Models):
    """The steps of a plan (module docstring), in order: the rivals (:func:`~bikerider.gap.plan.rivals.choose_rivals`),
    the speeds and laws, the signals' noise (:func:`~bikerider.gap.plan.noise.sample_noise`), the decays (templates,
    predictions, their noise), the multisines (:mod:`~bikerider.gap.plan.sweeps`); :func:`plan_next` freezes
    what they give into a :class:`NextExperiment` and ranks it (:func:`~bikerider.gap.plan.discrimination.rank`)."""

    @single_blas_thread
    def __init__(
        self,
        diagnosis,
        rivals: Sequence[str] | None = None,
        speeds=None,
        repeats: int = DEFAULT_REPEATS,
        noise: dict[str, float] | None = None,
        signals: Sequence[str] | None = None,
        sweeps: bool = True,
        torque: float = DEFAULT_TORQUE,
        run_time: float = DEFAULT_RUN_TIME,
        distortion: float | None = None,
    ):
        d = self.diagnosis = diagnosis
        self.problem = d.problem
        if not isinstance(repeats, int | np.integer) or not 1 <= repeats <= MAX_REPEATS:
            raise InputError("repeats", repeats, f"a whole number of decays from 1 to {MAX_REPEATS}")
        if not (isinstance(torque, int | float) and 0 < torque <= MAX_TORQUE):  # also NaN
            raise InputError("torque", torque, f"a positive peak steer torque of at most {MAX_TORQUE:g} N m")
        lo, hi = RUN_TIME_RANGE
        if not (isinstance(run_time, int | float) and lo <= run_time <= hi):
            raise InputError("run_time", run_time, f"a recorded run length from {lo:g} to {hi:g} s")
        if distortion is not None and not (isinstance(distortion, int | float) and 0 <= distortion < 1):
            raise InputError("distortion", distortion, "a share of the response from 0 to below 1")
        self.repeats, self.torque, self.run_time, self.distortion = int(repeats), torque, run_time, distortion
        self.signals = tuple(signals) if signals else SIGNALS
        self.run_sweeps = bool(sweeps)
        self.named = bool(rivals)
        self.rivals, self.all_pairs = choose_rivals(d, rivals)
        if len(self.rivals) < 2:
            raise (InputError if rivals is not None else NoExperiment)(
                "rivals",
                [r.name for r in self.rivals],
                "at least two candidates to tell apart (name them, or a diagnosis with two candidates that beat "
                "the nominal model)",
            )
        self.records = bool(d.record_rows)
        self.speeds = self._speeds(speeds)
        self.laws = self._laws()
        self.sample_noise, self.noise_source, self.signal_fits = sample_noise(d, noise)
        self.templates: dict[Experiment, RecordFit] = {}
        self.simulator: RecordSimulator | None = None
        self.kick_rates: tuple[float, ...] = (0.0,)
        self.kick_weights: tuple[float, ...] = (1.0,)
        self.points, self.left_out = self._experiments()
        if not self.points:
            raise NoExperiment("experiments", "none measurable", "speeds and laws at which a decay shows a weave")
        self._predict()
        self._drop_unpredicted()
        self.sweeps = self._plan_sweeps() if self.run_sweeps else []
        self._predict_sweeps()
        if self.all_pairs:  # a tie (or rivals named): which of them
            self.pairs = [(i, j) for i in range(len(self.rivals)) for j in range(i + 1, len(self.rivals))]
        else:  # runners-up: whether the first stands against each
            self.pairs = [(0, j) for j in range(1, len(self.rivals))]

    # -- the space of experiments -----------------------------------------------------------------
    def _speeds(self, speeds) -> np.ndarray:
        if speeds is not None:
            out = np.asarray(speeds, dtype=float).ravel()
            if out.size == 0 or not np.all(np.isfinite(out)) or np.any(out <= 0):
                raise InputError("speeds", out.tolist(), "finite, positive speeds [m/s]")
            return np.unique(out)
        eig = self.problem.eigen
        if not len(eig):
            raise NoExperiment("data", "no eigenvalue rows", "measured eigenvalues or records to plan from")
        lo, hi = SPEED_SPAN[0] * float(eig.speed.min()), SPEED_SPAN[1] * float(eig.speed.max())
        return np.round(np.linspace(max(lo, 0.5), hi, N_SPEEDS), 2)

    def _laws(self) -> dict[str, ControlLaw]:
        laws: dict[str, ControlLaw] = {}
        for law in self.problem.eigen.laws.values():
            laws[law.name] = law
            if not law.is_zero:
                for factor in GAIN_FACTORS:
                    scaled = law.scaled(factor)
                    laws[scaled.name] = scaled
        laws.setdefault(NO_CONTROL.name, NO_CONTROL)
        return laws

    def _experiments(self) -> tuple[list[Experiment], list[dict]]:
        if not self.records:
            return [Experiment(float(v), name) for name in self.laws for v in self.speeds], []
        signals = self.signals
        for s in signals:
            if s not in SIGNALS:
                raise InputError("signal", s, "one of " + ", ".join(SIGNALS))
        pushes = PUSHES if any(r.nonlinear for r in self.rivals) else (1.0,)
        candidates = [
            Experiment(float(v), name, s, p) for name in self.laws for v in self.speeds for p in pushes for s in signals
        ]
        self.templates, left = self._templates(candidates)
        points = [e for e in candidates if e in self.templates]
        return points, left

    # -- templates (records) ------------------------------------------------------------------------
    def _templates(self, experiments: list[Experiment]) -> tuple[dict[Experiment, RecordFit], list[dict]]:
        """A fitted template decay per experiment (module docstring); those that fail, with the reason.

        Records that log no steer: each experiment's noise-free templates from the initial steer rates of
        :func:`~bikerider.gap.plan.decays.kick_steer_rates` (the simulator's records ``m K + k``, ``K`` of them
        per experiment), the first the noisy template's own; an experiment is kept when that one is comparable
        with models (a kick's steer rate bends the record fit more, in the truth's runs alike: the rivals predict
        what the fit finds)."""

        d = self.diagnosis
        used = [d.records[k].record for k in d.record_rows]
        nominal = EffectModel(self.problem.nominal, self.problem.geometry)
        self.kick_rates, self.kick_weights = kick_steer_rates(used)
        K = len(self.kick_rates)
        records, clean, kicks = template_records(nominal, used, experiments, self.laws, self.sample_noise)
        fits = fit_templates(nominal, records)
        left = [{"experiment": e.describe(), "reason": f.reason} for e, f in zip(experiments, fits) if not f.used]
        kept = [(e, f, c) for e, f, c in zip(experiments, fits, clean) if f.used]
        kicks = [x for x, f in zip(kicks, fits) if f.used]
        if not kept:
            return {}, left
        rows = eigenvalues_of([f for _, f, _ in kept])
        matched = Predictor(rows, _no_canonical(), self.problem.nominal, self.problem.geometry).eigenvalues(nominal)
        # the rivals predict the noise-free template (the noisy one's fit gives the acceptance and the
        # standard errors): a prediction is then a smooth function of the experiment, not of a noise draw
        smooth = [RecordFit(replace(f.record, signals=c), f.estimate, f.fits) for _, f, c in kept]
        if K > 1:  # every experiment's templates from the other initial steer rates, after its own
            _, others, other_kicks = template_records(
                nominal,
                used,
                [e for e, _, _ in kept for _ in self.kick_rates[1:]],
                self.laws,
                self.sample_noise,
                [r for _ in kept for r in self.kick_rates[1:]],
            )
            smooth = [
                item
                for j, (_, f, _) in enumerate(kept)
                for item in [smooth[j]]
                + [
                    RecordFit(replace(f.record, signals=c), f.estimate, f.fits)
                    for c in others[j * (K - 1) : (j + 1) * (K - 1)]
                ]
            ]
            kicks = [x for j in range(len(kept)) for x in [kicks[j]] + other_kicks[j * (K - 1) : (j + 1) * (K - 1)]]
            matched = np.repeat(matched, K)
        simulator = RecordSimulator(smooth, self.problem.nominal, self.problem.geometry, kicks=np.array(kicks))
        _, reasons = comparable(simulator.settle(), matched)
        out = {}
        keep = []
        for j, (e, f, _) in enumerate(kept):
            why = reasons[j * K]  # the data's own state's template (the others bend as the truth's runs would)
            if why is None:
                out[e] = f
                keep.append(j)
            else:
                left.append({"experiment": e.describe(), "reason": why})
        self.simulator = simulator.subset(self._rows_of(keep))
        return out, left

    def _rows_of(self, points) -> list[int]:
        """The simulator's templates of experiments ``points`` (each experiment's ``K``, in turn)."""
        K = len(self.kick_rates)
        return [m * K + k for m in points for k in range(K)]

    # -- predictions --------------------------------------------------------------------------------
    def _predict(self) -> None:

        n = len(self.points)
        p = self.problem
        self.mean = np.zeros((len(self.rivals), n), complex)
        self.own_cov = np.zeros((len(self.rivals), n, 2, 2))
        self.own_factor = [np.zeros((n, 2, 0)) for _ in self.rivals]
        base = self._reference_points()
        # independent pieces, one per core: each rival's prediction at its fit and at its secants' points
        # (a linear rival's points in chunks: each point's prediction is its own), and the nominal
        # parameters' uncertainty as the diagnosis carries it
        # a friction rival's decays also at the other corners of its friction law (smoothing_nodes), at its fit
        jobs: list[tuple[int, np.ndarray | None, float | None]] = []
        secants = {}
        corners = self._corners()
        for k, rival in enumerate(self.rivals):
            jobs.append((k, rival.fit.values[None, :], None))  # its first: with a friction rival's per-run spread
            if rival.fit.names:
                X, width, cov = secant_points(rival.fit)
                secants[k] = (width, cov, len(jobs))
                size = len(X) if rival.nonlinear else max(4, -(-len(X) // (2 * workers())))
                jobs += [(k, X[lo : lo + size], None) for lo in range(0, len(X), size)]
            if rival.nonlinear and self.records:
                jobs += [(k, rival.fit.values[None, :], eps) for eps in corners[0][1:]]
        if p.free:
            jobs.append((-1, None, None))

        firsts = {job[0]: j for j, job in reversed(list(enumerate(jobs)))}

        def task(j: int):
            k, X, eps = jobs[j]
            if k >= 0 and self.rivals[k].nonlinear:  # a friction rival (records): its decays over the corners
                mean, runs = self._friction_runs(self.rivals[k], X, eps)
                return (mean, runs) if j == firsts[k] else mean
            if k >= 0:  # (P, n, K): from each template's initial steer rate, not yet averaged
                return self._predict_linear(self.rivals[k].effects, X, None, self.points, nodes=True)
            stage = DifferencedStage(
                "nominal parameters",
                lambda v: _split(self._predict_linear((), np.zeros((np.size(next(iter(v.values()))), 0)), v, base)),
                p.free,
                range(2 * len(base)),
                dict(zip(p.free, p.free_sigma)),
                batched=True,
            )
            J = (stage.jacobian({k: p.nominal[k] for k in p.free}) * p.free_sigma).reshape(2, len(base), -1)
            return np.einsum("anj,bnj->nab", J, J)

        order = sorted(range(len(jobs)), key=lambda j: -(0 if jobs[j][1] is None else len(jobs[j][1])))
        done = dict(zip(order, map_forked(task, order)))
        results = [done[j] for j in range(len(jobs))]
        w = np.asarray(self.kick_weights, float)
        spread = np.zeros((len(self.rivals), n, 2, 2))
        self.form_cov = np.zeros((len(self.rivals), n, 2, 2))
        for k, rival in enumerate(self.rivals):
            first = results[firsts[k]]
            valleys = 0.0
            if isinstance(first, tuple):  # a friction rival: the spread of a new record's fit over its valleys
                first, valleys = first[0], first[1][0]
            nodes = first[0]  # (n, K): the prediction from each initial steer rate
            self.mean[k] = nodes @ w
            dev = nodes - self.mean[k][:, None]
            dev = np.stack([dev.real, dev.imag])  # (2, n, K)
            spread[k] = np.einsum("ank,k,bnk->nab", dev, w, dev) + valleys
            others = [results[j][0] @ w for j, job in enumerate(jobs) if job[0] == k and job[2] is not None]
            if others:
                self.mean[k], self.form_cov[k] = self._over_corners(self.mean[k], others, corners[1])
            if k in secants:
                width, cov, start = secants[k]
                pred = (
                    np.concatenate(
                        [results[j] for j in range(start, len(jobs)) if jobs[j][0] == k and jobs[j][2] is None]
                    )
                    @ w
                )
                J = secant_slopes(_split(pred), width).reshape(2, n, -1)  # per unit of each value
                self.own_cov[k] = np.einsum("anj,jk,bnk->nab", J, cov, J)
                self.own_factor[k] = np.einsum("anj,jk->nak", J, _root(cov))  # own_cov = F F^T, across experiments
        # the friction law's corner, which no run of the same bicycle averages away: the rival's own uncertainty
        self.own_cov += self.form_cov
        self.model_cov = np.zeros((n, 2, 2))
        if p.free:
            cov = results[-1]
            index = {(e.speed, e.law): m for m, e in enumerate(base)}
            for m, e in enumerate(self.points):
                self.model_cov[m] = cov[index[(e.speed, e.law)]]
        self.data_cov = self._data_noise()
        self.kick_cov = spread

    def _corners(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """The friction smoothings a friction rival's decays are predicted at, and their weights
        (:func:`~bikerider.gap.plan.decays.smoothing_nodes`; the fits' own alone for tables)."""
        return smoothing_nodes() if self.records else ((SMOOTHING,), (1.0,))

    def _over_corners(self, own: np.ndarray, others: list[np.ndarray], weights) -> tuple[np.ndarray, np.ndarray]:
        """A friction rival's decays ``(n,)`` over the corners of its friction law: ``own`` at the fits' smoothing,
        ``others`` at the other :meth:`_corners`.  Each corner's prediction is taken as a move from the decay at
        the data's push of the same speed, law and signal (where the plan holds one): the rival's values were
        fitted at the data's push, where a fit at any corner meets the data alike, so the corner moves what a
        push changes, not the level.  Returns the weighted mean and covariance ``(n, 2, 2)``."""
        where = {(e.speed, e.law, e.signal): m for m, e in enumerate(self.points) if e.push == 1.0}
        anchor = np.array([where.get((e.speed, e.law, e.signal), -1) for e in self.points])
        have = anchor >= 0  # elsewhere the corner's own prediction
        anchor = np.where(have, anchor, 0)
        nodes = np.stack([own] + [np.where(have, o - o[anchor] + own[anchor], o) for o in others], axis=-1)  # (n, E)
        w = np.asarray(weights, float)
        mean = nodes @ w
        dev = nodes - mean[:, None]
        dev = np.stack([dev.real, dev.imag])  # (2, n, E)
        return mean, np.einsum("ane,e,bne->nab", dev, w, dev)

    def _drop_unpredicted(self) -> None:
        """Leave out experiments where a rival's response shows no weave the record fit finds."""
        bad = ~np.all(np.isfinite(self.mean), axis=0) | ~np.all(np.isfinite(self.own_cov), axis=(0, 2, 3))
        bad |= ~np.all(np.isfinite(self.model_cov), axis=(1, 2)) | ~np.all(np.isfinite(self.data_cov), axis=(1, 2))
        growing = np.any(self.mean.real >= 0, axis=0)
        for m in np.flatnonzero(bad | growing):
            missing = [r.name for k, r in enumerate(self.rivals) if not np.isfinite(self.mean[k, m])]
            grows = [r.name for k, r in enumerate(self.rivals) if self.mean[k, m].real >= 0]
            if missing:
                why = f"the response of {', '.join(missing)} shows no weave the record fit finds"
                if len(self.kick_rates) > 1:
                    why += " (from one of the kick's initial steer rates, or more)"
                elif self.records and any(self.rivals[k].nonlinear for k in range(len(self.rivals))):
                    why += " (at the fits' friction law, or one of its other corners)"
            elif grows:
                why = (
                    f"the weave of {', '.join(grows)} grows there: no free decay to record (the bicycle falls "
                    "unless a controller or a catch stops it)"
                )
            else:
                why = "an uncertainty cannot be evaluated there"
            self.left_out.append({"experiment": self.points[m].describe(), "reason": why})
        keep = np.flatnonzero(~(bad | growing))
        if not keep.size:  # say why, with the reasons counted: the command prints the diagnosis and this
            counts: dict[str, int] = {}
            for entry in self.left_out:
                counts[entry["reason"]] = counts.get(entry["reason"], 0) + 1
            reasons = "; ".join(f"{why} ({n} of {len(self.left_out)})" for why, n in counts.items())
            raise NoExperiment(
                "experiments",
                "none predicted",
                "speeds and laws where every rival shows a weave",
                f"none of the {len(self.left_out)} experiments considered (speeds, laws, signals, pushes) can be "
                f"predicted by every rival ({', '.join(r.name for r in self.rivals)}): {reasons}. Other speeds "
                "(--next-speeds) or other rivals (--next-between) may give a plan",
            )
        self.points = [self.points[m] for m in keep]
        self.mean, self.own_cov = self.mean[:, keep], self.own_cov[:, keep]
        self.own_factor = [f[keep] for f in self.own_factor]
        self.model_cov, self.data_cov = self.model_cov[keep], self.data_cov[keep]
        self.kick_cov = self.kick_cov[:, keep]
        self.form_cov = self.form_cov[:, keep]
        if self.records:
            self.simulator = self.simulator.subset(self._rows_of(keep))

    def _reference_points(self) -> list[Experiment]:
        """One experiment per speed and law (the roll-rate, standard-push one where there is one)."""
        out: dict[tuple[float, str], Experiment] = {}
        for e in self.points:
            key = (e.speed, e.law)
            best = out.get(key)
            if best is None or (e.push == 1.0 and e.signal == "roll_rate"):
                out[key] = e
        return list(out.values())

    def _friction_runs(self, rival: Rival, X: np.ndarray, smoothing: float | None) -> tuple[np.ndarray, np.ndarray]:
        """A friction rival's decays as a new record's fit finds them (:meth:`~bikerider.gap.inference.indirect.
        RecordSimulator.time_domain_runs`, the template's fit and the record fit's own scan of the response as
        starts): the mean ``(P, n_points, K)`` from each template's initial steer rate, and the per-run
        covariance ``(P, n_points, 2, 2)`` where the fit's valleys trade places, averaged over the templates.
        The friction's response is no sum of modes: a refit from the template's fit alone (the nominal
        model's) can end in another valley than a record's own fit would, and jumped over speed."""
        mean, cov = self.simulator.time_domain_runs(Layout.of(rival.effects), X, self.sample_noise, smoothing)
        K = len(self.kick_rates)
        mean = mean.reshape(mean.shape[0], len(self.points), K)
        cov = np.einsum("pnkab,k->pnab", cov.reshape(cov.shape[0], len(self.points), K, 2, 2), self.kick_weights)
        return mean, cov

    def _predict_linear(self, effects, X, values=None, points=None, nodes: bool = False) -> np.ndarray:
        """Predicted eigenvalue ``(P, len(points))`` of linear effects at fitted values ``X``, or of the
        nominal model with benchmark values ``values`` (a batch); with records, what the record fit finds
        in the model's response over each template (the mean over its initial steer rates; with ``nodes``
        each, ``(P, len(points), K)``)."""
        p = self.problem
        values, config, scale, P = self._configured(effects, X, values)
        K = len(self.kick_rates)
        if self.records:
            # a linear model's response is proportional to its push, and the record fit finds the same
            # eigenvalue in it at any size: one template per speed, law, signal and initial steer rate
            where = {e: m for m, e in enumerate(self.points)}
            keys = [(e.speed, e.law, e.signal) for e in points]
            unique = {key: where[e] for key, e in zip(keys, points)}
            index = list(unique.values())
            sub = self.simulator.subset(self._rows_of(index)) if len(index) != len(self.points) else self.simulator
            res = np.broadcast_to(sub.apparent(values, config, scale), (P, len(index) * K)).reshape(P, len(index), K)
            column = {key: j for j, key in enumerate(unique)}
            res = res[:, [column[key] for key in keys]].copy()
            return res if nodes else res @ np.asarray(self.kick_weights, float)
        rows = self._rows(points)

        predictor = Predictor(rows, _no_canonical(), p.nominal, p.geometry)
        with np.errstate(all="ignore"):
            out = predictor.eigenvalues(EffectModel(values, p.geometry, config))
        out = np.broadcast_to(out, (P, len(points))).copy()
        return out[..., None] if nodes else out

    def _rows(self, points: list[Experiment]):
        return planned_rows(points, self.laws, self._speed_measured() if self.records else None)

    def _data_noise(self) -> np.ndarray:
        """Per decay ``(n_points, 2, 2)``: the data's noise (module docstring), continuous in speed (each
        quantity's median per speed of the data, linearly between those speeds: :func:`over_speed`)."""
        p = self.problem
        eig = p.eigen
        first = np.cumsum([0] + [2 if m == "weave" else 1 for m in eig.mode])
        weave = [r for r in range(len(eig)) if eig.mode[r] == "weave"]
        real = np.array([p.var_data[first[r]] for r in weave])
        imag = np.array([p.var_data[first[r] + 1] for r in weave])
        speeds = eig.speed[weave]
        decay = np.maximum(-np.array([p.baseline[first[r]] for r in weave]), MIN_DECAY)
        out = np.zeros((len(self.points), 2, 2))
        decay, real, imag = (over_speed(speeds, x) for x in (decay, real, imag))
        run = run_scatter(self.problem, self.records)
        scatter: dict[str, object] = {}
        for m, e in enumerate(self.points):
            if not self.records:
                # a fitted decay rate's and frequency's standard error grows as (decay rate)^(3/2)
                scale = (max(-float(np.mean(self.mean[:, m].real)), MIN_DECAY) / decay(e.speed)) ** 3
                out[m, 0, 0], out[m, 1, 1] = scale * real(e.speed), scale * imag(e.speed)
                continue
            # records: the template's own standard errors plus the data's scatter beyond their records' own;
            # for a signal the diagnosis did not fit, the scatter of that signal's own fits when they replicate
            est = self.templates[e].estimate
            if e.signal not in scatter:
                scatter[e.signal] = signal_scatter(self.diagnosis, self.signal_fits, e.signal)
            own = (scatter[e.signal] or run)(e.speed)
            out[m, 0, 0] = est.real_sigma**2 + own[0]
            out[m, 1, 1] = est.imag_sigma**2 + own[1]
        return out

    # -- sweeps ----------------------------------------------------------------------------------------
    def _plan_sweeps(self) -> list[Sweep]:
        """Multisine runs per speed, law and output, around the nominal weave (:mod:`bikerider.gap.plan.sweeps`);
        where the nominal closed loop is unstable or shows no weave, left out with the reason."""
        nominal = EffectModel(self.problem.nominal, self.problem.geometry)
        out = []
        for name, law in self.laws.items():
            for v in self.speeds:
                v = float(v)
                ev = nominal.eigenvalues([v], law(v)[None, :])[0]
                fs = self._sample_rate(v)
                where = f"multisines at {v:.2f} m/s under {name}"
                oscillating = ev[ev.imag > 1e-6]
                if ev.real.max() >= 1.0 / self.run_time:
                    why = (
                        "the nominal closed loop is unstable there (a mode grows e-fold within the run): no steady "
                        "response to measure"
                    )
                elif not oscillating.size:
                    why = "the nominal model shows no weave there to place the lines around"
                else:
                    lines = lines_for(float(oscillating.imag.max()) / (2 * math.pi), float(self.run_time))
                    if lines[-1] >= fs / 2:
                        why = f"its highest line {lines[-1]:.3g} Hz is above the Nyquist frequency of {fs:g} Hz"
                    else:
                        out += [Sweep(v, name, o, float(self.torque), float(self.run_time), lines) for o in FRF_SIGNALS]
                        continue
                self.left_out.append({"experiment": where, "reason": why})
        return out

    def _sweep_response(self, A, b, outputs) -> np.ndarray:
        """Each sweep's frequency response ``(P, s, K)`` from its systems."""
        omegas = np.array([s.omegas for s in self.sweeps])
        roll = response(A, b, outputs[2], omegas[None])
        steer = response(A, b, outputs[1], omegas[None])
        is_roll = np.array([s.output == "roll_rate" for s in self.sweeps])
        return np.where(is_roll[None, :, None], roll, steer)

    def _sweep_rival(self, rival: Rival, X) -> np.ndarray:
        if rival.nonlinear:
            return self._sweep_simulated(rival.effects, X)
        return self._sweep_response(*self._sweep_systems(rival.effects, X))

    def _sweep_simulated(self, effects, X, stick: bool = False, roll: bool = False):
        """Each sweep's frequency response ``(P, s, K)`` for a nonlinear rival's fitted-value vectors ``X (P, p)``:
        its runs simulated in time with the steer's Coulomb friction and read by the DFT
        (:func:`bikerider.gap.plan.sweeps.simulated_response`; one run per speed and law serves both outputs).
        With ``roll``, also each run's largest lean ``(P, s)`` [rad]."""
        p = self.problem
        first: dict[tuple[float, str], int] = {}
        for m, x in enumerate(self.sweeps):
            first.setdefault((x.speed, x.law), m)
        runs = [self.sweeps[m] for m in first.values()]
        measured = self._speed_measured()
        stand_ins = [run_stand_in(x, self.laws[x.law](x.speed), measured) for x in runs]
        A, b, outputs, friction = systems(p.nominal, p.geometry, stand_ins, Layout.of(tuple(effects)), np.atleast_2d(X))
        out = simulated_response(
            A, b, friction, outputs[3], (outputs[2], outputs[1]), runs, stick, outputs[0] if roll else None
        )
        H, peak = out if roll else (out, None)  # (P, runs, 2, K), (P, runs)
        column = {key: j for j, key in enumerate(first)}
        pick = [column[(x.speed, x.law)] for x in self.sweeps]
        part = [0 if x.output == "roll_rate" else 1 for x in self.sweeps]
        return (H[:, pick, part], peak[:, pick]) if roll else H[:, pick, part]

    def _predict_sweeps(self) -> None:
        """Every rival's frequency responses and their uncertainties (module docstring of
        :mod:`bikerider.gap.plan.sweeps`); sweeps where a rival's loop is unstable are left out."""

        R, p = len(self.rivals), self.problem
        if not self.sweeps:
            self.sweep_mean = np.zeros((R, 0, 0), complex)
            self.sweep_own = self.sweep_form = np.zeros((R, 0, 0, 0))
            self.sweep_factor = [np.zeros((0, 0, 0)) for _ in range(R)]
            self.sweep_data = self.sweep_model = self.sweep_run = np.zeros((0, 0, 0))
            self.sweep_settle, self.sweep_roll = np.zeros(0), np.zeros((R, 0))
            self.sweep_distortion, self.distortion_source = self._linear_misfit()
            return
        K = len(self.sweeps[0].lines)
        s = len(self.sweeps)
        self.sweep_mean = np.zeros((R, s, K), complex)
        self.sweep_own = np.zeros((R, s, 2 * K, 2 * K))
        self.sweep_form = np.zeros((R, s, 2 * K, 2 * K))
        self.sweep_factor = [np.zeros((s, 2 * K, 0)) for _ in range(R)]
        unstable = np.zeros(s, bool)
        # every rival's loop (a friction rival's without its Coulomb friction, which only takes energy out)
        loops = [
            self._sweep_systems(rival.effects, rival.fit.values[None, :], nonlinear=rival.nonlinear)
            for rival in self.rivals
        ]
        # each run settles until the slowest transient of the nominal loop and of every rival's has died
        # (sweeps.settle_time, SETTLE_RANGE)
        with np.errstate(all="ignore"):
            eigenvalues = [np.linalg.eigvals(self._sweep_systems((), np.zeros((1, 0)))[0][0])]
            eigenvalues += [np.linalg.eigvals(loop[0][0]) for loop in loops]
        self.sweep_settle = np.array([max(settle_time(ev[m]) for ev in eigenvalues) for m in range(s)])
        self.sweep_roll = np.zeros((R, s))
        for k, rival in enumerate(self.rivals):
            fit, loop = rival.fit, loops[k]
            # a mode that grows e-fold within the run (a slow capsize a rider or a catch holds is allowed)
            unstable |= eigenvalues[1 + k].real.max(axis=-1) >= 1.0 / self.run_time
            # how far the run leans: a run whose lean passes MAX_ROLL is likely lost (it falls or is caught);
            # a friction rival's response and lean from its runs simulated in time
            if rival.nonlinear:
                H, lean = self._sweep_simulated(rival.effects, fit.values[None, :], roll=True)
                self.sweep_mean[k], self.sweep_roll[k] = H[0], lean[0]
            else:
                with np.errstate(all="ignore"):
                    self.sweep_roll[k] = peak_roll(loop[0], loop[1], loop[2][0], self.sweeps, self.sweep_settle)[0]
                self.sweep_mean[k] = self._sweep_rival(rival, fit.values[None, :])[0]
            if fit.names:
                J, cov = secants(fit, lambda X, rival=rival: split(self._sweep_rival(rival, X)).reshape(len(X), -1))
                J = J.reshape(s, 2 * K, -1)
                self.sweep_own[k] = np.einsum("naj,jk,nbk->nab", J, cov, J)
                self.sweep_factor[k] = np.einsum("naj,jk->nak", J, _root(cov))
            if rival.nonlinear:
                # the friction law's form: the fitted smoothed friction against the same friction sticking
                # (Karnopp), a systematic difference more runs do not average away
                form = split(self._sweep_simulated(rival.effects, fit.values[None, :], stick=True)[0]) - split(
                    self.sweep_mean[k]
                )
                self.sweep_form[k] = np.einsum("na,nb->nab", form, form)
                self.sweep_own[k] += self.sweep_form[k]
        # per run: the sensor noise at the lines, and the speed scattering as the data's
        nominal = ((), np.zeros((1, 0)))
        self.sweep_data = np.array(
            [
                noise_covariance(
                    x, self.sample_noise.get(x.output, ASSUMED_NOISE[x.output]), self._sample_rate(x.speed)
                )
                for x in self.sweeps
            ]
        )
        speeds = np.array([x.speed for x in self.sweeps])
        h = 0.01 * speeds
        up = self._sweep_response(*self._sweep_systems(*nominal, speeds=speeds + h))[0]
        down = self._sweep_response(*self._sweep_systems(*nominal, speeds=speeds - h))[0]
        Jv = split((up - down) / (2 * h[:, None]))
        self.sweep_data += np.einsum("na,nb->nab", Jv, Jv) * self._speed_sigma() ** 2
        # and the bicycle itself varying from run to run as the data's weave did (next_sweep.weave_shift):
        # more torque does not average it away
        A, b, outputs = self._sweep_systems(*nominal)
        self.sweep_run = np.zeros_like(self.sweep_data)
        run = run_scatter(self.problem, self.records)
        for m, x in enumerate(self.sweeps):
            index = outputs[2] if x.output == "roll_rate" else outputs[1]
            J = weave_shift(A[0, m], b[0, m], index, x.omegas)
            if J is not None:
                self.sweep_run[m] = J @ np.diag(run(x.speed)) @ J.T
        self.sweep_data += self.sweep_run
        # and what a linear response misses of a real run, line by line (next_sweep.linear_misfit)
        self.sweep_distortion, self.distortion_source = self._linear_misfit()
        H = self._sweep_response(A, b, outputs)[0]  # (s, K), the nominal model's
        part = (self.sweep_distortion * np.abs(H)) ** 2 / 2
        self.sweep_data += np.einsum("na,ab->nab", np.concatenate([part, part], axis=-1), np.eye(2 * H.shape[-1]))
        self.sweep_model = np.zeros((s, 2 * K, 2 * K))
        if p.free:
            stage = DifferencedStage(
                "nominal parameters",
                lambda v: split(
                    self._sweep_response(*self._sweep_systems((), np.zeros((np.size(next(iter(v.values()))), 0)), v))
                ).reshape(np.size(next(iter(v.values()))), -1),
                p.free,
                range(s * 2 * K),
                dict(zip(p.free, p.free_sigma)),
                batched=True,
            )
            J = (stage.jacobian({k: p.nominal[k] for k in p.free}) * p.free_sigma).reshape(s, 2 * K, -1)
            self.sweep_model = np.einsum("naj,nbj->nab", J, J)
        leans = ~(np.max(self.sweep_roll, axis=0) <= MAX_ROLL)  # NaN too
        bad = unstable | leans | ~np.all(np.isfinite(self.sweep_mean), axis=(0, 2))
        bad |= ~np.all(np.isfinite(self.sweep_own), axis=(0, 2, 3)) | ~np.all(
            np.isfinite(self.sweep_model), axis=(1, 2)
        )
        for m in np.flatnonzero(bad):
            if unstable[m]:
                why = (
                    "a rival's closed loop is unstable there (a mode grows e-fold within the run): no steady response "
                    "to measure"
                )
            elif leans[m]:
                k = int(np.argmax(np.nan_to_num(self.sweep_roll[:, m], nan=np.inf)))
                when = (
                    "in its run simulated in time"
                    if self.rivals[k].nonlinear
                    else f"during its {self.sweep_settle[m]:.0f} s settling time and the recorded period"
                )
                why = (
                    f"the run would likely be lost: {self.rivals[k].name} predicts a lean of "
                    f"{self.sweep_roll[k, m]:.2g} rad {when} (more than {MAX_ROLL:g} rad: the bicycle falls or is "
                    "caught, and the run teaches nothing); a smaller torque (--next-torque) leans less"
                )
            else:
                why = "an uncertainty cannot be evaluated there"
            self.left_out.append({"experiment": self.sweeps[m].describe(), "reason": why})
        keep = np.flatnonzero(~bad)
        self.sweep_settle, self.sweep_roll = self.sweep_settle[keep], self.sweep_roll[:, keep]
        self.sweeps = [self.sweeps[m] for m in keep]
        self.sweep_mean, self.sweep_own = self.sweep_mean[:, keep], self.sweep_own[:, keep]
        self.sweep_form = self.sweep_form[:, keep]
        self.sweep_factor = [f[keep] for f in self.sweep_factor]
        self.sweep_data, self.sweep_model = self.sweep_data[keep], self.sweep_model[keep]
        self.sweep_run = self.sweep_run[keep]

    def _linear_misfit(self) -> tuple[float, str]:
        """The share of a run's response a linear model misses (:data:`ASSUMED_DISTORTION` without records)."""
        if self.distortion is not None:
            return float(self.distortion), "given"
        if not self.records:
            return ASSUMED_DISTORTION, "assumed (the data hold no records)"
        d = self.diagnosis
        r2 = [d.records[k].estimate.r2 for k in d.record_rows]
        r2 = [x for x in r2 if math.isfinite(x)]
        if not r2:
            return ASSUMED_DISTORTION, "assumed (the records' fits give no r^2)"
        share = float(np.median(np.sqrt(np.clip(1.0 - np.array(r2), 0.0, 1.0))))
        return share, f"the records: sqrt(1 - r^2) of their fits, median over {len(r2)}"

    def _speed_sigma(self) -> float:
        """A run's speed scatter [m/s]: the median of the data's speed uncertainties."""
        if self.records:
            d = self.diagnosis
            return float(np.median([d.records[k].record.speed_sigma for k in d.record_rows]))
        eig = self.problem.eigen
        return float(np.median(eig.speed_sigma)) if len(eig) else 0.0


@dataclass(frozen=True, eq=False)
class NextExperiment(_Models):
    """The ranked plan of new measurements for a diagnosis (module docstring), as :func:`plan_next` made it.

    Attributes
    ----------
    diagnosis : bikerider.gap.diagnosis.result.Diagnosis
    rivals : tuple of Rival
        The candidates (or pairs) to tell apart.
    all_pairs : bool
        Every pair of rivals is to be told apart (``False``: the first against each runner-up).
    named : bool
        The rivals were named.
    pairs : tuple of (int, int)
    repeats : int
        Runs per experiment the plan is ranked for.
    speeds : ndarray
        Speeds considered [m/s].
    laws : dict
        Control laws considered, by name.
    records : bool
        Planned from records (templates and indirect inference) rather than tables.
    sample_noise, noise_source : dict
        Each signal's sample noise and where it came from.
    signal_fits : dict
        Every record's fit of each signal, ``(speed, fit)``.
    points : tuple of Experiment
        The decays planned (those left out are in ``left_out``).
    templates : dict
        Each decay's fitted template (records only).
    simulator : RecordSimulator or None
        The noise-free templates, one per decay (records only).
    mean : ndarray
        ``(rivals, points)`` complex: each rival's predicted weave eigenvalue.
    own_cov, data_cov, model_cov : ndarray
        ``(rivals, points, 2, 2)``, ``(points, 2, 2)``, ``(points, 2, 2)``: the rivals' own, one decay's data
        noise and the nominal parameters' covariance (real, imaginary).
    run_sweeps : bool
    torque, run_time : float
        The multisines' peak torque [N m] and recorded run length [s].
    sweeps : tuple of Sweep
    sweep_mean, sweep_own, sweep_form, sweep_data, sweep_model, sweep_run : ndarray
        As for decays, per line (real parts, then imaginary parts); ``sweep_form`` the friction law's form
        (part of ``sweep_own``), ``sweep_run`` the run-to-run part of ``sweep_data``.
    sweep_distortion : float
    distortion_source : str
    left_out : tuple of dict
        Experiments left out, with the reason.
    plan : tuple of dict
        Every experiment, best first (:func:`~bikerider.gap.plan.discrimination.rank`).
    own_factor, sweep_factor : tuple of ndarray, optional
        Per rival ``(points, 2, q)`` and ``(sweeps, 2K, q)``: its own uncertainty's factor ``F`` (``own_cov = F F^T + form_cov``;
        one set of fitted values for every experiment, so the covariance across experiments too).
    next_run : dict, optional
        The next single run (:func:`~bikerider.gap.plan.sequential.next_run`): where the Jensen-Renyi divergence
        of the rivals' predictive distributions of one run is largest, the closed loop's best criterion.
    sweep_settle, sweep_roll : ndarray, optional
        ``(sweeps,)`` each multisine run's settling time [s] (:func:`~bikerider.gap.plan.sweeps.settle_time`) and
        ``(rivals, sweeps)`` the largest lean each rival predicts for it [rad] (:func:`~bikerider.gap.plan.sweeps.peak_roll`).
    kick_cov : ndarray, optional
        ``(rivals, points, 2, 2)``: per run, the spread of each rival's prediction over the kick's initial steer
        rate where the records do not log it (``kick_rates``; zero otherwise), and a friction rival's over the
        record fit's valleys in its response; added to one run's noise.
    kick_rates : tuple of float
        The templates' initial steer rates as multiples of their roll rate
        (:func:`~bikerider.gap.plan.decays.kick_steer_rates`).
    form_cov : ndarray, optional
        ``(rivals, points, 2, 2)``: a friction rival's spread over the corner of its friction law
        (:func:`~bikerider.gap.plan.decays.smoothing_nodes`; zero for the others and for tables), part of
        ``own_cov`` (systematic: runs of one bicycle share it).
    combined : dict, optional
        Runs spread over several experiments (:func:`~bikerider.gap.plan.discrimination.combine`): the greedy
        allocation of up to :data:`MAX_REPEATS` runs and its resolution probability; ``None`` without factors.
    """

    diagnosis: Diagnosis
    problem: GapProblem
    rivals: tuple[Rival, ...]
    all_pairs: bool
    named: bool
    pairs: tuple[tuple[int, int], ...]
    repeats: int
    speeds: np.ndarray
    laws: dict[str, ControlLaw]
    records: bool
    sample_noise: dict[str, float]
    noise_source: dict[str, str]
    signal_fits: dict[str, list]
    points: tuple[Experiment, ...]
    templates: dict[Experiment, RecordFit]
    simulator: RecordSimulator | None
    mean: np.ndarray
    own_cov: np.ndarray
    data_cov: np.ndarray
    model_cov: np.ndarray
    run_sweeps: bool
    torque: float
    run_time: float
    sweeps: tuple[Sweep, ...]
    sweep_mean: np.ndarray
    sweep_own: np.ndarray
    sweep_form: np.ndarray
    sweep_data: np.ndarray
    sweep_model: np.ndarray
    sweep_run: np.ndarray
    sweep_distortion: float
    distortion_source: str
    left_out: tuple[dict, ...]
    plan: tuple[dict, ...] = field(default=())
    sweep_settle: np.ndarray | None = None
    sweep_roll: np.ndarray | None = None
    next_run: dict | None = None
    own_factor: tuple[np.ndarray, ...] | None = None
    sweep_factor: tuple[np.ndarray, ...] | None = None
    combined: dict | None = None
    kick_cov: np.ndarray | None = None
    kick_rates: tuple[float, ...] = (0.0,)
    form_cov: np.ndarray | None = None

    @property
    def experiments(self) -> list[Experiment | Sweep]:
        """The decays, then the multisines (the order of :meth:`separation`'s last axis)."""
        return list(self.points) + list(self.sweeps)

    def separation(self, repeats: float) -> np.ndarray:
        """``d`` of every pair at every experiment for ``repeats`` runs each, ``(n_pairs, 2, n_points)``
        (:func:`~bikerider.gap.plan.discrimination.separation`)."""
        return separation(self, repeats)

    def probability(self, repeats: float) -> np.ndarray:
        """Resolution probability of every pair at every experiment for ``repeats`` runs of it, ``(n_pairs,
        n_points)``: the probability the plan states
        (:func:`~bikerider.gap.plan.discrimination.stated_probability`), the mean over which of the two is true
        (even prior odds)."""
        return stated_probability(self, repeats)

    def as_dict(self, top: int = 10) -> dict:
        """The plan and every experiment's numbers, JSON-ready."""

        def best_of(key):
            seen = {}
            for item in self.plan:
                k = getattr(item["experiment"], key)
                if k is not None and k not in seen:
                    seen[k] = item_dict(item)
            return seen

        return {
            "rivals": [
                {
                    "effects": list(r.effects),
                    "fitted": {n: float(v) for n, v in zip(r.fit.names, r.fit.values)},
                    "heldout_error": math.sqrt(1.0 + r.misfit) if r.misfit > 0 else None,
                    "heldout_misfit": r.misfit,
                }
                for r in self.rivals
            ],
            "measure": (
                "expected log-likelihood ratio between the rivals' Gaussian predictive distributions of the mean "
                "weave eigenvalue of the new decays, or of the mean frequency response of the new steer-torque "
                f"multisines (d^2 / 2), which ranks the experiments by Phi(d / 2 - ln {ODDS:g} / d); resolution "
                f"probability: the new runs favour the true rival by odds of {ODDS:g} to 1 or more"
                + "".join(
                    f"; for {name} "
                    + (
                        f"both rivals' predictive distributions compared ({DRAWS} simulated outcomes per rival taken "
                        "true, a fixed seed)"
                        if discrimination.STATED.get(kind) == "combined"
                        else f"Phi(d / 2 - ln {ODDS:g} / d)"
                    )
                    for kind, name in (("decay", "decays"), ("sweep", "multisines"))
                )
            ),
            "rivals_rule": (
                "named"
                if self.named
                else (
                    "the first-ranked candidate and those tied with it"
                    if self.all_pairs
                    else "no candidate is tied with the first: the first against the runners-up that beat the nominal "
                    "model"
                )
            ),
            "pairs": [[self.rivals[i].name, self.rivals[j].name] for i, j in self.pairs],
            "repeats": self.repeats,
            "experiments": len(self.plan),
            "max_repeats": MAX_REPEATS,
            "noise": {
                "signals": {s: {"value": v, "source": self.noise_source[s]} for s, v in self.sample_noise.items()},
                "note": (
                    "per decay: the template fit's standard errors plus the data's run-to-run scatter (per speed of "
                    "the data, linear between them)"
                    + (
                        "; the records log no steer: each rival's spread over the kick's initial steer rate "
                        f"(up to {max(self.kick_rates) / KICK_NODES[-1]:g} times the roll rate either way) per run"
                        if len(self.kick_rates) > 1
                        else ""
                    )
                    if self.records
                    else "per decay: the data's standard uncertainty (per measured speed, linear between them)"
                ),
            },
            "plan": [item_dict(item) for item in self.plan[:top]],
            "combined": self.combined,
            "next_run": self.next_run,
            "best_per_signal": best_of("signal") if self.records or self.sweeps else None,
            "best_per_law": best_of("law"),
            "best_per_speed": {f"{k:g}": v for k, v in best_of("speed").items()},
            "best_per_push": {f"{k:g}": v for k, v in best_of("push").items()} if self.records else None,
            "left_out": self.left_out,
            "laws": {name: law.describe() for name, law in self.laws.items()},
            "points": [
                {
                    "kind": "decay",
                    "speed": e.speed,
                    "law": e.law,
                    "signal": e.signal,
                    "push": e.push,
                    "predicted": {
                        r.name: {
                            "real": float(self.mean[k, m].real),
                            "imag": float(self.mean[k, m].imag),
                            "sigma": [
                                float(math.sqrt(self.own_cov[k, m, 0, 0])),
                                float(math.sqrt(self.own_cov[k, m, 1, 1])),
                            ],
                            "kick_sigma": [
                                float(math.sqrt(self.kick_cov[k, m, 0, 0])),
                                float(math.sqrt(self.kick_cov[k, m, 1, 1])),
                            ]
                            if self.kick_cov is not None
                            else None,
                            "form_sigma": [
                                float(math.sqrt(self.form_cov[k, m, 0, 0])),
                                float(math.sqrt(self.form_cov[k, m, 1, 1])),
                            ]
                            if self.form_cov is not None
                            else None,
                        }
                        for k, r in enumerate(self.rivals)
                    },
                    "data_sigma": [float(math.sqrt(self.data_cov[m, 0, 0])), float(math.sqrt(self.data_cov[m, 1, 1]))],
                    "model_sigma": [
                        float(math.sqrt(self.model_cov[m, 0, 0])),
                        float(math.sqrt(self.model_cov[m, 1, 1])),
                    ],
                }
                for m, e in enumerate(self.points)
            ]
            + [self._sweep_point(m) for m in range(len(self.sweeps))],
            "sweeps": {
                "torque": float(self.torque),
                "run_time": float(self.run_time),
                "distortion": {"value": self.sweep_distortion, "source": self.distortion_source},
                "record": RECORD,
                "note": (
                    "per run: the DFT estimate's variance 2 sigma_y^2 / (N a^2) at each line (sigma_y the signal's "
                    "sample noise, N samples, a the line's torque amplitude), the data's speed scatter, and the "
                    "response moving as the weave eigenvalue moved from run to run in the data, and at each line "
                    "the share of the response a linear model misses (distortion); a friction rival by its runs "
                    "simulated in time, the same friction sticking (stick-slip) counted as its own uncertainty"
                ),
            }
            if self.run_sweeps
            else None,
        }

    def _sweep_point(self, m: int) -> dict:
        e = self.sweeps[m]
        K = len(e.lines)

        def sd(cov):
            return np.sqrt(np.diag(cov)).reshape(2, K).tolist()

        return {
            "kind": "sweep",
            "speed": e.speed,
            "law": e.law,
            "signal": e.signal,
            "torque": e.torque,
            "run_time": e.run_time,
            "lines": list(e.lines),
            "predicted": {
                r.name: {
                    "real": self.sweep_mean[k, m].real.tolist(),
                    "imag": self.sweep_mean[k, m].imag.tolist(),
                    "sigma": sd(self.sweep_own[k, m]),
                }
                for k, r in enumerate(self.rivals)
            },
            "settle": float(self.sweep_settle[m]) if self.sweep_settle is not None else None,
            "peak_roll": {r.name: float(self.sweep_roll[k, m]) for k, r in enumerate(self.rivals)}
            if self.sweep_roll is not None
            else None,
            "data_sigma": sd(self.sweep_data[m]),
            "run_to_run_sigma": sd(self.sweep_run[m]),
            "model_sigma": sd(self.sweep_model[m]),
        }


def planned_rows(points, laws: dict[str, ControlLaw], speed_measured: bool | None = None) -> EigenvalueData:
    """Eigenvalue rows (no measured values) at planned experiments ``points``, for the rivals to predict:
    each point's speed and the gains of its law there; ``speed_measured``, when given, says whether a
    speed sensor reads the runs' speed (as the data's)."""
    n = len(points)
    gains = np.array([laws[e.law](e.speed) for e in points]).reshape(n, 4)
    return EigenvalueData(
        np.array([e.speed for e in points]),
        np.zeros(n, complex),
        np.ones(n),
        np.ones(n),
        np.zeros(n),
        ["weave"] * n,
        ["next"] * n,
        gains,
        [e.describe() for e in points],
        [e.law for e in points],
        {e.law: laws[e.law] for e in points},
        speed_sensor=None if speed_measured is None else np.full(n, speed_measured),
    )


def _split(z: np.ndarray) -> np.ndarray:
    """Complex ``(P, n)`` to real ``(P, 2 n)``: real parts, then imaginary parts."""
    z = np.asarray(z)
    return np.concatenate([z.real, z.imag], axis=-1)


def _root(cov: np.ndarray) -> np.ndarray:
    """``L`` with ``L L^T = cov`` (symmetric, positive semi-definite; the negative rounding clipped)."""
    vals, vecs = np.linalg.eigh((cov + cov.T) / 2)
    return vecs * np.sqrt(np.clip(vals, 0.0, None))


def _no_canonical():

    return CanonicalData.empty()


def plan_next(
    diagnosis,
    rivals: Sequence[str] | None = None,
    speeds=None,
    repeats: int = DEFAULT_REPEATS,
    noise: dict[str, float] | None = None,
    signals: Sequence[str] | None = None,
    sweeps: bool = True,
    torque: float = DEFAULT_TORQUE,
    run_time: float = DEFAULT_RUN_TIME,
    distortion: float | None = None,
) -> NextExperiment:
    """The ranked plan of new measurements for ``diagnosis`` (module docstring), frozen.

    Parameters
    ----------
    diagnosis : bikerider.gap.diagnosis.result.Diagnosis
    rivals : sequence of str, optional
        Candidates to tell apart (``"steer_damping"``, ``"parameters+steer_damping"``); default as the
        module docstring says.
    speeds : array_like, optional
        Speeds to consider [m/s] (default :data:`N_SPEEDS` over :data:`SPEED_SPAN` of the data's).
    repeats : int
        Decays per experiment the plan is ranked for.
    noise : dict, optional
        Sample noise of signals (overrides what the data give and :data:`~bikerider.gap.plan.noise.ASSUMED_NOISE`).
    signals : sequence of str, optional
        Signals to consider with records (default: every one of :data:`bikerider.gap.measured.records.SIGNALS`).
    sweeps : bool
        Also plan steer-torque frequency responses (:mod:`bikerider.gap.plan.sweeps`).
    torque : float
        Peak steer torque of a planned multisine [N m].
    run_time : float
        Recorded length of one multisine run [s].
    distortion : float, optional
        Share of a multisine run's response a linear model misses at each line (default: from the records'
        fits, ``sqrt(1 - r^2)``, or :data:`ASSUMED_DISTORTION`); 0 is an ideal, linear test rig.

    Raises
    ------
    NoExperiment
        When nothing can be planned (no rivals, no measurable experiment), with the reason.
    bikerider.errors.InputError
        For a bad option.
    """
    b = _Planner(diagnosis, rivals, speeds, repeats, noise, signals, sweeps, torque, run_time, distortion)
    unranked = NextExperiment(
        diagnosis=b.diagnosis,
        problem=b.problem,
        rivals=tuple(b.rivals),
        all_pairs=b.all_pairs,
        named=b.named,
        pairs=tuple(b.pairs),
        repeats=b.repeats,
        speeds=b.speeds,
        laws=b.laws,
        records=b.records,
        sample_noise=b.sample_noise,
        noise_source=b.noise_source,
        signal_fits=b.signal_fits,
        points=tuple(b.points),
        templates=b.templates,
        simulator=b.simulator,
        mean=b.mean,
        own_cov=b.own_cov,
        data_cov=b.data_cov,
        model_cov=b.model_cov,
        run_sweeps=b.run_sweeps,
        torque=float(b.torque),
        run_time=float(b.run_time),
        sweeps=tuple(b.sweeps),
        sweep_mean=b.sweep_mean,
        sweep_own=b.sweep_own,
        sweep_form=b.sweep_form,
        sweep_data=b.sweep_data,
        sweep_model=b.sweep_model,
        sweep_run=b.sweep_run,
        sweep_distortion=b.sweep_distortion,
        distortion_source=b.distortion_source,
        left_out=tuple(b.left_out),
        own_factor=tuple(b.own_factor),
        sweep_factor=tuple(b.sweep_factor),
        sweep_settle=b.sweep_settle,
        sweep_roll=b.sweep_roll,
        kick_cov=b.kick_cov,
        kick_rates=tuple(b.kick_rates),
        form_cov=b.form_cov,
    )
    try:
        combined = combine(unranked)
    except (np.linalg.LinAlgError, ValueError) as exc:  # the ranked plan stands without it
        LOG.warning("runs combined over experiments not evaluated: %s", exc)
        combined = None
    ranked = replace(unranked, plan=tuple(rank(unranked)), combined=combined)
    return replace(ranked, next_run=sequential.next_run(ranked))
