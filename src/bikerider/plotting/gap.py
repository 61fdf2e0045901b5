"""Figures of a gap diagnosis (matplotlib, Agg backend, the house style of :mod:`bikerider.plotting.common`).

The figure functions return matplotlib figures; :func:`bikerider.diagnose.write_report` writes them
with ``report.md`` (:func:`bikerider.gap.text.markdown`) into a folder:

``records.png`` (then ``records_2.png``, ... with more than :data:`RECORDS_PER_PAGE` records)
    a contact sheet of the records: each record's roll rate with its fitted decay, the model's
    own response from the record's initial state (selected effects, or the nominal model), and
    the reason of every record left out (shortened to fit its panel; in full in ``report.md``);
``eigenvalues.png``
    measured eigenvalues against speed (error bars: data uncertainty) and one predicted curve per
    control law, nominal (dashed) and with the selected effects (solid), labelled by the law's name;
``effects.png``
    the weave of every candidate (and the best pairs) as fitted, each on its own;
``gap_map.png``, ``ranking.png``, ``time_response.png``, ``canonical.png``.

:func:`plot_effect` draws any effect model on its own (eigenvalues against speed and a time
response) for users exploring a candidate.
"""

from __future__ import annotations

import math
import textwrap

import numpy as np
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from bikerider.benchmark.model import label_modes
from bikerider.errors import FitError
from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.candidates.effects import SPEED_SENSOR, STEER_DAMPING, STEER_FRICTION
from bikerider.gap.inference.timedomain import (
    OBSERVED,
    Layout,
    closed_loop,
    friction_states,
    initial_states,
    make_batches,
    simulate_friction,
    simulate_linear,
    systems,
)
from bikerider.gap.measured.repair import repair_tags
from bikerider.plotting.common import pyplot
from bikerider.plotting.gap_multisine import plot_multisines


# ---------------------------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------------------------
def _speed_grid(diagnosis) -> np.ndarray:
    speeds = diagnosis.problem.obs.speed
    lo, hi = float(np.min(speeds)), float(np.max(speeds))
    pad = 0.1 * max(hi - lo, 1.0)
    return np.linspace(max(lo - pad, 0.3), hi + pad, 80)


def weave_curve(model, speeds: np.ndarray, law, reference_model, speed_scale: float = 1.0) -> np.ndarray:
    """Weave eigenvalue of ``model`` along the recorded ``speeds`` under a control law.

    The law's gains are those at the recorded speed; the model runs at ``speed_scale`` times it.
    Matched to ``reference_model``'s weave (the nominal model under the same law).
    """

    gains = law(speeds)
    ref, _ = label_modes(reference_model.eigenvalues(speeds, gains))
    ev = model.eigenvalues(speeds * speed_scale, gains)
    scale = 1e-9 * np.maximum(1.0, np.abs(ev).max(axis=-1, keepdims=True))
    ok = ev.imag > scale
    dist = np.abs(ev - ref[:, :1]) + 1e6 * ~ok
    pick = np.argmin(dist, axis=-1)
    out = np.take_along_axis(ev, pick[..., None], axis=-1)[..., 0]
    none = ~np.any(ok, axis=-1)
    return np.where(none, np.nan + 1j * np.nan, out)


def parameter_band(problem, speeds: np.ndarray, law, reference_model) -> np.ndarray:
    """Standard uncertainty of the nominal weave along ``speeds`` from the parameters' (first order).

    Returns ``(S,)`` complex: the real part's uncertainty plus i times the imaginary part's.
    """

    if not problem.free:
        return np.zeros(speeds.size, complex)
    n = len(problem.free)
    steps = np.concatenate([np.diag(problem.free_sigma), -np.diag(problem.free_sigma)])
    curves = weave_curve(EffectModel(problem._values_batch(steps), problem.geometry), speeds, law, reference_model)
    half = (curves[:n] - curves[n:]) / 2
    return np.sqrt(np.nansum(half.real**2, axis=0)) + 1j * np.sqrt(np.nansum(half.imag**2, axis=0))


def _colours(plt) -> list[str]:
    return plt.rcParams["axes.prop_cycle"].by_key()["color"]


def _selected_model(diagnosis):
    """``(model, speed_scale, label)`` of the selection's full fit (the linear part), or ``None``."""
    fit = diagnosis.selected_fit
    if fit is None:
        return None
    p = diagnosis.problem
    scale = fit.config.get(SPEED_SENSOR, {}).get("speed_scale", 1.0)
    if STEER_FRICTION in fit.effects:
        c = fit.config[STEER_FRICTION]["c_viscous"]
        linear = {e: v for e, v in fit.config.items() if e not in (STEER_FRICTION, SPEED_SENSOR)}
        model = EffectModel(p.nominal, p.geometry, {STEER_DAMPING: {"c_steer": c}, **linear})
        return model, scale, f"{'+'.join(fit.effects)} without its Coulomb friction (viscous c = {c:.3g} N m s/rad)"
    return p.fitted_model(fit), scale, "with " + "+".join(diagnosis.selected)


def plot_eigenvalues(diagnosis):
    """Measured and predicted weave against speed, one curve per control law (module docstring)."""
    plt = pyplot()

    p = diagnosis.problem
    e = p.predictor.eigen
    if not len(e):
        return None
    grid = _speed_grid(diagnosis)
    nominal = EffectModel(p.nominal, p.geometry)
    chosen = _selected_model(diagnosis)
    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4.4), sharex=True)
    colours = _colours(plt)
    weave_rows = [i for i in range(len(e)) if e.mode[i] == "weave"]
    sig = {
        "real": np.sqrt(
            p.var_data[
                [
                    k
                    for k, q in enumerate(p.obs.quantity)
                    if q == "real" and p.obs.kind[k] == "eigenvalue" and p.obs.mode[k] == "weave"
                ]
            ]
        ),
        "imag": np.sqrt(p.var_data[[k for k, q in enumerate(p.obs.quantity) if q == "imag"]]),
    }
    laws = list(dict.fromkeys(e.law[i] for i in weave_rows))
    shown = diagnosis.shown_values()
    apparent = diagnosis.selected_predictions()
    for k, name in enumerate(laws):
        law = e.laws[name]
        colour = colours[k % len(colours)]
        before = weave_curve(nominal, grid, law, nominal)
        band = parameter_band(p, grid, law, nominal)
        axes[0].plot(grid, before.real, "--", color=colour, lw=1.2, label=f"{name}: nominal model")
        axes[1].plot(grid, before.imag, "--", color=colour, lw=1.2)
        if np.any(band != 0):
            axes[0].fill_between(
                grid,
                before.real - band.real,
                before.real + band.real,
                color=colour,
                alpha=0.12,
                lw=0,
                label=f"{name}: nominal, 1 sigma of the parameters",
            )
            axes[1].fill_between(grid, before.imag - band.imag, before.imag + band.imag, color=colour, alpha=0.12, lw=0)
        if chosen is not None:
            model, scale, label = chosen
            after = weave_curve(model, grid, law, nominal, scale)
            axes[0].plot(grid, after.real, "-", color=colour, lw=1.8, label=f"{name}: {label}")
            axes[1].plot(grid, after.imag, "-", color=colour, lw=1.8)
        rows = [j for j, i in enumerate(weave_rows) if e.law[i] == name]
        idx = [weave_rows[j] for j in rows]
        what = "measured, nominal extraction bias removed" if diagnosis.record_rows else "measured"
        axes[0].errorbar(
            e.speed[idx],
            shown.real[idx],
            yerr=sig["real"][rows],
            fmt="o",
            ms=3.5,
            color=colour,
            capsize=2,
            alpha=0.8,
            label=f"{name}: {what} ({len(idx)})",
        )
        if apparent is not None and np.any(np.isfinite(apparent[idx])):
            axes[0].plot(
                e.speed[idx],
                apparent[idx].real,
                "x",
                color="k",
                ms=5,
                mew=1,
                label=f"{name}: {'+'.join(diagnosis.selected)} as fitted, per record",
            )
            axes[1].plot(e.speed[idx], apparent[idx].imag, "x", color="k", ms=5, mew=1)
        axes[1].errorbar(
            e.speed[idx], shown.imag[idx], yerr=sig["imag"][rows], fmt="o", ms=3.5, color=colour, capsize=2, alpha=0.8
        )
    axes[0].axhline(0, color="0.6", lw=0.8)
    axes[0].set_ylabel("weave real part [1/s]")
    axes[1].set_ylabel("weave imaginary part [rad/s]")
    for ax in axes:
        ax.set_xlabel("speed [m/s]")
        ax.grid(alpha=0.3)
    verdict = f"verdict {diagnosis.verdict}; selected: {'+'.join(diagnosis.selected) or 'nothing'}"
    fig.suptitle(
        f"Weave eigenvalue against speed, measured (points, 1 sigma) and predicted per control law ({verdict})",
        fontsize=9,
    )
    # the legend below both panels: inside one (loc="best") it hid measured points wherever they filled the panel
    # (the steer-by-wire decays at 1.5 m/s)
    handles, labels = axes[0].get_legend_handles_labels()
    legend = fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=7, frameon=False)
    below = legend.get_window_extent().height / fig.bbox.height  # measured by the figure's renderer, no drawing
    fig.tight_layout(rect=(0.0, below + 0.01, 1.0, 1.0))
    return fig


RECORDS_PER_PAGE = 20
"""Panels on one page of the records' contact sheet (``records.png``, ``records_2.png``, ...)."""
SHEET_COLUMNS = 4
"""Panels across one page of the contact sheet."""
_PANEL = (2.9, 2.1)
"""Size of one panel of the contact sheet [in] (axes, its title and tick labels)."""
_SHEET_TEXT = 8.0
"""Size of the ticks and notes of the contact sheet [pt]: readable at the report's 110 dpi."""


def plot_records(diagnosis, columns: int = SHEET_COLUMNS, per_page: int = RECORDS_PER_PAGE) -> list:
    """Contact sheet: every record's roll rate, its fitted decay and the model's response.

    Returns one figure per page of at most ``per_page`` records (an empty list without records).
    """
    fits = diagnosis.records
    if not fits:
        return []
    responses, model_label = _record_responses(diagnosis)
    return record_sheets(fits, responses, model_label, columns=columns, per_page=per_page)


def _record_responses(diagnosis) -> tuple[dict, str]:
    """The model's roll rate from every used record's initial state (by record index) and its label."""
    fits = diagnosis.records
    chosen = _selected_model(diagnosis)
    p = diagnosis.problem
    if chosen is not None:
        model, model_label = chosen[0], chosen[2]
    else:
        model, model_label = EffectModel(p.nominal, p.geometry), "nominal model"
    responses = {}
    used = [k for k, f in enumerate(fits) if f.used]
    fit = diagnosis.selected_fit
    timed = fit is not None and STEER_FRICTION in fit.effects
    if timed:
        model_label = (
            "+".join(fit.effects) + " (" + ", ".join(f"{n} {v:.3g}" for n, v in zip(fit.names, fit.values)) + ")"
        )
    try:
        records = [fits[k].record for k in used]
        for idx, batch in make_batches(records, max_duration=math.inf):
            if timed:
                layout = Layout.of(fit.effects)
                A, b, outputs, T = systems(p.nominal, p.geometry, batch.records, layout, fit.values)
                states = friction_states(batch, A, b, outputs, T)[0][0]
            else:
                A, _, outputs = closed_loop(model, batch.records)
                states = simulate_linear(A, initial_states(batch, A, outputs), batch.dt, batch.N)
            for j, k in enumerate(idx):
                L = batch.length[j]
                responses[used[k]] = states[j, :L, outputs[OBSERVED["roll_rate"]]]
    except FitError:  # records not uniformly sampled: the sheet is still useful without the model's response
        responses = {}
    return responses, model_label


def record_sheets(
    fits, responses: dict, model_label: str, columns: int = SHEET_COLUMNS, per_page: int = RECORDS_PER_PAGE
) -> list:
    """The pages of the contact sheet of ``fits`` (record fits), ``per_page`` panels each.

    ``responses`` maps a record's index to the model's roll rate from its initial state.  A page has
    ``columns`` panels across (fewer when there are fewer records) and only the rows it needs; the
    explanation of a record left out is wrapped (and if need be shortened) to stay inside its panel:
    the full reason is in ``report.md`` and the JSON result.
    """
    plt = pyplot()
    repaired = any(f.record.raw is not None for f in fits)
    pages = []
    for start in range(0, len(fits), per_page):
        page = list(enumerate(fits))[start : start + per_page]
        pages.append(_record_page(plt, page, responses, model_label, min(columns, len(fits)), repaired))
    return pages


def _record_page(plt, page, responses: dict, model_label: str, columns: int, repaired: bool):
    """One page of the contact sheet: the panels of ``page`` (``(index, fit)`` pairs) and the key."""
    rows = math.ceil(len(page) / columns)
    width, height = _PANEL
    if columns <= 2:  # a few records: larger panels, not a thin strip
        width, height = 3.6, 2.6
    handles = [
        plt.Line2D([], [], color="k", lw=0.8),
        plt.Line2D([], [], color="tab:red", lw=1.2),
        plt.Line2D([], [], color="tab:blue", ls="--", lw=1),
    ]
    labels = [
        "measured roll rate [rad/s] against time [s]",
        "fitted decay (weave + slow mode)",
        f"{model_label}, from the record's initial state",
    ]
    if repaired:
        handles.append(plt.Line2D([], [], ls="", marker=".", color="tab:orange"))
        labels.append("samples as recorded (repaired records)")
    fig, axes = plt.subplots(rows, columns, figsize=(width * columns, height * rows + 0.5), squeeze=False)
    for ax in axes.flat[len(page) :]:
        ax.axis("off")
    notes = []
    for ax, (k, f) in zip(axes.flat, page):
        notes += _record_panel(ax, k, f, responses)
    for _, note in notes:  # fitted inside its axes after the layout: it must not shape the layout
        note.set_in_layout(False)
    ncol = 1 if width * columns < 6 else 2
    chars = int(width * columns * 72 / (0.6 * _SHEET_TEXT) / ncol) - 6  # a label's room (0.6 em a character)
    labels = [textwrap.fill(label, chars) for label in labels]
    legend = fig.legend(handles, labels, loc="upper center", ncol=ncol, fontsize=_SHEET_TEXT)
    renderer = fig.canvas.get_renderer()
    key = legend.get_window_extent(renderer).height / fig.bbox.height
    fig.tight_layout(rect=(0, 0, 1, 1 - key - 0.01), h_pad=0.6)
    for ax, note in notes:
        _fit_inside(note, ax, renderer)
    return fig


def _record_panel(ax, k: int, f, responses: dict) -> list:
    """Draw record fit ``f`` (index ``k``) into ``ax``; return its notes to fit inside the axes."""
    r = f.record
    y = r.signals.get("roll_rate")
    notes = []
    if r.raw is not None:  # a repaired record: the samples as recorded, then the record the fits used
        ax.plot(r.raw[0], r.raw[1], ".", color="tab:orange", ms=1.4, zorder=1)
        note = ax.text(
            0.02,
            0.95 if not f.used else 0.04,
            "repaired: " + ", ".join(repair_tags(r.repairs)),
            transform=ax.transAxes,
            fontsize=_SHEET_TEXT - 1,
            va="top" if not f.used else "bottom",
            color="tab:orange",
        )
        notes.append((ax, note))
    ax.plot(r.time, y, color="k", lw=0.7)
    if f.used:
        est = f.estimate
        ax.plot(r.time, est.evaluate(r.time), color="tab:red", lw=1.1)
        if k in responses:
            resp = responses[k]
            offset = float(np.mean(y[: resp.size] - resp))
            ax.plot(r.time[: resp.size], resp + offset, "--", color="tab:blue", lw=0.9)
        ax.text(
            0.98,
            0.95,
            f"{est.eigenvalue.real:.2f}{est.eigenvalue.imag:+.2f}i\nr2 {est.r2:.2f}",
            transform=ax.transAxes,
            ha="right",
            va="top",
            fontsize=_SHEET_TEXT - 0.5,
        )
    else:
        ax.set_facecolor("0.93")
        note = ax.text(
            0.02,
            0.04,
            "left out: " + (f.reason or ""),
            transform=ax.transAxes,
            fontsize=_SHEET_TEXT - 1,
            va="bottom",
            color="tab:red",
            bbox={"facecolor": "0.93", "edgecolor": "none", "alpha": 0.8, "pad": 1},
        )
        notes.append((ax, note))
    ax.set_title(f"{_short(r.name)}  {r.speed:.2f} m/s", fontsize=_SHEET_TEXT + 0.5)
    ax.tick_params(labelsize=_SHEET_TEXT)
    ax.grid(alpha=0.25)
    return notes


def _fit_inside(note, ax, renderer) -> None:
    """Wrap ``note``'s text to the width of ``ax`` (measured), shortened with "..." to its height."""
    text = " ".join(note.get_text().split())
    box = ax.get_window_extent(renderer)
    room_w, room_h = 0.94 * box.width, 0.9 * box.height
    width = max(10, len(text))
    while True:
        lines = textwrap.wrap(text, width) or [""]
        note.set_text("\n".join(lines))
        extent = note.get_window_extent(renderer)
        if extent.width <= room_w or width <= 10:
            break
        width = max(10, int(width * room_w / extent.width) if extent.width > room_w * 1.05 else width - 1)
    while note.get_window_extent(renderer).height > room_h and len(lines) > 1:
        lines = lines[:-1]
        lines[-1] = lines[-1].rstrip(" .,;:") + " ..."
        note.set_text("\n".join(lines))


def _short(name: str) -> str:
    """A record's name without the common log-name clutter (``...5.4kph.log.gz[4486:4775]`` -> ``5.4kph[4486:4775]``)."""
    base, _, window = name.partition("[")
    base = base.removesuffix(".gz").removesuffix(".log").removesuffix(".csv")
    if "_" in base:
        base = base.rsplit("_", 1)[-1]
    return f"{base}[{window}" if window else base


def plot_gap_map(result: dict):
    """Signed RMS residual of every gap-map cell, over the combined uncertainty and over the data's alone."""
    plt = pyplot()
    cells = result["gap"]["map"]
    rows = list(dict.fromkeys(f"{c['mode']} {c['quantity']}" for c in cells))
    cols = list(dict.fromkeys(f"{c['speed_band'][0]:.1f}-{c['speed_band'][1]:.1f}" for c in cells))
    panels = [("rms_z", "combined uncertainty")]
    if all(c.get("rms_z_data") is not None for c in cells):
        panels.append(("rms_z_data", "the data's uncertainty alone"))
    fig, axes = plt.subplots(
        1,
        len(panels),
        figsize=(max(5, 1.2 * len(cols) + 3) * len(panels), max(2.6, 0.4 * len(rows) + 1.6)),
        squeeze=False,
    )
    for ax, (key, what) in zip(axes[0], panels):
        table = np.full((len(rows), len(cols)), np.nan)
        for c in cells:
            table[
                rows.index(f"{c['mode']} {c['quantity']}"),
                cols.index(f"{c['speed_band'][0]:.1f}-{c['speed_band'][1]:.1f}"),
            ] = np.sign(c["mean_residual"]) * c[key]
        limit = max(3.0, float(np.nanmax(np.abs(table)))) if np.any(np.isfinite(table)) else 3.0
        im = ax.imshow(table, cmap="RdBu_r", vmin=-limit, vmax=limit, aspect="auto")
        ax.set_xticks(range(len(cols)), cols, fontsize=7, rotation=30)
        ax.set_yticks(range(len(rows)), rows, fontsize=7)
        ax.set_xlabel("speed band [m/s]")
        for i in range(len(rows)):
            for j in range(len(cols)):
                if np.isfinite(table[i, j]):
                    ax.text(
                        j,
                        i,
                        f"{table[i, j]:.1f}",
                        ha="center",
                        va="center",
                        fontsize=7,
                        color="white" if abs(table[i, j]) > 0.6 * limit else "black",
                    )
        fig.colorbar(im, ax=ax, label="signed RMS z")
        ax.set_title(f"measured - model, over {what}", fontsize=8)
    fig.suptitle("Gap map: residuals by mode, quantity and speed band", fontsize=9)
    fig.tight_layout()
    return fig


def plot_ranking(result: dict):
    """Held-out errors of every candidate and the best pairs: over the combined uncertainty, and over the
    data's alone (where every row has one)."""
    plt = pyplot()
    entries = [
        (r["effect"], r["heldout_error_after"], r.get("data_error_after"), r["plausible"]) for r in result["ranking"]
    ]
    entries += [
        ("+".join(p["effects"]), p["heldout_error_after"], p.get("data_error_after"), p.get("plausible"))
        for p in result.get("pairs", [])[:6]
    ]
    if not entries:
        return None
    first = result["ranking"][0]
    floor = result.get("noise_floor_rms") or 1.0  # results stored before the floor was written: its mean
    panels = [("combined uncertainty", 1, first["heldout_error_before"])]
    if all(e[2] is not None for e in entries) and first.get("data_error_before") is not None:
        panels.append(("the data's uncertainty alone", 2, first["data_error_before"]))
    fig, axes = plt.subplots(
        1, len(panels), figsize=(5.2 * len(panels) + 1.5, 0.32 * len(entries) + 1.6), squeeze=False
    )
    colour = {True: "tab:green", False: "tab:orange", None: "0.7"}
    for ax, (what, col, before) in zip(axes[0], panels):
        # from the nominal model's error to the candidate's (a log axis has no zero for bars to start at)
        rows = np.arange(len(entries))
        values = np.array([e[col] for e in entries], dtype=float)
        colours = [colour[e[3]] for e in entries]
        ax.hlines(rows, before, values, colors=colours, lw=2.5)
        ax.scatter(values, rows, c=colours, s=28, zorder=3)
        ax.axvline(before, color="k", ls="--", label=f"nominal model ({before:.2f})")
        ax.axvline(floor, color="0.5", ls=":", label=f"noise floor ({floor:.2f}: chi-square 95 %)")
        ax.set_yticks(
            range(len(entries)), [e[0] for e in entries] if ax is axes[0][0] else [""] * len(entries), fontsize=7
        )
        ax.invert_yaxis()
        _decade_axis(ax, [*values[np.isfinite(values)], before, floor])
        ax.set_xlabel(f"held-out error: RMS residual over {what}", fontsize=8)
        ax.legend(fontsize=7)
    fig.suptitle(
        "Candidates and pairs fitted on training folds, scored on held-out folds: each line from the nominal "
        "model's error to the candidate's\n(green: usual values; orange: a value outside its usual range or not "
        "determined, flagged; grey: pair not judged)",
        fontsize=8,
    )
    fig.tight_layout()
    return fig


def _decade_axis(ax, values) -> None:
    """A log x axis over ``values`` (positive) spanning at least a decade, about their geometric
    middle, with plain numbers at 1, 2 and 5 times the powers of ten (``0.5``, not ``5x10^-1``)."""

    v = np.asarray([x for x in values if np.isfinite(x) and x > 0], dtype=float)
    lo, hi = (float(v.min()), float(v.max())) if v.size else (0.1, 10.0)
    lo, hi = lo / 1.15, hi * 1.15
    if hi / lo < 10.0:
        middle = math.sqrt(lo * hi)
        lo, hi = middle / math.sqrt(10.0), middle * math.sqrt(10.0)
    ax.set_xscale("log")
    ax.set_xlim(lo, hi)
    ax.xaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
    ax.xaxis.set_minor_locator(LogLocator(base=10.0, subs=np.arange(2, 10) * 1.0))
    ax.xaxis.set_minor_formatter(NullFormatter())


def plot_effects(diagnosis):
    """Every candidate as fitted to all the data, on its own (and the best pairs), under the main law.

    The nominal model is drawn last, on top (a candidate fitted at its nominal values lies under it
    and says so); the selection is drawn thick and, when it is a time-domain effect (steer friction,
    whose apparent eigenvalue depends on each record's amplitude), as its prediction of each record.
    """
    plt = pyplot()

    p = diagnosis.problem
    e = p.predictor.eigen
    if not len(e):
        return None
    grid = _speed_grid(diagnosis)
    nominal = EffectModel(p.nominal, p.geometry)
    main = max(set(e.law), key=e.law.count)
    law = e.laws[main]
    fig, axes = plt.subplots(1, 2, figsize=(14.0, 4.6), sharex=True, layout="constrained")
    base = weave_curve(nominal, grid, law, nominal)
    linear = [
        pr
        for pr in sorted(diagnosis.pairs, key=lambda r: r.error_after)
        if pr.effects in diagnosis.full_fits and STEER_FRICTION not in pr.effects
    ]
    sets = [(name,) for name in diagnosis.candidates if name != STEER_FRICTION] + [pr.effects for pr in linear[:2]]
    selected = tuple(diagnosis.selected)
    scale_of_base = max(float(np.nanmax(np.abs(base))), 1.0) if np.isfinite(base).any() else 1.0
    for effects in sets:
        fit = diagnosis.fit_of(effects)
        scale = fit.config.get(SPEED_SENSOR, {}).get("speed_scale", 1.0)
        plausible, _ = diagnosis.priors.plausibility(fit)
        curve = weave_curve(p.fitted_model(fit), grid, law, nominal, scale)
        at_nominal = bool(np.nanmax(np.abs(curve - base)) < 1e-3 * scale_of_base) if np.isfinite(curve).any() else False
        label = "+".join(effects) + ("" if plausible else " (unusual values)")
        if effects == selected:
            label += " (selected)"
        if at_nominal:
            label += ": fitted at the nominal, under its line"
        style = "-" if len(effects) == 1 else ":"
        lw = 2.4 if effects == selected else 1.4
        axes[0].plot(grid, curve.real, style, lw=lw, label=label)
        axes[1].plot(grid, curve.imag, style, lw=lw)
    rows = [i for i in range(len(e)) if e.law[i] == main and e.mode[i] == "weave"]
    shown = diagnosis.shown_values()
    what = "measured, nominal extraction bias removed" if diagnosis.record_rows else "measured"
    axes[0].plot(e.speed[rows], shown.real[rows], "k.", ms=3, label=f"{what} ({main})")
    axes[1].plot(e.speed[rows], shown.imag[rows], "k.", ms=3)
    apparent = diagnosis.selected_predictions() if selected and _time_domain_selection(selected) else None
    if apparent is not None and np.any(np.isfinite(apparent[rows])):
        label = f"{'+'.join(selected)} (selected, time domain): as fitted, per record"
        axes[0].plot(e.speed[rows], apparent[rows].real, "x", color="k", ms=5, mew=1, label=label)
        axes[1].plot(e.speed[rows], apparent[rows].imag, "x", color="k", ms=5, mew=1)
    # the nominal model last: on top of the candidates fitted at it
    axes[0].plot(grid, base.real, "k--", lw=1.6, zorder=5, label="nominal")
    axes[1].plot(grid, base.imag, "k--", lw=1.6, zorder=5)
    axes[0].set_ylabel("weave real part [1/s]")
    axes[1].set_ylabel("weave imaginary part [rad/s]")
    for ax in axes:
        ax.set_xlabel("speed [m/s]")
        ax.grid(alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    order = [labels.index("nominal")] + [k for k, lab in enumerate(labels) if lab != "nominal"]
    fig.legend(
        [handles[k] for k in order],
        [labels[k] for k in order],
        fontsize=7,
        loc="outside right center",
    )
    fig.suptitle(
        f"Every linear candidate fitted to all the data, on its own, and the best two linear pairs (dotted); "
        f"control law {main}",
        fontsize=9,
    )
    return fig


def _time_domain_selection(effects: tuple[str, ...]) -> bool:
    """Whether a selection is fitted in the time domain (steer friction: no eigenvalue curve)."""
    return STEER_FRICTION in effects


def plot_time_response(diagnosis):
    """Roll rate after a kick at the median speed: the nominal model and the selection (with its friction)."""
    plt = pyplot()

    p = diagnosis.problem
    e = p.predictor.eigen
    speed = float(np.median(p.obs.speed))
    law = e.laws[max(set(e.law), key=e.law.count)] if len(e) else None
    if law is None and getattr(diagnosis, "multisines", None):  # multisine records only: their law
        law = diagnosis.multisines[0].record.law
    gains = law(speed) if law is not None else None
    t = np.linspace(0, 3, 301)
    fig, ax = plt.subplots(figsize=(7, 3.2))
    nominal = EffectModel(p.nominal, p.geometry).simulate(speed, t, gains=gains)
    ax.plot(t, nominal["phid"], "k--", label="nominal")
    chosen = _selected_model(diagnosis)
    if chosen is not None:
        model, scale, label = chosen
        fit = diagnosis.selected_fit
        if STEER_FRICTION in fit.effects:
            ss = model.state_space([speed * scale])
            A = ss.closed_loop(None if gains is None else np.asarray(gains)[None, :])[0]
            x0 = np.zeros(A.shape[-1])
            x0[ss.output_states[2]] = 0.5
            T = fit.config[STEER_FRICTION]["T_coulomb"]
            states = simulate_friction(A, ss.B[0][:, 1], x0, T, t[1] - t[0], t.size, ss.output_states[3])
            ax.plot(
                t, states[:, ss.output_states[2]], label="+".join(fit.effects) + f" (Coulomb {T:.3g} N m, as fitted)"
            )
        else:
            sel = model.simulate(speed * scale, t, gains=gains)
            ax.plot(t, sel["phid"], label=label)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("roll rate [rad/s]")
    ax.set_title(
        f"Response to a 0.5 rad/s roll-rate kick at {speed:.1f} m/s"
        + (f", control law {law.name}" if law is not None and not law.is_zero else ", no control"),
        fontsize=9,
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def plot_canonical(diagnosis):
    plt = pyplot()
    p = diagnosis.problem
    obs = p.obs
    idx = [i for i, k in enumerate(obs.kind) if k == "canonical"]
    if not idx:
        return None
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
    return fig


def plot_effect(model, speeds, *, gains=None, speed: float | None = None, title: str = ""):
    """Eigenvalues against speed and a roll-rate time response of one :class:`EffectModel` (a figure)."""
    plt = pyplot()
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
    return fig


def figures(diagnosis, result: dict) -> list[tuple[str, str, object]]:
    """Every figure of a report: ``(file name, caption, figure)``, those that apply."""
    sheets = plot_records(diagnosis)
    out = [(_page_name(page), _page_caption(page, len(sheets)), fig) for page, fig in enumerate(sheets, start=1)]
    out += [
        ("eigenvalues.png", "Measured and predicted weave eigenvalues, per control law", plot_eigenvalues(diagnosis)),
        ("effects.png", "Every candidate as fitted, on its own", plot_effects(diagnosis)),
        ("canonical.png", "Identified canonical entries", plot_canonical(diagnosis)),
        ("gap_map.png", "Gap map", plot_gap_map(result)),
        ("ranking.png", "Held-out ranking", plot_ranking(result)),
        ("time_response.png", "Time response", plot_time_response(diagnosis)),
        ("multisines.png", "Multisine records: frequency responses at their lines", plot_multisines(diagnosis)),
    ]
    return [(name, caption, fig) for name, caption, fig in out if fig is not None]


def _page_name(page: int) -> str:
    """``records.png`` for the contact sheet's first page, ``records_2.png`` ... for the others."""
    return "records.png" if page == 1 else f"records_{page}.png"


def _page_caption(page: int, pages: int) -> str:
    """The caption of a page of the contact sheet (its number when there are several)."""
    caption = "Records and their fitted decays"
    return caption if pages == 1 else f"{caption} (page {page} of {pages})"
