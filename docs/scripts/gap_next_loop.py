"""The closed measure-diagnose-plan loop against hidden truths (issue 25; :mod:`validation.loop`).

Two steps, so that a stopped study keeps what it did::

    # run cases until enough ties (or the deadline), appending one JSON line per case
    nice -n 10 .venv/bin/python docs/scripts/gap_next_loop.py run --ties 100 --workers 2 --until 15:30
    # judge the loop's wrong or undecided ties by the diagnosis itself (optional, about a minute a tie)
    nice -n 10 .venv/bin/python docs/scripts/gap_next_loop.py check --max 10
    # write part 5 of docs/gap_validation.md and docs/figures/gap_next_loop.png from the stored cases
    .venv/bin/python docs/scripts/gap_next_loop.py report

``run`` skips the cases already stored, so it resumes where it stopped.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import logging
import math
import os
import sys
import time
from collections import Counter
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one BLAS thread per worker: the workers are the parallelism
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402 (after the thread settings, which must precede NumPy's import)

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # validation/ (the gap's blind-check harnesses) lives beside src/, not installed
    sys.path.insert(0, str(ROOT))
BP = ROOT / "src" / "bikerider" / "data" / "bicycleparameters"
RESULTS = Path(__file__).with_name("gap_next_loop.jsonl")
CHECKS = Path(__file__).with_name("gap_next_loop_checks.jsonl")
SHARED = Path(__file__).with_name("gap_next_loop_shared.jsonl")
"""The main study's ties again, the nominal parameters' uncertainty shared by all runs (``run --shared``)."""
RERUN = Path(__file__).with_name("gap_next_loop_rerun.jsonl")
RERUN_ALL = Path(__file__).with_name("gap_next_loop_rerun_all.jsonl")
"""Every stored tie's plan strategies again under the new rule (``rerun --all``), to see what else it changes."""
"""The ties the plan declared unbreakable and the even spread broke, run again with the plan strategies under
the unbreakable rule of runs combined over experiments (``rerun``)."""
"""Ties run again and judged by the diagnosis itself (:func:`validation.loop.diagnosis_check`)."""
SWEEP_RULE = Path(__file__).with_name("gap_next_loop_repeat_sweep.jsonl")
"""Every stored tie again, the plan's best multisine repeated only, with the plan's lean rule
(``rerun --strategy repeat:sweep``)."""
SWEEP_NO_RULE = Path(__file__).with_name("gap_next_loop_repeat_sweep_max_roll_inf.jsonl")
"""The same on the same code with the lean rule off (``rerun --strategy repeat:sweep --max-roll inf``)."""
SWEEP_SETTLED = Path(__file__).with_name("gap_next_loop_repeat_sweep_settled.jsonl")
"""The same on later code: a friction rival's multisine judged by its run simulated in time, every run read
after the slowest rival's transient, the first run no rival describes noted (``rerun --strategy repeat:sweep
--tag settled``)."""
JR_SETTLED = Path(__file__).with_name("gap_next_loop_plan_jensen_renyi_settled.jsonl")
EVEN_SETTLED = Path(__file__).with_name("gap_next_loop_even_settled.jsonl")
"""``plan:jensen_renyi`` and ``even`` on every stored tie on the code of :data:`SWEEP_SETTLED` (``rerun --strategy
... --tag settled``)."""
JR_SHARED_SETTLED = Path(__file__).with_name("gap_next_loop_plan_jensen_renyi_shared_settled.jsonl")
EVEN_SHARED_SETTLED = Path(__file__).with_name("gap_next_loop_even_shared_settled.jsonl")
"""The same two strategies with the nominal parameters' uncertainty shared by all runs (``rerun --strategy ...
--shared --tag settled``)."""
SWEEP_TODAY = Path(__file__).with_name("gap_next_loop_repeat_sweep_today.jsonl")
SWEEP_SHARED_TODAY = Path(__file__).with_name("gap_next_loop_repeat_sweep_shared_today.jsonl")
DECAY_TODAY = Path(__file__).with_name("gap_next_loop_repeat_decay_today.jsonl")
DECAY_SHARED_TODAY = Path(__file__).with_name("gap_next_loop_repeat_decay_shared_today.jsonl")
"""The plan's best decay and best multisine repeated on every stored tie, on the code of 2026-11-29 (commit
f47fb70), with the loop's evidence counting the nominal parameters' uncertainty per run (``rerun --strategy
repeat:decay --tag today``, ``rerun --strategy repeat:sweep --tag today``) and shared by all runs (the same with
``--shared``): the plan's odds against the loop's outcomes under either evidence model."""
SWEEP_ODDS = Path(__file__).with_name("gap_next_loop_repeat_sweep_odds.jsonl")
SWEEP_SHARED_ODDS = Path(__file__).with_name("gap_next_loop_repeat_sweep_shared_odds.jsonl")
DECAY_ODDS = Path(__file__).with_name("gap_next_loop_repeat_decay_odds.jsonl")
DECAY_SHARED_ODDS = Path(__file__).with_name("gap_next_loop_repeat_decay_shared_odds.jsonl")
"""The same four runs on the code of issue 25 item 3 (``rerun --strategy repeat:decay|repeat:sweep [--shared]
--stated combined --tag odds``): the plan stating the probability of its measure of runs combined, both rivals'
predictive distributions simulated (``predicted``), beside its Gaussian approximation (``predicted_gaussian``,
the probability it states by default, reproduced), and the repeat strategies run on past their decision
(``posterior``), so the plan's probability of ``k`` runs is scored at ``k`` runs.  The ties, experiments and
runs are those of :data:`DECAY_TODAY` and the others (the plan ranks by the Gaussian approximation either way)."""
JR_RULE = Path(__file__).with_name("gap_next_loop_plan_jensen_renyi.jsonl")
JR_NO_RULE = Path(__file__).with_name("gap_next_loop_plan_jensen_renyi_max_roll_inf.jsonl")
EVEN_NOW = Path(__file__).with_name("gap_next_loop_even.jsonl")
"""``plan:jensen_renyi`` on every stored tie with the lean rule and without it, and ``even`` (which takes decays
only, so the rule does not touch it), all on the same code (``rerun --strategy ...``)."""
RECORDS = Path(__file__).with_name("gap_next_loop_records.jsonl")
"""The records mode (``records``): the friction pairs, the tie's data records, pushes among the experiments."""
RECORDS_PUSH = Path(__file__).with_name("gap_next_loop_records_push.jsonl")
"""The records mode's ties again, the truth's runs at every push against the rivals' predictions (``push-check``)."""
RECORDS_BEFORE_FRICTION = Path(__file__).with_name("gap_next_loop_records_before_friction.jsonl")
"""The records mode as it was run on the code of commit 0ec9c83, before issue 21 changed the friction candidate's fits
(each record's initial state under friction by Gauss-Newton steps from several starts, the slopes with the states
held at their fits, the intervals over the friction corner's range): the study before it was run again."""
RECORDS_BEFORE_VALLEYS = Path(__file__).with_name("gap_next_loop_records_before_valleys.jsonl")
"""The records mode as it was run on the code of commit 0ce6cac, before the plan predicted a friction rival's decays
from its template's kick and over the record fit's valleys (the diagnosis, so the ties, the same): its ties were run
again (``records --ties-of``), the other cases kept."""
RECORDS_PUSH_BEFORE_FRICTION = Path(__file__).with_name("gap_next_loop_records_push_before_friction.jsonl")
"""The push check of :data:`RECORDS_BEFORE_FRICTION`'s ties, on the code of their time (commit a2973b2)."""
RECORDS_BEFORE = Path(__file__).with_name("gap_next_loop_records_before_kick.jsonl")
"""The records mode as it was run before the plan spanned the kick's initial steer rate."""
RECORDS_PUSH_BEFORE = Path(__file__).with_name("gap_next_loop_records_push_before_kick.jsonl")
"""The push check of those ties."""
RECORDS_PUSH_NO_KICK = Path(__file__).with_name("gap_next_loop_records_push_no_kick.jsonl")
"""The push check on today's code with the kick's steer rate not spanned (``push-check --no-kick``)."""
FIRST_RECORD_SEED = 9000
DOC = ROOT / "docs" / "gap_validation.md"
FIGURE = ROOT / "docs" / "figures" / "gap_next_loop.png"
RECORDS_FIGURE = ROOT / "docs" / "figures" / "gap_next_loop_records.png"
BEGIN, END = "<!-- loop:begin -->", "<!-- loop:end -->"
FIRST_SEED = 7000
LOG = logging.getLogger("gap_next_loop")

_MODELS = None


def _models():
    global _MODELS
    if _MODELS is None:
        from bikerider.io.gap_model import load_model

        bicycle = BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt"
        _MODELS = {
            "riderless": load_model(bicycle),
            "rider": load_model(bicycle, BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt"),
        }
    return _MODELS


def _one(job):
    from validation import loop as L

    k, seed, shared = job
    logging.getLogger("bikerider").setLevel(logging.ERROR)
    try:
        return L.run_loop_case(_models(), L.SCENARIOS[k], seed, shared=shared)
    except Exception as exc:  # a case that breaks the harness is stored with its error, not lost silently
        return {"scenario": L.SCENARIOS[k].label, "seed": seed, "tie": False, "status": f"error: {exc!r}"}


def _one_record(job):
    from validation import loop as L

    k, seed = job
    logging.getLogger("bikerider").setLevel(logging.ERROR)
    try:
        return L.run_loop_case(_models(), L.RECORD_SCENARIOS[k], seed, records=True)
    except Exception as exc:  # a case that breaks the harness is stored with its error, not lost silently
        return {"scenario": L.RECORD_SCENARIOS[k].label, "seed": seed, "tie": False, "status": f"error: {exc!r}"}


def records(args) -> int:
    """The records mode (:data:`RECORDS`): the friction pairs in turn from seed :data:`FIRST_RECORD_SEED`, until
    ``--ties`` ties or ``--until``; resumes where it stopped."""

    from validation import loop as L

    done = {(c["scenario"], c["seed"]) for c in _stored(RECORDS)}
    ties = sum(bool(c.get("strategies")) for c in _stored(RECORDS))
    only = None
    if args.ties_of:  # the cases that tied in a stored run (the diagnosis unchanged, the plan changed)
        only = {(c["scenario"], c["seed"]) for c in _stored(Path(args.ties_of)) if c.get("strategies")}
    jobs = []
    for i in range(args.attempts):
        k = i % len(L.RECORD_SCENARIOS)
        case = (L.RECORD_SCENARIOS[k].label, FIRST_RECORD_SEED + i)
        if case not in done and (only is None or case in only):
            jobs.append((k, FIRST_RECORD_SEED + i))
    return _run_pool(
        _one_record,
        jobs,
        RECORDS,
        args,
        ties,
        lambda r: {k: (v["status"], v["runs"]) for k, v in (r.get("strategies") or {}).items()} or r.get("status"),
    )


def push_check(args) -> int:
    """The stored records ties again (:func:`validation.loop.push_check`), appended to :data:`RECORDS_PUSH`
    (``--no-kick``: with the plan's template started from the data's steer state alone, as before it spanned the
    kick's steer rate, to :data:`RECORDS_PUSH_NO_KICK`: the control on today's code)."""
    from bikerider.gap.plan import ranking
    from validation import loop as L

    path = RECORDS_PUSH
    if args.no_kick:
        ranking.kick_steer_rates = lambda records: ((0.0,), (1.0,))
        path = RECORDS_PUSH_NO_KICK
    if args.out:
        path = Path(args.out)
    index = {s.label: k for k, s in enumerate(L.RECORD_SCENARIOS)}
    done = {(c["scenario"], c["seed"]) for c in _stored(path)}
    todo = [(c["scenario"], c["seed"]) for c in _stored(RECORDS) if c.get("strategies")]
    todo = [t for t in todo if t not in done]
    if args.part:  # "i/n": every n-th tie from the i-th (1-based), for n processes side by side
        i, n = (int(x) for x in args.part.split("/"))
        todo = todo[i - 1 :: n]
    todo = todo[: args.max]
    deadline = _deadline(args.until)
    logging.getLogger("bikerider").setLevel(logging.ERROR)
    for label, seed in todo:
        result = L.push_check(_models(), L.RECORD_SCENARIOS[index[label]], seed)
        with path.open("a", encoding="utf-8") as out:
            out.write(json.dumps(result) + "\n")
        LOG.info("%s seed %s: %s, %d runs", label, seed, result["status"], len(result.get("runs", [])))
        if deadline and dt.datetime.now(dt.UTC) >= deadline:
            break
    return 0


def _deadline(until: str | None) -> dt.datetime | None:
    """``--until HH:MM`` (UTC, the next such time: tomorrow's when today's has passed) as a time, or ``None``."""
    if not until:
        return None
    hh, mm = (int(x) for x in until.split(":"))
    now = dt.datetime.now(dt.UTC)
    at = now.replace(hour=hh, minute=mm, second=0, microsecond=0)
    return at if at > now else at + dt.timedelta(days=1)


def _run_pool(worker, jobs: list, path: Path, args, ties: int, status) -> int:
    """Run ``jobs`` through ``worker`` on ``args.workers`` processes, appending each case to ``path`` as it
    ends, until ``args.ties`` ties or ``args.until``; ``status(result)`` is what the log line says of it."""
    from multiprocessing import get_context

    deadline = _deadline(args.until)
    LOG.info("%d ties stored, %d cases to try", ties, len(jobs))
    start = time.perf_counter()
    with get_context("fork").Pool(args.workers) as pool, path.open("a", encoding="utf-8") as out:
        for result in pool.imap_unordered(worker, jobs):
            out.write(json.dumps(result) + "\n")
            out.flush()
            ties += bool(result.get("strategies"))
            LOG.info(
                "%s seed %s: %s (%.1f s); %d ties, %.0f s",
                result.get("scenario"),
                result.get("seed"),
                status(result),
                result.get("seconds", math.nan),
                ties,
                time.perf_counter() - start,
            )
            if ties >= args.ties or (deadline and dt.datetime.now(dt.UTC) >= deadline):
                LOG.info("stopping: %d ties", ties)
                pool.terminate()
                break
    return 0


def _stored(path: Path = RESULTS) -> list[dict]:
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]


def run(args) -> int:

    from validation import loop as L

    path = SHARED if args.shared else RESULTS
    done = {(c["scenario"], c["seed"]) for c in _stored(path)}
    ties = sum(bool(c.get("strategies")) for c in _stored(path))
    jobs = []
    if args.shared:  # the ties of the main study, again with the nominal uncertainty shared by the runs
        index = {s.label: k for k, s in enumerate(L.SCENARIOS)}
        for c in _stored():
            if c.get("strategies") and (c["scenario"], c["seed"]) not in done:
                jobs.append((index[c["scenario"]], c["seed"], True))
    else:
        for i in range(args.attempts):
            k = i % len(L.SCENARIOS)
            seed = FIRST_SEED + i
            if (L.SCENARIOS[k].label, seed) not in done:
                jobs.append((k, seed, False))
    return _run_pool(_one, jobs, path, args, ties, lambda r: r.get("status"))


def _rerun_one(job):
    from validation import loop as L

    k, seed, only, max_roll, shared, stated = job
    logging.getLogger("bikerider").setLevel(logging.ERROR)
    if stated is not None:  # the probability the plan states (bikerider.gap.plan.discrimination.STATED)
        from bikerider.gap.plan import discrimination

        discrimination.STATED = {"decay": stated, "sweep": stated}
    if max_roll is not None:  # the plan's lean rule off (inf) or moved, to measure what it changes
        from bikerider.gap.plan import ranking

        ranking.MAX_ROLL = max_roll
    names = (only,) if only else tuple(n for n in L.STRATEGIES if n.startswith("plan:"))
    try:
        return L.run_loop_case(_models(), L.SCENARIOS[k], seed, strategies=names, shared=shared)
    except Exception as exc:  # stored with its error, not lost silently
        return {"scenario": L.SCENARIOS[k].label, "seed": seed, "tie": False, "status": f"error: {exc!r}"}


def _rerun_targets() -> list[tuple[str, int]]:
    """The stored ties the best criterion declared unbreakable and the even spread resolved."""
    out = []
    for c in _stored():
        s = c.get("strategies") or {}
        if s.get("plan:jensen_renyi", {}).get("status") == "unbreakable" and s.get("even", {}).get("status") == (
            "resolved"
        ):
            out.append((c["scenario"], c["seed"]))
    return out


def rerun(args) -> int:
    """The ties of :func:`_rerun_targets` again, the plan strategies only (the others' runs do not depend on
    the unbreakable rule), appended to :data:`RERUN`; the main study's stored cases are left as they are."""
    from multiprocessing import get_context

    from validation import loop as L

    index = {s.label: k for k, s in enumerate(L.SCENARIOS)}
    if args.strategy:  # one strategy, every stored tie, to a file of its own
        if args.strategy not in L.STRATEGIES:
            raise SystemExit(f"--strategy {args.strategy!r}: expected one of {', '.join(L.STRATEGIES)}")
        suffix = "" if args.max_roll is None else f"_max_roll_{args.max_roll:g}"
        suffix += "_shared" if args.shared else ""
        suffix += f"_{args.tag}" if args.tag else ""
        path = ROOT / "docs" / "scripts" / f"gap_next_loop_{args.strategy.replace(':', '_')}{suffix}.jsonl"
    else:
        path = RERUN_ALL if args.all else RERUN
    done = {(c["scenario"], c["seed"]) for c in _stored(path)}
    every = args.all or args.strategy
    targets = [(c["scenario"], c["seed"]) for c in _stored() if c.get("strategies")] if every else _rerun_targets()
    shared = bool(args.strategy and args.shared)
    jobs = [
        (index[label], seed, args.strategy, args.max_roll, shared, args.stated)
        for label, seed in targets
        if (label, seed) not in done
    ]
    LOG.info("%d ties to run again", len(jobs))
    with get_context("fork").Pool(args.workers) as pool, path.open("a", encoding="utf-8") as out:
        for result in pool.imap_unordered(_rerun_one, jobs):
            out.write(json.dumps(result) + "\n")
            out.flush()
            LOG.info(
                "%s seed %s: %s (%.1f s)",
                result.get("scenario"),
                result.get("seed"),
                {k: (v["status"], v["runs"]) for k, v in (result.get("strategies") or {}).items()},
                result.get("seconds", math.nan),
            )
    return 0


def check(args) -> int:
    """Ties where the even spread (else the plan's best decay repeated) went wrong or stayed undecided, run
    again and judged by the diagnosis itself, appended to :data:`CHECKS`."""
    from validation import loop as L

    labels = {s.label: s for s in L.SCENARIOS}
    done = set()
    if CHECKS.exists():
        done = {(c["scenario"], c["seed"]) for c in map(json.loads, CHECKS.read_text(encoding="utf-8").splitlines())}
    todo = []
    for c in _stored():
        if not c.get("strategies") or (c["scenario"], c["seed"]) in done:
            continue
        for name in ("even", "repeat:decay"):
            if c["strategies"].get(name, {}).get("status") in ("wrong", "undecided"):
                todo.append((c["scenario"], c["seed"], name))
                break
    for label, seed, name in todo[: args.max]:
        result = L.diagnosis_check(_models(), labels[label], seed, name)
        with CHECKS.open("a", encoding="utf-8") as out:
            out.write(json.dumps(result) + "\n")
        LOG.info("%s", result)
    return 0


# -- the report -------------------------------------------------------------------------------------------
def _runs_needed(s: dict) -> int | None:
    return s["runs"] if s["status"] == "resolved" else None


def _fmt(x: float, n_max: int) -> str:
    return f"> {n_max}" if not math.isfinite(x) else f"{x:g}"


def _reliability(cases, kind: str, n_max: int, at: bool = False, key: str = "predicted"):
    """(predicted, resolved, seed) for every tie with a best experiment of ``kind`` and every number ``k`` of its
    runs: resolved *by* ``k`` runs (the loop's decision for the hidden effect at any run up to ``k``) or, with
    ``at``, *at* ``k`` runs (the hidden effect's probability after run ``k`` at :data:`validation.loop.DECIDED` or
    more, the loop run on past its decision: ``posterior``), what the plan's probability of ``k`` runs states;
    ``key`` the stored prediction (``predicted``: the plan's stated probability; ``predicted_gaussian``: its
    Gaussian approximation, the plan's probability before issue 25 item 3)."""
    from validation.loop import DECIDED

    pairs = []
    for c in cases:
        s = c["strategies"].get(f"repeat:{kind}")
        p = (c.get(key) or {}).get(kind)
        if s is None or p is None or (at and "posterior" not in s):
            continue
        for k in range(1, n_max + 1):
            if at:
                resolved = s["posterior"][k - 1] >= DECIDED
            else:
                resolved = s["status"] == "resolved" and s["runs"] <= k
            pairs.append((p[k - 1], resolved, c["seed"]))
    return pairs


def _bins(pairs, edges=(0.0, 0.05, 0.2, 0.4, 0.6, 0.8, 0.95, 1.0001)):
    rows = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        inside = [(p, r) for p, r, _ in pairs if lo <= p < hi]
        if inside:
            cases = len({seed for p, r, seed in pairs if lo <= p < hi})
            rows.append(
                (
                    lo,
                    min(hi, 1.0),
                    len(inside),
                    cases,
                    float(np.mean([p for p, _ in inside])),
                    float(np.mean([r for _, r in inside])),
                )
            )
    return rows


def _merit(ties: list[dict], names: list[str]) -> dict:
    """Per strategy: counts by outcome, the figure of merit, runs to any decision, runs spent and lost."""
    from validation import loop as L

    merit = {}
    for n in names:
        runs = [_runs_needed(c["strategies"][n]) for c in ties if n in c["strategies"]]
        statuses = [c["strategies"][n]["status"] for c in ties if n in c["strategies"]]
        merit[n] = {
            "n": len(runs),
            "median_p90": L.figure_of_merit(runs),
            **{k: statuses.count(k) for k in ("resolved", "wrong", "undecided", "unbreakable")},
            "lost": sum(c["strategies"][n]["lost"] for c in ties if n in c["strategies"]),
            "spent": sum(c["strategies"][n]["runs"] for c in ties if n in c["strategies"]),
            # to any decision, right or wrong: how fast the strategy makes the data speak
            "decided": L.figure_of_merit(
                [
                    c["strategies"][n]["runs"] if c["strategies"][n]["status"] in ("resolved", "wrong") else None
                    for c in ties
                    if n in c["strategies"]
                ]
            ),
        }
    return merit


def _rerun_lines(ties: list[dict], best: str | None, n_max: int) -> list[str]:
    """The section on the re-run ties (:data:`RERUN`, :data:`RERUN_ALL`), from their own files: the study's
    stored results above are not rewritten."""
    from validation import loop as L

    again = {(c["scenario"], c["seed"]): c for c in _stored(RERUN) if c.get("strategies")}
    every = [c for c in _stored(RERUN_ALL) if c.get("strategies")]
    if not again and not every:
        return []
    plans = [n for n in L.STRATEGIES if n.startswith("plan:")]
    out = [
        "### Re-run under the combined-runs rule",
        "",
        "The plan's unbreakable rule above looked at one experiment repeated, with the rivals' means as they stand.",
        "Two rivals fitted to the same tie often predict the same at every experiment (steer stiffness and steer",
        "inertia both fitted at the nominal model), so no experiment repeated parts their means; what tells them",
        "apart is that their own uncertainty moves their predictions differently across speeds. The rule is now",
        "(`bikerider.gap.plan.allocation`, used by `--next` and by `validation.loop.best_chance`): the expected log",
        "Bayes factor of runs spread over the experiments (the Kullback-Leibler divergence between the rivals'",
        "predictive distributions of the runs' means, each rival's fitted values integrated over their uncertainty,",
        "one set for all experiments; the experiments' contributions add), allocated greedily one run at a time over",
        "at most three experiments, and",
        "the resolution probability, where its Gaussian approximation reaches the target, checked by simulating",
        "the runs. A tie is unbreakable only when no allocation of the runs left found so reaches the odds with",
        f"probability {L.HOPELESS:g} or more. These results come from `rerun` (the plan strategies only; the other",
        "strategies' runs do not depend on the rule and the same experiment's k-th run is the same simulated run),",
        "stored in files of their own; the results above are the study's as it was run.",
        "",
    ]
    if again:
        rows = []
        for (label, seed), c in sorted(again.items(), key=lambda kv: kv[0][1]):
            old = next((t for t in ties if (t["scenario"], t["seed"]) == (label, seed)), None)
            even = old["strategies"]["even"] if old else None
            cells = [f"{c['strategies'][n]['status']} ({c['strategies'][n]['runs']})" for n in plans]
            rows.append(
                f"| {label} | {seed} | "
                + " | ".join(cells)
                + (f" | {even['status']} ({even['runs']}) |" if even else " | - |")
            )
        runs = {
            n: [c["strategies"][n]["runs"] for c in again.values() if c["strategies"][n]["status"] == "resolved"]
            for n in plans
        }
        even_runs = [t["strategies"]["even"]["runs"] for t in ties if (t["scenario"], t["seed"]) in again]
        out += [
            f"The {len(again)} ties the plan ({best}) declared unbreakable and the even spread broke, again (status and runs):",
            "",
            "| pair | seed | " + " | ".join(plans) + " | even (stored) |",
            "|---|---|" + "---|" * (len(plans) + 1),
            *rows,
            "",
            *[
                f"* {n}: {len(runs[n])} of {len(again)} resolved, in {sum(runs[n])} runs "
                f"(median {np.median(runs[n]) if runs[n] else float('nan'):g}, at most {max(runs[n]) if runs[n] else 0})."
                for n in plans
            ],
            f"* The even spread (stored) resolved them in {sum(even_runs)} runs (median {np.median(even_runs):g}).",
            "",
        ]
    if every:
        keys = {(c["scenario"], c["seed"]) for c in every}
        same = [t for t in ties if (t["scenario"], t["seed"]) in keys]
        new, old = _merit(every, plans), _merit(same, plans)
        broken = [
            c
            for c in every
            if best
            and c["strategies"][best]["status"] == "unbreakable"
            and next(t for t in same if (t["scenario"], t["seed"]) == (c["scenario"], c["seed"]))["strategies"]["even"][
                "status"
            ]
            == "resolved"
        ]
        out += [
            f"Every stored tie's plan strategies again under the new rule ({len(every)} of {len(ties)} ties; old / new):",
            "",
            "| strategy | resolved | wrong | undecided | unbreakable | runs needed: median | 90th percentile |",
            "|---|---|---|---|---|---|---|",
        ]
        for n in plans:
            a, v = old[n], new[n]
            out.append(
                f"| {n} | {a['resolved']} / {v['resolved']} | {a['wrong']} / {v['wrong']} | {a['undecided']} / "
                f"{v['undecided']} | {a['unbreakable']} / {v['unbreakable']} | {_fmt(a['median_p90'][0], n_max)} / "
                f"{_fmt(v['median_p90'][0], n_max)} | {_fmt(a['median_p90'][1], n_max)} / {_fmt(v['median_p90'][1], n_max)} |"
            )
        out += [
            "",
            f"* Goal 2 under the new rule ({best}): {len(broken)} ties declared unbreakable that the even spread breaks"
            + (": " + ", ".join(f"{c['scenario']} seed {c['seed']}" for c in broken) if broken else "")
            + ".",
            "",
        ]
    return out


def _bin_table(cases: list[dict], n_max: int) -> list[str]:
    """The reliability of the best multisine repeated as a table: predicted probability in bins, resolved."""
    out = ["| predicted | points (ties) | mean predicted | fraction resolved |", "|---|---|---|---|"]
    return out + [
        f"| {lo:.2f}-{hi:.2f} | {n} ({nc}) | {mp:.2f} | {fr:.2f} |"
        for lo, hi, n, nc, mp, fr in _bins(_reliability(cases, "sweep", n_max))
    ]


def _at10(cases: list[dict], n_max: int) -> tuple[int, float, int, float]:
    """Ties with a best multisine, the plan's probabilities at 10 runs added up, how many were resolved, and the
    standard deviation of that count were the probabilities right (``sqrt(sum p (1 - p))``)."""
    pairs = _reliability(cases, "sweep", n_max)
    at10 = [(p, r) for p, r, _ in pairs[9::n_max]]
    sd = math.sqrt(sum(p * (1 - p) for p, _ in at10))
    return len(at10), sum(p for p, _ in at10), sum(r for _, r in at10), sd


def _lean_lines(ties: list[dict], n_max: int) -> list[str]:
    """The section on the multisines' lean rule, from :data:`SWEEP_RULE` and :data:`SWEEP_NO_RULE`."""
    from bikerider.gap.plan.sweeps import MAX_ROLL

    rule, off = _stored(SWEEP_RULE), _stored(SWEEP_NO_RULE)
    if not rule or not off:
        return []
    out = [
        "### Multisines that would lean too far, left out",
        "",
        "Most runs of the plan's best multisine repeated were lost above: the truth fell (past 0.5 rad of roll) during",
        "the settling time or the recording, under a torque the plan judged safe (it accepted a capsize slower than",
        "one e-fold per run as held by the rider or a catch, and this truth has neither) or with a lightly damped",
        "weave driven at resonance. A lost run teaches nothing, and the plan's probability did not foresee it. The",
        "plan now predicts each multisine's largest lean: every rival's closed loop, linear, driven from rest by the",
        "multisine over the settling time (three time constants of the nominal closed loop's slowest mode, 5-20 s,",
        "the loop's rule, now `bikerider.gap.plan.sweeps.settle_time`) and the recorded period",
        f"(`sweeps.peak_roll`), and leaves out a run any rival predicts to lean past {MAX_ROLL:g} rad, with the reason.",
        "Every stored tie again (`rerun --strategy repeat:sweep`, the best multisine repeated only), on the same code",
        "with the rule and with it off (`--max-roll inf`): the same truths, seeds and runs; the diagnosis and plan",
        "are today's, so a few cases no longer tie.",
        "",
        "| lean rule | cases | ties | with a multisine | multisines left out for the lean (mean per tie) | at 10 runs: "
        "predicted, added | resolved | resolved (within 20) | wrong | undecided | runs lost / spent |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    rows = {}
    for name, cases in (("off", off), (f"{MAX_ROLL:g} rad", rule)):
        t = [c for c in cases if c.get("status") == "loop"]
        w = [c for c in t if "repeat:sweep" in (c.get("strategies") or {})]
        n10, p10, r10, sd10 = _at10(w, n_max)
        st = [c["strategies"]["repeat:sweep"] for c in w]
        lean = np.mean([c.get("sweeps_left_out_lean", 0) for c in t]) if t else math.nan
        rows[name] = (w, n10, p10, r10, sd10)
        out.append(
            f"| {name} | {len(cases)} | {len(t)} | {len(w)} | {lean:.1f} | {p10:.1f} | {r10} | "
            f"{sum(s['status'] == 'resolved' for s in st)} | {sum(s['status'] == 'wrong' for s in st)} | "
            f"{sum(s['status'] == 'undecided' for s in st)} | {sum(s['lost'] for s in st)} / {sum(s['runs'] for s in st)} |"
        )
    old = [c for c in ties if "repeat:sweep" in c["strategies"]]
    n_old, p_old, r_old, _ = _at10(old, n_max)
    lost_old = sum(c["strategies"]["repeat:sweep"]["lost"] for c in old)
    spent_old = sum(c["strategies"]["repeat:sweep"]["runs"] for c in old)
    w, n10, p10, r10, sd10 = rows[f"{MAX_ROLL:g} rad"]
    out += [
        "",
        f"For comparison, the stored study above: {n_old} ties with a multisine, predicted {p_old:.1f} at 10 runs, "
        f"{r_old} resolved, {lost_old} of {spent_old} runs lost.",
        "",
        "With the rule, the plan's best multisine repeated, binned as above:",
        "",
    ]
    out += _bin_table(w, n_max)
    n_off, p_off, r_off, _ = rows["off"][1:]
    high10 = [c["strategies"]["repeat:sweep"]["status"] for c in w if c["predicted"]["sweep"][9] >= 0.8]
    lost_all = sum(
        c["strategies"]["repeat:sweep"]["lost"] == c["strategies"]["repeat:sweep"]["runs"]
        for c in w
        if c["predicted"]["sweep"][9] >= 0.8
    )
    high = [(n, mp, fr) for lo, _, n, _, mp, fr in _bins(_reliability(w, "sweep", n_max)) if lo >= 0.8]
    top = None
    if high:
        count = sum(n for n, _, _ in high)
        top = (0, 0, count, 0, sum(n * mp for n, mp, _ in high) / count, sum(n * fr for n, _, fr in high) / count)
    out += [
        "",
        f"* Lost runs fall from {sum(c['strategies']['repeat:sweep']['lost'] for c in rows['off'][0])} to "
        f"{sum(c['strategies']['repeat:sweep']['lost'] for c in w)}, and at 10 runs the odds move from "
        f"{p_off:.1f} predicted for {r_off} resolved ({n_off} ties) to {p10:.1f} predicted for {r10} resolved "
        f"({n10} ties; were the probabilities right, the count would scatter by {sd10:.1f}): "
        + (
            "in total within twice that scatter"
            if abs(p10 - r10) <= 2 * sd10
            else "closer, still " + ("optimistic" if p10 > r10 else "pessimistic")
        )
        + f" ({abs(p10 - r10) / max(sd10, 1e-9):.1f} of it"
        + (f", {'more' if p10 > r10 else 'fewer'} predicted than resolved)." if p10 != r10 else ").")
        + (
            f" By bins the top is still optimistic: predicted {top[4]:.2f} on average above 0.8, {top[5]:.2f} resolved."
            if top
            else ""
        )
        + (
            f" At 10 runs, {len(high10)} ties were predicted 0.8 or more: "
            + ", ".join(f"{n} {status}" for status, n in Counter(high10).most_common())
            + f" ({lost_all} of them lost every run)."
            if high10
            else ""
        )
        + " The runs still lost: "
        + "; ".join(
            f"{c['scenario']} seed {c['seed']} ({c['strategies']['repeat:sweep']['lost']} of "
            f"{c['strategies']['repeat:sweep']['runs']}: {c['best']['sweep']})"
            for c in w
            if c["strategies"]["repeat:sweep"]["lost"]
        )
        + ". Checked for seed 7280: the hidden tyre slip (`c_alpha` 15.9) makes the truth's own "
        "closed loop there weakly unstable (weave +0.07 1/s), which neither rival's fit foresees (they predict a "
        f"lean of 0.15 and 0.08 rad, within {MAX_ROLL:g}): a lean rule from the rivals cannot catch a truth that "
        "neither describes. The wrong decisions (the loop's posterior reaching 0.95 for the rival) count against "
        "the odds as in the decays'.",
        "",
    ]
    return out


def _settled_lines(n_max: int) -> list[str]:
    """The section on the multisines with today's plan (:data:`SWEEP_SETTLED` against :data:`SWEEP_RULE`)."""
    from validation.loop import NEITHER_P

    before, now = _stored(SWEEP_RULE), _stored(SWEEP_SETTLED)
    if not before or not now:
        return []

    def with_sweep(cases):
        return [c for c in cases if c.get("status") == "loop" and "repeat:sweep" in (c.get("strategies") or {})]

    out = [
        "### Multisines: friction rivals' runs simulated, every rival's transient settled",
        "",
        "The same ties again, the plan's best multisine repeated, after two changes to the plan. A friction rival's",
        "multisine is judged by its run simulated in time, not by a describing function that locks the steer wherever",
        "the multisine alone cannot move it (the locked-steer bicycle falls, so such runs were left out as leaning too",
        "far, or kept with a lean the run does not have). And each run settles for three time constants of the slowest",
        "mode of the nominal loop and of every rival's, 5-60 s (`sweeps.SETTLE_RANGE`), not of the nominal loop's",
        "alone: a truth with a slower mode was read with its transient (seed 7206, a heavily damped steer: chi^2 96 on",
        "18 degrees of freedom after 11 s, 1.5 after 37 s). The loop also notes the first run that no rival describes",
        f"(its best chi-square beyond the {1 - NEITHER_P:g} quantile: `validation.loop.NEITHER_P`).",
        "",
        "| plan | ties with a multisine | multisines left out for the lean (mean per tie) | resolved | wrong | "
        "wrong after a run no rival describes | undecided | runs lost / spent | at 10 runs: predicted, added | "
        "resolved |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, cases in (("stored (above)", before), ("today's", now)):
        w = with_sweep(cases)
        st = [c["strategies"]["repeat:sweep"] for c in w]
        ties = [c for c in cases if c.get("status") == "loop"]
        lean = np.mean([c.get("sweeps_left_out_lean", 0) for c in ties]) if ties else math.nan
        noted = "neither" in (st[0] if st else {})
        wrong_neither = sum(s["status"] == "wrong" and s.get("neither") is not None for s in st) if noted else None
        n10, p10, r10, sd10 = _at10(w, n_max)
        out.append(
            f"| {name} | {len(w)} | {lean:.1f} | {sum(s['status'] == 'resolved' for s in st)} | "
            f"{sum(s['status'] == 'wrong' for s in st)} | {'not noted' if wrong_neither is None else wrong_neither} | "
            f"{sum(s['status'] == 'undecided' for s in st)} | {sum(s['lost'] for s in st)} / "
            f"{sum(s['runs'] for s in st)} | {p10:.1f} (scatter {sd10:.1f}) | {r10} |"
        )
    w = with_sweep(now)
    st = {(c["scenario"], c["seed"]): c["strategies"]["repeat:sweep"] for c in w}
    wrong = Counter(c["scenario"] for c in w if st[(c["scenario"], c["seed"])]["status"] == "wrong")
    neither = [s for s in st.values() if s.get("neither") is not None]
    resolved_neither = sum(s["status"] == "resolved" for s in neither)
    chi = sorted(s["neither"]["chi2"] for s in neither)
    friction_only = all(
        "friction" in key[0].split(" vs ")[0] or "coulomb" in key[0].split(" vs ")[0]
        for key, s in st.items()
        if s.get("neither") is not None
    )
    high = Counter(c["strategies"]["repeat:sweep"]["status"] for c in w if c["predicted"]["sweep"][9] >= 0.8)
    out += [
        "",
        "Today's plan, binned as above:",
        "",
    ]
    out += _bin_table(w, n_max)
    out += [
        "",
        "* Wrong decisions by scenario: " + ", ".join(f"{k} {v}" for k, v in wrong.most_common()) + ". "
        f"{len(neither)} ties met a run no rival describes (chi-square {chi[0]:.0f} to {chi[-1]:.0f}), "
        f"{sum(s['status'] == 'wrong' for s in neither)} of them decided wrong and {resolved_neither} right: "
        "decisions between two models the data reject. "
        + ("They are all" if friction_only else "Most are")
        + " friction truths of the tables mode, whose rival "
        "is the viscous damping that acts as the friction at the decays' amplitude; a multisine drives the steer at "
        "another amplitude, where that damping is not the friction's. The diagnosis, given the multisine's records, "
        "fits the friction itself (records are read with every candidate); the loop's linear rivals cannot, so these "
        "ties say nothing of the plan's odds."
        if neither
        else "* No run met that no rival describes.",
        "* At 10 runs, ties predicted 0.8 or more: " + ", ".join(f"{n} {k}" for k, n in high.most_common()) + ".",
    ]
    rest = [c for c in w if st[(c["scenario"], c["seed"])].get("neither") is None]
    if neither and rest:
        n10, p10, r10, sd10 = _at10(rest, n_max)
        status = Counter(st[(c["scenario"], c["seed"])]["status"] for c in rest)
        out.append(
            f"* The other {len(rest)} ties (every run described by a rival): "
            + ", ".join(f"{n} {k}" for k, n in status.most_common())
            + f"; at 10 runs predicted {p10:.1f}, resolved {r10} (scatter {sd10:.1f}): "
            + ("pessimistic" if p10 < r10 else "optimistic")
            + f" by {abs(p10 - r10) / max(sd10, 1e-9):.1f} of the scatter. By bins:"
        )
        out += [""] + _bin_table(rest, n_max)
    out.append("")
    return out


def _now_lines(n_max: int) -> list[str]:
    """The next run's strategy (``plan:jensen_renyi``) with and without the lean rule, beside the even spread, on
    today's code (:data:`JR_RULE`, :data:`JR_NO_RULE`, :data:`EVEN_NOW`)."""
    from validation import loop as L

    files = (("plan:jensen_renyi, lean rule off", JR_NO_RULE), ("plan:jensen_renyi, lean rule", JR_RULE))
    files += (("even", EVEN_NOW),)
    got = {label: [c for c in _stored(path) if c.get("strategies")] for label, path in files}
    if not all(got.values()):
        return []
    keys = set.intersection(*({(c["scenario"], c["seed"]) for c in cs} for cs in got.values()))
    out = [
        "### The next run `--next` names, with the lean rule",
        "",
        f"`plan:jensen_renyi` (the next run of `--next`) with the lean rule and without, and the even spread, on the "
        f"{len(keys)} stored ties that still tied on the code of the lean rule (`rerun --strategy plan:jensen_renyi [--max-roll inf]`, "
        "`rerun --strategy even`; the unbreakable rule of runs combined):",
        "",
        "| strategy | resolved | wrong | undecided | unbreakable | runs needed: median | 90th percentile | runs lost / spent |",
        "|---|---|---|---|---|---|---|---|",
    ]
    merit = {}
    for label, cases in got.items():
        name = "even" if label == "even" else "plan:jensen_renyi"
        st = [c["strategies"][name] for c in cases if (c["scenario"], c["seed"]) in keys]
        med, p90 = L.figure_of_merit([x["runs"] if x["status"] == "resolved" else None for x in st])
        merit[label] = (st, med, p90)
        counts = {k: sum(x["status"] == k for x in st) for k in ("resolved", "wrong", "undecided", "unbreakable")}
        out.append(
            f"| {label} | {counts['resolved']} | {counts['wrong']} | {counts['undecided']} | {counts['unbreakable']} | "
            f"{_fmt(med, n_max)} | {_fmt(p90, n_max)} | {sum(x['lost'] for x in st)} / {sum(x['runs'] for x in st)} |"
        )
    jr = {(c["scenario"], c["seed"]): c["strategies"]["plan:jensen_renyi"] for c in got[files[1][0]]}
    even = {(c["scenario"], c["seed"]): c["strategies"]["even"] for c in got["even"]}
    broken = sorted(k for k in keys if jr[k]["status"] == "unbreakable" and even[k]["status"] == "resolved")
    (off, m_off, _), (on, m_on, _), (ev, m_ev, _) = (merit[label] for label, _ in files)

    def resolved(st):
        return sum(x["status"] == "resolved" for x in st)

    out += [
        "",
        f"* With the rule the next run resolves {resolved(on)} ties against {resolved(off)} without it, losing "
        f"{sum(x['lost'] for x in on)} runs instead of {sum(x['lost'] for x in off)}; the even spread resolves "
        f"{resolved(ev)}. Goal 1 (the plan's median at most half the even spread's): {_fmt(m_on, n_max)} against "
        f"{_fmt(m_ev, n_max)}, "
        + ("**met**." if math.isfinite(m_on) and (not math.isfinite(m_ev) or m_on <= m_ev / 2) else "**not met**."),
        f"* Goal 2 with the lean rule: {len(broken)} ties declared unbreakable that the even spread breaks"
        + (": " + ", ".join(f"{a} seed {b}" for a, b in broken) if broken else "")
        + ".",
        "",
    ]
    return out


def _today_lines(n_max: int) -> list[str]:
    """The next run's strategy against the even spread on the code of :data:`SWEEP_SETTLED` (:data:`JR_SETTLED`,
    :data:`EVEN_SETTLED`), the runs no rival describes counted apart."""
    return _against_even_lines(
        n_max,
        (("plan:jensen_renyi", JR_SETTLED), ("even", EVEN_SETTLED)),
        "### The next run `--next` names, on the same plan",
        "`plan:jensen_renyi` and the even spread again on the {n} stored ties that tie on the code of the "
        "previous section (friction rivals' multisines simulated, every rival's transient settled; `rerun "
        "--strategy plan:jensen_renyi --tag settled`, `rerun --strategy even --tag settled`). *Described* are the ties "
        "where every run of the strategy was described by a rival (`validation.loop.NEITHER_P`):",
    )


def _shared_today_lines(n_max: int) -> list[str]:
    """:func:`_today_lines` with the nominal parameters' uncertainty shared by all runs (:data:`JR_SHARED_SETTLED`,
    :data:`EVEN_SHARED_SETTLED`)."""
    return _against_even_lines(
        n_max,
        (("plan:jensen_renyi", JR_SHARED_SETTLED), ("even", EVEN_SHARED_SETTLED)),
        "### The next run against the even spread, the parameters' error shared by the runs",
        "The same {n} ties and runs as the previous section, each rival's evidence counting the nominal parameters' "
        "uncertainty once for all runs (linearised in their shifts, standard normal prior; `rerun --strategy "
        "plan:jensen_renyi --shared --tag settled`, `rerun --strategy even --shared --tag settled`), as the diagnosis "
        "counts it (one parameter error moves every run at once; `gap.diagnosis.fits.with_parameter_uncertainty`). Per "
        "run, a run the truth's parameter error moves alike every time it is repeated counts that error anew, and "
        "the rival with the more values to fit takes it: seed 7098 (steer inertia against passive arms) went to 0.94 "
        "in five runs, then its plan repeated one decay twelve times and the hidden effect's probability fell to "
        "0.52, where the even spread resolved it at run 13. Shared:",
    )


def _shared_odds_lines(n_max: int) -> list[str]:
    """The plan's resolution probabilities against the loop's outcomes on today's code, per run and shared
    (:data:`DECAY_TODAY`, :data:`DECAY_SHARED_TODAY`, :data:`SWEEP_TODAY`, :data:`SWEEP_SHARED_TODAY`)."""
    files = {
        "decay": (DECAY_TODAY, DECAY_SHARED_TODAY),
        "sweep": (SWEEP_TODAY, SWEEP_SHARED_TODAY),
    }
    stored = {
        kind: [[c for c in _stored(path) if c.get("strategies")] for path in pair] for kind, pair in files.items()
    }
    if not all(all(got) for got in stored.values()):
        return []
    out = [
        "### Honest odds on today's code, the parameters' error per run and shared",
        "",
        "The plan's best decay and its best multisine, each repeated `k` times (k = 1-20) on every stored tie, on "
        "the code of 2026-11-29 (`rerun --strategy repeat:decay|repeat:sweep [--shared] --tag today`): the plan's "
        "probability that `k` runs favour the true rival by 19 to 1 (`Phi(d / 2 - ln 19 / d)`, the Gaussian "
        "approximation, which the plan still states for multisines; the next section sets the measure of runs "
        "combined beside it, both scored at `k` runs), "
        "binned, against the fraction the loop resolved by `k` runs, with the loop's evidence counting the nominal parameters' uncertainty per run and shared by "
        "all runs (one tie's points at different `k` are not independent; *described*: the ties whose every run a "
        "rival describes, `validation.loop.NEITHER_P`).",
        "",
    ]
    names = {"decay": "decays", "sweep": "multisines"}
    for kind, (per_run, shared) in stored.items():
        rows = {}
        for label, cases in (("per run", per_run), ("shared", shared)):
            every = _bins(_reliability(cases, kind, n_max))
            described = [c for c in cases if (c["strategies"].get(f"repeat:{kind}") or {}).get("neither") is None]
            rows[label] = ({r[0]: r for r in every}, {r[0]: r for r in _bins(_reliability(described, kind, n_max))})
            at10 = [(p, r) for p, r, _ in _reliability(cases, kind, n_max)[9::n_max]]
            rows[label] += (len(at10), sum(p for p, _ in at10), sum(r for _, r in at10),
                            math.sqrt(sum(p * (1 - p) for p, _ in at10)))  # fmt: skip
        out += [
            f"The plan's best {names[kind][:-1]} repeated:",
            "",
            "| predicted | points (ties), per run | mean predicted | resolved, per run | described | points (ties), "
            "shared | resolved, shared | described |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for lo in sorted(set(rows["per run"][0]) | set(rows["shared"][0])):
            a, b = rows["per run"][0].get(lo), rows["shared"][0].get(lo)
            da, db = rows["per run"][1].get(lo), rows["shared"][1].get(lo)
            ref = a or b
            out.append(
                f"| {ref[0]:.2f}-{ref[1]:.2f} | {f'{a[2]} ({a[3]})' if a else '-'} | {ref[4]:.2f} | "
                f"{f'{a[5]:.2f}' if a else '-'} | {f'{da[5]:.2f}' if da else '-'} | "
                f"{f'{b[2]} ({b[3]})' if b else '-'} | {f'{b[5]:.2f}' if b else '-'} | "
                f"{f'{db[5]:.2f}' if db else '-'} |"
            )
        for label in ("per run", "shared"):
            off = []
            for lo, hi, _, ties, mean, fraction in rows[label][0].values():
                scatter = math.sqrt(max(mean * (1 - mean), 0.01) / ties)  # the ties as the count: points of one
                if abs(fraction - mean) > 2 * scatter:  # tie at different k are not independent
                    off.append(f"{lo:.2f}-{hi:.2f} ({'under' if fraction > mean else 'over'}confident: {mean:.2f} "
                               f"predicted, {fraction:.2f} resolved)")  # fmt: skip
            out.append("")
            out.append(
                f"* {label.capitalize()}, bins beyond twice their scatter (the ties as the count): "
                + ("; ".join(off) if off else "none")
                + "."
            )
        for label in ("per run", "shared"):
            n10, p10, r10, sd10 = rows[label][2:]
            out.append("")
            out.append(
                f"* {label.capitalize()}, at the plan's default of 10 runs ({n10} ties, one point each): predicted "
                f"probabilities add up to {p10:.1f} (scatter {sd10:.1f} were they right), {r10} were resolved "
                f"({(r10 - p10) / sd10:+.1f} scatters)."
                if sd10 > 0
                else f"* {label.capitalize()}: no ties."
            )
        out.append("")
    return out


def _brier(points) -> float:
    """The Brier score of ``(predicted, resolved, seed)`` points: the mean squared difference, lower is better."""
    return float(np.mean([(p - r) ** 2 for p, r, _ in points])) if points else math.nan


def _off_bins(rows) -> list[str]:
    """The bins of :func:`_bins` whose fraction resolved is beyond twice its scatter (the ties as the count)."""
    off = []
    for lo, hi, _, ties, mean, fraction in rows:
        scatter = math.sqrt(max(mean * (1 - mean), 0.01) / ties)
        if abs(fraction - mean) > 2 * scatter:
            off.append(f"{lo:.2f}-{hi:.2f} ({'under' if fraction > mean else 'over'}confident: {mean:.2f} "
                       f"predicted, {fraction:.2f} resolved)")  # fmt: skip
    return off


def _odds_fixed_lines(n_max: int) -> list[str]:
    """The plan's stated probability after issue 25 item 3 against its Gaussian approximation (the probability
    it stated before), both scored at ``k`` runs on the same ties and runs (:data:`DECAY_ODDS`,
    :data:`SWEEP_ODDS`, and with the parameters' error shared :data:`DECAY_SHARED_ODDS`,
    :data:`SWEEP_SHARED_ODDS`); empty without the per-run files."""
    files = {"decay": (DECAY_ODDS, DECAY_SHARED_ODDS), "sweep": (SWEEP_ODDS, SWEEP_SHARED_ODDS)}
    stored = {
        kind: [[c for c in _stored(path) if c.get("strategies")] for path in pair] for kind, pair in files.items()
    }
    if not all(pair[0] for pair in stored.values()):
        return []
    example = ""
    for c in stored["decay"][0]:
        if c["seed"] == 7050 and c.get("predicted_gaussian"):
            s = c["strategies"]["repeat:decay"]
            example = (
                f" (seed 7050, {c['scenario']}: one decay {c['predicted_gaussian']['decay'][0]:.3f} by the Gaussian "
                f"approximation, {c['predicted']['decay'][0]:.3f} by the combined measure; the loop's probability "
                f"of the hidden effect after it {s['posterior'][0]:.3f})"
            )
    undone = {}
    for kind in ("decay", "sweep"):
        runs = [c["strategies"][f"repeat:{kind}"] for c in stored[kind][0] if f"repeat:{kind}" in c["strategies"]]
        early = [s for s in runs if "posterior" in s and s["status"] == "resolved" and s["runs"] <= 10]
        undone[kind] = (sum(s["posterior"][9] < 0.95 for s in early), len(early))
    out = [
        "### Honest odds with both rivals' distributions: the measure of runs combined, scored at `k` runs",
        "",
        "The probability above is `Phi(d / 2 - ln 19 / d)`, `d` the rivals' difference of means weighed by the "
        "true rival's covariance alone: a rival much vaguer than the other, whose means nearly coincide, is told "
        "apart by a run near the sharp rival's prediction, which the difference of means cannot see" + example + ". "
        "The plan's own measure of runs combined compares both rivals' predictive distributions; for `k` runs of "
        "the one experiment (`gap.plan.discrimination.combined_probability`): under each rival taken true the "
        "runs' mean drawn from its predictive distribution (its fitted values' uncertainty, the runs' noise, its "
        "held-out misfit systematic), the exact log Bayes factor against the other rival's predictive "
        "distribution counted against ln 19 (2000 draws per rival, a fixed seed). The same ties, experiments and "
        "runs as the previous section, the plan made to state this measure (`rerun --strategy "
        "repeat:decay|repeat:sweep [--shared] --stated combined --tag odds`; the ranking, by the Gaussian "
        "approximation, is the same, and each case stores both probabilities). Scored *at* `k` runs, as the plan "
        "states its probability: resolved is the hidden effect's probability at 0.95 or more after run `k`, the "
        "loop run on past its decision (the previous section scored *by* `k` runs, a decision at any run up to "
        "`k`, which later runs may undo: of the ties the loop resolved within 10 runs, "
        f"{undone['decay'][0]} of {undone['decay'][1]} by decays and {undone['sweep'][0]} of {undone['sweep'][1]} "
        "by multisines stood below 0.95 at run 10). Before: the Gaussian approximation; after: the combined "
        "measure; the loop's evidence counting the nominal parameters' uncertainty per run:",
        "",
    ]
    briers, shared_briers = {}, {}
    names = {"decay": "decays", "sweep": "multisines"}
    for kind, (per_run, shared) in stored.items():
        before = _reliability(per_run, kind, n_max, at=True, key="predicted_gaussian")
        after = _reliability(per_run, kind, n_max, at=True)
        rows_b, rows_a = {r[0]: r for r in _bins(before)}, {r[0]: r for r in _bins(after)}
        out += [
            f"The plan's best {names[kind][:-1]} repeated:",
            "",
            "| predicted | before: points (ties) | mean predicted | resolved at `k` | after: points (ties) | "
            "mean predicted | resolved at `k` |",
            "|---|---|---|---|---|---|---|",
        ]
        for lo in sorted(set(rows_b) | set(rows_a)):
            b, a = rows_b.get(lo), rows_a.get(lo)
            ref = a or b
            cells = [f"{x[2]} ({x[3]}) | {x[4]:.2f} | {x[5]:.2f}" if x else "- | - | -" for x in (b, a)]
            out.append(f"| {ref[0]:.2f}-{ref[1]:.2f} | {cells[0]} | {cells[1]} |")
        out.append("")
        briers[kind] = (_brier(before), _brier(after))
        by_k = [_reliability(per_run, kind, n_max, key=key) for key in ("predicted_gaussian", "predicted")]
        out.append(
            f"* Brier score at `k` runs, per run: before {_brier(before):.3f}, after {_brier(after):.3f} (scored by "
            f"`k` runs, as the previous section: before {_brier(by_k[0]):.3f}, after {_brier(by_k[1]):.3f})."
        )
        off = {label: _off_bins(_bins(x)) for label, x in (("before", before), ("after", after))}
        out.append("")
        out.append(
            "* Bins beyond twice their scatter (the ties as the count), per run: before "
            + ("; ".join(off["before"]) if off["before"] else "none")
            + "; after "
            + ("; ".join(off["after"]) if off["after"] else "none")
            + "."
        )
        for label, cases in (("per run", per_run), ("shared", shared)):
            if not cases:
                continue
            b = _reliability(cases, kind, n_max, at=True, key="predicted_gaussian")
            a = _reliability(cases, kind, n_max, at=True)
            b10, a10 = b[9::n_max], a[9::n_max]
            resolved = sum(r for _, r, _ in a10)
            by10 = sum(r for _, r, _ in _reliability(cases, kind, n_max)[9::n_max])
            sd = math.sqrt(sum(p * (1 - p) for p, _, _ in a10))
            shared_brier = (
                f"; Brier score at `k` runs: before {_brier(b):.3f}, after {_brier(a):.3f}" if label == "shared" else ""
            )
            if label == "shared":
                shared_briers[kind] = (_brier(b), _brier(a))
            out.append("")
            out.append(
                f"* {label.capitalize()}, at the plan's default of 10 runs ({len(a10)} ties, one point each): "
                f"probabilities before add up to {sum(p for p, _, _ in b10):.1f}, after to "
                f"{sum(p for p, _, _ in a10):.1f} (scatter {sd:.1f} were they right); {resolved} at 0.95 or more at "
                f"run 10 ({by10} resolved by run 10){shared_brier}."
            )
        out.append("")
    from bikerider.gap.plan.discrimination import STATED

    out += [
        "* Which the plan states (`gap.plan.discrimination.STATED`): "
        + "; ".join(
            f"for {names[k]} "
            + ("the combined measure" if STATED.get(k) == "combined" else "the Gaussian approximation")
            + f" (Brier score at `k` runs, per run, {b:.3f} -> {a:.3f}"
            + (f"; shared {shared_briers[k][0]:.3f} -> {shared_briers[k][1]:.3f}" if k in shared_briers else "")
            + ")"
            for k, (b, a) in briers.items()
        )
        + ". The evidence with the parameters' error shared by the runs is the diagnosis's own (one parameter "
        "error moves every run at once); counted per run, a decision the runs' shared error made is undone by "
        "later runs.",
        "",
    ]
    return out


RECALIBRATION_SPLITS = 50
"""Random halves of the ties (seeded) on which :func:`_recalibration_lines` fits a map and scores it on the rest."""


def _platt(predicted: np.ndarray, resolved: np.ndarray) -> np.ndarray:
    """A logistic map of the predicted probability's log odds, ``(a, b)`` of ``logit q = a + b logit p``, fitted by
    maximum likelihood to the loop's outcomes (Platt 1999), by Newton's method (iteratively reweighted least
    squares; the log-likelihood is concave in ``(a, b)``)."""
    x = _logit(predicted)
    X = np.stack([np.ones_like(x), x], axis=1)
    y = np.asarray(resolved, float)

    def loss(w: np.ndarray) -> float:
        z = X @ w
        return float(np.sum(np.logaddexp(0.0, z) - y * z))

    w = np.array([0.0, 1.0])
    for _ in range(200):
        q = 1 / (1 + np.exp(-(X @ w)))
        gradient = X.T @ (q - y)
        if np.max(np.abs(gradient)) < 1e-8 * max(1, y.size):
            return w
        H = X.T @ (X * (q * (1 - q))[:, None]) + 1e-9 * np.eye(2)
        step, t = np.linalg.solve(H, gradient), 1.0
        while loss(w - t * step) > loss(w) and t > 1e-12:  # backtracking: the loss never rises
            t /= 2
        w = w - t * step
    raise RuntimeError("the logistic map of the plan's probabilities did not converge")


def _logit(p: np.ndarray) -> np.ndarray:
    p = np.clip(p, 1e-4, 1 - 1e-4)  # the plan rounds to five digits: 0 and 1 stand for beyond 1e-4 of them
    return np.log(p / (1 - p))


def _isotonic(predicted: np.ndarray, resolved: np.ndarray):
    """A non-decreasing map of the predicted probability fitted to the outcomes (pool-adjacent-violators), as a
    function interpolating between the training points."""
    from scipy.optimize import isotonic_regression

    order = np.argsort(predicted, kind="stable")
    x, y = predicted[order], isotonic_regression(resolved[order].astype(float)).x
    return lambda p: np.interp(p, x, y)


def _recalibration_lines(n_max: int) -> list[str]:
    """Whether a map of the plan's probabilities fitted to the loop's outcomes would predict other ties' outcomes
    better: the probabilities the plan states (:data:`bikerider.gap.plan.discrimination.STATED`) scored at ``k``
    runs (:data:`DECAY_ODDS`, :data:`SWEEP_ODDS`), else, without those files, the ones stored in
    :data:`DECAY_TODAY`, :data:`SWEEP_TODAY` scored by ``k`` runs; fitted on a random half of the ties, scored on the other half (Brier score, the count
    resolved at 10 runs), :data:`RECALIBRATION_SPLITS` times."""
    from bikerider.gap.plan.discrimination import STATED

    now = all(any(c.get("strategies") for c in _stored(path)) for path in (DECAY_ODDS, SWEEP_ODDS))
    out = [
        (
            "A map of the probabilities the plan states (for decays "
            + ("the combined measure" if STATED.get("decay") == "combined" else "the Gaussian approximation")
            + ", for multisines "
            + ("the combined measure" if STATED.get("sweep") == "combined" else "the Gaussian approximation")
            + "), fitted to the outcomes at `k` runs of the previous section, scored on ties it was not fitted to"
            if now
            else "A map of the plan's probabilities fitted to these outcomes, scored on ties it was not fitted to"
        )
        + " (per run; "
        f"fitted on a random half of the ties, scored on the other half, {RECALIBRATION_SPLITS} halvings; Brier "
        "score: the mean squared difference of probability and outcome, lower is better; a logistic map of the "
        "log odds, Platt 1999, and a non-decreasing one, pool-adjacent-violators):",
        "",
        "| experiment | ties | Brier: plan | logistic map | non-decreasing map | at 10 runs: plan | logistic map "
        "| non-decreasing map | resolved | logistic map on all ties |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    names = {"decay": "decays", "sweep": "multisines"}
    verdicts = []
    for kind, path in (("decay", DECAY_ODDS if now else DECAY_TODAY), ("sweep", SWEEP_ODDS if now else SWEEP_TODAY)):
        cases = [c for c in _stored(path) if c.get("strategies")]
        key = "predicted" if STATED.get(kind) == "combined" or not now else "predicted_gaussian"
        points = _reliability(cases, kind, n_max, at=now, key=key)
        if not points:
            return []
        p = np.array([q for q, _, _ in points])
        y = np.array([r for _, r, _ in points], dtype=float)
        seed = np.array([s for _, _, s in points])
        k = np.tile(np.arange(1, n_max + 1), len(points) // n_max)
        ties = np.unique(seed)
        rng = np.random.default_rng(0)
        scores = []
        for _ in range(RECALIBRATION_SPLITS):
            test = np.isin(seed, rng.choice(ties, ties.size // 2, replace=False))
            a, b = _platt(p[~test], y[~test])
            logistic = 1 / (1 + np.exp(-(a + b * _logit(p[test]))))
            isotonic = _isotonic(p[~test], y[~test])(p[test])
            at10 = k[test] == 10
            scores.append(
                [np.mean((q - y[test]) ** 2) for q in (p[test], logistic, isotonic)]
                + [q[at10].sum() for q in (p[test], logistic, isotonic, y[test])]
            )
        m = np.mean(scores, axis=0)
        a, b = _platt(p, y)
        out.append(
            f"| {names[kind]} | {ties.size} (halves of {ties.size // 2}) | {m[0]:.3f} | {m[1]:.3f} | {m[2]:.3f} | "
            f"{m[3]:.1f} | {m[4]:.1f} | {m[5]:.1f} | {m[6]:.1f} | logit q = {a:+.2f} + {b:.2f} logit p |"
        )
        best = min((m[1], "logistic"), (m[2], "non-decreasing"))
        verdicts.append(
            f"{names[kind]}: the {best[1]} map lowers the held-out Brier score {m[0]:.3f} -> {best[0]:.3f}"
            if best[0] < m[0]
            else f"{names[kind]}: neither map lowers the held-out Brier score ({m[0]:.3f} -> {m[1]:.3f}, {m[2]:.3f})"
        )
    out += [
        "",
        "* " + "; ".join(verdicts) + ". No map is applied to the plan's output: it would be learned from the "
        "simulated loop, whose runs scatter as the truth's simulator makes them, and tell a researcher's real runs "
        "the simulation's odds (docs/gap.md, *What to measure next*).",
        "",
    ]
    return out


def _shared_reading_lines() -> list[str]:
    """The reading of :func:`_shared_today_lines` against :func:`_today_lines`: how the evidence's model of the
    parameters' error moves the decisions (empty without both pairs of files)."""
    pairs = {}
    for label, files in (("per run", (JR_SETTLED, EVEN_SETTLED)), ("shared", (JR_SHARED_SETTLED, EVEN_SHARED_SETTLED))):
        got = [{(c["scenario"], c["seed"]): c for c in _stored(path) if c.get("strategies")} for path in files]
        if not all(got):
            return []
        pairs[label] = got
    counts = {}
    for label, (jr, ev) in pairs.items():
        counts[label] = {
            name: Counter(c["strategies"][name]["status"] for c in cases.values())
            for name, cases in (("plan:jensen_renyi", jr), ("even", ev))
        }
    a, b = counts["per run"], counts["shared"]
    return [
        "* On today's code (the two *next run* sections above) the loop's evidence model decides the goals. Counting "
        "the truth's parameter error once for all runs, as the diagnosis does, the next run resolves "
        f"{b['plan:jensen_renyi']['resolved']} ties and decides {b['plan:jensen_renyi']['wrong']} wrongly (per run "
        f"{a['plan:jensen_renyi']['resolved']} and {a['plan:jensen_renyi']['wrong']}; the even spread "
        f"{b['even']['resolved']} and {b['even']['wrong']}, per run {a['even']['resolved']} and {a['even']['wrong']}; "
        "the goals are judged under each section's table). Counted per run, a parameter error that moves a repeated run alike every time "
        "is counted anew at each repeat, the rival with the more values to fit absorbs it, and a plan that repeats its "
        "best run is led away from the truth by it (seed 7098); the even spread, never repeating, suffers it less. "
        "The per-run loop is the harsher test, and the one the tables above the *next run* sections use.",
    ]


def _against_even_lines(n_max: int, files, title: str, intro: str) -> list[str]:
    """One strategy against the even spread on the ties both files hold (``files``: ``(name, path)`` pairs, the
    strategy first), the runs no rival describes counted apart; ``intro``'s ``{n}`` is the number of ties."""
    from validation import loop as L

    got = {name: {(c["scenario"], c["seed"]): c for c in _stored(path) if c.get("strategies")} for name, path in files}
    if not all(got.values()):
        return []
    keys = sorted(set.intersection(*(set(cs) for cs in got.values())))
    out = [
        title,
        "",
        intro.format(n=len(keys)),
        "",
        "| strategy | ties | resolved | wrong | wrong after a run no rival describes | undecided | unbreakable | "
        "runs needed: median | 90th percentile | described: ties, resolved, wrong, median | runs lost / spent |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    merit, described = {}, {}
    for name, _ in files:
        st = {k: got[name][k]["strategies"][name] for k in keys}
        med, p90 = L.figure_of_merit([x["runs"] if x["status"] == "resolved" else None for x in st.values()])
        clean = {k: x for k, x in st.items() if x.get("neither") is None}
        med_c, _ = L.figure_of_merit([x["runs"] if x["status"] == "resolved" else None for x in clean.values()])
        merit[name], described[name] = (st, med, p90), (clean, med_c)
        counts = Counter(x["status"] for x in st.values())
        out.append(
            f"| {name} | {len(st)} | {counts['resolved']} | {counts['wrong']} | "
            f"{sum(x['status'] == 'wrong' and x.get('neither') is not None for x in st.values())} | "
            f"{counts['undecided']} | {counts['unbreakable']} | {_fmt(med, n_max)} | {_fmt(p90, n_max)} | "
            f"{len(clean)}, {sum(x['status'] == 'resolved' for x in clean.values())}, "
            f"{sum(x['status'] == 'wrong' for x in clean.values())}, {_fmt(med_c, n_max)} | "
            f"{sum(x['lost'] for x in st.values())} / {sum(x['runs'] for x in st.values())} |"
        )
    (jr, m_jr, _), (ev, m_ev, _) = merit[files[0][0]], merit["even"]
    both = [k for k in keys if k in described[files[0][0]][0] and k in described["even"][0]]
    med_jr, _ = L.figure_of_merit(
        [jr[k]["runs"] if jr[k]["status"] == "resolved" else None for k in both]  # the same ties for both
    )
    med_ev, _ = L.figure_of_merit([ev[k]["runs"] if ev[k]["status"] == "resolved" else None for k in both])
    broken = [k for k in keys if jr[k]["status"] == "unbreakable" and ev[k]["status"] == "resolved"]

    def met(a, b):
        return "**met**" if math.isfinite(a) and (not math.isfinite(b) or a <= b / 2) else "**not met**"

    out += [
        "",
        f"* Goal 1 (the plan's median at most half the even spread's): {_fmt(m_jr, n_max)} against "
        f"{_fmt(m_ev, n_max)} on every tie, {met(m_jr, m_ev)}; on the {len(both)} ties both strategies saw described "
        f"throughout, {_fmt(med_jr, n_max)} against {_fmt(med_ev, n_max)}, {met(med_jr, med_ev)}.",
        f"* Goal 2: {len(broken)} {'tie' if len(broken) == 1 else 'ties'} declared unbreakable that the even spread "
        "breaks" + (": " + ", ".join(f"{a} seed {b}" for a, b in broken) if broken else "") + ".",
        "",
    ]
    return out


def _same_first(a: dict | None, b: dict | None) -> bool:
    """Whether two next runs (``validation.loop._first``) are the same experiment: kind, speed, law and push."""
    if a is None or b is None:
        return False
    return (a["kind"], round(a["speed"], 2), a["law"], a.get("push") or 1.0) == (
        b["kind"],
        round(b["speed"], 2),
        b["law"],
        b.get("push") or 1.0,
    )


def _push_of(c: dict, e: int) -> float | None:
    """The push of experiment ``e`` of a records case (``None``: a multisine)."""
    return c["pushes"][e] if e < len(c["pushes"]) else None


def _by_first(ties: list[dict], plan: str) -> str:
    """The plan's outcomes grouped by what its first run was (a decay at the data's push, at another, a multisine)."""
    groups: dict[str, list[str]] = {}
    for c in ties:
        s = c["strategies"][plan]
        if not s["chosen"]:
            continue
        push = _push_of(c, s["chosen"][0])
        what = (
            "a multisine"
            if push is None
            else ("a decay at the data's push" if push == 1.0 else f"a decay at {push:g} times")
        )
        groups.setdefault(what, []).append(s["status"])
    return "; ".join(
        f"{what}, {len(st)} ties: " + ", ".join(f"{n} {status}" for status, n in Counter(st).most_common())
        for what, st in sorted(groups.items())
    )


def _push_stats(path: Path, only: set | None = None) -> tuple[int, list, dict, list]:
    """From a push-check file: the ties checked, ``rows`` (push, candidate's z real, z freq, other's z real, z
    freq), ``moves`` (push -> (truth's move, candidate's predicted move, other's, the runs' noise)) and
    ``odds`` (push, the plan's probability that the run favours the candidate by 19 to 1, whether it did);
    ``only``: those (scenario, seed) alone."""
    checked = [c for c in _stored(path) if c.get("runs") and (only is None or (c["scenario"], c["seed"]) in only)]
    rows, moves, odds = [], {}, []
    for c in checked:
        cand = c["candidate"]
        other = next(n for n in c["rivals"] if n != cand)
        groups: dict[tuple, dict] = {}
        for r in c["runs"]:
            if r["lost"]:
                continue
            groups.setdefault((r["speed"], r["law"]), {})[r["push"]] = r
            z = []
            y, noise = np.array(r["y"]), np.array(r["sd"])
            pred = {}
            for name in (cand, other):
                mu, sd = np.array(r["rivals"][name]["mean"]), np.array(r["rivals"][name]["sd"])
                z += list((y - mu) / np.hypot(sd, noise))
                pred[name] = (mu, sd**2 + noise**2)
            rows.append((r["push"], *z))
            odds.append((r["push"], *_one_run_odds(y, pred[cand], pred[other])))
        for g in groups.values():
            if 1.0 not in g:
                continue
            base = g[1.0]
            for push, r in g.items():
                if push == 1.0:
                    continue
                truth = np.array(r["y"]) - np.array(base["y"])
                pred = [np.array(r["rivals"][n]["mean"]) - np.array(base["rivals"][n]["mean"]) for n in (cand, other)]
                moves.setdefault(push, []).append((truth, *pred, np.hypot(r["sd"], base["sd"])))
    return len(checked), rows, moves, odds


def _control_lines() -> list[str]:
    """Today's code with the kick spanned against the same code without (:data:`RECORDS_PUSH_NO_KICK`), on the
    ties both checked: what the kick's span alone changes."""
    control = {(c["scenario"], c["seed"]) for c in _stored(RECORDS_PUSH_NO_KICK) if c.get("runs")}
    if not control:
        return []
    spanned = RECORDS_PUSH_BEFORE_FRICTION  # the control ran beside this check, on the code of its time
    common = control & {(c["scenario"], c["seed"]) for c in _stored(spanned) if c.get("runs")}
    _, rows, moves, odds = _push_stats(spanned, common)
    _, rows_off, moves_off, odds_off = _push_stats(RECORDS_PUSH_NO_KICK, common)
    out = [
        "",
        f"The kick's span alone (the check before, `{spanned.name}`): the same {len(common)} ties on the code of its "
        f"time with the span off (`push-check --no-kick`, `{RECORDS_PUSH_NO_KICK.name}`: templates from the data's "
        "steer state, the steer rate 0), z mean (RMS), spanned / off:",
        "",
        "| push | runs | candidate: z of the decay rate | z of the frequency | rival: z of the decay rate | "
        "z of the frequency | candidate's sd of the frequency, median [rad/s] | its predicted move of the frequency |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for push in sorted({r[0] for r in rows}):
        now, off = _z_cells(rows, push), _z_cells(rows_off, push)
        n_now, n_off = sum(r[0] == push for r in rows), sum(r[0] == push for r in rows_off)
        sd = f"{_median_sd(spanned, push, common):.3f} / {_median_sd(RECORDS_PUSH_NO_KICK, push, common):.3f}"
        move = "-"
        if push in moves and push in moves_off:
            move = (
                f"{np.median(np.abs([x[1][1] for x in moves[push]])):.3f} / "
                f"{np.median(np.abs([x[1][1] for x in moves_off[push]])):.3f}"
            )
        out.append(
            f"| {push:g} | {n_now} / {n_off} | "
            + " | ".join(f"{a} / {b}" for a, b in zip(now, off))
            + f" | {sd} | {move} |"
        )
    rms = {}
    for push in sorted({r[0] for r in rows} & {r[0] for r in rows_off}):
        z_now = np.array([r[2] for r in rows if r[0] == push])
        z_off = np.array([r[2] for r in rows_off if r[0] == push])
        rms[push] = (float(np.sqrt(np.mean(z_now**2))), float(np.sqrt(np.mean(z_off**2))))
    if rms:
        out += [
            "",
            "* The candidate's z RMS of the frequency, spanned / off: "
            + "; ".join(f"{p:g} times {a:.2f} / {b:.2f}" for p, (a, b) in rms.items())
            + ". Where z RMS stays above 1 the truth's runs scatter and move with the push further than the "
            "candidate's own friction law, kicked over the whole range, responds (below).",
        ]
    for label, keep in (("a push other than the data's", lambda x: x != 1.0), ("the data's push", lambda x: x == 1.0)):
        a = [(p, h) for push, p, h in odds if keep(push)]
        b = [(p, h) for push, p, h in odds_off if keep(push)]
        top_a = [h for p, h in a if p >= 0.95]
        top_b = [h for p, h in b if p >= 0.95]
        out.append("")
        out.append(
            f"* One run at {label}, spanned / off: predicted probabilities add up to {sum(p for p, _ in a):.1f} / "
            f"{sum(p for p, _ in b):.1f} over {len(a)} / {len(b)} runs, {sum(h for _, h in a)} / "
            f"{sum(h for _, h in b)} did; of the runs predicted at 0.95 or more, {np.mean(top_a) if top_a else math.nan:.2f}"
            f" / {np.mean(top_b) if top_b else math.nan:.2f} did."
        )
    return out


def _median_sd(path: Path, push: float, only: set) -> float:
    """The friction candidate's predictive standard deviation of the frequency at ``push``, median over the runs."""
    sd = [
        r["rivals"][c["candidate"]]["sd"][1]
        for c in _stored(path)
        if c.get("runs") and (c["scenario"], c["seed"]) in only
        for r in c["runs"]
        if not r["lost"] and r["push"] == push
    ]
    return float(np.median(sd)) if sd else math.nan


def _one_run_odds(y: np.ndarray, true: tuple, other: tuple) -> tuple[float, bool]:
    """One run ``y`` against two rivals' predictive distributions ``(mean, variances)`` (diagonal, as stored):
    the plan's probability that it favours the first by 19 to 1 (``Phi(d / 2 - ln 19 / d)``, ``d`` weighted by
    the first's variances) and whether its likelihood ratio did."""
    from scipy.special import ndtr

    delta = true[0] - other[0]
    d = math.sqrt(float(np.sum(delta**2 / true[1])))
    p = float(ndtr(d / 2 - math.log(19) / d)) if d > 0 else 0.0

    def log_density(mu, var):
        return float(-0.5 * np.sum((y - mu) ** 2 / var + np.log(2 * math.pi * var)))

    return p, log_density(*true) - log_density(*other) >= math.log(19)


def _z_cells(rows: list, push: float) -> list[str]:
    z = np.array([r[1:] for r in rows if r[0] == push])
    if not len(z):
        return ["-"] * 4
    return [f"{np.mean(z[:, j]):+.2f} ({np.sqrt(np.mean(z[:, j] ** 2)):.2f})" for j in range(4)]


def _push_lines() -> list[str]:
    """How the truth's decay moves with the push against how the rivals predict it (:data:`RECORDS_PUSH`), and
    the same check of the run before (:data:`RECORDS_PUSH_BEFORE_FRICTION`, on its own ties)."""
    n_checked, rows, moves, odds = _push_stats(RECORDS_PUSH)
    if not n_checked:
        return []
    checked = {(c["scenario"], c["seed"]) for c in _stored(RECORDS_PUSH) if c.get("runs")}
    n_before, rows_before, moves_before, odds_before = _push_stats(RECORDS_PUSH_BEFORE_FRICTION)
    checked_before = {(c["scenario"], c["seed"]) for c in _stored(RECORDS_PUSH_BEFORE_FRICTION) if c.get("runs")}
    pushes = sorted({r[0] for r in rows} | {r[0] for r in rows_before})
    out = [
        f"How the truth's decay moves with the push ({n_checked} ties of the run above, `push-check`: at up to four "
        "speeds and laws where the plan holds a decay at every push, the truth's first run at each push, as the "
        "loop runs it, against the rivals' predictions, each with its spread over the kick's initial steer rate, "
        "a friction rival's over its friction law's corner and over the record fit's valleys; the friction truths' "
        "candidate `steer_friction` first). z: the truth's run minus the rival's prediction over their standard "
        "deviations combined (a rival that foresees the truth has z of mean 0 and RMS about 1); before: the same "
        f"check of the run before the friction fits changed, on its own ties ({n_before} ties, "
        f"`{RECORDS_PUSH_BEFORE_FRICTION.name}`, code of commit a2973b2: templates over the kick's steer rate, no "
        f"friction corners, the friction rival's initial state fitted to the nominal template; "
        f"{len(checked & checked_before)} ties in both):",
        "",
        "| push | runs (before) | candidate: z of the decay rate, mean (RMS) | before | z of the frequency | before | "
        "rival: z of the decay rate | before | z of the frequency | before |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for push in pushes:
        now, then = _z_cells(rows, push), _z_cells(rows_before, push)
        n_now = sum(r[0] == push for r in rows)
        n_then = sum(r[0] == push for r in rows_before)
        cells = [x for pair in zip(now, then) for x in pair]
        out.append(f"| {push:g} | {n_now} ({n_then}) | " + " | ".join(cells) + " |")
    out += [
        "",
        "The move from the data's push: the truth's run at the push minus its run at the data's push (the same "
        "draws, the kick scaled), against the move the candidate predicts (before: the check before):",
        "",
        "| push | pairs of runs | truth's move of the frequency: median abs [rad/s] | candidate's predicted move | "
        "before | same sign | truth's move of the decay rate: median abs [1/s] | candidate's predicted move | before | "
        "truth's moves beyond twice the runs' noise |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]

    def median_move(m, j, what=1):
        return float(np.median(np.abs(np.array([x[what] for x in m])[:, j]))) if m else math.nan

    for push, m in sorted(moves.items()):
        truth = np.array([x[0] for x in m])
        cand = np.array([x[1] for x in m])
        noise = np.array([x[3] for x in m])
        then = moves_before.get(push, [])
        same = np.mean(np.sign(truth[:, 1]) == np.sign(cand[:, 1]))
        beyond = np.mean(np.any(np.abs(truth) > 2 * noise, axis=1))
        out.append(
            f"| {push:g} | {len(m)} | {np.median(np.abs(truth[:, 1])):.3f} | {np.median(np.abs(cand[:, 1])):.3f} | "
            f"{median_move(then, 1):.3f} | {same:.0%} | {np.median(np.abs(truth[:, 0])):.3f} | "
            f"{np.median(np.abs(cand[:, 0])):.3f} | {median_move(then, 0):.3f} | {beyond:.0%} |"
        )
    out += [
        "",
        "Honest odds of one run at a push: for every run above, the plan's probability that this one run favours "
        "the hidden effect's candidate over the rival by 19 to 1 (`Phi(d / 2 - ln 19 / d)` from the two predictive "
        "distributions as stored, variances only), binned, against the fraction of the truth's runs whose likelihood "
        "ratio did; runs at a push other than the data's (0.5 and 2 times), then at the data's push:",
        "",
        "| pushes | predicted | runs | mean predicted | fraction that did | before: runs | mean predicted | "
        "fraction that did |",
        "|---|---|---|---|---|---|---|---|",
    ]
    edges = (0.0, 0.05, 0.2, 0.4, 0.6, 0.8, 0.95, 1.0001)
    for label, keep in (("0.5, 2", lambda x: x != 1.0), ("1", lambda x: x == 1.0)):
        now = [(p, hit) for push, p, hit in odds if keep(push)]
        then = [(p, hit) for push, p, hit in odds_before if keep(push)]
        for lo, hi in zip(edges[:-1], edges[1:]):
            a = [(p, h) for p, h in now if lo <= p < hi]
            b = [(p, h) for p, h in then if lo <= p < hi]
            if not a and not b:
                continue

            def cells(x):
                if not x:
                    return "0 | - | -"
                return f"{len(x)} | {np.mean([p for p, _ in x]):.2f} | {np.mean([h for _, h in x]):.2f}"

            out.append(f"| {label} | {lo:.2f}-{min(hi, 1.0):.2f} | {cells(a)} | {cells(b)} |")
    for label, keep in (("a push other than the data's", lambda x: x != 1.0), ("the data's push", lambda x: x == 1.0)):
        now = [(p, hit) for push, p, hit in odds if keep(push)]
        then = [(p, hit) for push, p, hit in odds_before if keep(push)]
        if now:
            out.append("")
            out.append(
                f"* At {label}: predicted probabilities add up to {sum(p for p, _ in now):.1f} over {len(now)} runs, "
                f"{sum(h for _, h in now)} runs did (before: {sum(p for p, _ in then):.1f} over {len(then)}, "
                f"{sum(h for _, h in then)} did)."
            )
    out += _control_lines()
    every = [x for m in moves.values() for x in m]
    every_before = [x for m in moves_before.values() for x in m]
    if every:
        truth = np.array([x[0] for x in every])
        cand = np.array([x[1] for x in every])
        ratio = np.median(np.abs(truth[:, 1])) / max(np.median(np.abs(cand[:, 1])), 1e-12)
        ratio_before = (
            np.median(np.abs(np.array([x[0] for x in every_before])[:, 1]))
            / max(np.median(np.abs(np.array([x[1] for x in every_before])[:, 1])), 1e-12)
            if every_before
            else math.nan
        )
        out += [
            "",
            f"* The truth's weave frequency moves with the push about {ratio:.0f} times as far as the friction candidate "
            f"predicts (median over {len(every)} pairs of runs; {ratio_before:.0f} times before), in the direction it "
            f"predicts in {np.mean(np.sign(truth[:, 1]) == np.sign(cand[:, 1])):.0%}.",
            "* The candidate's predictive standard deviation of one run's frequency (its own uncertainty and its "
            "spread over the kick's steer rate; now also over its friction law's corner and the record fit's valleys; "
            "median), now / before: "
            + "; ".join(
                f"{push:g} times {_median_sd(RECORDS_PUSH, push, checked):.3f} / "
                f"{_median_sd(RECORDS_PUSH_BEFORE_FRICTION, push, checked_before):.3f} rad/s"
                for push in pushes
            )
            + ".",
        ]
    out.append(
        "* Why the spread stayed small before (the check before): the candidate's friction is smoothed as `tanh(deltad / 0.05)` "
        "(`bikerider.gap.inference.timedomain.SMOOTHING`, 0.05 rad/s), the truth's as `tanh(deltad / 0.02)`, so "
        "near a standstill of the steer the candidate's friction acts as a viscous damper of `T_coulomb / 0.05` "
        "and the truth's sticks two and a half times as hard. Checked on seed 9311 (the candidate's fitted "
        "friction, the plan's 20 decays, templates from steer rates 0 and -+1.94 times the roll rate), the "
        "candidate's predictions with its own smoothing and with the truth's: its spread over the kick, median "
        "0.10 and 0.19 rad/s of the weave frequency (largest 0.13 and 0.61), its move from the data's push to "
        "twice it, median 0.96 and 1.63 rad/s, where the truth's runs move 1.41 (its values fitted with its own "
        "smoothing in both). On this one case the candidate's smoothing, more than the kick, keeps it from "
        "foreseeing how far a push or a kick moves the decay: a form of the friction law the data do not decide. "
        "Since this study the plan carries it (docs/gap.md, *The friction law's corner*): a friction rival's decay "
        "at another push is the mean over three corners, `eps` log-uniform from 0.02 to 0.125 rad/s, their spread "
        "part of its own uncertainty; the diagnosis's fits keep 0.05 (the steer-by-wire logs do not decide it). "
        "On 38 of these ties rerun both ways (`gap_next_loop_records_push_main_first90.jsonl`, "
        "`..._corner_first90.jsonl`) the candidate's z RMS of the frequency at half the push fell from 4.20 to "
        "2.74, and the runs predicted at 0.95 or more that reached 19:1 rose from 0.67 to 0.82; the loop on them "
        "(`gap_next_loop_records_main_38ties.jsonl`, `..._corner_38ties.jsonl`): plan 26 resolved / 10 wrong "
        "then, 28 / 8 now, the even spread 30 / 2 both. The records mode's tables and the push checks above carry it."
    )
    out += _seed_lines(9311)
    out.append("")
    return out


def _before_lines(stored: list[dict], names: list[str], n_max: int, path: Path, what: str, why: str) -> list[str]:
    """The same seeds as an earlier run of the records mode (``path``) ran them: ``what`` came after it, ``why``
    says what else differs."""
    seeds = {(c["scenario"], c["seed"]) for c in stored}
    before = [c for c in _stored(path) if (c["scenario"], c["seed"]) in seeds]
    ties_before = [c for c in before if c.get("strategies")]
    ties_now = [c for c in stored if c.get("strategies")]
    if not ties_before:
        return []
    now, then = _merit(ties_now, names), _merit(ties_before, names)
    both = {(c["scenario"], c["seed"]) for c in ties_now} & {(c["scenario"], c["seed"]) for c in ties_before}
    out = [
        f"Before {what} (`{path.name}`, the same {len(before)} cases: {len(ties_before)} ties then, "
        f"{len(ties_now)} now, {len(both)} both), now / before. {why}",
        "",
        "| strategy | ties | resolved | wrong | undecided | unbreakable | runs needed: median | 90th percentile | "
        "runs lost / spent |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for n in names:
        a, b = now[n], then[n]
        cells = _merit_pair_cells(a, b, ("n", "resolved", "wrong", "undecided", "unbreakable"), n_max)
        cells.append(f"{a['lost']} / {a['spent']} ({b['lost']} / {b['spent']})")
        out.append(f"| {n} | " + " | ".join(cells) + " |")
    out.append("")
    return out


def _merit_pair_cells(a: dict, b: dict, keys: tuple[str, ...], n_max: int) -> list[str]:
    """Table cells ``a / b`` of two figures of merit (:func:`_merit`): the counts ``keys``, then the runs
    needed, median and 90th percentile."""
    cells = [f"{a[k]} / {b[k]}" for k in keys]
    cells += [f"{_fmt(a['median_p90'][j], n_max)} / {_fmt(b['median_p90'][j], n_max)}" for j in (0, 1)]
    return cells


def _seed_lines(seed: int) -> list[str]:
    """The records case ``seed`` (the one decided wrong before the plan spanned the kick's steer rate), before
    and now."""
    plan = "plan:jensen_renyi"

    def outcome(path):
        c = next((c for c in _stored(path) if c["seed"] == seed and c.get("strategies")), None)
        if c is None:
            return None
        s = c["strategies"][plan]
        first = c["first"]["text"] if c.get("first") else "none"
        held = Counter(c.get("pushes", []))
        pushes = ", ".join(f"{held[p]} at {p:g} times" for p in sorted(held))
        return (
            f"{s['status']} in {s['runs']} run{'s' if s['runs'] != 1 else ''} (first run: {first}; the plan held "
            f"{sum(held.values())} decays, {pushes})"
        )

    before, now = outcome(RECORDS_BEFORE), outcome(RECORDS)
    if before is None:
        return []
    return [
        f"* Seed {seed} (steer_friction vs tyre_slip, riderless; the truth's `T_coulomb` 0.157 N m, `c_steer` 0.90 "
        f"N m s/rad), before the plan spanned the kick's steer rate: {plan} {before}. The friction candidate "
        "(fitted `T_coulomb` 0.204 +- 0.129, `c_viscous` 0.77 +- 1.29) predicted a weave frequency of 1.84 +- 0.33 "
        "rad/s there, tyre slip 5.01 +- 0.52, the truth's run gave 3.99 +- 0.12; the truth's own runs there "
        "(`fit_record`, 0.01 rad/s noise) give 1.8-3.1 rad/s from a roll-rate kick of 0.3 rad/s and 3.1-3.7 rad/s "
        "from 0.6 rad/s, by the kick's steer rate (-1.6 to 1.6 rad/s) alone: with Coulomb friction the decay depends "
        "on how the steer moves at the start, which the template, started from the data's roll rate alone (these "
        "records log no steer), did not carry. Now: "
        + (now if now is not None else "not among the ties stored")
        + " (a decay is left out where the friction candidate's response from one of the kick's steer rates shows "
        "no weave the record fit finds).",
    ]


def _records_lines(n_max: int) -> list[str]:
    """The records mode's subsection, from :data:`RECORDS` (and its figure, :data:`RECORDS_FIGURE`)."""
    import matplotlib.pyplot as plt

    from bikerider.gap.plan.ranking import PUSHES
    from validation import loop as L

    stored = _stored(RECORDS)
    ties = [c for c in stored if c.get("strategies")]
    if not ties:
        return []
    names = [n for n in L.RECORD_STRATEGIES if all(n in c["strategies"] for c in ties)]
    merit = _merit(ties, names)
    plan = "plan:jensen_renyi"
    chosen = [(c, e) for c in ties for e in c["strategies"][plan]["chosen"]]
    pushes = Counter(_push_of(c, e) for c, e in chosen)
    other = sum(n for push, n in pushes.items() if push is not None and push != 1.0)
    decays = sum(n for push, n in pushes.items() if push is not None)
    with_other = sum(any((_push_of(c, e) or 1.0) != 1.0 for e in c["strategies"][plan]["chosen"]) for c in ties)
    first_other = sum(c["first"] is not None and c["first"]["push"] not in (None, 1.0) for c in ties)
    compared = [c for c in ties if c.get("first") and c.get("table_first")]
    same = [c for c in compared if _same_first(c["first"], c["table_first"])]
    kind = sum(c["first"]["kind"] != c["table_first"]["kind"] for c in compared)
    law = sum(
        c["first"]["kind"] == c["table_first"]["kind"] and c["first"]["law"] != c["table_first"]["law"]
        for c in compared
    )
    by_push = sum(
        c["first"]["kind"] == "decay" == c["table_first"]["kind"]
        and (c["first"]["law"], round(c["first"]["speed"], 2))
        == (c["table_first"]["law"], round(c["table_first"]["speed"], 2))
        and c["first"]["push"] != 1.0
        for c in compared
    )
    matches = [c.get("first_is_next_run") for c in ties if c.get("first_is_next_run") is not None]
    m_plan, m_even = merit[plan]["median_p90"][0], merit["even"]["median_p90"][0]
    goal1 = math.isfinite(m_plan) and (not math.isfinite(m_even) or m_plan <= m_even / 2)
    broken = [
        c
        for c in ties
        if c["strategies"][plan]["status"] == "unbreakable" and c["strategies"]["even"]["status"] == "resolved"
    ]
    both = [
        (c["strategies"][plan]["runs"], c["strategies"]["even"]["runs"])
        for c in ties
        if c["strategies"][plan]["status"] == "resolved" == c["strategies"]["even"]["status"]
    ]
    by_scenario: dict[str, list] = {}
    for c in stored:
        by_scenario.setdefault(c["scenario"], []).append(c)
    errors = [c for c in stored if str(c.get("status", "")).startswith("error")]

    # figure: runs to a decision, and the pushes the plan chose
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    k = np.arange(0, n_max + 1)
    for n in names:
        got = [c["strategies"][n] for c in ties]
        for status, style in (("resolved", "-"), ("wrong", ":")):
            frac = [np.mean([s["status"] == status and s["runs"] <= j for s in got]) for j in k]
            axes[0].step(k, frac, where="post", ls=style, color="C0" if n == plan else "C1", label=f"{n}, {status}")
    axes[0].set_xlabel("runs after the tie")
    axes[0].set_ylabel("fraction of ties decided")
    axes[0].set_title(f"Records mode, friction pairs: {len(ties)} ties")
    axes[0].set_ylim(0, 1)
    axes[0].grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    labels = ["decay x0.5", "decay x1", "decay x2", "multisine"]
    counts = [pushes.get(0.5, 0), pushes.get(1.0, 0), pushes.get(2.0, 0), pushes.get(None, 0)]
    axes[1].bar(labels, counts, color=["C2", "C0", "C3", "0.6"])
    for x, n in enumerate(counts):
        axes[1].annotate(str(n), (x, n), ha="center", va="bottom", fontsize=9)
    axes[1].set_ylabel("runs")
    axes[1].set_title(f"The runs {plan} chose ({len(chosen)} in all)")
    fig.tight_layout()
    fig.savefig(RECORDS_FIGURE, dpi=110)
    plt.close(fig)

    def cell(n):
        m = merit[n]
        med, p90 = m["median_p90"]
        dmed, dp90 = m["decided"]
        return (
            f"| {n} | {m['n']} | {m['resolved']} | {m['wrong']} | {m['undecided']} | {m['unbreakable']} | "
            f"{_fmt(med, n_max)} | {_fmt(p90, n_max)} | {within(n, 2)} | {within(n, 5)} | {_fmt(dmed, n_max)} | "
            f"{_fmt(dp90, n_max)} | {m['lost']} / {m['spent']} |"
        )

    def within(n, k):
        return sum(c["strategies"][n]["status"] == "resolved" and c["strategies"][n]["runs"] <= k for c in ties)

    out = [
        "### Records: pushes among the experiments",
        "",
        "The loop's records mode (`validation.loop.run_loop_case(..., records=True)`, `gap_next_loop.py records`):",
        "the tie's data are **records**, the truth's noisy roll rate of each kicked run as part 4's trials make them",
        "(`validation.cases.measure` with records; Coulomb friction simulated in time by the truth's own simulator,",
        "nine runs near one speed in three sessions, `RECORD_NARROW`: the steer friction fitted in time has",
        "standard errors from the jackknife over three or more sessions, which sees the scatter between sessions;",
        "the fallback for fewer than three, the fit's own covariance, does not see that scatter; the first run of",
        "this study was made when two sessions gave none). It was run again on the code of 2026-11-29, after issue 21",
        "changed the friction candidate's fits (each record's initial state under friction by Gauss-Newton steps",
        "from several starts, the slopes with the states held at their fits, intervals over the friction corner's",
        "range: part 4, items 16-18); the run before, whose friction fits split Coulomb friction into too little",
        "Coulomb and some viscous part where the friction holds the steer, is compared below. Its ties were run",
        "once more after the plan predicted a friction rival's decays from its template's kick and over the record",
        "fit's valleys (docs/gap.md, *A friction rival's decays*; `records --ties-of`): the diagnosis is the same, so",
        "the cases that do not tie are kept from that run. The friction truths' candidate",
        "is `steer_friction` (viscous and Coulomb, fitted in time), nonlinear, so the plan (`NextExperiment`,",
        "roll-rate decays) plans each decay at "
        + ", ".join(f"{x:g}" for x in PUSHES)
        + " times the data's push, besides the multisines.",
        "The rivals' predictions are the plan's own (indirect inference over each experiment's template at its",
        "push; the friction rival's response simulated in time), linear in their fitted values through the plan's",
        "secants (`validation.loop.from_plan`; they give back the plan's covariances to "
        f"{max(c.get('own_cov_error') or 0.0 for c in ties):.0e}, relative). A push run is the truth's",
        "kick (as the data's, drawn the same way; the runs at the pushes of one speed and law share their draws)",
        "times the push, 6 s, read by the diagnosis's own record fit (`fit_record`); its weight is the plan's noise",
        "of one run (the data's scatter from run to run beyond their fits' standard errors, as the diagnosis weighs",
        "a record by its replicates' scatter) with the run's own standard errors in place of the template's, plus",
        "the nominal parameters' uncertainty. These records log no steer, and a kick's steer rate is drawn anew",
        "for each run: the plan takes it as unknown, uniform within 2.5 times the roll rate either way",
        "(`bikerider.gap.plan.decays.KICK_STEER_RATE`), predicts each decay as the mean over three templates",
        "across that range and adds each rival's spread over them to one run's noise (the loop likewise). The",
        "even spread takes decays at the data's push (a researcher without a plan pushes as before); multisines",
        f"are as in the table study. Pairs: {'; '.join(s.label for s in L.RECORD_SCENARIOS)}; seeds from "
        f"{FIRST_RECORD_SEED}, the pairs in turn.",
        "",
        f"* **{len(ties)} ties** out of {len(stored)} cases tried"
        + (f" ({len(errors)} failed with an error)" if errors else "")
        + ".",
        "",
        "| strategy | ties | resolved | wrong | undecided | unbreakable | runs needed: median | 90th percentile | "
        "resolved within 2 runs | within 5 | runs to any decision: median | 90th percentile | runs lost / spent |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        *[cell(n) for n in names],
        "",
        f"* Goal 1 (the plan's median at most half the even spread's): {_fmt(merit[plan]['median_p90'][0], n_max)} "
        f"against {_fmt(merit['even']['median_p90'][0], n_max)}, "
        + ("**met**" if goal1 else "**not met**")
        + f"; the plan spends {merit[plan]['spent']} runs in all, the even spread {merit['even']['spent']}. Goal 2: "
        f"{len(broken)} ties declared unbreakable that the even spread breaks"
        + (": " + ", ".join(f"{c['scenario']} seed {c['seed']}" for c in broken) if broken else "")
        + ".",
        f"* The runs {plan} chose: {decays} decays, {other} of them at a push other than the data's "
        f"({pushes.get(0.5, 0)} at 0.5 times, {pushes.get(2.0, 0)} at 2 times; in {with_other} of {len(ties)} ties), "
        f"and {pushes.get(None, 0)} multisines. Its first run was a push other than the data's in {first_other} ties.",
        f"* The first run ({plan}, the next run `--next` names; the loop's first choice was that run in "
        f"{sum(matches)} of {len(matches)} ties) against the table loop's on the same runs (their fitted weave "
        "eigenvalues as a table, the table study's candidate `steer_damping` for the friction and the same rival, "
        f"planned as the table study plans): the same experiment in {len(same)} of {len(compared)} ties, "
        f"different in {len(compared) - len(same)} ({kind} a different kind, decay or multisine; {law} a different "
        f"law; {by_push} the same speed and law at another push).",
        f"* By the plan's first run: {_by_first(ties, plan)}.",
        f"* On the {len(both)} ties both resolved: {plan} {sum(a for a, _ in both)} runs in all (mean "
        f"{np.mean([a for a, _ in both]) if both else math.nan:.2f}), the even spread {sum(b for _, b in both)} (mean "
        f"{np.mean([b for _, b in both]) if both else math.nan:.2f}); fewer runs for the plan in "
        f"{sum(a < b for a, b in both)}, more in {sum(a > b for a, b in both)}.",
        "",
        *_before_lines(
            stored,
            names,
            n_max,
            RECORDS_BEFORE_VALLEYS,
            "the plan predicted a friction rival's decays from its template's kick and over the record fit's valleys",
            "The diagnosis is the same, so are the ties: what differs is the plan alone (its choices, its stated "
            "odds and the rivals' predictions the loop weighs the truth's runs by).",
        ),
        *_before_lines(
            stored,
            names,
            n_max,
            RECORDS_BEFORE_FRICTION,
            "issue 21 changed the friction candidate's fits",
            "A tie is the diagnosis's: with the friction fits it changes too (the friction candidate ranks and "
            "sizes otherwise), so the ties differ beyond where a plan failed.",
        ),
        *_before_lines(
            stored,
            names,
            n_max,
            RECORDS_BEFORE,
            "the plan spanned the kick's steer rate",
            "That run came from an earlier commit than 0ec9c83, and main has changed since in other ways too (the "
            "friction fit's covariance, the linear fits' search for other minima, and the friction fits above), so "
            "not every difference is the kick's: on seed 9311 the code of that time without the kick's span planned 36 "
            "decays where the stored run planned 13.",
        ),
        "| pair | cases | ties | plan resolved | plan wrong | even resolved | even wrong | first run differs from the table loop's |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for label, cs in by_scenario.items():
        t = [c for c in cs if c.get("strategies")]

        def count(name, status, t=t):
            return sum(c["strategies"][name]["status"] == status for c in t)

        differ = sum(
            not _same_first(c["first"], c["table_first"]) for c in t if c.get("first") and c.get("table_first")
        )
        out.append(
            f"| {label} | {len(cs)} | {len(t)} | {count(plan, 'resolved')} | {count(plan, 'wrong')} | "
            f"{count('even', 'resolved')} | {count('even', 'wrong')} | {differ} |"
        )
    seconds = sum(c.get("seconds", 0.0) for c in stored)
    out += [
        "",
        f"![records mode: runs to a decision and the pushes chosen](figures/{RECORDS_FIGURE.name})",
        "",
        *_push_lines(),
        f"* Cost: {len(stored)} cases in {seconds:.0f} s of one worker ({seconds / max(len(ties), 1):.1f} s a tie, "
        "non-ties included).",
        "",
    ]
    return out


def report(args) -> int:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from validation import loop as L

    stored = _stored()
    if not stored:
        print(f"no stored cases in {RESULTS}: run the study first")
        return 1
    n_max = L.N_MAX
    ties = [c for c in stored if c.get("strategies")]
    names = [n for n in L.STRATEGIES if any(n in c["strategies"] for c in ties)]
    merit = _merit(ties, names)
    plans = [n for n in names if n.startswith("plan:")]

    def key(n):
        med, p90 = merit[n]["median_p90"]
        return (-merit[n]["resolved"], med, p90, merit[n]["wrong"])

    best = min(plans, key=key) if plans else None
    # goal 2: no tie the plan declares unbreakable that the even spread breaks
    broken_by_even = [
        c
        for c in ties
        if best and c["strategies"][best]["status"] == "unbreakable" and c["strategies"]["even"]["status"] == "resolved"
    ]
    # cost
    seconds = [c["seconds"] for c in stored if "seconds" in c]
    tie_seconds = [c["seconds"] for c in ties]
    decay_runs = sum(c["truth_runs"]["count"]["decay"] for c in ties)
    sweep_runs = sum(c["truth_runs"]["count"]["sweep"] for c in ties)
    decay_s = sum(c["truth_runs"]["seconds"]["decay"] for c in ties)
    sweep_s = sum(c["truth_runs"]["seconds"]["sweep"] for c in ties)
    tie_rate = len(ties) / max(len(stored), 1)
    per_tie = sum(seconds) / max(len(ties), 1)
    untied = [c for c in stored if c.get("status") == "no tie"]
    by_scenario: dict[str, list] = {}
    for c in stored:
        by_scenario.setdefault(c["scenario"], []).append(c)

    # -- figure: runs-to-decision curves and the reliability diagrams
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    ax = axes[0]
    k = np.arange(0, n_max + 1)
    for n in names:
        got = [c["strategies"][n] for c in ties if n in c["strategies"]]
        frac = [np.mean([s["status"] == "resolved" and s["runs"] <= j for s in got]) for j in k]
        style = "-" if n.startswith("plan:") else ("--" if n in ("even", "random") else ":")
        ax.step(k, frac, where="post", ls=style, lw=2.2 if n == best else 1.3, label=n)
    ax.set_xlabel("runs after the tie")
    ax.set_ylabel("fraction of ties resolved (true effect at 0.95)")
    ax.set_title(f"Runs to a decision, {len(ties)} ties")
    ax.set_ylim(0, 1)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    rel = {}
    for ax, kind, title in ((axes[1], "decay", "decays"), (axes[2], "sweep", "multisines")):
        pairs = _reliability(ties, kind, n_max)
        rows = _bins(pairs)
        rel[kind] = (pairs, rows)
        ax.plot([0, 1], [0, 1], color="0.6", lw=1)
        if rows:
            x = [r[4] for r in rows]
            y = [r[5] for r in rows]
            ax.plot(x, y, "o-", color="C3")
            for r, xi, yi in zip(rows, x, y):
                ax.annotate(f"{r[2]} ({r[3]})", (xi, yi), textcoords="offset points", xytext=(4, -10), fontsize=7)
        if kind == "sweep" and SWEEP_RULE.exists():  # the re-run with the lean rule (its own file)
            again = [c for c in _stored(SWEEP_RULE) if "repeat:sweep" in (c.get("strategies") or {})]
            extra = _bins(_reliability(again, "sweep", n_max))
            if extra:
                ax.plot([r[4] for r in extra], [r[5] for r in extra], "s-", color="C0", label="re-run, lean rule")
                ax.plot([], [], "o-", color="C3", label="stored study")
                ax.legend(fontsize=7, loc="upper left")
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1)
        ax.set_xlabel("plan's resolution probability (bin mean)")
        ax.set_ylabel("fraction resolved by the loop")
        ax.set_title(f"Reliability, the plan's best {title} repeated")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    FIGURE.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(FIGURE, dpi=110)
    plt.close(fig)

    # -- part 5
    lines = [
        BEGIN,
        "",
        "## 5. The closed loop: runs to a decision, following the plan against an even spread",
        "",
        "Produced by `docs/scripts/gap_next_loop.py` (`run` stores the cases in `gap_next_loop.jsonl` beside it,",
        "`records` the records mode's in `gap_next_loop_records.jsonl`, `report` writes this part from them); the",
        "cases are `validation.loop`.",
        "",
        "### Set-up",
        "",
        "* **Cases**: a hidden effect with its sizes drawn over the candidate's prior (`validation.cases.draw_truth`),",
        "  on the Davis bicycle with rider Jason or riderless, measured by six decays near one speed in two sessions (three",
        "  under the stabilising control) and simulated by the independent truth of part 1 (Meijaard's Appendix A",
        "  typed in by hand, the nonlinear effects, Coulomb steer friction in time, LSODA, noise, the weave fitted",
        "  from the noisy roll rate). The diagnosis is given the hidden effect's candidate and a rival that often",
        "  stands in for it; a case counts when it **ties** them. Pairs: "
        + "; ".join(f"{s.label}" for s in L.SCENARIOS)
        + ". `steer_friction` (viscous and Coulomb) and `steer_coulomb` (Coulomb alone) are truths the candidate",
        "  `steer_damping` stands for.",
        "* **Plan**: `bikerider gap --next` (`NextExperiment`, 10 runs, decays and multisines) plans once on the tie;",
        "  its experiments (decays at 12 speeds under the data's control law, the law's gains halved or times 1.5,",
        "  or no control; steer-torque multisines of 0.5 N m, 10 s, roll rate or steer angle, at the same speeds",
        "  and laws), each rival's predictions and one run's noise and nominal-parameter uncertainty are the loop's.",
        "  Pushes are not an experiment in this study: its diagnosis reads eigenvalue tables, whose decays carry no",
        "  push size. With records and a nonlinear rival the plan also plans pushes; the loop's records mode runs",
        "  them (*Records: pushes among the experiments*, below).",
        "* **Loop** (cheap by design): each rival is linearised at its fit to the tie's data (its predictions of every",
        "  experiment and their secant slopes in its fitted values, through the same public model code the diagnosis",
        "  uses; they reproduce the plan's own predictions to "
        + f"{max((c.get('linearisation_error') or 0) for c in ties):.1e}"
        + "). Every new run updates each rival's",
        "  values as a refit of the linearised model would (a Kalman step from the fit's covariance) and adds the",
        "  run's predictive log density to the rival's log evidence; model probabilities start even at the tie. A",
        "  run every rival misses beyond its noise is down-weighted by the better rival's chi-square per number",
        "  (lack of fit). Runs: a **decay** is the truth's kicked 6-s run fitted as in part 1; a **multisine** is the",
        f"  truth driven by the Schroeder multisine plus its control law, the motor's total torque saturating at {L.MOTOR_LIMIT:g} N m,",
        "  the truth's own friction, a settling time of three time constants of its slowest mode (5-20 s), one",
        "  period recorded at 100 Hz with sensor noise and read as the frequency response at the lines (the run is",
        "  simulated, not drawn from the plan's noise model; the loop weighs it with that model). The diagnosis",
        "  reads no multisine records yet (a record kind for them was being added at the same time), so the loop",
        "  reads multisines at the frequency-response level. A run where the bicycle falls or no weave is fitted",
        "  is spent and teaches nothing.",
        "  The same experiment's k-th run is the same simulated run for every strategy.",
        f"* **Strategies** (at most {n_max} runs each): `plan:<criterion>` takes the next run where the criterion",
        "  (`bikerider.gap.plan.criteria`: Hunter-Reiner 1965, Box-Hill 1967, Buzzi-Ferraris-Forzatti 1984,",
        "  Jensen-Renyi) is largest, from the rivals and probabilities as updated, and declares the tie",
        f"  **unbreakable** when no experiment repeated for the runs left resolves it with probability {L.HOPELESS:g} or more",
        "  (the rule of the stored study below; the rule now in `validation.loop`, runs combined over experiments, is",
        "  judged in *Re-run under the combined-runs rule*);",
        "  `even` runs decays under the laws in turn at speeds spread evenly over the feasible range; `random`",
        "  runs any feasible experiment; `repeat:decay` and `repeat:sweep` repeat the plan's best decay or",
        "  multisine (what `--next` ranks first). `plan:jensen_renyi`'s first run at a tie is the next run `--next`",
        "  now names (`bikerider.gap.plan.sequential`, checked equal by `tests/gap/plan/test_gap_next_run.py`).",
        f"* **Figure of merit**: runs until the hidden effect's probability reaches {L.DECIDED}; `> {n_max}` when not",
        f"  within {n_max} runs (a wrong decision, undecided, or declared unbreakable).",
        "",
        "### Results",
        "",
        f"* **{len(ties)} ties** out of {len(stored)} cases tried"
        + (f" (goal: 100; **only {len(ties)} finished** in the time)" if len(ties) < 100 else "")
        + ".",
        "",
        "| strategy | ties | resolved | wrong | undecided | unbreakable | runs needed: median | 90th percentile "
        "| runs to any decision: median | 90th percentile | right of decided | runs spent | lost |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for n in names:
        m = merit[n]
        med, p90 = m["median_p90"]
        lines.append(
            f"| {'**' + n + '**' if n == best else n} | {m['n']} | {m['resolved']} | {m['wrong']} | {m['undecided']} | "
            f"{m['unbreakable']} | {_fmt(med, n_max)} | {_fmt(p90, n_max)} | {_fmt(m['decided'][0], n_max)} | "
            f"{_fmt(m['decided'][1], n_max)} | {m['resolved'] / max(m['resolved'] + m['wrong'], 1):.0%} | "
            f"{m['spent']} | {m['lost']} |"
        )
    if best:
        bm, em = merit[best]["median_p90"], merit["even"]["median_p90"]
        half = math.isfinite(bm[0]) and (not math.isfinite(em[0]) or bm[0] <= em[0] / 2)
        lines += [
            "",
            f"* Best criterion by the figure of merit: **{best}** (most ties resolved, then the median).",
            f"* Goal 1, the plan needs at most half the runs of an even spread: median {_fmt(bm[0], n_max)} against "
            f"{_fmt(em[0], n_max)}, 90th percentile {_fmt(bm[1], n_max)} against {_fmt(em[1], n_max)}: "
            + ("**met**." if half else "**not met**."),
            "* On the ties both resolved, paired: "
            + "; ".join(
                f"{n} {len(both)} ties, median {np.median([x for x, _ in both]):g} runs against the even spread's "
                f"{np.median([y for _, y in both]):g} (90th percentile {np.quantile([x for x, _ in both], 0.9):.0f} "
                f"against {np.quantile([y for _, y in both], 0.9):.0f})"
                for n in plans + ["random"]
                for both in [
                    [
                        (c["strategies"][n]["runs"], c["strategies"]["even"]["runs"])
                        for c in ties
                        if c["strategies"][n]["status"] == "resolved"
                        and c["strategies"]["even"]["status"] == "resolved"
                    ]
                ]
                if both
            )
            + ".",
            f"* Goal 2, no tie declared unbreakable that the even spread breaks: {len(broken_by_even)} such ties"
            + (": " + ", ".join(f"{c['scenario']} seed {c['seed']}" for c in broken_by_even) if broken_by_even else "")
            + (" (**met**)." if not broken_by_even else " (**not met**)."),
        ]
    if best:
        picked = [e for c in ties for e in c["strategies"][best]["chosen"]]
        sweeps = sum(e >= c["experiments"]["decays"] for c in ties for e in c["strategies"][best]["chosen"])
        lines.append(
            f"* The runs {best} chose: {len(picked) - sweeps} decays and {sweeps} multisines "
            f"({sweeps / max(len(picked), 1):.0%})."
        )
    nobody = [c for c in ties if not any(s["status"] == "resolved" for s in c["strategies"].values())]
    all_wrong = [c for c in ties if all(s["status"] == "wrong" for s in c["strategies"].values())]
    lines.append(
        f"* {len(nobody)} ties no strategy resolved within {n_max} runs; in {len(all_wrong)} of them every strategy "
        "decided for the rival (by the loop's posterior; the diagnosis's own judgement of such ties is below): "
        + (
            "; ".join(
                f"{c['scenario']} seed {c['seed']} ({', '.join(f'{k} {v:.3g}' for k, v in c['sizes'].items())})"
                for c in all_wrong
            )
            or "none"
        )
        + "."
    )
    lines += ["", "Ties per pair, the best criterion against the even spread:", ""]
    lines += [
        "| pair | cases | ties | plan resolved | plan wrong | even resolved | even wrong |",
        "|---|---|---|---|---|---|---|",
    ]
    for label, cs in by_scenario.items():
        t = [c for c in cs if c.get("strategies")]

        def count(name, status, t=t):
            return sum(c["strategies"][name]["status"] == status for c in t) if name else 0

        lines.append(
            f"| {label} | {len(cs)} | {len(t)} | {count(best, 'resolved')} | {count(best, 'wrong')} | "
            f"{count('even', 'resolved')} | {count('even', 'wrong')} |"
        )
    lines += ["", "### Honest odds: the plan's resolution probability against the loop", ""]
    for kind, title in (("decay", "decays"), ("sweep", "multisines")):
        pairs, rows = rel[kind]
        lines.append(
            f"The plan's best {title} repeated `k` times (k = 1-{n_max}), {len({s for _, _, s in pairs})} ties: "
            "the plan's probability that `k` runs favour the true rival by 19 to 1, binned, against the fraction "
            "the loop resolved by `k` runs (points of one tie at different `k` are not independent)."
        )
        lines += ["", "| predicted | points (ties) | mean predicted | fraction resolved |", "|---|---|---|---|"]
        lines += [f"| {lo:.2f}-{hi:.2f} | {n} ({nc}) | {mp:.2f} | {fr:.2f} |" for lo, hi, n, nc, mp, fr in rows]
        at10 = [(p, r) for p, r, _ in pairs[9::n_max]]
        if at10:
            lines += [
                "",
                f"At the plan's default of 10 runs ({len(at10)} ties, one point each): predicted probabilities add up to "
                f"{sum(p for p, _ in at10):.1f}, {sum(r for _, r in at10)} were resolved.",
            ]
        lines.append("")
    lines += [f"![runs to a decision and reliability](figures/{FIGURE.name})", ""]
    lines += _rerun_lines(ties, best, n_max)
    lines += _lean_lines(ties, n_max)
    lines += _now_lines(n_max)
    lines += _settled_lines(n_max)
    lines += _today_lines(n_max)
    lines += _shared_today_lines(n_max)
    lines += _shared_odds_lines(n_max)
    lines += _odds_fixed_lines(n_max)
    lines += _recalibration_lines(n_max)
    lines += _records_lines(n_max)
    shared = [c for c in _stored(SHARED) if c.get("strategies")]
    if shared:
        keys = {(c["scenario"], c["seed"]) for c in shared}
        same = [c for c in ties if (c["scenario"], c["seed"]) in keys]
        variant, main = _merit(shared, names), _merit(same, names)
        lines += [
            "### Variant: the nominal parameters' uncertainty shared by all runs",
            "",
            "The loop above counts the nominal parameters' uncertainty per run, as the plan and the diagnosis do, so",
            "repeated runs average it away although the truth's parameter error is the same in every run. Here",
            "(`run --shared`) each rival is linearised in the nominal parameters' shifts too (standard normal prior,",
            f"one set for all runs); the same {len(shared)} ties, the same runs (the unbreakable rule as before):",
            "",
            "| strategy | resolved (per run / shared) | wrong | undecided | unbreakable | runs needed: median | "
            "90th percentile | right of decided |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for n in names:
            a, v = main[n], variant[n]
            cells = _merit_pair_cells(a, v, ("resolved", "wrong", "undecided", "unbreakable"), n_max)
            cells.append(
                f"{a['resolved'] / max(a['resolved'] + a['wrong'], 1):.0%} / "
                f"{v['resolved'] / max(v['resolved'] + v['wrong'], 1):.0%}"
            )
            lines.append(f"| {n} | " + " | ".join(cells) + " |")
        if best:
            lines += [
                "",
                f"Shared, the wrong decisions fall ({best}: {main[best]['wrong']} -> {variant[best]['wrong']}; even "
                f"spread: {main['even']['wrong']} -> {variant['even']['wrong']}), the resolved ties barely move "
                f"({main[best]['resolved']} -> {variant[best]['resolved']}; {main['even']['resolved']} -> "
                f"{variant['even']['resolved']}) and the plan declares more ties unbreakable "
                f"({main[best]['unbreakable']} -> {variant[best]['unbreakable']}).",
            ]
        lines.append("")
    checks = (
        [json.loads(x) for x in CHECKS.read_text(encoding="utf-8").splitlines() if x.strip()] if CHECKS.exists() else []
    )
    checks = [c for c in checks if "diagnosis_first" in c]
    if checks:

        def verdict(c):
            if c["diagnosis_tied"]:
                return "tied"
            return "hidden" if c["diagnosis_first"] == c["hidden"] else "rival"

        tally = {
            loop: {v: sum(verdict(c) == v for c in checks if c["loop"] == loop) for v in ("rival", "tied", "hidden")}
            for loop in ("wrong", "undecided")
        }
        lines += [
            "### The loop's decisions judged by the diagnosis itself",
            "",
            "Ties where the loop decided for the rival (or stayed undecided), run again with the same runs "
            "(`validation.loop.diagnosis_check`), and the diagnosis itself (`Diagnosis` with the two rivals, its "
            "priors and held-out tie rule) given the tie's data plus the strategy's decays (multisines left out: "
            "the diagnosis reads no frequency responses):",
            "",
            "| pair | seed | strategy | loop | runs | decays to the diagnosis | diagnosis: first (tied with) |",
            "|---|---|---|---|---|---|---|",
        ]
        for c in checks:
            tied = f" ({', '.join(c['diagnosis_tied'])})" if c["diagnosis_tied"] else ""
            lines.append(
                f"| {c['scenario']} | {c['seed']} | {c['strategy']} | {c['loop']} | {c['runs']} | {c['decays_used']} | "
                f"{c['diagnosis_first']}{tied} |"
            )
        lines += [
            "",
            "Where the loop decided for the rival, the diagnosis picks the rival in "
            f"{tally['wrong']['rival']}, keeps the tie in {tally['wrong']['tied']} and picks the hidden effect in "
            f"{tally['wrong']['hidden']}; where the loop stayed undecided, it keeps the tie in "
            f"{tally['undecided']['tied']}, picks the hidden effect in {tally['undecided']['hidden']} and the rival in "
            f"{tally['undecided']['rival']}.",
            "",
        ]
    if best:
        decided_plan, decided_even = merit[best]["decided"], merit["even"]["decided"]
        unbreakable = [c for c in ties if c["strategies"][best]["status"] == "unbreakable"]
        lines += [
            "### Reading the results",
            "",
            f"* Speed of a decision: {best} reaches one (right or wrong) in a median of {_fmt(decided_plan[0], n_max)} "
            f"runs, the even spread in {_fmt(decided_even[0], n_max)}"
            + ("." if decided_plan[0] != decided_even[0] else " (the same).")
            + f" Fastest to a decision of all strategies: {min(names, key=lambda n: merit[n]['decided'])}.",
            f"* Right decisions: {merit[best]['resolved']} of {merit[best]['resolved'] + merit[best]['wrong']} for "
            f"{best}, {merit['even']['resolved']} of {merit['even']['resolved'] + merit['even']['wrong']} for the even "
            "spread. A wrong decision is the loop's posterior reaching 0.95 for the rival: the truth is neither rival "
            "(parameter error within the stated uncertainty, a rider whose geometry differs from the diagnosis's "
            "default, Coulomb friction where a rival is viscous), the runs that part the rivals also show what neither "
            "describes, and the rival with more freedom (passive arms: a mass, a spring and a damper at the grips) "
            "absorbs more of it. Two linearised rivals' posterior odds are then overconfident, whichever runs are "
            "taken.",
            f"* For comparison, the diagnosis itself (its candidates' priors, its held-out tie rule) ranked the hidden "
            f"effect first, untied, in {sum(c.get('first') == c.get('candidate') for c in untied)} of {len(untied)} "
            "cases it did not tie on the six runs: the loop's decision rule (the rivals' evidence from their fits' "
            "covariance, with no prior odds from the candidates' priors) is weaker than the diagnosis's, and the "
            "wrong decisions above are as much its failure as the data's. Judging each step with the diagnosis "
            "itself (part 3's rule) would be the better loop, at about a diagnosis (2-10 s here) per run.",
            f"* {len(unbreakable)} ties declared unbreakable by {best}; the even spread resolved "
            f"{len(broken_by_even)} of them.",
            "* The plan's resolution probabilities assume one rival is the truth; the reliability diagrams show how far "
            "they hold when it is not.",
        ]
        if broken_by_even:
            lines.append(
                "* The unbreakable rule (the plan's own measure) judges one experiment repeated, with the rivals' own "
                "uncertainty as it stands; where runs at several speeds would first pin a rival's values and then part "
                "the rivals, it declares unbreakable a tie an even spread breaks ("
                + ", ".join(sorted({c["scenario"] for c in broken_by_even}))
                + "). The rule now combines runs over experiments: see *Re-run under the combined-runs rule* above."
            )
        if "repeat:sweep" in merit:
            m = merit["repeat:sweep"]
            lines.append(
                f"* The plan's best multisine repeated lost {m['lost']} of its {m['spent']} runs: the truth fell (past "
                "0.5 rad of roll) during the settling time or the recording, under a torque the plan judged safe (it "
                "accepts a capsize slower than one e-fold per run as held by the rider or a catch, and this truth has "
                "neither) or with a lightly damped weave driven at resonance; a lost run teaches nothing, which the "
                "plan's probability does not foresee. The plan now leaves such runs out (*Multisines that would lean "
                "too far, left out*, above)."
            )
        lines += _shared_reading_lines()
        lines += [
            "",
        ]
    lines += [
        "### Cost",
        "",
        f"* {len(stored)} cases in {sum(seconds):.0f} s of worker time ({sum(seconds) / max(len(stored), 1):.1f} s a case,"
        f" {np.mean(tie_seconds) if tie_seconds else math.nan:.1f} s a tie); a tie every {1 / max(tie_rate, 1e-9):.1f} cases.",
        f"* Truth runs: {decay_runs} decays in {decay_s:.0f} s ({decay_s / max(decay_runs, 1):.2f} s each), {sweep_runs}"
        f" multisines in {sweep_s:.0f} s ({sweep_s / max(sweep_runs, 1):.2f} s each); the rest is the diagnosis and the plan"
        " at the tie.",
        f"* 100 ties need about {100 * per_tie / 60:.0f} min of one core ({per_tie:.0f} s of worker time per tie,"
        " non-ties included).",
        "",
        END,
    ]
    text = DOC.read_text(encoding="utf-8")
    block = "\n".join(lines)
    if BEGIN in text and END in text:
        text = text.split(BEGIN, 1)[0] + block + text.split(END, 1)[1]
    else:
        text = text.rstrip("\n") + "\n\n" + block + "\n"
    DOC.write_text(text, encoding="utf-8")
    print(f"wrote {DOC} part 5 and {FIGURE}: {len(ties)} ties, best {best}")
    return 0


def main() -> int:
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run cases, appending to the JSON lines file")
    r.add_argument("--ties", type=int, default=100, help="stop after this many ties stored")
    r.add_argument("--attempts", type=int, default=400, help="cases to try at most (scenarios in turn)")
    r.add_argument("--workers", type=int, default=2)
    r.add_argument("--until", help="stop at this UTC time, HH:MM")
    r.add_argument(
        "--shared",
        action="store_true",
        help="the stored ties again, the nominal parameters' uncertainty shared by the runs",
    )
    c = sub.add_parser("check", help="judge the loop's wrong or undecided ties by the diagnosis itself")
    c.add_argument("--max", type=int, default=10, help="ties to check at most")
    rr = sub.add_parser(
        "rerun", help="the ties declared unbreakable that the even spread broke, again under the combined-runs rule"
    )
    rr.add_argument("--workers", type=int, default=1)
    rr.add_argument("--all", action="store_true", help="every stored tie (to a file of its own)")
    rr.add_argument(
        "--strategy",
        help="this strategy only (e.g. repeat:sweep), on every stored tie, to gap_next_loop_<strategy>.jsonl",
    )
    rr.add_argument(
        "--max-roll",
        type=float,
        help="with --strategy: the plan's largest lean of a multisine run [rad] (inf: the rule off), to its own file",
    )
    rr.add_argument(
        "--tag",
        help="with --strategy: appended to the file's name (the same strategy on later code, beside the stored run)",
    )
    rr.add_argument(
        "--stated",
        choices=("gaussian", "combined"),
        help="the probability the plan states (bikerider.gap.plan.discrimination.STATED; default: the code's)",
    )
    rr.add_argument(
        "--shared",
        action="store_true",
        help="with --strategy: the nominal parameters' uncertainty shared by the runs (to a file of its own)",
    )
    rc = sub.add_parser("records", help="the records mode on the friction pairs (pushes among the experiments)")
    rc.add_argument("--ties", type=int, default=40, help="stop after this many ties stored")
    rc.add_argument("--attempts", type=int, default=300, help="cases to try at most (the friction pairs in turn)")
    rc.add_argument("--workers", type=int, default=1)
    rc.add_argument("--until", help="stop at this UTC time, HH:MM")
    rc.add_argument("--ties-of", help="only the cases that tied in this stored run (JSON lines)")
    pc = sub.add_parser("push-check", help="the records ties again: the truth's runs at every push against the rivals'")
    pc.add_argument("--max", type=int, default=200, help="ties to check at most")
    pc.add_argument("--until", help="stop at this UTC time, HH:MM")
    pc.add_argument(
        "--no-kick", action="store_true", help="the control: templates from the data's steer state alone (own file)"
    )
    pc.add_argument("--out", help="write to this JSON lines file instead of the stored one (a subset, a trial)")
    pc.add_argument("--part", help="i/n: every n-th tie from the i-th, for n processes (each with its own --out)")
    sub.add_parser("report", help="write part 5 of docs/gap_validation.md and the figure")
    args = parser.parse_args()
    commands = {"run": run, "check": check, "rerun": rerun, "records": records, "push-check": push_check}
    commands["report"] = report
    return commands[args.command](args)


if __name__ == "__main__":
    sys.exit(main())
