"""What to measure next on the steer-by-wire bicycle (Pasma 2024): ``bikerider gap --next`` on the
diagnosis of docs/gap_real_data.md (section 3); writes docs/gap_sbw_next.md and docs/gap_sbw_next.png.

The plan takes about 12 s of processor time beyond the diagnosis; ``make docs`` runs this script.  Run from the
project root::

    .venv/bin/python docs/scripts/gap_sbw_next.py
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SBW = ROOT / "src" / "bikerider" / "data" / "gap" / "pasma2024_sbw"
OUT = ROOT / "docs" / "gap_sbw_next.md"
FIGURE = ROOT / "docs" / "gap_sbw_next.png"


def _sbw_next(diagnosis):
    """What to measure next on the steer-by-wire bicycle (``bikerider gap --next``)."""
    from bikerider.gap.plan.ranking import plan_next
    from bikerider.gap.plan.sweeps import MAX_ROLL

    plan = plan_next(diagnosis)
    out = plan.as_dict(top=len(plan.plan))
    rivals = [" + ".join(r["effects"]) for r in out["rivals"]]
    decays = [item for item in out["plan"] if item["kind"] == "decay"]
    sweeps = [item for item in out["plan"] if item["kind"] == "sweep"]
    best = decays[0]
    by_signal = out["best_per_signal"] or {}
    considered = len(plan.points) + len(plan.sweeps) + len(out["left_out"])
    lean = sum("would likely be lost" in x["reason"] for x in out["left_out"])
    lines = [
        "# What to measure next on the steer-by-wire bicycle",
        "",
        "Produced by `docs/scripts/gap_sbw_next.py` (`make docs`), from the diagnosis of",
        "`docs/gap_real_data.md` (section 3); the method is in `docs/gap.md` (What to measure next).",
        "",
        "```",
        "bikerider gap --model .../sbw_bicycle.toml --experiment .../experiment.toml --next --report sbw_report",
        "```",
        "",
        f"No candidate ties with the friction; `--next` plans how to tell it from the runners-up ({', '.join(rivals[1:])})",
        f"({considered} experiments considered over {plan.speeds.min():.1f}-{plan.speeds.max():.1f} m/s: the `sil` law,",
        "the same controller at half and 1.5 times its gain, and no control; free decays with four signals and three",
        "push sizes, and steer-torque multisines read at the roll rate or the steer angle;",
        f"{len(out['left_out'])} left out, where a mode grows, a decay holds no weave the record fit accepts, or a"
        f" multisine would lean past {MAX_ROLL:g} rad: {lean} of them).",
        "The best multisines, the best decays, and the best decay of each logged signal and with the data's push:",
        "",
        "| experiment | resolution probability, 10 runs | runs for 95 % | d (friction true / other true) |",
        "|---|---|---|---|",
    ]
    shown = sweeps[:2] + decays[:2]
    for extra in [by_signal.get("roll_rate"), by_signal.get("steer_angle")] + [
        next((x for x in decays if x["push"] == 1.0), None)
    ]:
        if extra is not None and all(extra["text"] != x["text"] for x in shown):
            shown.append(extra)
    for item in shown:
        d = "; ".join(f"{p['rivals'][1]} {p['separation'][0]:.1f} / {p['separation'][1]:.1f}" for p in item["pairs"])
        need = "-" if item["decays_for_95"] is None else str(item["decays_for_95"])
        lines.append(f"| {item['text']} | {item['resolution_probability']:.2f} | {need} | {d} |")
    noise = out["noise"]["signals"]
    lines += [
        "",
        f"The plan asks for **small pushes** (x{best['push']:g} the data's) at about {best['speed']:.1f} m/s under "
        + (
            "the experiment's own controller"
            if best["law"] == "sil"
            else f"`{best['law']}` (the experiment's controller, `sil`, at another gain)"
            if best["law"].startswith("sil")
            else f"`{best['law']}`"
        )
        + ": Coulomb friction makes the decay depend on its size, so small pushes show it where",
        "viscous damping and parameter errors, which scale with the push, cannot follow.",
        "",
    ]
    if sweeps:
        top = sweeps[0]
        rho = out["sweeps"]["distortion"]["value"]
        friction = next(r for r in diagnosis.as_dict()["ranking"] if r["effect"] == "steer_friction")
        coulomb = friction["parameters"]["T_coulomb"]["value"]
        lines += [
            f"Steer-torque multisines do it more surely ({top['text']}: {top['resolution_probability']:.2f}, "
            f"{top['decays_for_95']} run{'' if top['decays_for_95'] == 1 else 's'} for 95 %). At a peak of {out['sweeps']['torque']:g} N m, the fitted Coulomb "
            f"friction ({coulomb:.2f} N m) takes a large share of the drive: the steer's runs, simulated in time with the",
            "fitted friction (and again with the steer sticking, whose difference the plan counts as the friction's own",
            "uncertainty), respond as no viscous rival does, and the responses part by more than a run's noise: the",
            "sensor's, the speed's scatter, the data's run-to-run variation of the weave carried to the response, and",
            f"the share a linear model misses of a real run ({rho:.2f} per line, sqrt(1 - r^2) of the records' fits).",
            "`validation/multisine_check.py` simulates these runs by its own stick-slip integrator: they achieve the",
            "planned separation (docs/gap.md). The diagnosis reads the runs back (the manifest's `[multisine]` table:",
            "the logged torque and response, `bikerider.io.multisine`), and the closed loop of docs/gap_validation.md,",
            "part 5, runs them against hidden truths; the torque must be what the motor delivers (its bandwidth is not",
            "modelled), and a run is planned only where no rival leans past 0.2 rad (a friction rival's lean from its",
            "run simulated in time).",
            "",
        ]
    nxt = out["next_run"]
    if nxt:
        lines += [
            f"**The next run, one at a time**: {nxt['text']} (ranked {nxt['rank']} of {len(out['plan'])} by the resolution",
            f"probability; one run of it resolves with probability {nxt['resolution_probability']:.2f}). It is where the",
            f"Jensen-Renyi divergence of the three candidates' predictions of one run is largest ({nxt['divergence']:.2f} of",
            f"at most ln 3 = {nxt['bound']:.2f} nats), the criterion that needed the fewest runs in the closed loop",
            "(docs/gap_validation.md, part 5). Record it, add it to the experiment's manifest, run `--next` again.",
            "",
        ]
    lines += [
        "Each signal's noise comes from the logs: the larger of its sample-to-sample scatter and the residual its",
        f"records' own fits leave (roll rate {noise['roll_rate']['value']:.2g} rad/s, roll angle "
        f"{noise['roll_angle']['value']:.2g} rad, steer angle {noise['steer_angle']['value']:.2g} rad; the steer rate",
        "is not logged and its noise is assumed), and each signal's run-to-run scatter from its own fits of the",
        "records per speed of the data (linear between those speeds). The roll angle is the IMU's fused estimate: it scatters from sample to",
        "sample about thirty times less than its fits' residual, and its errors are not independent from sample",
        "to sample as a fit's standard errors assume, so where it ranks first the roll-rate and steer-angle",
        "rows are the safer choice.",
        "",
        "![The rivals' predictions diverging over speed](gap_sbw_next.png)",
        "",
        "The figure (`next.png` of the command's report) draws the three candidates' predictions for the best",
        "decay over speed, with bands of one standard deviation of ten decays' mean, the data as taken (each",
        "record's weave eigenvalue with its standard error), the planned speeds, and the resolution probability",
        "against speed per law (solid: the signal and push of the law's best decay, named in the legend; dotted:",
        "the best of any signal and push at each speed, jagged where that best switches); its second row, the best",
        "multisine's frequency response per candidate (magnitude and phase, bands of ten runs' mean) and the",
        "multisines' separation d of one run against speed (log scale, with the d one run needs for 95 %); the",
        "star marks the next run.",
        "",
    ]
    return lines, plan, out


def main() -> int:
    from bikerider.diagnose import diagnose_files
    from bikerider.plotting.common import pyplot
    from bikerider.plotting.gap_plan import plot_next

    diagnosis = diagnose_files(str(SBW / "sbw_bicycle.toml"), experiment=(str(SBW / "experiment.toml"),))
    lines, plan, out = _sbw_next(diagnosis)
    OUT.write_text("\n".join(lines), encoding="utf-8")
    fig = plot_next(plan, out)
    fig.savefig(FIGURE, dpi=80)
    pyplot().close(fig)
    print(f"wrote {OUT} and {FIGURE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
