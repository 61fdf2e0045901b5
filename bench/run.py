"""Run every benchmark in bench/ and print one table: item | bikerider | baseline(s) | ratio | goal | met?

Usage (``make bench`` runs the first)::

    .venv/bin/python bench/run.py                  # everything, print the table
    .venv/bin/python bench/run.py --write-docs     # also write docs/performance.md
    .venv/bin/python bench/run.py --quick          # fewer repeats, smaller baselines (a smoke run)
    .venv/bin/python bench/run.py --only eigenvalues critical_speeds

Each ``bench/bench_<name>.py`` module with a ``run(ctx) -> list[Row]`` function is one group of
items (see :mod:`common`).  A ``bench_*.py`` module without ``run`` is executed as a script and its
output is shown under the table.  A module that fails is reported and the others still run.
The exit status is 0 unless ``--strict`` is given and a goal is not met.
"""

from __future__ import annotations

import argparse
import datetime
import importlib
import logging
import os
import subprocess
import sys
import textwrap
import time
import traceback
import warnings
from pathlib import Path

BENCH = Path(__file__).resolve().parent
sys.path.insert(0, str(BENCH))

from common import ROOT, Context, Row, machine_facts  # noqa: E402

ORDER = ("eigenvalues", "critical_speeds", "batch", "raw_to_benchmark", "derive", "cold_start")
"""Modules run first, in this order; any other bench_*.py follows alphabetically."""


def discover(only: list[str] | None) -> list[str]:
    found = sorted(p.stem[len("bench_") :] for p in BENCH.glob("bench_*.py"))
    ordered = [n for n in ORDER if n in found] + [n for n in found if n not in ORDER]
    if only:
        unknown = [n for n in only if n not in found]
        if unknown:
            raise SystemExit(f"bench/run.py: no bench_{unknown[0]}.py (have: {', '.join(found)})")
        ordered = [n for n in ordered if n in only]
    return ordered


DESCRIPTIONS: dict[str, str] = {}
"""Module docstrings of the modules run, for the document's "what is measured" section."""


def run_module(name: str, ctx: Context) -> tuple[list[Row], str]:
    """Rows of one module, or its script output; failures become a row saying so."""
    try:
        module = importlib.import_module(f"bench_{name}")
    except Exception as exc:  # noqa: BLE001 - a broken module must not stop the others
        return [Row(name, f"could not import bench_{name}.py: {exc}", met=None)], ""
    if module.__doc__:
        DESCRIPTIONS[name] = module.__doc__.strip()
    if not hasattr(module, "run"):
        proc = subprocess.run(
            [sys.executable, str(BENCH / f"bench_{name}.py")],
            capture_output=True,
            text=True,
            cwd=str(ROOT),
            timeout=1800,
        )
        output = proc.stdout + (f"\n(exit status {proc.returncode}) {proc.stderr[-2000:]}" if proc.returncode else "")
        return [], f"### bench_{name}.py (script output)\n\n```\n{output.strip()}\n```\n"
    try:
        return list(module.run(ctx)), ""
    except Exception:  # noqa: BLE001
        return [
            Row(
                name,
                "FAILED: " + traceback.format_exc(limit=3).strip().splitlines()[-1],
                met=False,
                notes=[traceback.format_exc(limit=6)],
            )
        ], ""


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def table(rows: list[Row]) -> str:
    lines = ["| item | bikerider | baseline(s) | ratio | goal | met? |", "|---|---|---|---|---|---|"]
    for row in rows:
        baselines = "<br>".join(f"{name}: {value}" for name, value in row.baselines) or "-"
        met = {True: "yes", False: "**no**", None: "n/a"}[row.met]
        lines.append(
            "| " + " | ".join(_cell(x) for x in (row.item, row.bikerider, baselines, row.ratio, row.goal, met)) + " |"
        )
    return "\n".join(lines)


def notes_text(rows: list[Row]) -> str:
    out = []
    for row in rows:
        if row.notes:
            out.append(f"- **{row.item}**")
            out.extend(textwrap.indent("\n".join(f"- {n}" for n in row.notes), "  ").splitlines())
    return "\n".join(out)


def document(command: str, facts: dict[str, str], rows: list[Row], extra: str, seconds: float) -> str:
    met = sum(r.met is True for r in rows)
    judged = sum(r.met is not None for r in rows)
    when = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    parts = [
        "# Performance",
        "",
        "Speed and memory of bikerider against the tools a user would otherwise pick, all measured in",
        "one run on one machine (`make bench`, source in `bench/`). Times are medians over repeats",
        "(`median of R x L` = R timed loops of L calls each); a ratio is baseline time / bikerider time.",
        "Within one process the timed loops of bikerider and its baselines are interleaved round by",
        "round, so a change of load hits them alike. BicycleParameters runs in its own virtual",
        "environment (`bench/.venv-baseline`), timed inside its own process; for the one item whose",
        "ratio is near its goal (one bicycle from raw measurements) that process stays up and its",
        "rounds alternate with bikerider's, and the ratio is the median of the rounds' ratios. The",
        "machine is a shared virtual machine (2 cores) whose speed changes by up to 2x within seconds,",
        "so absolute times move from run to run; the ratios move less.",
        "",
        f"Produced by `{command}` on {when} in {seconds:.0f} s.",
        "",
        "## Machine and versions",
        "",
        *[f"- {k}: {v}" for k, v in facts.items()],
        "",
        f"## Results ({met} of {judged} goals met)",
        "",
        table(rows),
        "",
        "## Notes",
        "",
        notes_text(rows),
        "",
    ]
    if extra:
        parts += ["## Other benchmarks", "", extra, ""]
    if DESCRIPTIONS:
        parts += ["## What each benchmark measures", ""]
        for name, doc in DESCRIPTIONS.items():
            parts += [f"### bench/bench_{name}.py", "", doc, ""]
    return "\n".join(parts)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats and smaller baselines")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="run only bench_NAME.py modules")
    parser.add_argument("--write-docs", action="store_true", help="write the results to docs/performance.md")
    parser.add_argument("--strict", action="store_true", help="exit 1 when a goal is not met")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")  # lambdified baselines warn with whole expressions
    logging.disable(logging.WARNING)  # the data's own warnings (e.g. an accepted IRyy) are not results
    ctx = Context(quick=args.quick, repeats=3 if args.quick else 7, only=tuple(args.only or ()))
    start = time.perf_counter()
    try:
        facts = machine_facts(ctx)
        rows: list[Row] = []
        extra = []
        for name in discover(args.only):
            print(f"bench: {name} ...", file=sys.stderr, flush=True)
            t0 = time.perf_counter()
            module_rows, output = run_module(name, ctx)
            print(f"bench: {name} done in {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
            rows += module_rows
            if output:
                extra.append(output)
    finally:
        ctx.cleanup()
    seconds = time.perf_counter() - start
    command = (
        "make bench"
        if not argv and os.environ.get("MAKELEVEL")
        else "python bench/run.py " + " ".join(argv or sys.argv[1:])
    )
    text = document(command.strip(), facts, rows, "\n".join(extra), seconds)
    print(text)
    if args.write_docs:
        (ROOT / "docs" / "performance.md").write_text(text, encoding="utf-8")
        print("bench: wrote docs/performance.md", file=sys.stderr)
    unmet = [r for r in rows if r.met is False]
    return 1 if args.strict and unmet else 0


if __name__ == "__main__":
    sys.exit(main())
