"""Side view of a bicycle (and its rider) as in Moore et al. (2009) Fig. 4, with a key.

Drawn from the benchmark parameters alone: wheels, steer axis and fork, a schematic frame, the
centre of mass of each body (the usual quartered-circle symbol) and of the whole bicycle, and an
inertia ellipse for the rear body and the front assembly.  With the rider model's grid points
(``bikerider estimate``) the frame is drawn through the bicycle's grid points and the rider's
segments are added.  Coordinates: x forward from the rear contact, height up (``-z`` of the
benchmark frame).

Inertia ellipse: the section in the XZ plane of the uniform solid ellipsoid that has the body's
mass and inertia tensor (principal moments ``I1``, ``I2`` in the plane and ``Iyy``: semi-axes
``sqrt(5 (I2 + Iyy - I1) / 2m)`` along the first principal direction and ``sqrt(5 (I1 + Iyy - I2) /
2m)`` along the second); where ``Iyy`` is not determined, that of a flat body (``Iyy = I1 + I2``).
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.patches import Circle, Ellipse, Wedge

from bikerider.benchmark.parameters import BenchmarkParameters
from bikerider.plotting.common import BODY_COLOURS, legend_outside, new_figure
from bikerider.rider.model import SEGMENT_LINES

_BODY_NAMES = {"B": "rear body B", "H": "front assembly H", "T": "whole bicycle"}
_FRAME_POINTS = [(2, 5), (5, 10), (10, 2), (10, 12), (12, 11), (11, 7), (10, 13), (12, 16), (16, 17), (17, 19)]
"""Bicycle grid points joined by the frame (1-based, Moore et al. 2009 Table 10)."""


def inertia_ellipse(mass: float, Ixx: float, Izz: float, Ixz: float, Iyy: float | None = None):
    """``(semi-axis 1, semi-axis 2, angle)`` of the inertia ellipse in the (x, height) plane [m, m, rad]
    (the module docstring's definition; the angle of the first axis from +x, counter-clockwise)."""
    # (x, height = -z): the xz product changes sign
    tensor = np.array([[Ixx, -Ixz], [-Ixz, Izz]])
    moments, vectors = np.linalg.eigh(tensor)
    i1, i2 = moments
    iyy = i1 + i2 if Iyy is None else Iyy
    a = math.sqrt(max(5 * (i2 + iyy - i1) / (2 * mass), 0.0))
    c = math.sqrt(max(5 * (i1 + iyy - i2) / (2 * mass), 0.0))
    return a, c, math.atan2(vectors[1, 0], vectors[0, 0])


def _com_symbol(ax, x: float, y: float, radius: float, colour: str, zorder: int = 6) -> None:
    for start in (0, 180):
        ax.add_patch(Wedge((x, y), radius, start, start + 90, facecolor=colour, edgecolor="none", zorder=zorder))
    for start in (90, 270):
        ax.add_patch(Wedge((x, y), radius, start, start + 90, facecolor="white", edgecolor="none", zorder=zorder))
    ax.add_patch(Circle((x, y), radius, fill=False, edgecolor=colour, lw=0.9, zorder=zorder + 1))


def plot_side_view(
    ax,
    parameters: BenchmarkParameters,
    grid_points: np.ndarray | None = None,
    *,
    inertia: bool = True,
    key: bool = True,
    label_points: bool = False,
):
    """Draw the side view of ``parameters`` (and the rider of ``grid_points``) on ``ax``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    parameters : BenchmarkParameters
        The bicycle (with its rider merged into the rear body B, if any).
    grid_points : numpy.ndarray, shape (31, 3), optional
        The rider model's grid points (``EstimateResult.rider_model.grid_points``).
    inertia : bool
        Draw the inertia ellipses of B and H.
    key : bool
        Draw the key (legend) to the right of the axes.
    label_points : bool
        Number the grid points (small; for checking the rider model).

    Returns
    -------
    matplotlib.axes.Axes
    """
    p = parameters.values
    w, c, lam, rR, rF = (float(p[k]) for k in ("w", "c", "lam", "rR", "rF"))  # type: ignore[arg-type]
    bodies = {
        "B": (float(p["mB"]), float(p["xB"]), -float(p["zB"])),  # type: ignore[arg-type]
        "H": (float(p["mH"]), float(p["xH"]), -float(p["zH"])),  # type: ignore[arg-type]
        "R": (float(p["mR"]), 0.0, rR),
        "F": (float(p["mF"]), w, rF),
    }  # type: ignore[arg-type]
    mass = sum(m for m, _, _ in bodies.values())
    bodies["T"] = (
        mass,
        sum(m * x for m, x, _ in bodies.values()) / mass,
        sum(m * y for m, _, y in bodies.values()) / mass,
    )
    extents: list[tuple[float, float, float, float]] = []  # (x0, x1, y0, y1) the limits must hold
    wheel_style = {"fill": False, "edgecolor": "0.25", "lw": 1.4}
    ax.add_patch(Circle((0.0, rR), rR, **wheel_style))
    ax.add_patch(Circle((w, rF), rF, **wheel_style))
    ax.plot([], [], "o", mfc="none", mec="0.25", ms=9, mew=1.2, label="wheels")
    # steer axis: through (w + c, 0), tilted back by lam
    up = np.array([-math.sin(lam), math.cos(lam)])
    ground = np.array([w + c, 0.0])
    axle = np.array([w, rF])
    crown = ground + np.dot(axle - ground, up) * up  # foot of the fork offset on the axis
    top_height = max(bodies["H"][2] + 0.2, rF * 2.2)
    top = ground + (top_height / up[1]) * up
    ax.plot(*np.c_[ground, top], color="0.45", lw=0.8, ls=(0, (6, 3)), label="steer axis")
    if grid_points is None:
        ax.plot(
            *np.c_[axle, crown, top],
            color=BODY_COLOURS["H"],
            lw=2.2,
            solid_capstyle="round",
            label="fork and handlebar (schematic)",
        )
        head = crown + 0.35 * (top - crown)
        ax.plot(
            *np.c_[[0.0, rR], head],
            color=BODY_COLOURS["B"],
            lw=2.2,
            solid_capstyle="round",
            label="rear frame (schematic)",
        )
    else:
        g = np.asarray(grid_points, dtype=float)
        for k, (a, b) in enumerate(_FRAME_POINTS):
            ax.plot(
                g[[a - 1, b - 1], 0],
                -g[[a - 1, b - 1], 2],
                color="0.2",
                lw=1.8,
                label="bicycle (grid points)" if k == 0 else None,
            )
        first = True
        for name, a, b in SEGMENT_LINES:
            if "left" in name:
                continue
            ax.plot(
                g[[a - 1, b - 1], 0],
                -g[[a - 1, b - 1], 2],
                color="#c44e52",
                lw=5,
                alpha=0.55,
                solid_capstyle="round",
                label="rider (right side)" if first else None,
            )
            first = False
        head = g[24]
        ax.add_patch(Circle((head[0], -head[2]), float(np.linalg.norm(g[24] - g[14])), color="#c44e52", alpha=0.35))
        if label_points:
            for i, (x, y, z) in enumerate(g):
                if y >= 0 and np.isfinite(x):
                    ax.annotate(str(i + 1), (x, -z), fontsize=5, xytext=(2, 2), textcoords="offset points", color="0.3")
    ax.axhline(0.0, color="0.2", lw=0.8)
    radius = 0.022 * max(w + rR + rF, 1.0)
    for name, (m, x, y) in bodies.items():
        colour = BODY_COLOURS[name]
        if name in ("R", "F"):
            _com_symbol(ax, x, y, radius * 0.7, colour)
            continue
        _com_symbol(ax, x, y, radius if name != "T" else radius * 1.15, colour)
        ax.plot(
            [],
            [],
            "o",
            mfc="white",
            mec=colour,
            ms=6,
            label=f"{_BODY_NAMES[name]}: centre of mass" + (" and inertia ellipse" if inertia and name != "T" else ""),
        )
        if inertia and name != "T":
            iyy = p[f"I{name}yy"]
            a, b, angle = inertia_ellipse(
                m,
                float(p[f"I{name}xx"]),
                float(p[f"I{name}zz"]),  # type: ignore[arg-type]
                float(p[f"I{name}xz"]),
                None if iyy is None else float(iyy),
            )  # type: ignore[arg-type]
            # the ellipse's bounding box: half-widths of an ellipse turned by `angle`
            dx = math.hypot(a * math.cos(angle), b * math.sin(angle))
            dy = math.hypot(a * math.sin(angle), b * math.cos(angle))
            extents.append((x - dx, x + dx, y - dy, y + dy))
            ax.add_patch(
                Ellipse(
                    (x, y),
                    2 * a,
                    2 * b,
                    angle=math.degrees(angle),
                    fill=True,
                    facecolor=colour,
                    alpha=0.12,
                    edgecolor=colour,
                    lw=0.9,
                )
            )
    ax.plot([], [], "o", mfc="white", mec="0.3", ms=4, label="wheel centres of mass")
    ax.set_aspect("equal")
    xs = [-rR, w + rF, top[0]]
    heights = [0.0, 2 * rR, 2 * rF, top[1]] + [y + 0.1 for _, _, y in bodies.values()]
    if grid_points is not None:
        finite = np.isfinite(g[:, 0])
        xs += [g[finite, 0].min(), g[finite, 0].max()]
        heights += [(-g[finite, 2]).max() + 0.15]
    xs += [e[0] for e in extents] + [e[1] for e in extents]
    heights += [e[3] for e in extents]
    ax.set_xlim(min(xs) - 0.08, max(xs) + 0.08)
    ax.set_ylim(min([-0.05] + [e[2] - 0.02 for e in extents]), max(heights) + 0.05)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("height [m]")
    if key:
        legend_outside(ax)
    return ax


def side_view_figure(
    parameters: BenchmarkParameters, grid_points: np.ndarray | None = None, title: str = "", **options
):
    """A figure of :func:`plot_side_view`."""
    fig, ax = new_figure(width=7.0, height=4.0)
    fig.subplots_adjust(left=0.08, right=0.56, bottom=0.12, top=0.92)
    plot_side_view(ax, parameters, grid_points, **options)
    if title:
        ax.set_title(title, loc="left")
    return fig


__all__ = ["inertia_ellipse", "plot_side_view", "side_view_figure"]
