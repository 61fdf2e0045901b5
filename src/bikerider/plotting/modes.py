"""Mode shapes: roll and steer of each mode as phasors at one speed, and against speed.

The shapes are those of :func:`bikerider.benchmark.mode_shapes.mode_shapes` (unit norm, roll real and
positive): a phasor's length is the relative amplitude of roll or steer in the mode and its angle
the phase (steer relative to roll; counter-clockwise: steer leads).
"""

from __future__ import annotations

import numpy as np

from bikerider.benchmark.mode_shapes import ModeShapes, mode_shapes
from bikerider.benchmark.model import WhippleModel
from bikerider.plotting.common import MODE_COLOURS, WIDTH, legend_outside, pyplot
from bikerider.plotting.eigenvalues import speed_grid

PARTS = {"roll": ("#444444", "-"), "steer": ("#d95f02", "-")}


def plot_mode_phasors(ax, shapes: ModeShapes, speed: float, mode: str = "weave"):
    """Roll and steer phasors of ``mode`` at the tracked speed nearest ``speed`` on a polar ``ax``.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax`` (a polar axes).
    """
    k = int(np.argmin(np.abs(shapes.speeds - speed)))
    column = shapes.column(mode)
    roll, steer = shapes.shapes[k, column]
    for name, z in (("roll", roll), ("steer", steer)):
        colour, _ = PARTS[name]
        ax.annotate(
            "",
            xy=(np.angle(z), abs(z)),
            xytext=(0, 0),
            arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 1.6, "shrinkA": 0, "shrinkB": 0},
        )
        angle = np.degrees(np.angle(z))
        angle = 0.0 if abs(angle) < 0.5 else (180.0 if abs(angle) > 179.5 else angle)
        ax.plot([], [], color=colour, lw=1.6, label=f"{name} {abs(z):.2f}, {angle:+.0f} deg")
    s = shapes.eigenvalues[k, column]
    value = f"{s.real:.2f} {'+' if s.imag >= 0 else '-'} {abs(s.imag):.2f}i" if abs(s.imag) > 1e-9 else f"{s.real:.2f}"
    ax.set_title(f"{mode}: s = {value} 1/s", color=MODE_COLOURS.get(mode, "0.2"), pad=12)
    ax.set_ylim(0, 1.0)
    ax.set_yticks([0.5, 1.0])
    ax.set_yticklabels(["0.5", "1"], fontsize=6)
    ax.set_xticks(np.radians([0, 90, 180, 270]))
    ax.tick_params(axis="x", labelsize=7, pad=0)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.08), fontsize=7, handlelength=1.2)
    return ax


def plot_mode_shape_speeds(ax, shapes: ModeShapes, phase_ax=None, modes=("weave", "capsize", "castor")):
    """Steer-to-roll amplitude ratio (``ax``, log scale) and steer phase relative to roll
    (``phase_ax``) of each mode against speed.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``.
    """
    v = shapes.speeds
    for mode in modes:
        if mode not in tuple(shapes.names):
            continue
        k = shapes.column(mode)
        roll, steer = np.abs(shapes.roll[:, k]), np.abs(shapes.steer[:, k])
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(roll > 1e-12, steer / roll, np.nan)
        ax.plot(v, ratio, color=MODE_COLOURS[mode], label=mode)
        if phase_ax is not None:
            phase = np.degrees(shapes.steer_phase[:, k])
            phase = 180.0 - (180.0 - phase) % 360.0  # in (-180, 180]
            phase = np.where(phase < -179.5, 180.0, phase)
            jumps = np.abs(np.diff(phase)) > 90
            phase[1:][jumps] = np.nan  # no line across a jump (a sign change of a real mode, or the wrap)
            phase_ax.plot(v, phase, color=MODE_COLOURS[mode], label=mode)
    ax.set_yscale("log")
    ax.set_ylabel("|steer| / |roll|")
    ax.set_xlabel("speed $v$ [m/s]")
    if phase_ax is not None:
        phase_ax.set_ylabel("steer phase from roll [deg]")
        phase_ax.set_xlabel("speed $v$ [m/s]")
        phase_ax.set_ylim(-185, 185)
        phase_ax.set_yticks([-180, -90, 0, 90, 180])
        phase_ax.axhline(0.0, color="0.4", lw=0.5)
        legend_outside(phase_ax)
    return ax


def mode_shape_figure(model: WhippleModel, speed: float, speeds=None, title: str = ""):
    """Phasors of weave, capsize and castor at ``speed`` (top) and the shapes against speed (bottom)."""
    plt = pyplot()
    shapes = mode_shapes(model, speed_grid(speeds))
    fig = plt.figure(figsize=(WIDTH, 5.6))
    grid = fig.add_gridspec(
        2, 3, height_ratios=(1.2, 1.0), hspace=0.62, wspace=0.45, left=0.09, right=0.86, top=0.88, bottom=0.09
    )
    for i, mode in enumerate(m for m in ("weave", "capsize", "castor") if m in tuple(shapes.names)):
        plot_mode_phasors(fig.add_subplot(grid[0, i], projection="polar"), shapes, speed, mode)
    bottom = grid[1, :].subgridspec(1, 2, wspace=0.3)
    ax, phase_ax = fig.add_subplot(bottom[0]), fig.add_subplot(bottom[1])
    plot_mode_shape_speeds(ax, shapes, phase_ax)
    k = int(np.argmin(np.abs(shapes.speeds - speed)))
    for target in (ax, phase_ax):
        target.axvline(shapes.speeds[k], color="0.5", lw=0.7, ls=":")
    fig.suptitle(
        (title + ": " if title else "") + f"mode shapes at {shapes.speeds[k]:.2f} m/s (top) and against speed",
        x=0.02,
        ha="left",
        fontsize=9,
    )
    return fig


__all__ = ["mode_shape_figure", "plot_mode_phasors", "plot_mode_shape_speeds"]
