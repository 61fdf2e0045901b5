"""Write the example inputs of ``bikerider gap`` into src/bikerider/data/gap_examples/.

The examples are synthetic: the Davis instrumented bicycle with its rider Jason (BicycleParameters
files in bikerider/data/bicycleparameters) simulated in the time domain by
:mod:`validation.cases` with a hidden steer damping (0.3 N m s/rad viscous, 0.05 N m
Coulomb), so a user can see the diagnosis find it.  Run from the project root::

    .venv/bin/python docs/scripts/gap_examples.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]

if str(ROOT) not in sys.path:  # validation/ (the gap's blind-check harnesses) lives beside src/, not installed
    sys.path.insert(0, str(ROOT))
OUT = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "src" / "bikerider" / "data" / "gap_examples"
BP = ROOT / "src" / "bikerider" / "data" / "bicycleparameters"
RIGID = BP / "bicycles" / "Rigid" / "Parameters" / "RigidBenchmark.txt"
JASON = BP / "riders" / "Jason" / "Parameters" / "JasonRigidBenchmark.txt"
SEED = 7


def main() -> int:
    from bikerider.io.gap_model import load_model
    from validation import cases as V

    OUT.mkdir(parents=True, exist_ok=True)
    model = load_model(RIGID, JASON)
    rng = np.random.default_rng(SEED)
    truth = V.TruthSimulator(model, V.TRUTHS["steer_damping"], rng)
    data, notes = V.measure(truth, V.FULL, rng)
    header = [
        "# Synthetic example (docs/scripts/gap_examples.py): weave eigenvalues of the Davis instrumented bicycle",
        "# with rider Jason, simulated in the time domain with a hidden steer friction (0.3 N m s/rad viscous,",
        "# 0.05 N m Coulomb) and fitted from the noisy roll rate of each run.  Session day3-controlled ran with a",
        "# known rider control (gains in the k_ columns, benchmark sign convention).",
    ]
    rows = ["speed,real,imag,real_sigma,imag_sigma,speed_sigma,group,k_phi,k_phid,k_delta,k_deltad"]
    for k in range(len(data)):
        g = data.gains[k]
        rows.append(
            f"{data.speed[k]:.3f},{data.value[k].real:.4f},{data.value[k].imag:.4f},"
            f"{data.real_sigma[k]:.2g},{data.imag_sigma[k]:.2g},{data.speed_sigma[k]:.2g},{data.group[k]},"
            f"{g[0]:g},{g[1]:g},{g[2]:g},{g[3]:g}"
        )
    (OUT / "eigenvalues.csv").write_text("\n".join(header + rows) + "\n", encoding="utf-8")

    # One perturbation run at 7 m/s, the raw time series a user would record: roll and steer rate.
    speed = 7.0
    t, states = truth.states(speed, (0.0, 0.0, 0.0, 0.0), {"phid": 0.3, "deltad": 0.4}, 6.0, 100.0)
    noisy = states["phid"] + V.FULL.gyro_noise * rng.standard_normal(t.size)
    noisy_steer = states["deltad"] + V.FULL.gyro_noise * rng.standard_normal(t.size)
    keep = t >= V.FULL.start
    lines = [
        "# Synthetic example (docs/scripts/gap_examples.py): roll and steer rate of one perturbation run of the",
        "# Davis bicycle with rider Jason and a hidden steer friction, after a roll-rate and steer-rate kick;",
        "# gyro noise 0.01 rad/s on both; the first 0.3 s after the kick left out.",
        f"# speed = {speed}",
        "# group = run7",
        "time,roll_rate,steer_rate",
    ]
    lines += [f"{tt:.2f},{yy:.5f},{ss:.5f}" for tt, yy, ss in zip(t[keep], noisy[keep], noisy_steer[keep])]
    (OUT / "perturbation_run.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")

    (OUT / "control.toml").write_text(
        "# Known control acting during the test: steer torque T_delta = k_phi phi + k_phid phid + k_delta delta\n"
        "# + k_deltad deltad [N m], benchmark sign convention (positive torque turns the handlebar to positive\n"
        "# steer).  Used for data rows that give no gains of their own.\n"
        "[control]\nk_phi = 0.0\nk_phid = 5.0\nk_delta = -2.0\nk_deltad = -0.5\n",
        encoding="utf-8",
    )

    canonical = (ROOT / "src" / "bikerider" / "data" / "gap" / "moore2012_canonical_id.csv").read_text().splitlines()
    keep_lines = [
        ln
        for ln in canonical
        if ln.startswith("#") or ln.startswith("rider,") or ln.startswith("J,P,") or ln.startswith("J,H,")
    ]
    keep_lines.insert(
        0, "# Excerpt of bikerider/data/gap/moore2012_canonical_id.csv: rider J(ason), treadmill and floor."
    )
    (OUT / "canonical.csv").write_text("\n".join(keep_lines) + "\n", encoding="utf-8")
    for note in notes:
        print(note, file=sys.stderr)
    print(
        f"wrote {len(data)} eigenvalues, one run of {int(keep.sum())} samples, control and canonical examples to {OUT}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
