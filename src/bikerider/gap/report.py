"""Text summary, markdown report and figures of a gap diagnosis (matplotlib, Agg backend).

:func:`write_report` writes ``report.md`` and PNG figures into a folder:

``eigenvalues.png``
    measured eigenvalues against speed (error bars: data uncertainty) with the nominal model and
    the model with the selected effects, one line per control law in the data;
``gap_map.png``
    the normalised residual of every gap-map cell (mode and quantity by speed band);
``ranking.png``
    held-out error of every candidate before and after;
``effects.png``
    the weave eigenvalue against speed of every candidate as fitted (each effect on its own);
``time_response.png``
    roll rate after a kick, nominal against the selected model;
``canonical.png``
    identified canonical entries against the nominal and selected models' equivalents.

:func:`plot_effect` draws any effect model on its own (eigenvalues against speed and a time
response) for users exploring a candidate.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from bikerider.gap.effects import EFFECTS


def _save(fig, path: Path) -> None:
    """Write a figure atomically (a failed render leaves the previous file) and close it."""
    from bikerider.io.atomic import atomic_write_bytes, figure_bytes

    plt = _pyplot()
    try:
        atomic_write_bytes(path, figure_bytes(fig, dpi=110, format="png"))
    finally:
        plt.close(fig)


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _fmt(x, digits: int = 3) -> str:
    if x is None:
        return "-"
    if isinstance(x, float):
        if not math.isfinite(x):
            return str(x)
        return f"{x:.{digits}g}"
    return str(x)


# ---------------------------------------------------------------------------------------------
# Text
# ---------------------------------------------------------------------------------------------
def summary_text(result: dict) -> str:
    """A plain-text summary of :meth:`Diagnosis.as_dict` for the terminal."""
    lines = []
    test = result["gap"]["test"]
    lines.append(f"Verdict: {result['verdict']}")
    lines.append(
        f"Gap: chi2 = {test['chi2']:.1f} on {test['dof']} observations (p = {test['p_value']:.2g}), "
        f"RMS normalised residual {test['rms_z']:.2f}"
    )
    if result.get("parameter_fit") and result["parameter_fit"].get("test"):
        pt = result["parameter_fit"]["test"]
        lines.append(
            f"Parameters alone (fitted within their uncertainty): chi2 = {pt['chi2']:.1f} "
            f"(p = {pt['p_value']:.2g}; prior {pt['prior_chi2']:.1f} on {pt['prior_dof']} parameters)"
        )
    lines.append("")
    lines.append("Where (gap map; significant cells):")
    lines.append(
        f"  {'mode':<10} {'speed band':<14} {'quantity':<26} {'n':>3} {'measured-model':>15} {'sigma':>8} {'RMS z':>7}"
    )
    for cell in result["gap"]["map"]:
        if cell["significant"]:
            band = f"{cell['speed_band'][0]:.1f}-{cell['speed_band'][1]:.1f}"
            lines.append(
                f"  {cell['mode']:<10} {band:<14} {cell['quantity']:<26} {cell['n']:>3} "
                f"{cell['mean_residual']:>15.4g} {cell['combined_sigma']:>8.3g} {cell['rms_z']:>7.2f}"
            )
    if not any(c["significant"] for c in result["gap"]["map"]):
        lines.append("  (none)")
    lines.append("")
    if result["ranking"]:
        lines.append("Which (held-out error, RMS of normalised residuals; folds: " + ", ".join(result["folds"]) + "):")
        lines.append(f"  {'rank':<5}{'effect':<17}{'before':>8}{'after':>8}{'shrink':>8}  plausible  fitted")
        for r in result["ranking"]:
            params = ", ".join(
                f"{k}={v['value']:.3g} [{v['ci95'][0]:.3g}, {v['ci95'][1]:.3g}] {v['unit']}"
                for k, v in r["parameters"].items()
                if not k.startswith("parameters.")
            )
            if r["effect"] == "parameters":
                params = f"{len(r['parameters'])} benchmark parameters shifted"
            ties = f"  (tied with {', '.join(r['tied_with'])})" if r["tied_with"] else ""
            lines.append(
                f"  {r['rank']:<5}{r['effect']:<17}{r['heldout_error_before']:>8.2f}{r['heldout_error_after']:>8.2f}"
                f"{_fmt(r['shrink'], 2):>8}  {'yes' if r['plausible'] else 'no':<9}  {params}{ties}"
            )
    else:
        lines.append("Which: no ranking (" + "; ".join(result["notes"][-1:]) + ")")
    for name, why in result.get("not_applicable", {}).items():
        lines.append(f"  {name}: not applicable ({why})")
    lines.append("")
    lines.append("Selected: " + (", ".join(result["selected"]) if result["selected"] else "nothing"))
    hf = result.get("how_far")
    if hf:
        lines.append(
            f"How far: held-out error {hf['heldout_error_before']:.2f} -> {hf['heldout_error_after']:.2f}; "
            f"gap above the noise floor removed: {_fmt(hf['shrink'], 2)}"
        )
        for f in hf["folds"]:
            lines.append(f"  {f['fold']}: {f['error_before']:.2f} -> {f['error_after']:.2f} ({f['n']} observations)")
    for note in result["notes"]:
        lines.append(f"Note: {note}")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------------------------
def _speed_grid(diagnosis) -> np.ndarray:
    speeds = diagnosis.problem.obs.speed
    lo, hi = float(np.min(speeds)), float(np.max(speeds))
    pad = 0.1 * max(hi - lo, 1.0)
    return np.linspace(max(lo - pad, 0.5), hi + pad, 80)


def _weave_curve(model, speeds: np.ndarray, gains, reference_model) -> np.ndarray:
    """Weave eigenvalue of ``model`` along ``speeds``, matched to ``reference_model``'s weave."""
    from bikerider.benchmark.model import label_modes

    ref, _ = label_modes(reference_model.eigenvalues(speeds, gains))
    ev = model.eigenvalues(speeds, gains)
    scale = 1e-9 * np.maximum(1.0, np.abs(ev).max(axis=-1, keepdims=True))
    ok = ev.imag > scale
    dist = np.abs(ev - ref[:, :1]) + 1e6 * ~ok
    pick = np.argmin(dist, axis=-1)
    out = np.take_along_axis(ev, pick[:, None], axis=-1)[:, 0]
    none = ~np.any(ok, axis=-1)
    out = np.where(none, np.nan + 1j * np.nan, out)
    return out


def plot_eigenvalues(diagnosis, path: Path) -> None:
    plt = _pyplot()
    from bikerider.gap.models import EffectModel

    p = diagnosis.problem
    e = p.predictor.eigen
    if not len(e):
        return
    grid = _speed_grid(diagnosis)
    nominal = EffectModel(p.nominal, p.geometry)
    selected = p.fitted_model(diagnosis.selected_fit) if diagnosis.selected_fit is not None else None
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharex=True)
    gain_sets = {tuple(g) for g in e.gains}
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, gains in enumerate(sorted(gain_sets)):
        g = np.array(gains)
        label = "" if not np.any(g) else f" (control {', '.join(f'{x:g}' for x in g)})"
        before = _weave_curve(nominal, grid, g, nominal)
        axes[0].plot(grid, before.real, "--", color=colours[k % 10], label=f"nominal{label}")
        axes[1].plot(grid, before.imag, "--", color=colours[k % 10])
        if selected is not None:
            after = _weave_curve(selected, grid, g, nominal)
            axes[0].plot(
                grid, after.real, "-", color=colours[k % 10], label=f"with {'+'.join(diagnosis.selected)}{label}"
            )
            axes[1].plot(grid, after.imag, "-", color=colours[k % 10])
        rows = [i for i in range(len(e)) if tuple(e.gains[i]) == gains]
        for ax, part, sig in ((axes[0], e.value.real, e.real_sigma), (axes[1], e.value.imag, e.imag_sigma)):
            ax.errorbar(
                e.speed[rows],
                part[rows],
                yerr=np.nan_to_num(sig[rows]),
                fmt="o",
                ms=4,
                color=colours[k % 10],
                capsize=2,
            )
    axes[0].axhline(0, color="0.6", lw=0.8)
    axes[0].set_ylabel("weave real part [1/s]")
    axes[1].set_ylabel("weave imaginary part [rad/s]")
    for ax in axes:
        ax.set_xlabel("speed [m/s]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle(
        "Measured (points) and predicted weave eigenvalues: nominal (dashed), selected effects (solid)", fontsize=9
    )
    fig.tight_layout()
    _save(fig, path)


def plot_gap_map(result: dict, path: Path) -> None:
    plt = _pyplot()
    cells = result["gap"]["map"]
    rows = list(dict.fromkeys(f"{c['mode']} {c['quantity']}" for c in cells))
    cols = list(dict.fromkeys(f"{c['speed_band'][0]:.1f}-{c['speed_band'][1]:.1f}" for c in cells))
    table = np.full((len(rows), len(cols)), np.nan)
    for c in cells:
        table[
            rows.index(f"{c['mode']} {c['quantity']}"), cols.index(f"{c['speed_band'][0]:.1f}-{c['speed_band'][1]:.1f}")
        ] = np.sign(c["mean_residual"]) * c["rms_z"]
    fig, ax = plt.subplots(figsize=(max(5, 1.2 * len(cols) + 3), max(2.5, 0.4 * len(rows) + 1.5)))
    limit = max(3.0, float(np.nanmax(np.abs(table)))) if np.any(np.isfinite(table)) else 3.0
    im = ax.imshow(table, cmap="RdBu_r", vmin=-limit, vmax=limit, aspect="auto")
    ax.set_xticks(range(len(cols)), cols, fontsize=7, rotation=30)
    ax.set_yticks(range(len(rows)), rows, fontsize=7)
    ax.set_xlabel("speed band [m/s]")
    for i in range(len(rows)):
        for j in range(len(cols)):
            if np.isfinite(table[i, j]):
                ax.text(j, i, f"{table[i, j]:.1f}", ha="center", va="center", fontsize=7)
    fig.colorbar(im, ax=ax, label="signed RMS z")
    ax.set_title("Gap map: residuals in units of the combined uncertainty", fontsize=9)
    fig.tight_layout()
    _save(fig, path)


def plot_ranking(result: dict, path: Path) -> None:
    plt = _pyplot()
    ranking = result["ranking"]
    if not ranking:
        return
    names = [r["effect"] for r in ranking]
    after = [r["heldout_error_after"] for r in ranking]
    before = ranking[0]["heldout_error_before"]
    fig, ax = plt.subplots(figsize=(7, 3.2))
    ax.barh(range(len(names)), after, color=["tab:green" if r["plausible"] else "tab:orange" for r in ranking])
    ax.axvline(before, color="k", ls="--", label=f"nominal model ({before:.2f})")
    ax.axvline(1.0, color="0.5", ls=":", label="noise floor (1)")
    ax.set_yticks(range(len(names)), names)
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.set_xlabel("held-out error (RMS normalised residual)")
    ax.legend(fontsize=7)
    ax.set_title(
        "Candidates fitted on training folds, scored on held-out folds (orange: implausible values)", fontsize=8
    )
    fig.tight_layout()
    _save(fig, path)


def plot_effects(diagnosis, path: Path) -> None:
    plt = _pyplot()
    from bikerider.gap.models import EffectModel

    p = diagnosis.problem
    grid = _speed_grid(diagnosis)
    nominal = EffectModel(p.nominal, p.geometry)
    gains = p.predictor.eigen.gains[0] if len(p.predictor.eigen) else np.zeros(4)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharex=True)
    base = _weave_curve(nominal, grid, gains, nominal)
    axes[0].plot(grid, base.real, "k--", label="nominal")
    axes[1].plot(grid, base.imag, "k--")
    for name, fit in diagnosis.full_fits.items():
        curve = _weave_curve(p.fitted_model(fit), grid, gains, nominal)
        axes[0].plot(grid, curve.real, label=name)
        axes[1].plot(grid, curve.imag)
    axes[0].set_ylabel("weave real part [1/s]")
    axes[1].set_ylabel("weave imaginary part [rad/s]")
    for ax in axes:
        ax.set_xlabel("speed [m/s]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Every candidate fitted to all the data, on its own", fontsize=9)
    fig.tight_layout()
    _save(fig, path)


def plot_time_response(diagnosis, path: Path) -> None:
    plt = _pyplot()
    from bikerider.gap.models import EffectModel

    p = diagnosis.problem
    speed = float(np.median(p.obs.speed))
    t = np.linspace(0, 5, 501)
    fig, ax = plt.subplots(figsize=(7, 3.2))
    nominal = EffectModel(p.nominal, p.geometry).simulate(speed, t)
    ax.plot(t, nominal["phid"], "k--", label="nominal")
    if diagnosis.selected_fit is not None:
        sel = p.fitted_model(diagnosis.selected_fit).simulate(speed, t)
        ax.plot(t, sel["phid"], label="+".join(diagnosis.selected))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("roll rate [rad/s]")
    ax.set_title(f"Free response to a 0.5 rad/s roll-rate kick at {speed:.1f} m/s (no control)", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    _save(fig, path)


def plot_canonical(diagnosis, path: Path) -> None:
    plt = _pyplot()
    p = diagnosis.problem
    obs = p.obs
    idx = [i for i, k in enumerate(obs.kind) if k == "canonical"]
    if not idx:
        return
    after = p.predict_fit(diagnosis.selected_fit) if diagnosis.selected_fit is not None else None
    labels = [f"{obs.quantity[i]}\n{obs.group[i]}" for i in idx]
    fig, ax = plt.subplots(figsize=(max(7, 0.55 * len(idx)), 4))
    x = np.arange(len(idx))
    scale = np.abs(p.baseline[idx])
    scale = np.where(scale > 0, scale, 1.0)
    ax.errorbar(x, p.y[idx] / scale, yerr=np.sqrt(p.var_data[idx]) / scale, fmt="o", label="identified", capsize=2)
    ax.plot(x, p.baseline[idx] / scale, "k_", ms=14, label="nominal Whipple")
    if after is not None:
        ax.plot(x, after[idx] / scale, "r_", ms=14, label="+".join(diagnosis.selected))
    ax.set_xticks(x, labels, fontsize=6, rotation=90)
    ax.set_ylabel("value / |nominal value|")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title("Identified canonical entries and what each model's identification would give", fontsize=9)
    fig.tight_layout()
    _save(fig, path)


def plot_effect(model, speeds, path: Path, *, gains=None, speed: float | None = None, title: str = "") -> None:
    """Eigenvalues against speed and a roll-rate time response of one :class:`EffectModel`."""
    plt = _pyplot()
    speeds = np.asarray(speeds, dtype=float)
    ev = model.eigenvalues(speeds, gains)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for k in range(ev.shape[-1]):
        axes[0].plot(speeds, ev[:, k].real, ".", ms=3, color="tab:blue")
        axes[0].plot(speeds, np.abs(ev[:, k].imag), ".", ms=3, color="tab:orange")
    axes[0].set_ylim(-15, 15)
    axes[0].set_xlabel("speed [m/s]")
    axes[0].set_ylabel("eigenvalues: real (blue), |imag| (orange) [1/s]")
    axes[0].grid(alpha=0.3)
    v = float(speed if speed is not None else np.median(speeds))
    t = np.linspace(0, 5, 501)
    response = model.simulate(v, t, gains=gains)
    axes[1].plot(t, response["phid"], label="roll rate")
    axes[1].plot(t, response["deltad"], label="steer rate")
    axes[1].set_xlabel("time [s]")
    axes[1].set_ylabel("[rad/s]")
    axes[1].set_title(f"response to a roll-rate kick at {v:.1f} m/s", fontsize=8)
    axes[1].legend(fontsize=7)
    axes[1].grid(alpha=0.3)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    _save(fig, path)


# ---------------------------------------------------------------------------------------------
# Markdown
# ---------------------------------------------------------------------------------------------
def write_report(diagnosis, folder: str | Path, title: str = "Sim-to-real gap diagnosis") -> Path:
    """Write ``report.md`` and the figures into ``folder`` (created if needed); return the report path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    result = diagnosis.as_dict()
    figures = []
    if len(diagnosis.problem.predictor.eigen):
        plot_eigenvalues(diagnosis, folder / "eigenvalues.png")
        figures.append(("eigenvalues.png", "Measured and predicted weave eigenvalues"))
        plot_effects(diagnosis, folder / "effects.png")
        figures.append(("effects.png", "Every candidate as fitted, on its own"))
    if len(diagnosis.problem.predictor.canonical):
        plot_canonical(diagnosis, folder / "canonical.png")
        figures.append(("canonical.png", "Identified canonical entries"))
    plot_gap_map(result, folder / "gap_map.png")
    figures.append(("gap_map.png", "Gap map"))
    if result["ranking"]:
        plot_ranking(result, folder / "ranking.png")
        figures.append(("ranking.png", "Held-out ranking"))
    plot_time_response(diagnosis, folder / "time_response.png")
    figures.append(("time_response.png", "Time response"))
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
    md += ["## Candidates", "", "| effect | what it is |", "|---|---|"]
    md += [f"| {e.name} | {e.description} |" for e in EFFECTS.values()]
    md += [""]
    for name, caption in figures:
        md += [f"## {caption}", "", f"![{caption}]({name})", ""]
    from bikerider.io.atomic import atomic_write_text

    path = folder / "report.md"
    atomic_write_text(path, "\n".join(md))
    return path
