"""Gap diagnosis of the SBW experiment from its raw logs, and its plan (``--next``): this version
against the version before the speed work (issue 21), in one run.

The command as a user runs it (docs/gap.md), in a fresh process each time::

    bikerider gap --model sbw_bicycle.toml --experiment experiment.toml --json [--next]

on the project's copy of the Pasma (2024) logs (59 windows from eight gzipped 100 Hz logs).  The
baseline is the same command from the source of commit :data:`BASELINE_REF` (the code before the
speed work), extracted with ``git archive`` into a temporary folder and imported from there
(``PYTHONPATH``), with the same interpreter and libraries.  Baseline and current runs alternate round
by round, so a change of the machine's load hits both alike; the ratio is baseline time / current
time (medians over the rounds).  Wall and processor time (user + system, of the child process) are
both reported: on a shared machine the wall time depends on the other work, the processor time
less.  Each round's two ``--json`` outputs are compared: verdict, selection, ranking, pairs and
plan must be the same, and the largest relative difference of any number is reported.

Goals (issue 21): the diagnosis at most 10 s, with ``--next`` at most 30 s on the project's 2-core
machine (wall time of the current version).  Run alone: ``.venv/bin/python bench/run.py --only gap_speed``
(``--quick``: one round).
"""

from __future__ import annotations

import json
import math
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

from common import ROOT, Context, Row, fmt_time

BASELINE_REF = "6eea8f4fe59a8947941ef416f9e337a750c3781f"
"""The commit before the gap speed work (main, 2026-11-27): the baseline of the ratios."""
GOALS = {"diagnosis": 10.0, "next": 30.0}
"""Wall-time goals [s] of issue 21 on the project's 2-core machine."""
SBW = ROOT / "src" / "bikerider" / "data" / "gap" / "pasma2024_sbw"
IGNORED = ("elapsed_s",)
"""Output fields that are measurements of the run itself."""


def _baseline_source(ctx: Context) -> tuple[Path | None, str]:
    """The baseline's source tree (``src`` folder to put on ``PYTHONPATH``), or why there is none."""
    target = ctx.tmpdir() / "gap_baseline"
    src = target / "src"
    if (src / "bikerider").is_dir():
        return src, ""
    try:
        commit = subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--verify", f"{BASELINE_REF}^{{commit}}"],
            capture_output=True,
            text=True,
            timeout=60,
            check=True,
        ).stdout.strip()
        target.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(
            ["git", "-C", str(ROOT), "archive", commit, "src", "generated"],
            capture_output=True,
            timeout=120,
            check=True,
        )
        subprocess.run(["tar", "-x", "-C", str(target)], input=archive.stdout, timeout=120, check=True)
    except (OSError, subprocess.SubprocessError) as exc:
        return (
            None,
            f"baseline commit {BASELINE_REF[:7]} not available here ({type(exc).__name__}: a git checkout is needed)",
        )
    # the package maps bikerider.generated onto the repository's generated/ folder
    (src / "bikerider" / "generated").symlink_to(target / "generated", target_is_directory=True)
    return src, ""


def _command(next_plan: bool) -> list[str]:
    cmd = [
        sys.executable,
        "-m",
        "bikerider",
        "gap",
        "--model",
        str(SBW / "sbw_bicycle.toml"),
        "--experiment",
        str(SBW / "experiment.toml"),
        "--json",
    ]
    return cmd + (["--next"] if next_plan else [])


def _run(cmd: list[str], pythonpath: Path | None) -> tuple[float, float, dict | str]:
    """Wall seconds, processor seconds (user + system) and the parsed ``--json`` output (or the error)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    if pythonpath is not None:
        env["PYTHONPATH"] = str(pythonpath)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=str(ROOT), env=env, timeout=1800)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if proc.returncode != 0:
        tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        return wall, cpu, f"exit status {proc.returncode}: {tail}"
    try:
        return wall, cpu, json.loads(proc.stdout)
    except json.JSONDecodeError:
        return wall, cpu, "no JSON output"


def _numbers(value, path: str = ""):
    """``(path, number)`` of every number in a JSON value (measurements of the run left out)."""
    if isinstance(value, dict):
        for key, item in value.items():
            if key not in IGNORED:
                yield from _numbers(item, f"{path}/{key}")
    elif isinstance(value, list):
        for k, item in enumerate(value):
            yield from _numbers(item, f"{path}[{k}]")
    elif isinstance(value, float | int) and not isinstance(value, bool):
        yield path, float(value)


def _skeleton(value):
    """The JSON value with every float replaced by None: what must be identical (names, order, flags)."""
    if isinstance(value, dict):
        return {k: _skeleton(v) for k, v in value.items() if k not in IGNORED}
    if isinstance(value, list):
        return [_skeleton(v) for v in value]
    if isinstance(value, float):
        return None
    return value


def compare(base: dict, ours: dict) -> tuple[bool, float, str]:
    """Whether everything but the floats is the same, the largest relative difference of a number, where."""
    same = _skeleton(base) == _skeleton(ours)
    a, b = dict(_numbers(base)), dict(_numbers(ours))
    worst, where = 0.0, "-"
    for path in a.keys() & b.keys():
        x, y = a[path], b[path]
        if x == y or (math.isnan(x) and math.isnan(y)):
            continue
        rel = abs(x - y) / max(abs(x), abs(y), 1e-300)
        if rel > worst:
            worst, where = rel, path
    return same and a.keys() == b.keys(), worst, where


def run(ctx: Context) -> list[Row]:
    rounds = 1 if ctx.quick else 3
    src, why = _baseline_source(ctx)
    rows = []
    for kind, label in (("diagnosis", "gap diagnosis"), ("next", "gap diagnosis and plan (--next)")):
        cmd = _command(kind == "next")
        samples: dict[str, list[tuple[float, float]]] = {"current": [], "baseline": []}
        outputs: dict[str, dict | str] = {}
        for r in range(rounds):
            order = ("baseline", "current") if r % 2 == 0 else ("current", "baseline")
            for who in order:
                if who == "baseline" and src is None:
                    continue
                wall, cpu, out = _run(cmd, src if who == "baseline" else None)
                samples[who].append((wall, cpu))
                outputs[who] = out
        wall = statistics.median(w for w, _ in samples["current"])
        cpu = statistics.median(c for _, c in samples["current"])
        goal = GOALS[kind]
        notes = [f"command: bikerider {' '.join(Path(c).name for c in cmd[3:])} ({rounds} round(s), fresh processes)"]
        current = outputs["current"]
        if isinstance(current, str):
            return [Row(f"{label} of the SBW experiment from raw logs", f"FAILED: {current}", met=False)]
        baselines, ratio = [], "-"
        if src is None:
            notes.append(why)
        else:
            base_wall = statistics.median(w for w, _ in samples["baseline"])
            base_cpu = statistics.median(c for _, c in samples["baseline"])
            baselines.append(
                (
                    f"bikerider {BASELINE_REF[:7]} (before the speed work)",
                    f"{fmt_time(base_wall)} wall, {fmt_time(base_cpu)} processor",
                )
            )
            ratio = f"{base_wall / wall:.1f}x wall, {base_cpu / cpu:.1f}x processor"
            base = outputs["baseline"]
            if isinstance(base, str):
                notes.append(f"baseline failed: {base}")
            else:
                same, worst, where = compare(base, current)
                notes.append(
                    (
                        "verdict, selection, ranking, pairs"
                        + (", plan" if kind == "next" else "")
                        + " and every name the same"
                        if same
                        else "OUTPUTS DIFFER beyond their numbers"
                    )
                    + f"; largest relative difference of a number {worst:.1e} ({where})"
                )
        notes.append(
            f"current: verdict {current['verdict']}, selected {', '.join(current['selected']) or 'nothing'}, "
            f"records used {current['records']['used']} of {current['records']['total']}"
        )
        rows.append(
            Row(
                f"{label} of the SBW experiment from raw logs, fresh process",
                f"{fmt_time(wall)} wall, {fmt_time(cpu)} processor (median of {rounds})",
                baselines=baselines,
                ratio=ratio,
                goal=f"<= {goal:.0f} s wall on 2 cores",
                met=wall <= goal,
                notes=notes,
            )
        )
    return rows


def main() -> int:
    ctx = Context(quick="--quick" in sys.argv)
    try:
        for row in run(ctx):
            print(
                f"{row.item}: {row.bikerider}; baseline {row.baselines}; ratio {row.ratio}; goal {row.goal} met {row.met}"
            )
            for note in row.notes:
                print(f"  - {note}")
    finally:
        ctx.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main())
