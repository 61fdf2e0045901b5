"""Close the loop once on the steer-by-wire data: plan, record the planned multisines, diagnose again.

    .venv/bin/python docs/scripts/gap_multisine_loop.py OUT_DIR [BEFORE_JSON]

1. **Plan.** ``bikerider gap --next --json`` on the shipped SBW experiment (55 real decays), or the
   output of that command given as ``BEFORE_JSON``.
2. **Record.** The plan's first-ranked steer-torque multisine (speed, control law, peak torque, run
   time, lines) is run ``max(runs for 95 %, RUNS)`` times on a simulated bicycle, the independent truth
   of ``validation/multisine.py``: the SBW bicycle's nominal benchmark values with the steer friction the
   diagnosis of the real decays selected (Coulomb ``T_COULOMB`` N m, viscous ``C_VISCOUS`` N m s/rad;
   a stand-in for the real bicycle, which we cannot ride here), gyro and encoder noise.  The logs are
   written as the SBW logger writes them (100 Hz, no time column, the SBW column names plus
   ``steer_torque``).
3. **Add and rerun.** ``OUT_DIR/experiment.toml`` is the SBW manifest (its logs and windows, by
   relative path) plus a ``[multisine]`` table naming the new runs and the plan's law; the script
   runs ``bikerider gap --next --json`` on it and prints what changed: the records used, the selection
   and the friction's values, the rivals and the plan's first experiments, before and after.

Both diagnoses take a few minutes on two shared cores.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from bikerider.gap.candidates.effect_model import BENCH_ARGS
from bikerider.io.gap_model import load_model

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # validation/ (the gap's blind-check harnesses) lives beside src/, not installed
    sys.path.insert(0, str(ROOT))
from validation.multisine import multisine_log, write_log  # noqa: E402 (after the path above)

SBW = ROOT / "src" / "bikerider" / "data" / "gap" / "pasma2024_sbw"
T_COULOMB = 0.19
C_VISCOUS = 0.05
"""The truth's steer friction: what the diagnosis of the real SBW decays selects (docs/gap_real_data.md)."""
RUNS = 2
"""Fewest runs recorded (two groups of multisines for the held-out folds)."""
SEED = 2025
SBW_COLUMNS = {"roll_rate": "lean_rate", "roll_angle": "lean_angle", "steer_angle": "fork_angle", "speed": "speed"}
BASE_GAINS = {"k_phid": (2.0, "below"), "k_phi": (0.7, "above")}
"""The SBW controller (``sil``, experiment.toml): ``K (v0 - v)`` below, ``K (v - v0)`` above ``v0 = 6.5 m/s``."""


def gap_next(manifest: Path) -> dict:
    """``bikerider gap --next --json`` on a manifest."""
    command = [
        str(Path(sys.executable).with_name("bikerider")),
        "gap",
        "--model",
        str(SBW / "sbw_bicycle.toml"),
        "--experiment",
        str(manifest),
        "--next",
        "--json",
        "--quiet",
    ]
    print("$", " ".join(command), flush=True)
    return json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)


def law_gains(name: str, speed: float) -> tuple[np.ndarray, str]:
    """Gains ``[k_phi, k_phid, k_delta, k_deltad]`` of the plan's law ``sil``, ``sil xF`` or ``no control``,
    and its manifest table."""
    if name == "no control":
        return np.zeros(4), ""
    factor = float(name.split(" x")[1]) if " x" in name else 1.0
    k_phid = factor * BASE_GAINS["k_phid"][0] * max(6.5 - speed, 0.0)
    k_phi = factor * BASE_GAINS["k_phi"][0] * max(speed - 6.5, 0.0)
    table = (
        f'[control."{name}"]\n'
        f'k_phid = {{ K = {factor * 2.0:g}, v0 = 6.5, when = "below" }}\n'
        f'k_phi = {{ K = {factor * 0.7:g}, v0 = 6.5, when = "above" }}\n'
    )
    return np.array([k_phi, k_phid, 0.0, 0.0]), table


def summary(result: dict) -> dict:
    records = result["records"]
    kinds = [e.get("kind", "decay") for e in records["list"] if e["used"]]
    fit = next((r for r in result["ranking"] if r["effect"] == (result["selected"] or [""])[0]), None)
    nxt = result.get("next") or {}
    return {
        "records used": f"{kinds.count('decay')} decays, {kinds.count('multisine')} multisines "
        f"({records['left_out']} left out)",
        "selected": result["selected"],
        "fitted": {k: (round(v["value"], 3), [round(x, 3) for x in v["ci95"]]) for k, v in fit["parameters"].items()}
        if fit
        else None,
        "ranking": [(r["effect"], round(r["heldout_error_after"], 2)) for r in result["ranking"]],
        "rivals": [" + ".join(r["effects"]) for r in nxt.get("rivals", [])],
        "plan": [(p["text"], round(p["resolution_probability"], 3)) for p in nxt.get("plan", [])[:3]],
    }


def main(out: Path, before_json: Path | None) -> None:
    out.mkdir(parents=True, exist_ok=True)
    before = json.loads(before_json.read_text()) if before_json else gap_next(SBW / "experiment.toml")
    best = next(p for p in before["next"]["plan"] if p["kind"] == "sweep")
    runs = max(int(best["decays_for_95"] or RUNS), RUNS)
    print(f"planned: {best['text']} (P = {best['resolution_probability']:.2f}); recording {runs}", flush=True)
    model = load_model(SBW / "sbw_bicycle.toml")
    values = {k: float(model.parameters.values[k]) for k in BENCH_ARGS + ("g",)}
    gains, law_table = law_gains(best["law"], best["speed"])
    rng = np.random.default_rng(SEED)
    entries = []
    for k in range(runs):
        columns = multisine_log(
            values,
            best["speed"],
            gains,
            best["lines"],
            best["torque"],
            best["run_time"],
            c_steer=C_VISCOUS,
            coulomb=T_COULOMB,
            rng=rng,
            with_roll_angle=True,
        )
        log = {SBW_COLUMNS[k]: v for k, v in columns.items() if k in SBW_COLUMNS}
        log["steer_torque"] = columns["steer_torque"]
        name = f"multisine_{k + 1}.csv"
        write_log(out / name, log)
        entries.append(f'\n[[multisine.run]]\npath = "{name}"\ncontrol = "{best["law"]}"\n')
    manifest = (SBW / "experiment.toml").read_text()
    rel = os.path.relpath(SBW, out)
    manifest = manifest.replace('logs = "logs"', f'logs = "{rel}/logs"').replace(
        'windows = "windows.csv"', f'windows = "{rel}/windows.csv"'
    )
    if law_table and f'[control."{best["law"]}"]' not in manifest and best["law"] != "sil":
        manifest += "\n" + law_table
    manifest += (
        "\n# The plan's first-ranked multisine, recorded (simulated by docs/scripts/gap_multisine_loop.py)\n"
        '[multisine]\ntorque = "steer_torque"\nlogs = "."\n' + "".join(entries)
    )
    (out / "experiment.toml").write_text(manifest)
    after = gap_next(out / "experiment.toml")
    (out / "before.json").write_text(json.dumps(summary(before), indent=1))
    (out / "after.json").write_text(json.dumps(summary(after), indent=1))
    for label, result in (("before", before), ("after", after)):
        print(f"--- {label}")
        for key, value in summary(result).items():
            print(f"{key}: {value}")


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]) if len(sys.argv) > 2 else None)
