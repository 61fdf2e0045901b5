"""Gap diagnosis: cost against the size of the data (linear time, bounded memory).

Item 1, eigenvalue rows: a table of ``n`` measured weave eigenvalues of the Davis bicycle with rider
Jason (one group, speeds spread over 4-9 m/s, no stated uncertainties: the replicate-scatter path)
diagnosed with one candidate (steer damping), at n = 1,000 and 10,000 rows in the same run.  Ratio:
time per row at 10,000 over time per row at 1,000 (1 when the cost is linear; the gap test once
built the dense n x n covariance, 10,000 rows took 103 s and 6.4 GB), and likewise the peak traced
memory per row.  Goal: both ratios at most 1.5.

Item 2, record samples: one perturbation run of ``n`` samples (a slowly decaying 0.8 Hz oscillation
with noise, 100 Hz) fitted as a record (the weave fit, with its grid scan for a start), at n = 2,000 and
20,000 in the same run.  Ratio: peak traced memory per sample at 20,000 over that at 2,000 (the grid
scan once held all its basis functions for every sample, about 82 kB a sample: 300,000 samples asked
for 22.9 GiB), with the bytes per sample shown.  Goal: ratio at most 1.5 and at most 2 kB a sample.

Run alone: ``.venv/bin/python bench/bench_gap_scaling.py``.
"""

from __future__ import annotations

import sys
import time
import tracemalloc
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ROWS = (1_000, 10_000)
SAMPLES = (2_000, 20_000)
RATIO_GOAL = 1.5
BYTES_PER_SAMPLE_GOAL = 2_000


def _model():
    from bikerider.io.gap_model import load_model

    bp = ROOT / "src" / "bikerider" / "data" / "bicycleparameters"
    return load_model(
        bp / "bicycles/Rigid/Parameters/RigidBenchmark.txt", bp / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
    )


def eigenvalue_table(n: int):
    """``n`` weave eigenvalues near the model's, one group, no stated uncertainty (fixed seed)."""
    import numpy as np

    from bikerider.gap.measured.control import ControlLaw
    from bikerider.gap.measured.tables import EigenvalueData

    rng = np.random.default_rng(12)
    speed = rng.uniform(4.0, 9.0, n)
    value = (-0.3 * (speed - 6.0) + 0.05 * rng.standard_normal(n)) + 1j * (2.5 + 0.05 * rng.standard_normal(n))
    law = ControlLaw.constant(np.zeros(4))
    return EigenvalueData(
        speed,
        value,
        np.full(n, np.nan),
        np.full(n, np.nan),
        np.zeros(n),
        ["weave"] * n,
        ["bench"] * n,
        np.zeros((n, 4)),
        [f"bench:{k}" for k in range(n)],
        [law.name] * n,
        {law.name: law},
    )


def _measured(fn) -> tuple[float, int]:
    """Seconds and peak traced bytes of one call."""
    tracemalloc.start()
    start = time.perf_counter()
    fn()
    seconds = time.perf_counter() - start
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return seconds, peak


def time_rows(n: int, model) -> tuple[float, int]:
    from bikerider.gap.diagnosis.result import diagnose
    from bikerider.gap.measured.tables import CanonicalData

    data = eigenvalue_table(n)
    return _measured(lambda: diagnose(model, data, CanonicalData.empty(), ("steer_damping",)).as_dict())


def record(n: int):
    import numpy as np

    from bikerider.gap.measured.control import ControlLaw
    from bikerider.gap.measured.records import Record

    t = np.arange(n) / 100.0
    rng = np.random.default_rng(3)
    roll_rate = 0.3 * np.exp(-0.01 * t) * np.sin(5.0 * t) + 0.01 * rng.standard_normal(n)
    law = ControlLaw.constant(np.zeros(4))
    return Record("bench", "bench", t, {"roll_rate": roll_rate}, 7.0, 0.0, "bench", law, 7.0, None, None)


def time_samples(n: int) -> tuple[float, int]:
    from bikerider.gap.measured.records import fit_records

    r = record(n)
    return _measured(lambda: fit_records([r]))


def run(ctx):
    from common import Row, fmt_time

    model = _model()
    time_rows(100, model)  # warm up: imports, caches
    (t1, m1), (t2, m2) = (time_rows(n, model) for n in ROWS)
    time_ratio = (t2 / ROWS[1]) / (t1 / ROWS[0])
    memory_ratio = (m2 / ROWS[1]) / (m1 / ROWS[0])
    rows = [
        Row(
            f"gap diagnosis, {ROWS[1]:,} vs {ROWS[0]:,} eigenvalue rows, one candidate: time per row",
            f"{fmt_time(t2 / ROWS[1])} a row ({fmt_time(t2)} for {ROWS[1]:,})",
            baselines=[(f"{ROWS[0]:,} rows, same run", f"{fmt_time(t1 / ROWS[0])} a row ({fmt_time(t1)})")],
            ratio=f"{time_ratio:.2f}",
            goal=f"<= {RATIO_GOAL}",
            met=time_ratio <= RATIO_GOAL,
        ),
        Row(
            f"gap diagnosis, {ROWS[1]:,} vs {ROWS[0]:,} eigenvalue rows: peak memory per row",
            f"{m2 / ROWS[1] / 1e3:.1f} kB a row ({m2 / 1e6:.0f} MB)",
            baselines=[(f"{ROWS[0]:,} rows, same run", f"{m1 / ROWS[0] / 1e3:.1f} kB a row ({m1 / 1e6:.0f} MB)")],
            ratio=f"{memory_ratio:.2f}",
            goal=f"<= {RATIO_GOAL}",
            met=memory_ratio <= RATIO_GOAL,
        ),
    ]
    (s1, b1), (s2, b2) = (time_samples(n) for n in SAMPLES)
    per_sample = b2 / SAMPLES[1]
    ratio = per_sample / (b1 / SAMPLES[0])
    rows.append(
        Row(
            f"record fit, {SAMPLES[1]:,} vs {SAMPLES[0]:,} samples: peak memory per sample",
            f"{per_sample:.0f} B a sample ({b2 / 1e6:.1f} MB, {fmt_time(s2)})",
            baselines=[(f"{SAMPLES[0]:,} samples, same run", f"{b1 / SAMPLES[0]:.0f} B a sample ({fmt_time(s1)})")],
            ratio=f"{ratio:.2f}",
            goal=f"<= {RATIO_GOAL} and <= {BYTES_PER_SAMPLE_GOAL} B a sample",
            met=ratio <= RATIO_GOAL and per_sample <= BYTES_PER_SAMPLE_GOAL,
        )
    )
    return rows


def main() -> int:
    sys.path.insert(0, str(ROOT / "bench"))
    for row in run(None):
        print(f"{row.item}: {row.bikerider}; {', '.join(f'{a}: {b}' for a, b in row.baselines)}; ratio {row.ratio}")
        print(f"  goal {row.goal}: {'met' if row.met else 'NOT met'}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT / "src"))
    sys.exit(main())
