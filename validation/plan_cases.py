"""Blind check of the next-experiment plan: does following it resolve a tie more often than more of the same?

Cases are the hidden truths of :mod:`validation.cases` measured by a narrow protocol
(:data:`NARROW`: three sessions at 6-7.2 m/s, as a lab that has run only near one speed), where
candidates tie.  For every case whose first-ranked candidate is tied with another and the hidden
effect is among them:

* the plan (:func:`bikerider.gap.plan.ranking.plan_next`, the tied candidates as rivals,
  :data:`FOLLOW_UP` decays; multisines are left out, since the diagnosis that judges the follow-up reads
  no frequency responses) recommends one experiment, a speed and a control law;
* *planned*: :data:`FOLLOW_UP` new runs of that experiment, simulated by the independent truth
  (:class:`validation.cases.TruthSimulator`: Meijaard's Appendix A typed in by hand, the
  nonlinear effects, LSODA, noise, the weave fitted from the noisy roll rate), as a new session;
* *spread evenly*: the same number of runs under the data's own control laws in turn, at speeds spread
  evenly over the range where the plan found a decay to record under that law (more of the same
  protocol, over the widest range it can be run at);
* each data set is diagnosed again with the tied candidates alone; the tie is *resolved* when the
  hidden effect ranks first and no other candidate is tied with it (the diagnosis's own tie rule:
  a paired bootstrap of the held-out errors).

The rate of resolved ties, planned against spread evenly, is the check.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from bikerider.gap.candidates.nominal import GapModelInput
from bikerider.gap.diagnosis.result import diagnose
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
from bikerider.gap.plan.ranking import plan_next
from validation.cases import TRUTHS, Protocol, Session, TruthSimulator, measure

LOG = logging.getLogger(__name__)

NARROW = Protocol(
    (
        Session("day1", (6.0, 6.5, 7.0)),
        Session("day2", (6.1, 6.6, 7.1)),
        Session("day3", (6.2, 6.7, 7.2)),
    )
)
"""Three sessions of three uncontrolled runs between 6 and 7.2 m/s: a lab that ran near one speed."""
FOLLOW_UP = 10
"""New runs of the follow-up session (planned or spread evenly)."""
STANDS_FOR = {"steer_damping": ("steer_damping", "steer_friction")}
"""Candidates that stand for a hidden effect (a viscous steer damping holds in steer friction)."""


@dataclass
class NextCase:
    """One blind check: the tie, the plan, and what each follow-up resolved."""

    truth: str
    seed: int
    rivals: list[str]
    tie: bool
    planned: str = ""
    planned_probability: float | None = None
    resolved_planned: bool | None = None
    resolved_even: bool | None = None
    first_planned: str = ""
    first_even: str = ""
    measured: tuple[int, int] = (0, 0)
    seconds: float = 0.0
    notes: list[str] = field(default_factory=list)


def _resolved(model: GapModelInput, data: EigenvalueData, rivals: list[str], hidden: tuple[str, ...]):
    """Diagnose ``data`` with the rivals alone: (resolved, first-ranked with its ties)."""

    d = diagnose(model, data, CanonicalData.empty(), effects=tuple(rivals))
    if not d.ranking:
        return False, "no ranking"
    first = d.ranking[0]
    truth = {c for h in hidden for c in STANDS_FOR.get(h, (h,))}
    label = first["effect"] + (f" (tied with {', '.join(first['tied_with'])})" if first["tied_with"] else "")
    return first["effect"] in truth and not first["tied_with"], label


def run_next_case(model: GapModelInput, truth_name: str, seed: int, follow_up: int = FOLLOW_UP) -> NextCase:
    """Measure a truth narrowly, diagnose it, and when it ends in a tie holding the hidden effect, follow
    the plan and the even spread with runs from the independent simulation and diagnose again."""

    start = time.perf_counter()
    truth = TRUTHS[truth_name]
    rng = np.random.default_rng(seed)
    simulator = TruthSimulator(model, truth, rng)
    data, _ = measure(simulator, NARROW, rng)
    diagnosis = diagnose(model, data, CanonicalData.empty())
    first = diagnosis.ranking[0] if diagnosis.ranking else None
    rivals = [first["effect"]] + [t for t in first["tied_with"] if "+" not in t] if first else []
    hidden = {c for h in truth.effects for c in STANDS_FOR.get(h, (h,))}
    case = NextCase(truth_name, seed, rivals, tie=len(rivals) > 1 and bool(hidden & set(rivals)))
    if not case.tie:
        case.notes.append("no tie holding the hidden effect" if first else "no ranking")
        case.seconds = time.perf_counter() - start
        return case
    # decays only: the follow-up is diagnosed again, and the diagnosis reads no frequency responses
    plan = plan_next(diagnosis, rivals=rivals, repeats=follow_up, sweeps=False)
    best = plan.plan[0]
    e = best["experiment"]
    case.planned, case.planned_probability = best["text"], best["resolution_probability"]
    gains = tuple(float(g) for g in plan.laws[e.law](e.speed))
    planned = Protocol((Session("follow-up", (e.speed,) * follow_up, gains),))
    # spread evenly: over the speeds where the plan found a decay to record under each of the data's laws
    sessions = []
    names = [name for name in data.laws if any(p.law == name for p in plan.points)]
    for k in range(follow_up):
        name = names[k % len(names)]
        span = [p.speed for p in plan.points if p.law == name]
        runs = [j for j in range(follow_up) if j % len(names) == k % len(names)]
        position = runs.index(k) / max(len(runs) - 1, 1)
        v = float(min(span) + position * (max(span) - min(span)))
        sessions.append(Session("follow-up", (v,), tuple(float(g) for g in plan.laws[name](v))))
    even = Protocol(tuple(sessions))
    follow_rng = np.random.default_rng(seed + 20_000)
    new_planned, _ = measure(simulator, planned, follow_rng)
    new_even, _ = measure(simulator, even, np.random.default_rng(seed + 20_000))
    case.measured = (len(new_planned), len(new_even))
    case.resolved_planned, case.first_planned = _resolved(
        model, EigenvalueData.concatenate([data, new_planned]), rivals, truth.effects
    )
    case.resolved_even, case.first_even = _resolved(
        model, EigenvalueData.concatenate([data, new_even]), rivals, truth.effects
    )
    case.seconds = time.perf_counter() - start
    LOG.info(
        "%s seed %d: planned %s -> %s; even -> %s", truth_name, seed, case.planned, case.first_planned, case.first_even
    )
    return case


NEXT_CASES = [
    (truth, 500 + k)
    for truth in ("rider_lean", "steer_inertia", "tyre_slip", "steer_damping", "passive_arms")
    for k in range(4)
]
"""The documented cases: five truths of four seeds each (only those ending in a tie count)."""


def run_next_suite(model: GapModelInput, cases=NEXT_CASES, follow_up: int = FOLLOW_UP) -> list[NextCase]:
    return [run_next_case(model, truth, seed, follow_up) for truth, seed in cases]


def rates(cases: list[NextCase]) -> dict:
    """Ties resolved, planned and spread evenly, over the cases that tied."""
    tied = [c for c in cases if c.tie]
    return {
        "cases": len(cases),
        "ties": len(tied),
        "resolved_planned": sum(bool(c.resolved_planned) for c in tied),
        "resolved_even": sum(bool(c.resolved_even) for c in tied),
    }
