"""Write the example inputs of ``bikerider period`` into src/bikerider/data/period_examples/.

Synthetic rate-gyro records of the paper's front wheel on the torsional pendulum (Moore et al.
2009, Table 6: 0.78 s): three trials of 8 s at 200 Hz, each with its own amplitude, a slightly
different period (a clamp reseated: 0.2 % scatter), light damping (zeta = 0.008), a gyro bias and
white noise of 0.02 rad/s.  The true periods are in each file's header, so a user can compare
what the fit finds with what was put in.  Run from the project root::

    .venv/bin/python docs/scripts/period_examples.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
OUT = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "src" / "bikerider" / "data" / "period_examples"
SEED = 11
PERIOD = 0.78
"""Front wheel, torsional pendulum [s] (Moore et al. 2009, Table 6)."""
ZETA = 0.008
RATE = 200.0
DURATION = 8.0
NOISE = 0.02


def main() -> int:
    rng = np.random.default_rng(SEED)
    OUT.mkdir(parents=True, exist_ok=True)
    t = np.arange(0.0, DURATION, 1.0 / RATE)
    for trial in (1, 2, 3):
        period = PERIOD * (1 + 0.002 * rng.standard_normal())
        omega_d = 2 * np.pi / period
        sigma = ZETA * omega_d / np.sqrt(1 - ZETA**2)
        amplitude = rng.uniform(1.5, 3.0)  # rad/s
        phase = rng.uniform(0, 2 * np.pi)
        bias = rng.normal(0.0, 0.01)
        rate = bias + amplitude * np.exp(-sigma * t) * np.sin(omega_d * t + phase) + NOISE * rng.standard_normal(t.size)
        lines = [
            f"# synthetic rate-gyro record: front wheel on the torsional pendulum, trial {trial}",
            f"# true period {period:.6f} s, damping ratio {ZETA}, {RATE:g} Hz, noise {NOISE} rad/s "
            "(docs/scripts/period_examples.py)",
            "time [s],rate [rad/s]",
        ]
        lines += [f"{a:.4f},{b:.5f}" for a, b in zip(t, rate)]
        (OUT / f"front_wheel_torsional_{trial}.csv").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
