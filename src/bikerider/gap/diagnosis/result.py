"""Where, whether, which and how far: the sim-to-real gap diagnosis.

Where.  Every measured scalar's residual (measured minus nominal model) is divided by the combined
standard uncertainty of data and model parameters (:mod:`bikerider.gap.inference.problem`); residuals are
summarised in a gap map by mode (weave, capsize, castor, or identified canonical entries), speed
band and quantity (real part, imaginary part, entry), each cell with its chi-square and p-value.

Whether.  The whole gap is tested with the full covariance, ``chi2 = r^T (D + J J^T)^-1 r`` with
``n`` degrees of freedom, and against the data's noise alone, ``r^T D^-1 r``.  Not significant at
:data:`ALPHA` against either: verdict ``none``.  Significant against the data alone but within the
combined uncertainty: the parameters' uncertainty covers the gap, verdict ``parameters``.  Otherwise
the benchmark parameters are fitted with their uncertainties as a Gaussian prior (maximum a
posteriori); if the fitted model passes the same test (data plus prior chi-square, ``n`` degrees of
freedom) plausible parameter errors explain the gap (``parameters``), else it is ``structural``.
With verdict ``parameters`` the parameter fit is selected when it is plausible; when it needs
implausible shifts the candidates are compared as for a structural gap.

Which.  Folds are the data's groups (runs, riders, environments; more than :data:`~bikerider.gap.diagnosis.folds.MAX_FOLDS` groups
are held out in blocks of whole groups), or, for a single group, contiguous speed bands; never
random points.  Every candidate is fitted on the training folds and scored on
the held-out fold; the held-out error is the root mean square of the normalised residuals over all
held-out points.  Candidates are ranked by it; a candidate within :data:`TIE_RELATIVE` of a better
one, or not significantly better at :data:`TIE_P`, is
tied with it, and within a tie the candidate with fewer fitted parameters ranks first (Occam).
"Better" is a paired bootstrap of the held-out points' RMS error (:func:`significantly_better`).
Pairs are cross-validated as well (fitted jointly on the same folds): every pair of candidates that
each, alone, predict the held-out folds better than the nominal model (by more than 1 %; an effect that makes the
held-out predictions worse on its own is not searched further).

Usual, and priors.  Every fitted value of a candidate (fitted to all the data) has a usual range (the
literature's, or the bicycle's own ``[plausible]`` table) and a prior with its source
(:class:`bikerider.gap.candidates.effects.Prior`; the ``[plausible]`` range made a prior).  A value outside its usual
range is flagged ("above the usual ... from ...: check ..."), never refused: only what is physically
impossible (negative damping, mass, inertia) is a bound of the fit.  A value is usable when the data
determine it (its standard error no larger than the width of its usual range) and it is not pinned at the
edge of the search.  A candidate is ``plausible`` when every value is usual and usable; ``parameters`` when
its shifts pass their prior test (chi-square at 1 %) with none pinned at a bound.

Selection (structural verdict).  The evidence for a set of effects is its held-out log-likelihood,
``-sum(z^2) / (2 s^2)`` over the held-out points, plus the log prior ratio of its fitted values
(``ln p(value) - ln p(mode)``, :meth:`Diagnosis.log_prior`): roughly the log posterior odds against the
nominal model, whose evidence is ``-sum(z_nominal^2) / (2 s^2)``.  ``s^2`` is the lack of fit, the
smallest mean held-out ``z^2`` of any candidate or pair, at least 1 (:meth:`Diagnosis.lack_of_fit`).  A candidate is eligible when it beats the
nominal model significantly on the held-out folds, its log posterior odds against it are positive, and its
values are usable or it explains the held-out data to the noise floor (so "structural, selected nothing"
never stands beside a candidate at the noise floor).  The first eligible single of the ranking is
selected, unless another eligible single's evidence is higher by more than :data:`PRIOR_ODDS` (19 to 1).
A pair replaces it when the single leaves a gap above the noise floor (held-out RMS error against the
data's noise above one) and an eligible pair beats it significantly with more evidence.  The values
outside their usual range are flagged in the selection; the best held-out fit that is not selected is
named with what it needs (``best_implausible``).

How far.  For the selection, the held-out error before and after per fold and overall, and the
fraction of the gap above the noise floor removed: with ``G = mean(z^2) - 1`` (the noise floor of
normalised residuals is ``E[z^2] = 1``), ``shrink = (G_before - G_after) / G_before``.
"""

from __future__ import annotations

import itertools
import logging
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from bikerider import progress
from bikerider.errors import InputError
from bikerider.gap.blas_threads import single_blas_thread
from bikerider.gap.candidates.effect_model import BENCH_ARGS, EffectModel
from bikerider.gap.candidates.effects import (
    COULOMB_RANGE,
    EFFECT_NAMES,
    EFFECTS,
    LITERATURE_EXTRA,
    OBSERVATION_EFFECTS,
    TIME_DOMAIN_EFFECTS,
    EffectParameter,
    Prior,
    prior_from_range,
)
from bikerider.gap.candidates.nominal import GapModelInput
from bikerider.gap.diagnosis.folds import N_SPEED_BANDS, folds
from bikerider.gap.diagnosis.statistics import (
    ALPHA,
    _n_params,
    _named_values,
    at_noise_floor,
    gap_shrink,
    jackknife_quantile,
    rms,
    significantly_better,
)
from bikerider.gap.distributions import chi2
from bikerider.gap.inference.indirect import RecordRows, RecordSimulator
from bikerider.gap.inference.low_rank import low_rank_chi2
from bikerider.gap.inference.predict import Predictor
from bikerider.gap.inference.problem import EffectFit, GapProblem
from bikerider.gap.inference.timedomain import Layout, fit_time_domain
from bikerider.gap.measured.records import RecordFit, eigenvalues_of
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
from bikerider.gap.parallel import cross_validate_all

LOG = logging.getLogger(__name__)

MAX_SELECTED = 2
"""Most effects selected together (pairs are searched on the held-out folds)."""
TIME_DOMAIN_PARTNERS = ("steer_inertia", "steer_stiffness", "speed_sensor")
"""Linear candidates searched together with steer friction in the time domain: a steer motor's rotor
inertia, a spring, and an error of the speed sensor (the other pairs are searched between linear
candidates only, to keep the time-domain fits few)."""
HELPFUL = 0.01
"""A candidate predicts the held-out folds better than the nominal model (and enters the pair search)
when its held-out error is lower by more than this fraction (a fit that stays at its neutral value
changes nothing and pairs nothing)."""
UNDETERMINED = 1.0
"""A fitted value whose standard error exceeds this many times the width of its plausible range is
not determined by the data (the data narrow it down less than the literature already does)."""
AMPLITUDE_SPREAD = 2.0
"""Records whose steer-rate amplitudes span less than this factor (10th to 90th percentile) are decays of
one amplitude: they do not tell Coulomb from viscous friction (:meth:`Diagnosis.friction_equivalent`)."""
PRIOR_ODDS = math.log(19.0)
"""Evidence [nats] by which another candidate must beat the first of the ranking to be selected instead
(posterior odds 19 to 1, the 95 % of ``--next``)."""
UNPREDICTED_Z = 1e3
"""Normalised residual given to a held-out point the fitted model cannot predict (singular model)."""


@dataclass
class CrossValidation:
    """Held-out errors of one set of effects.

    Attributes
    ----------
    effects : tuple of str
    folds : list of dict
        ``name, n, error_before, error_after`` per fold.
    z_before, z_after : ndarray
        Normalised held-out residuals of every observation (each is held out once).
    error_before, error_after : float
        Root mean square of ``z`` over all held-out points.
    shrink : float or None
        Fraction of the gap above the noise floor removed (``None`` without a gap above it).
    fits : list of EffectFit
    data_before, data_after, data_shrink : float or None
        The same against the data's own uncertainty alone (residuals over the data's standard
        uncertainty, the parameters' left out): how far the held-out predictions are from the
        measurements in units of their noise, which stays meaningful when the parameters'
        uncertainty covers the gap.
    """

    effects: tuple[str, ...]
    folds: list[dict]
    z_before: np.ndarray
    z_after: np.ndarray
    error_before: float
    error_after: float
    shrink: float | None
    fits: list[EffectFit] = field(default_factory=list)
    data_before: float | None = None
    data_after: float | None = None
    data_shrink: float | None = None


class Diagnosis:
    """Run the diagnosis of one bicycle's data; results in :meth:`as_dict`.

    Parameters
    ----------
    model : GapModelInput
    eigen : EigenvalueData
        Eigenvalue rows from tables.
    canonical : CanonicalData
    effects : sequence of str, optional
        Candidates (default: all of :data:`EFFECT_NAMES`).
    records : list of RecordFit, optional
        Fitted records (:func:`bikerider.gap.measured.records.fit_records`); those fitted become eigenvalue
        rows, which every model predicts by indirect inference (:mod:`bikerider.gap.inference.indirect`), and
        the others are left out with their reason.

    Raises
    ------
    InputError
        When no observation remains (every record left out): too few records for a diagnosis.
    """

    @single_blas_thread
    def __init__(
        self,
        model: GapModelInput,
        eigen: EigenvalueData,
        canonical: CanonicalData,
        effects=EFFECT_NAMES,
        records: list[RecordFit] | None = None,
    ):
        start = time.perf_counter()
        self.model_input = model
        self.records = [replace(f) for f in records or []]  # copies: records left out here get their reason
        self.record_rows: dict[int, int] = {}  # index in self.records -> eigenvalue row
        self._time_domain_full: dict[tuple[str, ...], EffectFit] = {}
        self.bias = np.zeros(0, complex)  # each record row's extraction bias under the nominal model
        self._record_set = None
        eigen = self._with_records(model, eigen)
        if len(eigen) + len(canonical) == 0:
            if not self.records:
                raise InputError("data", "empty", "at least one measured eigenvalue or identified entry")
            left = [f for f in self.records if not f.used]
            reasons = "; ".join(f"{f.record.name}: {f.reason}" for f in left[:3]) + (" ..." if len(left) > 3 else "")
            raise InputError(
                "data",
                f"{len(left)} of {len(self.records)} records left out",
                f"enough records for a diagnosis: none could be used ({reasons})",
            )
        progress.begin("the model's uncertainty at every observation")
        self.problem = GapProblem(model, eigen, canonical, records=self._record_set)
        self.effects = [e for e in effects]
        self.not_applicable = {}
        for e in self.effects:
            if EFFECTS[e].needs_rider and model.geometry.upper_body is None:
                self.not_applicable[e] = "needs a rider on the bicycle (the model has none)"
            elif e in OBSERVATION_EFFECTS and not np.any(eigen.speed_sensor):
                self.not_applicable[e] = (
                    "needs records whose speed a sensor read during the test (a speed column); "
                    "the speeds given are taken as the speeds the bicycle ran at"
                )
            elif EFFECTS[e].needs_records and not self._time_domain_ready():
                self.not_applicable[e] = (
                    "fitted in the time domain: needs every eigenvalue to come from a record "
                    "(uniformly sampled) and records in at least two groups"
                )
        if not self.problem.free and "parameters" in self.effects:
            self.not_applicable["parameters"] = "the model file gives no parameter uncertainties"
        self.candidates = [e for e in self.effects if e not in self.not_applicable]
        self.folds = folds(self.problem.obs)
        self.gap_map = self._gap_map()
        self.gap_test = self._gap_test()
        self.full_fits: dict[tuple[str, ...], EffectFit] = {}
        self.parameter_fit = self.fit_of(("parameters",)) if "parameters" in self.candidates else None
        self.verdict = self._verdict()
        self.ranking: list[dict] = []
        self.cv: dict[tuple[str, ...], CrossValidation] = {}
        self.selected: list[str] = []
        self.selection: dict = {}
        self.best_implausible: dict | None = None
        self.best_single_implausible: dict | None = None
        if len(self.folds) >= 2:
            self._rank()
            self._search_pairs()
        for e in self.candidates:
            self.fit_of((e,))
        progress.begin("selecting")
        self._select()
        self.selected_fit = self.fit_of(tuple(self.selected)) if self.selected else None
        self.elapsed = time.perf_counter() - start

    # -- records -----------------------------------------------------------------------------------
    def _with_records(self, model: GapModelInput, eigen: EigenvalueData) -> EigenvalueData:
        """Table rows plus one row per comparable record (others get their reason).

        A record's row holds the eigenvalue its fit found; every model predicts it by indirect
        inference (:mod:`bikerider.gap.inference.indirect`), like with like however far its result lies from the
        model's weave eigenvalue; a record is left out only where the model within its parameters'
        uncertainty shows no weave the fit finds (its prediction is then undefined).
        """

        used = [k for k, f in enumerate(self.records) if f.used]
        if not used:
            return eigen
        progress.begin("comparing the records with the model")
        rows = eigenvalues_of(self.records)
        nominal = {k: float(model.parameters.values[k]) for k in BENCH_ARGS + ("g",)}  # type: ignore[arg-type]
        fits = [self.records[k] for k in used]
        simulator = RecordSimulator(fits, nominal, model.geometry)
        apparent = simulator.settle()
        matched = Predictor(rows, CanonicalData.empty(), nominal, model.geometry).eigenvalues(
            EffectModel(nominal, model.geometry)
        )
        lost = np.flatnonzero(~np.isfinite(apparent))
        if lost.size:
            # the same fit, started from the model's own weave eigenvalue instead of the record's: far
            # from the model, a start near the record can lead the refit of the model's response astray
            starts = [dict(s) for s in simulator.starts]
            for j in lost:
                for name, p in starts[j].items():
                    p = np.array(p, dtype=float)
                    p[0], p[1] = matched[j].imag, -matched[j].real
                    starts[j][name] = p
            simulator = RecordSimulator(fits, nominal, model.geometry, starts)
            apparent = simulator.settle()
        # Every model predicts a record by the same fit applied to its own response (indirect
        # inference), so how far that lies from the model's weave eigenvalue is no reason to leave a
        # record out.  A record is left out only where the model, within its parameters' uncertainty,
        # predicts nothing the fit finds: its prediction and its uncertainty are then undefined.
        bias = apparent - matched
        reasons: list[str | None] = [
            None
            if np.isfinite(a)
            else (
                "the record fit finds no weave in the model's own response over this window (less than half a "
                "cycle, started from the record's fit and from the model's weave eigenvalue): the model predicts "
                "nothing to compare the record with"
            )
            for a in apparent
        ]
        sigmas = model.parameters.sigmas
        free = [k for k in BENCH_ARGS if sigmas.get(k, 0.0) > 0]
        if free:  # the parameters' uncertainty enters through secants over +-1 sigma: those must exist too
            values = {k: np.full(2 * len(free), v) for k, v in nominal.items()}
            for j, k in enumerate(free):
                values[k][2 * j] += sigmas[k]
                values[k][2 * j + 1] -= sigmas[k]
            shifted = simulator.apparent(values)
            for j in range(len(used)):
                gone = sorted({free[m // 2] for m in np.flatnonzero(~np.isfinite(shifted[:, j]))})
                if reasons[j] is None and gone:
                    reasons[j] = (
                        "the record fit finds no weave in the model's response over this window when "
                        f"{', '.join(gone[:3])}{' ...' if len(gone) > 3 else ''} moves by one standard uncertainty: "
                        "the model's prediction of this record is undefined within its parameters' uncertainty"
                    )
        keep = []
        for j, k in enumerate(used):
            if reasons[j] is not None:
                self.records[k].reason = reasons[j]
                self.records[k].estimate = None
            else:
                keep.append(j)
        rows = rows.subset(np.array(keep, dtype=int))
        self.bias = bias[keep]
        still = [k for k in used if self.records[k].used]
        self.record_rows = {k: len(eigen) + j for j, k in enumerate(still)}
        self._record_set = RecordRows(simulator.subset(keep), np.array(list(self.record_rows.values()), int))
        return EigenvalueData.concatenate([eigen, rows])

    def _time_domain_ready(self) -> bool:
        used = [f for f in self.records if f.used]
        if not used or len(self.record_rows) != len(self.problem.eigen) or len(self.problem.predictor.canonical):
            return False
        if len({f.record.group for f in used}) < 2:
            return False
        for f in used:
            steps = np.diff(f.record.time)
            if steps.size == 0 or not np.allclose(steps, steps[0], rtol=1e-6):
                return False
        return True

    # -- fits ---------------------------------------------------------------------------------------
    def fit_of(self, effects: tuple[str, ...]) -> EffectFit:
        """The fit of a set of effects to all the data (cached)."""
        effects = tuple(effects)
        if effects not in self.full_fits:
            if _time_domain(effects):
                self.full_fits[effects] = self._time_domain_fit(effects, None)
            else:
                self.full_fits[effects] = self._with_parameter_uncertainty(self.problem.fit(effects))
        return self.full_fits[effects]

    def _with_parameter_uncertainty(self, fit: EffectFit) -> EffectFit:
        """A linear fit's covariance and 95 % intervals with the benchmark parameters' uncertainty as the
        systematic error it is.

        The fit weighs each residual by the combined variance of data and parameters, as if the
        parameters' share were independent from row to row; but one parameter error moves every row at
        once, and does not average out over the rows.  The covariance of the fitted values is the sandwich
        ``B A^T C A B`` (``A`` the weighted Jacobian of the predictions in the fitted values, ``B =
        (A^T A)^-1``, ``C`` the weighted covariance of the observations: the data's variance plus
        ``J_p J_p^T`` of the parameters' slopes per sigma), times the reduced chi-square when above one
        (lack of fit).  Fits holding ``parameters`` fit the shifts themselves and keep their own.

        With rows from records the fit's estimating equation weighs the residuals of the apparent
        eigenvalues (indirect inference) by the weave eigenvalues' slopes ``A`` (the iterated bias
        correction of :meth:`GapProblem.fit`), so the bread of the sandwich is ``(A^T A_i)^-1`` with the
        apparent eigenvalues' slopes ``A_i``: ``B A^T C A B^T``.  Without records ``A_i = A``.
        """
        p = self.problem
        if "parameters" in fit.effects or not p.free or not fit.names or not len(p.obs):
            return fit
        lay = p.layout(fit.effects)
        x = np.asarray(fit.values, float)
        lower, upper = np.asarray(fit.lower, float), np.asarray(fit.upper, float)
        span = np.maximum(upper - lower, 1e-9)
        h = 1e-5 * np.minimum(span, 10.0)
        X = [x]
        for k in range(x.size):
            up, down = x.copy(), x.copy()
            up[k] = min(x[k] + h[k], upper[k])
            down[k] = max(x[k] - h[k], lower[k])
            X += [up, down]
        steps = np.array([X[1 + 2 * k][k] - X[2 + 2 * k][k] for k in range(x.size)])

        def slopes(indirect: bool) -> np.ndarray:
            pred = p.predict_batch(lay, np.array(X), indirect=indirect)
            return np.stack([(pred[1 + 2 * k] - pred[2 + 2 * k]) / steps[k] for k in range(x.size)], axis=1)

        w = np.sqrt(p.var_total)
        A = slopes(False) / w[:, None]
        # rows from records are predicted by indirect inference; the fit solves A^T (apparent - y) = 0 (its
        # iterated bias correction weighs the residuals by the weave eigenvalues' slopes), so its covariance
        # is the sandwich of that estimating equation: bread (A^T A_i)^-1 with the apparent eigenvalues'
        # slopes A_i, which a short record's fit can make several times flatter than the weave's
        records = p.records is not None and len(p.record_obs)
        A_i = slopes(True) / w[:, None] if records else A
        if not (np.all(np.isfinite(A)) and np.all(np.isfinite(A_i))):
            return fit
        B = np.linalg.pinv(A.T @ A_i)
        Jp = p.jacobian / w[:, None]
        AC = A.T * (p.var_data / p.var_total)
        cov = B @ (AC @ A + (A.T @ Jp) @ (Jp.T @ A)) @ B.T
        dof = max(fit.n - x.size, 1)
        cov *= max(1.0, fit.chi2 / dof)
        stderr = np.sqrt(np.clip(np.diag(cov), 0, None))
        stderr = np.where(np.isfinite(fit.stderr), stderr, np.inf)  # a value the data do not move stays so
        return replace(
            fit,
            stderr=stderr,
            ci_low=np.clip(x - 1.96 * stderr, lower, upper),
            ci_high=np.clip(x + 1.96 * stderr, lower, upper),
            covariance=cov,
        )

    def _record_indices(self, mask: np.ndarray | None) -> list[int]:
        """Records whose rows are (all) in the observation mask (every record when None)."""
        obs_row = self._obs_rows()
        out = []
        for k, row in self.record_rows.items():
            if mask is None or all(mask[i] for i in obs_row[row]):
                out.append(k)
        return out

    def _obs_rows(self) -> dict[int, list[int]]:
        """Eigenvalue row -> its observation indices (real part, and imaginary part for a weave)."""
        out: dict[int, list[int]] = {}
        k = 0
        e = self.problem.eigen
        for row in range(len(e)):
            n = 2 if e.mode[row] == "weave" else 1
            out[row] = list(range(k, k + n))
            k += n
        return out

    def _time_domain_fit(
        self, effects: tuple[str, ...], mask: np.ndarray | None, start=None, jackknife: bool = True
    ) -> EffectFit:
        """A time-domain candidate (steer friction, alone or with one linear effect) fitted to the records
        in ``mask`` (:func:`bikerider.gap.inference.timedomain.fit_time_domain`).

        The fit to all the data gets standard errors by the jackknife over the held-out folds' fits
        (leave one group out), when there are three folds or more, and 95 % intervals from Student's t
        with one degree of freedom fewer than the folds (:func:`jackknife_quantile`).
        """

        cached = self._time_domain_full.get(effects) if mask is None else None
        if cached is not None and (not jackknife or np.all(np.isfinite(cached.stderr))):
            return cached
        layout = Layout.of(effects)
        lower, upper = np.array(layout.lower), np.array(layout.upper)
        if cached is not None:
            values, cost, n, success = cached.values, cached.chi2, cached.n, cached.success
        else:
            records = [self.records[k] for k in self._record_indices(mask)]
            fit = fit_time_domain(
                [f.record for f in records], self.problem.nominal, self.problem.geometry, layout, start=start
            )
            values, cost, n, success = fit.values, fit.cost, fit.n_samples, fit.success
        stderr = np.full(values.size, np.inf)
        covariance = None
        if mask is None and jackknife and len(self.folds) >= 3:  # jackknife over the held-out folds' fits
            folds = np.array([f.values for f in self.cross_validate(effects).fits])
            g = len(folds)
            centred = folds - folds.mean(axis=0)
            covariance = (g - 1) / g * centred.T @ centred
            stderr = np.sqrt(np.diag(covariance))
            quantile = jackknife_quantile(g)
        else:
            quantile = 1.96
        ci_low = np.clip(values - quantile * stderr, lower, upper)
        ci_high = np.clip(values + quantile * stderr, lower, upper)
        config: dict[str, dict[str, float]] = {}
        for (effect, param), value in zip(layout.names, values):
            config.setdefault(effect, {})[param] = float(value)
        units = [next(p.unit for p in EFFECTS[e].parameters if p.name == n) for e, n in layout.names]
        out = EffectFit(
            effects=effects,
            names=[n for _, n in layout.names],
            units=units,
            values=values,
            stderr=stderr,
            ci_low=ci_low,
            ci_high=ci_high,
            config=config,
            shift={},
            chi2=cost,
            prior_chi2=0.0,
            n=n,
            success=success,
            message="time-domain fit",
            lower=lower,
            upper=upper,
            covariance=covariance,
        )
        if mask is None:
            self._time_domain_full[effects] = out
        return out

    def _time_domain_predict(self, fit: EffectFit, mask: np.ndarray) -> np.ndarray:
        """Predicted observations of the records in ``mask`` under a time-domain fit: what the record fit
        finds in the candidate's simulated response over each record (indirect inference, as for every
        candidate)."""

        idx = self._record_indices(mask)
        pred = np.full(len(self.problem.obs), np.nan)
        order = list(self.record_rows)
        simulator = self.problem.records.simulator.subset([order.index(k) for k in idx])
        apparent = simulator.apparent_time_domain(Layout.of(fit.effects), fit.values)[0]
        obs_row = self._obs_rows()
        for j, k in enumerate(idx):
            parts = obs_row[self.record_rows[k]]
            pred[parts[0]] = apparent[j].real
            if len(parts) > 1:
                pred[parts[1]] = apparent[j].imag
        return pred

    def nominal_bias_per_row(self) -> np.ndarray:
        """Each eigenvalue row's extraction bias under the nominal model (0 for rows from tables)."""
        out = np.zeros(len(self.problem.eigen), complex)
        for j, row in enumerate(self.record_rows.values()):
            out[row] = self.bias[j]
        return out

    def shown_values(self) -> np.ndarray:
        """Measured eigenvalue of each row as figures show it beside weave-eigenvalue curves: a record's
        value with the nominal model's extraction bias removed (the display's only use of that bias)."""
        return self.problem.eigen.value - self.nominal_bias_per_row()

    def selected_predictions(self) -> np.ndarray | None:
        """The selection's prediction of each record row, on the scale of :meth:`shown_values`.

        Its apparent eigenvalue (indirect inference; amplitude-dependent for a time-domain effect) minus
        the nominal model's extraction bias.  ``None`` without a selection or without records.
        """
        if self.selected_fit is None or not self.record_rows:
            return None
        if not hasattr(self, "_selected_predictions"):
            every = np.ones(len(self.problem.obs), bool)
            if _time_domain(tuple(self.selected)):
                pred = self._time_domain_predict(self.selected_fit, every)
            else:
                pred = self.problem.predict_fit(self.selected_fit)
            out = np.full(len(self.problem.eigen), np.nan + 1j * np.nan)
            for row, parts in self._obs_rows().items():
                if row in self.record_rows.values():
                    out[row] = complex(pred[parts[0]], pred[parts[1]] if len(parts) > 1 else 0.0)
            self._selected_predictions = out - self.nominal_bias_per_row()
        return self._selected_predictions

    # -- folds --------------------------------------------------------------------------------------
    # -- where -----------------------------------------------------------------------------------
    def _gap_map(self) -> list[dict]:

        p = self.problem
        obs = p.obs
        z = -p.z(p.baseline)  # measured minus model, normalised
        eig_speeds = np.unique(obs.speed[[k == "eigenvalue" for k in obs.kind]])
        bands = np.array_split(eig_speeds, min(N_SPEED_BANDS, eig_speeds.size)) if eig_speeds.size else []
        cells = []
        keys = []
        for i in range(len(obs)):
            if obs.kind[i] == "eigenvalue":
                band = next(b for b in bands if b[0] <= obs.speed[i] <= b[-1])
                band_key = (float(band[0]), float(band[-1]))
            else:
                band_key = tuple(float(x) for x in self.problem.predictor.canonical.speed_range[obs.group[i]])
            key = (
                (obs.mode[i], band_key, obs.quantity[i])
                if obs.kind[i] == "eigenvalue"
                else ("canonical", band_key, f"{obs.quantity[i]} ({obs.group[i]})")
            )
            keys.append(key)
        unique = list(dict.fromkeys(keys))
        for key in unique:
            idx = [i for i, k in enumerate(keys) if k == key]
            zz = z[idx]
            stat = float(np.sum(zz**2))
            pval = float(chi2.sf(stat, len(idx)))
            cells.append(
                {
                    "mode": key[0],
                    "speed_band": list(key[1]),
                    "quantity": key[2],
                    "n": len(idx),
                    "mean_residual": float(np.mean(p.y[idx] - p.baseline[idx])),
                    "mean_measured": float(np.mean(p.y[idx])),
                    "mean_predicted": float(np.mean(p.baseline[idx])),
                    "combined_sigma": float(np.sqrt(np.mean(p.var_total[idx]))),
                    "data_sigma": float(np.sqrt(np.mean(p.var_data[idx]))),
                    "model_sigma": float(np.sqrt(np.mean(p.var_model[idx]))),
                    "rms_z": rms(zz),
                    "chi2": stat,
                    "p_value": pval,
                    "significant": bool(pval < ALPHA / max(len(unique), 1)),
                    **_data_only_cell(p, idx, ALPHA / max(len(unique), 1)),
                }
            )
        return cells

    def _gap_test(self) -> dict:

        p = self.problem
        r = p.y - p.baseline
        stat, n = low_rank_chi2(r, p.var_data, p.jacobian)  # r^T (D + J J^T)^-1 r in linear time
        if np.all(p.var_data > 0):
            data_stat = float(np.sum(r**2 / p.var_data))
        else:  # rows taken as exact: any residual is a gap against the data alone
            data_stat = (
                math.inf
                if np.any(r[p.var_data <= 0] != 0)
                else float(np.sum(r[p.var_data > 0] ** 2 / p.var_data[p.var_data > 0]))
            )
        return {
            "chi2": stat,
            "dof": n,
            "p_value": float(chi2.sf(stat, n)),
            "rms_z": rms(-p.z(p.baseline)),
            "significant": bool(chi2.sf(stat, n) < ALPHA),
            "data_only": {
                "chi2": data_stat,
                "p_value": float(chi2.sf(data_stat, n)),
                "significant": bool(chi2.sf(data_stat, n) < ALPHA),
            },
        }

    # -- whether ----------------------------------------------------------------------------------
    def _verdict(self) -> str:

        fit = self.parameter_fit
        if fit is not None:
            stat = fit.chi2 + fit.prior_chi2
            self.parameter_test = {
                "chi2": stat,
                "dof": fit.n,
                "p_value": float(chi2.sf(stat, fit.n)),
                "prior_chi2": fit.prior_chi2,
                "prior_dof": len(self.problem.free),
            }
        if not self.gap_test["significant"]:
            # within the combined uncertainty: no gap at all, or one the parameters' uncertainty covers
            return "parameters" if self.gap_test["data_only"]["significant"] and self.problem.free else "none"
        if fit is None:
            return "structural"
        return "parameters" if chi2.sf(self.parameter_test["chi2"], fit.n) >= ALPHA else "structural"

    # -- which ------------------------------------------------------------------------------------
    def cross_validate(self, effects: tuple[str, ...]) -> CrossValidation:
        if effects in self.cv:
            return self.cv[effects]
        p = self.problem
        z_before = p.z(p.baseline)
        z_after = np.full(len(p.obs), np.nan)
        folds, fits = [], []
        timed = _time_domain(effects)
        if timed:
            start = None
            if len(effects) > 1 and ("steer_friction",) in self._time_domain_full:  # from the friction alone
                alone = self._time_domain_full[("steer_friction",)].values
                start = list(alone) + [1.0 if n == "speed_scale" else 0.0 for _, n in Layout.of(effects).names[2:]]
            full = self._time_domain_fit(effects, None, start=start, jackknife=False)
        else:
            full = self.fit_of(effects)
        for name, held in self.folds:  # every fold starts from the fit to all the data
            progress.advance()
            if timed:
                fit = self._time_domain_fit(effects, ~held, start=full.values)
                pred = self._time_domain_predict(fit, held)
            else:
                fit = p.fit(effects, ~held, start=full.values, bias=full.bias)
                pred = p.predict_fit(fit)
            fits.append(fit)
            z_fold = p.z(pred)[held]
            # a model that cannot be evaluated (singular) predicts nothing: count it as far off
            z_after[held] = np.where(np.isfinite(z_fold), z_fold, UNPREDICTED_Z)
            entry = {
                "fold": name,
                "n": int(held.sum()),
                "error_before": rms(z_before[held]),
                "error_after": rms(z_after[held]),
                "fitted": _named_values(fit),
            }
            if np.all(p.var_data[held] > 0):
                scale = np.sqrt(p.var_total[held] / p.var_data[held])
                entry["data_error_before"] = rms(z_before[held] * scale)
                entry["data_error_after"] = rms(z_after[held] * scale)
            folds.append(entry)
        held_any = np.any([h for _, h in self.folds], axis=0)
        result = CrossValidation(
            effects,
            folds,
            z_before[held_any],
            z_after[held_any],
            rms(z_before[held_any]),
            rms(z_after[held_any]),
            gap_shrink(z_before[held_any], z_after[held_any]),
            fits,
        )
        data_sigma = np.sqrt(p.var_data)[held_any]
        if np.all(data_sigma > 0):
            scale = np.sqrt(p.var_total)[held_any] / data_sigma
            zb, za = z_before[held_any] * scale, z_after[held_any] * scale
            result.data_before, result.data_after, result.data_shrink = rms(zb), rms(za), gap_shrink(zb, za)
        self.cv[effects] = result
        return result

    def _order(self, results: list[CrossValidation]) -> list[tuple[CrossValidation, list[str]]]:
        """Sort by held-out error; ties (see module docstring) go to the simpler candidate."""
        results = sorted(results, key=lambda r: r.error_after)
        ordered: list[CrossValidation] = list(results)
        ties: dict[tuple, list[str]] = {r.effects: [] for r in results}
        for i, a in enumerate(results):
            for b in results[i + 1 :]:
                better, _ = significantly_better(a.z_after, b.z_after)
                if not better:
                    ties[a.effects].append("+".join(b.effects))
                    ties[b.effects].append("+".join(a.effects))
        # bubble simpler candidates ahead of tied, better-scoring but more complex ones
        changed = True
        while changed:
            changed = False
            for i in range(len(ordered) - 1):
                a, b = ordered[i], ordered[i + 1]
                if "+".join(b.effects) in ties[a.effects] and _n_params(self.problem, b.effects) < _n_params(
                    self.problem, a.effects
                ):
                    ordered[i], ordered[i + 1] = b, a
                    changed = True
        return [(r, ties[r.effects]) for r in ordered]

    def _rank(self) -> None:
        progress.begin("candidates", len(self.candidates) * len(self.folds), "fold fits")
        cross_validate_all(self, [(e,) for e in self.candidates], _fit_cost)  # on every core; the same results
        results = [self.cross_validate((e,)) for e in self.candidates]
        for rank, (r, ties) in enumerate(self._order(results), start=1):
            self.ranking.append(
                {
                    "rank": rank,
                    "effect": r.effects[0],
                    "heldout_error_before": r.error_before,
                    "heldout_error_after": r.error_after,
                    "shrink": r.shrink,
                    "tied_with": ties,
                    "folds": r.folds,
                    "data_error_before": r.data_before,
                    "data_error_after": r.data_after,
                    "data_shrink": r.data_shrink,
                }
            )

    def pair_candidates(self) -> list[tuple[str, str]]:
        """Pairs searched on the held-out folds (module docstring): any two linear candidates that each,
        alone, predict the held-out folds better than the nominal model (by :data:`HELPFUL`), fitted jointly; and steer
        friction (in the time domain) with each such one of :data:`TIME_DOMAIN_PARTNERS`."""

        helpful = [
            e
            for e in self.candidates
            if (e,) in self.cv and self.cv[(e,)].error_after < (1 - HELPFUL) * self.cv[(e,)].error_before
        ]
        linear = [e for e in helpful if e not in TIME_DOMAIN_EFFECTS]
        pairs = [tuple(sorted(pair, key=EFFECT_NAMES.index)) for pair in itertools.combinations(linear, 2)]
        if "steer_friction" in helpful:
            pairs += [
                tuple(sorted((e, "steer_friction"), key=EFFECT_NAMES.index))
                for e in TIME_DOMAIN_PARTNERS
                if e in helpful
            ]
        return pairs

    def _search_pairs(self) -> None:
        self.pairs = []
        pairs = self.pair_candidates()
        progress.begin("pairs", len(pairs) * len(self.folds), "fold fits")
        cross_validate_all(self, pairs, _fit_cost)  # on every core; the same results
        for pair in pairs:
            r = self.cross_validate(pair)
            self.pairs.append(r)

    def score(self, r: CrossValidation, lack_of_fit: float = 1.0) -> float:
        """The selection's evidence for a set of effects [nats]: held-out log-likelihood
        ``-sum(z^2) / (2 s^2)`` plus the log prior ratio of its values fitted to all the data
        (:meth:`log_prior`); ``s^2`` is the lack of fit (:meth:`lack_of_fit`)."""
        return -0.5 * float(np.sum(np.square(r.z_after))) / lack_of_fit + self.log_prior(self.fit_of(r.effects))

    def lack_of_fit(self) -> float:
        """``s^2 = max(1, min mean(z^2))`` over every candidate and pair on the held-out folds: the variance
        of the held-out residuals that no candidate explains, in units of their stated uncertainty.  The
        held-out log-likelihood is taken with the noise inflated by it (a quasi-likelihood): where even the
        best candidate misses the data by several standard deviations, the stated noise would make every
        added freedom look decisive against the priors."""
        every = [self.cv[(r["effect"],)] for r in self.ranking] + list(getattr(self, "pairs", []))
        means = [float(np.mean(np.square(r.z_after))) for r in every if r.z_after.size]
        return max(1.0, min(means)) if means else 1.0

    def _select(self) -> None:
        """Selection (module docstring): by held-out error and prior together; a value outside its usual
        range is flagged, never refused; a pair only when it beats the single."""
        if self.verdict == "none":
            self.selection = {"rule": "no gap above the noise: nothing to explain"}
            return
        parameters_note = None
        if self.verdict == "parameters":
            if "parameters" in self.candidates:
                ok, checks = self.plausibility(self.fit_of(("parameters",)))
                if ok:
                    self.selected = ["parameters"]
                    self.selection = {"rule": "plausible parameter errors explain the gap"}
                    return
                parameters_note = (
                    "the gap lies within the parameters' uncertainty, but the parameter fit needs "
                    "implausible shifts (" + "; ".join(_implausible_reasons(checks)) + "): the candidates "
                    "are compared as for a structural gap"
                )
            else:
                parameters_note = (
                    "the gap lies within the parameters' uncertainty (parameters are not a candidate): "
                    "the candidates are compared as for a structural gap"
                )
        if len(self.folds) < 2:
            self.selection = {"rule": "fewer than two folds: no held-out comparison, nothing selected"}
            return
        p = self.problem
        held_any = np.any([h for _, h in self.folds], axis=0)
        z_nominal = p.z(p.baseline)[held_any]
        lack = self.lack_of_fit()
        nominal_score = -0.5 * float(np.sum(np.square(z_nominal))) / lack
        singles = [self.cv[(r["effect"],)] for r in self.ranking]
        considered = []
        judged: dict[tuple[str, ...], dict] = {}

        def judge(r: CrossValidation, reference: np.ndarray, key: str) -> dict:
            ok, checks = self.plausibility(self.fit_of(r.effects))
            better, pval = significantly_better(r.z_after, reference)
            left = r.data_after if r.data_after is not None else r.error_after
            usable = all(c.get("usable", True) for c in checks)
            at_floor = at_noise_floor(left, r.z_after.size)
            score = self.score(r, lack)
            entry = {
                "effects": list(r.effects),
                "heldout_error": r.error_after,
                "plausible": ok,
                key: better,
                "p_value": pval,
                "at_noise_floor": at_floor,
                "usable": usable,
                "log_prior": self.log_prior(self.fit_of(r.effects)),
                "log_odds_vs_nominal": score - nominal_score,
                "flags": [c["flag"] for c in checks if c.get("flag")],
                "eligible": bool(better and (usable or at_floor) and score > nominal_score),
            }
            judged[r.effects] = {**entry, "score": score, "checks": checks}
            considered.append(entry)
            return judged[r.effects]

        best_single = None
        for r in singles:
            j = judge(r, z_nominal, "beats_nominal")
            if not j["eligible"]:
                continue
            if best_single is None:
                best_single = r
            elif j["score"] > judged[best_single.effects]["score"] + PRIOR_ODDS:
                best_single = r  # the prior and held-out data together favour it by more than 19 to 1
        chosen = best_single
        reference = best_single.z_after if best_single is not None else z_nominal
        # a pair only where the single leaves a gap above the noise floor (Occam: nothing left to explain)
        left = (
            None
            if best_single is None
            else (best_single.data_after if best_single.data_after is not None else best_single.error_after)
        )
        floor_reached = left is not None and at_noise_floor(left, best_single.z_after.size)
        pairs = [] if floor_reached else getattr(self, "pairs", [])
        floor_score = judged[best_single.effects]["score"] if best_single is not None else nominal_score
        for r in sorted(pairs, key=lambda r: r.error_after):
            j = judge(r, reference, "beats_single" if best_single is not None else "beats_nominal")
            if j["eligible"] and j["score"] > floor_score and chosen is best_single:
                chosen = r
        rule = (
            "the first single candidate of the ranking that beats the nominal model significantly on held-out "
            "folds with posterior odds above even (held-out log-likelihood, its noise inflated by the lack of fit "
            "no candidate removes, plus log prior ratio), unless another "
            "such candidate's odds are 19 times higher; a pair when the single leaves a gap above the noise "
            "floor and the pair beats it significantly with higher odds; values outside their usual range are "
            "flagged, not refused; a value the data do not determine (or pinned at the edge of the search) "
            "is selected only when its candidate explains the held-out data to the noise floor"
        )
        # the best held-out fit overall, and the best single one: when not chosen and unusual, say why
        every = singles + list(getattr(self, "pairs", []))
        for pool, key in ((every, "best_implausible"), (singles, "best_single_implausible")):
            best = min(pool, key=lambda r: r.error_after) if pool else None
            if best is not None and (chosen is None or best.effects != chosen.effects):
                ok, checks = self.plausibility(self.fit_of(best.effects))
                if not ok:
                    j = judged.get(best.effects)
                    entry = {
                        "effects": list(best.effects),
                        "heldout_error": best.error_after,
                        "why": _implausible_reasons(checks),
                    }
                    if j is not None and chosen is not None:
                        entry["log_odds_vs_selected"] = j["score"] - judged[chosen.effects]["score"]
                    ranked = next((r for r in self.ranking if (r["effect"],) == best.effects), None)
                    if ranked is not None:  # where the ranking (ties to the simpler) puts it
                        entry["rank"], entry["tied_with"] = ranked["rank"], list(ranked["tied_with"])
                    setattr(self, key, entry)
        if self.best_single_implausible == self.best_implausible:
            self.best_single_implausible = None
        self.selected = list(chosen.effects) if chosen is not None else []
        self.selection = {"rule": rule, "considered": considered, "lack_of_fit": lack}
        if chosen is not None:
            j = judged[chosen.effects]
            self.selection.update(
                {"log_odds_vs_nominal": j["log_odds_vs_nominal"], "log_prior": j["log_prior"], "flags": j["flags"]}
            )
            equivalent = self.friction_equivalent(self.fit_of(chosen.effects))
            if equivalent is not None and not equivalent["separable"]:
                self.selection["flags"] = self.selection["flags"] + ["steer_friction: " + equivalent["note"]]
        if parameters_note:
            self.selection["note"] = parameters_note

    # -- plausibility --------------------------------------------------------------------------------
    def steer_rate_amplitude(self) -> float | None:
        """Median steer-rate amplitude of the records used [rad/s] (None without steer signals).

        ``sqrt(2)`` times the RMS steer rate over the record, from a steer-rate signal, or from a
        steer-angle signal times the record's weave frequency.
        """
        amplitudes = self.steer_rate_amplitudes()
        return float(np.median(amplitudes)) if amplitudes.size else None

    def plausible_range(self, name: str) -> tuple[float, float, str]:
        """The usual range of a fitted parameter and where it comes from (a value outside it is flagged)."""
        if name in self.model_input.plausible:
            return self.model_input.plausible[name]
        param = _parameter(name)
        lo, hi = param.literature
        if name == "c_steer":
            amplitude = self.steer_rate_amplitude()
            if amplitude is not None and amplitude > 0:
                extra = 4 * COULOMB_RANGE[1] / (math.pi * amplitude)
                return (
                    lo,
                    hi + extra,
                    (
                        f"{param.source}; above it, the linear equivalent 4 T / (pi A) of Coulomb "
                        f"friction T up to {COULOMB_RANGE[1]:g} N m at the records' steer-rate "
                        f"amplitude A = {amplitude:.3g} rad/s adds up to {extra:.3g} N m s/rad"
                    ),
                )
        return lo, hi, param.source

    def steer_rate_amplitudes(self) -> np.ndarray:
        """Each used record's steer-rate amplitude [rad/s] (as :meth:`steer_rate_amplitude`), where known."""
        out = []
        for k in self.record_rows:
            f = self.records[k]
            r = f.record
            if "steer_rate" in r.signals and np.all(np.isfinite(r.signals["steer_rate"])):
                out.append(math.sqrt(2) * float(np.std(r.signals["steer_rate"])))
            elif (
                "steer_angle" in r.signals and np.all(np.isfinite(r.signals["steer_angle"])) and f.estimate is not None
            ):
                x = r.signals["steer_angle"]
                out.append(math.sqrt(2) * float(np.std(x)) * abs(f.estimate.eigenvalue))
        return np.array(out, float)

    def friction_equivalent(self, fit: EffectFit) -> dict | None:
        """Coulomb plus viscous steer friction as the viscous damping it equals at the records' amplitude.

        The describing function of Coulomb friction ``T`` on a sinusoidal steer rate of amplitude ``A`` is a
        viscous damping ``4 T / (pi A)``, so ``c_eq = c_viscous + 4 T / (pi A)`` at the records' median
        amplitude, with its standard error from the fit's covariance.  Records whose amplitudes span less
        than a factor :data:`AMPLITUDE_SPREAD` (10th to 90th percentile) are decays of one amplitude: they
        determine ``c_eq`` but not the split between Coulomb and viscous friction (``separable`` false).
        ``None`` for a fit without steer friction or records without a steer signal.
        """
        if "steer_friction" not in fit.effects or "T_coulomb" not in fit.names:
            return None
        amplitudes = self.steer_rate_amplitudes()
        amplitudes = amplitudes[np.isfinite(amplitudes) & (amplitudes > 0)]
        if not amplitudes.size:
            return None
        a = float(np.median(amplitudes))
        lo, hi = np.percentile(amplitudes, [10, 90])
        spread = float(hi / lo)
        i, j = fit.names.index("T_coulomb"), fit.names.index("c_viscous")
        gradient = np.zeros(len(fit.names))
        gradient[i], gradient[j] = 4 / (math.pi * a), 1.0
        value = float(gradient @ fit.values)
        if fit.covariance is not None and np.all(np.isfinite(fit.covariance)):
            stderr = float(math.sqrt(max(gradient @ fit.covariance @ gradient, 0.0)))
        else:
            stderr = float(math.hypot(gradient[i] * fit.stderr[i], fit.stderr[j]))
        separable = spread >= AMPLITUDE_SPREAD
        timed = _time_domain(fit.effects) and fit.covariance is not None and len(self.folds) >= 3
        quantile = jackknife_quantile(len(self.folds)) if timed else 1.96
        low, high = max(value - quantile * stderr, 0.0), value + quantile * stderr
        return {
            "c_equivalent": value,
            "stderr": stderr,
            "ci95": [low, high],
            "unit": "N m s/rad",
            "amplitude": a,
            "amplitude_spread": spread,
            "separable": bool(separable),
            "note": (
                f"the records' steer-rate amplitudes span a factor {spread:.2g} (10th-90th percentile, median "
                f"A = {a:.3g} rad/s)"
                + (
                    ": Coulomb and viscous friction are told apart by how the damping changes with amplitude"
                    if separable
                    else (
                        ": decays of one amplitude, which cannot tell Coulomb from viscous friction; what they "
                        f"determine is the equivalent viscous damping c_eq = c_viscous + 4 T_coulomb / (pi A) = "
                        f"{value:.3g} [{low:.3g}, {high:.3g}] "
                        "N m s/rad, not the split"
                    )
                )
            ),
        }

    def prior_of(self, name: str) -> Prior:
        """The prior of a fitted parameter: the bicycle's own ``[plausible]`` range made a prior
        (:func:`bikerider.gap.candidates.effects.prior_from_range`), else the registry's."""
        if name in self.model_input.plausible:
            lo, hi, why = self.model_input.plausible[name]
            return prior_from_range(lo, hi, f"this bicycle's [plausible] table: {why}")
        return _parameter(name).the_prior()

    def log_prior(self, fit: EffectFit) -> float:
        """``ln p(values) - ln p(modes)`` of a fit's values under their priors [nats, <= 0]: what the
        selection weighs against the held-out log-likelihood (the benchmark shifts: ``-chi2 / 2`` of
        their Gaussian prior)."""
        total = -0.5 * fit.prior_chi2 if "parameters" in fit.effects else 0.0
        for k, name in enumerate(fit.names):
            if not name.startswith("parameters."):
                total += self.prior_of(name).log_ratio(float(fit.values[k]))
        return float(total)

    def plausibility(self, fit: EffectFit) -> tuple[bool, list[dict]]:
        """Whether every fitted value is usual (module docstring), with one check per fitted value.

        A check holds the value, its 95 % interval, the usual range and its source, the prior and its
        log ratio, whether the data determine the value and whether it is pinned at a search bound, and a
        ``flag`` (text) when the value lies outside the usual range.  ``usable`` is false only where the
        data cannot carry the value (undetermined, or pinned at the edge of the search).
        """

        checks = []
        ok = True
        pinned = set(fit.at_bound()) if fit.names else set()
        if "parameters" in fit.effects:
            limit = float(chi2.ppf(1 - ALPHA, max(len(self.problem.free), 1)))
            good = fit.prior_chi2 <= limit
            shifted = [n for n in fit.names if n.startswith("parameters.")]
            at = sorted(n.split(".", 1)[1] for n in shifted if n in pinned)
            checks.append(
                {
                    "name": "sum of squared shifts / sigma^2",
                    "value": fit.prior_chi2,
                    "literature": [0.0, limit],
                    "plausible": bool(good and not at),
                    "usable": not at,
                    "at_bound": at,
                    "log_prior": -0.5 * fit.prior_chi2,
                    "source": "the parameters' stated uncertainties (chi-square at 1 %)",
                }
            )
            ok = ok and bool(good) and not at
        for k, name in enumerate(fit.names):
            if name.startswith("parameters."):
                continue
            lo, hi, source = self.plausible_range(name)
            param = _parameter(name)
            prior = self.prior_of(name)
            unit = fit.units[k]
            at_bound = name in pinned
            ci = (float(fit.ci_low[k]), float(fit.ci_high[k]))
            if name == "m_arm":
                # judge the arms by their inertia about the steer axis
                inertia = arm_inertia(self.problem, fit.values[k])
                (lo, hi), unit, source = LITERATURE_EXTRA["I_arm_steer"]
                scale = inertia / fit.values[k] if fit.values[k] > 0 else arm_inertia(self.problem, 1.0)
                value, shown, ci = inertia, "I_arm_steer", (ci[0] * scale, ci[1] * scale)
                determined = math.isfinite(fit.stderr[k]) and fit.stderr[k] * scale <= UNDETERMINED * (hi - lo)
            else:
                value, shown = float(fit.values[k]), name
                determined = math.isfinite(fit.stderr[k]) and fit.stderr[k] <= UNDETERMINED * max(hi - lo, 1e-12)
            # below the usual range is usual too where the prior makes zero the most probable size
            usual = bool(lo <= value <= hi or (value < lo and prior.kind == "halfcauchy"))
            flag = None
            if not usual:
                side = "above" if value > hi else "below"
                precise = " (the data determine it: 95 % interval " if determined else " (95 % interval "
                flag = (
                    f"{shown} = {value:.3g} {unit}{precise}[{ci[0]:.3g}, {ci[1]:.3g}]) is {side} the usual "
                    f"{lo:g}-{hi:.3g} {unit} from {source}"
                    + (f": check {param.check}" if side == "above" and param.check else "")
                )
            good = bool(usual and determined and not at_bound)
            checks.append(
                {
                    "name": shown,
                    "value": value,
                    "unit": unit,
                    "literature": [lo, hi],
                    "plausible": good,
                    "in_range": usual,
                    "determined": bool(determined),
                    "at_bound": bool(at_bound),
                    "usable": bool(determined and not at_bound),
                    "bounds": [float(fit.lower[k]), float(fit.upper[k])],
                    "ci95": list(ci),
                    "source": source,
                    "prior": prior.describe(fit.units[k]),
                    "prior_source": prior.source,
                    "log_prior": prior.log_ratio(float(fit.values[k])),
                    "flag": flag,
                }
            )
            ok = ok and good
        return ok, checks

    # -- report ---------------------------------------------------------------------------------
    def as_dict(self) -> dict:
        """Everything, as plain JSON-ready values."""
        p = self.problem
        ranking = []
        for entry in self.ranking:
            fit = self.fit_of((entry["effect"],))
            plausible, checks = self.plausibility(fit)
            ranking.append(
                {
                    **{k: entry[k] for k in ("rank", "effect")},
                    "parameters": _named_values(fit),
                    "heldout_error_before": entry["heldout_error_before"],
                    "heldout_error_after": entry["heldout_error_after"],
                    "shrink": entry["shrink"],
                    "plausible": plausible,
                    "plausibility": checks,
                    "tied_with": entry["tied_with"],
                    "n_parameters": len(fit.names),
                    "data_error_before": entry["data_error_before"],
                    "data_error_after": entry["data_error_after"],
                    "data_shrink": entry["data_shrink"],
                    "folds": entry["folds"],
                    "equivalent": self.friction_equivalent(fit),
                }
            )
        pairs = []
        for r in sorted(getattr(self, "pairs", []), key=lambda r: r.error_after):
            entry = {
                "effects": list(r.effects),
                "heldout_error_before": r.error_before,
                "heldout_error_after": r.error_after,
                "shrink": r.shrink,
                "data_error_after": r.data_after,
                "data_shrink": r.data_shrink,
            }
            fit = self.fit_of(r.effects)
            ok, checks = self.plausibility(fit)
            entry.update(
                {
                    "plausible": ok,
                    "parameters": _named_values(fit),
                    "plausibility": checks,
                    "equivalent": self.friction_equivalent(fit),
                }
            )
            pairs.append(entry)
        out = {
            "verdict": self.verdict,
            "gap": {"test": self.gap_test, "map": self.gap_map},
            "parameter_fit": None,
            "ranking": ranking,
            "pairs": pairs,
            "selected": list(self.selected),
            "selection": self.selection,
            "best_implausible": self.best_implausible,
            "best_single_implausible": self.best_single_implausible,
            "how_far": None,
            "not_applicable": self.not_applicable,
            "folds": [name for name, _ in self.folds],
            "n_observations": len(p.obs),
            "records": self._records_summary(),
            "noise": p.noise,
            "uncertainty": self._uncertainty_summary(),
            "laws": {name: law.describe() for name, law in p.eigen.laws.items()},
            "notes": list(p.notes)
            + ([] if len(self.folds) >= 2 else ["fewer than two folds (groups or speeds): no held-out ranking"]),
            "model": {"source": p.model_input.source, "geometry": p.geometry.notes, "uncertain_parameters": p.free},
            "elapsed_s": self.elapsed,
        }
        if self.parameter_fit is not None:
            fit = self.parameter_fit
            plausible, checks = self.plausibility(fit)
            out["parameter_fit"] = {
                "shift": fit.shift,
                "shift_in_sigma": dict(zip(p.free, map(float, fit.values))),
                "test": getattr(self, "parameter_test", None),
                "plausible": plausible,
                "at_bound": checks[0]["at_bound"],
            }
        if self.selected and len(self.folds) >= 2:
            cv = self.cross_validate(tuple(self.selected))
            fit = self.selected_fit
            out["how_far"] = {
                "effects": list(self.selected),
                "folds": cv.folds,
                "heldout_error_before": cv.error_before,
                "heldout_error_after": cv.error_after,
                "shrink": cv.shrink,
                "data_error_before": cv.data_before,
                "data_error_after": cv.data_after,
                "data_shrink": cv.data_shrink,
                "parameters": _named_values(fit) if fit else {},
                "equivalent": self.friction_equivalent(fit) if fit else None,
            }
        return out

    def _uncertainty_summary(self) -> dict:
        """Typical data and parameter standard uncertainties, and the parameters contributing most."""
        p = self.problem
        out = {
            "data": float(np.median(np.sqrt(p.var_data))) if len(p.obs) else None,
            "parameters": float(np.median(np.sqrt(p.var_model))) if len(p.obs) else None,
            "largest": [],
        }
        if p.free:
            contribution = np.sqrt(np.mean(p.jacobian**2, axis=0))
            order = np.argsort(-contribution)[:5]
            out["largest"] = [
                {"parameter": p.free[k], "sigma": float(p.free_sigma[k]), "rms_effect": float(contribution[k])}
                for k in order
            ]
        return out

    def _records_summary(self) -> dict | None:
        if not self.records:
            return None
        rows = list(self.record_rows)
        out = []
        for k, f in enumerate(self.records):
            entry = f.summary()
            if k in self.record_rows:
                b = self.bias[rows.index(k)]
                entry["bias"] = [float(b.real), float(b.imag)]
            out.append(entry)
        used = sum(1 for e in out if e["used"])
        return {
            "total": len(out),
            "used": used,
            "left_out": len(out) - used,
            "reasons": [{"record": e["record"], "reason": e["reason"]} for e in out if not e["used"]],
            "repaired": [{"record": e["record"], "repairs": e["repairs"]} for e in out if e["used"] and e["repairs"]],
            "list": out,
        }


def _parameter(name: str) -> EffectParameter:
    """The registry's entry of a fitted parameter, by name."""
    return next(p for e in EFFECTS.values() for p in e.parameters if p.name == name)


def arm_inertia(problem: GapProblem, m_arm: float) -> float:
    """Moment of inertia of the arm masses about the steer axis [kg m^2]."""
    g = problem.geometry.grips
    v = problem.nominal
    lam, w, c = v["lam"], v["w"], v["c"]
    # distance of a grip from the steer axis (axis through (w + c, 0, 0), direction (sin lam, 0, cos lam))
    rel = np.array([g["x_grip"] - (w + c), g["b_grip"], g["z_grip"]])
    axis = np.array([math.sin(lam), 0.0, math.cos(lam)])
    perp = rel - (rel @ axis) * axis
    return float(m_arm * (perp @ perp))


def _fit_cost(effects: tuple[str, ...]) -> int:
    """A rough rank of a candidate's cost, to start the longest first on the worker processes: fits in
    the time domain, then the benchmark parameters' shifts, then more effects."""
    return 4 * any(e in TIME_DOMAIN_EFFECTS for e in effects) + 2 * ("parameters" in effects) + len(effects)


def _data_only_cell(problem: GapProblem, idx: list[int], alpha: float) -> dict:
    """A gap-map cell's RMS residual and significance against the data's uncertainty alone."""

    var = problem.var_data[idx]
    if not np.all(var > 0):
        return {"rms_z_data": None, "significant_data": None}
    z = (problem.y[idx] - problem.baseline[idx]) / np.sqrt(var)
    return {"rms_z_data": rms(z), "significant_data": bool(chi2.sf(float(np.sum(z**2)), len(idx)) < alpha)}


def _time_domain(effects: tuple[str, ...]) -> bool:
    """Whether a set of effects is fitted in the time domain (it holds a nonlinear candidate)."""
    return any(e in TIME_DOMAIN_EFFECTS for e in effects)


def _implausible_reasons(checks: list[dict]) -> list[str]:
    """Why a fit is implausible, one phrase per failing value."""
    out = []
    for c in checks:
        if c.get("plausible", True):
            continue
        name = c["name"]
        if name.startswith("sum of squared shifts"):
            parts = []
            if c["value"] > c["literature"][1]:
                parts.append(
                    f"parameter shifts of chi-square {c['value']:.3g} (the prior allows {c['literature'][1]:.3g})"
                )
            if c.get("at_bound"):
                parts.append("shifts pinned at a bound: " + ", ".join(c["at_bound"]))
            out.append("; ".join(parts))
            continue
        unit = c.get("unit", "")
        if c.get("at_bound"):
            out.append(f"{name} = {c['value']:.3g} {unit} at its search bound {c['bounds']}")
        elif not c.get("determined", True):
            out.append(
                f"{name} = {c['value']:.3g} {unit} not determined by the data (95 % interval "
                f"[{c['ci95'][0]:.3g}, {c['ci95'][1]:.3g}])"
            )
        else:
            out.append(
                c.get("flag")
                or f"{name} = {c['value']:.3g} {unit} outside the usual {c['literature'][0]:g}-"
                f"{c['literature'][1]:.3g} {unit}"
            )
    return out


def diagnose(
    model: GapModelInput,
    eigen: EigenvalueData | None = None,
    canonical: CanonicalData | None = None,
    effects=EFFECT_NAMES,
    records: list[RecordFit] | None = None,
) -> Diagnosis:
    """Run the diagnosis (see the module docstring)."""
    eigen = eigen if eigen is not None else EigenvalueData.empty()
    canonical = canonical if canonical is not None else CanonicalData.empty()
    return Diagnosis(model, eigen, canonical, effects, records)
