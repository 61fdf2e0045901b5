"""Which: every candidate cross-validated and ranked by its held-out error (ties to the simpler), and
the pairs searched on the held-out folds (module docstring of :mod:`bikerider.gap.diagnosis.result`)."""

from __future__ import annotations

import itertools

from bikerider import progress
from bikerider.gap.candidates.effects import EFFECT_NAMES, EFFECTS, PARAMETERS, TIME_DOMAIN_EFFECTS
from bikerider.gap.diagnosis.fits import CrossValidation, Fits
from bikerider.gap.diagnosis.statistics import _n_params, by_error, significantly_better
from bikerider.gap.parallel import cross_validate_all

HELPFUL = 0.01
"""A candidate predicts the held-out folds better than the nominal model (and enters the pair search)
when its held-out error is lower by more than this fraction (a fit that stays at its neutral value
changes nothing and pairs nothing)."""


def order(results: list[CrossValidation], fits: Fits) -> list[tuple[CrossValidation, list[str]]]:
    """Sort by held-out error; ties (see the module docstring of :mod:`~bikerider.gap.diagnosis.result`)
    go to the simpler candidate; errors equal to the fits' tolerance in a fixed order
    (:func:`~bikerider.gap.diagnosis.statistics.by_error`).  Each with the candidates it is tied with.

    A candidate that holds a simpler one as a special case (:attr:`~bikerider.gap.candidates.effects.Effect.nests`)
    is tied with it, whatever their held-out errors, when its fit to all the data does not exclude the values
    that make it the simpler one (each such value inside its 95 % interval): the data do not determine what
    it adds."""
    problem = fits.problem
    results = by_error(results, problem)
    ordered: list[CrossValidation] = list(results)
    ties: dict[tuple, list[str]] = {r.effects: [] for r in results}
    for i, a in enumerate(results):
        for b in results[i + 1 :]:
            better, _ = significantly_better(a.z_after, b.z_after)
            if (
                not better
                or undetermined_extra(fits, a.effects, b.effects)
                or undetermined_extra(fits, b.effects, a.effects)
            ):
                ties[a.effects].append("+".join(b.effects))
                ties[b.effects].append("+".join(a.effects))
    # bubble simpler candidates ahead of tied, better-scoring but more complex ones
    changed = True
    while changed:
        changed = False
        for i in range(len(ordered) - 1):
            a, b = ordered[i], ordered[i + 1]
            if "+".join(b.effects) in ties[a.effects] and _n_params(problem, b.effects) < _n_params(problem, a.effects):
                ordered[i], ordered[i + 1] = b, a
                changed = True
    return [(r, ties[r.effects]) for r in ordered]


def rank(fits: Fits, candidates: list[str]) -> list[dict]:
    """Every candidate cross-validated (on every core; the same results) and ranked: one entry each."""
    progress.begin("candidates", len(candidates) * len(fits.folds), "fold fits")

    def ready_pairs() -> list[tuple[str, str]]:  # pairs of candidates done: a free worker starts on them
        return pair_candidates([e for e in candidates if (e,) in fits.cv], fits.cv)

    cross_validate_all(fits, [(e,) for e in candidates], fit_cost, then=ready_pairs)
    results = [fits.cross_validate((e,)) for e in candidates]
    return [
        {
            "rank": position,
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
        for position, (r, ties) in enumerate(order(results, fits), start=1)
    ]


def undetermined_extra(fits: Fits, general: tuple[str, ...], simpler: tuple[str, ...]) -> bool:
    """Whether single candidate ``general`` holds ``simpler`` as a special case
    (:attr:`~bikerider.gap.candidates.effects.Effect.nests`) and its fit to all the data leaves every value
    that makes it so inside that parameter's 95 % interval (``steer_friction`` whose ``T_coulomb`` interval
    reaches 0 is not told from ``steer_damping``)."""
    if len(general) != 1 or len(simpler) != 1 or general[0] not in EFFECTS:
        return False
    neutral = EFFECTS[general[0]].nests.get(simpler[0])
    if not neutral:
        return False
    fit = fits.fit_of(general)
    index = {name: k for k, name in enumerate(fit.names)}
    return all(
        name in index and fit.ci_low[index[name]] <= value <= fit.ci_high[index[name]]
        for name, value in neutral.items()
    )


def pair_candidates(candidates: list[str], cv: dict[tuple[str, ...], CrossValidation]) -> list[tuple[str, str]]:
    """Pairs searched on the held-out folds (module docstring of :mod:`~bikerider.gap.diagnosis.result`):
    any two linear candidates that each, alone, predict the held-out folds better than the nominal model
    (by :data:`HELPFUL`), fitted jointly; and each time-domain candidate with each such one of its
    partners (:attr:`bikerider.gap.candidates.effects.Effect.partners`)."""
    helpful = [e for e in candidates if (e,) in cv and cv[(e,)].error_after < (1 - HELPFUL) * cv[(e,)].error_before]
    linear = [e for e in helpful if e not in TIME_DOMAIN_EFFECTS]
    pairs = [tuple(sorted(pair, key=EFFECT_NAMES.index)) for pair in itertools.combinations(linear, 2)]
    for timed in (e for e in TIME_DOMAIN_EFFECTS if e in helpful):
        pairs += [tuple(sorted((e, timed), key=EFFECT_NAMES.index)) for e in EFFECTS[timed].partners if e in helpful]
    return pairs


def search_pairs(fits: Fits, candidates: list[str]) -> list[CrossValidation]:
    """The pairs of :func:`pair_candidates` cross-validated (on every core; the same results)."""
    pairs = pair_candidates(candidates, fits.cv)
    progress.begin("pairs", len(pairs) * len(fits.folds), "fold fits")
    progress.advance(sum(len(fits.folds) for pair in pairs if pair in fits.cv))  # begun with the candidates
    cross_validate_all(fits, pairs, fit_cost)
    return [fits.cross_validate(pair) for pair in pairs]


def fit_cost(effects: tuple[str, ...]) -> int:
    """A rough rank of a candidate's cost, to start the longest first on the worker processes: fits in
    the time domain, then the benchmark parameters' shifts, then more effects; a model with tyres
    counts twice (its eigenvalues are those of 8x8 matrices, by LAPACK, instead of the 4x4 quartic:
    on the SBW records parameters + tyre_slip is the costliest set, 2.3 s against 1.7 s for the next)."""
    linear = 2 * (PARAMETERS in effects) + len(effects)
    tyres = any(EFFECTS[e].adds_tyres for e in effects if e in EFFECTS)
    return 4 * any(e in TIME_DOMAIN_EFFECTS for e in effects) + linear * (2 if tyres else 1)
