"""Eigenvalues against speed, as Meijaard et al. (2007) Fig. 3 and Moore et al. (2009) Fig. 5 draw them.

One line per tracked mode (:func:`bikerider.benchmark.mode_shapes.mode_shapes`): real parts solid,
imaginary parts dashed (or on a second axes), the self-stable speed intervals shaded, the weave and
capsize speeds marked, an optional first-order uncertainty band, the legend outside the data.
Nothing is clipped silently: where a line leaves the vertical range a marker sits on the axis edge
and a note beside the legend says which mode, from which speed and how far it goes.
"""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from bikerider.benchmark.mode_shapes import ModeShapes, mode_shapes
from bikerider.benchmark.model import ModalEigenvalues, WhippleModel
from bikerider.plotting.common import CYCLE, MODE_COLOURS, STABLE_SHADE, legend_outside, new_figure

DEFAULT_SPEEDS = np.linspace(0.0, 10.0, 401)
"""Speeds of the figures when none are given [m/s]."""
_COMPLEX = 1e-9


def speed_grid(speeds=None, n: int = 401) -> np.ndarray:
    """A fine grid over the range of ``speeds`` (0-10 m/s when None or a single speed)."""
    if speeds is None:
        return DEFAULT_SPEEDS
    v = np.asarray(speeds, dtype=float)
    lo, hi = float(v.min()), float(v.max())
    return DEFAULT_SPEEDS if hi <= lo else np.linspace(lo, hi, n)


def _lines(shapes: ModeShapes):
    """``(name, column, real, imag)`` per tracked column; ``imag`` NaN where the eigenvalue is real."""
    names = tuple(shapes.names)
    for k, name in enumerate(names):
        z = shapes.eigenvalues[:, k]
        complex_ = np.abs(z.imag) > _COMPLEX * np.maximum(1.0, np.abs(z))
        imag = np.where(complex_, np.abs(z.imag), np.nan)
        yield name, k, z.real, imag


def auto_limits(shapes: ModeShapes, uncertainty=None) -> tuple[float, float]:
    """Vertical range that shows the weave and capsize modes whole, with their uncertainty bands
    when given (the castor mode, much faster, may leave it)."""
    keep = [line for line in _lines(shapes) if line[0] in ("weave", "capsize")] or list(_lines(shapes))
    values = np.concatenate([np.r_[real, imag] for _, _, real, imag in keep])
    if uncertainty is not None:
        s = uncertainty.sensitivity
        mine = np.isin(np.asarray(s.labels), ("weave", "capsize"))
        z, sr, si = np.asarray(s.values)[mine], uncertainty.sigma_real[mine], uncertainty.sigma_imag[mine]
        values = np.r_[values, z.real + sr, z.real - sr, np.abs(z.imag) + si]
    values = values[np.isfinite(values)]
    hi = max(float(values.max()), 1.0)
    lo = min(float(values.min()), -hi)  # as far below zero as above: the castor mode's start shows
    pad = 0.06 * (hi - lo)
    return lo - pad, hi + pad


def plot_eigenvalues(
    ax,
    model: WhippleModel,
    speeds=None,
    *,
    imag_ax=None,
    shapes: ModeShapes | None = None,
    uncertainty=None,
    ylim="auto",
    color: str | None = None,
    label: str | None = None,
    shade: bool = True,
    critical: bool = True,
    legend: bool = True,
    notes: bool = True,
):
    """Draw the eigenvalues of one bicycle against speed on ``ax``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw (real parts, and imaginary parts unless ``imag_ax`` is given).
    model : WhippleModel or ClosedLoopModel
        One bicycle (under a control law: :func:`bikerider.closed_loop`).
    speeds : array_like, optional
        The speed range (a fine grid over its extent is used); 0-10 m/s by default.
    imag_ax : matplotlib.axes.Axes, optional
        A second axes for the imaginary parts (a two-panel figure).
    shapes : ModeShapes, optional
        Tracked eigenvalues already computed (their speeds are used as they are).
    uncertainty : bikerider.uncertainty.propagation.EigenvalueUncertainty, optional
        First-order sigmas of the eigenvalues (``estimate_uncertainty(result, speeds).eigenvalues``):
        drawn as a band of one sigma around each mode.
    ylim : "auto", "all" or (float, float)
        Vertical range of ``ax``: ``"auto"`` shows the weave and capsize modes whole (see
        :func:`auto_limits`), ``"all"`` every line, or a given range.  Lines that leave the range
        are marked on the edge and described in a note.
    color : str, optional
        One colour for every mode (to compare bicycles on one axes); modes are then told apart by
        line width and the legend labels carry ``label``.
    label : str, optional
        Prefix of the legend labels (the bicycle's name when comparing).
    shade, critical, legend, notes : bool
        Shade the self-stable intervals, mark the weave and capsize speeds, draw the legend outside
        the axes, write the clipping notes.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``.
    """
    if shapes is None:
        shapes = mode_shapes(model, speed_grid(speeds))
    v = shapes.speeds
    prefix = f"{label}: " if label else ""
    imag_target = imag_ax if imag_ax is not None else ax
    drawn_imag = set()
    for name, k, real, imag in _lines(shapes):
        colour = color or MODE_COLOURS.get(name, MODE_COLOURS["other"])
        width = 1.6 if name == "weave" or color is None else (1.0 if name == "capsize" else 0.7)
        first = k == tuple(shapes.names).index(name)
        ax.plot(v, real, "-", color=colour, lw=width, label=f"{prefix}{name}, real part" if first else None)
        if np.isfinite(imag).any() and name not in drawn_imag:
            imag_target.plot(v, imag, "--", color=colour, lw=width, label=f"{prefix}{name}, imaginary part")
            drawn_imag.add(name)
    if uncertainty is not None:
        _band(ax, imag_target, uncertainty, color)
    stability = model.stability()
    stable_word = "self-stable" if isinstance(model, WhippleModel) else "stable under the law"  # a closed loop
    for target in {id(ax): ax, id(imag_target): imag_target}.values():
        target.axhline(0.0, color="0.3", lw=0.6, zorder=0)
        target.set_xlim(v[0], v[-1])
        if shade:
            for k, interval in enumerate(stability.intervals):
                lo, hi = max(interval.lower, v[0]), min(interval.upper, v[-1])
                if hi > lo:
                    target.axvspan(
                        lo,
                        hi,
                        color=STABLE_SHADE,
                        zorder=-1,
                        label=f"{prefix}{stable_word}" if k == 0 and target is ax else None,
                    )
        if critical:
            marks = ((stability.weave, "weave", (0, (1, 1.5))), (stability.capsize, "capsize", (0, (4, 2))))
            for value, name, style in marks:
                if value is not None and v[0] <= value <= v[-1]:
                    target.axvline(
                        value,
                        color=color or MODE_COLOURS[name],
                        lw=0.9,
                        ls=style,
                        label=f"{prefix}{name} speed {value:.2f} m/s" if target is ax else None,
                    )
    if imag_ax is None:
        ax.set_xlabel("speed $v$ [m/s]")
    ax.set_ylabel("eigenvalue, real and imaginary parts [1/s]" if imag_ax is None else "real part [1/s]")
    if imag_ax is not None:
        imag_ax.set_xlabel("speed $v$ [m/s]")
        imag_ax.set_ylabel("imaginary part [1/s]")
        imag_ax.set_ylim(bottom=0)
    limits = (
        auto_limits(shapes, uncertainty)
        if isinstance(ylim, str) and ylim == "auto"
        else None
        if isinstance(ylim, str)
        else ylim
    )
    clipped = _limit(ax, shapes, limits, imag_ax is None, color) if limits is not None else []
    notes_text = ["marked on the edge:"] + clipped if notes and clipped else []
    if legend:
        legend_outside(ax, notes=notes_text)
        if imag_ax is not None:
            legend_outside(imag_ax)
    elif notes_text:
        ax.text(
            1.02,
            0.0,
            "\n".join(notes_text),
            transform=ax.transAxes,
            ha="left",
            va="bottom",
            fontsize=7,
            style="italic",
            color="0.25",
        )
    return ax


def _limit(ax, shapes: ModeShapes, limits, with_imag: bool, color) -> list[str]:
    """Set the vertical range; mark and describe every mode whose line leaves it."""
    lo, hi = limits
    ax.set_ylim(lo, hi)
    v = shapes.speeds
    by_mode: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for name, _, real, imag in _lines(shapes):
        by_mode.setdefault(name, []).append((real, imag))
    notes = []
    for name, lines in by_mode.items():
        parts = [("real", np.vstack([real for real, _ in lines]))]
        if with_imag:
            parts.append(("imaginary", np.vstack([imag for _, imag in lines])))
        for part, values in parts:
            for side, edge in (("below", lo), ("above", hi)):
                with np.errstate(invalid="ignore"):
                    outside = np.any(values < lo if side == "below" else values > hi, axis=0)
                if not outside.any():
                    continue
                start = int(np.argmax(outside))
                column = np.nanmin(values, axis=0) if side == "below" else np.nanmax(values, axis=0)
                extreme = int(np.nanargmin(column) if side == "below" else np.nanargmax(column))
                ax.plot(
                    [v[start]],
                    [edge],
                    marker="v" if side == "below" else "^",
                    ms=5,
                    clip_on=False,
                    color=color or MODE_COLOURS.get(name, "0.5"),
                    zorder=5,
                )
                notes.append(
                    f"{name} {part} part {side} the axes\nfrom {v[start]:.1f} m/s on "
                    f"(to {column[extreme]:.3g} 1/s at {v[extreme]:.1f} m/s)"
                )
    return notes


def _band(ax, imag_ax, uncertainty, color) -> None:
    """One-sigma bands of ``EigenvalueUncertainty`` around each mode."""
    s = uncertainty.sensitivity
    speeds, values, labels = np.asarray(s.speeds), np.asarray(s.values), np.asarray(s.labels)
    first = True
    for name in ("weave", "capsize", "castor"):
        for k in range(values.shape[1]):
            mine = (labels[:, k] == name) & ((values[:, k].imag >= 0) if name == "weave" else True)
            if mine.sum() < 2:
                continue
            x = speeds[mine]
            z = values[mine, k]
            colour = color or MODE_COLOURS[name]
            sr, si = uncertainty.sigma_real[mine, k], uncertainty.sigma_imag[mine, k]
            ok = np.isfinite(sr)
            ax.fill_between(
                x[ok],
                (z.real - sr)[ok],
                (z.real + sr)[ok],
                color=colour,
                alpha=0.22,
                lw=0,
                label="one standard uncertainty (first order)" if first else None,
            )
            first = False
            if name == "weave" and np.any(np.abs(z.imag) > 0):
                ok = np.isfinite(si) & (np.abs(z.imag) > 0)
                imag_ax.fill_between(
                    x[ok], (np.abs(z.imag) - si)[ok], (np.abs(z.imag) + si)[ok], color=colour, alpha=0.22, lw=0
                )


def eigenvalue_figure(
    model: WhippleModel, speeds=None, title: str = "", *, uncertainty=None, two_panel: bool = False, ylim="auto"
):
    """A figure of :func:`plot_eigenvalues` (``speeds`` may be a :class:`ModalEigenvalues`, whose
    speed range is used)."""
    if isinstance(speeds, ModalEigenvalues):
        speeds = speeds.speeds
    if two_panel:
        fig, (ax, imag_ax) = new_figure(height=5.0, nrows=2, sharex=True)
    else:
        fig, ax = new_figure()
        imag_ax = None
    fig.subplots_adjust(left=0.08, right=0.66, bottom=0.13, top=0.92)
    plot_eigenvalues(ax, model, speeds, imag_ax=imag_ax, uncertainty=uncertainty, ylim=ylim)
    if title:
        ax.set_title(title, loc="left")
    return fig


COMPARISON_STYLES = {"weave": "-", "capsize": "--", "castor": ":", "other": "-."}
"""Line style of each mode's real part when several bicycles share an axes."""


def plot_eigenvalue_comparison(
    ax, models: dict[str, WhippleModel], speeds=None, *, imag_ax=None, bar_ax=None, ylim="auto"
):
    """Several bicycles on one axes: real parts (one colour per bicycle, one line style per mode),
    the weave frequency on ``imag_ax`` and the self-stable intervals as bars on ``bar_ax``.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``.
    """
    grid = speed_grid(speeds)
    every = {name: mode_shapes(model, grid) for name, model in models.items()}
    handles, labels = [], []
    for n, (name, shapes) in enumerate(every.items()):
        colour = CYCLE[n % len(CYCLE)]
        for mode, _, real, imag in _lines(shapes):
            ax.plot(grid, real, COMPARISON_STYLES.get(mode, "-"), color=colour, lw=1.3 if mode == "weave" else 1.0)
            if imag_ax is not None and mode == "weave":
                imag_ax.plot(grid, imag, "-", color=colour, lw=1.3)
        handles.append(Line2D([], [], color=colour, lw=2))
        labels.append(name)
        if bar_ax is not None:
            for interval in models[name].stability().intervals:
                bar_ax.plot(
                    [interval.lower, min(interval.upper, grid[-1])], [n, n], color=colour, lw=4, solid_capstyle="butt"
                )
    for target in (ax, imag_ax, bar_ax):
        if target is not None:
            target.set_xlim(grid[0], grid[-1])
    ax.axhline(0.0, color="0.3", lw=0.6, zorder=0)
    ax.set_ylabel("real part [1/s]")
    clipped = []
    if ylim is not None:
        if isinstance(ylim, str):
            reals = np.concatenate(
                [
                    real
                    for shapes in every.values()
                    for mode, _, real, _ in _lines(shapes)
                    if mode in ("weave", "capsize")
                ]
            )
            top = max(float(np.nanmax(np.abs(reals))), 1.0) * 1.08
            ylim = (-top, top)
        for name, shapes in every.items():
            clipped += [f"{name}: {note}" for note in _limit(ax, shapes, ylim, False, "0.4")]
    modes = [Line2D([], [], color="0.2", ls=COMPARISON_STYLES[m]) for m in ("weave", "capsize", "castor")]
    legend_outside(ax, handles + modes, labels + ["weave", "capsize", "castor"], title="bicycle; mode (real parts)")
    if clipped:
        target = imag_ax if imag_ax is not None else ax
        target.text(
            1.02,
            1.0,
            "marked on the edge:\n" + "\n".join(clipped),
            transform=target.transAxes,
            ha="left",
            va="top",
            fontsize=7,
            style="italic",
            color="0.25",
        )
    if imag_ax is not None:
        imag_ax.set_ylabel("weave frequency,\nimaginary part [1/s]")
        imag_ax.set_ylim(bottom=0)
    if bar_ax is not None:
        bar_ax.set_yticks(range(len(models)), labels)
        bar_ax.set_ylim(len(models) - 0.5, -0.5)
        bar_ax.set_ylabel("self-stable")
        bar_ax.spines["left"].set_visible(False)
        bar_ax.tick_params(axis="y", length=0)
    (bar_ax or imag_ax or ax).set_xlabel("speed $v$ [m/s]")
    return ax


def eigenvalue_comparison_figure(models: dict[str, WhippleModel], speeds=None, title: str = ""):
    """A figure of :func:`plot_eigenvalue_comparison`: real parts, weave frequency, stable intervals."""
    fig, (ax, imag_ax, bar_ax) = new_figure(
        height=5.6, nrows=3, sharex=True, gridspec_kw={"height_ratios": (3.0, 1.6, 0.25 + 0.22 * len(models))}
    )
    fig.subplots_adjust(left=0.1, right=0.7, hspace=0.12, top=0.94, bottom=0.09)
    plot_eigenvalue_comparison(ax, models, speeds, imag_ax=imag_ax, bar_ax=bar_ax)
    if title:
        ax.set_title(title, loc="left")
    fig.align_ylabels()
    return fig


__all__ = [
    "auto_limits",
    "eigenvalue_comparison_figure",
    "eigenvalue_figure",
    "plot_eigenvalue_comparison",
    "plot_eigenvalues",
    "speed_grid",
]
