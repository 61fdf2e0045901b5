"""Run the gap diagnosis on the published real data and write docs/gap_real_data.md.

Data (project copies in src/bikerider/data/gap/, sources in their headers):

* Kooijman, Schwab, Meijaard (2008): the riderless city bicycle and its one measured weave
  eigenvalue quoted in numbers (run 52);
* Moore (2012): identified canonical-matrix entries of the Davis instrumented bicycle with riders,
  with the bicycle (BicycleParameters Rigid) and the rider Jason (lumped).

Run from the project root::

    .venv/bin/python docs/scripts/gap_real_data.py
"""
from __future__ import annotations

import sys
from pathlib import Path


ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "src" / "bikerider" / "data"
BP = DATA / "bicycleparameters"
OUT = ROOT / "docs" / "gap_real_data.md"


def _diagnose(model, groups=None, eigen_file=None):
    from bikerider.gap import data as gd
    from bikerider.gap.diagnosis import diagnose

    eigen = gd.read_eigenvalues(eigen_file) if eigen_file else None
    canonical = gd.read_canonical(DATA / "gap" / "moore2012_canonical_id.csv", groups) if groups else None
    return diagnose(model, eigen, canonical)


def _ranking_table(result) -> list[str]:
    lines = ["| rank | effect | held-out before | after | shrink | plausible | fitted (95 % interval) | tied with |",
             "|---|---|---|---|---|---|---|---|"]
    for r in result["ranking"]:
        if r["effect"] == "parameters":
            fitted = f"{len(r['parameters'])} shifts"
        else:
            fitted = ", ".join(f"{k} = {_shown(v['value'], v['ci95'])} [{_shown(v['ci95'][0], v['ci95'])}, "
                               f"{_shown(v['ci95'][1], v['ci95'])}] {v['unit']}" for k, v in r["parameters"].items())
        shrink = "-" if r["shrink"] is None else f"{r['shrink']:+.2f}"
        lines.append(f"| {r['rank']} | {r['effect']} | {r['heldout_error_before']:.1f} | {r['heldout_error_after']:.1f} | "
                     f"{shrink} | {'yes' if r['plausible'] else 'no'} | {fitted} | {', '.join(r['tied_with']) or '-'} |")
    return lines


def _shown(x: float, ci95) -> str:
    """``x`` to 3 digits; 0 where it is a billionth of its interval's width or less (an optimiser's
    round-off at a bound, whose digits change with the last bit of any input)."""
    width = abs(ci95[1] - ci95[0]) or 1.0
    return "0" if abs(x) <= 1e-9 * width else f"{x:.3g}"


def build() -> str:
    """The text of docs/gap_real_data.md."""
    from bikerider.io.gap_model import load_model

    kooijman = load_model(DATA / "gap" / "kooijman2008_bicycle.toml")
    k = _diagnose(kooijman, eigen_file=DATA / "gap" / "kooijman2008_run52.csv").as_dict()
    cells = {c["quantity"]: c for c in k["gap"]["map"]}
    from bikerider.benchmark import WhippleModel

    kw = WhippleModel.from_parameters(kooijman.parameters).critical_speeds()

    rigid = BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt"
    jason = BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
    davis = load_model(rigid, jason)
    davis5 = load_model(rigid, jason, rider_rel_sigma=0.05)
    runs = {
        "J-H,J-P": _diagnose(davis, ["J-H", "J-P"]).as_dict(),
        "J-H,J-P (rider 5 %)": _diagnose(davis5, ["J-H", "J-P"]).as_dict(),
        "C-P,J-P,L-P": _diagnose(davis, ["C-P", "J-P", "L-P"]).as_dict(),
        "C-H,J-H,L-H": _diagnose(davis, ["C-H", "J-H", "L-H"]).as_dict(),
    }
    dw = WhippleModel.from_parameters(davis.parameters).critical_speeds()
    jj = runs["J-H,J-P"]

    lines = [
        "# The gap diagnosis on real data",
        "",
        "Produced by `docs/scripts/gap_real_data.py` (numbers regenerate with it). Reproduce any one with",
        "`bikerider gap` (commands below); `--report DIR` adds the figures.",
        "",
        "## 1. The riderless bicycle of Kooijman, Schwab and Meijaard (2008)",
        "",
        "```",
        "bikerider gap --model src/bikerider/data/gap/kooijman2008_bicycle.toml \\",
        "              --data src/bikerider/data/gap/kooijman2008_run52.csv",
        "```",
        "",
        "The city bicycle of their Table 1 (fork flipped, trail 0.19 m) converted to the benchmark parameters",
        "reproduces their canonical matrices (Eq. 5) to the five printed decimals and their weave and capsize",
        f"speeds ({kw.weave:.2f} and {kw.capsize:.2f} m/s; they report 4.0 and 7.9). The one measured eigenvalue",
        "quoted in numbers, run 52, is -1.16 +/- 5.44i 1/s while the speed fell from 5.4 to 4.8 m/s.",
        "",
        "| quantity | measured | model at 5.1 m/s | combined sigma | of which data (speed) | of which parameters | z |",
        "|---|---|---|---|---|---|---|",
    ]
    for q in ("real", "imag"):
        c = cells[q]
        lines.append(f"| weave {q} part [1/s] | {c['mean_measured']:.2f} | {c['mean_predicted']:.3f} | "
                     f"{c['combined_sigma']:.3f} | {c['data_sigma']:.3f} | {c['model_sigma']:.3f} | "
                     f"{(c['mean_measured'] - c['mean_predicted']) / c['combined_sigma']:+.2f} |")
    lines += [
        "",
        f"Gap test: chi2 = {k['gap']['test']['chi2']:.2f} on {k['gap']['test']['dof']} (p = {k['gap']['test']['p_value']:.2f}):",
        f"verdict **{k['verdict']}**. The model's damping of the weave matches to 0.03 1/s; its frequency is 5 % low,",
        "a difference the speed's fall during the fitted window (0.17 m/s standard uncertainty through the",
        "slope of the weave frequency, about 1.7 rad/s per m/s) covers. The paper states no uncertainty of the",
        "eigenvalue itself and the parameter uncertainties are assumed (see the model file), so this is a",
        "consistency check, not a test of power; with one point there are no folds and no ranking. This agrees",
        "with the authors' conclusion that the linearized Whipple model describes the measured weave of their",
        "uncontrolled bicycle well in the speed range they tested. Their other 75 runs are only plotted in the",
        "paper, so the diagnosis cannot use them.",
        "",
        "## 2. The Davis instrumented bicycle with riders (Moore 2012)",
        "",
        "```",
        "bikerider gap --model src/bikerider/data/bicycleparameters/bicycles/Rigid/Parameters/RigidBenchmark.txt \\",
        "              --rider src/bikerider/data/bicycleparameters/riders/Jason/Parameters/JasonRigidBenchmark.txt \\",
        "              --data src/bikerider/data/gap/moore2012_canonical_id.csv --groups J-H,J-P",
        "```",
        "",
        "The nominal model (BicycleParameters Rigid with the lumped rider Jason) reproduces the Whipple entries",
        "Moore back-computed for rider J within 0.3 % (`tests/test_gap_diagnosis.py`), so it is the model he",
        f"compared with (weave speed {dw.weave:.2f} m/s, capsize {dw.capsize:.2f} m/s). The data are his identified",
        "entries of the roll and steer equations for rider J on the treadmill (H) and the floor (P).",
        "",
        "### Where",
        "",
        "| entry | group | identified | nominal Whipple | difference | z |",
        "|---|---|---|---|---|---|",
    ]
    for c in jj["gap"]["map"]:
        entry, group = c["quantity"].split(" ")
        diff = c["mean_measured"] - c["mean_predicted"]
        rel = diff / abs(c["mean_predicted"])
        lines.append(f"| {entry} | {group.strip('()')} | {c['mean_measured']:.4g} | {c['mean_predicted']:.4g} | "
                     f"{rel:+.0%} | {diff / c['combined_sigma']:+.0f} |")
    t = jj["gap"]["test"]
    pt = jj["parameter_fit"]["test"]
    pt5 = runs["J-H,J-P (rider 5 %)"]["parameter_fit"]["test"]
    lines += [
        "",
        f"Every identified entry lies far outside its reported standard error (chi2 = {t['chi2']:.3g} on {t['dof']}).",
        "The largest departures, as Moore's own percentages show, are in the roll equation's steer-rate term",
        "`C1_phidelta` (a third to a half lower) and in `C1_deltaphi`, the steer equation's roll-rate term,",
        "which is about three times the Whipple value (the reference data's `trail_from_C1deltaphi.csv`: a trail",
        "of 0.17-1.3 m would be needed against the measured 0.06 m). The treadmill and the floor disagree",
        "with each other as much as with the model (`M_phidelta` 0.95 against 2.53, `K0_deltadelta` -0.36 against",
        "-0.66), so the reported standard errors, which come from equation-error least squares over many runs,",
        "understate the real scatter by far.",
        "",
        "### Whether",
        "",
        f"Parameters alone, fitted within their uncertainty: chi2 = {pt['chi2']:.3g} (prior {pt['prior_chi2']:.0f} on "
        f"{pt['prior_dof']} parameters); with a 5 % uncertainty on every rider value: chi2 = {pt5['chi2']:.3g}. Verdict",
        f"**{jj['verdict']}**: no plausible parameter error explains the identified matrices.",
        "",
        "### Which",
        "",
        "Folds are the two environments (fit on the treadmill, predict the floor, and the other way round):",
        "",
    ]
    lines += _ranking_table(jj)
    lines += [
        "",
        f"Selected: {', '.join(jj['selected']) or 'nothing'}. No candidate predicts the other environment better",
        "than the Whipple model: whatever one environment's fit does, the other environment moves the opposite way.",
        "Across the three riders within one environment (Jason's model for all three riders, whose back-computed",
        "Whipple entries differ from his by up to 11 %, small beside the gaps):",
        "",
        "Floor (C-P, J-P, L-P):",
        "",
    ]
    lines += _ranking_table(runs["C-P,J-P,L-P"])
    lines += ["", "Treadmill (C-H, J-H, L-H):", ""]
    lines += _ranking_table(runs["C-H,J-H,L-H"])
    floor = runs["C-P,J-P,L-P"]["ranking"]
    best = min(floor, key=lambda r: r["heldout_error_after"])
    cut = 1 - best["heldout_error_after"] / best["heldout_error_before"]
    lines += [
        "",
        f"On the floor the best candidate, {best['effect']}, takes {cut:.0%} off the held-out error, not",
        "significantly (a steer spring and damper between the frames, a few N m/rad and N m s/rad, the arm mass",
        "fitted at zero, do about the same); on the treadmill nothing helps. The tyre model with literature values moves",
        "`C1_deltaphi` towards positive values, the opposite of the measurements, and its fits run to rigid tyres.",
        "The leaning upper body fits only with almost no damping, far from Moore's values, and the riders' torsos",
        "were rigidified in these experiments.",
        "",
        "### How far, and what it means",
        "",
        "Nothing is selected, so the gap stays: the structural departure of the identified matrices is not one of",
        "the passive effects offered here. This agrees with Moore's variance-accounted-for tables (reference data,",
        "`median_VAF_*.csv`): in simulation the identified models reproduce the measured motions far better than",
        "the Whipple model (all data: roll angle 29 % against -21 %, steer angle 62 % against 10 %), his arm",
        "model helps only the steer-side outputs (steer angle 20 %, roll angle -33 %), and in the roll equation",
        "itself no model, identified ones included, accounts for much (Whipple -11 %, arm model -12 % over all",
        "data). The coupling from roll rate to steer torque in the data is several times stronger than any",
        "passive model here gives. What remains are effects no candidate here represents: inputs of the rider",
        "that the measured steer torque does not contain (upper-body and knee motions push on the frame even",
        "with the torso braced), and the bias of equation-error least squares that the reference data note,",
        "all the more with the riders closing the loop.",
        "Telling them apart needs the runs' time series (or eigenvalues), which are not available here.",
        "",
    ]
    return "\n".join(lines)


def main() -> int:
    OUT.write_text(build(), encoding="utf-8")
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
