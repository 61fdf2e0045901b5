"""Item 6: ``bikerider estimate`` from a cold start (a new process, the paper's bicycle and rider).

Wall time of the whole subprocess - interpreter start, imports, reading both files, the estimate,
eigenvalues at 11 speeds, printing - median of several runs.  The heaviest imports are listed
from ``python -X importtime``.  For comparison, a fresh BicycleParameters process doing the same
kind of job: import, ``Bicycle('Browser', forceRawCalc=True)``, ``add_rider('Jason')``, ``eig`` at
11 speeds, print.
"""

from __future__ import annotations

import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

from common import BASELINE_PYTHON, ROOT, Context, Row, fmt_time, ratio_text

GOAL_SECONDS = 1.0

BP_SCRIPT = """
import contextlib, io, sys, warnings
warnings.simplefilter("ignore")
import numpy as np
import bicycleparameters as bp
with contextlib.redirect_stdout(io.StringIO()):
    b = bp.Bicycle("Browser", pathToData=sys.argv[1], forceRawCalc=True)
    b.add_rider("Jason")
    values, _ = b.eig(np.linspace(0, 10, 11))
print(values)
"""


def _wall(cmd: list[str], runs: int, env: dict | None = None) -> tuple[float, int]:
    times, status = [], 0
    for _ in range(runs):
        start = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=str(ROOT), env=env, timeout=120)
        times.append(time.perf_counter() - start)
        status = status or proc.returncode
    return statistics.median(times), status


def heaviest_imports(top: int = 5) -> list[str]:
    """``module cumulative-ms`` of the slowest top-level imports of ``bikerider estimate``."""
    code = "import sys; sys.argv = ['bikerider', 'estimate']; from bikerider.cli import main; main()"
    proc = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", code], capture_output=True, text=True, cwd=str(ROOT), timeout=120
    )
    rows = []
    for line in proc.stderr.splitlines():
        m = re.match(r"import time:\s+(\d+) \|\s+(\d+) \| (\s*)(\S+)", line)
        if m and len(m.group(3)) <= 1:  # top-level imports only
            rows.append((int(m.group(2)), m.group(4)))
    rows.sort(reverse=True)
    return [f"{name} {us / 1000:.0f} ms" for us, name in rows[:top]]


def run(ctx: Context) -> list[Row]:
    runs = 3 if ctx.quick else 7
    cli = Path(sys.executable).with_name("bikerider")
    cmd = [str(cli), "estimate"] if cli.exists() else [sys.executable, "-m", "bikerider", "estimate"]
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    ours, status = _wall(cmd, runs, env)
    notes = [
        f"command: {' '.join(Path(c).name if i == 0 else c for i, c in enumerate(cmd))} "
        f"(exit status {status}), median of {runs} runs",
        "heaviest imports (python -X importtime, cumulative): " + ", ".join(heaviest_imports()),
    ]
    baselines = []
    ratio = "-"
    if BASELINE_PYTHON.exists():
        bp_time, bp_status = _wall([str(BASELINE_PYTHON), "-c", BP_SCRIPT, str(ctx.bp_data())], runs)
        if bp_status == 0:
            baselines.append(
                (
                    "BicycleParameters, fresh process (import, Bicycle from raw, add_rider, eig)",
                    f"{fmt_time(bp_time)} (median of {runs})",
                )
            )
            ratio = f"{ratio_text(bp_time, ours)} vs BicycleParameters"
        else:
            notes.append(f"BicycleParameters cold run failed (exit status {bp_status})")
    else:
        notes.append("BicycleParameters baseline not installed")
    return [
        Row(
            "bikerider estimate, cold start",
            f"{fmt_time(ours)} wall (median of {runs})",
            baselines,
            ratio,
            f"<= {GOAL_SECONDS:.0f} s",
            ours <= GOAL_SECONDS and status == 0,
            notes,
        )
    ]
