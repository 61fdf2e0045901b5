"""Item 5: ``make derive`` - regenerating every module of generated/ from the SymPy derivations.

Runs ``python -m derive --out <temporary folder>`` (the same code ``make derive`` runs, written
elsewhere so the benchmark never touches the tree), wall time from a fresh process.  One run
(two with ``--quick`` off would double a minute-long benchmark for little).  Also compares the
operation counts it produced with ``bench/operation_counts_baseline.json`` (the test
``tests/test_operation_counts.py`` enforces the 5 % limit on the committed counts).
"""

from __future__ import annotations

import subprocess
import sys
import time

from common import BENCH, ROOT, Context, Row, fmt_time

GOAL_SECONDS = 60.0


def run(ctx: Context) -> list[Row]:
    sys.path.insert(0, str(BENCH))
    import operation_counts as oc

    out = ctx.tmpdir() / "generated"
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "derive", "--out", str(out), "-q"],
        cwd=str(ROOT),
        capture_output=True,
        text=True,
        timeout=1800,
    )
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        return [Row("make derive", f"FAILED after {seconds:.1f} s: {tail}", met=False)]
    produced = oc.load_counts(out / "operation_counts.json")
    result = oc.compare(oc.load_counts(oc.BASELINE), produced)
    total = sum(v["after_cse"] for v in produced.values())
    notes = [
        f"{len(produced)} generated functions, {total} operations after CSE in all",
        "operation counts against bench/operation_counts_baseline.json: " + oc.report(result).replace("\n", "; "),
    ]
    counts_ok = not result.grown
    return [
        Row(
            "make derive (python -m derive, all modules)",
            f"{fmt_time(seconds)} (1 run, fresh process)",
            [("operation counts vs baseline", "no growth > 5 %" if counts_ok else f"{len(result.grown)} grew > 5 %")],
            "-",
            f"<= {GOAL_SECONDS:.0f} s; no function's operation count +5 %",
            seconds <= GOAL_SECONDS and counts_ok,
            notes,
        )
    ]
