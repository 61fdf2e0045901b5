"""Part 4 of docs/gap_validation.md from the calibration trials (see gap_calibration.py beside it)."""

from __future__ import annotations

import json
import math
import sys
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # validation/ (the gap's blind-check harnesses) lives beside src/, not installed
    sys.path.insert(0, str(ROOT))

BEGIN, END = "<!-- calibration:begin -->", "<!-- calibration:end -->"
BEFORE = Path(__file__).with_name("gap_calibration_before.jsonl")
"""The first rounds of the study run before the interval fix (same seeds)."""


def load(path: Path) -> list[dict]:
    """The stored trials, one JSON object a line."""
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]


def _pct(k: int, n: int) -> str:
    return f"{k}/{n} ({100 * k / n:.0f} %)" if n else "-"


def _identified(t: dict) -> bool:
    return t["verdict"] == "structural" and t["first"] == t["candidate"]


def _selected(t: dict) -> bool:
    return t["candidate"] in t["selected"]


def coverage_rows(trials: list[dict]) -> list[tuple]:
    """Per effect and fitted size: trials, coverage of the 95 % interval, relative bias, relative RMS error."""
    rows = []
    by = defaultdict(list)
    for t in trials:
        for name, ref in t["reference"].items():
            f = t["fitted"].get(name)
            if f is None or ref is None or not math.isfinite(ref):
                continue
            by[(t["effect"], name)].append((ref, f["value"], f["ci95"][0], f["ci95"][1], _selected(t)))
    for (effect, name), xs in by.items():
        ref = np.array([x[0] for x in xs])
        val = np.array([x[1] for x in xs])
        inside = np.array([x[2] <= x[0] <= x[3] for x in xs])
        sel = np.array([x[4] for x in xs])
        scale = np.where(np.abs(ref) > 0, np.abs(ref), np.nan)
        rel = (val - ref) / scale
        finite = np.isfinite(rel)
        rows.append(
            (
                effect,
                name,
                len(xs),
                int(inside.sum()),
                float(np.median(rel[finite])) if finite.any() else math.nan,
                float(np.sqrt(np.mean(rel[finite] ** 2))) if finite.any() else math.nan,
                int(sel.sum()),
                int((inside & sel).sum()),
                float(np.median(np.abs(val - ref))),
            )
        )
    return rows


def _arm_inertia_factors() -> tuple[float, float]:
    """Squared distance of the grips from the steer axis [m^2]: the diagnosis's default grips, the truth's.

    The arms' mass the diagnosis fits sits at its default grips; the truth's at grips 8 cm higher and 2 cm
    wider (``validation.cases.TRUTH_GEOMETRY``): what the records carry is the arms' inertia about
    the steer axis, ``m d^2``, which is scored beside the mass.
    """
    from bikerider.io.gap_model import load_model
    from validation import cases as V

    root = Path(__file__).resolve().parents[2] / "src" / "bikerider" / "data" / "bicycleparameters"
    model = load_model(
        root / "bicycles/Rigid/Parameters/RigidBenchmark.txt", root / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
    )
    v = model.parameters.values
    lam, w, c = float(v["lam"]), float(v["w"]), float(v["c"])
    axis = np.array([math.sin(lam), 0.0, math.cos(lam)])

    def d2(g: dict) -> float:
        rel = np.array([g["x_grip"] - (w + c), g["b_grip"], g["z_grip"]])
        perp = rel - (rel @ axis) * axis
        return float(perp @ perp)

    return d2(model.geometry.grips), d2(V._truth_geometry(model)["grips"])


def _with_arm_inertia(trials: list[dict]) -> list[dict]:
    """Passive-arms trials with the arms' inertia about the steer axis scored beside their mass."""
    if not any(t["effect"] == "passive_arms" for t in trials):
        return trials
    fitted_d2, truth_d2 = _arm_inertia_factors()
    out = []
    for t in trials:
        if t["effect"] == "passive_arms" and "m_arm" in t["fitted"]:
            t = json.loads(json.dumps(t))
            f = t["fitted"]["m_arm"]
            t["fitted"]["I_arm_steer"] = {"value": f["value"] * fitted_d2, "ci95": [x * fitted_d2 for x in f["ci95"]]}
            t["reference"]["I_arm_steer"] = t["truth"]["m_arm"] * truth_d2
        out.append(t)
    return out


def write_report(results: Path, doc: Path, goal: int) -> None:
    """Write part 4 into ``doc`` between the calibration markers (the rest is left as it is)."""
    trials = _with_arm_inertia(load(results))
    lines = section(trials, goal)
    text = doc.read_text(encoding="utf-8") if doc.exists() else ""
    block = "\n".join([BEGIN, *lines, END])
    if BEGIN in text and END in text:
        head, rest = text.split(BEGIN, 1)
        tail = rest.split(END, 1)[1]
        text = head + block + tail
    else:
        text = text.rstrip("\n") + "\n\n" + block + "\n"
    doc.write_text(text, encoding="utf-8")
    print(f"wrote {doc}: {len(trials)} trials")


def section(trials: list[dict], goal: int) -> list[str]:
    from bikerider.gap.candidates.effects import EFFECTS
    from validation import cases as V

    table = [t for t in trials if t["effect"] != V.CALIBRATION_FRICTION.name]
    friction = [t for t in trials if t["effect"] == V.CALIBRATION_FRICTION.name]
    effects = [e.name for e in V.CALIBRATION_EFFECTS]
    counts = Counter(t["effect"] for t in table)
    n_min = min((counts[e] for e in effects), default=0)
    seconds = sum(t["seconds"] for t in trials)
    priors = {p.name: (p.the_prior(), p.unit) for e in EFFECTS.values() for p in e.parameters}
    lines = [
        "## 4. Calibration: identification, sizes and intervals over the priors",
        "",
        "Produced by `docs/scripts/gap_calibration.py` (do not edit by hand; the trials are stored in",
        "`docs/scripts/gap_calibration_trials.jsonl` and `--report-only` rewrites this part from them).",
        "",
        "### Set-up",
        "",
        "Each trial hides one effect whose sizes are **drawn over the candidate's prior** (the priors of",
        "`docs/gap.md`, section Priors; a lognormal or normal prior within its central 95 %, a half-Cauchy",
        "within its 80 %), on a bicycle whose benchmark parameters are **drawn from their stated",
        "uncertainties** (the Davis bicycle `RigidBenchmark.txt`; with the lumped rider",
        "`JasonRigidBenchmark.txt` on odd seeds, and for the rider's own effects always), and simulates **short",
        "noisy runs** with the independent truth of part 1 (`TruthSimulator`: Meijaard's Appendix A typed in",
        "by hand, the effects added by hand, LSODA): three sessions of three 3-s runs, one session under the",
        "known control `T = 5 phid - 2 delta - 0.5 deltad`, 0.01 rad/s gyro noise, the weave fitted from the",
        "noisy roll rate; with the rider 4.5-9 m/s, riderless 2.5-6.5 m/s. The diagnosis runs blind on the",
        "nine (fewer where a run cannot be fitted) weave eigenvalues with every candidate, and the selection's",
        "predicted shrinkage is checked on fresh runs of the same truth.",
        "",
        "* **steer_coulomb** is pure Coulomb steer friction, simulated **nonlinearly in time**",
        "  (`T tanh(deltad / 0.02)` in the truth's equations, which share no code with the candidates). A",
        "  table of eigenvalues carries no amplitude, so the candidate that can stand for it is",
        "  `steer_damping`, and its size is scored against the describing-function equivalent",
        "  `c_eq = 4 T / (pi A)` at the runs' median steer-rate amplitude `A` (`sqrt(2)` times the RMS",
        "  steer rate over the fitted window), not against a split the data do not carry.",
        f"* **{V.CALIBRATION_FRICTION.name}**: pure Coulomb friction again, diagnosed from raw records",
        "  (riderless, the SBW control `sil`, three speeds of three records of 1.2-2.5 s, 0.015 rad/s gyro noise,",
        "  a 13-bit steer encoder) with `steer_friction` fitted in the time domain; scored on its split",
        "  (`T_coulomb`, `c_viscous` = 0) and on the equivalent `c_eq` it reports",
        "  (`Priors.friction_equivalent` of `bikerider.gap.diagnosis.priors`). These trials cost several times a table trial: one runs every",
        "  few rounds.",
        "",
        "| effect | sizes drawn from | rider |",
        "|---|---|---|",
    ]
    for e in V.CALIBRATION_EFFECTS:
        sizes = []
        for name in e.sizes:
            if e.name == "steer_coulomb":
                prior = next(p for p in EFFECTS["steer_friction"].parameters if p.name == name).the_prior()
                unit = "N m"
            else:
                prior, unit = priors[name]
            sizes.append(f"{name}: {prior.describe(unit)}")
        fixed = ", ".join(f"{k} = {v:g}" for k, v in e.fixed.items())
        rider = {"both": "alternating", "rider": "with rider", "riderless": "riderless"}[e.rider]
        lines.append(f"| {e.name} | {'; '.join(sizes)}{'; fixed ' + fixed if fixed else ''} | {rider} |")
    lines += [
        "",
        "### How many trials",
        "",
        f"{len(trials)} trials in {seconds / 60:.0f} min of computing: "
        + ", ".join(f"{e} {counts[e]}" for e in effects)
        + f", {V.CALIBRATION_FRICTION.name} {len(friction)}.",
    ]
    if n_min < goal:
        lines += [
            "",
            f"**Fewer than the {goal} trials per effect the study calls for**: the study ran once, limited to",
            "about 25 minutes on a shared 2-core machine (a table trial takes 2-6 s, a record trial 6-15 s). The",
            "rates below carry the binomial uncertainty of these counts (about +/-"
            f" {100 * 1.96 * math.sqrt(0.25 / max(n_min, 1)):.0f} points at 95 % for a rate near one half, less near"
            " 0 or 1); run `gap_calibration.py --trials 200 --max-minutes 0` (no limit) for the full study.",
        ]
    # identification
    lines += [
        "",
        "### Identification",
        "",
        "Ranked first: a structural verdict with the candidate first of the ranking (ties to the simpler).",
        "Selected: the candidate in the selection (alone or in a pair).",
        "",
        "| effect | trials | ranked first | selected | tied with another when first | nothing selected |",
        "|---|---|---|---|---|---|",
    ]
    for e in effects:
        ts = [t for t in table if t["effect"] == e]
        n = len(ts)
        first = sum(_identified(t) for t in ts)
        sel = sum(_selected(t) for t in ts)
        tied = sum(_identified(t) and bool(t["tied_with_first"]) for t in ts)
        none = sum(not t["selected"] for t in ts)
        lines.append(f"| {e} | {n} | {_pct(first, n)} | {_pct(sel, n)} | {_pct(tied, first)} | {_pct(none, n)} |")
    if friction:
        n = len(friction)
        first = sum(_identified(t) for t in friction)
        sel = sum(_selected(t) for t in friction)
        none = sum(not t["selected"] for t in friction)
        lines.append(
            f"| {V.CALIBRATION_FRICTION.name} | {n} | {_pct(first, n)} | {_pct(sel, n)} | - | {_pct(none, n)} |"
        )
    # confusion
    labels = list(dict.fromkeys(["none", "parameters"] + sorted({_label(t) for t in trials} - {"none", "parameters"})))
    lines += [
        "",
        "#### Confusion matrix",
        "",
        "Rows: hidden effect; columns: the first-ranked candidate when the verdict is structural, else the verdict.",
        "",
        "| effect | " + " | ".join(labels) + " |",
        "|---|" + "---|" * len(labels),
    ]
    for e in effects + ([V.CALIBRATION_FRICTION.name] if friction else []):
        c = Counter(_label(t) for t in trials if t["effect"] == e)
        lines.append(f"| {e} | " + " | ".join(str(c[k]) if c[k] else "." for k in labels) + " |")
    # identification against size
    lines += [
        "",
        "#### Identification against the size drawn",
        "",
        "Ranked first, by third of the drawn size (first size of the effect; for steer_coulomb its equivalent",
        "`c_eq`): small effects hide in the noise and the parameters' uncertainty.",
        "",
        "| effect | size | small third | middle third | large third |",
        "|---|---|---|---|---|",
    ]
    for e in effects:
        ts = [t for t in table if t["effect"] == e]
        if len(ts) < 6:
            continue
        key = next(iter(ts[0]["reference"]))
        ts = sorted(ts, key=lambda t: t["reference"].get(key, math.nan))
        parts = np.array_split(np.arange(len(ts)), 3)
        cells = []
        for idx in parts:
            sub = [ts[i] for i in idx]
            lo, hi = sub[0]["reference"][key], sub[-1]["reference"][key]
            cells.append(f"{_pct(sum(_identified(t) for t in sub), len(sub))} at {lo:.3g}-{hi:.3g}")
        lines.append(f"| {e} | {key} | " + " | ".join(cells) + " |")
    # coverage
    rows = coverage_rows(trials)
    lines += [
        "",
        "### Sizes and their 95 % intervals",
        "",
        "How the intervals are made: a linear candidate's covariance is the sandwich of its fit's Jacobian",
        "with the covariance of the observations, the data's variance plus the benchmark parameters' (one",
        "parameter error moves every row at once), times the reduced chi-square when above one",
        "(`bikerider.gap.diagnosis.fits.with_parameter_uncertainty`); steer friction's comes from the jackknife over the",
        "held-out folds' fits, with Student's t for one degree of freedom fewer than the folds.",
        "",
        "The candidate's own fit to all the data (whatever was selected), against the truth: coverage of its",
        "95 % interval (goal 90-97 %), median relative error (bias) and RMS relative error; and the same",
        "coverage over the trials that selected it.",
        "",
        "| effect | size | trials | coverage | median error | RMS error | median abs error | selected | coverage when selected |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for effect, name, n, inside, bias, rmse, nsel, insel, mae in rows:
        lines.append(
            f"| {effect} | {name} | {n} | {_pct(inside, n)} | {bias:+.1%} | {rmse:.1%} | {mae:.3g} | {nsel} | "
            f"{_pct(insel, nsel)} |"
        )
    before = _with_arm_inertia(load(BEFORE))
    if before:
        now = {(t["effect"], t["seed"]): t for t in trials}
        pairs_before = [t for t in before if (t["effect"], t["seed"]) in now]
        old_rows = {(r[0], r[1]): r for r in coverage_rows(pairs_before)}
        new_rows = {(r[0], r[1]): r for r in coverage_rows([now[(t["effect"], t["seed"])] for t in pairs_before])}
        k_old = sum(r[3] for r in old_rows.values())
        n_old = sum(r[2] for r in old_rows.values())
        k_new = sum(new_rows[key][3] for key in old_rows if key in new_rows)
        n_new = sum(new_rows[key][2] for key in old_rows if key in new_rows)
        lines += [
            "",
            f"**Before the interval fix**, on the same {len(pairs_before)} trials (same seeds, so the same sizes,",
            "bicycles and noise; `docs/scripts/gap_calibration_before.jsonl`): the linear fits' intervals came",
            "from the fit's Jacobian alone, which treats the parameters' uncertainty as independent from row to",
            "row, and the time-domain jackknife used 1.96: coverage "
            f"{_pct(k_old, n_old)} over every size, against {_pct(k_new, n_new)} now. Per size, before -> now: "
            + "; ".join(
                f"{e} {n} {_pct(r[3], r[2])} -> {_pct(new_rows[(e, n)][3], new_rows[(e, n)][2])}"
                for (e, n), r in old_rows.items()
                if (e, n) in new_rows
            )
            + ".",
        ]
    if friction:
        sep = [t for t in friction if "c_equivalent" in t["fitted"]]
        k = sum(bool(t["fitted"]["c_equivalent"].get("separable")) for t in sep)
        lines += [
            "",
            f"Of the {len(sep)} record trials with a steer signal, {k} had records whose steer-rate amplitudes span a",
            "factor 2 or more (10th-90th percentile), where the diagnosis reports the split; the others are",
            "reported as the equivalent viscous damping only (see `docs/gap.md`, Priors).",
        ]
    # shrinkage
    pairs = [
        (t["effect"], t["predicted_shrink"], t["achieved_shrink"])
        for t in table
        if t["predicted_shrink"] is not None and t["achieved_shrink"] is not None
    ]
    lines += ["", "### Predicted against achieved shrinkage", ""]
    if pairs:
        err = np.array([p - a for _, p, a in pairs])
        lines += [
            "The fraction of the gap above the noise floor the selection removes, predicted on held-out groups",
            "and achieved on fresh runs of the same truth (predicted minus achieved):",
            "",
            f"* all {err.size} trials with a selection: mean {err.mean():+.3f}, RMS {np.sqrt(np.mean(err**2)):.3f}, "
            f"largest {err[np.argmax(np.abs(err))]:+.3f}; {np.mean(np.abs(err) <= 0.1):.0%} within 0.1.",
            "",
            "| effect | trials | mean error | RMS error | largest |",
            "|---|---|---|---|---|",
        ]
        for e in effects:
            x = np.array([p - a for name, p, a in pairs if name == e])
            if x.size:
                lines.append(
                    f"| {e} | {x.size} | {x.mean():+.3f} | {np.sqrt(np.mean(x**2)):.3f} | {x[np.argmax(np.abs(x))]:+.3f} |"
                )
    lines += _reading(trials, table, friction, pairs, rows)
    lines.append("")
    return lines


def _reading(trials, table, friction, pairs, rows) -> list[str]:
    """What the numbers say (the numbers computed here; the reasons from looking at the trials)."""
    cover = [r for r in rows if r[0] != "steer_friction_records" and r[1] != "m_arm"]
    k = sum(r[3] for r in cover)
    n = sum(r[2] for r in cover)
    low = [f"{r[0]} {r[1]} {_pct(r[3], r[2])}" for r in cover if r[2] and r[3] / r[2] < 0.9]
    split = {}
    for rider in (False, True):
        sub = [r for r in coverage_rows([t for t in table if t["rider"] == rider]) if r[1] != "m_arm"]
        split[rider] = (sum(r[3] for r in sub), sum(r[2] for r in sub), [r for r in sub if r[2] and r[3] / r[2] < 0.9])
    out = [
        "",
        "### Reading the results",
        "",
        f"* Coverage over every size of the table trials (the arms by their inertia, not their mass): {_pct(k, n)}"
        " (goal 90-97 %)" + (f"; below 90 %: {'; '.join(low)}." if low else "."),
        f"* **Riderless {_pct(*split[False][:2])}, with the rider {_pct(*split[True][:2])}.** The shortfall is with",
        "  the rider. With the rider, below 90 %: "
        + ("; ".join(f"{r[0]} {r[1]} {_pct(r[3], r[2])}" for r in split[True][2]) or "none")
        + ".",
        "  For the rider's own effects part of it is the rider's geometry: the truth's differs from the",
        "  diagnosis's default (upper body 45 % of the rider's mass instead of 50 %, hip axis 5 cm lower,",
        "  grips 8 cm higher and 2 cm wider), as a real rider differs from any default, and the intervals carry",
        "  the benchmark parameters' uncertainty but not the geometry's. The arms' mass is fitted at the",
        "  default grips and is biased by the ratio of the grips' squared distances from the steer axis; their",
        "  inertia about the axis, which is what the data carry (and what the usual range judges), is scored",
        "  beside it. The truths without an upper body or arms (steer stiffness, tyres, Coulomb friction) fall",
        "  short with the rider too. Taken apart on four missed steer-stiffness trials (seeds 1005, 1007, 1013,",
        "  1017): fitted to the truth's exact weave eigenvalues instead of those fitted from its runs, the same",
        "  diagnosis's interval holds the truth in three (1.76 [1.50, 2.02] becomes 2.02 [1.76, 2.28] for a",
        "  hidden 2.09 N m/rad), while with the fitted eigenvalues the residuals sit at the noise (chi-square",
        "  per degree of freedom 0.7-1.3 against the rows' stated uncertainties). So the misses come from a",
        "  **systematic extraction bias**: the weave fitted from a 3-s roll-rate run at 4.5-9 m/s is off in the",
        "  same direction for runs alike, by more than its standard error says, and a table's stated",
        "  uncertainties cannot carry that. Records, which the diagnosis compares by indirect inference (the",
        "  same fit applied to each candidate's own response), correct for such a bias by construction;",
        "  eigenvalue tables cannot, and the intervals from them are too narrow by as much. Riderless",
        "  (2.5-6.5 m/s) the intervals meet the goal; why the bias matters less there was not taken apart.",
        "  Not fixed here: a table's rows would need the fitting method's bias (or the raw records).",
        "  With this few trials per size, one miss moves a rate by several points: a coverage of 90 % measured",
        "  on 20 trials has a 95 % binomial interval of about 70-99 %.",
        "* Small effects hide: the smallest third of the drawn sizes is ranked first less often, as the",
        "  parameters' uncertainty alone bends the weave as much (verdict `parameters` or `none`). That is the",
        "  diagnosis being right about what the data carry, not a miss of the method.",
        "* `steer_coulomb`: through eigenvalue tables Coulomb friction is named as the damping it acts as,",
        "  and sized against `4 T / (pi A)`, the describing function of a sustained oscillation; a decay's",
        "  amplitude falls within each run, so that reference is itself an approximation, and its bias here",
        "  says how far the equivalent stretches, not only how the fit errs.",
    ]
    if friction:
        t_rows = [r for r in rows if r[0] == "steer_friction_records" and r[1] == "T_coulomb"]
        if t_rows:
            r = t_rows[0]
            viscous = [t["fitted"]["c_viscous"]["value"] for t in friction if "c_viscous" in t["fitted"]]
            out += [
                f"* Friction from records ({len(friction)} trials): `T_coulomb` median error {r[4]:+.0%}, coverage "
                f"{_pct(r[3], r[2])}; the viscous part that is not there is fitted at a median "
                f"{np.median(viscous) if viscous else math.nan:.2g} N m s/rad. The time-domain fit sizes pure",
                "  Coulomb friction low, and the bias is not explained yet: the truth smooths the sign with `tanh(deltad / 0.02)`, the candidate with",
                "  0.05 rad/s, which alone would push the fitted Coulomb level up, not down. Few of these trials",
                "  select friction: the drawn sizes (half-Cauchy, scale 0.1 N m) are mostly small beside what the",
                "  riderless bicycle's parameter uncertainty does to nine short records.",
            ]
    if pairs:
        worst = max(pairs, key=lambda x: abs(x[1] - x[2]))
        out += [
            f"* Shrinkage: the largest error ({worst[1] - worst[2]:+.2f}, {worst[0]}) and the few others above",
            "  0.1 come from the fresh runs as much as from the prediction: a fresh run whose weave the record",
            "  fit gets wrong (one such run lay 16,000 standard errors from every model in trial 1009) leaves",
            "  nothing a selection can remove, and a selection that reaches the noise floor on its held-out",
            "  groups then 'achieves' nothing.",
        ]
    return out


def _label(t: dict) -> str:
    if t["verdict"] != "structural" or not t["first"]:
        return t["verdict"]
    return t["first"]
