"""Damaged copies of the shipped steer-by-wire logs, as a lab's logger might write them (for tests).

:func:`damaged_copy` writes, from the project's clean 100 Hz logs, a copy with a time column whose
stamps jitter by +/-5 % of a step, 5 % of the samples dropped, 1 % of the rows repeated, a gap of
missing roll-rate cells inside one window of each log, a constant bias on the roll rate and the
steer angle, optionally a clock reset and one log at half the rate; the windows are moved to the
rows that hold the same samples.  Seeded: the same damage every run.
"""

from __future__ import annotations

import csv
import gzip
import io
from pathlib import Path

import numpy as np

STEP = 0.01
"""The clean logs' sampling step [s]."""
ROLL_RATE_BIAS = 0.01
"""Constant bias added to the roll rate [rad/s]."""
STEER_BIAS = 0.005
"""Constant bias added to the steer angle [rad]."""


def damaged_copy(sbw: Path, out: Path, seed: int = 1, reset: bool = True, half_rate: bool = True) -> Path:
    """Write the damaged experiment into ``out``; returns its manifest."""
    rng = np.random.default_rng(seed)
    (out / "logs").mkdir(parents=True)
    windows: dict[str, list[tuple[int, int]]] = {}
    with open(sbw / "windows.csv") as f:
        for row in csv.DictReader(f):
            windows.setdefault(row["file"], []).append((int(row["start_sample"]), int(row["end_sample"])))
    new_windows = []
    for k, (name, spans) in enumerate(windows.items()):
        text = gzip.decompress((sbw / "logs" / (name + ".gz")).read_bytes()).decode()
        lines = text.splitlines()
        header, rows = lines[0].split(","), [line.split(",") for line in lines[1:]]
        col = {c: i for i, c in enumerate(header)}
        n = len(rows)
        stride = 2 if (half_rate and k == 3) else 1  # one log at 50 Hz
        index = np.arange(0, n, stride)
        keep = index[rng.random(index.size) >= 0.05]
        keep = np.unique(np.concatenate([[0], keep]))
        dup = rng.random(keep.size) < 0.01
        order = np.repeat(keep, np.where(dup, 2, 1))
        stamps = order * STEP + rng.uniform(-0.05, 0.05, order.size) * STEP * stride
        stamps[np.flatnonzero(np.diff(order) == 0) + 1] = stamps[np.flatnonzero(np.diff(order) == 0)]  # same stamp
        if reset and k == 1:  # the logger's clock restarts in the middle of the third window
            a, b = spans[2]
            at = int(np.searchsorted(order, (a + b) // 2))
            stamps[at:] -= stamps[at] - 0.0005
        gap_in = spans[len(spans) // 2]
        gap_at = int(np.searchsorted(order, gap_in[0] + (gap_in[1] - gap_in[0]) // 3))
        body = io.StringIO()
        body.write(",".join(["t"] + header) + "\n")
        for j, (orig, t) in enumerate(zip(order, stamps)):
            cells = list(rows[orig])
            for name_, bias in (("lean_rate", ROLL_RATE_BIAS), ("fork_angle", STEER_BIAS)):
                if cells[col[name_]].strip():
                    cells[col[name_]] = f"{float(cells[col[name_]]) + bias:.5f}"
            if gap_at <= j < gap_at + 3:
                cells[col["lean_rate"]] = ""
            body.write(",".join([f"{t:.5f}"] + cells) + "\n")
        (out / "logs" / (name + ".gz")).write_bytes(gzip.compress(body.getvalue().encode()))
        for a, b in spans:
            new_windows.append((name, int(np.searchsorted(order, a)), int(np.searchsorted(order, b))))
    with open(out / "windows.csv", "w") as f:
        f.write("file,start_sample,end_sample\n")
        for name, a, b in new_windows:
            f.write(f"{name},{a},{b}\n")
    manifest = (
        (sbw / "experiment.toml")
        .read_text()
        .replace("sample_rate = 100.0          # Hz: the logs have no time column", 'time_column = "t"')
    )
    assert 'time_column = "t"' in manifest
    (out / "experiment.toml").write_text(manifest)
    return out / "experiment.toml"
