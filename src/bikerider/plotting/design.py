"""Figures of a design-space run: self-stable fraction and stable-interval sensitivity against each
parameter, and two-dimensional stability maps (slices of a grid).

Angles are drawn in degrees (the store keeps radians).
"""

from __future__ import annotations

import math

import matplotlib.patches as mpatches
import numpy as np
from matplotlib.colors import ListedColormap

from bikerider.generated.symbol_table import SYMBOLS
from bikerider.plotting.common import MODE_COLOURS, WIDTH, new_figure

_NEVER = "////"
MAX_PANELS = 9
"""Parameters drawn at most; with more, those whose sensitivity indices are largest."""


def chosen_parameters(summary, limit: int = MAX_PANELS) -> tuple[list, str]:
    """The parameters to draw (all, or the ``limit`` with the largest first-order index of the weave
    or capsize speed, in the space's order) and a note saying which."""
    parameters = list(summary.parameters)
    if len(parameters) <= limit:
        return parameters, ""

    def weight(p) -> float:
        values = [v for v in (p.sensitivity["weave_speed"], p.sensitivity["capsize_speed"]) if np.isfinite(v)]
        return max(values, default=0.0)

    keep = sorted(sorted(parameters, key=weight, reverse=True)[:limit], key=parameters.index)
    return keep, f"the {limit} of {len(parameters)} parameters with the largest sensitivity indices"


def _unit(name: str) -> tuple[str, float]:
    """Axis unit and scale of a parameter (radians shown in degrees)."""
    unit = SYMBOLS.get(name, ("", "-", ""))[1]
    return ("deg", 180 / math.pi) if unit == "rad" else (unit, 1.0)


def axis_label(name: str) -> str:
    """``name [unit]`` (angles in degrees)."""
    unit, _ = _unit(name)
    return f"{name} [{unit}]"


def _scaled(name: str, values) -> np.ndarray:
    return np.asarray(values, dtype=float) * _unit(name)[1]


def _panels(n: int, height_each: float = 2.0):
    cols = min(3, n)
    rows = -(-n // cols)
    fig, axes = new_figure(
        width=WIDTH, height=height_each * rows + 0.4, nrows=rows, ncols=cols, squeeze=False, constrained_layout=True
    )
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    return fig, axes.ravel()[:n]


def plot_stable_fraction(ax, parameter, base: float | None = None):
    """Fraction of the valid designs that is self-stable, against one parameter's values (bins).

    Returns
    -------
    matplotlib.axes.Axes
    """
    x = _scaled(parameter.name, parameter.values)
    ax.plot(x, parameter.stable_fraction, color="k", marker="o" if x.size <= 25 else None, ms=3)
    invalid = parameter.valid < parameter.count
    if invalid.any():
        share = 1 - parameter.valid / np.maximum(parameter.count, 1)
        ax.plot(x, share, color="0.55", ls="--", lw=1.0, label="share of impossible designs")
    if base is not None and np.isfinite(base):
        ax.axvline(_scaled(parameter.name, base), color="0.3", lw=0.7, ls=":", label="base value")
    ax.set_ylim(0, 1.02)
    ax.set_xlim(x.min(), x.max()) if x.size > 1 else None
    ax.set_xlabel(axis_label(parameter.name))
    ax.set_ylabel("self-stable fraction")
    return ax


def stable_fraction_figure(summary, base: dict[str, float] | None = None, title: str = ""):
    """:func:`plot_stable_fraction` for every varied parameter (at most :data:`MAX_PANELS`)."""
    parameters, which = chosen_parameters(summary)
    fig, axes = _panels(len(parameters))
    for ax, p in zip(axes, parameters):
        plot_stable_fraction(ax, p, (base or {}).get(p.name))
    lo, hi = summary.speed_range
    note = (
        f"self-stable: a stable speed interval within {lo:g}-{hi:g} m/s; {summary.valid:,} of "
        f"{summary.designs:,} designs valid,\n{summary.stable / max(summary.valid, 1):.1%} of them self-stable"
        + (f"; {which}" if which else "")
    )
    fig.suptitle(f"{title}\n{note}" if title else note, x=0.01, ha="left", fontsize=9)
    handles, labels = axes[0].get_legend_handles_labels()
    for ax in axes[1:]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    if handles:
        fig.legend(handles, labels, loc="outside lower center", ncols=len(handles), fontsize=7)
    return fig


def plot_interval_sensitivity(ax, parameter, base: float | None = None):
    """Median and interquartile range (over the other parameters) of the weave and capsize speeds
    against one parameter; the title gives their first-order sensitivity indices.

    Returns
    -------
    matplotlib.axes.Axes
    """
    x = _scaled(parameter.name, parameter.values)
    for output, colour, label in (
        ("weave_speed", MODE_COLOURS["weave"], "weave speed"),
        ("capsize_speed", MODE_COLOURS["capsize"], "capsize speed"),
    ):
        q = parameter.quartiles[output]
        ax.plot(x, q[:, 1], color=colour, label=f"{label}: median")
        ax.fill_between(x, q[:, 0], q[:, 2], color=colour, alpha=0.18, lw=0, label=f"{label}: 25-75 %")
    if base is not None and np.isfinite(base):
        ax.axvline(_scaled(parameter.name, base), color="0.3", lw=0.7, ls=":", label="base value")
    sw, sc = parameter.sensitivity["weave_speed"], parameter.sensitivity["capsize_speed"]
    ax.set_title(f"S(weave) = {sw:.2f}, S(capsize) = {sc:.2f}", fontsize=8, loc="left")
    ax.set_xlabel(axis_label(parameter.name))
    ax.set_ylabel("speed [m/s]")
    ax.set_ylim(*summary_range(parameter))
    ax.set_xlim(x.min(), x.max()) if x.size > 1 else None
    return ax


def summary_range(parameter) -> tuple[float, float]:
    """Speed axis limits: the quartiles' span, from 0."""
    q = np.concatenate([parameter.quartiles[o].ravel() for o in ("weave_speed", "capsize_speed")])
    q = q[np.isfinite(q)]
    return (0.0, float(q.max()) * 1.08) if q.size else (0.0, 10.0)


def interval_sensitivity_figure(summary, base: dict[str, float] | None = None, title: str = ""):
    """:func:`plot_interval_sensitivity` for every varied parameter (at most :data:`MAX_PANELS`)."""
    parameters, which = chosen_parameters(summary)
    fig, axes = _panels(len(parameters), 2.2)
    for ax, p in zip(axes, parameters):
        plot_interval_sensitivity(ax, p, (base or {}).get(p.name))
    lo, hi = summary.speed_range
    note = (
        f"ends of the first self-stable interval (speeds within {lo:g}-{hi:g} m/s) over the other parameters;\n"
        "S: first-order sensitivity index, the share of a speed's variance the parameter explains alone"
        + (f";\n{which}" if which else "")
    )
    fig.suptitle(f"{title}\n{note}" if title else note, x=0.01, ha="left", fontsize=9)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=len(handles), fontsize=7)
    return fig


def _hatch_cells(ax, x, y, mask: np.ndarray, face: str, hatch: str | None = None) -> None:
    """Fill (and hatch) the grid cells where ``mask`` (shape (ny, nx)), aligned with a
    ``shading="nearest"`` mesh."""
    if mask.any():
        ax.pcolor(
            x,
            y,
            np.ma.masked_where(~mask, np.ones(mask.shape)),
            shading="nearest",
            cmap=ListedColormap([face]),
            hatch=hatch,
            edgecolor="0.45",
            linewidth=0.0,
        )


def plot_design_slice(ax, design_slice, colorbar: bool = True, legend: bool = True):
    """A stability map over two parameters of a grid: where the first self-stable interval begins
    (colour: the weave speed) and ends (contours: the capsize speed), designs never self-stable
    (hatched) or impossible (grey).

    Returns
    -------
    matplotlib.axes.Axes
    """
    (xn, xv), (yn, yv) = design_slice.x, design_slice.y
    x, y = _scaled(xn, xv), _scaled(yn, yv)
    lower = design_slice.lower[..., 0].T
    upper = design_slice.upper[..., 0].T
    valid = design_slice.valid.T
    never = valid & ~np.isfinite(lower)
    mesh = ax.pcolormesh(x, y, np.ma.masked_invalid(lower), shading="nearest", cmap="viridis")
    _hatch_cells(ax, x, y, never, "white", _NEVER)
    _hatch_cells(ax, x, y, ~valid, "0.8")
    finite_upper = np.where(np.isfinite(upper), upper, np.nan)
    if np.isfinite(finite_upper).sum() > 3 and x.size > 1 and y.size > 1:
        contours = ax.contour(x, y, finite_upper, colors="k", linewidths=0.6)
        ax.clabel(contours, fontsize=6, fmt="%.1f")
    base = design_slice.base
    where = base_on_slice(design_slice)
    if where is not None:
        # on the slice: the base design itself; off it: where its two values are, hollow
        face = "w" if where else "none"
        ax.plot(_scaled(xn, base[xn]), _scaled(yn, base[yn]), "*", mfc=face, ms=9, mec="k", mew=0.6)
    ax.set_xlabel(axis_label(xn))
    ax.set_ylabel(axis_label(yn))
    if colorbar:
        bar = ax.figure.colorbar(mesh, ax=ax, pad=0.02)
        bar.set_label("self-stable from [m/s] (weave speed)")
    if legend:
        ax.legend(
            handles=slice_legend_handles(ax, design_slice),
            loc="upper left",
            bbox_to_anchor=(0.0, -0.16),
            ncols=2,
            fontsize=7,
        )
    return ax


def base_on_slice(design_slice) -> bool | None:
    """Whether the slice holds the base design (every other parameter at its base value); False when
    it does not but the base's two values lie within the slice's axes (the star then marks only
    where they are); None when they lie outside or the base lacks one of them."""
    (xn, xv), (yn, yv) = design_slice.x, design_slice.y
    base = design_slice.base
    bx, by = base.get(xn, np.nan), base.get(yn, np.nan)
    if not (np.isfinite(bx) and np.isfinite(by)):
        return None
    if not (xv.min() <= bx <= xv.max() and yv.min() <= by <= yv.max()):
        return None
    return all(
        name in base and math.isclose(value, base[name], rel_tol=1e-9, abs_tol=1e-12)
        for name, value in design_slice.fixed.items()
    )


def _off_base(design_slice) -> str:
    """The base's values of the fixed parameters where the slice leaves them (``w = 1.02 m``)."""
    base = design_slice.base
    return ", ".join(
        f"{k} = {_scaled(k, base[k]):.4g} {_unit(k)[0]}"
        for k, v in design_slice.fixed.items()
        if k in base and not math.isclose(v, base[k], rel_tol=1e-9, abs_tol=1e-12)
    )


def slice_legend_handles(ax, design_slice=None) -> list:
    """The key of :func:`plot_design_slice`: an entry for what the slice shows (all four entries
    without ``design_slice``)."""
    handles = []
    if design_slice is None:
        never = impossible = contours = True
        where: bool | None = True
    else:
        valid = np.asarray(design_slice.valid, bool)
        lower, upper = design_slice.lower[..., 0], design_slice.upper[..., 0]
        never = bool((valid & ~np.isfinite(lower)).any())
        impossible = bool((~valid).any())
        contours = bool(np.isfinite(upper).sum() > 3 and lower.shape[0] > 1 and lower.shape[1] > 1)
        where = base_on_slice(design_slice)
    if never:
        handles.append(mpatches.Patch(facecolor="white", edgecolor="0.45", hatch=_NEVER, label="never self-stable"))
    if impossible:
        handles.append(mpatches.Patch(color="0.8", label="impossible design"))
    if contours:
        handles.append(ax.plot([], [], color="k", lw=0.6, label="self-stable up to [m/s] (capsize speed)")[0])
    if where:
        handles.append(ax.plot([], [], "w*", mec="k", ms=8, label="base design")[0])
    elif where is False:
        label = f"base design's values (the base is off this slice: {_off_base(design_slice)})"
        handles.append(ax.plot([], [], "*", mfc="none", mec="k", ms=8, label=label)[0])
    return handles


def plot_stable_speed_share(ax, design_slice, speeds, colorbar: bool = True):
    """Over two parameters of a grid: the share of the map speeds at which the design is self-stable.

    Returns
    -------
    matplotlib.axes.Axes
    """
    (xn, xv), (yn, yv) = design_slice.x, design_slice.y
    x, y = _scaled(xn, xv), _scaled(yn, yv)
    share = np.where(design_slice.valid, design_slice.stable_fraction, np.nan).T
    top = float(np.nanmax(share)) if np.isfinite(share).any() else 1.0
    top = min(1.0, max(0.1, np.ceil(top * 10) / 10))
    mesh = ax.pcolormesh(x, y, np.ma.masked_invalid(share), shading="nearest", cmap="Greens", vmin=0, vmax=top)
    _hatch_cells(ax, x, y, ~design_slice.valid.T, "0.8")
    ax.set_xlabel(axis_label(xn))
    ax.set_ylabel(axis_label(yn))
    if colorbar:
        v = np.asarray(speeds, dtype=float)
        bar = ax.figure.colorbar(mesh, ax=ax, pad=0.02)
        bar.set_label(f"share of {v.size} speeds {v.min():g}-{v.max():g} m/s self-stable" if v.size else "share")
    return ax


def design_slice_figure(design_slice, speeds=(), title: str = ""):
    """:func:`plot_design_slice` and, with map speeds, :func:`plot_stable_speed_share` beside it."""
    two = np.size(speeds) > 0
    fig, axes = new_figure(
        width=WIDTH if two else 5.6, height=4.6, ncols=2 if two else 1, squeeze=False, constrained_layout=True
    )
    plot_design_slice(axes[0, 0], design_slice, legend=False)
    if two:
        plot_stable_speed_share(axes[0, 1], design_slice, speeds)
    handles = slice_legend_handles(axes[0, 0], design_slice)
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 4), fontsize=7)
    fixed = ", ".join(f"{k} = {_scaled(k, v):.4g} {_unit(k)[0]}" for k, v in design_slice.fixed.items())
    heading = title + (f"\n{fixed}" if fixed else "")
    if heading:
        fig.suptitle(heading, x=0.01, ha="left", fontsize=9)
    return fig


__all__ = [
    "axis_label",
    "base_on_slice",
    "design_slice_figure",
    "interval_sensitivity_figure",
    "plot_design_slice",
    "plot_interval_sensitivity",
    "plot_stable_fraction",
    "plot_stable_speed_share",
    "stable_fraction_figure",
]
