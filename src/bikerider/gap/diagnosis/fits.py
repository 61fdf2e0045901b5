"""The one place a candidate is fitted: every fit of a set of effects, to all the data or to the
training folds, and every cross-validation, cached.

A linear set of effects is fitted by :meth:`bikerider.gap.inference.problem.GapProblem.fit` (the fit
to all the data then gets the benchmark parameters' uncertainty as the systematic error it is,
:func:`with_parameter_uncertainty`); a set holding a time-domain effect (steer friction) is fitted
to the records themselves (:func:`bikerider.gap.inference.timedomain.fit_time_domain`), and its fit to
all the data gets standard errors by the jackknife over the held-out folds' fits (with fewer than three
folds, from the fit's own Gauss-Newton covariance).  So fitting and
cross-validating call each other, and both live here.

The caches fill in the order the diagnosis asks (the time-domain pairs start from the friction
fitted alone when that is known): :func:`bikerider.gap.diagnosis.result.diagnose` asks in a fixed
order, so the results do not depend on which worker process computed what
(:func:`bikerider.gap.parallel.cross_validate_all`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np

from bikerider import progress
from bikerider.gap.candidates.effect_model import geometry_keys
from bikerider.gap.candidates.effects import EFFECTS, PARAMETERS, STEER_FRICTION, TIME_DOMAIN_EFFECTS
from bikerider.gap.diagnosis.statistics import _named_values, gap_shrink, interval_quantile, rms
from bikerider.gap.inference.frequency_response import predict_frf_friction
from bikerider.gap.inference.problem import (
    MINIMUM_STARTS,
    PROFILE_MAX_RECORDS,
    EffectFit,
    GapProblem,
    scale_and_quantile,
)
from bikerider.gap.inference.timedomain import (
    CornerShare,
    Layout,
    corner_share,
    fit_covariance,
    fit_time_domain,
    parameter_share,
)
from bikerider.gap.measured.multisine import MultisineFit
from bikerider.gap.measured.records import RecordFit

logger = logging.getLogger(__name__)

UNPREDICTED_Z = 1e3
"""Normalised residual given to a held-out point the fitted model cannot predict (singular model).  A
record over whose window the model's simulated response shows no weave the record fit finds is scored
at the nominal model's error instead (the candidate claims no improvement there): the nominal model leaves
such records out where its own prediction is undefined within its parameters' uncertainty, and a candidate
that meets one (Coulomb friction holding the steer at the slowest speed) is not thereby far off everywhere
(SBW logs with SbwBenchmark.txt: four such records put steer friction's held-out error at 225)."""


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


def time_domain(effects: tuple[str, ...]) -> bool:
    """Whether a set of effects is fitted in the time domain (it holds a nonlinear candidate)."""
    return any(e in TIME_DOMAIN_EFFECTS for e in effects)


def obs_rows(problem: GapProblem) -> dict[int, list[int]]:
    """Eigenvalue row -> its observation indices (real part, and imaginary part for a weave)."""
    out: dict[int, list[int]] = {}
    k = 0
    e = problem.eigen
    for row in range(len(e)):
        n = 2 if e.mode[row] == "weave" else 1
        out[row] = list(range(k, k + n))
        k += n
    return out


class Fits:
    """Every fit and cross-validation of the candidates of one diagnosis (a cache, filled on demand).

    Parameters
    ----------
    problem : GapProblem
    records : list of RecordFit
        The diagnosis's records (those left out included).
    record_rows : dict
        Index in ``records`` -> its eigenvalue row, for the records used.
    folds : list of (str, ndarray)
        The held-out folds (:func:`bikerider.gap.diagnosis.folds.folds`).
    multisines : list of MultisineFit, optional
        The diagnosis's multisine records (their rows follow the eigenvalue rows).
    """

    def __init__(
        self,
        problem: GapProblem,
        records: list[RecordFit],
        record_rows: dict[int, int],
        folds: list[tuple[str, np.ndarray]],
        multisines: list[MultisineFit] | None = None,
    ):
        self.problem = problem
        self.records = records
        self.multisines = multisines or []
        self.record_rows = record_rows
        self.folds = folds
        self.full: dict[tuple[str, ...], EffectFit] = {}
        """Fits to all the data, by set of effects (time-domain ones with their jackknife errors)."""
        self.time_domain_full: dict[tuple[str, ...], EffectFit] = {}
        """Time-domain fits to all the data, with or without their jackknife errors yet."""
        self.bias_corrected: dict[tuple[str, ...], EffectFit] = {}
        """Linear fits to all the data by the iterated bias correction alone (before the polish of
        :meth:`GapProblem.fit_apparent`): the held-out folds' fits start from them, as they are fitted
        the same way."""
        self.cv: dict[tuple[str, ...], CrossValidation] = {}
        """Cross-validations, by set of effects."""
        self.corner_shares: dict[tuple, CornerShare] = {}
        """The friction corner's shares of time-domain fits to all the data, by set of effects and values
        (:meth:`corner_share`; worked out on the worker that cross-validates the set, where there are
        workers)."""
        self._predictions: dict[tuple[str, ...], np.ndarray] = {}

    # -- fits to all the data -----------------------------------------------------------------------
    def fit_of(self, effects: tuple[str, ...]) -> EffectFit:
        """The fit of a set of effects to all the data (cached)."""
        effects = tuple(effects)
        if effects not in self.full:
            if time_domain(effects):
                self.full[effects] = self.time_domain_fit(effects, None)
            else:
                # records: the bias-corrected fit polished to the least squares of the apparent eigenvalues
                corrected = self.problem.fit(effects)
                if len(effects) > 1:
                    corrected = self._no_worse_than_its_singles(effects, corrected)
                self.bias_corrected[effects] = corrected
                # a single candidate's fit also searches for other minima of its chi-square; a pair's does not
                # (the pairs' fits would double its cost on the steer-by-wire records: their intervals stay
                # linearised about the polished fit)
                starts = MINIMUM_STARTS if len(effects) == 1 else 0
                polished = self.problem.fit_apparent(corrected, starts=starts)
                # and its intervals are profile-likelihood intervals where that is affordable (few records)
                records = self.problem.records is not None and len(self.problem.record_obs)
                profile = len(effects) == 1 and bool(records) and len(self.problem.record_obs) <= PROFILE_MAX_RECORDS
                self.full[effects] = with_parameter_uncertainty(
                    self.problem, polished, at_fit=len(effects) == 1, profile=profile
                )
        return self.full[effects]

    def _no_worse_than_its_singles(self, effects: tuple[str, ...], fit: EffectFit) -> EffectFit:
        """A linear pair's bias-corrected fit, or the pair held at its singles' values (each effect's own fit
        to all the data) where those values, with their own extraction bias, fit the data better.

        The pair's model at its singles' values is (about) the better single, so a pair's fit worse than
        that has failed: the iterated bias correction assumes the records' extraction bias changes slowly
        with the values, which fails where another mode takes over a model's response (on the SBW records,
        parameters + tyre_slip settled at soft tyres whose 27 rad/s mode the record fit finds in place of
        the weave: chi-square 2e4 against 60 for tyre_slip alone, held-out error 6.7 against 0.75).
        """
        p = self.problem
        if p.records is None or not len(p.record_obs):
            return fit
        singles = {e: self.fit_of((e,)) for e in effects}
        by_name = {}
        for e, single in singles.items():
            by_name.update({(e, n): v for n, v in zip(single.names, single.values)})
        lay = p.layout(effects)
        names = [(e, n) for e, n in lay.structural] + [(PARAMETERS, f"parameters.{k}") for k in p.free][: lay.n_shift]
        if not all(key in by_name for key in names):
            return fit
        x = np.array([by_name[key] for key in names], dtype=float)
        every = np.ones(len(p.obs), bool)
        own = p.own_bias(lay, x)
        chi2 = float(np.sum(p._residuals(lay, every, x, own)[: len(p.obs)] ** 2))
        if not chi2 < fit.chi2:
            return fit
        logger.info(
            "%s: chi-square %.4g at its singles' values against %.4g fitted: held there", effects, chi2, fit.chi2
        )
        # not refitted from there: on the SBW records that refit went into the same trap (chi-square 2.3e4)
        # and cost a third of the pair search's time
        return p.fit_at(effects, x, own, "held at its singles' values (its own fit ended worse)")

    def record_indices(self, mask: np.ndarray | None) -> list[int]:
        """Records whose rows are (all) in the observation mask (every record when None)."""
        rows = obs_rows(self.problem)
        return [k for k, row in self.record_rows.items() if mask is None or all(mask[i] for i in rows[row])]

    def time_domain_fit(
        self, effects: tuple[str, ...], mask: np.ndarray | None, start=None, jackknife: bool = True
    ) -> EffectFit:
        """A time-domain candidate (steer friction, alone or with one linear effect) fitted to the records
        in ``mask`` (:func:`bikerider.gap.inference.timedomain.fit_time_domain`).

        The fit to all the data gets its covariance as the data's share plus the benchmark parameters'
        share (:meth:`parameter_covariance`: their error is common to every record and fold, so the
        data's spread cannot show it) plus the friction corner's share (the law's corner the data do not
        decide: :func:`bikerider.gap.inference.timedomain.corner_share`, two more fits).  The 95 % intervals
        hold each corner's fit within Student's t of the data's and the parameters' shares (the
        Welch-Satterthwaite degrees of freedom of their sum, :func:`interval_quantile`, the parameters'
        share known), mixed over the corner's range (``CornerShare.interval`` of
        :mod:`bikerider.gap.inference.timedomain`: the values move with the corner, seldom linearly).  The
        data's share is

        * with three folds or more, the jackknife over the held-out folds' fits (leave one group out;
          one degree of freedom fewer than the folds): it sees the scatter from session to session;
        * with fewer (a record set of one or two sessions), the fit's own Gauss-Newton covariance
          ``s^2 (J^T J)^-1`` of the time-domain least squares, scaled by its reduced chi-square
          (:func:`bikerider.gap.inference.timedomain.fit_covariance`; degrees of freedom the residuals
          less the fitted values and the records' initial states).  It treats the samples as
          independent and sees no scatter from session to session, so on real records it is far
          narrower than a jackknife (SBW, two sessions: 0.003 N m for ``T_coulomb``, where the
          jackknife over eight puts 0.086): the interval is then mostly the parameters' share.

        The held-out folds' fits (``jackknife`` false) get no covariance: infinite standard errors.
        """

        cached = self.time_domain_full.get(effects) if mask is None else None
        if cached is not None and (not jackknife or np.all(np.isfinite(cached.stderr))):
            return cached
        layout = Layout.of(effects)
        lower, upper = np.array(layout.lower), np.array(layout.upper)
        if cached is not None:
            values, cost, n, success = cached.values, cached.chi2, cached.n, cached.success
        else:
            records = [self.records[k] for k in self.record_indices(mask)]
            fit = fit_time_domain(
                [f.record for f in records], self.problem.nominal, self.problem.geometry, layout, start=start
            )
            values, cost, n, success = fit.values, fit.cost, fit.n_samples, fit.success
        stderr = np.full(values.size, np.inf)
        covariance = spread = corners = known = None
        if mask is None and jackknife:  # the friction's corner, which no fold decides either
            corners = self.corner_share(effects, values)
        if mask is None and jackknife and len(self.folds) >= 3:  # jackknife over the held-out folds' fits
            folds = np.array([f.values for f in self.cross_validate(effects).fits])
            g = len(folds)
            centred = folds - folds.mean(axis=0)
            spread = (g - 1) / g * centred.T @ centred
            # the benchmark parameters' error is common to every fold, so the folds' spread cannot show
            # it: it is counted apart, as the fit's move over their error (its bounds respected); so is
            # the friction corner's
            known = self.parameter_covariance(layout, values)
            covariance = spread + known + corners.covariance
            stderr = np.sqrt(np.diag(covariance))
            data_share, data_dof = spread, g
        elif mask is None and jackknife:  # too few folds for a jackknife: the fit's own Gauss-Newton covariance
            records = [self.records[k].record for k in self.record_indices(None)]
            own = fit_covariance(records, self.problem.nominal, self.problem.geometry, layout, values)
            known = self.parameter_covariance(layout, values)
            covariance = own.covariance + known + corners.covariance
            stderr = np.sqrt(np.clip(np.diag(covariance), 0, None))
            # the data's share rests on a scale estimated from own.dof residuals: interval_quantile's
            # Welch-Satterthwaite sum with that many degrees of freedom (its folds less one)
            data_share, data_dof = own.covariance, own.dof + 1
        ci_low, ci_high = lower.astype(float), upper.astype(float)  # a held-out fold's fit: no interval
        if known is not None:
            # over the corner's whole range: each corner's fit within the data's and the parameters' shares
            # (Student's t of their Welch-Satterthwaite sum), mixed over the corner (CornerShare.interval)
            base = data_share + known
            for k, row in enumerate(np.eye(values.size)):
                half = interval_quantile(row, base, data_share, data_dof) * math.sqrt(max(base[k, k], 0.0))
                ci_low[k], ci_high[k] = corners.interval(k, half, lower[k], upper[k])
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
            jackknife_covariance=spread,
            corners=[] if corners is None else corners.corners,
            corner_covariance=None if corners is None else corners.covariance,
        )
        if mask is None:
            self.time_domain_full[effects] = out
        return out

    def corner_share(self, effects: tuple[str, ...], values: np.ndarray) -> CornerShare:
        """The friction corner's share of the time-domain fit of ``effects`` to all the data at ``values``
        (cached; :func:`bikerider.gap.inference.timedomain.corner_share`)."""
        key = (tuple(effects), tuple(np.asarray(values, float)))
        if key not in self.corner_shares:
            records = [self.records[k].record for k in self.record_indices(None)]
            p = self.problem
            self.corner_shares[key] = corner_share(records, p.nominal, p.geometry, Layout.of(effects), values)
        return self.corner_shares[key]

    def parameter_covariance(self, layout: Layout, values: np.ndarray) -> np.ndarray:
        """Covariance of a time-domain fit's values from the benchmark parameters' uncertainty: the mean
        square of the fit's move over their error, the fit's bounds respected (``G G^T`` where no bound is
        met, ``G`` the fit's response to one standard uncertainty of each parameter;
        :func:`bikerider.gap.inference.timedomain.parameter_share`); zero without free parameters."""
        p = self.problem
        if not p.free:
            return np.zeros((values.size, values.size))
        records = [self.records[k].record for k in self.record_indices(None)]
        sigmas = dict(zip(p.free, (float(s) for s in p.free_sigma)))
        share = parameter_share(records, p.nominal, p.geometry, layout, values, sigmas)
        C = share.covariance
        return C if np.all(np.isfinite(C)) else np.zeros((values.size, values.size))

    def time_domain_predict(self, fit: EffectFit, mask: np.ndarray) -> np.ndarray:
        """Predicted observations of the records in ``mask`` under a time-domain fit: what the record fit
        finds in the candidate's simulated response over each record (indirect inference, as for every
        candidate)."""

        idx = self.record_indices(mask)
        pred = np.full(len(self.problem.obs), np.nan)
        order = list(self.record_rows)
        simulator = self.problem.records.simulator.subset([order.index(k) for k in idx])
        apparent = simulator.apparent_time_domain(Layout.of(fit.effects), fit.values)[0]
        rows = obs_rows(self.problem)
        for j, k in enumerate(idx):
            parts = rows[self.record_rows[k]]
            pred[parts[0]] = apparent[j].real
            if len(parts) > 1:
                pred[parts[1]] = apparent[j].imag
        frf = self.problem.predictor.frf
        if len(frf):  # multisine records: the friction's loop simulated with each record's own torque
            at = slice(len(pred) - 2 * len(frf), len(pred))
            p = self.problem
            whole = predict_frf_friction(
                frf, self.multisines, p.nominal, p.geometry, Layout.of(fit.effects), fit.values
            )
            pred[at] = np.where(mask[at], whole, pred[at])
        return pred

    def predictions(self, effects: tuple[str, ...]) -> np.ndarray:
        """Every observation's prediction by the fit of ``effects`` to all the data (cached): the
        records' apparent eigenvalues (indirect inference; amplitude-dependent in the time domain)."""
        effects = tuple(effects)
        if effects not in self._predictions:
            fit = self.fit_of(effects)
            if time_domain(effects):
                every = np.ones(len(self.problem.obs), bool)
                self._predictions[effects] = self.time_domain_predict(fit, every)
            else:
                self._predictions[effects] = self.problem.predict_fit(fit)
        return self._predictions[effects]

    # -- held out -------------------------------------------------------------------------------------
    def cross_validate(self, effects: tuple[str, ...]) -> CrossValidation:
        """A set of effects fitted on the training folds and scored on each held-out fold (cached)."""
        if effects in self.cv:
            return self.cv[effects]
        p = self.problem
        z_before = p.z(p.baseline)
        z_after = np.full(len(p.obs), np.nan)
        record_rows = np.zeros(len(p.obs), bool)
        if p.records is not None and len(p.record_obs):
            record_rows[p.record_obs.ravel()] = True
        folds, fits = [], []
        timed = time_domain(effects)
        if timed:
            start = None
            if len(effects) > 1 and (STEER_FRICTION,) in self.time_domain_full:  # from the friction alone
                alone = self.time_domain_full[(STEER_FRICTION,)].values
                start = list(alone) + [1.0 if n == "speed_scale" else 0.0 for _, n in Layout.of(effects).names[2:]]
            full = self.time_domain_fit(effects, None, start=start, jackknife=False)
        else:
            full = self.fit_of(effects)
        # every fold starts from the fit to all the data by the same iterated bias correction; the folds'
        # bias corrections advance together
        start = full if timed else self.bias_corrected.get(effects, full)
        together = None if timed else p.fit_many(effects, [~held for _, held in self.folds], start.values, start.bias)
        for k, (name, held) in enumerate(self.folds):
            progress.advance()
            if timed:
                fit = self.time_domain_fit(effects, ~held, start=full.values)
                pred = self.time_domain_predict(fit, held)
            else:
                fit = together[k]
                pred = p.predict_fit(fit)
            fits.append(fit)
            z_fold = p.z(pred)[held]
            # a model that cannot be evaluated (singular) predicts nothing: count it as far off; a record
            # whose simulated response holds no weave: the nominal model's error (UNPREDICTED_Z)
            unpredicted = np.where(np.isfinite(z_fold), 0.0, UNPREDICTED_Z)
            if np.any(np.isfinite(z_fold)):
                unpredicted = np.where(record_rows[held], z_before[held], unpredicted)
            z_after[held] = np.where(np.isfinite(z_fold), z_fold, unpredicted)
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
            effects=effects,
            folds=folds,
            z_before=z_before[held_any],
            z_after=z_after[held_any],
            error_before=rms(z_before[held_any]),
            error_after=rms(z_after[held_any]),
            shrink=gap_shrink(z_before[held_any], z_after[held_any]),
            fits=fits,
        )
        data_sigma = np.sqrt(p.var_data)[held_any]
        if np.all(data_sigma > 0):
            scale = np.sqrt(p.var_total)[held_any] / data_sigma
            zb, za = z_before[held_any] * scale, z_after[held_any] * scale
            result.data_before, result.data_after, result.data_shrink = rms(zb), rms(za), gap_shrink(zb, za)
        self.cv[effects] = result
        return result


PARAMETER_TAIL = 0.01
"""Share of the parameters' part of a linear fit's covariance (by the nominal slopes) whose parameters keep
their nominal slopes in :func:`with_parameter_uncertainty`; the others are taken at the fit."""


def with_parameter_uncertainty(p: GapProblem, fit: EffectFit, at_fit: bool = True, profile: bool = False) -> EffectFit:
    """A linear fit's covariance and 95 % intervals with the benchmark parameters' uncertainty as the
    systematic error it is, holding every local minimum the data cannot tell from the fit.

    The fit weighs each residual by the combined variance of data and parameters, as if the
    parameters' share were independent from row to row; but one parameter error moves every row at
    once, and does not average out over the rows.  The covariance of the fitted values is the sandwich
    ``B A^T C A B`` (``A`` the weighted Jacobian of the predictions in the fitted values, ``B =
    (A^T A)^-1``, ``C`` the weighted covariance of the observations: the data's variance plus
    ``J_p J_p^T`` of the parameters' slopes per sigma), times the reduced chi-square ``s^2`` when above
    one (lack of fit).  Fits holding ``parameters`` fit the shifts themselves and keep their own.

    The quantile.  Scaled by ``s^2``, the covariance rests on a scale estimated from the ``n - p``
    residuals, so the 95 % interval is ``+- t_{n-p}(0.975)`` standard errors (Student's t), not
    ``+- 1.96``, which holds only for a scale known in advance
    (:func:`bikerider.gap.inference.problem.scale_and_quantile`; a record set of six weave records fitted
    with three sizes has 9 degrees of freedom: 2.26).

    Other minima.  An interval linearised about one minimum cannot hold another of nearly the same
    depth (:meth:`GapProblem.fit_apparent` finds them).  A minimum whose chi-square lies within the 95 %
    profile-likelihood threshold of the fit's, ``chi2 - chi2_fit <= q^2 max(1, s^2)`` (``q`` the quantile
    above: 3.84 for a known scale; the F(1, n - p) point with an estimated one), cannot be rejected
    by the data, so each size's 95 % interval is the hull of the fit's and of every such minimum's
    own linearised interval (its sandwich at its values, scaled by the fit's ``s^2``), an approximation
    of the profile-likelihood interval whose region holds both.  ``EffectFit.minima_within`` counts them.
    The same holds for any point whose chi-square lies within the threshold (the profile at each of its
    sizes is at most that chi-square), so the interval also holds every point the search for minima
    stepped to within it (``EffectFit.visited``): where the chi-square is a long curved valley, more of
    the valley than the fit's linearisation reaches.

    The parameters' slopes.  ``J_p`` is taken at the fitted values (``at_fit``, the default;
    :meth:`GapProblem.parameter_jacobian_at`), not at the nominal model: an effect that moves the bicycle
    far from it changes how each parameter moves the predictions (a steer inertia of the steer assembly's
    own size made the share four times the nominal slopes', and the calibration's steer-inertia misses
    were the bicycle parameters' error: the same trials with the nominal bicycle were covered).  Only
    the parameters carrying all but :data:`PARAMETER_TAIL` of the share by the nominal slopes are
    evaluated there (about half of them); the rest keep their nominal slopes.  A pair's fit keeps the
    nominal slopes (``at_fit=False``), as its fit is not searched for other minima: the steer-by-wire
    diagnosis is at its time goal (the single candidates' secants took its processor time 16.2 -> 17.3 s).

    The rider's geometry.  Where the effects use it (the passive arms the grips, the rider's lean the
    upper body: :func:`bikerider.gap.candidates.effect_model.geometry_keys`), its stated uncertainty
    (:attr:`bikerider.gap.candidates.effect_model.RiderGeometry.uncertainty`) is a systematic error
    like the parameters', one more term ``(A^T J_g)(J_g^T A)`` in the sandwich's middle, ``J_g`` the
    predictions' secants per sigma of each source at the fitted values
    (:meth:`GapProblem.geometry_jacobian`; at the nominal model, without the rider's effects, the
    geometry moves nothing).  The fit's own weights do not hold it (it would be zero there).

    With rows from records the fit to all the data is the least squares of the apparent eigenvalues
    (indirect inference, :meth:`GapProblem.fit_apparent`), so ``A`` holds the apparent eigenvalues'
    slopes, not the weave eigenvalues'.

    The profile (``profile``; :meth:`Fits.fit_of` asks for it for a single candidate's fit on at most
    :data:`bikerider.gap.inference.problem.PROFILE_MAX_RECORDS` records).  The interval linearised about the
    fit, and the hull of the points searched, hold the chi-square's valley only as far as its linearisation
    and the searches reach (the tyres' relaxation length and the rider's lean damping, whose valleys are long
    and curved, were missed on the far side).  With ``profile`` the data's share of each size's interval is
    its profile-likelihood interval instead: where the profile chi-square (the chi-square minimised over the
    other sizes at each value of this one, :meth:`GapProblem.profile_apparent`) rises ``q^2 max(1, s^2)
    D_kk / B_kk`` above the fit's, on each side.  ``B = (A^T A)^-1`` is the inverse of the chi-square's own
    curvature and ``D = B A^T diag(var_data / var_total) A B`` the sandwich's data share: the chi-square
    weighs each row by the data's and the parameters' variance together, as if the parameters' error were
    independent from row to row, so its curvature is not the data's share, and a profile to the plain
    threshold ``q^2 max(1, s^2)`` would count the parameters' share once as row-wise noise and again below.
    Scaled so, the rise is the data's own likelihood-ratio statistic (the magnitude adjustment of a
    misspecified likelihood's ratio test for one size: Kent 1982, Biometrika 69, 19-27; Varin, Reid and Firth
    2011, Statistica Sinica 21, 5-42), and where the chi-square is quadratic the profile's reach is exactly
    the data share's ``q sqrt(max(1, s^2) D_kk)``.  The shares the chi-square cannot see, the benchmark
    parameters' and the rider geometry's (``S - D``, common to every row: a systematic shift of the fit,
    linearised as above), are added to each side's reach in quadrature: ``x - sqrt((x - low)^2 + q^2 max(1,
    s^2) (S - D)_kk)`` and its mirror, ``S`` the sandwich.  Each share is so counted once, the interval is the
    sandwich interval where the chi-square is quadratic, and it follows the valley's own shape where it is
    not.  Other minima and visited points within ``q^2 max(1, s^2)`` widen it as above.  A size whose profile
    ends are not found keeps the linearised interval; ``EffectFit.profiled`` names the sizes profiled.
    """
    if PARAMETERS in fit.effects or not fit.names or not len(p.obs):
        return fit
    lay = p.layout(fit.effects)
    geometric = bool(geometry_keys(fit.effects)) and bool(p.geometry_sources(lay))
    if not p.free and not geometric:
        return fit
    x = np.asarray(fit.values, float)
    lower, upper = np.asarray(fit.lower, float), np.asarray(fit.upper, float)
    cov, bread, data = _sandwich(p, lay, x, lower, upper, geometric, at_fit, bread=True)
    if cov is None:
        return fit
    factor, quantile = scale_and_quantile(fit.chi2, fit.n, x.size)
    threshold = quantile**2 * factor
    known = np.isfinite(fit.stderr)  # a value the data do not move stays so
    stderr = np.where(known, np.sqrt(np.clip(np.diag(cov) * factor, 0, None)), np.inf)
    low = np.clip(x - quantile * stderr, lower, upper)
    high = np.clip(x + quantile * stderr, lower, upper)
    profiled = np.zeros(x.size, bool)
    if profile:
        # the data's share by the profile, its threshold scaled by the data's variance over the chi-square's
        # own (D_kk / B_kk); the parameters' and the geometry's shares, which the chi-square cannot see, added
        # to each side's reach in quadrature
        with np.errstate(all="ignore"):
            targets = np.where(known, threshold * np.diag(data) / np.diag(bread), np.nan)
        ends = p.profile_apparent(fit, targets, bread)
        profiled = known & np.isfinite(ends.low) & np.isfinite(ends.high)
        systematic = threshold * np.clip(np.diag(cov) - np.diag(data), 0, None)
        with np.errstate(invalid="ignore"):
            reach_low = np.sqrt((x - ends.low) ** 2 + systematic)
            reach_high = np.sqrt((ends.high - x) ** 2 + systematic)
        low = np.where(profiled, np.clip(x - reach_low, lower, upper), low)
        high = np.where(profiled, np.clip(x + reach_high, lower, upper), high)
    cov = cov * factor
    held = [chi2 - fit.chi2 <= threshold for _values, chi2 in fit.minima]
    within = [m for m, ok in zip(fit.minima, held) if ok]
    for values, _chi2 in within:
        other = _sandwich(p, lay, values, lower, upper, geometric, at_fit)
        spread = np.sqrt(np.clip(np.diag(other), 0, None) * factor) if other is not None else np.zeros(x.size)
        spread = np.where(known, spread, np.inf)
        low = np.minimum(low, np.clip(values - quantile * spread, lower, upper))
        high = np.maximum(high, np.clip(values + quantile * spread, lower, upper))
    # every point the search visited within the threshold lies in each size's profile-likelihood interval
    # (the profile at its value is at most its chi-square): the interval holds it
    near = [values for values, chi2 in fit.visited if chi2 - fit.chi2 <= threshold]
    if near:
        low, high = np.minimum(low, np.min(near, axis=0)), np.maximum(high, np.max(near, axis=0))
    minima = within + [m for m, ok in zip(fit.minima, held) if not ok]
    return replace(
        fit,
        stderr=stderr,
        ci_low=low,
        ci_high=high,
        covariance=cov,
        minima=minima,
        minima_within=len(within),
        profiled=[n for n, ok in zip(fit.names, profiled) if ok],
    )


def _sandwich(
    p: GapProblem,
    lay,
    x: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    geometric: bool = False,
    at_fit: bool = True,
    bread: bool = False,
):
    """The sandwich covariance of :func:`with_parameter_uncertainty` at values ``x``, before the reduced
    chi-square's scale (``None`` where a slope cannot be evaluated); with ``geometric``, the rider
    geometry's share included; with ``at_fit``, the parameters' slopes taken at ``x``.  With ``bread``,
    ``(covariance, B, data)``: ``B = (A^T A)^-1`` the inverse of the fit's chi-square's own Gauss-Newton
    curvature, ``data`` the data's share of the covariance (``(None, None, None)`` where a slope cannot be
    evaluated)."""
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
    # rows from records are predicted by indirect inference, and the fit to all the data is the least
    # squares of the apparent eigenvalues (GapProblem.fit_apparent): it solves A_i^T (apparent - y) = 0
    # with the apparent eigenvalues' slopes A_i, which a short record's fit can make several times
    # flatter than the weave eigenvalues'; the sandwich's bread is (A_i^T A_i)^-1
    records = p.records is not None and len(p.record_obs)
    A = slopes(bool(records)) / w[:, None]
    if not np.all(np.isfinite(A)):
        return (None, None, None) if bread else None
    B = np.linalg.pinv(A.T @ A)
    # the parameters' slopes at these values (an effect that moves the bicycle far from the nominal model
    # changes how each parameter moves the predictions: steer inertia of the steer assembly's own size made
    # the share four times the nominal slopes'), for the parameters that carry all but PARAMETER_TAIL of
    # the share by the nominal slopes; the others keep their nominal slopes
    Jp = p.jacobian / w[:, None]
    if at_fit and Jp.shape[1]:
        share = np.sum((B @ (A.T @ Jp)) ** 2, axis=0)
        order = np.argsort(-share, kind="stable")
        total = float(np.sum(share))
        count = int(np.searchsorted(np.cumsum(share[order]), (1 - PARAMETER_TAIL) * total)) + 1 if total > 0 else 0
        if count:
            Jp = p.parameter_jacobian_at(lay, x, indirect=bool(records), columns=np.sort(order[:count])) / w[:, None]
    AC = A.T * (p.var_data / p.var_total)
    data = AC @ A
    meat = data + (A.T @ Jp) @ (Jp.T @ A)
    if geometric:  # the rider geometry's uncertainty: its slopes at these values, per sigma
        Jg = p.geometry_jacobian(lay, x, indirect=bool(records)) / w[:, None]
        bad = ~np.all(np.isfinite(Jg), axis=0)
        if np.any(bad):  # a shifted geometry whose model cannot be evaluated: that source left out, said
            names = [n for n, b in zip(p.geometry_sources(lay), bad) if b]
            logger.warning("%s: no slope in the rider geometry's %s; left out of the interval", lay.effects, names)
            Jg = Jg[:, ~bad]
        meat = meat + (A.T @ Jg) @ (Jg.T @ A)
    return (B @ meat @ B.T, B, B @ data @ B.T) if bread else B @ meat @ B.T
