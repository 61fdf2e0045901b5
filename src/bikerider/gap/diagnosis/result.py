"""Where, whether, which and how far: the sim-to-real gap diagnosis.

Where.  Every measured scalar's residual (measured minus nominal model) is divided by the combined
standard uncertainty of data and model parameters (:mod:`bikerider.gap.inference.problem`); residuals
are summarised in a gap map by mode (weave, capsize, castor, or identified canonical entries), speed
band and quantity (real part, imaginary part, entry), each cell with its chi-square and p-value.

Whether.  The whole gap is tested with the full covariance, ``chi2 = r^T (D + J J^T)^-1 r`` with ``n``
degrees of freedom, and against the data's noise alone, ``r^T D^-1 r``.  Not significant at
:data:`~bikerider.gap.diagnosis.statistics.ALPHA` against either: verdict ``none``.  Significant against
the data alone but within the combined uncertainty: the parameters' uncertainty covers the gap, verdict
``parameters``.  Otherwise the benchmark parameters are fitted with their uncertainties as a Gaussian
prior (maximum a posteriori); if the fitted model passes the same test (data plus prior chi-square,
``n`` degrees of freedom) plausible parameter errors explain the gap (``parameters``), else it is
``structural``. With verdict ``parameters`` the parameter fit is selected when it is plausible; when it
needs implausible shifts the candidates are compared as for a structural gap.

Which.  Folds are the data's groups (runs, riders, environments; more than
:data:`~bikerider.gap.diagnosis.folds.MAX_FOLDS` groups are held out in blocks of whole groups), or, for
a single group, contiguous speed bands; never random points.  Every candidate is fitted on the training
folds and scored on the held-out fold; the held-out error is the root mean square of the normalised
residuals over all held-out points.  Candidates are ranked by it; a candidate within
:data:`~bikerider.gap.diagnosis.statistics.TIE_RELATIVE` of a better one, or not significantly better at
:data:`~bikerider.gap.diagnosis.statistics.TIE_P`, is tied with it, and within a tie the candidate with
fewer fitted parameters ranks first (Occam); a candidate that holds a simpler one as a special case is
tied with it when its fit does not exclude the values that make it so
(:func:`~bikerider.gap.diagnosis.which.undetermined_extra`). "Better" is a paired bootstrap of the held-out points' RMS
error (:func:`~bikerider.gap.diagnosis.statistics.significantly_better`). Pairs are cross-validated as
well (fitted jointly on the same folds): every pair of candidates that each, alone, predict the held-out
folds better than the nominal model (by more than 1 %; an effect that makes the held-out predictions
worse on its own is not searched further).

Usual, and priors.  Every fitted value of a candidate (fitted to all the data) has a usual range (the
literature's, or the bicycle's own ``[plausible]`` table) and a prior with its source
(:class:`bikerider.gap.candidates.effects.Prior`; the ``[plausible]`` range made a prior).  A value
outside its usual range is flagged ("above the usual ... from ...: check ..."), never refused: only what
is physically impossible (negative damping, mass, inertia) is a bound of the fit.  A value is usable when
the data determine it (its standard error no larger than the width of its usual range) and it is not
pinned at the edge of the search.  A candidate is ``plausible`` when every value is usual and usable;
``parameters`` when its shifts pass their prior test (chi-square at 1 %) with none pinned at a bound.

Selection (structural verdict).  The evidence for a set of effects is its held-out log-likelihood,
``-sum(z^2) / (2 s^2)`` over the held-out points, plus the log prior ratio of its fitted values (``ln
p(value) - ln p(mode)``, :meth:`~bikerider.gap.diagnosis.priors.Priors.log_prior`): roughly the log
posterior odds against the nominal model, whose evidence is ``-sum(z_nominal^2) / (2 s^2)``.  ``s^2`` is
the lack of fit, the smallest mean held-out ``z^2`` of any candidate or pair, at least 1
(:func:`~bikerider.gap.diagnosis.select.lack_of_fit`).  A candidate is eligible when it beats the nominal
model significantly on the held-out folds, its log posterior odds against it are positive, and its
values are usable or it explains the held-out data to the noise floor (so "structural, selected nothing"
never stands beside a candidate at the noise floor).  The first eligible single of the ranking is
selected, unless another eligible single's evidence is higher by more than
:data:`~bikerider.gap.diagnosis.select.PRIOR_ODDS` (19 to 1). A pair replaces it when the single leaves
a gap above the noise floor (held-out RMS error against the data's noise above one) and an eligible pair
beats it significantly with more evidence.  The values outside their usual range are flagged in the
selection; the best held-out fit that is not selected is named with what it needs
(``best_implausible``).

How far.  For the selection, the held-out error before and after per fold and overall, and the fraction
of the gap above the noise floor removed: with ``G = mean(z^2) - 1`` (the noise floor of normalised
residuals is ``E[z^2] = 1``), ``shrink = (G_before - G_after) / G_before``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from bikerider import progress
from bikerider.errors import InputError
from bikerider.gap.blas_threads import single_blas_thread
from bikerider.gap.candidates.effects import EFFECT_NAMES, PARAMETERS
from bikerider.gap.candidates.nominal import GapModelInput
from bikerider.gap.diagnosis.compare import compare_multisines, compare_records, not_applicable
from bikerider.gap.diagnosis.fits import CrossValidation, Fits, obs_rows
from bikerider.gap.diagnosis.folds import folds
from bikerider.gap.diagnosis.priors import (
    Priors,
    inferred_steer_rate_amplitudes,
    steer_rate_amplitudes,
    unsteered_records,
)
from bikerider.gap.diagnosis.select import select
from bikerider.gap.diagnosis.statistics import _minima, _named_values, by_error, noise_floor_rms
from bikerider.gap.diagnosis.where import gap_map, gap_test, whether
from bikerider.gap.diagnosis.which import rank, search_pairs
from bikerider.gap.inference.problem import EffectFit, GapProblem
from bikerider.gap.measured.multisine import MultisineFit
from bikerider.gap.measured.records import RecordFit
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData

__all__ = ["CrossValidation", "Diagnosis", "diagnose"]


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """The diagnosis of one bicycle's data (:func:`diagnose`); everything as plain values in :meth:`as_dict`.

    Attributes
    ----------
    model_input : GapModelInput
    records : list of RecordFit
        Copies of the records given; those left out carry their reason.
    record_rows : dict
        Index in ``records`` -> its eigenvalue row, for the records used.
    multisines : list of MultisineFit
        Copies of the multisine records given; those left out carry their reason.
    bias : ndarray
        Each record row's extraction bias under the nominal model (complex).
    problem : GapProblem
        The observations, the nominal model's predictions and their uncertainty.
    effects, candidates : list of str
        The effects asked for, and those the data can try (the others in ``not_applicable`` with why).
    not_applicable : dict
    folds : list of (str, ndarray)
        The held-out folds (name, mask of observations).
    gap_map : list of dict
    gap_test : dict
    parameter_fit : EffectFit or None
        The benchmark parameters fitted as shifts (when ``parameters`` is a candidate).
    parameter_test : dict or None
    verdict : str
        ``none``, ``parameters`` or ``structural``.
    ranking : list of dict
        The single candidates, best first.
    pairs : list of CrossValidation
        The pairs searched on the held-out folds.
    priors : Priors
        The usual ranges and priors the fitted values are judged against.
    selected : list of str
    selection : dict
    best_implausible, best_single_implausible : dict or None
    selected_fit : EffectFit or None
    elapsed : float
        Seconds the diagnosis took.
    fits : Fits
        Every fit and cross-validation made (a cache that :func:`bikerider.gap.plan.ranking.plan_next`
        may extend).
    """

    model_input: GapModelInput
    records: list[RecordFit]
    record_rows: dict[int, int]
    multisines: list[MultisineFit]
    bias: np.ndarray
    problem: GapProblem
    effects: list[str]
    candidates: list[str]
    not_applicable: dict[str, str]
    folds: list[tuple[str, np.ndarray]]
    gap_map: list[dict]
    gap_test: dict
    parameter_fit: EffectFit | None
    parameter_test: dict | None
    verdict: str
    ranking: list[dict]
    pairs: list[CrossValidation]
    priors: Priors
    selected: list[str]
    selection: dict
    best_implausible: dict | None
    best_single_implausible: dict | None
    selected_fit: EffectFit | None
    elapsed: float
    fits: Fits

    @property
    def cv(self) -> dict[tuple[str, ...], CrossValidation]:
        """Every cross-validation made, by set of effects."""
        return self.fits.cv

    @property
    def full_fits(self) -> dict[tuple[str, ...], EffectFit]:
        """Every fit to all the data made, by set of effects."""
        return self.fits.full

    def fit_of(self, effects: tuple[str, ...]) -> EffectFit:
        """The fit of a set of effects to all the data (cached in :attr:`fits`)."""
        return self.fits.fit_of(effects)

    def cross_validate(self, effects: tuple[str, ...]) -> CrossValidation:
        """The cross-validation of a set of effects (cached in :attr:`fits`)."""
        return self.fits.cross_validate(effects)

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
        pred = self.fits.predictions(tuple(self.selected))
        out = np.full(len(self.problem.eigen), np.nan + 1j * np.nan)
        for row, parts in obs_rows(self.problem).items():
            if row in self.record_rows.values():
                out[row] = complex(pred[parts[0]], pred[parts[1]] if len(parts) > 1 else 0.0)
        return out - self.nominal_bias_per_row()

    def as_dict(self) -> dict:
        """Everything, as plain JSON-ready values."""
        return as_dict(self)


@single_blas_thread
def diagnose(
    model: GapModelInput,
    eigen: EigenvalueData | None = None,
    canonical: CanonicalData | None = None,
    effects=EFFECT_NAMES,
    records: list[RecordFit] | None = None,
    multisines: list[MultisineFit] | None = None,
) -> Diagnosis:
    """Run the diagnosis of one bicycle's data (the module docstring): where, whether, which, priors,
    selection, in that order (the candidates' cross-validation, the first part of "which", runs before
    the verdict, because the parameter fit the verdict needs is made with them on the worker processes).

    Parameters
    ----------
    model : GapModelInput
    eigen : EigenvalueData, optional
        Eigenvalue rows from tables.
    canonical : CanonicalData, optional
    effects : sequence of str, optional
        Candidates (default: all of :data:`~bikerider.gap.candidates.effects.EFFECT_NAMES`).
    records : list of RecordFit, optional
        Fitted records (:func:`bikerider.gap.measured.records.fit_records`); those fitted become eigenvalue
        rows, which every model predicts by indirect inference (:mod:`bikerider.gap.inference.indirect`), and
        the others are left out with their reason.
    multisines : list of MultisineFit, optional
        Fitted steer-torque multisine records (:func:`bikerider.gap.measured.multisine.fit_multisines`);
        those used become frequency-response rows at their lines, compared with each candidate's
        closed-loop response (steer friction: its loop simulated with the record's own torque).

    Raises
    ------
    InputError
        When no observation remains (every record left out): too few records for a diagnosis.
    """
    start = time.perf_counter()
    eigen = eigen if eigen is not None else EigenvalueData.empty()
    canonical = canonical if canonical is not None else CanonicalData.empty()
    compared = compare_records(model, eigen, records)
    if multisines:
        kept, frf = compare_multisines(model, multisines)
        compared = replace(compared, multisines=kept, frf=frf)
    if len(compared.eigen) + len(canonical) + len(compared.frf) == 0:
        _no_data(compared.records + compared.multisines)
    progress.begin("the model's uncertainty at every observation")
    problem = GapProblem(model, compared.eigen, canonical, records=compared.record_set, frf=compared.frf)
    effects = list(effects)
    skipped = not_applicable(effects, model, compared, problem)
    candidates = [e for e in effects if e not in skipped]
    held = folds(problem.obs)
    fits = Fits(problem, compared.records, compared.record_rows, held, compared.multisines)
    # where
    where_map, test = gap_map(problem), gap_test(problem)
    # which (the ranking first: the parameter fit the verdict needs is made there, on a worker; the
    # ranking needs nothing from the verdict)
    ranking, pairs = (rank(fits, candidates) if len(held) >= 2 else []), []
    # whether
    parameter_fit = fits.fit_of((PARAMETERS,)) if PARAMETERS in candidates else None
    verdict = whether(test, parameter_fit, problem)
    # which: the pairs
    if len(held) >= 2:
        pairs = search_pairs(fits, candidates)
    for e in candidates:
        fits.fit_of((e,))
    # priors
    measured = steer_rate_amplitudes(compared.records, compared.record_rows)
    unsteered = unsteered_records(compared.records, compared.record_rows)
    amplitudes = np.concatenate([measured, inferred_steer_rate_amplitudes(unsteered, problem)])
    priors = Priors(model.plausible, amplitudes, len(held), problem, tuple(unsteered))
    # selection
    progress.begin("selecting")
    chosen = select(verdict.verdict, candidates, ranking, pairs, fits, priors)
    selected_fit = fits.fit_of(tuple(chosen.selected)) if chosen.selected else None
    return Diagnosis(
        model_input=model,
        records=compared.records,
        record_rows=compared.record_rows,
        multisines=compared.multisines,
        bias=compared.bias,
        problem=problem,
        effects=effects,
        candidates=candidates,
        not_applicable=skipped,
        folds=held,
        gap_map=where_map,
        gap_test=test,
        parameter_fit=parameter_fit,
        parameter_test=verdict.parameter_test,
        verdict=verdict.verdict,
        ranking=ranking,
        pairs=pairs,
        priors=priors,
        selected=chosen.selected,
        selection=chosen.selection,
        best_implausible=chosen.best_implausible,
        best_single_implausible=chosen.best_single_implausible,
        selected_fit=selected_fit,
        elapsed=time.perf_counter() - start,
        fits=fits,
    )


def _no_data(records: list) -> None:
    """Raise the error of a diagnosis left without observations."""
    if not records:
        raise InputError("data", "empty", "at least one measured eigenvalue or identified entry")
    left = [f for f in records if not f.used]
    reasons = "; ".join(f"{f.record.name}: {f.reason}" for f in left[:3]) + (" ..." if len(left) > 3 else "")
    raise InputError(
        "data",
        f"{len(left)} of {len(records)} records left out",
        f"enough records for a diagnosis: none could be used ({reasons})",
    )


FEW_FOLDS_FRICTION = (
    "steer friction fitted to fewer than three groups: its intervals hold the records' own scatter and the "
    "parameters' uncertainty, not the scatter from session to session (three groups or more give a jackknife "
    "that sees it; on the steer-by-wire records it was about 30 times the fit's own): record a third session "
    "before trusting its size"
)
"""The note of a diagnosis whose steer friction got its data's share of the covariance from the fit itself
(:meth:`bikerider.gap.diagnosis.fits.Fits.time_domain_fit`), not from a jackknife over the folds."""


def as_dict(d: Diagnosis) -> dict:
    """A diagnosis as plain JSON-ready values."""
    p = d.problem
    judge = d.priors
    ranking = []
    for entry in d.ranking:
        fit = d.fit_of((entry["effect"],))
        plausible, checks = judge.plausibility(fit)
        ranking.append(
            {
                **{k: entry[k] for k in ("rank", "effect")},
                "parameters": _named_values(fit),
                "other_minima": _minima(fit),
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
                "equivalent": judge.friction_equivalent(fit),
            }
        )
    pairs = []
    for r in by_error(d.pairs, p):
        entry = {
            "effects": list(r.effects),
            "heldout_error_before": r.error_before,
            "heldout_error_after": r.error_after,
            "shrink": r.shrink,
            "data_error_after": r.data_after,
            "data_shrink": r.data_shrink,
        }
        fit = d.fit_of(r.effects)
        ok, checks = judge.plausibility(fit)
        entry.update(
            {
                "plausible": ok,
                "parameters": _named_values(fit),
                "other_minima": _minima(fit),
                "plausibility": checks,
                "equivalent": judge.friction_equivalent(fit),
            }
        )
        pairs.append(entry)
    out = {
        "verdict": d.verdict,
        "gap": {"test": d.gap_test, "map": d.gap_map},
        "parameter_fit": None,
        "ranking": ranking,
        "pairs": pairs,
        "selected": list(d.selected),
        "selection": d.selection,
        "best_implausible": d.best_implausible,
        "best_single_implausible": d.best_single_implausible,
        "how_far": None,
        "not_applicable": d.not_applicable,
        "folds": [name for name, _ in d.folds],
        "n_observations": len(p.obs),
        "noise_floor_rms": noise_floor_rms(len(p.obs)) if len(d.folds) >= 2 else None,
        "records": _records_summary(d),
        "noise": p.noise,
        "uncertainty": _uncertainty_summary(p),
        "laws": {name: law.describe() for name, law in p.eigen.laws.items()},
        "notes": list(p.notes)
        + ([] if len(d.folds) >= 2 else ["fewer than two folds (groups or speeds): no held-out ranking"])
        + ([FEW_FOLDS_FRICTION] if d.fits.time_domain_full and len(d.folds) < 3 else []),
        "model": {
            "source": p.model_input.source,
            "geometry": p.geometry.notes,
            "uncertain_parameters": p.free,
            # the rider geometry's sources of uncertainty: name -> shift of each value per sigma (SI)
            "geometry_uncertainty": {name: dict(shift) for name, shift in p.geometry.uncertainty.items()},
        },
        "elapsed_s": d.elapsed,
    }
    if d.parameter_fit is not None:
        fit = d.parameter_fit
        plausible, checks = judge.plausibility(fit)
        out["parameter_fit"] = {
            "shift": fit.shift,
            "shift_in_sigma": dict(zip(p.free, map(float, fit.values))),
            "test": d.parameter_test,
            "plausible": plausible,
            "at_bound": checks[0]["at_bound"],
        }
    if d.selected and len(d.folds) >= 2:
        cv = d.cross_validate(tuple(d.selected))
        fit = d.selected_fit
        out["how_far"] = {
            "effects": list(d.selected),
            "folds": cv.folds,
            "heldout_error_before": cv.error_before,
            "heldout_error_after": cv.error_after,
            "shrink": cv.shrink,
            "data_error_before": cv.data_before,
            "data_error_after": cv.data_after,
            "data_shrink": cv.data_shrink,
            "parameters": _named_values(fit) if fit else {},
            "other_minima": _minima(fit),
            "equivalent": judge.friction_equivalent(fit) if fit else None,
        }
    return out


def _uncertainty_summary(p: GapProblem) -> dict:
    """Typical data and parameter standard uncertainties, and the parameters contributing most."""
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


def _records_summary(d: Diagnosis) -> dict | None:
    """The records used, repaired and left out (with why), and each one's summary."""
    if not d.records and not d.multisines:
        return None
    rows = list(d.record_rows)
    out = []
    for k, f in enumerate(d.records):
        entry = f.summary()
        if k in d.record_rows:
            b = d.bias[rows.index(k)]
            entry["bias"] = [float(b.real), float(b.imag)]
        out.append(entry)
    out += [f.summary() for f in d.multisines]  # kind "multisine"
    used = sum(1 for e in out if e["used"])
    return {
        "total": len(out),
        "used": used,
        "left_out": len(out) - used,
        "reasons": [{"record": e["record"], "reason": e["reason"]} for e in out if not e["used"]],
        "repaired": [{"record": e["record"], "repairs": e["repairs"]} for e in out if e["used"] and e["repairs"]],
        "list": out,
    }
