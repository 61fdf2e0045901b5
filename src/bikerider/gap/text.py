"""Text of a gap diagnosis: the terminal summary, the next experiment's plan as text, ``report.md``.

Plain strings from the diagnosis's and the plan's ``as_dict()`` (no matplotlib: the figures are
:mod:`bikerider.plotting.gap` and :mod:`bikerider.plotting.gap_plan`).
"""

from __future__ import annotations

import math

from bikerider.gap.candidates.effects import EFFECTS, PARAMETERS


def _fmt(x, digits: int = 3) -> str:
    if x is None:
        return "-"
    if isinstance(x, float):
        if not math.isfinite(x):
            return str(x)
        return f"{x:.{digits}g}"
    return str(x)


def _num(x) -> str:
    """A held-out error or shrinkage to two decimals (``-`` when there is none)."""
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.2f}"


ZERO = 1e-6
"""A fitted value below this share of its 95 % interval's larger end is shown as 0 (an optimiser's
1e-20 for a value at the bound 0)."""


def _interval_text(value: float, low: float, high: float) -> str:
    """``value [low, high]`` with three significant digits, or more where three would show ends that
    differ as equal (a well determined value: ``11.4711 [11.47106, 11.47114]``, not ``11.5 [11.5,
    11.5]``); a value or end within :data:`ZERO` of 0, relative to the interval, as 0."""
    numbers = [value, low, high]
    finite = [abs(x) for x in numbers if math.isfinite(x)]
    scale = max(finite, default=0.0)
    numbers = [0.0 if math.isfinite(x) and abs(x) < ZERO * scale else x for x in numbers]
    digits = 3
    while digits < 9:
        texts = [f"{x:.{digits}g}" for x in numbers]
        if all(texts[i] != texts[j] for i in range(3) for j in range(i) if numbers[i] != numbers[j]):
            break
        digits += 1
    texts = [f"{x:.{digits}g}" for x in numbers]
    return f"{texts[0]} [{texts[1]}, {texts[2]}]"


def _values(params: dict) -> str:
    return ", ".join(
        f"{k} = {_interval_text(v['value'], v['ci95'][0], v['ci95'][1])} {v['unit']}"
        for k, v in params.items()
        if not k.startswith("parameters.")
    )


def _minima_text(minima: list[dict], indent: str) -> list[str]:
    """A line for each other minimum of a fit's chi-square the intervals hold (the data cannot reject it)."""
    return [
        f"{indent}another minimum of nearly equal depth: "
        + ", ".join(f"{k} = {_fmt(v)}" for k, v in m["values"].items() if not k.startswith("parameters."))
        + f" (chi-square {m['chi2']:.3g} against the fit's {m['chi2_fit']:.3g}); the 95 % intervals hold both"
        for m in minima
        if m.get("within")
    ]


def _law_text(name: str, text: str) -> str:
    """``Control law NAME: GAINS``, or ``Control law: GAINS`` when the name is the gains themselves
    (an unnamed ``[control]`` table)."""

    def squeeze(x: str) -> str:
        return "".join(c for c in x if c not in " ,;")

    return f"Control law: {text}" if squeeze(name) == squeeze(text) else f"Control law {name}: {text}"


def summary_text(result: dict) -> str:
    """A plain-text summary of :meth:`Diagnosis.as_dict` for the terminal."""
    lines = []
    test = result["gap"]["test"]
    lines.append(f"Verdict: {result['verdict']}")
    # Two scales, each named on screen: against the combined uncertainty (data and parameters) and
    # against the data's noise alone; the parameter fit's chi2 belongs to the second.
    n = max(test["dof"], 1)
    lines.append(
        "Gap against the combined uncertainty of data and parameters (full covariance: the shared "
        "parameters correlate the residuals):"
    )
    lines.append(
        f"  chi2 = {test['chi2']:.1f} on {test['dof']} observations, chi2/n = {test['chi2'] / n:.2f}, p = {test['p_value']:.2g}"
    )
    lines.append(
        f"  each residual over its own combined sigma, correlation left out (the scale of the held-out "
        f"errors below): RMS {test['rms_z']:.2f}"
    )
    lines.append("Gap against the data's noise alone (the parameters taken as exact):")
    data = test["data_only"]
    lines.append(
        f"  nominal parameters: chi2 = {data['chi2']:.1f}, chi2/n = {data['chi2'] / n:.2f}, p = {data['p_value']:.2g}"
    )
    if result.get("parameter_fit") and result["parameter_fit"].get("test"):
        pt = result["parameter_fit"]["test"]
        lines.append(
            f"  parameters fitted within their uncertainty: chi2 = {pt['chi2']:.1f} (data "
            f"{pt['chi2'] - pt['prior_chi2']:.1f} + prior {pt['prior_chi2']:.1f} on {pt['prior_dof']} parameters), "
            f"chi2/n = {pt['chi2'] / max(pt['dof'], 1):.2f}, p = {pt['p_value']:.2g}"
        )
    unc = result.get("uncertainty") or {}
    if unc.get("largest"):
        lines.append(
            f"Typical standard uncertainty: data {_fmt(unc['data'])}, model parameters {_fmt(unc['parameters'])} "
            "(largest: " + ", ".join(f"{u['parameter']} {_fmt(u['rms_effect'], 2)}" for u in unc["largest"][:4]) + ")"
        )
    records = result.get("records")
    if records:
        repaired = records.get("repaired", [])
        fixed = f" ({len(repaired)} of them repaired)" if repaired else ""
        lines.append(f"Records: {records['used']} of {records['total']} used{fixed}, {records['left_out']} left out")
        for r in repaired:
            lines.append(f"  repaired {r['record']}: " + "; ".join(r["repairs"]))
        for r in records["reasons"]:
            lines.append(f"  left out {r['record']}: {r['reason']}")
    for name, text in result.get("laws", {}).items():
        if text != "no control":
            lines.append(_law_text(name, text))
    lines.append("")
    lines.append("Where (gap map; cells significant against the combined uncertainty, or * against the data's alone):")
    lines.append(
        f"  {'mode':<10} {'speed band':<14} {'quantity':<26} {'n':>3} {'measured-model':>15} {'sigma':>8} "
        f"{'RMS z':>7} {'data z':>7}"
    )
    shown = [c for c in result["gap"]["map"] if c["significant"] or c.get("significant_data")]
    for cell in shown:
        band = f"{cell['speed_band'][0]:.1f}-{cell['speed_band'][1]:.1f}"
        star = "" if cell["significant"] else " *"
        data_z = "-" if cell.get("rms_z_data") is None else f"{cell['rms_z_data']:.2f}"
        lines.append(
            f"  {cell['mode']:<10} {band:<14} {cell['quantity']:<26} {cell['n']:>3} "
            f"{cell['mean_residual']:>15.4g} {cell['combined_sigma']:>8.3g} {cell['rms_z']:>7.2f} {data_z:>7}{star}"
        )
    if not shown:
        lines.append("  (none)")
    lines.append("")
    if result["ranking"]:
        lines.append(
            "Which (held-out error: RMS of residuals over the combined uncertainty, and over the data's alone; "
            "folds: " + ", ".join(result["folds"]) + "):"
        )
        lines.append(
            f"  {'rank':<5}{'effect':<17}{'before':>8}{'after':>8}{'shrink':>8}{'data: after':>12}"
            f"{'shrink':>8}  plausible  fitted"
        )
        first = result["ranking"][0]
        lines.append(
            f"  {'':<5}{'(nominal)':<17}{first['heldout_error_before']:>8.2f}{'':>16}"
            f"{_num(first.get('data_error_before')):>12}"
        )
        for r in result["ranking"]:
            params = _values(r["parameters"])
            if r["effect"] == PARAMETERS:
                params = f"{len(r['parameters'])} benchmark parameters shifted"
            ties = f"  (tied with {', '.join(r['tied_with'])})" if r["tied_with"] else ""
            lines.append(
                f"  {r['rank']:<5}{r['effect']:<17}{r['heldout_error_before']:>8.2f}{r['heldout_error_after']:>8.2f}"
                f"{_num(r['shrink']):>8}{_num(r.get('data_error_after')):>12}{_num(r.get('data_shrink')):>8}"
                f"  {'yes' if r['plausible'] else 'no':<9}  {params}{ties}"
            )
            lines += _minima_text(r.get("other_minima", []), " " * 7)
        if result.get("pairs"):
            lines.append("  pairs (fitted jointly), best first:")
            for p in result["pairs"][:5]:
                plaus = {True: "yes", False: "no", None: "-"}[p.get("plausible")]
                lines.append(
                    f"       {'+'.join(p['effects']):<30}{p['heldout_error_after']:>8.2f}{_num(p['shrink']):>8}"
                    f"{_num(p.get('data_error_after')):>12}{_num(p.get('data_shrink')):>8}  {plaus:<9}  "
                    f"{_values(p.get('parameters', {}))}"
                )
                lines += _minima_text(p.get("other_minima", []), " " * 9)
    else:
        lines.append("Which: no ranking (" + "; ".join(result["notes"][-1:]) + ")")
    for name, why in result.get("not_applicable", {}).items():
        lines.append(f"  {name}: not applicable ({why})")
    lines.append("")
    lines.append("Selected: " + (", ".join(result["selected"]) if result["selected"] else "nothing"))
    selection = result.get("selection", {})
    if result["selected"] and selection.get("log_odds_vs_nominal") is not None:
        lack = selection.get("lack_of_fit", 1.0)
        lines.append(
            f"  evidence against the nominal model: {selection['log_odds_vs_nominal']:.1f} nats (held-out "
            "log-likelihood"
            + (f" with the noise inflated by the lack of fit s^2 = {lack:.3g}" if lack > 1.0 else "")
            + f", plus the log prior ratio {selection['log_prior']:.2f} of its values)"
        )
    for flag in selection.get("flags", []):
        lines.append(f"  flag: {flag}")
    single = result.get("best_single_implausible")
    if single:
        lines.append(
            f"The lowest held-out error of a single candidate ({single['heldout_error']:.3g}) is that of "
            f"{'+'.join(single['effects'])}{_rank_phrase(single)}, which needs unusual values: "
            + "; ".join(single["why"])
            + _odds_phrase(single)
            + "."
        )
    bad = result.get("best_implausible")
    if bad:
        lines.append(
            f"The lowest held-out error of any fit, single or pair ({bad['heldout_error']:.3g}), is that of "
            f"{'+'.join(bad['effects'])}{_rank_phrase(bad)}, which needs unusual values: "
            + "; ".join(bad["why"])
            + _odds_phrase(bad)
            + ". It is not selected."
        )
    if result["verdict"] == "none" and result["ranking"]:
        lines.append("No gap beyond the uncertainty of the data: nothing is selected.")
    if result.get("selection", {}).get("note"):
        lines.append("Note: " + result["selection"]["note"] + ".")
    hf = result.get("how_far")
    if hf:
        lines.append(
            f"How far: held-out error {hf['heldout_error_before']:.2f} -> {hf['heldout_error_after']:.2f}; "
            f"gap above the noise floor removed: {_fmt(hf['shrink'], 2)} (against the data's own noise: "
            f"{_fmt(hf.get('data_error_before'))} -> {_fmt(hf.get('data_error_after'))}, "
            f"{_fmt(hf.get('data_shrink'), 2)} removed)"
        )
        for f in hf["folds"]:
            lines.append(f"  {f['fold']}: {f['error_before']:.2f} -> {f['error_after']:.2f} ({f['n']} observations)")
    for note in result["notes"]:
        lines.append(f"Note: {note}")
    return "\n".join(lines)


def _odds_phrase(entry: dict) -> str:
    """How the evidence (held-out log-likelihood plus log prior) compares with the selection's."""
    odds = entry.get("log_odds_vs_selected")
    if odds is None:
        return ""
    return f" (its evidence {odds:+.1f} nats beside the selection's, prior included)"


def markdown(result: dict, title: str, figures: list[tuple[str, str]]) -> str:
    """``report.md``: the summary, the candidates, the records and the figures."""
    md = [
        f"# {title}",
        "",
        f"Model: `{result['model']['source']}`  ",
        f"Rider geometry: {result['model']['geometry']}",
        "",
        f"**Verdict: {result['verdict']}** — selected: {', '.join(result['selected']) or 'nothing'}",
        "",
    ]
    md += ["```", summary_text(result), "```", ""]
    if result.get("next"):
        md += ["## Next experiment", "", "```", next_text(result["next"], rows=12), "```", ""]
    md += ["## Candidates", "", "| effect | what it is |", "|---|---|"]
    md += [f"| {e.name} | {e.description} |" for e in EFFECTS.values()]
    md += [""]
    records = result.get("records")
    if records:
        md += [
            "## Records",
            "",
            "| record | group | law | speed [m/s] | eigenvalue [1/s] | r^2 | cycles | used |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for r in records["list"]:
            if r["used"] and r.get("kind") == "multisine":  # a steer-torque multisine: its frequency response
                lines = r["lines"]
                value = (
                    f"multisine: response of {', '.join(s.replace('_', ' ') for s in r['signals'])} at "
                    f"{len(lines)} lines {lines[0]:.2g}-{lines[-1]:.2g} Hz"
                )
                md.append(f"| {r['record']} | {r['group']} | {r['law']} | {r['speed']:.2f} | {value} | - | - | yes |")
            elif r["used"]:
                value = f"{r['real']:.2f} ± {r['real_sigma']:.2f} + ({r['imag']:.2f} ± {r['imag_sigma']:.2f}) i"
                md.append(
                    f"| {r['record']} | {r['group']} | {r['law']} | {r['speed']:.2f} | {value} | {r['r2']:.3f} | "
                    f"{r['cycles']:.1f} | yes |"
                )
            else:
                md.append(
                    f"| {r['record']} | {r['group']} | {r['law']} | {r['speed']:.2f} | - | - | - | no: {r['reason']} |"
                )
        md += [""]
    for name, caption in figures:
        md += [f"## {caption}", "", f"![{caption}]({name})", ""]
    return "\n".join(md)


def _rank_phrase(entry: dict) -> str:
    """`` (ranked 2nd: tied with steer_friction, which has fewer fitted values)`` for a ranked single."""
    if "rank" not in entry:
        return ""
    ties = entry.get("tied_with") or []
    if entry["rank"] == 1 or not ties:
        return f" (ranked {entry['rank']})"
    return (
        f" (ranked {entry['rank']}: tied with {', '.join(ties)}; within a tie the candidate with fewer fitted "
        "values ranks first)"
    )


def next_text(result: dict, rows: int = 8) -> str:
    """The plan in words: rivals, measure, noise, the ranked experiments, the best per signal and law."""
    rivals = [" + ".join(r["effects"]) for r in result["rivals"]]
    width = max([78] + [len(item["text"]) + 2 for item in result["plan"][:rows]])
    lines = [
        "Next experiment: to tell " + ", ".join(rivals[:-1]) + " and " + rivals[-1] + " apart "
        f"({result['rivals_rule']})",
        f"Measure: {result['measure']}.",
    ]
    missing = [r for r in result["rivals"] if r.get("heldout_error")]
    if missing:
        lines.append(
            "Misfit: "
            + ", ".join(f"{' + '.join(r['effects'])} misses held-out data by {r['heldout_error']:.2f}" for r in missing)
            + " (RMS over the uncertainties; noise alone gives about 1); the plan counts the misfit as a systematic error of "
            "each rival's prediction, so two rivals that both miss the data by more than they differ are not told apart."
        )
    lines += [
        "Noise: "
        + result["noise"]["note"]
        + (
            "; sample noise "
            + ", ".join(
                f"{s.replace('_', ' ')} {v['value']:.2g} ({_short_source(v['source'])})"
                for s, v in result["noise"]["signals"].items()
            )
            if result["noise"]["signals"]
            else ""
        )
        + ".",
    ]
    if result.get("sweeps"):
        sw = result["sweeps"]
        lines.append(
            f"Multisines: {sw['torque']:g} N m peak, {sw['run_time']:g} s per run; {sw['note']}; the share a linear "
            f"model misses {sw['distortion']['value']:.2f} per line ({_short_source(sw['distortion']['source'])})."
        )
    lines += [
        f"  {'rank':<5}{'experiment':<{width}}{'P':>6}{'n 95%':>7}{'limit':>7}  d per pair (first true/second true)",
    ]
    for k, item in enumerate(result["plan"][:rows], start=1):
        need = "-" if item["decays_for_95"] is None else str(item["decays_for_95"])
        pairs = ", ".join(
            f"{'/'.join(p['rivals'])} {p['separation'][0]:.1f}/{p['separation'][1]:.1f}" for p in item["pairs"]
        )
        lines.append(
            f"  {k:<5}{item['text']:<{width}}{item['resolution_probability']:>6.2f}{need:>7}{item['limit']:>7.2f}  {pairs}"
        )
    if result.get("best_per_signal"):
        lines.append(
            "  best per signal: "
            + "; ".join(
                f"{s.replace('_', ' ')} {v['resolution_probability']:.2f} at {v['speed']:.2f} m/s"
                for s, v in result["best_per_signal"].items()
            )
        )
    lines.append(
        "  best per law: "
        + "; ".join(
            f"{law} {v['resolution_probability']:.2f} at {v['speed']:.2f} m/s"
            for law, v in result["best_per_law"].items()
        )
    )
    best = result["plan"][0] if result["plan"] else None
    if best is not None:
        if best["decays_for_95"] is not None:
            verb = "tells" if best["decays_for_95"] == 1 else "tell"
            lines.append(f"Recommendation: {best['text_for_95']} {verb} the rivals apart with 95 % probability.")
        elif (combined := result.get("combined")) and combined["reached"]:
            lines.append(
                f"Recommendation: no experiment repeated reaches 95 % within {result['max_repeats']} runs, but runs "
                f"combined do: {combined['text']} ({combined['runs']} runs) tell the rivals apart with probability "
                f"{combined['probability']:.2f} (the runs at one speed or law pin a rival's values, those at another "
                "part the rivals; their evidence adds up)."
            )
        else:
            spread = (
                f"; nor does the best spread of up to {combined['budget']} runs over up to {combined['distinct']} "
                f"experiments found ({combined['text']}: {combined['probability']:.2f}): the tie is unbreakable by "
                "these experiments"
                if combined
                else ""
            )
            lines.append(
                f"Recommendation: no experiment considered reaches 95 % within {result['max_repeats']} runs; the best, "
                f"{best['text']}, reaches {best['resolution_probability']:.2f} (at most {best['limit']:.2f} with any "
                f"number of runs: the rivals' own uncertainty and their misfit on held-out data keep it there){spread}."
            )
    if nxt := result.get("next_run"):
        where = (
            f"ranked {nxt['rank']} of {result.get('experiments')} by the measure" if nxt.get("rank") else "in the plan"
        )
        lines.append(
            f"Next run, one at a time: {nxt['text']} ({where}; one run tells the rivals apart with probability "
            f"{nxt['resolution_probability']:.2f}): where the rivals' predictions of one run overlap least "
            f"(Jensen-Renyi divergence {nxt['divergence']:.3g} of at most {nxt['bound']:.3g} nats, the rivals "
            "weighted evenly), the criterion that needed the fewest runs in the closed-loop check "
            f"(docs/gap_validation.md, part 5). Then {nxt['instruction']}."
        )
    if result["left_out"]:
        lines.append(
            f"  {len(result['left_out'])} experiments left out (e.g. {result['left_out'][0]['experiment']}: "
            f"{result['left_out'][0]['reason']})"
        )
    return "\n".join(lines)


def _short_source(source: str) -> str:
    return "data" if source.startswith(("the data", "the records")) else source.split(" ")[0]
