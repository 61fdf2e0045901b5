"""Gap diagnosis: ~20 measured weave eigenvalues in 3 groups, every candidate effect.

Measured on the Davis instrumented bicycle with rider Jason: 21 runs (three sessions of seven,
one under a known control) simulated by :mod:`bikerider.gap.validation` with a hidden leaning upper
body and steer friction (two effects: the greedy selection fits and cross-validates pairs and triples),
weave eigenvalues fitted from the noisy roll rates.  Timed: :class:`bikerider.gap.diagnosis.Diagnosis`
(gap map, parameter fit, seven candidates on three held-out folds, greedy selection, full-data fits)
and ``as_dict``.  Goal: at most 30 s on 2 cores.  Run alone: ``.venv/bin/python bench/bench_gap.py``.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
GOAL_SECONDS = 30.0


def workload():
    import numpy as np

    from bikerider.gap import validation as V
    from bikerider.gap.data import CanonicalData
    from bikerider.io.gap_model import load_model

    bp = ROOT / "src" / "bikerider" / "data" / "bicycleparameters"
    model = load_model(bp / "bicycles/Rigid/Parameters/RigidBenchmark.txt", bp / "riders/Jason/Parameters/JasonRigidBenchmark.txt")
    protocol = V.Protocol((
        V.Session("day1", (5.5, 6.1, 6.7, 7.3, 7.9, 8.5, 9.1)),
        V.Session("day2", (5.7, 6.3, 6.9, 7.5, 8.1, 8.7, 9.3)),
        V.Session("day3-controlled", (4.0, 4.6, 5.2, 5.8, 6.4, 7.0, 7.6), V.CONTROL),
    ))
    rng = np.random.default_rng(2024)
    truth = V.TruthSimulator(model, V.TRUTHS["rider_lean+steer_damping"], rng)
    data, _ = V.measure(truth, protocol, rng)
    return model, data, CanonicalData([], np.empty(0), np.empty(0), [], {}, [])


def time_diagnosis() -> tuple[float, int, dict]:
    from bikerider.gap.diagnosis import Diagnosis

    model, data, empty = workload()
    start = time.perf_counter()
    result = Diagnosis(model, data, empty).as_dict()
    return time.perf_counter() - start, len(data), result


def run(ctx):
    from common import Row, fmt_time

    seconds, n, result = time_diagnosis()
    return [Row(f"gap diagnosis, {n} weave eigenvalues in 3 groups, 7 candidates", fmt_time(seconds),
                goal=f"<= {GOAL_SECONDS:.0f} s", met=seconds <= GOAL_SECONDS,
                notes=[f"verdict {result['verdict']}, selected {', '.join(result['selected']) or 'nothing'}"])]


def main() -> int:
    seconds, n, result = time_diagnosis()
    print(f"gap diagnosis of {n} weave eigenvalues in 3 groups with all candidates: {seconds:.1f} s "
          f"(goal <= {GOAL_SECONDS:.0f} s: {'met' if seconds <= GOAL_SECONDS else 'NOT met'}); "
          f"verdict {result['verdict']}, selected {', '.join(result['selected']) or 'nothing'}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT / "src"))
    sys.exit(main())
