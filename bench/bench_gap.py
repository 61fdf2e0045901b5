"""Gap diagnosis: ~20 measured weave eigenvalues in 3 groups; the steer-by-wire experiment from raw logs.

Item 2, the SBW experiment (Pasma 2024, the project's copy): the whole diagnosis from the raw logs
as ``bikerider gap --model sbw_bicycle.toml --experiment experiment.toml`` runs it: read the manifest
and the eight gzipped 100 Hz logs, cut the 59 windows, fit every record, remove the fit's bias,
cross-validate every candidate (steer friction in the time domain) and the pairs on the eight files
held out in turn, select, and build the result.  Goal: at most 60 s on 2 cores.

Item 1, measured on the Davis instrumented bicycle with rider Jason: 21 runs (three sessions of
seven, one under a known control) simulated by :mod:`validation.cases` with a hidden leaning
upper body and steer friction, weave eigenvalues fitted from the noisy roll rates.  Timed:
:class:`bikerider.gap.diagnosis.result.Diagnosis` (gap map, parameter fit, the candidates and their pairs on
three held-out folds, selection, full-data fits) and ``as_dict``.  Goal: at most 30 s on 2 cores.

Run alone: ``.venv/bin/python bench/bench_gap.py``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

if str(ROOT) not in sys.path:  # validation/ (the gap's blind-check harnesses) lives beside src/, not installed
    sys.path.insert(0, str(ROOT))
GOAL_SECONDS = 30.0
SBW_GOAL_SECONDS = 60.0
SBW = ROOT / "src" / "bikerider" / "data" / "gap" / "pasma2024_sbw"


def workload():
    import numpy as np

    from bikerider.gap.measured.tables import CanonicalData
    from bikerider.io.gap_model import load_model
    from validation import cases as V

    bp = ROOT / "src" / "bikerider" / "data" / "bicycleparameters"
    model = load_model(
        bp / "bicycles/Rigid/Parameters/RigidBenchmark.txt", bp / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
    )
    protocol = V.Protocol(
        (
            V.Session("day1", (5.5, 6.1, 6.7, 7.3, 7.9, 8.5, 9.1)),
            V.Session("day2", (5.7, 6.3, 6.9, 7.5, 8.1, 8.7, 9.3)),
            V.Session("day3-controlled", (4.0, 4.6, 5.2, 5.8, 6.4, 7.0, 7.6), V.CONTROL),
        )
    )
    rng = np.random.default_rng(2024)
    truth = V.TruthSimulator(model, V.TRUTHS["rider_lean+steer_damping"], rng)
    data, _ = V.measure(truth, protocol, rng)
    return model, data, CanonicalData([], np.empty(0), np.empty(0), [], {}, [])


def time_diagnosis() -> tuple[float, int, dict]:
    from bikerider.gap.diagnosis.result import diagnose

    model, data, empty = workload()
    start = time.perf_counter()
    result = diagnose(model, data, empty).as_dict()
    return time.perf_counter() - start, len(data), result


def time_sbw() -> tuple[dict[str, float], dict]:
    """Seconds of each stage of the SBW diagnosis from the raw logs, and its result."""
    from bikerider.diagnose import load_records
    from bikerider.gap.diagnosis.result import diagnose
    from bikerider.gap.measured.records import fit_records
    from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
    from bikerider.io.experiment import read_manifest
    from bikerider.io.gap_model import load_model

    stages = {}
    start = time.perf_counter()
    model = load_model(SBW / "sbw_bicycle.toml")
    settings, windows = read_manifest(SBW / "experiment.toml")
    records = load_records(settings, windows)
    stages["read"] = time.perf_counter() - start
    t = time.perf_counter()
    fits = fit_records(records)
    stages["fit records"] = time.perf_counter() - t
    t = time.perf_counter()
    result = diagnose(model, EigenvalueData.empty(), CanonicalData.empty(), records=fits).as_dict()
    stages["diagnose"] = time.perf_counter() - t
    stages["total"] = time.perf_counter() - start
    return stages, result


def run(ctx):
    from common import Row, fmt_time

    seconds, n, result = time_diagnosis()
    rows = [
        Row(
            f"gap diagnosis, {n} weave eigenvalues in 3 groups, 7 candidates",
            fmt_time(seconds),
            goal=f"<= {GOAL_SECONDS:.0f} s",
            met=seconds <= GOAL_SECONDS,
            notes=[f"verdict {result['verdict']}, selected {', '.join(result['selected']) or 'nothing'}"],
        )
    ]
    stages, sbw = time_sbw()
    rows.append(
        Row(
            f"gap diagnosis of the SBW experiment from raw logs, {sbw['records']['total']} records",
            fmt_time(stages["total"]),
            ratio=f"{stages['total'] / SBW_GOAL_SECONDS:.2f} of the goal",
            goal=f"<= {SBW_GOAL_SECONDS:.0f} s",
            met=stages["total"] <= SBW_GOAL_SECONDS,
            notes=[
                ", ".join(f"{k} {fmt_time(v)}" for k, v in stages.items() if k != "total")
                + f"; {sbw['records']['used']} records used, verdict {sbw['verdict']}, selected "
                f"{', '.join(sbw['selected']) or 'nothing'}"
            ],
        )
    )
    return rows


def main() -> int:
    seconds, n, result = time_diagnosis()
    print(
        f"gap diagnosis of {n} weave eigenvalues in 3 groups with all candidates: {seconds:.1f} s "
        f"(goal <= {GOAL_SECONDS:.0f} s: {'met' if seconds <= GOAL_SECONDS else 'NOT met'}); "
        f"verdict {result['verdict']}, selected {', '.join(result['selected']) or 'nothing'}"
    )
    stages, sbw = time_sbw()
    print(
        f"SBW experiment from raw logs ({sbw['records']['total']} records): {stages['total']:.1f} s "
        f"(goal <= {SBW_GOAL_SECONDS:.0f} s: {'met' if stages['total'] <= SBW_GOAL_SECONDS else 'NOT met'}; "
        + ", ".join(f"{k} {v:.1f} s" for k, v in stages.items() if k != "total")
        + f"); verdict {sbw['verdict']}, selected {', '.join(sbw['selected']) or 'nothing'}"
    )
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT / "src"))
    sys.exit(main())
