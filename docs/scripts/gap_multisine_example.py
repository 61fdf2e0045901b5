"""Write the shipped multisine example: steer-torque multisine runs of the steer-by-wire bicycle with a
hidden steer damper, simulated with noise by the independent truth of ``validation/multisine.py``.

    .venv/bin/python docs/scripts/gap_multisine_example.py [OUT_DIR]

The truth: the SBW bicycle's nominal benchmark values (``pasma2024_sbw/sbw_bicycle.toml``) under its
steer-into-lean controller (``sil``), plus a viscous steer damper of ``C_STEER`` N m s/rad.  Each run:
9 Schroeder-phased lines from a quarter to four times the nominal model's weave frequency at the
run's speed (the lines ``gap --next`` plans, :func:`bikerider.gap.plan.sweeps.lines_for`), peak
``PEAK`` N m, ``RUN_TIME`` s of steady response at 100 Hz with gyro and encoder noise
(``validation.multisine.NOISE``), speed read by a wheel encoder with 0.02 m/s noise; three sessions
(groups) at ``SPEEDS``.  Seeded: the same files every time.  Writes ``experiment.toml`` and the logs
(``ms_<session>_<speed>.csv.gz``) into ``OUT_DIR`` (default: the package's
``data/gap/multisine_example``).
"""

from __future__ import annotations

import gzip
import sys
from pathlib import Path

import numpy as np

from bikerider.gap.candidates.effect_model import BENCH_ARGS, EffectModel
from bikerider.gap.plan.sweeps import lines_for
from bikerider.io.experiment import read_manifest
from bikerider.io.gap_model import load_model

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # validation/ (the gap's blind-check harnesses) lives beside src/, not installed
    sys.path.insert(0, str(ROOT))
from validation.multisine import multisine_log, write_log  # noqa: E402 (after the path above)

DATA = ROOT / "src" / "bikerider" / "data" / "gap"
C_STEER = 0.6
"""The hidden steer damping [N m s/rad]."""
PEAK = 0.5
RUN_TIME = 10.0
SPEEDS = (2.5, 4.0)
SESSIONS = ("a", "b", "c")
SEED = 25

MANIFEST = """# Steer-torque multisine runs of the steer-by-wire bicycle with a hidden steer damper ({c} N m s/rad),
# simulated with noise by validation/multisine.py (docs/scripts/gap_multisine_example.py writes this folder).
# Run:  bikerider gap --model ../pasma2024_sbw/sbw_bicycle.toml --experiment experiment.toml
[experiment]
name = "multisine_example"
time_column = "time"         # the logs' own time stamps [s]
control = "sil"

[columns]
roll_rate = "roll_rate"      # rad/s
steer_angle = "steer_angle"  # rad
steer_rate = "steer_rate"    # rad/s
speed = "speed"              # m/s, wheel encoder

[speed]
source = "column"

[control.sil]
k_phid = {{ K = 2.0, v0 = 6.5, when = "below" }}
k_phi = {{ K = 0.7, v0 = 6.5, when = "above" }}

[multisine]
torque = "steer_torque"      # N m, the steer motor's command
outputs = ["roll_rate", "steer_angle"]
{runs}"""


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    model = load_model(DATA / "pasma2024_sbw" / "sbw_bicycle.toml")
    values = {k: float(model.parameters.values[k]) for k in BENCH_ARGS + ("g",)}
    law = read_manifest(DATA / "pasma2024_sbw" / "experiment.toml")[0].laws["sil"]
    nominal = EffectModel(values, model.geometry)
    rng = np.random.default_rng(SEED)
    runs = []
    for session in SESSIONS:
        for speed in SPEEDS:
            gains = law(speed)
            ev = nominal.eigenvalues([speed], gains)[0]
            weave_hz = float(np.max(ev.imag)) / (2 * np.pi)
            lines = lines_for(weave_hz, RUN_TIME)
            columns = multisine_log(values, speed, gains, lines, PEAK, RUN_TIME, c_steer=C_STEER, rng=rng, jitter=0.0)
            name = f"ms_{session}_{speed:.2f}.csv.gz"
            plain = out / name.removesuffix(".gz")
            write_log(plain, columns)
            with open(out / name, "wb") as raw, gzip.GzipFile(fileobj=raw, mode="wb", mtime=0) as dst:
                dst.write(plain.read_bytes())  # mtime 0: the same bytes every time
            plain.unlink()
            runs.append(f'\n[[multisine.run]]\npath = "{name}"\ngroup = "session {session}"\n')
    (out / "experiment.toml").write_text(MANIFEST.format(c=C_STEER, runs="".join(runs)))


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else DATA / "multisine_example")
