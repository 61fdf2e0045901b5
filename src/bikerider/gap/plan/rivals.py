"""The rivals of a plan: the candidates (or pairs) a new measurement is to tell apart.

By default the first-ranked candidate of a diagnosis and every (single) candidate tied with it; when none
is tied, the runners-up that also beat the nominal model on the held-out folds (at most :data:`MAX_RIVALS`
in all).  Any candidates (or pairs) fitted to all the data may be named instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from bikerider.errors import InputError
from bikerider.gap.candidates.effects import TIME_DOMAIN_EFFECTS
from bikerider.gap.inference.problem import EffectFit

MAX_RIVALS = 3
"""Most rivals chosen by default."""


class NoExperiment(InputError):
    """No experiment can be planned from this diagnosis (no rivals to tell apart, no speed where a decay
    shows a weave, every experiment left out); :attr:`why` says why in a sentence.  The command prints
    the diagnosis and the reason; a bad option stays an :class:`InputError`."""

    def __init__(self, name: str, value: object, expected: str, why: str | None = None):
        super().__init__(name, value, expected)
        self.why = why or f"{name} = {value}: expected {expected}"


@dataclass
class Rival:
    """A candidate (or pair) to tell apart from the others, as fitted to all the data."""

    effects: tuple[str, ...]
    fit: EffectFit
    misfit: float = 0.0
    """Its held-out mean squared normalised residual above the noise floor, ``max(0, error^2 - 1)``: how far
    beyond the uncertainties it misses data it was not fitted to."""

    @property
    def name(self) -> str:
        return "+".join(self.effects)

    @property
    def nonlinear(self) -> bool:
        return any(e in TIME_DOMAIN_EFFECTS for e in self.effects)


def choose_rivals(diagnosis, named) -> tuple[list[Rival], bool]:
    """The rivals of a plan (module docstring): ``named`` (candidates, pairs as ``a+b``) or the diagnosis's
    first-ranked and those tied with it, else the runners-up that beat the nominal model; and whether every
    pair of them is to be told apart (``False``: the first against each runner-up)."""
    d = diagnosis
    all_pairs = True
    if named:
        chosen = []
        for name in named:
            effects = tuple(e.strip() for e in str(name).split("+"))
            bad = [e for e in effects if e not in d.candidates]
            if bad:
                raise InputError(
                    "rival", name, "candidates of the diagnosis (" + ", ".join(d.candidates) + "), joined by +"
                )
            chosen.append(effects)
    else:
        if not d.ranking:
            raise NoExperiment("diagnosis", "no ranking", "a diagnosis with held-out folds (two groups or more)")
        first = d.ranking[0]
        chosen = [(first["effect"],)] + [tuple(t.split("+")) for t in first["tied_with"]]
        chosen = [c for c in chosen if len(c) == 1 or c in d.cv]
        if len(chosen) < 2:
            all_pairs = False
            for r in d.ranking[1:]:
                if len(chosen) >= MAX_RIVALS:
                    break
                cv = d.cv[(r["effect"],)]
                if cv.error_after < cv.error_before and (r["effect"],) not in chosen:
                    chosen.append((r["effect"],))
        chosen = chosen[:MAX_RIVALS]
    out = []
    for c in dict.fromkeys(chosen):
        error = d.cross_validate(c).error_after if len(d.folds) >= 2 else 1.0
        out.append(Rival(c, d.fit_of(c), max(0.0, error**2 - 1.0) if math.isfinite(error) else 0.0))
    return out, all_pairs
