"""Records in the time domain: linear responses, initial states, nonlinear steer friction.

* :func:`initial_states` fits each record's initial state (and a constant offset per signal) to the
  record's signals by linear least squares for a linear closed-loop model (the response is linear
  in the initial state), each signal weighted by its own scatter over the record, directions the record
  hardly sees left out (:data:`STATE_RCOND`).  What the record
  fit finds in a model's response from that state (the record's *apparent* eigenvalue under the
  model, and the fit's bias) is :mod:`bikerider.gap.inference.indirect`'s.

Nonlinear steer friction, ``T = -T_coulomb tanh(deltad / eps) - c_viscous deltad`` on the steer
axis, is fitted in the time domain (:func:`fit_time_domain`): the closed-loop bicycle (nominal
parameters, the records' control law and speed) is simulated from each record's initial state and
its roll rate and steer angle (the signals the record holds among them) are compared with the
record's, every signal weighted by its own scatter.  The simulation is an exponential integrator:
the linear part exact (matrix exponential), the friction torque held over steps of at most
:data:`MAX_STEP`.  The sign function is smoothed as ``tanh(deltad / eps)`` with ``eps =`` :data:`SMOOTHING`
rad/s (the friction reaches 76 % of its full value at ``eps``, 96 % at twice it).  Where the records move
the steer at rates of a few ``eps`` (roll-rate decays with a rider) the corner, which the records do not
decide, moves the fitted split: the fit to all the data carries it as a share of its covariance
(:func:`corner_share`).  Each record's initial
state is refitted for every trial friction (the best of a few starts, then Gauss-Newton steps on the
nonlinear response: :func:`friction_states`); the residuals' slopes in the fitted values hold each state at
its fit and move it to first order (variable projection: :func:`_held_changes`).  The friction's prediction of a record's eigenvalue is what the record fit
finds in the simulated response (indirect inference, as for every candidate; amplitude-dependent as
friction is: :meth:`bikerider.gap.inference.indirect.RecordSimulator.apparent_time_domain`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, least_squares
from scipy.special import ndtr

from bikerider.benchmark.simulation import discretise, expm
from bikerider.errors import FitError
from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.candidates.effects import EFFECTS, SPEED_SENSOR, STEER_DAMPING, STEER_FRICTION
from bikerider.gap.measured.records import Record

try:  # numpy.einsum's kernel without its Python wrapper, which costs as much as a product on these sizes
    from numpy._core._multiarray_umath import c_einsum
except ImportError:  # another NumPy layout: the public function (the same kernel)
    c_einsum = np.einsum

OBSERVED = {"roll_angle": 0, "steer_angle": 1, "roll_rate": 2, "steer_rate": 3}
"""Record signals and the index of their state among ``(phi, delta, phid, deltad)``."""
TIME_DOMAIN_SIGNALS = ("roll_rate", "steer_angle")
"""Signals the friction fit compares (those of them a record holds)."""
SMOOTHING = 0.05
"""``eps`` of the smoothed sign function ``tanh(deltad / eps)`` [rad/s]: the fits' own friction corner."""
CORNER_FACTOR = 2.5
"""The friction law's corner the data do not decide: ``eps`` log-uniform between :data:`SMOOTHING` divided and
multiplied by this factor (0.02-0.125 rad/s).  The steer-by-wire logs fit every corner from 0.01 to 0.1 rad/s
with the same friction and held-out errors against the noise of 1.18, 1.12, 0.98, 0.97 (eps 0.01, 0.02, 0.05,
0.1; docs/gap.md, *The friction law's corner*); a roll-rate-only decay with the rider moves the steer at
0.05-0.1 rad/s, where the corner moves the fitted Coulomb level by a third (:func:`corner_share`)."""
CORNER_NODES = (0.0, -math.sqrt(0.6), math.sqrt(0.6))
CORNER_WEIGHTS = (4.0 / 9.0, 5.0 / 18.0, 5.0 / 18.0)
"""Three-point Gauss-Legendre rule over the corner's uniform range in ``log eps`` (exact for a response
quadratic in ``log eps``: mean and variance of the range): the nodes as fractions of the half range, their
weights; the first node is the fits' own corner :data:`SMOOTHING`."""


def corner_nodes() -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The friction corners ``eps`` [rad/s] over which the corner's share is taken, and their weights:
    :data:`CORNER_NODES` over ``log eps`` across :data:`CORNER_FACTOR` either way of :data:`SMOOTHING` (the
    first node)."""
    half = math.log(CORNER_FACTOR)
    return tuple(SMOOTHING * math.exp(half * x) for x in CORNER_NODES), CORNER_WEIGHTS


CORNER_MIXTURE_POINTS = 201
"""Corners over the range (evenly in ``log eps``) of :meth:`CornerShare.interval`'s mixture."""

_SINE_NODES, _SINE_WEIGHTS = np.polynomial.legendre.leggauss(64)
_SINE_ANGLES = 0.25 * math.pi * (_SINE_NODES + 1.0)  # (0, pi/2)


def describing_gain(amplitude, smoothing: float | None = None) -> np.ndarray:
    """The viscous damping per unit Coulomb level of ``T tanh(deltad / eps)`` on a sinusoidal steer rate.

    Its describing function: for ``deltad = A sin(theta)`` the torque's first harmonic over ``A``,
    ``(4 / (pi A)) int_0^(pi/2) tanh(A sin(theta) / eps) sin(theta) dtheta`` [1/(rad/s)] (64-point
    Gauss-Legendre), which tends to ``4 / (pi A)`` for a sharp corner (``A >> eps``) and to ``1 / eps``
    for a slow one.  ``amplitude`` ``A`` [rad/s] broadcasts; ``eps`` is ``smoothing``, :data:`SMOOTHING`
    when not given.
    """
    eps = SMOOTHING if smoothing is None else float(smoothing)
    A = np.asarray(amplitude, dtype=float)
    if not eps > 0:
        raise ValueError(f"the friction's smoothing eps must be positive, got {smoothing!r} rad/s")
    if np.any(~(A > 0)):
        raise ValueError(f"a describing function needs a positive steer-rate amplitude, got {amplitude!r} rad/s")
    s = np.sin(_SINE_ANGLES)
    integral = 0.25 * math.pi * np.tanh(A[..., None] * s / eps) @ (_SINE_WEIGHTS * s)
    return 4.0 / (math.pi * A) * integral


MAX_STEP = 0.01
"""Longest integration step of the nonlinear simulation [s]; shorter where the friction's slope at
zero steer rate, ``T_coulomb / eps``, would make the explicit friction term stiff (step times that
slope over the steer inertia kept below one)."""
MAX_DURATION = 2.5
"""Longest part of a record the time-domain fits use [s] (the weave has decayed by then)."""
FIT_STEP = 0.02
"""Sampling step of the time-domain fits [s]: records sampled faster are compared at every k-th sample."""
FIT_GRID = ((0.02, 0.08, 0.2), (0.0, 0.1, 0.4))
"""Coulomb levels [N m] and viscous parts [N m s/rad] of the grid a time-domain fit without a start searches
(:func:`fit_time_domain`)."""
FIT_STARTS = 2
"""Grid points a time-domain fit without a start refines by local least squares: the residual over Coulomb
and viscous friction has more than one valley on roll-rate records (calibration seed 1036 with the truth's
own parameters, no noise: from the best point of the grid before, 0.15 N m and 0.30 N m s/rad at a weighted
residual of 0.71; from the truth, 0.18 N m and none at 0.075)."""
STATE_STEPS = 8
"""Most Gauss-Newton steps refining each record's initial state under friction (:func:`friction_states`),
each on the nonlinear response's own slopes in the state (one batched simulation of the state and its
``n`` probes) and kept only where it lowers the record's residual.  Chord steps on the linear part's slopes
did this before and did not converge where the friction holds the steer: on the calibration's
``steer_coulomb`` records (roll rate only) with the truth's own parameters, corner and no noise (seed 1028,
``T_coulomb`` 0.2025 N m), the truth's own initial states reproduced the records to a weighted residual of
0.04-2.1 per record, the chord steps' states missed them by 5-119 (one at a roll angle of -30 rad), and the
fit made up for it in the split: 0.105 N m Coulomb plus 0.93 N m s/rad viscous friction that is not there
(docs/gap_validation.md part 4, item 16).  Each step costs one batched simulation of the trial and its
``n`` probes (the last step's trial alone where no slopes are asked for); they stop early at :data:`STATE_TOLERANCE` or when a step no longer lowers the residuals by
:data:`STATE_GAIN` of them (on the steer-by-wire logs most calls still take all eight)."""
STATE_STANDINS = (1.0, 0.3, 0.01)
"""Steer-rate amplitudes [rad/s] of the viscous stand-ins of the friction whose linear least squares start
each record's initial state under friction (:func:`friction_states`): a steer damper of ``N(A) T_coulomb``,
``N`` the describing function of the fit's own law (:func:`describing_gain`: ``4 / (pi A)`` for a fast
steer, the slope at rest ``1 / eps`` for a slow one).  With a start from the linear part alone and one
from the records' first samples (the rest of the state at rest), the start whose nonlinear residual is
smallest begins the Gauss-Newton steps: the linear part alone starts far off where the friction holds the
steer."""
STATE_KICKS = (-2.5, -1.0, 1.0, 2.5)
"""Further starts for records of the roll rate alone: the records' first samples with a steer rate of these
multiples of the first roll rate (the steer rate such a record hardly shows, as a kick leaves it; the plan
spans a kick's steer rate over the same range, :data:`bikerider.gap.plan.decays.KICK_STEER_RATE`)."""
STATE_LIMITS = (0.5, 1.0)
"""Largest roll and steer angle [rad] of a record's initial state under friction: a start or a step beyond
them is not taken (a bicycle past 0.5 rad of roll has fallen; the linear least squares of a roll-rate record
put states of several radians in the directions it hardly sees, and the friction's response from there is
a valley of the residual far from the record's own state)."""
STATE_STARTS = 2
"""Starts of :data:`STATE_STANDINS` (and the rest start) each refined by the Gauss-Newton steps, the best
first, for records of the roll rate alone (records holding the steer angle: the best one)."""
STATE_TOLERANCE = 1e-4
"""The Gauss-Newton steps stop when no record's initial state would move by more than this share of its size
(its largest component, at least 1e-3 in the state's units), or none but records where the step, cut to
a sixteenth, still raised the residual."""
STATE_GAIN = 1e-4
"""The Gauss-Newton steps also stop when a step lowers the records' residuals (the better start's, summed)
by less than this share of them."""
STATE_PROBE = 1e-4
"""Finite-difference step of the nonlinear response's slopes in the initial state, relative to the state's
largest component (at least 0.1 in its units)."""
STATE_RCOND = 5e-4
"""Relative singular value below which a direction of a record's initial state is left out of its fit.

Each record's initial state (and offsets) is the least squares of its weighted design (:func:`_stack`),
solved by truncated SVD: a direction whose singular value is below ``STATE_RCOND`` times the design's
largest is left at zero (:func:`_truncated_inverse`).  A record holding the roll rate alone sees some
directions of the state hardly at all (relative singular values 1e-4 to 2e-3 in the calibration's
``steer_coulomb`` records: the fast caster mode, -8 to -27 1/s, at 1e-4 to 3e-4, 1e-3 to 3e-3 in the
controlled runs, and the slow capsize mode, within 0.1 1/s of zero, at 5e-4 to 2.4e-3; both hardly move
the roll rate); fitted, they took the
gyro's noise up to states of 2 to 250 rad/s (the ridge of the normal equations before acted only below
about 1e-6), and such a state then drove the nonlinear friction simulation and the fit's split (the
friction read as viscous damping that is not there).  Measured on the ``steer_coulomb`` trials of seeds
1000-1019 (95 % intervals holding the truth, median relative error of ``T_coulomb``; ``c_viscous``'s
truth is 0):

* 1e-6 (as the ridge before; the stored fits to one interval): ``T_coulomb`` 17/20, -36 %;
  ``c_viscous`` 14/20, median fit 0.38 N m s/rad;
* 1e-4: 16/20, -31 %; ``c_viscous`` 14/20;
* 5e-4: 17/20, -4 %; ``c_viscous`` 17/20;
* 1e-3: 17/20, -5 %; ``c_viscous`` 19/20;
* 3e-3: 17/20, +5 %; ``c_viscous`` 20/20.

Records holding the steer angle too see nearly every direction, and their fits must stay as they were:
the simulated friction trials' smallest relative singular value was 8.7e-3 (270 records), but the
steer-by-wire records of docs/gap_real_data.md reach down to 9.0e-4 (median 6.8e-3, 168 of 2915 designs
below 3e-3).  With 3e-3 or 2e-3 their speed-sensor-and-friction pair moved (held-out error 1.14 -> 1.18,
``T_coulomb`` interval [0.258, 0.462] -> [0.079, 0.71] N m), with 1e-3 one value's third digit; and a
hard cut makes the fit jump where a direction crosses it as the speed changes: with 1e-3 the
roll-rate-only plan's spread over the friction corner stepped by 0.117 rad/s between speeds 0.1 m/s apart
(0.057 before; tests/gap/plan/test_gap_next_kick.py).  5e-4 leaves both as they were (a factor 1.8 below
the steer-by-wire records' smallest) and takes part of the gain on the roll-rate-only records: over the
calibration's 200 ``steer_coulomb`` trials ``T_coulomb``'s coverage 63 % -> 71 % (median error -35 % ->
-6 %), ``c_viscous``'s 60 % -> 79 % (3e-3 gave 79 % and 90 %; docs/gap_validation.md part 4, item 11).
"""
THETA_STEP = 2e-3
"""Finite-difference step of the fitted values' slopes (N m, N m s/rad and the partner's units)."""


@dataclass
class Batch:
    """Records of one sampling step, padded to a common length.

    Attributes
    ----------
    records : list of Record
    dt : float
    length : ndarray of int
        Samples used of each record.
    y : dict
        Signal name to ``(R, N)`` samples (NaN beyond a record's length or where it lacks the signal).
    weight : dict
        Signal name to ``(R,)`` weights (1 / the signal's scatter over the record; 0 if absent).
    """

    records: list[Record]
    dt: float
    length: np.ndarray
    y: dict[str, np.ndarray]
    weight: dict[str, np.ndarray]

    @property
    def N(self) -> int:
        return int(self.length.max())


def make_batches(
    records: list[Record],
    signals=TIME_DOMAIN_SIGNALS,
    max_duration: float = MAX_DURATION,
    min_step: float = 0.0,
    skip_nonuniform: bool = False,
) -> list[tuple[list[int], Batch]]:
    """Group records by sampling step (uniformly sampled records only); ``[(indices, batch)]``, the indices
    into ``records``.

    Each record is used up to ``max_duration`` seconds, every ``k``-th sample where the sampling step
    is shorter than ``min_step`` (the fits compare the weave, a few hertz, at 50 Hz).  A record not
    uniformly sampled raises :class:`~bikerider.errors.FitError`, or with ``skip_nonuniform`` is left out
    of every batch.
    """
    groups: dict[float, list[int]] = {}
    for k, r in enumerate(records):
        steps = np.diff(r.time)
        if steps.size == 0 or not np.allclose(steps, steps[0], rtol=1e-6, atol=1e-9):
            if skip_nonuniform:
                continue
            raise FitError(f"{r.name}: the time-domain fit needs uniformly sampled records")
        groups.setdefault(round(float(steps[0]), 9), []).append(k)
    out = []
    for dt, idx in groups.items():
        every = max(1, int(round(min_step / dt))) if min_step > dt else 1
        step = dt * every
        recs = [records[k] for k in idx]
        limit = int(round(max_duration / step)) + 1 if math.isfinite(max_duration) else 1 << 30
        length = np.array([min((r.time.size - 1) // every + 1, limit) for r in recs])
        N = int(length.max())
        y, weight = {}, {}
        for name in signals:
            Y = np.full((len(recs), N), np.nan)
            W = np.zeros(len(recs))
            for j, r in enumerate(recs):
                if name in r.signals:
                    values = r.signals[name][::every][: length[j]]
                    if np.all(np.isfinite(values)):
                        Y[j, : length[j]] = values
                        spread = float(np.std(values))
                        W[j] = 1.0 / spread if spread > 0 else 0.0
            if np.any(W > 0):
                y[name], weight[name] = Y, W
        out.append((idx, Batch(recs, step, length, y, weight)))
    return out


@dataclass(frozen=True)
class Layout:
    """The fitted parameters of a time-domain candidate: ``(effect, parameter)`` pairs with bounds.

    ``steer_friction``'s ``T_coulomb`` and ``c_viscous`` come first; an added linear effect's
    parameters follow (``steer_inertia``, ``steer_stiffness``, ``speed_sensor``).
    """

    names: tuple[tuple[str, str], ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    start: tuple[float, ...]

    @staticmethod
    def of(effects: tuple[str, ...]) -> Layout:
        names, lower, upper, start = [], [], [], []
        for effect in sorted(effects, key=lambda e: e != STEER_FRICTION):
            for p in EFFECTS[effect].parameters:
                names.append((effect, p.name))
                lower.append(p.bounds[0])
                upper.append(p.bounds[1])
                start.append(p.start)
        return Layout(tuple(names), tuple(lower), tuple(upper), tuple(start))

    def value(self, theta: np.ndarray, name: str, default: float = 0.0) -> np.ndarray:
        """Column ``name`` of parameter vectors ``theta (P, k)`` (``default`` when not fitted)."""
        for k, (_, param) in enumerate(self.names):
            if param == name:
                return theta[:, k]
        return np.full(theta.shape[0], default)


NOMINAL = Layout((), (), (), ())
"""The nominal linear model (nothing fitted)."""


def systems(values: dict, geometry, records: list[Record], layout: Layout, theta: np.ndarray):
    """Closed-loop systems of every record for parameter vectors ``theta (P, k)``.

    Returns ``A (P, R, n, n)``, the steer-torque column ``b (P, R, n)``, the output state indices
    and the Coulomb friction ``T (P,)``.  A speed scale (``speed_sensor``) multiplies the speed of
    the records whose speed a sensor read; the control gains stay those of the recorded speed.
    """
    theta = np.atleast_2d(np.asarray(theta, dtype=float))
    P, R = theta.shape[0], len(records)
    config: dict[str, dict[str, np.ndarray]] = {}
    c = layout.value(theta, "c_viscous")
    if np.any(c != 0):
        config[STEER_DAMPING] = {"c_steer": c}
    for effect, param in layout.names:
        if effect not in (STEER_FRICTION, SPEED_SENSOR):
            config.setdefault(effect, {})[param] = layout.value(theta, param)
    scale = layout.value(theta, "speed_scale", 1.0)
    measured = np.array([r.speed_measured for r in records])
    speeds = np.array([r.speed for r in records])
    gains = np.array([r.gains for r in records])
    # one model call for every (parameter vector, record) pair
    flat_speeds = (np.where(measured[None, :], scale[:, None], 1.0) * speeds[None, :]).ravel()
    flat_values = {k: v for k, v in values.items()}
    flat_config = {e: {k: np.repeat(v, R) for k, v in p.items()} for e, p in config.items()}
    ss = EffectModel(flat_values, geometry, flat_config).state_space(flat_speeds)
    A = ss.closed_loop(np.tile(gains, (P, 1)))
    n = A.shape[-1]
    return (A.reshape(P, R, n, n), ss.B[..., :, 1].reshape(P, R, n), ss.output_states, layout.value(theta, "T_coulomb"))


def closed_loop(model: EffectModel, records: list[Record]) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
    """Closed-loop ``A (R, n, n)``, steer-torque column ``b (R, n)`` and output states of any linear model."""
    speeds = np.array([r.speed for r in records])
    gains = np.array([r.gains for r in records])
    ss = model.state_space(speeds)
    return ss.closed_loop(gains), ss.B[..., :, 1], ss.output_states


def _transitions(A: np.ndarray, dt: float, N: int) -> np.ndarray:
    """``Phi_k = expm(A k dt)`` for ``k < N``: shape ``A.shape[:-2] + (N, n, n)``."""
    step = expm(A * dt)
    out = np.empty(A.shape[:-2] + (N,) + A.shape[-2:])
    out[..., 0, :, :] = np.eye(A.shape[-1])
    for k in range(1, N):
        out[..., k, :, :] = step @ out[..., k - 1, :, :]
    return out


def _stack(batch: Batch, sensitivity: np.ndarray, outputs: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Weighted design ``(..., R, M, n + S)`` (state columns, then one offset per signal) and data ``(R, M)``.

    ``sensitivity`` is ``(..., R, N, n_out, n)``: each output state's response to the initial state.
    Samples beyond a record's length, and signals it lacks, are zero rows.
    """
    names = list(batch.y)
    mask = np.arange(batch.N)[None, :] < batch.length[:, None]  # (R, N)
    lead = sensitivity.shape[:-4]
    R, N, n = batch.y[names[0]].shape[0], batch.N, sensitivity.shape[-1]
    S = len(names)
    design = np.zeros(lead + (R, S, N, n + S))
    data = np.zeros((R, S, N))
    for m, s in enumerate(names):
        w = batch.weight[s][:, None] * mask  # (R, N)
        design[..., m, :, :n] = sensitivity[..., :, outputs[OBSERVED[s]], :] * w[..., None]
        design[..., m, :, n + m] = w
        data[:, m, :] = np.where(mask, np.nan_to_num(batch.y[s]), 0.0) * w
    return design.reshape(lead + (R, S * N, n + S)), data.reshape(R, S * N)


def _truncated_inverse(design: np.ndarray, rcond: float | None = None) -> np.ndarray:
    """The truncated inverse ``(..., R, k, k)`` of every ``(..., R)`` design's Gram matrix ``D^T D``.

    ``D^T D = V diag(s^2) V^T`` (``s`` the design's singular values, ``V`` its right singular vectors);
    directions whose singular value is below ``rcond`` (:data:`STATE_RCOND` when not given) times the
    largest are left out, so ``inverse @ D^T y`` is the minimum-norm least squares of the truncated SVD,
    ``D^+ y``: a state the record hardly sees is not fitted to its noise (a signal the record lacks, a zero
    offset column, is one such direction).  The Gram matrix's eigenvalues resolve ``rcond^2`` to the
    double's rounding of the largest, about 1e-16 of it, so ``rcond`` must be at least 1e-6; the
    decomposition then costs what the normal equations did (the SVD of the tall design, three times as much).
    """
    rcond = STATE_RCOND if rcond is None else float(rcond)
    if not rcond >= 1e-6:
        raise ValueError(f"rcond {rcond!r}: the Gram matrix resolves relative singular values down to 1e-6")
    gram = np.swapaxes(design, -1, -2) @ design
    w, V = np.linalg.eigh(gram)
    keep = w > rcond**2 * np.maximum(w[..., -1:], 1e-300)
    inverse_w = np.where(keep, 1.0 / np.where(keep, w, 1.0), 0.0)
    return (V * inverse_w[..., None, :]) @ np.swapaxes(V, -1, -2)


def _apply(design: np.ndarray, inverse: np.ndarray, data: np.ndarray) -> np.ndarray:
    """``inverse @ D^T data``: the least squares of data ``(..., R, M)`` (broadcast over the leading
    dimensions) with the truncated inverse of :func:`_truncated_inverse`."""
    rhs = np.einsum("...mk,...m->...k", design, data)
    return np.einsum("...kl,...l->...k", inverse, rhs)


def _solve(design: np.ndarray, data: np.ndarray, rcond: float | None = None) -> np.ndarray:
    """Least squares of every ``(..., R)`` design at once, truncated at ``rcond`` (:func:`_truncated_inverse`)."""
    return _apply(design, _truncated_inverse(design, rcond), data)


def initial_states(batch: Batch, A: np.ndarray, outputs: tuple[int, ...]) -> np.ndarray:
    """Initial states ``(..., R, n)`` fitted to each record for linear models ``A (..., R, n, n)``.

    Each signal ``s`` is modelled as ``C_s Phi(t) x0 + offset_s`` (an offset per signal, solved
    with the state), every signal weighted by its scatter over the record; directions the record hardly
    sees (relative singular value below :data:`STATE_RCOND`) are left out, not fitted to its noise.
    """
    Phi = _transitions(A, batch.dt, batch.N)  # (..., R, N, n, n)
    design, data = _stack(batch, Phi, outputs)
    return _solve(design, data)[..., : A.shape[-1]]


def simulate_linear(A: np.ndarray, x0: np.ndarray, dt: float, N: int) -> np.ndarray:
    """States ``(R, N, n)`` of ``x' = A x`` from ``x0`` ``(R, n)``."""
    step = expm(A * dt)
    out = np.empty(x0.shape[:-1] + (N, x0.shape[-1]))
    x = x0
    for k in range(N):
        out[..., k, :] = x
        x = np.einsum("...ij,...j->...i", step, x)
    return out


def simulate_friction(
    A: np.ndarray,
    b: np.ndarray,
    x0: np.ndarray,
    T_c,
    dt: float,
    N: int,
    rate_index: int,
    smoothing: float | None = None,
) -> np.ndarray:
    """States ``(..., N, n)`` of ``x' = A x + b (-T_c tanh(x[rate] / eps))`` (exponential integrator).

    ``A (..., n, n)``, ``b (..., n)``, ``x0 (..., n)`` and ``T_c`` broadcast together; ``eps`` is
    ``smoothing`` [rad/s], :data:`SMOOTHING` when not given.
    """
    eps = SMOOTHING if smoothing is None else float(smoothing)
    if not eps > 0:
        raise ValueError(f"the friction's smoothing eps must be positive, got {smoothing!r} rad/s")
    n = A.shape[-1]
    T_max = float(np.max(T_c)) if np.size(T_c) else 0.0
    stiffness = T_max / eps * float(np.max(np.abs(b[..., rate_index]))) if T_max > 0 else 0.0
    substeps = max(1, math.ceil(dt / MAX_STEP - 1e-9), math.ceil(dt * stiffness))
    h = dt / substeps
    Phi, Gamma, _ = discretise(A, b[..., None], h, hold="zoh")  # the friction torque held over each step
    Gamma = Gamma[..., 0]
    # The loop runs N * substeps times on small arrays: every system is a column of arrays whose
    # last axis runs over the systems (state rows first), so each step is a few vectorised operations
    # over all of them; the matrix-vector product by einsum over that layout.
    minus_T = -np.asarray(T_c, dtype=float)[..., None]
    x0 = np.asarray(x0, dtype=float)
    shape = np.broadcast_shapes(x0.shape, Gamma.shape, Phi.shape[:-1], minus_T.shape)
    lead = shape[:-1]
    count = math.prod(lead)
    phi = np.ascontiguousarray(np.moveaxis(np.broadcast_to(Phi, lead + (n, n)).reshape(count, n, n), 0, -1))
    gamma = np.ascontiguousarray(np.broadcast_to(Gamma, shape).reshape(count, n).T)  # (n, count)
    torque = np.broadcast_to(minus_T, lead + (1,)).reshape(count)
    x = np.ascontiguousarray(np.broadcast_to(x0, shape).reshape(count, n).T)  # (n, count)
    out = np.empty((N, n, count))
    u = np.empty(count)
    push = np.empty((n, count))
    spare = (np.empty((n, count)), np.empty((n, count)))
    if N:
        out[0] = x
    # each step written in place (the sample's row of ``out``, or a spare between substeps); the state
    # after the last sample is not computed (nothing uses it)
    for k in range(N - 1):
        x = out[k]
        for j in range(substeps):
            target = out[k + 1] if j == substeps - 1 else spare[j % 2]
            np.divide(x[rate_index], eps, out=u)
            np.tanh(u, out=u)
            np.multiply(torque, u, out=u)
            np.multiply(gamma, u, out=push)
            c_einsum("ijb,jb->ib", phi, x, out=target)
            target += push
            x = target
    return np.moveaxis(out, -1, 0).reshape(lead + (N, n))


def _residuals(batch: Batch, states: np.ndarray, outputs: tuple[int, ...]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Weighted residuals after the best constant offset per signal; ``(R, S, N)`` (0 outside)."""
    names = list(batch.y)
    mask = np.arange(batch.N)[None, :] < batch.length[:, None]
    res = np.zeros(states.shape[:-2] + (len(names), batch.N))
    offsets = {}
    for m, s in enumerate(names):
        sim = states[..., outputs[OBSERVED[s]]]
        diff = np.where(mask, batch.y[s] - sim, 0.0)
        off = diff.sum(axis=-1) / batch.length
        offsets[s] = off
        res[..., m, :] = np.where(mask, (sim + off[..., None] - batch.y[s]), 0.0) * batch.weight[s][..., None]
    return res, offsets


def friction_states(
    batch: Batch,
    A: np.ndarray,
    b: np.ndarray,
    outputs: tuple[int, ...],
    T_c,
    smoothing: float | None = None,
    slopes: bool = False,
) -> tuple[np.ndarray, ...]:
    """Each record's response to ``A (P, R, n, n)`` plus Coulomb friction ``T_c (P,)`` through ``b``
    (smoothed by ``smoothing``, :data:`SMOOTHING` when not given: :func:`simulate_friction`).

    The initial states are fitted to the records: for a linear model (no Coulomb friction) by linear least
    squares; under friction from the best of several starts (:func:`_friction_start`; the best two for
    records of the roll rate alone, whose residual has more than one valley), each refined by up to
    :data:`STATE_STEPS` Gauss-Newton steps on the nonlinear response's own slopes in the state, each kept
    only where it lowers the record's residual (and halved for that record where it did not), directions
    the record hardly sees left out as in the linear fit (:data:`STATE_RCOND`); the better end is kept.
    Returns the states ``(P, R, N, n)`` and the weighted residuals ``(P, R, S, N)``, and with ``slopes``
    the residuals' slopes in each record's initial state at its fit ``(P, R, S * N, n)`` (forward differences
    of :data:`STATE_PROBE`; the held-state slopes of :func:`_held_changes` project them out).
    """
    T = np.asarray(T_c, dtype=float).reshape(A.shape[:-3] + (1,))
    n = A.shape[-1]
    probes = np.eye(n)[:, None, None, None, :]  # (n, 1, 1, 1, n): one probe per state component
    if not np.any(T > 0):
        design, data = _stack(batch, _transitions(A, batch.dt, batch.N), outputs)
        x0 = _apply(design, _truncated_inverse(design), data)[..., :n]
        if not slopes:
            states = simulate_linear(A, x0, batch.dt, batch.N)
            return states, _residuals(batch, states, outputs)[0]
        h = STATE_PROBE * np.maximum(np.max(np.abs(x0), axis=-1), 0.1)  # (P, R)
        both = simulate_linear(
            A, np.concatenate([x0[None], x0[None] + probes[:, 0] * h[None, ..., None]]), batch.dt, batch.N
        )
        res = _residuals(batch, both, outputs)[0]
        J = (res[1:] - res[:1]) / h[None, ..., None, None]
        return both[0], res[0], np.moveaxis(J.reshape(J.shape[:-2] + (-1,)), 0, -1)
    rate = outputs[3]
    x0, states, res = _friction_start(batch, A, b, outputs, T, smoothing)  # (K, P, R, ...): K starts each
    cost = np.sum(res**2, axis=(-2, -1))
    scale = np.ones_like(cost)

    def responses(x: np.ndarray, slopes: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        # the response from x (K, P, R, n), its weighted residuals and, when asked, their slopes in x
        # (K, P, R, M, n), the probes simulated in the same pass as x itself (one pass of the loop
        # over the samples instead of two: the loop's cost is mostly per pass on the records' sizes)
        if not slopes:
            states = simulate_friction(A, b, x, T, batch.dt, batch.N, rate, smoothing)
            return states, _residuals(batch, states, outputs)[0], None
        h = STATE_PROBE * np.maximum(np.max(np.abs(x), axis=-1), 0.1)  # (K, P, R)
        both = simulate_friction(
            A,
            b,
            np.concatenate([x[None], x[None] + probes * h[None, ..., None]]),
            T,
            batch.dt,
            batch.N,
            rate,
            smoothing,
        )
        res = _residuals(batch, both, outputs)[0]
        J = (res[1:] - res[:1]) / h[None, ..., None, None]
        return both[0], res[0], np.moveaxis(J.reshape(J.shape[:-2] + (-1,)), 0, -1)

    J = responses(x0, True)[2]
    for step_index in range(STATE_STEPS):
        r = res.reshape(res.shape[:-2] + (-1,))
        step = -_apply(J, _truncated_inverse(J), r) * scale[..., None]
        size = np.maximum(np.max(np.abs(x0), axis=-1), 1e-3)
        if not np.any((np.max(np.abs(step), axis=-1) / size > STATE_TOLERANCE) & (scale >= 1 / 16)):
            break
        trial = x0 + step
        trial_states, trial_res, trial_J = responses(trial, slopes or step_index < STATE_STEPS - 1)
        trial_cost = np.sum(trial_res**2, axis=(-2, -1))
        better = (trial_cost < cost) & _within_limits(trial, outputs)
        gain = np.sum(np.where(better, cost - trial_cost, 0.0))
        x0 = np.where(better[..., None], trial, x0)
        states = np.where(better[..., None, None], trial_states, states)
        res = np.where(better[..., None, None], trial_res, res)
        if trial_J is not None:
            J = np.where(better[..., None, None], trial_J, J)
        cost = np.where(better, trial_cost, cost)
        scale = np.where(better, np.minimum(1.0, 2.0 * scale), 0.5 * scale)
        if gain <= STATE_GAIN * np.sum(np.min(cost, axis=0)):  # the residuals no longer fall
            break
    best = np.argmin(cost, axis=0)[None]  # (1, P, R): the better of the starts' ends
    states = np.take_along_axis(states, best[..., None, None], axis=0)[0]
    res = np.take_along_axis(res, best[..., None, None], axis=0)[0]
    if not slopes:
        return states, res
    return states, res, np.take_along_axis(J, best[..., None, None], axis=0)[0]


def _within_limits(x: np.ndarray, outputs: tuple[int, ...]) -> np.ndarray:
    """Whether initial states ``(..., n)`` hold the roll and steer angles within :data:`STATE_LIMITS`."""
    return (np.abs(x[..., outputs[0]]) <= STATE_LIMITS[0]) & (np.abs(x[..., outputs[1]]) <= STATE_LIMITS[1])


def _friction_start(
    batch: Batch, A: np.ndarray, b: np.ndarray, outputs: tuple[int, ...], T: np.ndarray, smoothing: float | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each record's starting initial states under friction ``T (P, 1)``: the best, by the nonlinear
    response's residual, of the linear least squares of the linear part alone and under each viscous stand-in
    of :data:`STATE_STANDINS`, and of the records' first samples with the rest of the state at rest (the best
    two for records of the roll rate alone).  Returns the states ``(K, P, R, n)``, their responses
    ``(K, P, R, N, n)`` and weighted residuals ``(K, P, R, S, N)``, ``K`` the starts kept."""
    n = A.shape[-1]
    rate = outputs[3]
    unit = np.zeros(n)
    unit[rate] = 1.0
    starts = []
    # records holding the steer angle see every direction of the state: the linear part's start is near
    # (the steer-by-wire logs); the stand-ins are for records of the roll rate alone
    steered = "steer_angle" in batch.y and bool(np.all(batch.weight["steer_angle"] > 0))
    for gain in (0.0,) if steered else (0.0, *describing_gain(np.array(STATE_STANDINS), smoothing)):
        c = T[..., None] * gain  # (P, 1, 1): a steer damper of c on the steer rate
        A_eq = A - (b * c)[..., :, None] * unit
        design, data = _stack(batch, _transitions(A_eq, batch.dt, batch.N), outputs)
        starts.append(_apply(design, _truncated_inverse(design), data)[..., :n])
    rest = np.zeros_like(starts[0])
    for name, index in (("roll_rate", outputs[2]), ("steer_angle", outputs[1])):
        if name in batch.y:
            rest[..., index] = np.nan_to_num(batch.y[name][:, 0])
    starts.append(rest)
    if not steered:  # the steer rate a roll-rate record hardly shows: spanned as a kick leaves it
        roll_rate = np.abs(rest[..., outputs[2]])
        for k in STATE_KICKS:
            kicked = rest.copy()
            kicked[..., rate] = k * roll_rate
            starts.append(kicked)
    X = np.stack(starts)  # (C, P, R, n)
    states = simulate_friction(A, b, X, T, batch.dt, batch.N, rate, smoothing)
    res, _ = _residuals(batch, states, outputs)
    keep = 1 if steered else STATE_STARTS
    cost = np.where(_within_limits(X, outputs), np.sum(res**2, axis=(-2, -1)), np.inf)
    best = np.argsort(cost, axis=0, kind="stable")[:keep]  # (K, P, R)

    def pick(Z: np.ndarray) -> np.ndarray:
        return np.take_along_axis(Z, best.reshape(best.shape + (1,) * (Z.ndim - 3)), axis=0)

    return pick(X), pick(states), pick(res)


@dataclass
class TimeDomainFit:
    """A time-domain candidate (steer friction, alone or with a linear partner) fitted to records.

    Attributes
    ----------
    values : ndarray
        The parameters in the order of the candidate's :class:`Layout` (``T_coulomb``, ``c_viscous``,
        then the partner's).
    cost : float
        Sum of squared weighted residuals.
    n_samples : int
    records : list of str
    success : bool
    """

    values: np.ndarray
    cost: float
    n_samples: int
    records: list[str]
    success: bool


def _weighted_residuals(
    batches,
    values: dict,
    geometry,
    layout: Layout,
    thetas: np.ndarray,
    rows: dict[str, np.ndarray] | None = None,
    smoothing: float | None = None,
) -> np.ndarray:
    """Weighted residuals ``(P, M)`` of every record for parameter vectors ``thetas (P, k)``, in one
    batched simulation per sampling step (each record's initial state refitted).  ``rows`` gives
    benchmark parameters a value per parameter vector (name to ``(P,)``); ``smoothing`` is the friction's
    corner (:data:`SMOOTHING` when not given)."""
    parts = []
    for _, batch in batches:
        R = len(batch.records)
        per_row = {k: np.repeat(np.asarray(v, float), R) for k, v in (rows or {}).items()}
        A, b, outputs, T = systems({**values, **per_row}, geometry, batch.records, layout, thetas)
        _, res = friction_states(batch, A, b, outputs, T, smoothing)
        parts.append(res.reshape(thetas.shape[0], -1))
    return np.concatenate(parts, axis=1)


def _held_fit(batches, values: dict, geometry, layout: Layout, theta: np.ndarray, smoothing: float | None = None):
    """Each batch's records fitted at ``theta`` ``(k,)``: a list, per batch, of the initial states ``(R, n)``,
    the weighted residuals ``(R, S, N)`` and their slopes in the initial states ``(R, S * N, n)``
    (:func:`friction_states`)."""
    out = []
    for _, batch in batches:
        A, b, outputs, T = systems(values, geometry, batch.records, layout, theta[None, :])
        states, res, J = friction_states(batch, A, b, outputs, T, smoothing, slopes=True)
        out.append((states[0, :, 0, :], res[0], J[0]))
    return out


def _held_changes(
    batches,
    values: dict,
    geometry,
    layout: Layout,
    held: list,
    thetas: np.ndarray,
    rows: dict[str, np.ndarray] | None = None,
    smoothing: float | None = None,
) -> np.ndarray:
    """The weighted residuals' changes ``(P, M)`` from a fit's (``held``, :func:`_held_fit`) at parameter
    vectors ``thetas (P, k)`` (and benchmark parameters ``rows``, name to ``(P,)``), each record's initial
    state held at its fit and moved to first order: the change simulated from the held state, less its
    projection on the residuals' slopes in the state (variable projection with Kaufman's slopes, Golub and
    Pereyra 2003).

    The residuals with each record's state refitted (the profile) are not a smooth function of the fitted
    values: the states' Gauss-Newton steps stop short of their minimum, which on the steer-by-wire logs
    lies along a valley where steps still lower the residuals by a few parts in 10^4 after eight, and a
    record may end in another valley.  Differences of refitted residuals over :data:`THETA_STEP` were off
    by 23 % and 32 % (the two friction values' columns) from differences refitted to convergence (40 steps),
    which themselves changed by 23 % when each refit started from the fit's states instead of afresh; the
    held states' slopes are the same every time and cost one simulation instead of a refit per value.
    """
    parts = []
    for (_, batch), (x0, res, Jx) in zip(batches, held):
        R, P = len(batch.records), thetas.shape[0]
        per_row = {k: np.repeat(np.asarray(v, float), R) for k, v in (rows or {}).items()}
        A, b, outputs, T = systems({**values, **per_row}, geometry, batch.records, layout, thetas)
        T = np.asarray(T, dtype=float).reshape(P, 1)
        states = simulate_friction(A, b, x0[None], T, batch.dt, batch.N, outputs[3], smoothing)
        change = (_residuals(batch, states, outputs)[0] - res[None]).reshape(P, R, -1)
        moved = np.einsum("rkl,rml,prm->prk", _truncated_inverse(Jx), Jx, change)  # the states' first-order move
        parts.append((change - np.einsum("rmk,prk->prm", Jx, moved)).reshape(P, -1))
    return np.concatenate(parts, axis=1)


def _held_residuals(held: list) -> np.ndarray:
    """The weighted residuals ``(M,)`` of a fit held by :func:`_held_fit`."""
    return np.concatenate([res.reshape(-1) for _, res, _ in held])


def _theta_steps(layout: Layout, theta: np.ndarray) -> np.ndarray:
    """Each fitted value's difference step: :data:`THETA_STEP`, backwards where forwards would pass its upper
    bound."""
    upper = np.asarray(layout.upper, float)
    return np.full(theta.size, THETA_STEP) * np.where(theta + THETA_STEP <= upper, 1.0, -1.0)


def _slopes(batches, values: dict, geometry, layout: Layout, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, list]:
    """The weighted residuals' slopes in the fitted values ``J (M, k)`` (differences of :data:`THETA_STEP`,
    backward at an upper bound, each record's initial state held at its fit and moved to first order:
    :func:`_held_changes`), the residuals at ``theta`` ``(M,)`` and the held fit (:func:`_held_fit`)."""
    held = _held_fit(batches, values, geometry, layout, theta)
    h = _theta_steps(layout, theta)
    J = (_held_changes(batches, values, geometry, layout, held, theta + np.diag(h)) / h[:, None]).T
    return J, _held_residuals(held), held


@dataclass
class FitCovariance:
    """The Gauss-Newton covariance of a time-domain fit from its own residuals (:func:`fit_covariance`).

    Attributes
    ----------
    covariance : ndarray
        ``s^2 (J^T J)^-1`` ``(k, k)``.
    reduced_chi2 : float
        ``s^2``: the sum of squared weighted residuals over the degrees of freedom.
    dof : int
        Residuals compared less the fitted values and each record's initial state and offsets.
    """

    covariance: np.ndarray
    reduced_chi2: float
    dof: int


def fit_covariance(records: list[Record], values: dict, geometry, layout: Layout, theta: np.ndarray) -> FitCovariance:
    """The data's share of a time-domain fit's covariance from the fit itself: ``s^2 (J^T J)^-1``.

    ``J`` is the slope of the weighted residuals in the fitted values (each record's initial state held at
    its fit and moved to first order: :func:`_held_changes`), ``s^2 = |r|^2 / (M - k - m)`` the reduced chi-square over
    the ``M`` residuals compared, the ``k`` fitted values and the ``m`` initial-state components and
    per-signal offsets fitted to each record.  The residuals are weighted by each signal's scatter over
    its record, not by its noise, so the weights fix only the signals' relative scale: the scale of the
    residuals is always estimated from them (``s^2`` is far below one on a good fit), and
    ``(value - truth) / stderr`` follows Student's t with ``M - k - m`` degrees of freedom.  Treating the
    samples as independent, this is optimistic where the residuals are correlated in time (model error,
    not white noise), which the jackknife over sessions is not; it is the fallback where there are too few
    sessions for one (:meth:`bikerider.gap.diagnosis.fits.Fits.time_domain_fit`).
    """
    batches = make_batches(records, min_step=FIT_STEP)
    theta = np.asarray(theta, dtype=float)
    J, r, _ = _slopes(batches, values, geometry, layout, theta)
    states = systems(values, geometry, batches[0][1].records[:1], layout, theta)[0].shape[-1]
    rows = nuisance = 0
    for _, batch in batches:
        for j in range(len(batch.records)):
            signals = sum(1 for w in batch.weight.values() if w[j] > 0)
            rows += int(batch.length[j]) * signals
            nuisance += states + signals
    dof = max(rows - theta.size - nuisance, 1)
    reduced = float(r @ r) / dof
    return FitCovariance(reduced * np.linalg.pinv(J.T @ J), reduced, dof)


def _parameter_slopes(
    records: list[Record], values: dict, geometry, layout: Layout, theta: np.ndarray, sigmas: dict[str, float]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The weighted residuals at ``theta`` ``(M,)``, their slopes in the fitted values ``J (M, k)`` and
    their change per standard uncertainty of each benchmark parameter in ``sigmas`` ``J_q (M, p)``
    (one-sided differences of one standard uncertainty; one batched simulation for ``J_q``)."""
    batches = make_batches(records, min_step=FIT_STEP)
    J, r, held = _slopes(batches, values, geometry, layout, theta)
    names = list(sigmas)
    shifted = np.diag([sigmas[n] for n in names])
    rows = {n: values[n] + shifted[:, j] for j, n in enumerate(names)}
    thetas = np.repeat(theta[None, :], len(names), axis=0)
    Jq = _held_changes(batches, values, geometry, layout, held, thetas, rows).T
    return r, J, Jq


def parameter_sensitivity(
    records: list[Record],
    values: dict,
    geometry,
    layout: Layout,
    theta: np.ndarray,
    sigmas: dict[str, float],
) -> np.ndarray:
    """How far a time-domain fit moves per standard uncertainty of each benchmark parameter, ``(k, p)``,
    every fitted value free (no bound in the way).

    The fit minimises ``|r(theta, q)|^2`` at the nominal parameters ``q``; a parameter error ``dq`` moves
    the minimum by ``dtheta = -(J^T J)^-1 J^T J_q dq`` (Gauss-Newton, ``J`` and ``J_q`` the residuals'
    slopes in the fitted values and in the parameters).  The columns are ``dtheta`` for one
    standard uncertainty of each parameter in ``sigmas`` (one-sided differences of that size: the
    parameters' error is a standard uncertainty, and the fit's response over it is what counts).  The
    error is common to every record, so no spread among the records or folds shows it.  Where a fitted
    value lies on a bound the fit does not move as this says: :func:`parameter_share`, which computes it
    (its ``sensitivity``) beside the bounded share the diagnosis uses.
    """
    return parameter_share(records, values, geometry, layout, theta, sigmas).sensitivity


PARAMETER_DRAWS = 4096
"""Draws of the benchmark parameters' error over which :func:`parameter_share` averages the fit's
bounded response (a fixed seed: the same share every run; its sampling error about 1 % of a standard
error, and none where no draw meets a bound)."""
PARAMETER_SEED = 20261128
"""Seed of those draws."""


def bounded_steps(H: np.ndarray, g: np.ndarray, low: np.ndarray, high: np.ndarray, tol: float = 1e-12) -> np.ndarray:
    """Minimisers ``d`` of ``g_s . d + d^T H d / 2`` within ``low <= d <= high``, one per row ``g_s``.

    ``H (k, k)`` positive (semi)definite, ``g (S, k)``; ``low``/``high`` ``(k,)`` (may be infinite).  Every
    face of the box (each value free, on its lower bound or on its upper one) is solved exactly and the
    lowest feasible point kept: the constrained minimum lies inside one face and is that face's own
    minimum.  For the few fitted values of a time-domain candidate (3^k faces) this is exact and vectorised
    over the rows.
    """
    S, k = g.shape
    best = np.zeros((S, k))
    best_cost = np.full(S, np.inf)
    for face in np.ndindex(*(3,) * k):  # 0 free, 1 on the lower bound, 2 on the upper
        state = np.array(face)
        bound = np.where(state == 1, low, np.where(state == 2, high, 0.0))
        if np.any(~np.isfinite(bound[state > 0])):
            continue
        free = state == 0
        d = np.broadcast_to(np.where(state > 0, bound, 0.0), (S, k)).copy()
        if np.any(free):
            Hff = H[np.ix_(free, free)]
            rhs = g[:, free] + (H[np.ix_(free, ~free)] @ bound[~free])[None, :]
            d[:, free] = -rhs @ np.linalg.pinv(Hff).T
        inside = np.all((d >= low - tol) & (d <= high + tol), axis=1)
        cost = np.einsum("sk,sk->s", g, d) + 0.5 * np.einsum("sk,kl,sl->s", d, H, d)
        better = inside & (cost < best_cost)
        best[better], best_cost[better] = d[better], cost[better]
    return best


@dataclass
class ParameterShare:
    """The benchmark parameters' share of a time-domain fit's covariance (:func:`parameter_share`).

    Attributes
    ----------
    covariance : ndarray
        ``(k, k)``: the mean square of the fit's move over the parameters' error, bounds respected.
    sensitivity : ndarray
        ``G (k, p)``, the free response per standard uncertainty (:func:`parameter_sensitivity`);
        ``covariance`` is ``G G^T`` where no draw meets a bound.
    bounded : float
        Share of the draws where a fitted value stayed on (or was moved onto) a bound.
    """

    covariance: np.ndarray
    sensitivity: np.ndarray
    bounded: float


def parameter_share(
    records: list[Record],
    values: dict,
    geometry,
    layout: Layout,
    theta: np.ndarray,
    sigmas: dict[str, float],
) -> ParameterShare:
    """The benchmark parameters' share of a time-domain fit's covariance, with the fit's bounds respected.

    A parameter error ``z`` (standard uncertainties) moves the fit to the minimum of the linearised
    ``|r + J d + J_q z|^2`` over the steps ``d`` that keep the values within their bounds
    (:func:`bounded_steps`; ``r`` the residuals at the fit, ``J``, ``J_q`` as in
    :func:`parameter_sensitivity`).  Inside the bounds that move is ``G z`` and its mean square over
    ``z ~ N(0, I)`` is ``G G^T``.  A value the fit holds on a bound (the viscous part at zero, where the
    residuals' slope pushes it below) cannot take its share of the move, and the rest of the fit takes
    it: calibration seed 1081 (Coulomb friction 0.199 N m, viscous 0, fitted 0.187 N m and 0), one
    standard uncertainty of the steer assembly's centre ``xH`` moves the refit ``T_coulomb`` by -0.0070
    N m, where the free ``G`` says -0.0007 N m and -0.0085 N m s/rad of viscous friction that the bound
    forbids.  Over the calibration's 200 friction trials (128 of them fitted on that bound) the intervals
    held the truth in 157 with ``G G^T``, every miss low, and in 190 with this share (the same fits).
    The share is the mean square of ``d(z) - d(0)`` over :data:`PARAMETER_DRAWS` draws, computed as
    ``G G^T`` plus the draws' mean of ``(d - d0)(d - d0)^T - (G z)(G z)^T`` (zero where no draw meets a
    bound, so it is then exactly ``G G^T``).  That mean is a difference of mean squares and can make the
    sum indefinite (a negative variance along some combination of the values: a NaN or too narrow an
    interval); the share returned is the sum made positive semidefinite, negative eigenvalues clipped to
    zero (:func:`positive_semidefinite`).
    """
    theta = np.asarray(theta, dtype=float)
    r, J, Jq = _parameter_slopes(records, values, geometry, layout, theta, sigmas)
    H = J.T @ J
    G = -np.linalg.pinv(H) @ (J.T @ Jq)
    low = np.asarray(layout.lower, float) - theta
    high = np.asarray(layout.upper, float) - theta
    z = np.random.default_rng(PARAMETER_SEED).standard_normal((PARAMETER_DRAWS, Jq.shape[1]))
    g0 = J.T @ r
    d = bounded_steps(H, g0[None, :] + z @ (J.T @ Jq).T, low, high)
    d0 = bounded_steps(H, g0[None, :], low, high)[0]
    free = z @ G.T
    moved = d - d0
    touched = np.any(np.abs(moved - free) > 1e-9 * (1.0 + np.abs(free)), axis=1)
    excess = (moved.T @ moved - free.T @ free) / PARAMETER_DRAWS
    return ParameterShare(positive_semidefinite(G @ G.T + excess), G, float(np.mean(touched)))


def positive_semidefinite(matrix: np.ndarray) -> np.ndarray:
    """``matrix`` symmetrised, its negative eigenvalues clipped to zero (unchanged where none is negative).

    :func:`parameter_share` adds to ``G G^T`` a difference of two mean squares, which rounding and the
    draws' sampling error can leave with a negative eigenvalue; a covariance with one gives a negative
    variance along it (a NaN or too narrow an interval for any value or combination that leans on it).
    """
    sym = 0.5 * (matrix + np.swapaxes(matrix, -1, -2))
    w, V = np.linalg.eigh(sym)
    if np.all(w >= 0):
        return sym
    return (V * np.clip(w, 0.0, None)[..., None, :]) @ np.swapaxes(V, -1, -2)


def fit_time_domain(
    records: list[Record], values: dict, geometry, layout: Layout, start=None, smoothing: float | None = None
) -> TimeDomainFit:
    """Fit a time-domain candidate (``layout``) to records (module docstring).

    Starts from ``start`` when given (a fit to more of the records, or the friction alone with the
    partner absent), else from the best :data:`FIT_STARTS` points of a small grid over the friction's
    range (:data:`FIT_GRID`, the partner absent), keeping the lowest of their local least squares.
    ``smoothing`` is the friction law's corner ``eps`` (:data:`SMOOTHING` when not given).
    """
    batches = make_batches(records, min_step=FIT_STEP)
    lower, upper = np.asarray(layout.lower, float), np.asarray(layout.upper, float)

    def costs(thetas: np.ndarray) -> np.ndarray:
        return _weighted_residuals(batches, values, geometry, layout, thetas, smoothing=smoothing)

    fitted: dict[bytes, list] = {}

    def held(theta: np.ndarray) -> list:
        # the records' fit at theta, kept for the slopes there (the least squares asks for the residuals
        # at a point, then for their slopes at the same point)
        key = theta.tobytes()
        if key not in fitted:
            fitted.clear()
            fitted[key] = _held_fit(batches, values, geometry, layout, theta, smoothing)
        return fitted[key]

    def fun(theta: np.ndarray) -> np.ndarray:
        return _held_residuals(held(theta))

    def jac(theta: np.ndarray) -> np.ndarray:
        h = _theta_steps(layout, theta)
        changes = _held_changes(batches, values, geometry, layout, held(theta), theta + np.diag(h), smoothing=smoothing)
        return (changes / h[:, None]).T

    if start is not None:
        starts = [np.clip(np.asarray(start, dtype=float), lower, upper)]
    else:
        rest = [1.0 if name == "speed_scale" else 0.0 for _, name in layout.names[2:]]  # the partner absent
        grid = np.array([[t, c] + rest for t in FIT_GRID[0] for c in FIT_GRID[1]] + [list(layout.start)])
        grid = np.clip(grid, lower, upper)
        order = np.argsort(np.sum(costs(grid) ** 2, axis=1), kind="stable")
        starts = [grid[k] for k in order[:FIT_STARTS]]
    scale = np.maximum(np.asarray(layout.start, float), 0.05) * 0.5
    result = None
    for x0 in starts:  # the lowest of the local least squares from each start
        local = least_squares(
            fun, x0, jac=jac, bounds=(lower, upper), method="trf", x_scale=scale, max_nfev=40, xtol=1e-3, ftol=1e-5
        )
        if result is None or np.sum(local.fun**2) < np.sum(result.fun**2):
            result = local
    n_samples = int(sum(batch.length.sum() for _, batch in batches))
    return TimeDomainFit(
        result.x, float(np.sum(result.fun**2)), n_samples, [r.name for r in records], bool(result.success)
    )


@dataclass
class CornerShare:
    """The friction corner's share of a time-domain fit's covariance (:func:`corner_share`).

    Attributes
    ----------
    covariance : ndarray
        ``(k, k)``: the weighted mean square of the fit's move from its own corner to each other.
    corners : list of (float, float, ndarray)
        ``(eps, weight, values)`` at each node of :func:`corner_nodes`, the fit's own first.
    """

    covariance: np.ndarray
    corners: list[tuple[float, float, np.ndarray]]

    def interval(self, k: int, half_width: float, lower: float, upper: float) -> tuple[float, float]:
        """The 95 % interval of value ``k`` over the corner's whole range, not only at the fit's own corner.

        Each corner's fit is known within ``+/- half_width`` (the 95 % half-width of the data's and the
        benchmark parameters' shares, the corner's left out).  The value is taken as a function of the
        corner, the quadratic in ``log eps`` through the three nodes' fits (exact at the Gauss-Legendre
        nodes; extended to the range's ends, 1.29 times the outer nodes' distance), and the interval is
        the central 95 % of the mixture over the corner's log-uniform prior of normal distributions
        centred there (each scaled so its own 95 % half-width is ``half_width``).  The fit's own corner
        lies at the middle of the range, and the values are seldom linear in ``log eps``: on 3-s
        roll-rate decays ``T_coulomb`` rises ever faster with the corner (0.018, 0.028, 0.052, 0.066 N m at
        0.02, 0.05, 0.10, 0.125 rad/s; steer_coulomb seed 1000, truth 0.066 at 0.10), so a symmetric interval
        about the middle corner's fit (the covariance's mean square of the moves) left the soft corners'
        truths above it: 20 of the 21 misses of docs/gap_validation.md item 17 lay low.  Where a corner's
        refit has no value, the interval is the fit's own corner's, ``+/- half_width``.
        """
        nodes = np.asarray(CORNER_NODES, float)
        at_nodes = np.array([c[2][k] for c in self.corners], float)
        if at_nodes.size != nodes.size or not np.all(np.isfinite(at_nodes)) or not math.isfinite(half_width):
            centre = float(self.corners[0][2][k])
            return max(centre - half_width, lower), min(centre + half_width, upper)
        u = np.linspace(-1.0, 1.0, CORNER_MIXTURE_POINTS)
        means = np.polyval(np.polyfit(nodes, at_nodes, 2), u)
        sd = half_width / 1.959963984540054
        if not sd > 0:  # each corner's fit exact: the central 95 % of the values over the corner
            low, high = np.quantile(means, [0.025, 0.975])
            return max(float(low), lower), min(float(high), upper)

        def below(x: float) -> float:
            return float(np.mean(ndtr((x - means) / sd)))

        span = (float(means.min()) - 10 * sd, float(means.max()) + 10 * sd)
        tol = 1e-9 * (span[1] - span[0])
        low = brentq(lambda x: below(x) - 0.025, *span, xtol=tol)
        high = brentq(lambda x: below(x) - 0.975, *span, xtol=tol)
        return max(low, lower), min(high, upper)


def corner_share(records: list[Record], values: dict, geometry, layout: Layout, theta: np.ndarray) -> CornerShare:
    """The share of a time-domain fit's covariance that comes from the friction corner the data do not decide.

    The fit models the sign of the steer rate as ``tanh(deltad / eps)`` at its own corner
    :data:`SMOOTHING`; real friction's corner (a sharp stick, a soft bearing seal) is not known, and where
    the records move the steer at rates of the order of ``eps`` it changes what the same torque does: on
    the calibration's 3-s roll-rate decays with the rider (steer-rate amplitudes 0.05-0.1 rad/s, a truth
    with a corner of 0.02 rad/s) the fit at 0.05 put ``T_coulomb`` a median 27 % above the truth, at 0.02
    about 10 % below it.  So the fit is refitted at the other nodes of :func:`corner_nodes`, and the share
    is the corner prior's mean square of the move from the fit, ``sum_k w_k (theta_k - theta)(theta_k -
    theta)^T``: the uncertainty of reporting the fit's own corner's values when the corner lies anywhere in
    its range.  It is known from the model, not estimated from the data, as the benchmark parameters' share
    is (:func:`parameter_share`).

    Each refit is the fit's own least squares at that corner (:func:`fit_time_domain`), started from the
    fit's values: two more fits, about 0.8 s on the steer-by-wire logs.  Chord steps with the fit's own
    slopes cost a fifth of that, but along the valley where Coulomb and viscous friction trade off they
    stopped at residuals up to 25 % above the refit's (decays of 0.03-0.07 rad/s steer rate), and the
    share would be a share of where they stopped.
    """
    theta = np.asarray(theta, dtype=float)
    eps, weights = corner_nodes()
    corners = [(eps[0], weights[0], theta)]
    for e, w in zip(eps[1:], weights[1:]):
        corners.append((e, w, fit_time_domain(records, values, geometry, layout, start=theta, smoothing=e).values))
    moves = np.array([c[2] - theta for c in corners])
    covariance = (np.asarray(weights)[:, None] * moves).T @ moves
    return CornerShare(covariance, corners)
