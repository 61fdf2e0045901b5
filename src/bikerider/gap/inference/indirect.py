"""Indirect inference on records: what the record fit finds in a model's own response over each record.

A record's weave eigenvalue is what :func:`bikerider.gap.measured.extraction.weave_eigenvalue` finds in a
short decay that also holds the castor and slow modes and the control's action.  A model's
prediction of that observation is therefore not its weave eigenvalue but what the *same* fit finds
in the model's own response over the record's window, from the initial state fitted to the record
under that model (indirect inference: the extraction is applied alike to the data and to every
candidate).  The difference between the two, the extraction's bias, depends on the model: a
candidate that damps the weave more or mixes the modes otherwise has a bias of its own, and
correcting every candidate by the nominal model's bias would favour or penalise candidates.

:class:`RecordSimulator` does it for many models at once, for ``P`` parameter vectors and ``R``
records in one batched computation:

* the closed-loop state matrix of every (model, record) pair at the record's speed and control law
  (one matrix exponential of the sampling step per pair; the response is linear in the initial
  state, so the output rows ``C Phi(t_k)`` follow by repeated multiplication);
* each record's initial state, and a constant offset per signal, by linear least squares on the
  record's signals (roll rate and steer angle where logged), each weighted by its scatter over the
  record, as in :func:`bikerider.gap.inference.timedomain.initial_states`;
* the simulated signals from that state, fitted by batched least squares of the same model (two-mode
  or plain, as the record's own fit) started from the record's own fit (variable projection with
  Levenberg-Marquardt steps; ``tests/gap/inference/test_gap_indirect.py`` holds it to SciPy's least squares one
  record at a time); signals combined with the weights of the record's own fit.

:func:`extract` is the last step alone, for responses simulated otherwise (the nonlinear friction
of :mod:`bikerider.gap.inference.timedomain`), so every candidate's apparent eigenvalue comes from one
extraction.  Where the extraction finds no weave in a model's response (a fit that leaves the
range the record fit accepts), the prediction is NaN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from bikerider.benchmark.simulation import expm
from bikerider.errors import FitError
from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.inference.timedomain import Batch, friction_states, simulate_friction, systems
from bikerider.gap.measured.extraction import (
    EXTRA_MODE_RANGE,
    MIN_CYCLES,
    SCAN_VALLEYS,
    nyquist_frequency,
    scan_valleys,
)
from bikerider.gap.measured.records import RecordFit
from bikerider.gap.parallel import MIN_RECORDS, map_forked, workers

OBSERVED = {"roll_angle": 0, "steer_angle": 1, "roll_rate": 2, "steer_rate": 3}
"""Record signals and the index of their state among ``(phi, delta, phid, deltad)``."""
STATE_SIGNALS = ("roll_rate", "steer_angle")
"""Signals the initial state is fitted to (those of them a record holds)."""
MAX_ELEMENTS = 3_000_000
"""Largest intermediate array (elements) of one batched chunk; larger batches are split over ``P``."""
MAX_RELATIVE_BIAS = 0.2
"""Largest extraction bias under the nominal model, as a fraction of its weave eigenvalue, for which a
record's eigenvalue is compared with models at all (:func:`comparable`)."""
SAME_VALLEY = 1e-3
"""Two ends of the record fit from different starts are one valley when their eigenvalues differ by less than
this share of their size (:func:`extract_runs`)."""
MAX_KNOWN = 4096
"""Most models whose apparent eigenvalues a :class:`RecordSimulator` keeps (the oldest dropped first)."""
LM_ITERATIONS = 60
"""Most Levenberg-Marquardt iterations of the batched extraction."""
LM_TOLERANCE = 1e-10
"""The batched extraction stops when an accepted step lowers the residual sum of squares by less than
this fraction of it."""
LM_STEP = 1e-8
"""... or when a step changes no parameter by more than this fraction of its size (the eigenvalue
is then settled far below any record's standard error)."""


# ---------------------------------------------------------------------------------------------
# The extraction models (as bikerider.gap.measured.extraction), batched, by variable projection
# ---------------------------------------------------------------------------------------------
# Both models are linear in four of their parameters (amplitudes, offset, the extra mode's amplitude
# or the drift) given the others (frequency, decay, the extra mode's eigenvalue).  The batched fit
# solves the linear ones exactly for every trial of the nonlinear ones (variable projection, with
# Kaufman's Jacobian), which converges in a few steps where a search over all of them crawls along
# the near-degenerate directions of offset and slow mode.
LAMBDA_BOUNDS = (EXTRA_MODE_RANGE[0] + 1e-6, EXTRA_MODE_RANGE[1] - 1e-6)
"""The two-mode fit's extra real mode is kept inside the range the record fit accepts
(:data:`bikerider.gap.measured.extraction.EXTRA_MODE_RANGE`): the same estimator on data and on models (the
model's response could otherwise lend the extra exponential to its faster castor mode)."""
NONLINEAR = {"two-mode": (0, 1, 6), "plain": (0, 1)}
"""Positions of the nonlinear parameters in each model's parameter vector."""
LINEAR = {"two-mode": (2, 3, 4, 5), "plain": (3, 4, 2, 5)}
"""Positions of the coefficients of :func:`_basis`'s four functions in each model's parameter vector."""


def _project(
    kind: str, theta: np.ndarray, y: np.ndarray, w: np.ndarray, tau: np.ndarray, jacobian: bool = True, dt=...
):
    """Linear coefficients, weighted residuals, cost and Kaufman's Jacobian at ``theta``.

    Two-mode: ``theta = (omega, sigma, lambda)``, basis ``e sin, e cos, 1, exp(lambda t)`` with
    ``e = exp(-sigma t)``; plain: ``theta = (omega, sigma)``, basis ``e sin, e cos, 1, t``.  Without
    ``jacobian`` the last item is what :func:`_kaufman` needs to form it for some of the rows later
    (a trial step that is rejected needs none).  ``dt``: :func:`_uniform_step` of ``tau`` when the
    caller has it.
    """
    B, N = theta.shape[0], tau.size
    if dt is ...:
        dt = _uniform_step(tau)
    if dt is not None:
        # e^{(-sigma + i omega) k dt} as powers of its first step, a running product (relative error
        # about k times the rounding, 1e-14 at 400 samples, far below the fit's tolerance) at a fifth
        # of the cost of an exp, a sin and a cos at every sample
        z = _powers(np.exp((-theta[:, 1] + 1j * theta[:, 0]) * dt), N)
        es, ec = z.imag, z.real
    else:
        omega, sigma = theta[:, 0, None], theta[:, 1, None]
        decay = np.exp(-sigma * tau)
        es, ec = decay * np.sin(omega * tau), decay * np.cos(omega * tau)
    phi = np.empty((B, N, 4))
    phi[..., 0], phi[..., 1], phi[..., 2] = es, ec, 1.0
    grow = None
    if kind == "two-mode":
        lam = theta[:, 2]
        grow = _powers(np.exp(lam * dt), N) if dt is not None else np.exp(lam[:, None] * tau)
    phi[..., 3] = grow if grow is not None else tau
    # the weights are 0 or 1 (a mask): weighting the basis in place and the residuals as
    # phi_w coef - y w is the same arithmetic as (phi coef - y) w, one array fewer
    phi *= w[..., None]
    phi_w = phi
    phi_wT = np.swapaxes(phi_w, 1, 2)
    gram = phi_wT @ phi_w
    gram = gram + 1e-12 * np.maximum(np.trace(gram, axis1=1, axis2=2), 1e-300)[:, None, None] * np.eye(4)
    yw = y * w
    coef = np.linalg.solve(gram, phi_wT @ yw[..., None])[..., 0]  # (B, 4)
    r = (phi_w @ coef[..., None])[..., 0] - yw
    parts = (es, ec, grow, phi_w, gram)
    if not jacobian:
        return coef, r, np.sum(r * r, axis=1), parts
    return coef, r, np.sum(r * r, axis=1), _kaufman(coef, w, tau, parts)


def _uniform_step(tau: np.ndarray) -> float | None:
    """The step of ``tau`` when it is ``k dt`` (``k = 0, 1, ...``, as :func:`extract` makes it), else ``None``."""
    if tau.size < 2 or tau[0] != 0.0:
        return None
    dt = float(tau[1])
    return dt if np.array_equal(tau, np.arange(tau.size) * dt) else None


def _powers(step: np.ndarray, n: int) -> np.ndarray:
    """``step[:, None] ** arange(n)`` as a running product, ``(B, n)``."""
    out = np.empty((step.size, n), step.dtype)
    out[:, :1] = 1.0
    out[:, 1:] = step[:, None]
    return np.cumprod(out, axis=1, out=out)


def _kaufman(coef: np.ndarray, w: np.ndarray, tau: np.ndarray, parts: tuple) -> np.ndarray:
    """Kaufman's Jacobian ``(B, N, k)`` of the weighted residuals in the nonlinear parameters, from the
    coefficients and the basis of :func:`_project` (each row on its own)."""
    es, ec, grow, phi_w, gram = parts
    a, b = coef[:, 0, None], coef[:, 1, None]
    J = np.empty(es.shape + (2 if grow is None else 3,))  # the columns written in place (no stacking)
    J[..., 0] = tau * (a * ec - b * es)  # d/d omega
    J[..., 1] = -tau * (a * es + b * ec)  # d/d sigma
    if grow is not None:
        J[..., 2] = coef[:, 3, None] * tau * grow  # d/d lambda
    J *= w[..., None]
    # Kaufman: the part of J the linear coefficients cannot follow
    phi_wT = np.swapaxes(phi_w, 1, 2)
    return J - phi_w @ np.linalg.solve(gram, phi_wT @ J)


def levenberg_marquardt(
    kind: str, beta: np.ndarray, y: np.ndarray, mask: np.ndarray, tau: np.ndarray, iterations: int = LM_ITERATIONS
) -> tuple[np.ndarray, np.ndarray]:
    """Least squares of the ``kind`` model to every row of ``y (B, N)`` (where ``mask``), from ``beta (B, k)``.

    Variable projection (the linear coefficients solved at every step) with Levenberg-Marquardt
    steps in the nonlinear parameters, Marquardt's scaling and one damping factor per row.  A row
    stops when the reduction a step achieves, or the linearised model predicts for it, is below
    :data:`LM_TOLERANCE` of the signal's sum of squares, or the step below :data:`LM_STEP` relative.
    A row whose frequency falls below half a cycle over its samples (:data:`bikerider.gap.measured.extraction.
    MIN_CYCLES`: the response holds no weave the record fit would accept) stops there and is NaN.
    Returns the full parameter vectors (in the model's order) and the residual sums of squares
    (``inf`` where the fit broke down).
    """
    nl, lin = list(NONLINEAR[kind]), list(LINEAR[kind])
    beta = np.array(beta, dtype=float)
    theta = beta[:, nl].copy()
    w = mask.astype(float)
    scale = np.maximum(np.sum((y * w) ** 2, axis=1), 1e-300)
    span = tau[np.maximum(np.sum(mask, axis=1) - 1, 0)]
    with np.errstate(all="ignore"):
        dt = _uniform_step(tau)
        coef, r, cost, J = _project(kind, theta, y, w, tau, dt=dt)
        cost = np.where(np.isfinite(cost), cost, np.inf)
        mu = np.full(theta.shape[0], 1e-3)
        active = np.isfinite(cost)
        eye = np.eye(theta.shape[1])
        for _ in range(iterations):
            if not np.any(active):
                break
            idx = np.flatnonzero(active)
            JT = np.swapaxes(J[idx], 1, 2)
            H = JT @ J[idx]  # two copies: NumPy forms A^T A of one buffer otherwise (syrk), rounding differently
            g = (JT @ r[idx][..., None])[..., 0]
            if kind == "two-mode":  # the extra mode held at a bound it presses against (active set)
                lam = theta[idx, 2]
                held = ((lam <= LAMBDA_BOUNDS[0]) & (g[:, 2] > 0)) | ((lam >= LAMBDA_BOUNDS[1]) & (g[:, 2] < 0))
                if np.any(held):
                    H[held, 2, :], H[held, :, 2], g[held, 2] = 0.0, 0.0, 0.0
                    H[held, 2, 2] = 1.0
            d = np.maximum(np.einsum("bkk->bk", H), 1e-30)
            try:
                step = np.linalg.solve(H + mu[idx, None, None] * d[:, :, None] * eye, -g[..., None])[..., 0]
            except np.linalg.LinAlgError:
                step = np.stack(
                    [np.linalg.lstsq(h + m * np.diag(dd), -gg, rcond=None)[0] for h, m, dd, gg in zip(H, mu[idx], d, g)]
                )
            trial = theta[idx] + step
            if kind == "two-mode":  # the extra mode stays where the record fit accepts it
                trial[:, 2] = np.clip(trial[:, 2], *LAMBDA_BOUNDS)
            coef2, r2, cost2, parts = _project(kind, trial, y[idx], w[idx], tau, jacobian=False, dt=dt)
            better = np.isfinite(cost2) & (cost2 <= cost[idx])
            predicted = -(2 * np.sum(g * step, axis=1) + np.einsum("bk,bkl,bl->b", step, H, step))
            gain = np.where(better, cost[idx] - cost2, predicted)
            small_step = np.max(np.abs(step) / (np.abs(theta[idx]) + 1e-6), axis=1) < LM_STEP
            good = idx[better]
            if good.size:  # the Jacobian only where the step is taken
                kept = tuple(None if part is None else part[better] for part in parts)
                J[good] = _kaufman(coef2[better], w[good], tau, kept)
            theta[good], coef[good], r[good] = trial[better], coef2[better], r2[better]
            cost[good] = cost2[better]
            mu[idx] = np.where(better, mu[idx] / 3.0, mu[idx] * 4.0)
            # no weave left: less than half a cycle over the record (the fit then wanders off)
            lost = theta[idx, 0] * span[idx] < 2 * math.pi * MIN_CYCLES
            done = (gain <= LM_TOLERANCE * scale[idx]) | small_step | (mu[idx] > 1e12) | lost
            active[idx[done]] = False
    beta[:, nl] = theta
    beta[:, lin] = coef
    # no weave either above the samples' Nyquist frequency: an alias (the record fit refuses it too)
    alias = theta[:, 0] >= nyquist_frequency(span, np.sum(mask, axis=1))
    beta[(theta[:, 0] * span < 2 * math.pi * MIN_CYCLES) | alias] = np.nan
    return beta, cost


def eigenvalue_of(beta: np.ndarray) -> np.ndarray:
    """The weave eigenvalue ``-sigma + i omega`` of fitted parameters ``beta (..., k)``; NaN unless a weave.

    A weave: finite parameters and a positive frequency (the fit keeps the extra mode in range and
    gives up below half a cycle).  The record fit's other checks (amplitude above the noise, the
    F-test against the plain fit) judge a noisy record; a model's response has no noise.
    """
    omega, sigma = beta[..., 0], beta[..., 1]
    ok = np.all(np.isfinite(beta), axis=-1) & (omega > 0)
    return np.where(ok, -sigma + 1j * omega, np.nan + 1j * np.nan)


# ---------------------------------------------------------------------------------------------
# Records prepared for batched simulation
# ---------------------------------------------------------------------------------------------
@dataclass
class FitItem:
    """One signal's fit of one record: what the extraction refits in a model's response."""

    record: int  # index among the batch's records
    signal: int  # index among the batch's signals
    kind: str  # "two-mode" or "plain"
    start: np.ndarray  # the record's own fitted parameters
    weight: complex  # weight of this signal's eigenvalue in the record's (real + i imag)


@dataclass
class RecordBatch:
    """Records of one sampling step, padded to a common length.

    Attributes
    ----------
    index : ndarray of int
        Position of each record in the simulator's list.
    dt : float
    length : ndarray of int
    signals : tuple of str
        Signals simulated (the state signals and every fitted signal).
    y, weight : ndarray
        ``(R, N, S)`` samples (0 where absent) and ``(R, S)`` weights for the initial-state fit
        (1 / the signal's scatter over the record; 0 where it is not used for the state).
    items : list of FitItem
    """

    index: np.ndarray
    dt: float
    length: np.ndarray
    signals: tuple[str, ...]
    y: np.ndarray
    weight: np.ndarray
    items: list[FitItem]

    @property
    def N(self) -> int:
        return int(self.length.max())

    @property
    def mask(self) -> np.ndarray:
        return np.arange(self.N)[None, :] < self.length[:, None]


def fit_weights(fit: RecordFit) -> list[tuple[str, complex]]:
    """The signals a record's eigenvalue came from and their weights (real part + i imaginary part).

    Inverse-variance weights of the record's own fits where :func:`bikerider.gap.measured.records.combine_fits`
    combined them, else the first signal alone: a model's apparent eigenvalue combines its refits
    with the same weights, so it is a smooth function of the model.
    """
    names = list(fit.fits)
    if len(names) == 1 or fit.estimate is None or fit.estimate == fit.fits[names[0]]:
        return [(names[0], 1 + 1j)]
    wr = np.array([1 / max(fit.fits[n].real_sigma, 1e-12) ** 2 for n in names])
    wi = np.array([1 / max(fit.fits[n].imag_sigma, 1e-12) ** 2 for n in names])
    return [(n, complex(a, b)) for n, a, b in zip(names, wr / wr.sum(), wi / wi.sum())]


class RecordSimulator:
    """Apparent eigenvalues of records under batches of models (module docstring).

    Parameters
    ----------
    fits : list of RecordFit
        Fitted records (each used); their order is the order of the results.
    values : dict
        Nominal benchmark values (the models' default).
    geometry : RiderGeometry
    starts : list of dict, optional
        Per record, the starting parameters of each signal's refit (default: the record's own fit,
        then :meth:`settle` replaces them by the nominal model's fit).

    Raises
    ------
    bikerider.errors.FitError
        For a record that is not uniformly sampled.
    """

    def __init__(
        self,
        fits: list[RecordFit],
        values: dict,
        geometry,
        starts: list[dict] | None = None,
        known: dict[bytes, np.ndarray] | None = None,
        kicks: np.ndarray | None = None,
    ):
        self.fits = list(fits)
        self.kicks = None if kicks is None else np.asarray(kicks, float).reshape(len(self.fits), 4)
        """The records' known initial states ``(R, 4)``: roll and steer angle and rate (a plan's templates, each
        the nominal model's response from a kick), or ``None`` (measured records: fitted under each model)."""
        self.values = dict(values)
        self.geometry = geometry
        records = [f.record for f in self.fits]
        self.speeds = np.array([r.speed for r in records], float)
        self.measured = np.array([r.speed_measured for r in records], bool)
        self.gains = np.array([r.gains for r in records], float).reshape(len(records), 4)
        self.starts = (
            starts
            if starts is not None
            else [{s: np.asarray(e.params, float) for s, e in f.fits.items()} for f in self.fits]
        )
        self.batches = self._batches()
        self.known: dict[bytes, np.ndarray] = dict(known or {})
        """Apparent eigenvalues ``(R,)`` of models of benchmark values alone already simulated from these
        starts, by :func:`_values_key` (:meth:`apparent` computes each such model once: the comparison
        of the records and the problem's parameter uncertainty simulate the same secants)."""

    def __len__(self) -> int:
        return len(self.fits)

    def subset(self, positions) -> RecordSimulator:
        """The simulator of some of the records (their starts kept)."""
        positions = [int(k) for k in positions]
        return RecordSimulator(
            [self.fits[k] for k in positions],
            self.values,
            self.geometry,
            [self.starts[k] for k in positions],
            {key: value[positions] for key, value in self.known.items()},
            None if self.kicks is None else self.kicks[positions],
        )

    def settle(self) -> np.ndarray:
        """Apparent eigenvalues of the nominal model, refitted from each record's own fit; their fits
        become the starts of every later refit (so a model near the nominal one is refitted in a few
        steps, and the nominal model's own apparent eigenvalue is reproduced exactly).  Returns them ``(R,)``."""
        out = np.full(len(self.fits), np.nan + 1j * np.nan)
        for batch in self.batches:
            A, outputs = self.closed_loop(self.values, {}, None, batch.index)
            sim = _linear_response(batch, A, outputs)
            eig, betas = extract(batch, sim, keep=True)
            out[batch.index] = eig[0]
            for it, beta in zip(batch.items, betas):
                if np.all(np.isfinite(beta[0])):
                    self.starts[batch.index[it.record]][batch.signals[it.signal]] = beta[0]
        self.batches = self._batches()
        self.known.clear()  # simulated from the old starts
        return out

    def _batches(self) -> list[RecordBatch]:
        groups: dict[float, list[int]] = {}
        for k, f in enumerate(self.fits):
            steps = np.diff(f.record.time)
            if steps.size == 0 or not np.allclose(steps, steps[0], rtol=1e-6, atol=1e-9):
                raise FitError(f"{f.record.name}: comparing a record with models needs it uniformly sampled")
            groups.setdefault(round(float(steps[0]), 9), []).append(k)
        out = []
        for dt, idx in groups.items():
            fits = [self.fits[k] for k in idx]
            weights = [fit_weights(f) for f in fits]
            signals = tuple(
                dict.fromkeys(
                    [s for f in fits for s in STATE_SIGNALS if s in f.record.signals]
                    + [s for w in weights for s, _ in w]
                )
            )
            length = np.array([f.record.time.size for f in fits])
            N = int(length.max())
            y = np.zeros((len(fits), N, len(signals)))
            weight = np.zeros((len(fits), len(signals)))
            items = []
            for j, (k, f, w) in enumerate(zip(idx, fits, weights)):
                for m, s in enumerate(signals):
                    values = f.record.signals.get(s)
                    if values is None or not np.all(np.isfinite(values)):
                        continue
                    y[j, : length[j], m] = values
                    spread = float(np.std(values))
                    weight[j, m] = 1.0 / spread if spread > 0 and s in STATE_SIGNALS else 0.0
                for s, wt in w:
                    items.append(FitItem(j, signals.index(s), f.fits[s].kind, self.starts[k][s], wt))
            out.append(RecordBatch(np.array(idx), float(dt), length, signals, y, weight, items))
        return out

    # -- models ---------------------------------------------------------------------------------
    def closed_loop(self, values: dict, config: dict, scale, index: np.ndarray) -> tuple[np.ndarray, tuple]:
        """Closed-loop ``A (P, R, n, n)`` of records ``index`` for batched linear models.

        ``values`` and ``config`` as :class:`bikerider.gap.candidates.effect_model.EffectModel` takes them, each value
        a number or an array of ``P`` (shape ``(P,)`` or ``(P, 1)``); ``scale`` ``None``, ``(P,)`` (the
        speed of the records a sensor read) or ``(P, R_all)`` (every record's own, e.g. for the
        speed's uncertainty).  The control gains stay those of the recorded speed.
        """

        P = _batch_size(values, config, scale)
        R = index.size
        speeds = np.broadcast_to(self.speeds[index], (P, R))
        if scale is not None:
            s = np.asarray(scale, dtype=float)
            if s.ndim == 2:
                speeds = speeds * s[:, index]
            else:
                speeds = speeds * np.where(self.measured[index][None, :], s.reshape(P, 1), 1.0)

        def flat(v):
            a = np.asarray(v, dtype=float)
            if a.ndim == 0:
                return float(a)
            return np.repeat(np.broadcast_to(a.reshape(a.shape[0], -1)[:, 0], (P,)), R)

        model = EffectModel(
            {k: flat(v) for k, v in values.items()},
            self.geometry,
            {e: {k: flat(v) for k, v in p.items()} for e, p in config.items()},
        )
        ss = model.state_space(speeds.ravel())
        A = ss.closed_loop(np.tile(self.gains[index], (P, 1)))
        n = A.shape[-1]
        return A.reshape(P, R, n, n), ss.output_states

    def apparent(self, values: dict | None = None, config: dict | None = None, scale=None) -> np.ndarray:
        """Apparent eigenvalue of every record, ``(P, R)`` complex, for batched linear models.

        Arguments as :meth:`closed_loop` (the nominal model when all are left out).
        """
        values = self.values if values is None else values
        config = config or {}
        P = _batch_size(values, config, scale)
        keys = [_values_key(values, p) for p in range(P)] if not config and scale is None else []
        if keys and all(key in self.known for key in keys):
            return np.array([self.known[key] for key in keys])
        out = self._apparent(values, config, scale, P)
        self._keep(keys, out)
        return out

    def _keep(self, keys: list[bytes], rows: np.ndarray) -> None:
        """Models' apparent eigenvalues kept by key (each model's rows are computed as alone: the same from
        any batch), the oldest dropped beyond :data:`MAX_KNOWN`."""
        for key, row in zip(keys, rows):
            self.known[key] = row.copy()
        while len(self.known) > MAX_KNOWN:
            del self.known[next(iter(self.known))]

    def apparent_on_workers(self, values: dict) -> np.ndarray:
        """:meth:`apparent` of a batch of models of benchmark values alone, the models shared among the
        worker processes (:func:`bikerider.gap.parallel.map_forked`; each model's rows are computed as
        alone, so they are the same), and kept in :attr:`known` as :meth:`apparent` keeps them."""
        P = _batch_size(values, {}, None)
        parts = [part for part in np.array_split(np.arange(P), max(1, min(workers(), P // 8))) if part.size]
        if len(parts) < 2 or len(self.fits) < MIN_RECORDS:  # too little to pay for starting the workers
            return self.apparent(values)

        def models(part: np.ndarray) -> dict:
            return {k: v if np.ndim(v) == 0 or np.size(v) == 1 else np.asarray(v)[part] for k, v in values.items()}

        out = np.concatenate(map_forked(lambda part: self.apparent(models(part)), parts))
        self._keep([_values_key(values, p) for p in range(P)], out)
        return out

    def _apparent(self, values: dict, config: dict, scale, P: int) -> np.ndarray:
        out = np.full((P, len(self.fits)), np.nan + 1j * np.nan)
        for batch in self.batches:
            A, outputs = self.closed_loop(values, config, scale, batch.index)
            R, N, S, n = batch.index.size, batch.N, len(batch.signals), A.shape[-1]
            chunk = max(1, MAX_ELEMENTS // max(R * N * S * (n + S), 1))
            for lo in range(0, P, chunk):
                hi = min(P, lo + chunk)
                out[lo:hi, batch.index] = extract(batch, _linear_response(batch, A[lo:hi], outputs))[0]
        return out

    def apparent_time_domain(self, layout, theta, smoothing: float | None = None) -> np.ndarray:
        """Apparent eigenvalue of every record ``(P, R)`` under a time-domain candidate (steer friction).

        The response comes from :func:`bikerider.gap.inference.timedomain.friction_states` (each record's
        initial state refitted under the nonlinear model; its friction smoothed by ``smoothing`` [rad/s],
        the fits' own :data:`~bikerider.gap.inference.timedomain.SMOOTHING` when not given), the extraction is
        :func:`extract`, as for every linear model.
        """
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        out = np.full((theta.shape[0], len(self.fits)), np.nan + 1j * np.nan)
        for batch, sim in self._friction_responses(layout, theta, smoothing):
            out[:, batch.index] = extract(batch, sim)[0]
        return out

    def time_domain_runs(
        self, layout, theta, noise: dict[str, float], smoothing: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """What the record fit finds in new records of a time-domain candidate, each signal with sample noise
        ``noise[signal]``: the mean ``(P, R)`` and the per-run covariance ``(P, R, 2, 2)`` over the fit's
        valleys (:func:`extract_runs`).

        A new record is the candidate's own response from the kick that starts it: with :attr:`kicks` (a plan's
        templates) the candidate's response from each template's own kick, which is what a run would record
        were the candidate true; else (measured records) from the initial state fitted under it, as
        :meth:`apparent_time_domain`.  The kick moves continuously with the speed, the law and the push; a state
        fitted under friction to the nominal model's template has more than one valley and jumped."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        mean = np.full((theta.shape[0], len(self.fits)), np.nan + 1j * np.nan)
        cov = np.full((theta.shape[0], len(self.fits), 2, 2), np.nan)
        for batch, sim in self._friction_responses(layout, theta, smoothing, kicked=self.kicks is not None):
            s = np.array([float(noise.get(name, 0.0)) for name in batch.signals])
            mean[:, batch.index], cov[:, batch.index] = extract_runs(batch, sim, s)
        return mean, cov

    def _friction_responses(self, layout, theta: np.ndarray, smoothing: float | None, kicked: bool = False):
        """Each batch and its records' simulated signals ``(P, R, N, S)`` under a time-domain candidate, from
        each record's initial state fitted under it, or with ``kicked`` from :attr:`kicks`."""
        for batch in self.batches:
            records = [self.fits[k].record for k in batch.index]
            A, b, outputs, T = systems(self.values, self.geometry, records, layout, theta)
            if kicked:
                x0 = np.zeros(A.shape[:-1])  # (P, R, n): the kick's four states, the others (if any) at rest
                x0[..., list(outputs[:4])] = self.kicks[batch.index]
                states = simulate_friction(
                    A,
                    b,
                    x0,
                    np.asarray(T, float).reshape(A.shape[:-3] + (1,)),
                    batch.dt,
                    batch.N,
                    outputs[3],
                    smoothing,
                )
            else:
                state = [m for m, s in enumerate(batch.signals) if np.any(batch.weight[:, m] > 0)]
                y = {batch.signals[m]: np.where(batch.mask, batch.y[..., m], np.nan) for m in state}
                weight = {batch.signals[m]: batch.weight[:, m] for m in state}
                batched = Batch(records, batch.dt, batch.length, y, weight)
                states, _ = friction_states(batched, A, b, outputs, T, smoothing)
            yield batch, states[..., [outputs[OBSERVED[s]] for s in batch.signals]]


def _values_key(values: dict, p: int) -> bytes:
    """The benchmark values of model ``p`` of a batch (each value a number or an array of the batch's
    size, shape ``(P,)`` or ``(P, 1)``), as bytes."""
    parts = []
    for name in sorted(values):
        a = np.asarray(values[name], dtype=float).reshape(-1)
        parts.append(name.encode() + a[p if a.size > 1 else 0].tobytes())
    return b"".join(parts)


def _batch_size(values: dict, config: dict, scale) -> int:
    sizes = {np.asarray(v).shape[0] for v in values.values() if np.ndim(v) > 0}
    sizes |= {np.asarray(v).shape[0] for p in config.values() for v in p.values() if np.ndim(v) > 0}
    if scale is not None and np.ndim(scale) > 0:
        sizes.add(np.asarray(scale).shape[0])
    sizes.discard(1)
    if len(sizes) > 1:
        raise ValueError(f"batched values of different sizes {sorted(sizes)}")
    return sizes.pop() if sizes else 1


def _linear_response(batch: RecordBatch, A: np.ndarray, outputs: tuple) -> np.ndarray:
    """Each record's response ``(P, R, N, S)`` under ``A (P, R, n, n)`` from its fitted initial state.

    One matrix exponential of the sampling step per (model, record); the output rows ``C Phi(t_k)``
    by repeated multiplication, doubling the samples known at each step (``C Phi(t_{k + m}) =
    C Phi(t_k) Phi(t_m)`` for the ``m`` samples known, ``Phi(t_{2m})`` by squaring), so a record of
    ``N`` samples takes ``log2 N`` batched products; the initial state (and an offset per signal) by
    linear least squares on the record's state signals, each weighted by its scatter
    (:func:`_initial_states`).
    """

    P, R, n = A.shape[0], A.shape[1], A.shape[-1]
    rows = [outputs[OBSERVED[s]] for s in batch.signals]
    power = expm(A * batch.dt)  # (P, R, n, n): Phi over m samples, m = 1, 2, 4, ...
    O = np.empty((P, R, batch.N, len(rows), n))
    O[:, :, 0] = np.eye(n)[rows]
    known = 1
    while known < batch.N:
        more = min(known, batch.N - known)
        O[:, :, known : known + more] = O[:, :, :more] @ power[:, :, None]
        known += more
        if known < batch.N:
            power = power @ power
    basis = resolved_basis(A, batch.dt)  # (P, R, n, n)
    # only where a fast mode is left out: elsewhere the basis is the identity (the product the same)
    changed = ~np.all(basis == np.eye(n), axis=(-2, -1))
    if np.any(changed):
        O[changed] = O[changed] @ basis[changed][:, None]
    z = _initial_states(batch, O)
    return (O.reshape(P, R, -1, n) @ z[..., None]).reshape(P, R, batch.N, len(rows))


def resolved_basis(A: np.ndarray, dt: float) -> np.ndarray:
    """A real basis ``(..., n, n)`` of the modes of ``A`` a record sampled every ``dt`` resolves.

    A mode decaying faster than ``1 / dt`` (by more than a factor e from one sample to the next:
    stiff tyres, a stiff lean spring) only shapes the first sample or two; left free, its initial value
    would fit those samples' noise and bend the response the extraction sees.  The initial state is
    fitted within the span of the other modes: the basis holds their (real and imaginary parts of)
    eigenvectors, and zero columns in place of the fast ones.  Where every mode is resolved (the
    Whipple bicycle's four at any ordinary speed) it is the identity, and nothing changes.
    """
    n = A.shape[-1]
    eye = np.broadcast_to(np.eye(n), A.shape).copy()
    with np.errstate(all="ignore"):
        lam, V = np.linalg.eig(A)
    fast = lam.real * dt < -1.0
    todo = np.any(fast, axis=-1) & np.all(np.isfinite(lam), axis=-1)
    if not np.any(todo):
        return eye
    lam, V, fast = lam[todo], V[todo], fast[todo]
    basis = np.zeros(V.shape)
    upper = lam.imag > 0
    lower = lam.imag < 0
    real = ~upper & ~lower
    # LAPACK returns a complex pair as neighbours, the positive imaginary part first
    basis = np.where(real[..., None, :], V.real, basis)
    basis = np.where(upper[..., None, :], V.real, basis)
    partner = np.roll(V.imag, 1, axis=-1)  # the column before each lower member: its upper partner
    basis = np.where(lower[..., None, :], partner, basis)
    basis = np.where(fast[..., None, :], 0.0, basis)
    eye[todo] = basis
    return eye


def _initial_states(batch: RecordBatch, O: np.ndarray) -> np.ndarray:
    """Each record's initial state ``(P, R, n)`` fitted to its signals (an offset per signal solved with it)."""
    P, R, N, S, n = O.shape
    w = batch.weight[:, None, :] * batch.mask[:, :, None]  # (R, N, S)
    design = np.zeros((P, R, N, S, n + S))
    design[..., :n] = O * w[None, :, :, :, None]
    design[..., n:] = np.eye(S)[None, None, None] * w[None, :, :, :, None]
    data = batch.y * w  # (R, N, S)
    design = design.reshape(P, R, N * S, n + S)
    designT = np.swapaxes(design, -1, -2)
    gram = designT @ design
    rhs = (designT @ data.reshape(R, N * S, 1))[..., 0]
    scale = np.maximum(np.trace(gram, axis1=-2, axis2=-1) / gram.shape[-1], 1e-300)
    gram = gram + 1e-12 * scale[..., None, None] * np.eye(n + S)
    return np.linalg.solve(gram, rhs[..., None])[..., :n, 0]


def extract(batch: RecordBatch, sim: np.ndarray, keep: bool = False):
    """The record fit applied to simulated signals ``sim (P, R, N, S)`` of a batch: ``(P, R)`` complex.

    Every fitted signal of every record is refitted with the model of the record's own fit (two-mode
    or plain) from the batch's starting parameters, by :func:`levenberg_marquardt`; the signals'
    eigenvalues are combined with the record's weights (:func:`fit_weights`).  Returns the
    eigenvalues and, with ``keep``, the fitted parameters ``(P, k)`` of every item (else ``None``).
    """
    P, R = sim.shape[:2]
    tau = np.arange(batch.N) * batch.dt
    out = np.zeros((P, R), complex)
    betas: list = [None] * len(batch.items)
    for kind, chosen, rec, sig, y, mask, start in _refits(batch, sim):
        items = [batch.items[j] for j in chosen]
        beta, _ = levenberg_marquardt(kind, start, y, mask, tau)
        eig = eigenvalue_of(beta).reshape(P, len(items))
        weight = np.array([it.weight for it in items])
        contrib = eig.real * weight.real + 1j * eig.imag * weight.imag
        np.add.at(out, (slice(None), rec), contrib)
        if keep:
            beta = beta.reshape(P, len(items), -1)
            for m, j in enumerate(chosen):
                betas[j] = beta[:, m]
    return out, (betas if keep else None)


def _refits(batch: RecordBatch, sim: np.ndarray):
    """Per kind of fit (two-mode, plain) with items in ``batch``: the kind, the items' positions, their records
    and signals, and their rows of ``sim (P, R, N, S)`` to refit ``(P * I, N)`` with masks and starts alike."""
    P = sim.shape[0]
    for kind in ("two-mode", "plain"):
        chosen = [j for j, it in enumerate(batch.items) if it.kind == kind]
        if not chosen:
            continue
        rec = np.array([batch.items[j].record for j in chosen])
        sig = np.array([batch.items[j].signal for j in chosen])
        y = np.moveaxis(sim[:, rec, :, sig], 0, 1).reshape(P * len(chosen), batch.N)  # (P * I, N)
        mask = np.tile(batch.mask[rec], (P, 1))
        start = np.tile(np.array([batch.items[j].start for j in chosen]), (P, 1))
        yield kind, chosen, rec, sig, y, mask, start


def extract_runs(batch: RecordBatch, sim: np.ndarray, noise: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """What the record fit finds in new, noisy records of the simulated signals ``sim (P, R, N, S)``: the mean
    eigenvalue ``(P, R)`` and its per-run covariance ``(P, R, 2, 2)`` (real and imaginary part), for signals
    of sample noise ``noise (S,)``.

    The two-mode fit of a response that is no sum of modes (Coulomb friction) can have more than one valley,
    and a refit from the template's own fit alone (:func:`extract`) ends in the one nearest it, which jumps
    over speed where another grows deeper.  A record's own fit takes the deepest it finds from its grid scan;
    so each signal is refitted from the batch's start and from the valleys of the scan
    (:func:`~bikerider.gap.measured.extraction.scan_valleys`), and the distinct ends are its valleys (a fit
    that finds no weave is none).  Noise decides between them: to first order in the noise ``e`` the residuals
    of valleys ``1`` (the deepest) and ``i`` differ by ``c_i - c_1 + 2 e.(m_1 - m_i)``, ``m`` the fitted curves,
    so ``i`` is the deeper with probability ``p_i = Phi((c_1 - c_i) / (2 s |m_1 - m_i|))``; the deepest stays
    so with ``p_1 = prod (1 - p_i)`` (each other valley's chance taken apart).  The valleys weighed by ``p``
    (normalised) give the mean and the per-run covariance: continuous where two valleys trade places (at equal
    depth each weighs one half, from either side).  Signals combine with the records' weights, as in
    :func:`extract`, their valleys taken as independent.
    """
    P, R = sim.shape[:2]
    tau = np.arange(batch.N) * batch.dt
    mean = np.zeros((P, R), complex)
    cov = np.zeros((P, R, 2, 2))
    for kind, chosen, rec, sig, y, mask, start in _refits(batch, sim):
        items = [batch.items[j] for j in chosen]
        starts = np.stack([start] + _valley_starts(kind, start, y, mask, tau))  # (M, B, k)
        M, B = starts.shape[:2]
        Y, W = np.tile(y, (M, 1)), np.tile(mask, (M, 1))
        with np.errstate(all="ignore"):
            beta, cost = _fit_distinct(kind, starts, Y, W, tau)
            eig = eigenvalue_of(beta)
            found = np.isfinite(eig) & np.isfinite(cost)
            nl = list(NONLINEAR[kind])
            theta = np.where(found[:, None], beta[:, nl], np.tile(start[:, nl], (M, 1)))  # finite where no weave
            _, r, _, _ = _project(kind, theta, Y, W.astype(float), tau, jacobian=False)
        order = np.argsort(np.where(found, cost, np.inf).reshape(M, B), axis=0, kind="stable")  # the deepest first
        rows = np.arange(B)
        eig, cost, r, found = eig.reshape(M, B), cost.reshape(M, B), r.reshape(M, B, -1), found.reshape(M, B)
        s = np.tile(np.asarray(noise, float)[sig], P)
        deepest = order[0]
        weights = np.zeros((M, B))
        valleys = np.zeros((M, B), complex)
        kept: list[np.ndarray] = []
        for a in range(M):
            here = order[a]
            lam = eig[here, rows]
            new = found[here, rows].copy()
            for other in kept:  # the same valley from another start is one (their ends differ by the tolerance)
                new &= ~(np.abs(lam - other) <= SAME_VALLEY * np.abs(other))
            kept.append(np.where(new, lam, np.nan))
            if a == 0:
                w = np.where(new, 1.0, 0.0)
            else:
                gap = np.sqrt(np.sum((r[deepest, rows] - r[here, rows]) ** 2, axis=1))  # |m_1 - m_i|: they share y
                with np.errstate(divide="ignore", invalid="ignore"):
                    z = (cost[deepest, rows] - cost[here, rows]) / (2 * s * gap)
                w = np.where(new & (gap > 0) & np.isfinite(z), ndtr(np.nan_to_num(z, neginf=-np.inf)), 0.0)
            weights[a], valleys[a] = w, np.where(new, lam, 0)
        weights[0] *= np.prod(1.0 - weights[1:], axis=0)  # the deepest stays the deepest
        total = weights.sum(axis=0)
        with np.errstate(divide="ignore", invalid="ignore"):
            weights = weights / total
        item_mean = np.where(total > 0, np.sum(weights * valleys, axis=0), np.nan + 1j * np.nan)
        dev = valleys - item_mean
        d = np.stack([dev.real, dev.imag], axis=-1)  # (M, B, 2)
        item_cov = np.einsum("mb,mbi,mbj->bij", np.where(weights > 0, weights, 0.0), d, d)
        item_cov = np.where((total > 0)[:, None, None], item_cov, np.nan)
        weight = np.array([it.weight for it in items])
        wr = np.stack([weight.real, weight.imag], axis=-1)  # (I, 2)
        item_mean = item_mean.reshape(P, len(items))
        np.add.at(mean, (slice(None), rec), item_mean.real * weight.real + 1j * item_mean.imag * weight.imag)
        np.add.at(cov, (slice(None), rec), item_cov.reshape(P, len(items), 2, 2) * wr[:, :, None] * wr[:, None, :])
    return mean, cov


def _fit_distinct(kind: str, starts: np.ndarray, Y: np.ndarray, W: np.ndarray, tau: np.ndarray):
    """:func:`levenberg_marquardt` of rows ``Y (M * B, N)`` from ``starts (M, B, k)``, each row's fit computed
    once where its start repeats an earlier one of the same row (the scan gives fewer valleys than starts)."""
    M, B = starts.shape[:2]
    flat = starts.reshape(M * B, -1)
    source = np.arange(M * B)
    for m in range(1, M):
        for earlier in range(m):
            same = np.all(starts[m] == starts[earlier], axis=1) & (source[m * B : (m + 1) * B] == m * B + np.arange(B))
            source[m * B : (m + 1) * B][same] = earlier * B + np.flatnonzero(same)
    own = np.flatnonzero(source == np.arange(M * B))
    beta = np.empty_like(flat)
    cost = np.empty(M * B)
    beta[own], cost[own] = levenberg_marquardt(kind, flat[own], Y[own], W[own], tau)
    return beta[source], cost[source]


def _valley_starts(kind: str, start: np.ndarray, y: np.ndarray, mask: np.ndarray, tau: np.ndarray) -> list[np.ndarray]:
    """Copies of ``start``, one per start of the record fit's grid scan of each row's own signal ``y``
    (:func:`~bikerider.gap.measured.extraction.scan_valleys`): its frequency, decay and (two-mode) extra mode,
    the amplitudes following by projection in the fit; rows without two finite samples keep ``start``."""
    out = [start.copy() for _ in range(SCAN_VALLEYS)]
    for j in range(y.shape[0]):
        seen = mask[j]
        if np.count_nonzero(seen) < 2 or not np.all(np.isfinite(y[j, seen])):
            continue
        for m, grid in enumerate(scan_valleys(tau[seen], y[j, seen])):
            out[m][j, 0], out[m][j, 1] = grid[0], grid[1]
            if kind == "two-mode":
                out[m][j, 6] = grid[6]
    return out


@dataclass
class RecordRows:
    """The eigenvalue rows of a problem that were fitted from records, and their simulator.

    Attributes
    ----------
    simulator : RecordSimulator
        One record per row, in the order of ``rows``.
    rows : ndarray of int
        The eigenvalue row of each record.
    """

    simulator: RecordSimulator
    rows: np.ndarray


def comparable(apparent: np.ndarray, matched: np.ndarray) -> tuple[np.ndarray, list[str | None]]:
    """Which records can be compared by their eigenvalue: the nominal model's extraction bias.

    ``apparent`` is what the record fit finds in the nominal model's response over each record,
    ``matched`` the nominal model's weave eigenvalue there.  Where the fit finds no weave, or one
    more than :data:`MAX_RELATIVE_BIAS` off the weave eigenvalue (another oscillating mode shares the
    record, as at the lowest speeds), the record is left out, for every candidate alike.  Returns
    the bias (NaN where left out) and the reason for each record left out (``None`` for the others).
    """
    bias = apparent - matched
    reasons: list[str | None] = []
    for a, m, b in zip(apparent, matched, bias):
        if not np.isfinite(a):
            reasons.append(
                "the model's own response over this window shows no weave the record fit can find "
                "(less than half a cycle); its eigenvalue cannot be compared with the model's"
            )
        elif abs(b) > MAX_RELATIVE_BIAS * abs(m):
            reasons.append(
                f"the fit applied to the model's own response over this window finds {_c(a)} against its "
                f"weave eigenvalue {_c(m)} (more than {MAX_RELATIVE_BIAS:.0%} off: other modes share the "
                "record); its eigenvalue cannot be compared with the model's"
            )
        else:
            reasons.append(None)
    return np.where([r is None for r in reasons], bias, np.nan), reasons


def _c(z: complex) -> str:
    return f"{z.real:.2f}{z.imag:+.2f}i 1/s"
