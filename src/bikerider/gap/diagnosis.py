"""Where, whether, which and how far: the sim-to-real gap diagnosis.

Where.  Every measured scalar's residual (measured minus nominal model) is divided by the combined
standard uncertainty of data and model parameters (:mod:`bikerider.gap.fit`); residuals are
summarised in a gap map by mode (weave, capsize, castor, or identified canonical entries), speed
band and quantity (real part, imaginary part, entry), each cell with its chi-square and p-value.

Whether.  The whole gap is tested with the full covariance, ``chi2 = r^T (D + J J^T)^-1 r`` with
``n`` degrees of freedom.  A gap below :data:`ALPHA` gives the verdict ``none``.  Otherwise the
benchmark parameters are fitted with their uncertainties as a Gaussian prior (maximum a
posteriori); if the fitted model passes the same test (data plus prior chi-square, ``n`` degrees
of freedom) plausible parameter errors explain the gap (``parameters``), else it is ``structural``.

Which.  Folds are the data's groups (runs, riders, environments), or, for a single group, contiguous
speed bands; never random points.  Every candidate is fitted on the training folds and scored on
the held-out fold; the held-out error is the root mean square of the normalised residuals over all
held-out points.  Candidates are ranked by it; a candidate within :data:`TIE_RELATIVE` of a better
one, or not significantly better at :data:`TIE_P`, is
tied with it, and within a tie the candidate with fewer fitted parameters ranks first (Occam).
"Better" is a paired bootstrap of the held-out points' RMS error (:func:`significantly_better`).
For a structural gap, effects are added greedily (each round the best-ranked candidate fitted
jointly with those already chosen) while the held-out error improves significantly (the same
paired test, and by more than :data:`TIE_RELATIVE`).

How far.  For the selection, the held-out error before and after per fold and overall, and the
fraction of the gap above the noise floor removed: with ``G = mean(z^2) - 1`` (the noise floor of
normalised residuals is ``E[z^2] = 1``), ``shrink = (G_before - G_after) / G_before``.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np

from bikerider.gap.data import CanonicalData, EigenvalueData
from bikerider.gap.effects import EFFECT_NAMES, EFFECTS, LITERATURE_EXTRA
from bikerider.gap.fit import EffectFit, GapProblem
from bikerider.gap.model_input import GapModelInput

LOG = logging.getLogger(__name__)

ALPHA = 0.01
"""Significance level of the gap tests."""
TIE_RELATIVE = 0.05
"""Held-out errors closer than this fraction of the better one are a tie."""
TIE_P = 0.05
"""One-sided p-value a better held-out error must reach to break a tie."""
MAX_SELECTED = 3
"""Most effects the greedy selection adds."""
N_SPEED_BANDS = 3
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
    """

    effects: tuple[str, ...]
    folds: list[dict]
    z_before: np.ndarray
    z_after: np.ndarray
    error_before: float
    error_after: float
    shrink: float | None
    fits: list[EffectFit] = field(default_factory=list)


def rms(z: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(z)))) if z.size else math.nan


def gap_shrink(z_before: np.ndarray, z_after: np.ndarray) -> float | None:
    """``(G_before - G_after) / G_before`` with ``G = mean(z^2) - 1``; ``None`` when ``G_before <= 0``."""
    g_before = float(np.mean(np.square(z_before))) - 1.0
    g_after = float(np.mean(np.square(z_after))) - 1.0
    if not g_before > 0:
        return None
    return (g_before - max(g_after, 0.0)) / g_before


N_BOOTSTRAP = 2000
"""Resamples of the paired bootstrap in :func:`significantly_better`."""


def significantly_better(z_better: np.ndarray, z_worse: np.ndarray) -> tuple[bool, float]:
    """Whether held-out residuals ``z_better`` beat ``z_worse``; returns (significant, p).

    Paired bootstrap over the held-out points (:data:`N_BOOTSTRAP` resamples, fixed seed): ``p`` is
    the fraction of resamples in which the RMS of ``z_better`` is not below that of ``z_worse``.
    Significant when ``p <`` :data:`TIE_P` and the RMS error is lower by more than
    :data:`TIE_RELATIVE`.  Points of one fold share a fit, so the test is optimistic about
    independence; it is a screening rule, not an exact test.
    """
    a, b = np.square(z_better), np.square(z_worse)
    n = a.size
    if n < 3:
        return False, 1.0
    index = np.random.default_rng(0).integers(0, n, size=(N_BOOTSTRAP, n))
    p = float(np.mean(a[index].sum(axis=1) >= b[index].sum(axis=1)))
    return p < TIE_P and rms(z_better) < (1 - TIE_RELATIVE) * rms(z_worse), p


class Diagnosis:
    """Run the diagnosis of one bicycle's data; results in :meth:`as_dict`.

    Parameters
    ----------
    model : GapModelInput
    eigen : EigenvalueData
    canonical : CanonicalData
    effects : sequence of str, optional
        Candidates (default: all of :data:`EFFECT_NAMES`).
    """

    def __init__(self, model: GapModelInput, eigen: EigenvalueData, canonical: CanonicalData, effects=EFFECT_NAMES):
        start = time.perf_counter()
        self.problem = GapProblem(model, eigen, canonical)
        self.effects = [e for e in effects]
        self.not_applicable = {
            e: "needs a rider on the bicycle (the model has none)"
            for e in self.effects
            if EFFECTS[e].needs_rider and model.geometry.upper_body is None
        }
        if not self.problem.free and "parameters" in self.effects:
            self.not_applicable["parameters"] = "the model file gives no parameter uncertainties"
        self.candidates = [e for e in self.effects if e not in self.not_applicable]
        self.folds = self._folds()
        self.gap_map = self._gap_map()
        self.gap_test = self._gap_test()
        self.parameter_fit = self.problem.fit(("parameters",)) if "parameters" in self.candidates else None
        self.verdict = self._verdict()
        self.ranking: list[dict] = []
        self.cv: dict[tuple[str, ...], CrossValidation] = {}
        self.selected: list[str] = []
        self.selection_steps: list[dict] = []
        if len(self.folds) >= 2:
            self._rank()
            self._select()
        self.full_fits = {e: self.problem.fit((e,)) for e in self.candidates}
        if self.selected:
            self.selected_fit = self.problem.fit(tuple(self.selected))
        else:
            self.selected_fit = None
        self.elapsed = time.perf_counter() - start

    # -- folds --------------------------------------------------------------------------------------
    def _folds(self) -> list[tuple[str, np.ndarray]]:
        obs = self.problem.obs
        groups = sorted(set(obs.group))
        if len(groups) >= 2:
            return [(f"group {g}", np.array([gg == g for gg in obs.group])) for g in groups]
        speeds = np.unique(obs.speed)
        if speeds.size < 2:
            return []
        bands = np.array_split(speeds, min(N_SPEED_BANDS, speeds.size))
        return [(f"speeds {b[0]:.2f}-{b[-1]:.2f} m/s", (obs.speed >= b[0]) & (obs.speed <= b[-1])) for b in bands]

    # -- where -----------------------------------------------------------------------------------
    def _gap_map(self) -> list[dict]:
        from scipy.stats import chi2

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
                }
            )
        return cells

    def _gap_test(self) -> dict:
        from scipy.stats import chi2

        p = self.problem
        r = p.y - p.baseline
        cov = np.diag(p.var_data) + p.jacobian @ p.jacobian.T
        stat = float(r @ np.linalg.solve(cov, r))
        n = r.size
        return {
            "chi2": stat,
            "dof": n,
            "p_value": float(chi2.sf(stat, n)),
            "rms_z": rms(-p.z(p.baseline)),
            "significant": bool(chi2.sf(stat, n) < ALPHA),
        }

    # -- whether ----------------------------------------------------------------------------------
    def _verdict(self) -> str:
        from scipy.stats import chi2

        if not self.gap_test["significant"]:
            return "none"
        fit = self.parameter_fit
        if fit is None:
            return "structural"
        stat = fit.chi2 + fit.prior_chi2
        self.parameter_test = {
            "chi2": stat,
            "dof": fit.n,
            "p_value": float(chi2.sf(stat, fit.n)),
            "prior_chi2": fit.prior_chi2,
            "prior_dof": len(self.problem.free),
        }
        return "parameters" if chi2.sf(stat, fit.n) >= ALPHA else "structural"

    # -- which ------------------------------------------------------------------------------------
    def cross_validate(self, effects: tuple[str, ...]) -> CrossValidation:
        if effects in self.cv:
            return self.cv[effects]
        p = self.problem
        z_before = p.z(p.baseline)
        z_after = np.full(len(p.obs), np.nan)
        folds, fits = [], []
        for name, held in self.folds:
            fit = p.fit(effects, ~held)
            fits.append(fit)
            z_fold = p.z(p.predict_fit(fit))[held]
            # a model that cannot be evaluated (singular) predicts nothing: count it as far off
            z_after[held] = np.where(np.isfinite(z_fold), z_fold, UNPREDICTED_Z)
            folds.append(
                {
                    "fold": name,
                    "n": int(held.sum()),
                    "error_before": rms(z_before[held]),
                    "error_after": rms(z_after[held]),
                    "fitted": _named_values(fit),
                }
            )
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
        self.cv[effects] = result
        return result

    def _order(self, results: list[CrossValidation]) -> list[tuple[CrossValidation, list[str]]]:
        """Sort by held-out error; ties (see module docstring) go to the simpler candidate."""
        results = sorted(results, key=lambda r: r.error_after)
        ordered: list[CrossValidation] = []
        for r in results:
            ordered.append(r)
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
                }
            )

    def _select(self) -> None:
        if self.verdict != "structural":
            if self.verdict == "parameters" and "parameters" in self.candidates:
                self.selected = ["parameters"]
            return
        current: tuple[str, ...] = ()
        current_z = self.problem.z(self.problem.baseline)[np.any([h for _, h in self.folds], axis=0)]
        while len(current) < MAX_SELECTED:
            remaining = [e for e in self.candidates if e not in current]
            if not remaining:
                break
            results = [self.cross_validate(tuple(sorted(current + (e,), key=EFFECT_NAMES.index))) for e in remaining]
            best, _ = self._order(results)[0]
            better, pval = significantly_better(best.z_after, current_z)
            added = [e for e in best.effects if e not in current][0]
            self.selection_steps.append(
                {
                    "added": added,
                    "heldout_error": best.error_after,
                    "previous_error": rms(current_z),
                    "p_value": pval,
                    "accepted": better,
                }
            )
            if not better:
                break
            current = best.effects
            current_z = best.z_after
        self.selected = list(current)

    # -- report ---------------------------------------------------------------------------------
    def plausibility(self, fit: EffectFit) -> tuple[bool, list[dict]]:
        """Whether every fitted value's 95 % interval reaches its literature range."""
        checks = []
        ok = True
        if fit.effects == ("parameters",):
            from scipy.stats import chi2

            limit = float(chi2.ppf(1 - ALPHA, max(len(self.problem.free), 1)))
            good = fit.prior_chi2 <= limit
            checks.append(
                {
                    "name": "sum of squared shifts / sigma^2",
                    "value": fit.prior_chi2,
                    "literature": [0.0, limit],
                    "plausible": bool(good),
                }
            )
            return bool(good), checks
        for k, name in enumerate(fit.names):
            effect = next(e for e in fit.effects if any(p.name == name for p in EFFECTS[e].parameters))
            param = next(p for p in EFFECTS[effect].parameters if p.name == name)
            lo, hi = param.literature
            good = fit.ci_high[k] >= lo and fit.ci_low[k] <= hi
            if name == "m_arm":
                # judge the arms by their inertia about the steer axis
                inertia = arm_inertia(self.problem, fit.values[k])
                (ilo, ihi), unit, source = LITERATURE_EXTRA["I_arm_steer"]
                scale = inertia / fit.values[k] if fit.values[k] > 0 else arm_inertia(self.problem, 1.0)
                good = fit.ci_high[k] * scale >= ilo and fit.ci_low[k] * scale <= ihi
                checks.append(
                    {
                        "name": "I_arm_steer",
                        "value": inertia,
                        "unit": unit,
                        "literature": [ilo, ihi],
                        "plausible": bool(good),
                        "source": source,
                    }
                )
            else:
                checks.append(
                    {
                        "name": name,
                        "value": float(fit.values[k]),
                        "unit": param.unit,
                        "literature": [lo, hi],
                        "plausible": bool(good),
                        "source": param.source,
                    }
                )
            ok = ok and bool(good)
        return ok, checks

    def as_dict(self) -> dict:
        """Everything, as plain JSON-ready values."""
        p = self.problem
        ranking = []
        for entry in self.ranking:
            fit = self.full_fits[entry["effect"]]
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
                    "folds": entry["folds"],
                }
            )
        out = {
            "verdict": self.verdict,
            "gap": {"test": self.gap_test, "map": self.gap_map},
            "parameter_fit": None,
            "ranking": ranking,
            "selected": list(self.selected),
            "selection_steps": self.selection_steps,
            "how_far": None,
            "not_applicable": self.not_applicable,
            "folds": [name for name, _ in self.folds],
            "n_observations": len(p.obs),
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
                "parameters": _named_values(fit) if fit else {},
            }
        return out


def _n_params(problem: GapProblem, effects: tuple[str, ...]) -> int:
    n = 0
    for e in effects:
        n += len(problem.free) if e == "parameters" else len(EFFECTS[e].parameters)
    return n


def _named_values(fit: EffectFit | None) -> dict:
    if fit is None:
        return {}
    return {
        name: {"value": float(v), "stderr": float(s), "ci95": [float(lo), float(hi)], "unit": u}
        for name, v, s, lo, hi, u in zip(fit.names, fit.values, fit.stderr, fit.ci_low, fit.ci_high, fit.units)
    }


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


def diagnose(
    model: GapModelInput,
    eigen: EigenvalueData | None = None,
    canonical: CanonicalData | None = None,
    effects=EFFECT_NAMES,
) -> Diagnosis:
    """Run the diagnosis (see the module docstring)."""
    eigen = eigen if eigen is not None else EigenvalueData.concatenate([])
    canonical = canonical if canonical is not None else CanonicalData.concatenate([])
    return Diagnosis(model, eigen, canonical, effects)
