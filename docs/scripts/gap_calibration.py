"""Calibration study of the gap diagnosis: many short trials per candidate effect; writes part 4 of
docs/gap_validation.md.

Every trial draws a hidden effect's sizes over its prior and the bicycle's parameters from their stated
uncertainties, simulates short noisy runs with the independent truth of
:mod:`validation.cases` (Coulomb friction nonlinear in time), diagnoses them blind and scores the
ranking, the selection, the candidate's fitted sizes and their 95 % intervals, and the predicted against
the achieved shrinkage.  Trials go round the effects in turn (a run stopped early stays balanced) and are
appended to a JSON-lines file as they finish; the report is written from that file.  Run from the project
root::

    .venv/bin/python docs/scripts/gap_calibration.py --trials 200 --max-minutes 25
    .venv/bin/python docs/scripts/gap_calibration.py --report-only   # the doc from the stored trials
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

if str(ROOT) not in sys.path:  # validation/ (the gap's blind-check harnesses) lives beside src/, not installed
    sys.path.insert(0, str(ROOT))
BP = ROOT / "src" / "bikerider" / "data" / "bicycleparameters"
DOC = ROOT / "docs" / "gap_validation.md"
RESULTS = Path(__file__).with_name("gap_calibration_trials.jsonl")


def _models():
    from bikerider.io.gap_model import load_model

    bicycle = BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt"
    return {
        "riderless": load_model(bicycle),
        "rider": load_model(bicycle, BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt"),
    }


def run(trials: int, friction_every: int, max_minutes: float, out: Path, seed0: int) -> int:
    """Run up to ``trials`` per effect (a friction-from-records trial every ``friction_every`` rounds)."""
    import logging

    from validation import cases as V

    logging.disable(logging.WARNING)
    models = _models()
    start = time.perf_counter()
    done = 0
    total = trials * len(V.CALIBRATION_EFFECTS) + (trials // friction_every if friction_every else 0)
    with out.open("a", encoding="utf-8") as sink:
        for k in range(trials):
            jobs = [(e, lambda e=e, s=seed0 + k: V.run_trial(models, e, s)) for e in V.CALIBRATION_EFFECTS]
            if friction_every and k % friction_every == 0:
                jobs.append((V.CALIBRATION_FRICTION, lambda s=seed0 + k: V.run_friction_trial(models["riderless"], s)))
            for effect, job in jobs:
                elapsed = time.perf_counter() - start
                if elapsed > 60 * max_minutes:
                    print(f"time limit {max_minutes:g} min reached after {done} trials", file=sys.stderr)
                    return done
                trial = job()
                sink.write(json.dumps(trial.as_dict()) + "\n")
                sink.flush()
                done += 1
                rate = done / max(time.perf_counter() - start, 1e-9)
                left = (total - done) / rate if rate > 0 else math.inf
                print(
                    f"[{done}/{total}] round {k + 1} {effect.name}: first {trial.first}, selected "
                    f"{'+'.join(trial.selected) or '-'} ({trial.seconds:.1f} s; {rate * 60:.1f} trials/min, "
                    f"about {left / 60:.0f} min left at most)",
                    file=sys.stderr,
                    flush=True,
                )
    return done


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=200, help="trials per effect (default 200)")
    parser.add_argument(
        "--friction-every", type=int, default=4, help="a friction-from-records trial every N rounds (default 4)"
    )
    parser.add_argument("--max-minutes", type=float, default=25.0, help="stop starting trials after this long")
    parser.add_argument("--results", type=Path, default=RESULTS, help="JSON-lines file of the trials")
    parser.add_argument("--seed", type=int, default=1000, help="seed of the first round")
    parser.add_argument("--fresh", action="store_true", help="start a new results file (else append)")
    parser.add_argument("--report-only", action="store_true", help="write the doc from the stored trials")
    parser.add_argument("--doc", type=Path, default=DOC, help="the document whose part 4 is written")
    args = parser.parse_args(argv)
    if not args.report_only:
        if args.fresh and args.results.exists():
            args.results.unlink()
        start = time.perf_counter()
        run(args.trials, args.friction_every, args.max_minutes, args.results, args.seed)
        minutes = (time.perf_counter() - start) / 60
        print(f"trials done in {minutes:.1f} min", file=sys.stderr)
    from gap_calibration_report import write_report  # the report beside this script

    write_report(args.results, args.doc, args.trials)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).parent))
    sys.exit(main())
