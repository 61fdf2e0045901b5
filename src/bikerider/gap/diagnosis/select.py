"""Selection: by held-out error and prior together; a value outside its usual range is flagged, never
refused; a pair only when it beats the single (module docstring of :mod:`bikerider.gap.diagnosis.result`,
"Selection")."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bikerider.gap.candidates.effects import EFFECTS, PARAMETERS, STEER_FRICTION
from bikerider.gap.diagnosis.fits import CrossValidation, Fits
from bikerider.gap.diagnosis.priors import Priors, implausible_reasons
from bikerider.gap.diagnosis.statistics import at_noise_floor, by_error, significantly_better
from bikerider.gap.diagnosis.which import undetermined_extra

MAX_SELECTED = 2
"""Most effects selected together (pairs are searched on the held-out folds)."""
PRIOR_ODDS = math.log(19.0)
"""Evidence [nats] by which another candidate must beat the first of the ranking to be selected instead
(posterior odds 19 to 1, the 95 % of ``--next``)."""
RULE = (
    "the first single candidate of the ranking that beats the nominal model significantly on held-out "
    "folds with posterior odds above even (held-out log-likelihood, its noise inflated by the lack of fit "
    "no candidate removes, plus log prior ratio), unless another "
    "such candidate's odds are 19 times higher; a pair when the single leaves a gap above the noise "
    "floor and the pair beats it significantly with higher odds; values outside their usual range are "
    "flagged, not refused; a value the data do not determine (or pinned at the edge of the search) "
    "is selected only when its candidate explains the held-out data to the noise floor"
)
"""The selection rule as the output states it."""


@dataclass(frozen=True)
class Selection:
    """What the diagnosis selects, and why.

    Attributes
    ----------
    selected : list of str
        The effects selected (empty: none).
    selection : dict
        The rule, every candidate and pair considered with its evidence, the lack of fit, and for a
        selection its log odds, log prior and flags.
    best_implausible, best_single_implausible : dict or None
        The best held-out fit overall (and the best single one) when it is not selected and unusual,
        with why.
    """

    selected: list[str]
    selection: dict
    best_implausible: dict | None = None
    best_single_implausible: dict | None = None


def lack_of_fit(singles: list[CrossValidation], pairs: list[CrossValidation]) -> float:
    """``s^2 = max(1, min mean(z^2))`` over every candidate and pair on the held-out folds: the variance
    of the held-out residuals that no candidate explains, in units of their stated uncertainty.  The
    held-out log-likelihood is taken with the noise inflated by it (a quasi-likelihood): where even the
    best candidate misses the data by several standard deviations, the stated noise would make every
    added freedom look decisive against the priors."""
    means = [float(np.mean(np.square(r.z_after))) for r in singles + pairs if r.z_after.size]
    return max(1.0, min(means)) if means else 1.0


def score(r: CrossValidation, fits: Fits, priors: Priors, lack: float = 1.0) -> float:
    """The selection's evidence for a set of effects [nats]: held-out log-likelihood
    ``-sum(z^2) / (2 s^2)`` plus the log prior ratio of its values fitted to all the data
    (:meth:`Priors.log_prior`); ``s^2`` is the lack of fit (:func:`lack_of_fit`)."""
    return -0.5 * float(np.sum(np.square(r.z_after))) / lack + priors.log_prior(fits.fit_of(r.effects))


def select(
    verdict: str,
    candidates: list[str],
    ranking: list[dict],
    pairs: list[CrossValidation],
    fits: Fits,
    priors: Priors,
) -> Selection:
    """The selection (module docstring of :mod:`~bikerider.gap.diagnosis.result`) from the verdict, the
    ranking of the single candidates and the pairs' cross-validations."""
    if verdict == "none":
        return Selection([], {"rule": "no gap above the noise: nothing to explain"})
    parameters_note = None
    if verdict == PARAMETERS:
        if PARAMETERS in candidates:
            ok, checks = priors.plausibility(fits.fit_of((PARAMETERS,)))
            if ok:
                return Selection([PARAMETERS], {"rule": "plausible parameter errors explain the gap"})
        parameters_note = _parameters_note(checks if PARAMETERS in candidates else None)
    if len(fits.folds) < 2:
        return Selection([], {"rule": "fewer than two folds: no held-out comparison, nothing selected"})
    p = fits.problem
    held_any = np.any([h for _, h in fits.folds], axis=0)
    z_nominal = p.z(p.baseline)[held_any]
    singles = [fits.cv[(r["effect"],)] for r in ranking]
    lack = lack_of_fit(singles, pairs)
    nominal_score = -0.5 * float(np.sum(np.square(z_nominal))) / lack
    considered = []
    judged: dict[tuple[str, ...], dict] = {}

    def judge(r: CrossValidation, reference: np.ndarray, key: str) -> dict:
        ok, checks = priors.plausibility(fits.fit_of(r.effects))
        better, pval = significantly_better(r.z_after, reference)
        left = r.data_after if r.data_after is not None else r.error_after
        usable = all(c.get("usable", True) for c in checks)
        at_floor = at_noise_floor(left, r.z_after.size)
        evidence = score(r, fits, priors, lack)
        entry = {
            "effects": list(r.effects),
            "heldout_error": r.error_after,
            "plausible": ok,
            key: better,
            "p_value": pval,
            "at_noise_floor": at_floor,
            "usable": usable,
            "log_prior": priors.log_prior(fits.fit_of(r.effects)),
            "log_odds_vs_nominal": evidence - nominal_score,
            "flags": [c["flag"] for c in checks if c.get("flag")],
            "eligible": bool(better and (usable or at_floor) and evidence > nominal_score),
        }
        judged[r.effects] = {**entry, "score": evidence, "checks": checks}
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
    floor_score = judged[best_single.effects]["score"] if best_single is not None else nominal_score
    for r in by_error([] if floor_reached else pairs, p):
        j = judge(r, reference, "beats_single" if best_single is not None else "beats_nominal")
        if j["eligible"] and j["score"] > floor_score and chosen is best_single:
            chosen = r
    # the best held-out fit overall, and the best single one: when not chosen and unusual, say why
    best_implausible = _unusual_best(singles + pairs, chosen, judged, ranking, fits, priors)
    best_single_implausible = _unusual_best(singles, chosen, judged, ranking, fits, priors)
    if best_single_implausible == best_implausible:
        best_single_implausible = None
    selection: dict = {"rule": RULE, "considered": considered, "lack_of_fit": lack}
    if chosen is not None:
        j = judged[chosen.effects]
        selection.update(
            {"log_odds_vs_nominal": j["log_odds_vs_nominal"], "log_prior": j["log_prior"], "flags": j["flags"]}
        )
        equivalent = priors.friction_equivalent(fits.fit_of(chosen.effects))
        if equivalent is not None and not equivalent["separable"]:
            selection["flags"] = selection["flags"] + [f"{STEER_FRICTION}: " + equivalent["note"]]
        selection["flags"] = selection["flags"] + _nested_flags(chosen.effects, candidates, fits)
    if parameters_note:
        selection["note"] = parameters_note
    return Selection(
        list(chosen.effects) if chosen is not None else [], selection, best_implausible, best_single_implausible
    )


def _nested_flags(chosen: tuple[str, ...], candidates: list[str], fits: Fits) -> list[str]:
    """A flag for each simpler candidate the selected one holds as a special case and whose values its fit
    does not exclude (:func:`~bikerider.gap.diagnosis.which.undetermined_extra`): the selection is then
    that simpler model, fitted by the selected candidate's route (``steer_friction`` whose ``T_coulomb``
    interval reaches 0 is viscous steer damping, fitted in the time domain)."""
    if len(chosen) != 1 or chosen[0] not in EFFECTS:
        return []
    fit = fits.fit_of(chosen)
    index = {name: k for k, name in enumerate(fit.names)}
    flags = []
    for simpler, neutral in EFFECTS[chosen[0]].nests.items():
        if simpler not in candidates or not undetermined_extra(fits, chosen, (simpler,)):
            continue
        held = ", ".join(
            f"{name} = {fit.values[index[name]]:.3g} [{fit.ci_low[index[name]]:.3g}, {fit.ci_high[index[name]]:.3g}]"
            f" reaches {value:g}"
            for name, value in neutral.items()
        )
        rest = ", ".join(f"{n} = {fit.values[k]:.3g}" for n, k in index.items() if n not in neutral)
        flags.append(
            f"{chosen[0]}: {held}: the data do not tell it from {simpler}, the special case it holds; read the "
            f"selection as {simpler} fitted as {chosen[0]} ({rest})"
        )
    return flags


def _parameters_note(checks: list[dict] | None) -> str:
    """Why a gap within the parameters' uncertainty is compared as a structural one: the parameter fit's
    implausible shifts (its ``checks``), or ``None``: the parameters are not a candidate."""
    if checks is None:
        return (
            "the gap lies within the parameters' uncertainty (parameters are not a candidate): "
            "the candidates are compared as for a structural gap"
        )
    return (
        "the gap lies within the parameters' uncertainty, but the parameter fit needs "
        "implausible shifts (" + "; ".join(implausible_reasons(checks)) + "): the candidates "
        "are compared as for a structural gap"
    )


def _unusual_best(
    pool: list[CrossValidation],
    chosen: CrossValidation | None,
    judged: dict[tuple[str, ...], dict],
    ranking: list[dict],
    fits: Fits,
    priors: Priors,
) -> dict | None:
    """The best held-out fit of ``pool`` when it is not the one chosen and its values are unusual: what
    it needs (``why``), its log odds against the selection and its place in the ranking; else ``None``."""
    best = by_error(pool, fits.problem)[0] if pool else None
    if best is None or (chosen is not None and best.effects == chosen.effects):
        return None
    ok, checks = priors.plausibility(fits.fit_of(best.effects))
    if ok:
        return None
    j = judged.get(best.effects)
    entry = {"effects": list(best.effects), "heldout_error": best.error_after, "why": implausible_reasons(checks)}
    if j is not None and chosen is not None:
        entry["log_odds_vs_selected"] = j["score"] - judged[chosen.effects]["score"]
    ranked = next((r for r in ranking if (r["effect"],) == best.effects), None)
    if ranked is not None:  # where the ranking (ties to the simpler) puts it
        entry["rank"], entry["tied_with"] = ranked["rank"], list(ranked["tied_with"])
    return entry
