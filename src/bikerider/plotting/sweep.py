"""Sweeps: the self-stable speeds against one parameter, and stability maps over two."""

from __future__ import annotations

import matplotlib.patches as mpatches
import numpy as np

from bikerider.benchmark.sweep import Sweep
from bikerider.plotting.common import MODE_COLOURS, STABLE_SHADE, legend_outside, new_figure

UNITS = {
    "w": "m",
    "c": "m",
    "lam": "deg",
    "g": "m/s^2",
    "rR": "m",
    "rF": "m",
    "xB": "m",
    "zB": "m",
    "xH": "m",
    "zH": "m",
    "mR": "kg",
    "mB": "kg",
    "mH": "kg",
    "mF": "kg",
}


ANGLES = frozenset({"lam"})
"""Parameters that are angles: radians in the sweep, shown in degrees (as they are given)."""


def _axis_label(name: str) -> str:
    return f"{name} [{UNITS.get(name, 'kg m^2' if name.startswith('I') else '-')}]"


def _shown(name: str, values):
    """Values of ``name`` as the axes show them (angles in degrees)."""
    return np.degrees(values) if name in ANGLES else np.asarray(values, dtype=float)


def _top(result: Sweep) -> float:
    finite = np.r_[
        result.stability.lower[np.isfinite(result.stability.lower)],
        result.stability.upper[np.isfinite(result.stability.upper)],
    ]
    if result.speeds.size:
        return float(result.speeds.max())
    return float(finite.max() * 1.15) if finite.size else 10.0


def plot_stability_sweep(ax, result: Sweep):
    """Self-stable speeds (shaded) against the one swept parameter, with the weave and capsize speeds.

    Returns
    -------
    matplotlib.axes.Axes
    """
    if len(result.names) != 1:
        raise ValueError("plot_stability_sweep needs a sweep over one parameter (plot_stability_map: two)")
    x = _shown(result.names[0], result.values[0])
    top = _top(result)
    s = result.stability
    for k in range(s.lower.shape[-1]):
        lower, upper = s.lower[:, k], np.minimum(s.upper[:, k], top)
        present = np.isfinite(lower)
        if present.any():
            ax.fill_between(
                x,
                np.where(present, lower, np.nan),
                np.where(present, upper, np.nan),
                color=STABLE_SHADE,
                edgecolor="#7fbf7f",
                lw=0.5,
                label=("self-stable" if result.law is None else "stable under the law") if k == 0 else None,
                step=None,
            )
    ax.plot(x, s.weave, color=MODE_COLOURS["weave"], label="weave speed")
    ax.plot(x, s.capsize, color=MODE_COLOURS["capsize"], label="capsize speed")
    unbounded = np.isinf(s.upper).any(axis=-1) & result.valid
    if unbounded.any():
        ax.plot(
            x[unbounded],
            np.full(unbounded.sum(), top),
            "^",
            color="#7fbf7f",
            ms=4,
            clip_on=False,
            label="stable at every higher speed",
        )
    for value in x[~result.valid]:
        ax.axvline(value, color="0.75", lw=2, zorder=0)
    if (~result.valid).any():
        ax.plot([], [], color="0.75", lw=2, label="impossible design")
    base = float(_shown(result.names[0], result.base.values[result.names[0]]))
    unit = UNITS.get(result.names[0], "kg m^2" if result.names[0].startswith("I") else "")
    ax.axvline(base, color="0.3", lw=0.7, ls=":", label=f"base value {base:.4g} {unit}".rstrip())
    ax.set_ylim(0, top)
    ax.set_xlim(x.min(), x.max())
    ax.set_xlabel(_axis_label(result.names[0]))
    ax.set_ylabel("speed $v$ [m/s]")
    legend_outside(ax)
    return ax


def plot_stability_map(ax, result: Sweep, colorbar: bool = True):
    """Over two parameters: the speed at which the first self-stable interval begins (colour), the
    speed at which it ends (contours), designs never self-stable (hatched) or impossible (grey).

    Returns
    -------
    matplotlib.axes.Axes
    """
    if len(result.names) != 2:
        raise ValueError("plot_stability_map needs a sweep over two parameters")
    x, y = (_shown(n, v) for n, v in zip(result.names, result.values))
    lower = result.stability.lower[..., 0].T
    upper = result.stability.upper[..., 0].T
    valid = result.valid.T
    never = valid & ~np.isfinite(lower)
    mesh = ax.pcolormesh(x, y, np.ma.masked_invalid(lower), shading="nearest", cmap="viridis")
    ax.contourf(x, y, np.where(never, 1.0, np.nan), levels=[0.5, 1.5], colors="none", hatches=["////"])
    ax.contourf(x, y, np.where(valid, np.nan, 1.0), levels=[0.5, 1.5], colors=["0.8"])
    finite_upper = np.where(np.isfinite(upper), upper, np.nan)
    if np.isfinite(finite_upper).sum() > 3:
        contours = ax.contour(x, y, finite_upper, colors="k", linewidths=0.6)
        ax.clabel(contours, fontsize=6, fmt="%.1f")
    bx, by = (float(_shown(n, result.base.values[n])) for n in result.names)
    base_shown = bool(np.min(x) <= bx <= np.max(x) and np.min(y) <= by <= np.max(y))
    if base_shown:
        ax.plot(bx, by, "w*", ms=9, mec="k", mew=0.6)
    ax.set_xlabel(_axis_label(result.names[0]))
    ax.set_ylabel(_axis_label(result.names[1]))
    if colorbar:
        bar = ax.figure.colorbar(mesh, ax=ax, pad=0.02)
        bar.set_label("self-stable from [m/s] (weave speed)")
    handles = []  # an entry for what the map shows, and only that
    if never.any():
        handles.append(mpatches.Patch(facecolor="white", edgecolor="0.3", hatch="////", label="never self-stable"))
    if (~valid).any():
        handles.append(mpatches.Patch(color="0.8", label="impossible design"))
    if np.isfinite(finite_upper).sum() > 3:
        handles.append(ax.plot([], [], color="k", lw=0.6, label="self-stable up to [m/s] (capsize speed)")[0])
    if base_shown:
        handles.append(ax.plot([], [], "w*", mec="k", ms=8, label="base design")[0])
    if handles:
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(0.0, -0.16), ncols=2, fontsize=7)
    return ax


def sweep_figure(result: Sweep, title: str = ""):
    """A figure of :func:`plot_stability_sweep` (one parameter) or :func:`plot_stability_map` (two)."""
    if len(result.names) == 1:
        fig, ax = new_figure(height=3.6)
        plot_stability_sweep(ax, result)
    else:
        fig, ax = new_figure(width=5.6, height=4.8)
        plot_stability_map(ax, result)
    if title:
        ax.set_title(title, loc="left")
    return fig


__all__ = ["plot_stability_map", "plot_stability_sweep", "sweep_figure"]
