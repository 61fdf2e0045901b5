"""Run the gap diagnosis blind on data from hidden truths and write docs/gap_validation.md.

Ten effect cases and ten null cases (:data:`bikerider.gap.validation.FULL_CASES`) on the Davis
instrumented bicycle with rider Jason, each with the full protocol (three sessions of six runs).
Run from the project root (takes a few minutes)::

    .venv/bin/python docs/scripts/gap_validation.py
"""
from __future__ import annotations

import logging
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
BP = ROOT / "src" / "bikerider" / "data" / "bicycleparameters"
OUT = ROOT / "docs" / "gap_validation.md"


def _fitted(x: float) -> str:
    """A fitted effect parameter to 3 digits; 0 below 1e-9 in SI units (every candidate parameter
    that matters is above 1e-3: smaller is an optimiser's round-off at a zero bound, whose digits
    change with the last bit of any input)."""
    return "0" if abs(x) < 1e-9 else f"{x:.3g}"


def _f(x, digits=2):
    return "-" if x is None else f"{x:.{digits}f}"


def main() -> int:
    from bikerider.gap import validation as V
    from bikerider.io.gap_model import load_model

    logging.basicConfig(level=logging.INFO, format="%(message)s")
    model = load_model(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt", BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt")
    start = time.perf_counter()
    suite = V.run_suite(model, V.FULL_CASES, V.FULL)
    elapsed = time.perf_counter() - start
    first, n_effect = suite.first_rate
    alarms, n_null = suite.false_alarms
    errors = suite.shrink_errors
    rows, cols, table = suite.confusion()
    lines = [
        "# Validation of the gap diagnosis with the effect withheld",
        "",
        "Produced by `docs/scripts/gap_validation.py` (do not edit by hand). The unit test",
        "`tests/test_gap_validation.py` runs a reduced set of the same cases.",
        "",
        "## Set-up",
        "",
        "The diagnosis (`bikerider gap`) sees only the nominal model (the Davis instrumented bicycle",
        "`RigidBenchmark.txt` with the lumped rider `JasonRigidBenchmark.txt`, BicycleParameters) and the",
        "measured weave eigenvalues. The measurements come from a hidden truth simulated by",
        "`bikerider.gap.validation`, an implementation that shares nothing with the candidate models but the",
        "meaning of the benchmark parameters:",
        "",
        "* the truth's equations are assembled by hand: the Whipple matrices from Meijaard et al. (2007)",
        "  Appendix A (not the Lagrangian the candidates come from), a hand-derived Newton-Euler coupling of",
        "  the leaning upper body, arm masses moved between bodies with the parallel-axis theorem, the added",
        "  steer inertia as a change of the front frame's inertia tensor, and, for the tyres, the contact",
        "  kinematics with an own saturating tyre law `F = mu N tanh(c_alpha alpha / mu)` relaxed in time;",
        "* the effects are nonlinear: Coulomb steer friction beside viscous, cubic springs, `sin(theta)`",
        "  gravity on the upper body, saturating tyres;",
        "* each run is a time-domain simulation (`scipy.integrate.solve_ivp`, LSODA) of a random roll-rate and",
        "  steer-rate kick, 6 s at 100 Hz, with 0.01 rad/s gyro noise on the roll rate and 0.03 m/s noise on",
        "  the speed reading; the weave eigenvalue and its standard errors are fitted to the noisy roll rate",
        "  from 0.3 s on (`bikerider.gap.extraction.weave_eigenvalue`), as from a real run; runs whose record",
        "  holds no fittable oscillation (e.g. a fall within a second) are dropped, as an experimenter would;",
        "* the truth's benchmark parameters are the nominal ones plus a random error within their stated",
        "  uncertainty, and its rider differs from the diagnosis's default geometry (upper body 45 % of the",
        "  rider's mass instead of 50 %, hip axis 5 cm lower, grips 8 cm higher and 2 cm wider);",
        "* protocol: three sessions of six runs, 5.5-9.2 m/s without control and 4.0-7.5 m/s under a known",
        "  stabilising control `T_delta = 5 phid - 2 delta - 0.5 deltad` (declared in the data).",
        "",
        "The predicted shrinkage (the fraction of the gap above the noise floor the selected effects remove,",
        "from held-out groups) is compared with the shrinkage the selected fit achieves on a fresh data set",
        "from the same truth (new kicks, noise and parameter-free speeds jitter).",
        "",
        "Hidden truths:",
        "",
        "| truth | effects and values |",
        "|---|---|",
    ]
    for name in dict.fromkeys(c.truth for c in suite.cases):
        lines.append(f"| {name} | {V.TRUTHS[name].description} |")
    lines += [
        "",
        "## Results",
        "",
        f"* Hidden effect ranked first, with a structural verdict: **{first} of {n_effect}** effect cases "
        "(goal: at least 9 of 10).",
        f"* False alarms (structural verdict on parameter error alone): **{alarms} of {n_null}** null cases "
        f"(goal: at most 1 of 10); rate {alarms / max(n_null, 1):.0%}.",
    ]
    if errors.size:
        lines.append(f"* Error of the predicted shrinkage (predicted minus achieved on fresh data), {errors.size} cases "
                     f"with a selection: mean {errors.mean():+.3f}, RMS {np.sqrt(np.mean(errors**2)):.3f}, "
                     f"largest {errors[np.argmax(np.abs(errors))]:+.3f}.")
    lines += [f"* {len(suite.cases)} cases in {elapsed:.0f} s (data generation, diagnosis and fresh test data).", "",
              "### Confusion matrix", "",
              "Rows: hidden truth; columns: the first-ranked effect when the verdict is structural, otherwise the "
              "verdict.", "", "| truth | " + " | ".join(cols) + " |", "|---|" + "---|" * len(cols)]
    for i, r in enumerate(rows):
        lines.append(f"| {r} | " + " | ".join(str(x) if x else "." for x in table[i]) + " |")
    lines += ["", "### Every case", "",
              "| truth | seed | measured | verdict | ranking (first three) | first's fitted values | tied with first | "
              "selected | predicted shrink | achieved shrink | correct |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for c in suite.cases:
        fitted = ", ".join(f"{k} {_fitted(v)}" for k, v in c.first_parameters.items()) or "-"
        lines.append(f"| {c.truth} | {c.seed} | {c.n_measured} | {c.verdict} | {', '.join(c.ranking[:3])} | {fitted} | "
                     f"{', '.join(c.ties_with_first) or '-'} | {', '.join(c.selected) or '-'} | "
                     f"{_f(c.predicted_shrink)} | {_f(c.actual_shrink)} | {'yes' if c.correct else '**no**'} |")
    misses = [c for c in suite.cases if not c.correct]
    lines += ["", "## Reading the results", ""]
    for c in misses:
        if c.hidden:
            lines.append(f"* Miss: `{c.truth}` (seed {c.seed}) gave `{c.top}` first"
                         + (f" and selected {', '.join(c.selected)}." if c.selected else " and selected nothing: no candidate "
                            "predicted the held-out groups significantly better than the nominal model."))
        else:
            lines.append(f"* False alarm: null case, seed {c.seed}, verdict {c.verdict}.")
    if any(c.truth == "strong_steer_damping" and not c.correct for c in misses):
        lines += ["  Coulomb friction of 0.1 N m is large against the steer torques of a small perturbation; its",
                  "  effect depends on the amplitude, which differs from run to run, and none of the linear candidates",
                  "  predicts the held-out sessions significantly better. The diagnosis reports a structural gap and",
                  "  selects nothing rather than naming an effect it cannot support."]
    lines += [
              "* Ties are common between `steer_damping` and `passive_arms` (whose damping can stand in for it)",
              "  and between the steer effects and `rider_lean`; the tie rule ranks the simpler effect first.",
              "* The fitted steer damping of the Coulomb-plus-viscous truths exceeds the viscous part: Coulomb",
              "  friction acts as an amplitude-dependent viscous damping at the small steer rates of a",
              "  perturbation run, which the plausibility check may then flag against the viscous literature range.",
              "* Compare the fitted values with the truths above: weave eigenvalues alone determine some parameters",
              "  poorly (the tyres' cornering stiffness and relaxation length above all); the 95 % intervals and the",
              "  plausibility flag in `bikerider gap`'s output say how well.",
              ""]
    OUT.write_text("\n".join(lines), encoding="utf-8")
    print(f"wrote {OUT}: first {first}/{n_effect}, false alarms {alarms}/{n_null}, {elapsed:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
