"""The fitting problem: observations, their uncertainties, and fits of effects to subsets of them.

Uncertainties.  Each measured scalar ``y_i`` has

* a data variance from the data alone, never from residuals against a model (see
  :meth:`GapProblem.data_sigma`): a stated standard uncertainty; for a row fitted from a record,
  the larger of the fit's standard error and the scatter of the replicates (records of the same
  group at the same speed, at least :data:`MIN_REPLICATES`); for a row without either, the pooled
  scatter of replicate rows; plus, for eigenvalues, the speed uncertainty carried through the
  nominal model's slope ``d lambda / d v``;
* a model variance: the benchmark parameters' standard uncertainties carried through the model at
  first order (central differences of one standard deviation), with the full covariance
  ``J J^T`` across observations.

Rows fitted from records.  A record's value is what the record fit finds in a short decay, and
every model predicts it by indirect inference: what the same fit finds in the model's own response
over the record's window from the record's initial state fitted under that model
(:mod:`bikerider.gap.inference.indirect`).  The data, the nominal model (``baseline``, the gap map and test),
the parameters' and the speed's uncertainties and every held-out prediction use it.  Fits use
*iterated bias correction*: a model's weave eigenvalues plus a fixed extraction bias are fitted
(fast; the first bias is the nominal model's, the correction issue 11 applied to every candidate
alike), the fitted model's own bias is computed by indirect inference, and the fitted values follow
the change of the bias by Gauss-Newton steps (the fit's Jacobian held; a step is shortened to
:data:`MAX_BIAS_STEP` of a value's search range) until the biases change by no more than
:data:`BIAS_TOLERANCE` of the data uncertainty (RMS over the records fitted), at most
:data:`MAX_BIAS_ITERATIONS` evaluations.  The fit's residuals, chi-square and held-out predictions are
those of the fitted model's own bias; only the bias's own change with the parameters is left out of
the search direction (``tests/gap/inference/test_gap_indirect.py`` compares the values with a full
indirect-inference least squares).

Fits.  A set of effects is fitted by bounded nonlinear least squares
(:func:`scipy.optimize.least_squares`) on the residuals ``(prediction - y) / w``: ``w`` is the
square root of data plus model variance for structural effects (the parameter uncertainty is a
nuisance they must live with); when ``parameters`` is in the set the benchmark parameters
themselves move, ``p = p0 + u sigma_p`` with the prior residuals ``u`` appended, and ``w`` holds the
data variance alone.  Starts are the best of a grid over each fitted parameter's literature range (at most
:data:`MAX_STARTS` points);
the Jacobian is a forward difference evaluated for all parameters in one batched model call.
Standard errors come from ``(J^T J)^-1``, scaled by the reduced chi-square when that exceeds one;
95 % intervals are +-1.96 standard errors, or +-``t_{n-p}(0.975)`` when so scaled (the scale is then
estimated: :func:`scale_and_quantile`), clipped to the bounds.  Benchmark parameters move at most
five standard deviations, and never to a non-positive mass, length, wheel radius or moment of
inertia (:data:`POSITIVE`).  The ``speed_sensor`` candidate scales the speed the bicycle ran at
(the control gains stay those of the recorded speed, which the controller used).
"""

from __future__ import annotations

import contextvars
import copy
import itertools
import logging
import math
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import least_squares
from scipy.special import stdtrit  # Student's t quantile (scipy.stats.t.ppf's own function, without its import)

from bikerider.engine import DifferencedStage
from bikerider.errors import InputError
from bikerider.gap.candidates.effect_model import BENCH_ARGS, STRUCTURAL_KEYS, EffectModel, RiderGeometry, geometry_keys
from bikerider.gap.candidates.effects import EFFECTS, OBSERVATION_EFFECTS, PARAMETERS, SPEED_SENSOR
from bikerider.gap.candidates.nominal import GapModelInput
from bikerider.gap.inference.differences import forward_jacobian
from bikerider.gap.inference.frequency_response import predict_frf_scaled  # multisine records
from bikerider.gap.inference.predict import Predictor
from bikerider.gap.measured.multisine import FrequencyResponseData
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData

if TYPE_CHECKING:
    from bikerider.gap.inference.indirect import RecordRows

LOG = logging.getLogger(__name__)
MAX_STARTS = 32
"""Most grid points tried as starting values of one fit (a fixed random subset beyond that)."""
_BAD = 1e3
"""Residual assigned to every observation when a model cannot be evaluated (singular matrices)."""
MAX_SHIFT = 5.0
"""Largest shift of a benchmark parameter in the ``parameters`` fit, in standard deviations."""
START_MARGIN = 1e-4
"""Starting values on a bound are moved this fraction of the search range inside it (see ``_fit``)."""
POSITIVE = ("w", "rR", "rF", "mR", "mB", "mH", "mF", "IRxx", "IRyy", "IBxx", "IBzz", "IHxx", "IHzz", "IFxx", "IFyy")
"""Benchmark parameters a shift must leave positive (at least 1 % of the nominal value)."""
MIN_REPLICATES = 3
"""Fewest records of one group and speed whose scatter counts as a replicate estimate."""
REPLICATE_SPEED = (0.05, 0.03)
"""Rows are replicates when their speeds differ by less than this many m/s or this fraction."""
MAX_BIAS_ITERATIONS = 4
"""Most evaluations of a fitted model's own extraction bias in the iterated bias correction."""
BIAS_TOLERANCE = 0.1
"""The iterated bias correction stops when the records' biases change by no more than this fraction of
their data standard uncertainties (root mean square over the records fitted): the fit's chi-square
then moves by a small fraction of one."""
APPARENT_ITERATIONS = 6
"""Most Gauss-Newton steps of the apparent eigenvalues' least squares polishing a fit to all the data
(:meth:`GapProblem.fit_apparent`)."""
APPARENT_TOLERANCE = 0.05
"""The polish stops when a step lowers the chi-square by less than this (a twentieth of what one
standard error's move of a fitted value changes it by)."""
MINIMUM_STARTS = 3
"""Grid starts from which the search for other local minima of the apparent eigenvalues' least squares
(:meth:`GapProblem.fit_apparent`) fits the cheap model (:meth:`GapProblem._further_starts`): those with
the lowest chi-square of the weave eigenvalues plus the nominal model's extraction bias."""
MINIMUM_ITERATIONS = 8
"""Most Gauss-Newton steps from each further start of that search."""
MINIMUM_DECREMENT = 0.5
"""A search from a further start counts as having found a local minimum when the Gauss-Newton step at
its last point (clipped to the bounds) would lower the chi-square by less than this."""
PROFILE_MAX_RECORDS = 20
"""Most records of a single candidate's fit whose 95 % intervals are profile-likelihood intervals
(:meth:`GapProblem.profile_apparent`; every profile point simulates every record, so its cost grows with
them: on the calibration's record sets of 3-9 records a profile adds 0.1-0.3 s to a fit, on the 55 used of the
steer-by-wire logs it would add seconds to a diagnosis at its time goal).  Fits on more keep the linearised
intervals and the hull of the points searched."""
PROFILE_POINTS = 8
"""Most profile points (each one fit of the other sizes) per size and side in :meth:`GapProblem.profile_apparent`."""
PROFILE_STEPS = 4
"""Most Gauss-Newton steps of the other sizes at one profile point."""
PROFILE_GAIN = 0.01
"""The other sizes are at their minimum for a profile point when the Gauss-Newton step (clipped to the
bounds) would lower the chi-square by less than this."""
PROFILE_TOLERANCE = 0.1
"""An end point of a profile-likelihood interval is a point whose profile chi-square lies within this of
the fit's chi-square plus the threshold (about 1 % of the interval's half-width at a threshold of 3.84)."""
MAX_BIAS_STEP = 0.2
"""Largest move of a fitted value in one step of the iterated bias correction, as a fraction of its
search range (a longer Gauss-Newton step is shortened to it)."""
MEMO_ELEMENTS = 1 << 20
"""Most predicted numbers :meth:`GapProblem.predict_batch` keeps (8 MB), the most recently used."""


@dataclass(kw_only=True)
class EffectFit:
    """A set of effects fitted to a subset of the observations.

    Attributes
    ----------
    effects : tuple of str
    names, units : list of str
        Fitted parameters (structural ones by symbol, benchmark ones as ``parameters.<name>``).
    values, stderr, ci_low, ci_high : ndarray
    config : dict
        Effect name to ``{parameter: value}`` for :class:`EffectModel` (fixed values included).
    shift : dict
        Benchmark parameter changes (``parameters`` effect), SI.
    chi2 : float
        Sum of squared data residuals over the fitted points.
    prior_chi2 : float
        Sum of squared prior residuals ``u`` (``parameters`` only, else 0).
    n : int
        Number of fitted points.
    success : bool
    message : str

    Built by keyword only (sixteen fields, several of one type: a position is easily mistaken).
    """

    effects: tuple[str, ...]
    names: list[str]
    units: list[str]
    values: np.ndarray
    stderr: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    config: dict[str, dict[str, float]]
    shift: dict[str, float]
    chi2: float
    prior_chi2: float
    n: int
    success: bool
    message: str = ""
    lower: np.ndarray = field(default_factory=lambda: np.zeros(0))
    upper: np.ndarray = field(default_factory=lambda: np.zeros(0))
    bias: np.ndarray | None = None
    """The fitted model's own extraction bias at every observation (records; see :meth:`GapProblem.fit`)."""
    bias_iterations: int = 0
    covariance: np.ndarray | None = None
    """Covariance of the fitted values (their standard errors are its diagonal's roots), where known."""
    jackknife_covariance: np.ndarray | None = None
    """The share of ``covariance`` estimated from the spread of the held-out folds' fits (a jackknife, few
    degrees of freedom: :func:`bikerider.gap.diagnosis.statistics.interval_quantile`), where there is one."""
    corners: list[tuple[float, float, np.ndarray]] = field(default_factory=list)
    """A time-domain fit refitted at each friction corner ``(eps, weight, values)``, its own first; their
    share is in ``covariance`` (:func:`bikerider.gap.inference.timedomain.corner_share`)."""
    corner_covariance: np.ndarray | None = None
    """That share of ``covariance``, where it was taken."""
    minima: list[tuple[np.ndarray, float]] = field(default_factory=list)
    """Other local minima of the fit's chi-square that a search from further starts found (values,
    chi-square), distinct from this one, which is the lowest found (:meth:`GapProblem.fit_apparent`)."""
    visited: list[tuple[np.ndarray, float]] = field(default_factory=list)
    """Every point those searches stepped to (values, chi-square): each with a chi-square within the 95 %
    profile-likelihood threshold of the fit's lies in every size's profile-likelihood interval."""
    minima_within: int = 0
    """How many of ``minima`` lie within the 95 % profile-likelihood threshold of the best, and so are held by
    every size's 95 % interval (:func:`bikerider.gap.diagnosis.fits.with_parameter_uncertainty`); they come
    first in ``minima``."""

    profiled: list[str] = field(default_factory=list)
    """The sizes whose 95 % interval is a profile-likelihood interval
    (:func:`bikerider.gap.diagnosis.fits.with_parameter_uncertainty` with ``profile``)."""

    def at_bound(self) -> list[str]:
        """Names of the fitted values pinned at a bound of the search."""
        out = []
        for k, name in enumerate(self.names):
            span = max(self.upper[k] - self.lower[k], 1e-12)
            if min(abs(self.values[k] - self.lower[k]), abs(self.upper[k] - self.values[k])) <= 1e-4 * span:
                out.append(name)
        return out


def scale_and_quantile(chi2: float, n: int, p: int) -> tuple[float, float]:
    """The factor a fit's covariance is scaled by and the 97.5 % point its 95 % intervals use.

    The covariance from the stated uncertainties assumes they are the data's scale; when the fit's
    reduced chi-square ``s^2 = chi2 / (n - p)`` exceeds one, the data scatter more than stated and the
    covariance is scaled by ``s^2``: the scale is then *estimated* from the ``n - p`` residuals, and
    ``(value - truth) / stderr`` follows Student's t with ``n - p`` degrees of freedom, not the normal
    (exactly so for a linear model with Gaussian errors of one unknown common scale; the regression
    textbooks' interval), so the quantile is ``t_{n-p}(0.975)`` (2.78 for 4 degrees of freedom, 2.07 for
    24, 1.96 as they grow).  With ``s^2 <= 1`` the stated scale stands and the normal 1.96 is used.
    Returns ``(max(1, s^2), quantile)``.
    """
    dof = max(int(n) - int(p), 1)
    reduced = float(chi2) / dof if np.isfinite(chi2) else math.inf
    if not reduced > 1.0:
        return 1.0, 1.96
    if not math.isfinite(reduced):
        return reduced, 1.96
    return reduced, float(stdtrit(dof, 0.975))


@dataclass
class Profile:
    """The profile-likelihood intervals of a fit's sizes (:meth:`GapProblem.profile_apparent`).

    Attributes
    ----------
    low, high : ndarray
        Each size's end points (NaN for a size not profiled); an end on a bound of the search where the
        profile stays below its target up to the bound.
    chi2_low, chi2_high : ndarray
        The profile chi-square at each end point (the other sizes minimised there).
    points : list of (ndarray, float)
        Every profile point (the values of all sizes, chi-square).
    calls : int
        Batched model calls made.
    seconds : float
    """

    low: np.ndarray
    high: np.ndarray
    chi2_low: np.ndarray
    chi2_high: np.ndarray
    points: list[tuple[np.ndarray, float]] = field(default_factory=list)
    calls: int = 0
    seconds: float = 0.0


@dataclass
class _Layout:
    """How a fit's parameter vector maps onto effect parameters and benchmark shifts."""

    effects: tuple[str, ...]
    structural: list[tuple[str, str]] = field(default_factory=list)  # (effect, parameter)
    lower: list[float] = field(default_factory=list)
    upper: list[float] = field(default_factory=list)
    starts: list[tuple[float, ...]] = field(default_factory=list)
    units: list[str] = field(default_factory=list)
    n_shift: int = 0


class GapProblem:
    """Observations of one bicycle, its nominal model and their uncertainties.

    Parameters
    ----------
    model : GapModelInput
    eigen : EigenvalueData
    canonical : CanonicalData
    """

    def __init__(
        self,
        model: GapModelInput,
        eigen: EigenvalueData,
        canonical: CanonicalData,
        records: RecordRows | None = None,
        frf: FrequencyResponseData | None = None,
    ):
        if len(eigen) + len(canonical) + (len(frf) if frf is not None else 0) == 0:
            raise InputError("data", "empty", "at least one measured eigenvalue or identified entry")
        self.model_input = model
        self.geometry = model.geometry
        values, sigmas = model.parameters.values, model.parameters.sigmas
        self.nominal = {k: float(values[k]) for k in BENCH_ARGS + ("g",)}  # type: ignore[arg-type]
        self.free = [k for k in BENCH_ARGS if sigmas.get(k, 0.0) > 0]
        self.free_sigma = np.array([sigmas[k] for k in self.free])
        self.shift_lower = np.array(
            [
                max(-MAX_SHIFT, (0.01 * self.nominal[k] - self.nominal[k]) / s)
                if k in POSITIVE and self.nominal[k] > 0
                else -MAX_SHIFT
                for k, s in zip(self.free, self.free_sigma)
            ]
        )
        self.shift_upper = np.full(len(self.free), MAX_SHIFT)
        self.eigen = eigen
        self.predictor = Predictor(eigen, canonical, self.nominal, self.geometry, frf)  # frf: the multisine records
        self.obs = self.predictor.observations
        self.y = self.obs.value
        self.records = records
        self.record_obs = self._record_observations()
        self._memo: OrderedDict[tuple, np.ndarray] = OrderedDict()
        self._layouts: dict[tuple[str, ...], _Layout] = {}
        self.baseline = self.predict_models(self.nominal, {})[0]
        # each record row's extraction bias under the nominal model (apparent minus weave eigenvalue):
        # the starting offset of the fits' iterated bias correction, and the replicate scatter's reference
        self.nominal_bias = self.baseline - self.predictor.predict(EffectModel(self.nominal, self.geometry))
        self.notes: list[str] = []
        self.noise: list[dict] = []
        self.jacobian = self._parameter_jacobian()  # (n_obs, n_free), per sigma
        self.var_model = np.sum(self.jacobian**2, axis=1)
        self.var_speed = self._speed_variance(eigen)
        self.sigma_data = self.data_sigma()
        self.var_data = self.sigma_data**2 + self.var_speed
        self.var_total = self.var_data + self.var_model
        bad = np.flatnonzero(~(self.var_total > 0))
        if bad.size:
            k = int(bad[0])
            raise InputError(
                f"uncertainty of {self.obs.source[k]} ({self.obs.mode[k]} {self.obs.quantity[k]})",
                0.0,
                "a data or parameter uncertainty: give real_sigma/imag_sigma (or sigma) in the data, "
                "replicate rows, or parameter uncertainties in the model file",
            )

    # -- uncertainties -------------------------------------------------------------------------
    def _parameter_jacobian(self) -> np.ndarray:
        """Slopes of the nominal predictions per standard uncertainty of each free parameter.

        A secant over +-1 sigma (central differences by the uncertainty engine), so that the
        model variance it gives is that of the parameters' plausible range, not of a tangent.
        """
        if not self.free:
            return np.zeros((len(self.obs), 0))
        stage = DifferencedStage(
            "gap predictions",
            lambda v: self.predict_models({**self.nominal, **v}, {}),
            inputs=self.free,
            outputs=range(len(self.obs)),
            steps=dict(zip(self.free, self.free_sigma)),
            batched=True,
            extra_dims=1,
        )
        return stage.jacobian({k: self.nominal[k] for k in self.free}) * self.free_sigma

    def with_geometry(self, geometry: RiderGeometry) -> GapProblem:
        """This problem with another rider geometry, for predictions only: the data, the nominal
        model's uncertainties and the records' starts shared, the predictions' store its own (its keys
        do not hold the geometry), nothing of this problem changed."""
        other = copy.copy(self)
        other.geometry = geometry
        other.model_input = replace(self.model_input, geometry=geometry)
        other.predictor = copy.copy(self.predictor)
        other.predictor.geometry = geometry
        if self.records is not None:
            simulator = copy.copy(self.records.simulator)
            simulator.geometry = geometry
            simulator.known = {}  # models of benchmark values alone, simulated with this problem's geometry
            other.records = replace(self.records, simulator=simulator)
        other._memo = OrderedDict()
        return other

    def geometry_sources(self, lay: _Layout) -> list[str]:
        """The sources of the rider geometry's uncertainty (:attr:`RiderGeometry.uncertainty`) that move
        the predictions of a layout's effects (none for effects that do not use the geometry)."""
        return self.geometry.sources(geometry_keys(lay.effects))

    def geometry_jacobian(self, lay: _Layout, x: np.ndarray, indirect: bool = True) -> np.ndarray:
        """Slopes ``(n_obs, n_sources)`` of the predictions at fitted values ``x`` per standard
        uncertainty of each of :meth:`geometry_sources`.

        The geometry moves the predictions only through the rider's effects, so the slopes are taken
        at the fit, not at the nominal model: a secant over +-1 sigma of each source (as
        :meth:`_parameter_jacobian`), one-sided where a step leaves an impossible geometry (a negative
        mass), the same prediction path as the fit's (``indirect``: the rows from records by indirect
        inference).  NaN where a shifted model cannot be evaluated.
        """
        sources = self.geometry_sources(lay)
        x = np.atleast_2d(np.asarray(x, dtype=float))
        out = np.zeros((len(self.obs), len(sources)))
        for j, name in enumerate(sources):
            ends = []
            for factor in (1.0, -1.0):
                try:
                    shifted = self.geometry.shifted(name, factor)
                except InputError:  # an impossible geometry one sigma away: the secant from the fit's own
                    ends.append((0.0, self.predict_batch(lay, x, indirect=indirect)[0]))
                    continue
                ends.append((factor, self.with_geometry(shifted).predict_batch(lay, x, indirect=indirect)[0]))
            (f_up, up), (f_down, down) = ends
            out[:, j] = (up - down) / (f_up - f_down) if f_up != f_down else np.nan
        return out

    def parameter_jacobian_at(
        self, lay: _Layout, x: np.ndarray, indirect: bool = True, columns: np.ndarray | None = None
    ) -> np.ndarray:
        """Slopes ``(n_obs, n_free)`` of the predictions at fitted values ``x`` per standard uncertainty
        of each free benchmark parameter.

        :attr:`jacobian` holds them at the nominal model, without any effect; an effect that moves the
        bicycle far from it (a steer inertia of the steer assembly's own size) changes how each
        parameter moves the predictions, and an interval taken with the nominal slopes then misses the
        parameters' share.  A secant from the fit to one sigma above it (one-sided: half the simulations
        of :meth:`_parameter_jacobian`'s secant over +-1 sigma), on the fit's own prediction path
        (``indirect``).  Only the parameters ``columns`` (indices into
        :attr:`free`; all when None) are taken at the fit, the others keep their nominal slopes; so does
        a parameter whose shifted model cannot be evaluated (the record fit finds no weave in its
        response).
        """
        out = np.array(self.jacobian, dtype=float)
        cols = np.arange(len(self.free)) if columns is None else np.asarray(columns, dtype=int)
        n = cols.size
        if not n:
            return out
        full = self.layout(tuple(lay.effects) + (PARAMETERS,))
        x = np.asarray(x, dtype=float).ravel()
        rows = np.zeros((1 + n, x.size + len(self.free)))
        rows[:, : x.size] = x
        rows[1 + np.arange(n), x.size + cols] = 1.0
        pred = self.predict_batch(full, rows, indirect=indirect)
        slopes = (pred[1:] - pred[0]).T
        good = np.all(np.isfinite(slopes), axis=0)
        out[:, cols[good]] = slopes[:, good]
        if not np.all(good):  # a shifted model the fit's path cannot evaluate: its nominal slopes, said
            names = [self.free[k] for k in cols[~good]]
            LOG.info("%s: no slope at the fit in %s; their nominal slopes taken", lay.effects, names)
        return out

    def _values_batch(self, shifts: np.ndarray) -> dict[str, object]:
        """Benchmark values with shifts ``(P, n_free)`` (SI) applied, shaped ``(P, 1)``."""
        values: dict[str, object] = dict(self.nominal)
        for j, name in enumerate(self.free):
            values[name] = (self.nominal[name] + shifts[:, j])[:, None]
        return values

    def _speed_variance(self, eigen: EigenvalueData) -> np.ndarray:
        out = np.zeros(len(self.obs))
        if not len(eigen) or not np.any(eigen.speed_sigma > 0):
            return out
        # the step: the speed uncertainty, at least 1 mm/s, at most half the speed (never a negative speed)
        h = np.minimum(np.maximum(eigen.speed_sigma, 1e-3), 0.5 * eigen.speed)
        slopes = [
            self.predict_models(self.nominal, {}, row_scale=1 + sign * h / eigen.speed)[0, : len(out)]
            for sign in (1, -1)
        ]
        slope = (slopes[0] - slopes[1]) / 2  # per h, eigenvalue parts first
        k = 0
        for row in range(len(eigen)):
            parts = 2 if eigen.mode[row] == "weave" else 1
            for _ in range(parts):
                out[k] = (slope[k] / h[row] * eigen.speed_sigma[row]) ** 2
                k += 1
        return out

    def data_sigma(self) -> np.ndarray:
        """Standard uncertainty of every observation from the data alone (module docstring).

        Never from residuals against a model: a model error must not become noise.  Which estimate
        each kind of row got is in :attr:`noise` and :attr:`notes`.
        """
        obs = self.obs
        sigma = obs.sigma.copy()
        kind = self._sigma_source()
        eig_rows = [i for i in range(len(obs)) if obs.kind[i] == "eigenvalue"]
        cells = self._replicate_cells(eig_rows)
        # records: the larger of each record's standard error and its cell's replicate scatter
        rec = [i for i in eig_rows if kind[i] == "record"]
        if rec:
            raised = 0
            scatter_used = 0
            for cell in cells:
                members = [i for i in cell if kind[i] == "record"]
                if len(members) >= MIN_REPLICATES:
                    # about each record's own expectation: the nominal model's extraction bias removed
                    s = float(np.std(self.y[members] - self.nominal_bias[members], ddof=1))
                    scatter_used += len(members)
                    for i in members:
                        if s > sigma[i]:
                            sigma[i] = s
                            raised += 1
            self.noise.append(
                {
                    "rows": "record",
                    "n": len(rec),
                    "estimate": "record fit standard errors and replicate scatter",
                    "replicates": scatter_used,
                    "raised_by_replicates": raised,
                }
            )
            self.notes.append(
                f"{len(rec)} record values: uncertainty the larger of the record's own fit standard error "
                f"and the scatter of its replicates (records of one group at one speed, at least "
                f"{MIN_REPLICATES}; {scatter_used} values had replicates, {raised} were raised by them)"
            )
        # rows without any: the pooled scatter of replicate rows of the same mode and quantity
        none = [i for i in eig_rows if kind[i] == "none"]
        for key in sorted({(obs.mode[i], obs.quantity[i]) for i in none}):
            idx = [i for i in none if (obs.mode[i], obs.quantity[i]) == key]
            dev, dof = 0.0, 0
            in_key = set(idx)
            for cell in cells:
                members = [i for i in cell if i in in_key]
                if len(members) >= 2:
                    dev += float(np.sum((self.y[members] - np.mean(self.y[members])) ** 2))
                    dof += len(members) - 1
            if dof >= 1:
                estimate = math.sqrt(dev / dof)
                sigma[idx] = estimate
                self.noise.append(
                    {
                        "rows": f"{key[0]} {key[1]}",
                        "n": len(idx),
                        "estimate": "pooled replicate scatter",
                        "value": estimate,
                        "dof": dof,
                    }
                )
                self.notes.append(
                    f"{key[0]} {key[1]}: no stated uncertainty; {estimate:.3g} 1/s from the pooled scatter "
                    f"of replicate rows (same group and speed; {dof} degrees of freedom)"
                )
            else:
                sigma[idx] = 0.0
                self.noise.append({"rows": f"{key[0]} {key[1]}", "n": len(idx), "estimate": "none"})
                self.notes.append(
                    f"{key[0]} {key[1]}: no stated uncertainty, no replicates and no records to estimate one "
                    "from; the rows are taken as exact and only the speed and parameter uncertainties count "
                    "(give real_sigma and imag_sigma, or the records)"
                )
        stated = [i for i in range(len(obs)) if kind[i] == "stated"]
        if stated:
            self.noise.append({"rows": "stated", "n": len(stated), "estimate": "stated in the data"})
        return np.where(np.isfinite(sigma), sigma, 0.0)

    def _sigma_source(self) -> list[str]:
        """Per observation: ``stated``, ``record`` or ``none`` (canonical entries state theirs)."""
        out = []
        e = self.eigen
        for k in range(len(e)):
            src = e.sigma_source[k] if e.sigma_source else "stated"
            parts = 2 if e.mode[k] == "weave" else 1
            for part in range(parts):
                given = np.isfinite(e.real_sigma[k] if part == 0 else e.imag_sigma[k])
                out.append(src if src != "stated" or given else "none")
        out += ["stated"] * (len(self.obs) - len(out))
        return out

    def _replicate_cells(self, rows: list[int]) -> list[list[int]]:
        """Observations of one group, mode and quantity at one speed (:data:`REPLICATE_SPEED`)."""
        obs = self.obs
        cells: list[list[int]] = []
        by_key: dict[tuple, list[int]] = {}
        for i in rows:  # one pass: the data may hold as many groups as rows
            by_key.setdefault((obs.group[i], obs.mode[i], obs.quantity[i]), []).append(i)
        for key in sorted(by_key):
            members = sorted(by_key[key], key=lambda i: obs.speed[i])
            current: list[int] = []
            for i in members:
                if current:
                    v0 = obs.speed[current[0]]
                    if abs(obs.speed[i] - v0) > max(REPLICATE_SPEED[0], REPLICATE_SPEED[1] * v0):
                        cells.append(current)
                        current = []
                current.append(i)
            if current:
                cells.append(current)
        return cells

    # -- models ------------------------------------------------------------------------------------
    def layout(self, effects: tuple[str, ...]) -> _Layout:
        """How the parameter vector of a set of effects maps onto the models (worked out once per set)."""
        effects = tuple(effects)
        if effects not in self._layouts:
            self._layouts[effects] = self._new_layout(effects)
        return self._layouts[effects]

    def _new_layout(self, effects: tuple[str, ...]) -> _Layout:
        lay = _Layout(tuple(effects))
        grids = []
        for name in effects:
            if name == PARAMETERS:
                lay.n_shift = len(self.free)
                continue
            for p in EFFECTS[name].parameters:
                lay.structural.append((name, p.name))
                lay.lower.append(p.bounds[0])
                lay.upper.append(p.bounds[1])
                lay.units.append(p.unit)
                lo, hi = p.literature
                grids.append(sorted({float(np.clip(x, *p.bounds)) for x in (lo, 0.5 * (lo + hi), hi, p.start)}))
        if not grids:
            lay.starts = [()]
            return lay
        mids = tuple(g[len(g) // 2] for g in grids)
        total = math.prod(len(g) for g in grids)
        if total <= MAX_STARTS:
            lay.starts = list(itertools.product(*grids))
        else:  # a fixed random subset of the grid, and the middle of every range
            rng = np.random.default_rng(0)
            picks = {tuple(int(rng.integers(len(g))) for g in grids) for _ in range(4 * MAX_STARTS)}
            lay.starts = [mids] + [tuple(g[i] for g, i in zip(grids, pick)) for pick in sorted(picks)][: MAX_STARTS - 1]
        return lay

    def configure(self, lay: _Layout, x: np.ndarray) -> tuple[dict[str, object], dict[str, dict[str, object]], object]:
        """Benchmark values, effect configuration and speed scale for parameter vectors ``x`` ``(P, p)``."""
        n_struct = len(lay.structural)
        config: dict[str, dict[str, object]] = {}
        scale: object = None
        for name in lay.effects:
            if name != PARAMETERS and name not in OBSERVATION_EFFECTS:
                config[name] = dict(EFFECTS[name].fixed)
        for j, (name, param) in enumerate(lay.structural):
            if name == SPEED_SENSOR:
                scale = x[:, j]
            else:
                config[name][param] = x[:, j : j + 1]
        if lay.n_shift:
            values = self._values_batch(x[:, n_struct:] * self.free_sigma)
        else:
            values = dict(self.nominal)
        return values, config, scale

    def _record_observations(self) -> np.ndarray:
        """Observation indices ``(R, 2)`` (real, imaginary part) of the rows fitted from records."""
        if self.records is None:
            return np.zeros((0, 2), int)
        first = np.cumsum([0] + [2 if m == "weave" else 1 for m in self.eigen.mode])
        return np.array([[first[row], first[row] + 1] for row in self.records.rows], int).reshape(-1, 2)

    def predict_models(
        self, values: dict, config: dict, scale=None, row_scale=None, indirect: bool = True, strict: bool = False
    ) -> np.ndarray:
        """Predictions ``(P, n_obs)`` of batched models; NaN rows when singular (``strict``: the
        ``LinAlgError`` raised instead).

        ``values`` and ``config`` as :class:`EffectModel` takes them (arrays of a leading size ``P``);
        ``scale`` a speed scale per model for the rows a sensor read (``speed_sensor``); ``row_scale`` a
        speed scale per eigenvalue row (the speed's uncertainty).  With ``indirect`` (the default), the
        rows fitted from records are predicted by indirect inference (:mod:`bikerider.gap.inference.indirect`):
        what the record fit finds in each model's own response over the record; otherwise by the
        models' weave eigenvalues.
        """
        try:
            with np.errstate(all="ignore"):
                if row_scale is not None:
                    out = self.predictor.predict(EffectModel(values, self.geometry, config), speed_scale=row_scale)
                elif scale is None:
                    out = self.predictor.predict(EffectModel(values, self.geometry, config))
                else:  # a speed scale per parameter vector: the (vector, row) pairs flattened into one call
                    n_rows = len(self.eigen)
                    P = np.asarray(scale).size

                    def flat(v):
                        a = np.asarray(v, dtype=float)
                        if a.size == 1:  # one value for every model: it broadcasts as it is
                            return float(a.reshape(-1)[0])
                        return np.repeat(np.broadcast_to(a.reshape(-1, 1)[:, :1], (P, 1))[:, 0], n_rows)

                    flat_values = {n: flat(v) for n, v in values.items()}
                    flat_config = {e: {n: flat(v) for n, v in p.items()} for e, p in config.items()}
                    eigen_part = (
                        self.predictor.predict_scaled(
                            EffectModel(flat_values, self.geometry, flat_config), np.asarray(scale, dtype=float)
                        )
                        if n_rows
                        else np.zeros((P, 0))  # multisine runs only
                    )
                    if len(self.predictor.canonical) or len(self.predictor.frf):  # the rest: canonical, multisines
                        rest = self.predictor.predict(EffectModel(values, self.geometry, config))[
                            ..., eigen_part.shape[-1] :
                        ]
                        out = np.concatenate([eigen_part, np.broadcast_to(rest, (P, rest.shape[-1]))], axis=-1)
                        frf = self.predictor.frf
                        if len(frf) and np.any(frf.speed_sensor):  # multisine runs a sensor's speed: rescaled
                            out[:, out.shape[-1] - 2 * len(frf) :] = predict_frf_scaled(
                                values, self.geometry, config, frf, scale
                            )
                    else:
                        out = eigen_part
                out = np.atleast_2d(out)
                if indirect and self.records is not None and len(self.record_obs):
                    rscale = None if row_scale is None else np.asarray(row_scale, float)[self.records.rows][None, :]
                    apparent = self.records.simulator.apparent(values, config, scale if rscale is None else rscale)
                    out = np.array(np.broadcast_to(out, (max(out.shape[0], apparent.shape[0]), out.shape[1])))
                    out[:, self.record_obs[:, 0]] = apparent.real
                    out[:, self.record_obs[:, 1]] = apparent.imag
        except np.linalg.LinAlgError:
            if strict:
                raise
            return np.full((1, len(self.obs)), np.nan)
        return out

    def predict_batch(self, lay: _Layout, x: np.ndarray, indirect: bool = True, strict: bool = False) -> np.ndarray:
        """Predictions ``(P, n_obs)`` for parameter vectors ``x`` ``(P, p)`` (see :meth:`predict_models`).

        Each parameter vector's predictions are kept (:data:`MEMO_ELEMENTS` numbers at most, the most
        recently used): the fits evaluate the same vectors again (a fold's fit starts where the fit to
        all the data ended, a Jacobian at the point just evaluated), and a vector's predictions do
        not depend on the others evaluated with it.  With ``indirect``, the weave eigenvalues come
        from the same store and only the rows fitted from records are simulated.
        """
        x = np.atleast_2d(np.asarray(x, dtype=float))
        if not indirect or self.records is None or not len(self.record_obs):
            return self._memo_rows(lay, x, False, lambda X: self._predict_rows(lay, X, False, strict))

        def simulate(X: np.ndarray) -> np.ndarray:
            base = self._memo_rows(lay, X, False, lambda Y: self._predict_rows(lay, Y, False))
            values, config, scale = self.configure(lay, X)
            try:
                with np.errstate(all="ignore"):
                    apparent = self.records.simulator.apparent(values, config, scale)
            except np.linalg.LinAlgError:
                return np.full((X.shape[0], len(self.obs)), np.nan)
            out = np.array(np.broadcast_to(base, (max(base.shape[0], apparent.shape[0]), base.shape[1])))
            out[:, self.record_obs[:, 0]] = apparent.real
            out[:, self.record_obs[:, 1]] = apparent.imag
            return out

        return self._memo_rows(lay, x, True, simulate)

    def _predict_rows(self, lay: _Layout, X: np.ndarray, indirect: bool, strict: bool = False) -> np.ndarray:
        values, config, scale = self.configure(lay, X)
        out = self.predict_models(values, config, scale, indirect=indirect, strict=strict)
        return np.broadcast_to(out, (X.shape[0], out.shape[-1]))

    def _memo_rows(self, lay: _Layout, X: np.ndarray, indirect: bool, compute) -> np.ndarray:
        """Rows of ``compute(X)`` ``(P, n_obs)``, each computed once per parameter vector (the store
        of :meth:`predict_batch`); the vectors not yet in it are computed together in one call."""
        memo = self._memo
        keys = [(lay.effects, indirect, row.tobytes()) for row in X]
        new = list(dict.fromkeys(k for k in keys if k not in memo))
        if new:
            first = {k: i for i, k in reversed(list(enumerate(keys)))}
            rows = np.asarray(compute(X[[first[k] for k in new]]), dtype=float)
            rows = np.broadcast_to(rows, (len(new), rows.shape[-1]))
            limit = max(1, MEMO_ELEMENTS // max(rows.shape[-1], 1))
            for k, row in zip(new, rows):
                memo[k] = row.copy()
            while len(memo) > limit:
                memo.popitem(last=False)
            fresh = dict(zip(new, rows))
        else:
            fresh = {}
        out = np.empty((X.shape[0], len(self.obs)))
        for i, k in enumerate(keys):
            row = fresh.get(k)
            if row is None:
                row = memo[k]
                memo.move_to_end(k)
            out[i] = row
        return out

    def z(self, prediction: np.ndarray) -> np.ndarray:
        """Residuals ``(prediction - y) / sqrt(data + model variance)``."""
        return (prediction - self.y) / np.sqrt(self.var_total)

    # -- fitting -------------------------------------------------------------------------------
    def bounds(self, lay: _Layout) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of a layout's parameter vector."""
        lower = np.array(lay.lower + (list(self.shift_lower) if lay.n_shift else []), dtype=float)
        upper = np.array(lay.upper + (list(self.shift_upper) if lay.n_shift else []), dtype=float)
        return lower, upper

    def fit(
        self,
        effects: tuple[str, ...],
        mask: np.ndarray | None = None,
        start: np.ndarray | None = None,
        bias: np.ndarray | None = None,
    ) -> EffectFit:
        """Fit ``effects`` to the observations selected by ``mask`` (all by default).

        ``start`` (a parameter vector, e.g. the fit to all the data when fitting a fold) replaces
        the grid of starting values.  Rows fitted from records are fitted by iterated bias correction
        (module docstring): ``bias`` (one value per observation) is the first correction, by default
        the nominal model's extraction bias.  Given both, ``bias`` is taken as the model's own at
        ``start``, and a fit that ends worse than ``start`` (chi-square with its own bias, on the
        observations in ``mask``) is held at ``start`` instead (:meth:`fit_many`).
        """
        return self.fit_many(effects, [mask], start, bias)[0]

    def fit_many(
        self,
        effects: tuple[str, ...],
        masks: list,
        start: np.ndarray | None = None,
        bias: np.ndarray | None = None,
    ) -> list[EffectFit]:
        """:meth:`fit` for each of ``masks`` (e.g. the folds of a cross-validation), the same ``start``
        and ``bias`` for all: the same fits, their bias corrections advanced together.

        Each bias iteration evaluates the own extraction bias of every fit not yet settled in one
        batched simulation (:meth:`own_bias` of several parameter vectors: one refit call for all of
        their records, the refits' fixed cost per step shared); each record's refit is computed as
        alone, so every fit is the one :meth:`fit` makes.

        Never worse than the start.  The bias correction assumes the records' extraction bias changes
        slowly with the values; where another mode takes over a model's response it does not, and a fit
        can settle where its weave eigenvalues plus the old bias fit the data while the model's own
        response does not (the SBW folds of parameters + tyre_slip: held-out error 6.7 against 0.88 for the
        nominal model).  With ``start`` and ``bias`` both given (``bias`` then the start's own, as for a
        fold started from the fit to all the data), a fit whose chi-square with its own bias ends above the
        start's on its observations is held at the start (:meth:`fit_at`).
        """
        if self.records is None or not len(self.record_obs):
            return self._fit_together(tuple(effects), masks, start, [None] * len(masks))
        lay = self.layout(tuple(effects))
        lower, upper = self.bounds(lay)
        runs = []
        offsets = [np.array(self.nominal_bias if bias is None else bias, dtype=float) for _ in masks]
        for mask, offset, fit in zip(masks, offsets, self._fit_together(tuple(effects), masks, start, offsets)):
            mask = np.ones(len(self.obs), bool) if mask is None else np.asarray(mask, bool)
            rec = self.record_obs.ravel()
            rec = rec[mask[rec]]
            runs.append({"mask": mask, "rec": rec, "sigma": np.sqrt(self.var_data[rec]), "offset": offset, "fit": fit})
            runs[-1].update(x=fit.values.copy(), iteration=0, done=False)
        for iteration in range(1, MAX_BIAS_ITERATIONS + 1):
            todo = [run for run in runs if not run["done"]]
            if not todo:
                break
            owns = self.own_bias(lay, np.array([run["x"] for run in todo]))
            for run, own in zip(todo, owns):
                run["iteration"] = iteration
                self._bias_step(run, own, iteration, lower, upper)
        out = []
        for run in runs:
            lay_fit, mask, x, offset = run["fit"], run["mask"], run["x"], run["offset"]
            # the residuals, chi-square and values reported: those of the fitted model's own bias
            r = self._residuals(lay, mask, x, offset)
            fit = self._result(
                lay, x, lay_fit.stderr, r, int(mask.sum()), lay_fit.success, lay_fit.message, lay_fit._quantile
            )
            fit.bias, fit.bias_iterations, fit.covariance = offset, run["iteration"], lay_fit.covariance
            if start is not None and bias is not None and np.size(start) == lay_fit.values.size:
                at_start = self._residuals(lay, mask, np.asarray(start, dtype=float), np.asarray(bias, dtype=float))
                chi2_start = float(np.sum(at_start[: int(mask.sum())] ** 2))
                if chi2_start < fit.chi2:
                    LOG.info("%s: a fit ended at chi-square %.4g, above its start's %.4g: held there", effects,
                             fit.chi2, chi2_start)  # fmt: skip
                    fit = self.fit_at(effects, start, bias, "held at its start (the fit from there went astray)", mask)
            out.append(fit)
        return out

    @staticmethod
    def _bias_step(run: dict, own: np.ndarray, iteration: int, lower: np.ndarray, upper: np.ndarray) -> None:
        """One iteration of :meth:`fit`'s bias correction of one fit (``run``, updated in place) given
        its model's own bias ``own`` at its current values."""
        rec, offset, x = run["rec"], run["offset"], run["x"]
        change = np.abs(own[rec] - offset[rec]) / run["sigma"]
        finite = change[np.isfinite(change)]
        settled = not finite.size or float(np.sqrt(np.mean(finite**2))) <= BIAS_TOLERANCE
        # a model whose response over a record shows no weave the record fit finds (NaN) cannot
        # predict that record; where that holds for most of the records fitted, the fit has left
        # the models that predict records at all and no bias correction brings it back
        lost = np.count_nonzero(~np.isfinite(own[rec])) > rec.size / 2
        if settled or lost or x.size == 0 or iteration == MAX_BIAS_ITERATIONS:
            # a record over which the fitted model's response shows no weave the record fit finds keeps
            # its last bias (its prediction the model's weave eigenvalue plus that bias, as the fit itself
            # used it), not NaN, which counted as a point no model predicts (SBW logs with
            # SbwBenchmark.txt: four such records put every candidate's held-out error in the hundreds)
            run["offset"], run["done"] = np.where(np.isfinite(own), own, offset), True
            return
        # the fit's residuals move by the change of the bias (records without a weave keep their
        # last one): a Gauss-Newton step follows them, shortened where it would move a value by more
        # than a fifth of its search range (a direction the data hardly determine)
        mask, J, weight = run["mask"], run["fit"]._jacobian, run["fit"]._weight
        own = np.where(np.isfinite(own), own, offset)
        # a change is known only where both biases are (a record whose weave the nominal model's response
        # did not show has no first bias: its residual gets no push from this step)
        change = np.where(np.isfinite(own) & np.isfinite(offset), own - offset, 0.0)
        delta = np.zeros(J.shape[0])
        delta[: int(mask.sum())] = change[mask] / weight
        step = -np.linalg.lstsq(J, delta, rcond=1e-6)[0]
        if not np.all(np.isfinite(step)):  # no step to take: the fit stays where it is
            run["offset"], run["done"] = own, True
            return
        step *= min(1.0, float(np.min(MAX_BIAS_STEP * (upper - lower) / np.maximum(np.abs(step), 1e-300))))
        run["x"] = np.clip(x + step, lower, upper)
        run["offset"] = own

    def own_bias(self, lay: _Layout, x: np.ndarray) -> np.ndarray:
        """A fitted model's own extraction bias at every observation: its apparent eigenvalue (indirect
        inference) minus its weave eigenvalue on the rows fitted from records, 0 elsewhere.

        ``x`` one parameter vector ``(p,)`` (returns ``(n_obs,)``) or several ``(P, p)`` (returns
        ``(P, n_obs)``, their records simulated and refitted in one batch)."""
        x = np.asarray(x, dtype=float)
        X = np.atleast_2d(x) if np.size(x) else np.zeros((max(x.shape[0], 1) if x.ndim == 2 else 1, 0))
        own = self.predict_batch(lay, X, indirect=True) - self.predict_batch(lay, X, indirect=False)
        return own if x.ndim == 2 else own[0]

    def _weights(self, lay: _Layout, mask: np.ndarray) -> np.ndarray:
        """The residuals' scale: data uncertainty with ``parameters`` (it moves them), else combined."""
        weight = np.sqrt(self.var_data if lay.n_shift else self.var_total)
        return np.where(weight > 0, weight, np.sqrt(self.var_total))[mask]

    def _residuals_batch(
        self, lay: _Layout, mask: np.ndarray, X: np.ndarray, offset: np.ndarray | None, predict=None
    ) -> np.ndarray:
        """Weighted residuals ``(P, m)`` of parameter vectors ``X``: weave eigenvalues plus ``offset``
        against the observations in ``mask``, then the prior residuals of any parameter shifts.
        ``predict(X)``: the predictions (default ``predict_batch(lay, X, indirect=False)``)."""
        pred = (self.predict_batch(lay, X, indirect=False) if predict is None else predict(X))[:, mask]
        if offset is not None:
            pred = pred + np.asarray(offset, dtype=float)[mask]
        r = (pred - self.y[mask]) / self._weights(lay, mask)
        r = np.where(np.isfinite(r), r, _BAD)
        if lay.n_shift:
            r = np.concatenate([r, X[:, len(lay.structural) :]], axis=1)
        return r

    def _residuals(self, lay: _Layout, mask: np.ndarray, x: np.ndarray, offset: np.ndarray | None) -> np.ndarray:
        X = np.atleast_2d(np.asarray(x, dtype=float)) if np.size(x) else np.zeros((1, 0))
        return self._residuals_batch(lay, mask, X, offset)[0]

    def _fit_together(
        self, effects: tuple[str, ...], masks: list, start: np.ndarray | None, offsets: list
    ) -> list[EffectFit]:
        """``[_fit(effects, mask, start, offset) ...]``, the fits run side by side (one thread each, in
        lockstep), their model evaluations made together (:class:`_Together`): the same fits, far
        fewer batched model calls (whose cost is mostly fixed per call)."""
        if len(masks) < 2:
            return [self._fit(effects, mask, start, offset) for mask, offset in zip(masks, offsets)]
        together = _Together(self, self.layout(effects), len(masks))
        out: list = [None] * len(masks)
        errors: list = [None] * len(masks)

        def run(k: int) -> None:
            try:
                out[k] = self._fit(effects, masks[k], start, offsets[k], lambda X: together.predict(k, X))
            except BaseException as exc:  # handed to the caller below
                errors[k] = exc
            finally:
                together.finished()

        # each thread in a copy of this one's context (NumPy's error state included)
        threads = [
            threading.Thread(target=contextvars.copy_context().run, args=(run, k), daemon=True)
            for k in range(len(masks))
        ]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        for exc in errors:
            if exc is not None:
                raise exc
        return out

    def _fit(
        self,
        effects: tuple[str, ...],
        mask: np.ndarray | None,
        start: np.ndarray | None,
        offset: np.ndarray | None,
        predict=None,
    ) -> EffectFit:
        """One least-squares fit; each model's predictions are its weave eigenvalues plus ``offset``.

        The result keeps the weighted Jacobian at the solution (``_jacobian``) and the weights
        (``_weight``), for the iterated bias correction.  ``predict``: as for :meth:`_residuals_batch`.
        """

        mask = np.ones(len(self.obs), bool) if mask is None else np.asarray(mask, bool)
        lay = self.layout(tuple(effects))
        n_struct = len(lay.structural)
        p = n_struct + lay.n_shift

        def residuals_batch(X: np.ndarray) -> np.ndarray:
            return self._residuals_batch(lay, mask, X, offset, predict)

        if p == 0:
            r = residuals_batch(np.zeros((1, 0)))[0]
            out = self._result(lay, np.zeros(0), np.zeros(0), r, int(mask.sum()), True, "nothing to fit")
            out._jacobian, out._weight, out._quantile = np.zeros((r.size, 0)), self._weights(lay, mask), 1.96
            return out
        lower, upper = self.bounds(lay)
        if start is not None and np.size(start) == p:
            starts = np.array([np.asarray(start, dtype=float)])
        else:
            starts = np.array([list(s) + [0.0] * lay.n_shift for s in lay.starts])
        # a start on a bound (0 is the first start of most sizes) is moved just inside: SciPy's "trf" scales
        # a step by the distance to the bound (Coleman-Li), so from x = lower it cannot leave the bound and
        # stops there (a steer stiffness of 1.5 N m/rad was fitted as 0 with chi-square 166 against 9.6)
        span = upper - lower
        margin = np.where(np.isfinite(span), START_MARGIN * span, 0.0)
        starts = np.clip(starts, lower + margin, upper - margin)
        costs = np.sum(residuals_batch(starts) ** 2, axis=1)
        x0 = starts[int(np.argmin(costs))]
        scale, steps = _scale_and_steps(lay)

        def jac(x: np.ndarray) -> np.ndarray:
            return self._jacobian(lay, mask, x, steps, upper, offset, residuals_batch)

        def fun(x: np.ndarray) -> np.ndarray:
            return residuals_batch(x[None, :])[0]

        result = least_squares(
            fun,
            x0,
            jac=jac,
            bounds=(lower, upper),
            x_scale=np.where(scale > 0, scale, 1.0) * 0.1,
            method="trf",
            max_nfev=50 * p,
            ftol=1e-6,
            xtol=1e-6,
            gtol=1e-8,
        )
        return self._finish(lay, mask, result.x, result.fun, jac(result.x), bool(result.success), result.message)

    def _finish(
        self, lay: _Layout, mask: np.ndarray, x: np.ndarray, r: np.ndarray, J: np.ndarray, ok: bool, message: str
    ) -> EffectFit:
        """The :class:`EffectFit` of a least-squares fit ending at ``x``, residuals ``r``, Jacobian ``J``:
        standard errors from ``J`` scaled by the residuals (:func:`scale_and_quantile`), and what the
        iterated bias correction needs (the Jacobian and the weights)."""
        p = x.size
        factor, quantile = scale_and_quantile(float(np.sum(r**2)), r.size, p)
        cov = None
        try:
            cov = np.linalg.pinv(J.T @ J) * factor
            stderr = np.sqrt(np.clip(np.diag(cov), 0, None))
            insensitive = ~np.any(J != 0, axis=0)
            stderr = np.where(insensitive, np.inf, stderr)
        except np.linalg.LinAlgError:
            stderr = np.full(p, np.inf)
        out = self._result(lay, x, stderr, r, int(mask.sum()), ok, message, quantile)
        out._jacobian, out._weight, out.covariance, out._quantile = J, self._weights(lay, mask), cov, quantile
        return out

    def fit_at(
        self, effects: tuple[str, ...], x: np.ndarray, bias: np.ndarray, message: str, mask: np.ndarray | None = None
    ) -> EffectFit:
        """The fit held at values ``x`` (no search) with the extraction bias ``bias`` (its model's own), to
        the observations in ``mask`` (all by default): residuals, standard errors and Jacobian there, as
        :meth:`fit` reports its end point."""
        lay = self.layout(tuple(effects))
        mask = np.ones(len(self.obs), bool) if mask is None else np.asarray(mask, bool)
        x = np.asarray(x, dtype=float)
        lower, upper = self.bounds(lay)
        _, steps = _scale_and_steps(lay)
        J = self._jacobian(lay, mask, x, steps, upper, bias, lambda X: self._residuals_batch(lay, mask, X, bias))
        out = self._finish(lay, mask, x, self._residuals(lay, mask, x, bias), J, True, message)
        out.bias, out.bias_iterations = np.asarray(bias, dtype=float), 0
        return out

    def _jacobian(
        self,
        lay: _Layout,
        mask: np.ndarray,
        x: np.ndarray,
        steps: np.ndarray,
        upper: np.ndarray,
        offset: np.ndarray | None,
        residuals_batch,
    ) -> np.ndarray:
        """The weighted residuals' Jacobian at ``x`` of a fit of weave eigenvalues plus ``offset``: by
        eigenvalue perturbation where it holds (:meth:`_perturbation_jacobian`), else by forward differences
        of ``residuals_batch``."""
        J = self._perturbation_jacobian(lay, mask, x, steps, upper, offset) if self._perturbable(lay) else None
        return forward_jacobian(residuals_batch, x, steps, upper) if J is None else J

    def _perturbable(self, lay: _Layout) -> bool:
        """Whether a fit of ``lay`` takes its Jacobian by eigenvalue perturbation
        (:meth:`_perturbation_jacobian`): observations that are all eigenvalues, no speed sensor (its
        scale moves the speeds, not the state matrix) and a model of more than four states (for four,
        the closed-form quartic already makes differencing the eigenvalues cheap)."""
        if len(self.predictor.canonical) or len(self.predictor.frf) or not len(self.eigen):
            return False
        if any(name == SPEED_SENSOR for name, _ in lay.structural):
            return False
        return any(EFFECTS[e].adds_tyres or EFFECTS[e].adds_lean for e in lay.effects if e in EFFECTS)

    def _perturbation_jacobian(
        self,
        lay: _Layout,
        mask: np.ndarray,
        x: np.ndarray,
        steps: np.ndarray,
        upper: np.ndarray,
        offset: np.ndarray | None,
    ) -> np.ndarray | None:
        """The weighted residuals' Jacobian at ``x``, as :func:`~bikerider.gap.inference.differences.
        forward_jacobian` takes it (the same steps, backwards at the upper bound), but with the matched
        eigenvalues' derivatives from one eigendecomposition per row
        (:meth:`~bikerider.gap.inference.predict.Predictor.eigen_derivatives`) instead of one per row
        and parameter: for a model with tyres (eight states) most of a fit's time.  ``None`` where that
        does not hold (the caller then differences the eigenvalues)."""
        h = steps * np.where(x + steps <= upper, 1.0, -1.0)
        X = np.vstack([x, x + np.diag(h)])
        values, config, scale = self.configure(lay, X)
        if scale is not None:
            return None
        try:
            with np.errstate(all="ignore"):
                d = self.predictor.eigen_derivatives(EffectModel(values, self.geometry, config), h)
        except np.linalg.LinAlgError:
            return None
        if d is None:
            return None
        J = (d[:, mask] / self._weights(lay, mask)).T  # (m, p)
        known = np.isfinite(self.y[mask])  # a residual that is not a number is held at _BAD: no slope
        if offset is not None:
            known &= np.isfinite(np.asarray(offset, dtype=float)[mask])
        J[~known] = 0.0
        if lay.n_shift:  # the prior residuals are the shifts themselves
            n_struct = len(lay.structural)
            prior = np.zeros((lay.n_shift, X.shape[1]))
            prior[:, n_struct:] = np.eye(lay.n_shift)
            J = np.vstack([J, prior])
        return J

    def _result(
        self,
        lay: _Layout,
        x: np.ndarray,
        stderr: np.ndarray,
        r: np.ndarray,
        n: int,
        ok: bool,
        message: str,
        quantile: float = 1.96,
    ) -> EffectFit:
        """The :class:`EffectFit` of values ``x`` with residuals ``r``; 95 % intervals ``x +- quantile
        stderr`` (:func:`scale_and_quantile`), clipped to the bounds."""
        n_struct = len(lay.structural)
        names = [f"{param}" for _, param in lay.structural] + [f"parameters.{k}" for k in self.free][: lay.n_shift]
        units = list(lay.units) + ["sigma"] * lay.n_shift
        values, config, scale = self.configure(lay, x[None, :] if x.size else np.zeros((1, 0)))
        config_out = {
            e: {k: float(np.asarray(v).ravel()[0]) for k, v in params.items()} for e, params in config.items()
        }
        if scale is not None:
            config_out[SPEED_SENSOR] = {"speed_scale": float(np.asarray(scale).ravel()[0])}
        shift = {}
        if lay.n_shift:
            for j, name in enumerate(self.free):
                shift[name] = float(x[n_struct + j] * self.free_sigma[j])
        lo, hi = self.bounds(lay)
        ci_low = np.clip(x - quantile * stderr, lo, hi) if x.size else x
        ci_high = np.clip(x + quantile * stderr, lo, hi) if x.size else x
        data_r = r[:n]
        prior = r[n:] if lay.n_shift else np.zeros(0)
        return EffectFit(
            effects=tuple(lay.effects),
            names=names,
            units=units,
            values=x,
            stderr=stderr,
            ci_low=ci_low,
            ci_high=ci_high,
            config=config_out,
            shift=shift,
            chi2=float(np.sum(data_r**2)),
            prior_chi2=float(np.sum(prior**2)),
            n=n,
            success=ok,
            message=str(message),
            lower=lo,
            upper=hi,
        )

    def fit_apparent(
        self, fit: EffectFit, max_iterations: int = APPARENT_ITERATIONS, starts: int = MINIMUM_STARTS
    ) -> EffectFit:
        """The least squares of the apparent eigenvalues (indirect inference), polishing a fit of
        :meth:`fit` to all the observations, and its other local minima.

        The iterated bias correction of :meth:`fit` solves ``A^T W (apparent(x) - y) = 0`` with the weave
        eigenvalues' slopes ``A`` (the bias's own change left out), in at most
        :data:`MAX_BIAS_ITERATIONS` steps of at most :data:`MAX_BIAS_STEP` of a range; where the
        apparent eigenvalues' slopes differ from the weave's in direction (several sizes, e.g. the
        tyres' cornering stiffness against their relaxation length), that root lies far from the least
        squares of the apparent eigenvalues, or is not reached (a 3-s record set with tyre slip:
        chi-square 8.3 at c_alpha 6.7, 2.6 at the least squares' 8.8, hidden 10.6).  This makes
        Gauss-Newton steps on the apparent eigenvalues themselves (their slopes by a batched forward
        difference; a step clipped to the bounds and halved while it does not lower the chi-square), from
        the bias-corrected values, at most ``max_iterations`` of them.

        Other minima.  The apparent eigenvalues' chi-square can have two minima of nearly equal depth
        (tyre slip on a 3-s record set with the rider: 3.85 at c_alpha 7.6 /rad, sigma_t 0.41 m and 4.10
        at 12.2, 0.108, hidden 13.5, 0.097), and an interval linearised about one cannot hold the other.
        So the same steps run, side by side in the same batched model calls, from further points (at most
        :data:`MINIMUM_ITERATIONS` steps each; :meth:`_further_starts`, from ``starts`` grid starts; none
        with ``starts = 0``); a further search that comes within the linearised reach of a lower one
        (``|J dx|^2 < 1``) stops and follows it.  A search
        that stops because a step gains less than :data:`APPARENT_TOLERANCE`, or because the Gauss-Newton
        step at its point would gain less than :data:`MINIMUM_DECREMENT`, has found a local minimum.
        The lowest point found is the fit; another minimum is kept (``EffectFit.minima``) when it is
        distinct from the fit: its linearised chi-square distance from the fit exceeds one and the
        chi-square halfway between them rises above both (a ridge between two valleys, not two points of
        one valley; a Gauss-Newton search creeping along a long curved valley stops where a step gains
        little, which is not a minimum: on the set above the searches stopped at chi-square 3.85, 4.10,
        3.41 and 3.19, all in one valley).  Every point the searches stepped to is kept as well
        (``EffectFit.visited``).  :func:`bikerider.gap.diagnosis.fits.with_parameter_uncertainty` makes
        each size's 95 % interval hold every kept minimum and every point visited within the 95 %
        profile-likelihood threshold.

        Without records, or with nothing fitted, or for sets holding ``parameters`` (20-odd shifts), the
        fit is returned unchanged; with the polish gaining nothing and no lower minimum, the values are
        the bias-corrected ones.
        """
        if self.records is None or not len(self.record_obs) or not np.size(fit.values) or PARAMETERS in fit.effects:
            return fit
        lay = self.layout(fit.effects)
        mask = np.ones(len(self.obs), bool)
        n_struct = len(lay.structural)
        p = n_struct + lay.n_shift
        lower, upper = self.bounds(lay)
        _, steps = _scale_and_steps(lay)
        residuals_batch = self._apparent_residuals(lay)

        began = time.perf_counter()
        X = np.array([np.asarray(fit.values, float)] + self._further_starts(lay, fit, starts))
        limit = np.array([max_iterations] + [max(MINIMUM_ITERATIONS, max_iterations)] * (len(X) - 1))
        R = residuals_batch(X)
        cost = np.sum(R**2, axis=1)
        start_cost = float(cost[0])
        J = np.zeros((len(X), R.shape[1], p))
        active = np.ones(len(X), bool)
        converged = np.zeros(len(X), bool)
        done = np.zeros(len(X), int)
        visited = [(x.copy(), float(c)) for x, c in zip(X, cost)]
        while active.any():
            idx = np.flatnonzero(active)
            # every active search's slopes in one batched call (forward differences, backwards at the upper
            # bound), then its Gauss-Newton step
            H = [steps * np.where(X[s] + steps <= upper, 1.0, -1.0) for s in idx]
            stack = residuals_batch(np.vstack([np.vstack([X[s], X[s] + np.diag(h)]) for s, h in zip(idx, H)]))
            step = {}
            for k, (s, h) in enumerate(zip(idx, H)):
                block = stack[k * (p + 1) : (k + 1) * (p + 1)]
                J[s] = ((block[1:] - block[0]) / h[:, None]).T
                step[s] = -np.linalg.lstsq(J[s], R[s], rcond=1e-10)[0]
            # halved while it does not lower the chi-square, the trial points of every search in one call
            pending, accepted = list(idx), {}
            for _halving in range(3):
                if not pending:
                    break
                T = np.array([np.clip(X[s] + step[s], lower, upper) for s in pending])
                RT = residuals_batch(T)
                still = []
                for s, t, rt in zip(pending, T, RT):
                    if float(rt @ rt) < cost[s]:
                        accepted[s] = (t, rt)
                    else:
                        step[s] = step[s] / 2
                        still.append(s)
                pending = still
            for s in idx:
                done[s] += 1
                # a further search that has come within the linearised reach of a lower one follows it
                near = [k for k in range(len(X)) if k != s and cost[k] <= cost[s] and k in step]
                if s and any(float(np.sum((J[k] @ (X[s] - X[k])) ** 2)) < 1.0 for k in near):
                    active[s] = False
                    continue
                if s not in accepted:
                    # no step gains: a minimum when the full Gauss-Newton step (clipped) would gain little
                    move = np.clip(X[s] - np.linalg.lstsq(J[s], R[s], rcond=1e-10)[0], lower, upper) - X[s]
                    predicted = R[s] + J[s] @ move
                    converged[s] = cost[s] - float(predicted @ predicted) < MINIMUM_DECREMENT
                    active[s] = False
                    continue
                t, rt = accepted[s]
                gain = cost[s] - float(rt @ rt)
                visited.append((t.copy(), float(rt @ rt)))
                X[s], R[s], cost[s] = t, rt, float(rt @ rt)
                if gain < APPARENT_TOLERANCE:
                    converged[s], active[s] = True, False
                elif done[s] >= limit[s]:
                    active[s] = False
        best = int(np.argmin(cost))
        LOG.debug(
            "%s: searches from %d starts (%d steps, %.2f s) end at %s (chi-square %s, converged %s)",
            "+".join(fit.effects),
            len(X),
            int(done.sum()),
            time.perf_counter() - began,
            np.array2string(X, precision=4),
            np.array2string(cost, precision=3),
            converged,
        )
        minima = self._distinct_minima(residuals_batch, X, cost, J, converged, best)
        if best == 0 and not cost[0] < start_cost:
            return replace(fit, minima=minima, visited=visited)
        x = X[best]
        own = self.own_bias(lay, x)
        r = self._residuals(lay, mask, x, own)
        message = "least squares of the apparent eigenvalues" + ("" if best == 0 else " (from a further start)")
        out = self._result(lay, x, fit.stderr, r, int(mask.sum()), fit.success, message)
        out.bias, out.bias_iterations, out.minima, out.visited = own, fit.bias_iterations, minima, visited
        return out

    def _apparent_residuals(self, lay: _Layout):
        """The weighted residuals ``(P, m)`` of parameter vectors ``(P, p)`` that :meth:`fit_apparent` minimises:
        the apparent eigenvalues (indirect inference) against every observation, then any prior residuals."""
        weight = self._weights(lay, np.ones(len(self.obs), bool))
        n_struct = len(lay.structural)

        def residuals_batch(X: np.ndarray) -> np.ndarray:
            r = (self.predict_batch(lay, X, indirect=True) - self.y) / weight
            r = np.where(np.isfinite(r), r, _BAD)
            return np.concatenate([r, X[:, n_struct:]], axis=1) if lay.n_shift else r

        return residuals_batch

    def profile_apparent(self, fit: EffectFit, targets: np.ndarray, curvature: np.ndarray | None = None) -> Profile:
        """Profile-likelihood intervals of a fit of :meth:`fit_apparent`: for each size ``k``, where the
        profile chi-square ``min over the other sizes of chi2(x_k, others)`` rises ``targets[k]`` above the
        fit's, on each side (a size with a target that is not finite and positive is not profiled).

        The chi-square is the apparent eigenvalues' least squares the fit minimised.  Each size is stepped
        outward from the fit on each side; at each profile point the other sizes are re-minimised by
        Gauss-Newton steps (at most :data:`PROFILE_STEPS`, until a step would gain less than
        :data:`PROFILE_GAIN`; clipped to the bounds; a step that does not lower the chi-square is halved), warm
        started from the previous profile point moved along the profile's own direction there.  The first
        step is the linearised crossing (``sqrt(target B_kk)``, ``B = curvature``, the inverse of the
        chi-square's Gauss-Newton curvature at the fit: ``(A^T A)^-1``; by default from the fit's slopes);
        the next ones are secants in the square root of the chi-square's rise (linear in the size where the
        chi-square is quadratic), extrapolated until the target is passed, then within the bracket.  An end is
        a point whose rise lies within :data:`PROFILE_TOLERANCE` of the target, a bound of the search reached
        below it, or, after :data:`PROFILE_POINTS` points, the last point below it (the interval taken from
        inside).  Every branch (size and side) advances in the same batched model call: the point and its
        forward differences for all branches at once.
        """
        began = time.perf_counter()
        lay = self.layout(fit.effects)
        residuals_batch = self._apparent_residuals(lay)
        lower, upper = self.bounds(lay)
        x0 = np.asarray(fit.values, float)
        p = x0.size
        _, steps = _scale_and_steps(lay)
        targets = np.asarray(targets, float)
        out = Profile(np.full(p, np.nan), np.full(p, np.nan), np.full(p, np.nan), np.full(p, np.nan))

        def differences(x: np.ndarray) -> np.ndarray:
            h = steps * np.where(x + steps <= upper, 1.0, -1.0)
            return np.vstack([x, x + np.diag(h)]), h

        R0 = residuals_batch(differences(x0)[0])
        out.calls = 1
        h0 = differences(x0)[1]
        J0 = ((R0[1:] - R0[0]) / h0[:, None]).T
        cost0 = float(R0[0] @ R0[0])
        B = np.linalg.pinv(J0.T @ J0) if curvature is None else np.asarray(curvature, float)

        def direction(J: np.ndarray, k: int) -> np.ndarray:
            """How the other sizes' minimum moves per unit of size ``k`` (the profile's direction)."""
            others = [j for j in range(p) if j != k]
            d = np.zeros(p)
            d[k] = 1.0
            if others:
                d[others] = -np.linalg.lstsq(J[:, others], J[:, k], rcond=1e-10)[0]
            return d

        branches = []
        for k in range(p):
            if not (np.isfinite(targets[k]) and targets[k] > 0 and np.isfinite(B[k, k]) and B[k, k] > 0):
                continue
            d0 = direction(J0, k)
            for side in (-1.0, 1.0):
                b = {"k": k, "side": side, "inside": [(0.0, 0.0, x0.copy(), d0)], "outside": None, "points": 0}
                b["root"] = math.sqrt(targets[k])
                self._profile_next(b, x0, math.sqrt(targets[k] * B[k, k]), lower, upper, out, cost0)
                branches.append(b)
        while True:
            active = [b for b in branches if not b.get("done")]
            if not active:
                break
            stacks = [differences(b["x"]) for b in active]
            R = residuals_batch(np.vstack([X for X, _h in stacks]))
            out.calls += 1
            for i, (b, (_X, h)) in enumerate(zip(active, stacks)):
                block = R[i * (p + 1) : (i + 1) * (p + 1)]
                r, k = block[0], b["k"]
                J = ((block[1:] - r) / h[:, None]).T
                c = float(r @ r)
                if b["trial"] and not c < b["best"][1]:  # the step did not lower the chi-square: halved
                    b["halvings"] += 1
                    if b["halvings"] <= 2:
                        b["x"] = b["best"][0] + 0.5 * (b["x"] - b["best"][0])
                        continue
                else:
                    b["best"] = (b["x"].copy(), c, r, J)
                x, c, r, J = b["best"]
                others = [j for j in range(p) if j != k]
                gain = 0.0
                if others and b["halvings"] <= 2:
                    step = np.zeros(p)
                    step[others] = -np.linalg.lstsq(J[:, others], r, rcond=1e-10)[0]
                    move = np.clip(x + step, lower, upper) - x
                    predicted = r + J @ move
                    gain = c - float(predicted @ predicted)
                if gain >= PROFILE_GAIN and b["steps"] < PROFILE_STEPS:
                    b["x"], b["trial"], b["steps"], b["halvings"] = x + move, True, b["steps"] + 1, 0
                    continue
                # the other sizes are at their minimum for this value of size k: a profile point
                out.points.append((x.copy(), c))
                self._profile_point(b, x, c - cost0, direction(J, k), x0, lower, upper, out, cost0)
        out.seconds = time.perf_counter() - began
        LOG.debug(
            "%s: profile of %d branches in %d calls (%.2f s): %s .. %s",
            "+".join(fit.effects),
            len(branches),
            out.calls,
            out.seconds,
            out.low,
            out.high,
        )
        return out

    @staticmethod
    def _profile_point(
        b: dict, x: np.ndarray, rise: float, d: np.ndarray, x0: np.ndarray, lower, upper, out: Profile, cost0: float
    ) -> None:
        """A branch of :meth:`profile_apparent` has reached a profile point (values ``x``, the chi-square's rise
        ``rise`` above the fit's, the profile's direction ``d`` there): an end, or the next value of its size."""
        k, side = b["k"], b["side"]
        distance = side * (x[k] - x0[k])
        u = math.sqrt(max(rise, 0.0))
        b["points"] += 1
        root = b["root"]
        bound = upper[k] if side > 0 else lower[k]
        if abs(rise - root**2) <= PROFILE_TOLERANCE:
            GapProblem._profile_end(b, x[k], rise, out, cost0)
            return
        if rise < root**2:
            b["inside"].append((distance, u, x.copy(), d))
            if abs(x[k] - bound) <= 1e-12 * max(abs(bound), 1.0) or b["points"] >= PROFILE_POINTS:
                GapProblem._profile_end(b, x[k], rise, out, cost0)
                return
        else:
            b["outside"] = (distance, u)
            if b["points"] >= PROFILE_POINTS:  # the last point below the target: the interval from inside
                d_in, _u, x_in, _d = b["inside"][-1]
                GapProblem._profile_end(b, x_in[k], None, out, cost0)
                return
        (d1, u1, _x1, _), (d2, u2, x2, dir2) = (
            (b["inside"][-2] if len(b["inside"]) > 1 else b["inside"][0]),
            b["inside"][-1],
        )
        if b["outside"] is None:  # extrapolated: the secant in the square root of the rise, at most 4 times as far
            new = d2 + (root - u2) * (d2 - d1) / (u2 - u1) if u2 > u1 and d2 > d1 else 2.0 * d2
            new = min(max(new, 1.1 * d2), 4.0 * d2)
        else:  # within the bracket: the secant, kept a tenth of the bracket inside it
            d_out, u_out = b["outside"]
            new = d2 + (root - u2) * (d_out - d2) / (u_out - u2) if u_out > u2 else 0.5 * (d2 + d_out)
            new = min(max(new, d2 + 0.1 * (d_out - d2)), d_out - 0.1 * (d_out - d2))
        GapProblem._profile_next(b, x2, new - d2, lower, upper, out, cost0, dir2)

    @staticmethod
    def _profile_next(b: dict, start: np.ndarray, step: float, lower, upper, out, cost0, d=None) -> None:
        """Start a branch's next profile point ``step`` further out from ``start`` (a profile point), the other
        sizes moved along the profile's direction ``d`` there (the branch's first direction by default)."""
        k, side = b["k"], b["side"]
        d = b["inside"][0][3] if d is None else d
        bound = upper[k] if side > 0 else lower[k]
        t = float(np.clip(start[k] + side * step, lower[k], upper[k]))
        if abs(t - start[k]) <= 1e-12 * max(abs(start[k]), 1.0):  # already on the bound: the interval ends there
            GapProblem._profile_end(b, bound, None, out, cost0)
            return
        x = np.clip(start + (t - start[k]) * d, lower, upper)
        x[k] = t
        b.update(x=x, trial=False, steps=0, halvings=0, best=(x, math.inf, None, None))

    @staticmethod
    def _profile_end(b: dict, value: float, rise: float | None, out: Profile, cost0: float) -> None:
        k = b["k"]
        chi2 = math.nan if rise is None else cost0 + rise
        if b["side"] > 0:
            out.high[k], out.chi2_high[k] = value, chi2
        else:
            out.low[k], out.chi2_low[k] = value, chi2
        b["done"] = True

    def _further_starts(self, lay: _Layout, fit: EffectFit, count: int) -> list[np.ndarray]:
        """Starts of :meth:`fit_apparent`'s search for other minima, found cheaply.

        From each of the ``count`` grid starts of :meth:`fit` (moved inside the bounds as there) with the
        lowest cheap chi-square, a least squares of the cheap model: the weave eigenvalues plus the fit's
        own extraction bias held (the model the iterated bias correction fits; no record is simulated).
        Its minima distinct from the fit's values and from one another (linearised chi-square distance
        above one, in the cheap model's slopes at the fit) are the starts, and the grid start with the
        lowest cheap chi-square itself when distinct as well (the cheap model is the apparent eigenvalues'
        only near the fit: on tyre-slip record sets its minima all lay in the fit's valley, and the
        searches from grid starts found the lower points).  The search on the apparent eigenvalues
        themselves runs only from these."""
        if count <= 0 or lay.n_shift or not lay.starts or len(lay.starts[0]) != len(lay.structural):
            return []
        lower, upper = self.bounds(lay)
        span = upper - lower
        margin = np.where(np.isfinite(span), START_MARGIN * span, 0.0)
        grid = np.clip(np.array([list(s) for s in lay.starts], dtype=float), lower + margin, upper - margin)
        mask = np.ones(len(self.obs), bool)
        offset = self.nominal_bias if fit.bias is None else fit.bias

        def residuals_batch(X: np.ndarray) -> np.ndarray:
            return self._residuals_batch(lay, mask, X, offset)

        scale = np.array([max(hi - lo, 1e-6) for lo, hi in zip(lay.lower, lay.upper)])
        steps = 1e-5 * np.minimum(scale, 10.0)

        def jac(x: np.ndarray) -> np.ndarray:
            return forward_jacobian(residuals_batch, x, steps, upper)

        x0 = np.asarray(fit.values, float)
        J0 = jac(x0)
        found = [x0]
        grid_cost = np.sum(residuals_batch(grid) ** 2, axis=1)  # the cheap chi-square of every grid start
        for i in np.argsort(grid_cost, kind="stable")[:count]:
            result = least_squares(
                lambda x: residuals_batch(x[None, :])[0],
                grid[i],
                jac=jac,
                bounds=(lower, upper),
                x_scale=scale * 0.1,
                method="trf",
                max_nfev=20 * x0.size,
                ftol=1e-6,
                xtol=1e-6,
            )
            if all(float(np.sum((J0 @ (result.x - f)) ** 2)) > 1.0 for f in found):
                found.append(result.x)
        # and the grid start the cheap model likes best itself: the cheap model is the apparent eigenvalues'
        # only near the fit, and a minimum it does not have can be reached from there
        best = grid[int(np.argmin(grid_cost))]
        if all(float(np.sum((J0 @ (best - f)) ** 2)) > 1.0 for f in found):
            found.append(best)
        return found[1:]

    @staticmethod
    def _distinct_minima(
        residuals_batch, X: np.ndarray, cost: np.ndarray, J: np.ndarray, converged: np.ndarray, best: int
    ) -> list[tuple[np.ndarray, float]]:
        """The local minima found besides the best (``X[best]``), each once, lowest chi-square first.

        A converged search's point is another minimum when its linearised chi-square distance from the
        best (``|J_best dx|^2``, the best's slopes) and from every minimum kept exceeds one, and the
        chi-square halfway to the best rises above both ends (a ridge between them)."""
        others = [s for s in np.argsort(cost, kind="stable") if s != best and converged[s]]
        kept: list[int] = []
        for s in others:
            if all(float(np.sum((J[best] @ (X[s] - X[k])) ** 2)) > 1.0 for k in [best, *kept]):
                kept.append(s)
        if not kept:
            return []
        halfway = residuals_batch(np.array([(X[s] + X[best]) / 2 for s in kept]))
        ridge = np.sum(halfway**2, axis=1)
        return [(X[s].copy(), float(cost[s])) for s, c in zip(kept, ridge) if c > max(cost[s], cost[best])]

    def predict_fit(self, fit: EffectFit) -> np.ndarray:
        """Predictions of every observation with a fitted set of effects.

        The rows fitted from records by indirect inference: the fitted model's weave eigenvalues plus
        its own extraction bias, which :meth:`fit` computed at the fitted values for every record
        (held out or not), so no record is simulated again.
        """
        lay = self.layout(fit.effects)
        if fit.bias is None:
            return self.predict_batch(lay, fit.values[None, :])[0]
        return self.predict_batch(lay, fit.values[None, :], indirect=False)[0] + fit.bias

    def fitted_model(self, fit: EffectFit) -> EffectModel:
        """The :class:`EffectModel` of a fit (nominal parameters plus any fitted shift; no speed scale)."""
        values = dict(self.nominal)
        for name, delta in fit.shift.items():
            values[name] = self.nominal[name] + delta
        return EffectModel(values, self.geometry, {e: p for e, p in fit.config.items() if e not in OBSERVATION_EFFECTS})


def _scale_and_steps(lay: _Layout) -> tuple[np.ndarray, np.ndarray]:
    """A layout's values' search ranges (1 for the parameters' shifts, in sigmas) and the forward-difference
    steps of its fits' Jacobians (1e-5 of a range, at most 1e-4; 1e-3 sigma for a shift)."""
    scale = np.array([max(hi - lo, 1e-6) for lo, hi in zip(lay.lower, lay.upper)] + [1.0] * lay.n_shift)
    steps = np.concatenate([1e-5 * np.minimum(scale[: len(lay.structural)], 10.0), np.full(lay.n_shift, 1e-3)])
    return scale, steps


class _Together:
    """The model evaluations of several fits running in threads (:meth:`GapProblem._fit_together`), made
    together: a fit asking for predictions waits until every fit still running has asked, then the
    last to ask evaluates all of their parameter vectors in one :meth:`GapProblem.predict_batch` call.

    Each vector's predictions are computed as alone (the batched arithmetic is per vector), so every
    fit gets what it would get alone; where the joint call meets a singular model, each fit's vectors
    are evaluated on their own instead (a singular model makes NaN of its whole call).
    """

    def __init__(self, problem: GapProblem, lay: _Layout, count: int):
        self.problem, self.lay, self.running = problem, lay, count
        self.condition = threading.Condition()
        self.pending: dict[int, np.ndarray] = {}
        self.results: dict[int, np.ndarray | BaseException] = {}

    def predict(self, k: int, X: np.ndarray) -> np.ndarray:
        """Predictions ``(P, n_obs)`` of fit ``k``'s parameter vectors ``X``."""
        with self.condition:
            self.pending[k] = np.atleast_2d(np.asarray(X, dtype=float))
            self._evaluate()
            while k not in self.results:
                self.condition.wait()
            out = self.results.pop(k)
        if isinstance(out, BaseException):
            raise out
        return out

    def finished(self) -> None:
        """A fit is done (or failed): the others no longer wait for it."""
        with self.condition:
            self.running -= 1
            self._evaluate()

    def _evaluate(self) -> None:
        if not self.pending or len(self.pending) < self.running:
            return
        order = sorted(self.pending)
        p, lay = self.problem, self.lay
        try:
            try:
                rows = p.predict_batch(lay, np.concatenate([self.pending[k] for k in order]), False, strict=True)
                ends = np.cumsum([len(self.pending[k]) for k in order])
                for k, part in zip(order, np.split(rows, ends[:-1])):
                    self.results[k] = part
            except np.linalg.LinAlgError:  # a singular model: each fit's vectors alone, as without company
                for k in order:
                    self.results[k] = p.predict_batch(lay, self.pending[k], False)
        except BaseException as exc:  # every waiting fit gets it
            for k in order:
                self.results.setdefault(k, exc)
        self.pending.clear()
        self.condition.notify_all()


def structural_parameter_names(effect: str) -> tuple[str, ...]:
    """Every model parameter an effect sets (fitted and fixed)."""
    return STRUCTURAL_KEYS.get(effect, ())
