"""Figures fit for a paper: eigenvalues against speed, side view, mode shapes, Bode, sweeps, gains.

Every ``plot_*`` function draws on a matplotlib ``ax`` it is given and returns it, so figures can
be composed; every ``*_figure`` function makes a whole figure in the bikerider style
(:mod:`bikerider.plotting.common`); :func:`save_figure` writes one as PNG, PDF or SVG.  matplotlib
is imported here only, with the non-interactive Agg backend.  The gallery (``docs/gallery.md``,
``make docs``) shows every figure.

============================================  ===================================================
:func:`plot_eigenvalues`                       eigenvalues against speed, tracked modes
:func:`eigenvalue_comparison_figure`           several bicycles on one figure
:func:`plot_side_view`                         bicycle (and rider), centres of mass, inertia ellipses
:func:`plot_mode_phasors`                      roll and steer of a mode as phasors
:func:`plot_mode_shape_speeds`                 mode shapes against speed
:func:`plot_bode`                              frequency responses
:func:`plot_stability_sweep`                   stable speeds against a parameter
:func:`plot_stability_map`                     stability over two parameters
:func:`gains_figure`                           control gains against speed (a law, LQR)
:mod:`bikerider.plotting.design`               design spaces: self-stable fraction and stable-
                                              interval sensitivity against each parameter, slices
============================================  ===================================================
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bikerider.benchmark.state_space import LateralForce
from bikerider.errors import InputError
from bikerider.plotting.bode import bode_figure, plot_bode
from bikerider.plotting.common import DEFAULT_DPI, FORMATS, check_format, pyplot, save_figure
from bikerider.plotting.eigenvalues import eigenvalue_comparison_figure, eigenvalue_figure, plot_eigenvalues
from bikerider.plotting.gains import gains_figure
from bikerider.plotting.modes import mode_shape_figure, plot_mode_phasors, plot_mode_shape_speeds
from bikerider.plotting.side_view import plot_side_view, side_view_figure
from bikerider.plotting.sweep import plot_stability_map, plot_stability_sweep, sweep_figure

FIGURES = ("eigenvalues", "side_view", "mode_shapes", "bode")
"""The figures :func:`write_figures` can write, by file stem."""


def figure_paths(directory: str | Path, figures=FIGURES, fmt: str = "png") -> list[Path]:
    """The files :func:`write_figures` writes for ``figures`` into ``directory`` (for output checks)."""
    return [Path(directory) / f"{name}.{fmt}" for name in figures]


def write_figures(
    directory: str | Path,
    model,
    eig,
    grid_points: np.ndarray | None,
    title: str = "",
    *,
    parameters=None,
    figures=("eigenvalues", "side_view"),
    fmt: str = "png",
    dpi: float | None = None,
    uncertainty=None,
) -> list[Path]:
    """Write figures of one bicycle into ``directory``; return their paths.

    Parameters
    ----------
    directory : str or Path
        Created if missing.
    model : WhippleModel
    eig : ModalEigenvalues or array_like
        Its speeds set the speed range of the eigenvalue and mode figures.
    grid_points : numpy.ndarray or None
        The rider model's grid points (the side view draws the rider).
    title : str
        Figure title (the bicycle's name).
    parameters : BenchmarkParameters, optional
        Needed for the side view without grid points and for the lateral force of the Bode figure
        (it acts at the rear body's centre of mass).
    figures : sequence of str
        Which of :data:`FIGURES`; a figure whose data are missing (a side view with neither grid
        points nor parameters) is skipped.
    fmt : {"png", "pdf", "svg"}
    dpi : float, optional
        Resolution of PNG files (default :data:`DEFAULT_DPI`).
    uncertainty : EigenvalueUncertainty, optional
        Draws a one-sigma band on the eigenvalue figure.
    """
    check_format(fmt, dpi)
    unknown = [f for f in figures if f not in FIGURES]
    if unknown:
        raise InputError("figures", unknown[0], f"one of {', '.join(FIGURES)}")
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    speeds = getattr(eig, "speeds", eig)
    written = []
    for name in figures:
        if name == "eigenvalues":
            fig = eigenvalue_figure(model, speeds, title, uncertainty=uncertainty)
        elif name == "side_view":
            if parameters is None and grid_points is None:
                continue
            if parameters is None:
                raise InputError("parameters", None, "the benchmark parameters for a side view")
            fig = side_view_figure(parameters, grid_points, title)
        elif name == "mode_shapes":
            fig = mode_shape_figure(model, _mode_speed(model, speeds), speeds, title)
        else:
            force = None if parameters is None else LateralForce(parameters.values["xB"], parameters.values["zB"])
            fig = bode_figure(model, _bode_speeds(model, speeds), lateral_force=force, title=title)
        (path,) = figure_paths(out, (name,), fmt)
        written.append(save_figure(fig, path, fmt, dpi))
    return written


def _mode_speed(model, speeds) -> float:
    """The middle of the first stable interval, else the middle of the speed range."""
    v = np.asarray(speeds, dtype=float)
    lo, hi = (float(v.min()), float(v.max())) if v.size > 1 and v.max() > v.min() else (0.0, 10.0)
    stable = model.critical_speeds().stable_range
    if stable and lo <= stable[0] <= hi:
        return 0.5 * (stable[0] + min(stable[1], hi))
    return 0.5 * (lo + hi)


def _bode_speeds(model, speeds) -> tuple[float, ...]:
    """Three round speeds across the range, one of them self-stable when the range holds a
    self-stable speed: the middle of the first stable interval inside the range, with a speed below
    it and one above it where the range reaches there (an unstable weave, a slowly diverging capsize);
    else 25, 55 and 85 % of the range."""
    v = np.asarray(speeds, dtype=float)
    lo, hi = (float(v.min()), float(v.max())) if v.size > 1 and v.max() > v.min() else (0.0, 10.0)
    stability = model.stability()
    fallback = tuple(float(np.round(x, 1)) for x in np.linspace(lo + 0.25 * (hi - lo), hi - 0.15 * (hi - lo), 3))
    for interval in stability.intervals:
        a, b = max(interval.lower, lo), min(interval.upper, hi)
        if not b > a:
            continue
        middle = _round_inside(0.5 * (a + b), a, b)
        below = _round_inside(0.5 * (lo + a), lo, a) if a > lo else None
        above = _round_inside(0.5 * (b + hi), b, hi) if b < hi else None
        chosen = [x for x in (below, middle, above) if x is not None]
        if len(chosen) < 3:  # the stable interval reaches an end of the range: two speeds inside it
            extra = _round_inside(a + 0.8 * (b - a) if above is None else a + 0.2 * (b - a), a, b)
            chosen.append(extra)
        return tuple(sorted(set(chosen)))
    return fallback


def _round_inside(x: float, a: float, b: float) -> float:
    """``x`` rounded to 0.1 m/s if that stays strictly inside (a, b), else to 0.01, else as it is."""
    for digits in (1, 2):
        r = float(np.round(x, digits))
        if a < r < b:
            return r
    return float(x)


__all__ = [
    "DEFAULT_DPI",
    "FIGURES",
    "FORMATS",
    "bode_figure",
    "eigenvalue_comparison_figure",
    "eigenvalue_figure",
    "figure_paths",
    "gains_figure",
    "mode_shape_figure",
    "plot_bode",
    "plot_eigenvalues",
    "plot_mode_phasors",
    "plot_mode_shape_speeds",
    "plot_side_view",
    "plot_stability_map",
    "plot_stability_sweep",
    "pyplot",
    "save_figure",
    "side_view_figure",
    "sweep_figure",
    "write_figures",
]
