"""Calibration study of the gap diagnosis: many short trials per candidate effect; writes part 4 of
docs/gap_validation.md.

Every trial draws a hidden effect's sizes over its prior and the bicycle's parameters from their stated
uncertainties, simulates short noisy runs with the independent truth of :mod:`validation.cases` (Coulomb
friction nonlinear in time), gives the diagnosis the runs as records (each predicted by indirect inference)
and scores the ranking, the selection, the candidate's fitted sizes and their 95 % intervals, and the
predicted against the achieved shrinkage.  In the first ``--compare-rounds`` rounds each trial is also run
with the method before (a table of the eigenvalues fitted from the same runs), for the comparison.

Trials go round the effects in turn (a run stopped early stays balanced), two at a time in worker
processes (one BLAS thread each); this process appends each finished trial to a JSON-lines file, and a
second start resumes where the file ends (trials already in it are not run again).  SIGTERM or Ctrl-C
stops it keeping every finished trial; the report is written from the file.  Run from the project root::

    nohup nice -n 10 .venv/bin/python docs/scripts/gap_calibration.py --trials 200 --compare-rounds 10 \
        --max-minutes 0 > calibration_run.log 2>&1 &
    .venv/bin/python docs/scripts/gap_calibration.py --report-only   # the doc from the stored trials

``--effects`` reruns some effects' trials alone (the same seeds as the whole study) into a separate file
and prints their coverage instead of writing the document, e.g. the friction trials after a change to
the friction fit::

    nice -n 10 .venv/bin/python docs/scripts/gap_calibration.py --fresh --effects steer_friction_records \
        --trials 200 --workers 1 --max-minutes 0 --results /tmp/friction.jsonl

``--seeds-of FILE`` (a JSON object, effect name to a list of seeds) keeps, of the effects it names, only the
trials at those seeds: a rerun of the trials a change can touch (those whose ranking or selection held the
candidates it reorders), the other trials of those effects being unchanged by it.
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import os
import signal
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before NumPy loads: each worker process computes on one thread
os.environ.setdefault("OMP_NUM_THREADS", "1")

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


def effect_names() -> list[str]:
    """Every effect of the study by the name its trials are stored under."""
    from validation import cases as V

    return [e.name for e in V.CALIBRATION_EFFECTS] + [V.CALIBRATION_FRICTION.name]


def jobs(
    trials: int, friction_every: int, compare_rounds: int, seed0: int, effects: list[str] | None = None
) -> list[tuple[str, int, str]]:
    """Every trial of the study in the order it is run: ``(effect, seed, method)``.

    Rounds go round the effects in turn (a run stopped early stays balanced, within a round); a
    friction-from-records trial every ``friction_every`` rounds; in the first ``compare_rounds`` rounds each
    table effect also with the method before issue 21 (``tables``: the eigenvalues fitted from the same
    runs), for the before/after comparison on the same seeds.  ``effects`` keeps only those effects'
    trials (the same seeds as in the whole study).
    """
    from validation import cases as V

    out = []
    for k in range(trials):
        seed = seed0 + k
        out += [(e.name, seed, "records") for e in V.CALIBRATION_EFFECTS]
        if friction_every and k % friction_every == 0:
            out.append((V.CALIBRATION_FRICTION.name, seed, "records"))
        if k < compare_rounds:
            out += [(e.name, seed, "tables") for e in V.CALIBRATION_EFFECTS]
    return out if effects is None else [j for j in out if j[0] in effects]


_MODELS = None
"""The nominal models of a worker process (loaded once per process)."""


def _start_worker() -> None:
    """A worker process: one BLAS thread, no worker processes of its own, warnings silenced."""
    import logging

    from bikerider.gap.blas_threads import limit_to_one_thread

    os.environ["BIKERIDER_GAP_WORKERS"] = "1"
    logging.disable(logging.WARNING)
    limit_to_one_thread()


def _run_job(job: tuple[str, int, str]) -> dict:
    """One trial (in a worker process); a failure comes back as ``{"error": text}`` (an exception of the
    project's would not survive the way back: its class takes more than a message)."""
    from validation import cases as V

    global _MODELS
    try:
        if _MODELS is None:
            _MODELS = _models()
        effect, seed, method = job
        if effect == V.CALIBRATION_FRICTION.name:
            trial = V.run_friction_trial(_MODELS["riderless"], seed)
        else:
            trial = V.run_trial(_MODELS, next(e for e in V.CALIBRATION_EFFECTS if e.name == effect), seed, method)
    except Exception as exc:  # reported by the parent and left out, never stopping the study
        return {"error": f"{type(exc).__name__}: {exc}"}
    return trial.as_dict()


def _key(trial: dict) -> tuple[str, int, str]:
    return trial["effect"], int(trial["seed"]), trial.get("method", "tables")


def run(
    trials: int,
    friction_every: int,
    max_minutes: float,
    out: Path,
    seed0: int,
    workers: int = 2,
    compare_rounds: int = 0,
    effects: list[str] | None = None,
    seeds_of: dict[str, list[int]] | None = None,
) -> int:
    """Run the study's trials not yet in ``out`` (resumable), ``workers`` at a time; each trial's result is
    appended to ``out`` by this process as soon as it finishes.  Stops starting trials after
    ``max_minutes`` (0: no limit) and on Ctrl-C / SIGTERM, keeping every finished trial.  ``seeds_of`` keeps,
    of the effects it names, only the trials at its seeds."""
    from gap_calibration_report import load  # the report beside this script

    done_keys = {_key(t) for t in load(out)}
    todo = [j for j in jobs(trials, friction_every, compare_rounds, seed0, effects) if j not in done_keys]
    if seeds_of:
        todo = [j for j in todo if j[0] not in seeds_of or j[1] in seeds_of[j[0]]]
    total = len(todo)
    print(f"{total} trials to run ({len(done_keys)} already in {out.name}), {workers} at a time", file=sys.stderr)
    start = time.perf_counter()
    done = 0
    stopping = []
    signal.signal(signal.SIGTERM, lambda *_: stopping.append("SIGTERM"))
    context = multiprocessing.get_context("fork")
    with (
        context.Pool(workers, initializer=_start_worker, maxtasksperchild=200) as pool,
        out.open("a", encoding="utf-8") as sink,
    ):
        pending = []
        queue = list(todo)
        try:
            while queue or pending:
                limit = max_minutes and time.perf_counter() - start > 60 * max_minutes
                while queue and len(pending) < workers and not limit and not stopping:
                    job = queue.pop(0)
                    pending.append((job, pool.apply_async(_run_job, (job,))))
                if not pending:
                    break
                finished = [(j, r) for j, r in pending if r.ready()]
                if not finished:
                    time.sleep(0.2)
                    continue
                for job, result in finished:
                    pending.remove((job, result))
                    trial = result.get()
                    if "error" in trial:  # a failed trial is reported and left out, never stops the study
                        print(f"{job}: failed ({trial['error']})", file=sys.stderr, flush=True)
                        continue
                    sink.write(json.dumps(trial) + "\n")
                    sink.flush()
                    done += 1
                    rate = done / max(time.perf_counter() - start, 1e-9)
                    left = (total - done) / rate if rate > 0 else math.inf
                    print(
                        f"[{done}/{total}] {job[0]} seed {job[1]} {job[2]}: first {trial['first']}, selected "
                        f"{'+'.join(trial['selected']) or '-'} ({trial['seconds']:.1f} s; {rate * 60:.1f} trials/min, "
                        f"about {left / 60:.0f} min left)",
                        file=sys.stderr,
                        flush=True,
                    )
                if (limit or stopping) and queue:
                    print(
                        f"stopping ({stopping[0] if stopping else f'time limit {max_minutes:g} min'}): "
                        f"{len(queue)} trials not started, waiting for {len(pending)}",
                        file=sys.stderr,
                        flush=True,
                    )
                    queue.clear()
        except KeyboardInterrupt:
            print(f"interrupted after {done} trials; every finished trial is in {out.name}", file=sys.stderr)
            pool.terminate()
    return done


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=200, help="trials per effect (default 200)")
    parser.add_argument(
        "--friction-every", type=int, default=1, help="a friction-from-records trial every N rounds (default 1)"
    )
    parser.add_argument("--max-minutes", type=float, default=25.0, help="stop starting trials after this long")
    parser.add_argument("--results", type=Path, default=RESULTS, help="JSON-lines file of the trials")
    parser.add_argument("--seed", type=int, default=1000, help="seed of the first round")
    parser.add_argument("--fresh", action="store_true", help="start a new results file (else append)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2, one per core)")
    parser.add_argument(
        "--compare-rounds",
        type=int,
        default=0,
        help="rounds whose table trials also run with the method before issue 21 (eigenvalue tables)",
    )
    parser.add_argument(
        "--effects",
        help="run only these effects' trials (comma-separated names as stored, e.g. steer_friction_records; "
        "the same seeds as the whole study) and print their coverage instead of writing the doc",
    )
    parser.add_argument(
        "--seeds-of",
        type=Path,
        help="JSON file, effect name to seeds: of the effects it names run only those seeds (with --effects)",
    )
    parser.add_argument("--report-only", action="store_true", help="write the doc from the stored trials")
    parser.add_argument("--doc", type=Path, default=DOC, help="the document whose part 4 is written")
    args = parser.parse_args(argv)
    effects = None
    if args.effects:
        effects = [e.strip() for e in args.effects.split(",") if e.strip()]
        unknown = [e for e in effects if e not in effect_names()]
        if unknown or not effects:
            parser.error(f"--effects {args.effects!r}: unknown {unknown}; the study's effects are {effect_names()}")
        if args.results == RESULTS:
            parser.error("--effects writes a part of the study: give it its own --results file")
    if args.seeds_of and not args.effects:
        parser.error("--seeds-of reruns a part of the study: give --effects (and its own --results file) too")
    if not args.report_only:
        if args.fresh and args.results.exists():
            args.results.unlink()
        start = time.perf_counter()
        run(
            args.trials,
            args.friction_every,
            args.max_minutes,
            args.results,
            args.seed,
            args.workers,
            args.compare_rounds,
            effects,
            _seeds_of(args.seeds_of, parser) if args.seeds_of else None,
        )
        minutes = (time.perf_counter() - start) / 60
        print(f"trials done in {minutes:.1f} min", file=sys.stderr)
    from gap_calibration_report import write_report  # the report beside this script

    if effects is not None:
        print_summary(args.results, effects)
        return 0
    write_report(args.results, args.doc, args.trials)
    return 0


def _seeds_of(path: Path, parser: argparse.ArgumentParser) -> dict[str, list[int]]:
    """The ``--seeds-of`` file read and checked (a usage error names what is wrong)."""
    try:
        seeds = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        parser.error(f"--seeds-of {path}: cannot read a JSON object of effect to seeds ({exc})")
    if not isinstance(seeds, dict) or not all(
        isinstance(v, list) and all(isinstance(x, int) for x in v) for v in seeds.values()
    ):
        parser.error(f"--seeds-of {path}: expected a JSON object of effect name to a list of integer seeds")
    unknown = [e for e in seeds if e not in effect_names()]
    if unknown:
        parser.error(f"--seeds-of {path}: unknown effects {unknown}; the study's effects are {effect_names()}")
    return seeds


def print_summary(results: Path, effects: list[str]) -> None:
    """Each fitted size's coverage of its 95 % interval, its errors over their stated standard error
    (``z = (fit - truth) / (half-width / 1.96)``) and its median relative error, for ``effects``' trials."""
    import numpy as np
    from gap_calibration_report import load

    trials = [t for t in load(results) if t["effect"] in effects]
    sizes = sorted({(t["effect"], n) for t in trials for n in t["fitted"] if n in t["reference"]})
    print("effect size trials coverage z_mean z_rms low_misses high_misses median_error")
    for effect, name in sizes:
        rows = [
            (t["reference"][name], t["fitted"][name])
            for t in trials
            if t["effect"] == effect and name in t["fitted"] and t["reference"].get(name) is not None
        ]
        truth = np.array([r[0] for r in rows])
        value = np.array([r[1]["value"] for r in rows])
        low, high = np.array([r[1]["ci95"] for r in rows]).T
        inside = (low <= truth) & (truth <= high)
        half = (high - low) / 2
        z = np.where(half > 0, (value - truth) / np.where(half > 0, half / 1.96, 1.0), np.nan)
        rel = np.where(truth != 0, (value - truth) / np.where(truth != 0, np.abs(truth), 1.0), np.nan)
        print(
            f"{effect} {name} {len(rows)} {inside.sum()}/{len(rows)} ({100 * inside.mean():.0f} %) "
            f"{np.nanmean(z):+.2f} {np.sqrt(np.nanmean(z**2)):.2f} {int(np.sum(truth > high))} "
            f"{int(np.sum(truth < low))} {np.nanmedian(rel) * 100 if np.isfinite(rel).any() else float('nan'):+.1f}%"
        )


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).parent))
    sys.exit(main())
