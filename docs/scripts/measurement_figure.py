"""Draw docs/figures/measurements.png: every bicycle and rider measurement, labelled, like Fig. 1 of
Moore et al. (2009), on the model's own geometry.

The points are the rider model's grid points (``bikerider.generated.rider_model.grid_points``,
Table 10) for the paper's bicycle and rider, so every line drawn is where the model puts it: a
measurement's two end points are the grid points the model places with it.  Run with ``make docs``
(or ``python docs/scripts/measurement_figure.py``).
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "figures" / "measurements.png"

LABELS = {
    # key: (panel, text)
    "w": ("bicycle", "w"),
    "c": ("bicycle", "c"),
    "rR": ("bicycle", "r_R"),
    "rF": ("bicycle", "r_F"),
    "h_bb": ("bicycle", "h_bb"),
    "l_cs": ("bicycle", "l_cs"),
    "l_st": ("bicycle", "l_st"),
    "l_sp": ("bicycle", "l_sp"),
    "lam_st_deg": ("bicycle", "λ_st"),
    "lam_ht_deg": ("bicycle", "λ_ht"),
    "l_f": ("bicycle", "l_f"),
    "l_s": ("bicycle", "l_s"),
    "l_hb": ("bicycle", "l_hb"),
    "l_ll": ("rider", "l_ll"),
    "l_ul": ("rider", "l_ul"),
    "l_to": ("rider", "l_to"),
    "l_ua": ("rider", "l_ua"),
    "l_la": ("rider", "l_la"),
    "lam_fl_deg": ("rider", "λ_fl"),
    "c_h": ("rider", "c_h / π"),
}
"""Every measurement drawn, by its key in the TOML files (the widths and circumferences other than
the head's lie across the bicycle and are described in docs/input_format.md instead)."""


def _points():
    from bikerider.generated import rider_model as gen

    from bikerider.estimate import default_files
    from bikerider.io.toml_input import load_bicycle_toml, load_rider_toml
    from bikerider.rider.model import _GRID, model_arguments

    bicycle_file, rider_file = default_files()
    bicycle, rider = load_bicycle_toml(bicycle_file), load_rider_toml(rider_file)
    args = model_arguments(bicycle, rider)
    p = np.asarray(gen.grid_points(**{k: args[k] for k in _GRID}))
    xy = np.column_stack([p[:, 0], -p[:, 2]])  # x forward, height up
    return {i + 1: xy[i] for i in range(len(xy))}, args


def _along(ax, a, b, text, offset=0.035, colour="C3", arrows=True, fontsize=9, side=1):
    """A dimension line parallel to a-b, shifted ``offset`` to one side, labelled at its middle."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    n = side * np.array([-d[1], d[0]]) / np.linalg.norm(d)
    a2, b2 = a + offset * n, b + offset * n
    style = "<|-|>" if arrows else "-"
    ax.annotate(
        "", a2, b2, arrowprops=dict(arrowstyle=style, color=colour, lw=0.9, shrinkA=0, shrinkB=0, mutation_scale=7)
    )
    for end, end2 in ((a, a2), (b, b2)):
        ax.plot(*zip(end, end2 + 0.3 * offset * n), color=colour, lw=0.5)
    mid = 0.5 * (a + b) + (offset + math.copysign(0.035, offset)) * n
    ax.text(
        *mid,
        text,
        color=colour,
        fontsize=fontsize,
        ha="center",
        va="center",
        bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.85),
    )


def _angle(ax, centre, start_deg, end_deg, radius, text, colour="C0", at_deg=None, distance=1.35):
    """An arc from ``start_deg`` to ``end_deg`` (counter-clockwise from +x) labelled at ``at_deg``."""
    from matplotlib.patches import Arc

    ax.add_patch(Arc(centre, 2 * radius, 2 * radius, theta1=start_deg, theta2=end_deg, color=colour, lw=1.0))
    mid = math.radians(0.5 * (start_deg + end_deg) if at_deg is None else at_deg)
    ax.text(
        centre[0] + distance * radius * math.cos(mid),
        centre[1] + distance * radius * math.sin(mid),
        text,
        color=colour,
        fontsize=9,
        ha="center",
        va="center",
    )


def _bicycle(ax, p, args, faint=False):
    from matplotlib.patches import Circle

    colour, lw = ("0.75", 1.0) if faint else ("0.2", 1.6)
    ax.axhline(0, color="0.4", lw=0.8)
    for centre, r in ((p[2], args["rR"]), (p[7], args["rF"])):
        ax.add_patch(Circle(centre, r, fill=False, color=colour, lw=lw))
    for a, b in ((2, 5), (5, 10), (10, 12), (12, 11), (11, 7), (12, 16), (16, 19)):
        ax.plot(*zip(p[a], p[b]), color=colour, lw=lw, solid_capstyle="round")
    ax.plot(*zip(p[10], p[13]), color="0.55" if not faint else "0.8", lw=lw, ls="-")  # seat post
    for k in (2, 5, 7, 10, 11, 12, 13, 16, 19):
        ax.plot(*p[k], "o", ms=2.5, color=colour)


def draw():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p, args = _points()
    lam_ht, lam_st, lam_fl = args["lam_ht"], args["lam_st"], args["lam_fl"]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12.5, 6.2))
    # ---------------------------------------------------------------- (a) the bicycle, Table 1
    _bicycle(ax1, p, args)
    ground_axis = np.array([args["w"] + args["c"], 0.0])  # where the steering axis meets the ground
    top = p[16] + 0.12 * np.array([-math.cos(lam_ht), math.sin(lam_ht)])
    ax1.plot(*zip(ground_axis, top), color="C0", lw=0.8, ls="--")
    ax1.text(*(top + [0.0, 0.03]), "steering axis", color="C0", fontsize=8, ha="center")
    _along(ax1, p[1], p[6], "w", offset=-0.07)
    _along(ax1, p[6], ground_axis, "c", offset=-0.16)
    _along(ax1, p[1], p[2], "r_R", offset=0.06)
    _along(ax1, p[6], p[7], "r_F", offset=-0.06)
    _along(ax1, [p[5][0], 0.0], p[5], "h_bb", offset=0.05)
    _along(ax1, p[2], p[5], "l_cs", offset=-0.05)
    _along(ax1, p[5], p[10], "l_st", offset=0.06)
    _along(ax1, p[10], p[13], "l_sp", offset=0.06)
    _along(ax1, p[7], p[11], "l_f", offset=-0.06)
    _along(ax1, p[12], p[16], "l_s", offset=-0.06)
    _along(ax1, p[16], p[19], "l_hb", offset=0.05)
    _angle(ax1, p[5], 180 - math.degrees(lam_st), 180, 0.13, "λ_st", at_deg=128, distance=1.5)
    ax1.plot(*zip(p[5], p[5] - [0.22, 0]), color="C0", lw=0.6, ls=":")
    _angle(ax1, ground_axis, 180 - math.degrees(lam_ht), 180, 0.13, "λ_ht")
    ax1.set_title("(a) Bicycle: the 13 measurements of Table 1 in the x-z plane", fontsize=10)
    ax1.annotate(
        "r1: rear contact, origin",
        p[1],
        (p[1][0] - 0.05, -0.22),
        fontsize=7,
        color="0.3",
        arrowprops=dict(arrowstyle="-", color="0.6", lw=0.5),
    )
    ax1.text(p[10][0] - 0.02, p[10][1] - 0.05, "top of seat tube", fontsize=7, color="0.3", ha="right")
    ax1.text(p[11][0] + 0.03, p[11][1] - 0.03, "bottom of head tube", fontsize=7, color="0.3")
    ax1.text(p[12][0] + 0.03, p[12][1] + 0.01, "top of head tube\n(at the top tube's height)", fontsize=7, color="0.3")
    ax1.text(p[19][0] - 0.01, p[19][1] + 0.035, "grip", fontsize=7, color="0.3", ha="center")
    ax1.text(p[13][0], p[13][1] + 0.03, "top of seat", fontsize=7, color="0.3", ha="center")
    # ---------------------------------------------------------------- (b) the rider, Table 7
    _bicycle(ax2, p, args, faint=True)
    for a, b in ((5, 14), (14, 13), (13, 15), (21, 23), (23, 19)):
        ax2.plot(*zip(p[a], p[b]), color="0.15", lw=2.2, solid_capstyle="round")
    for k in (5, 13, 14, 15, 19, 21, 23, 25):
        ax2.plot(*p[k], "o", ms=3, color="0.15")
    from matplotlib.patches import Circle

    head_radius = 0.58 / (2 * math.pi)
    ax2.add_patch(Circle(p[25], head_radius, fill=False, color="0.15", lw=1.6))
    _along(ax2, p[5], p[14], "l_ll", offset=-0.05)
    _along(ax2, p[14], p[13], "l_ul", offset=-0.05)
    _along(ax2, p[13], p[15], "l_to", offset=0.06)
    _along(ax2, p[21], p[23], "l_ua", offset=0.05)
    _along(ax2, p[23], p[19], "l_la", offset=0.05)
    ax2.plot(*zip(p[13], p[13] + [0.25, 0]), color="C0", lw=0.6, ls=":")
    _angle(ax2, p[13], 0, math.degrees(lam_fl), 0.13, "λ_fl")
    ax2.plot(*zip(p[15], p[25]), color="C0", lw=0.6, ls=":")
    _along(ax2, p[25] - [head_radius, 0], p[25] + [head_radius, 0], "c_h / π", offset=head_radius + 0.04)
    for k, text, dx, dy in (
        (5, "pedal axis (feet)", 0.03, -0.04),
        (13, "hip joint = top of seat", -0.02, -0.06),
        (14, "knee", 0.03, 0.0),
        (15, "shoulder joint", -0.03, 0.02),
        (19, "hand (grip)", 0.03, -0.03),
        (23, "elbow", -0.03, -0.06),
        (25, "head centre", 0.09, 0.0),
    ):
        ax2.text(p[k][0] + dx, p[k][1] + dy, text, fontsize=7, color="0.3", ha="left" if dx > 0 else "right")
    ax2.set_title("(b) Rider: Table 7's lengths and forward lean, seated as the model seats them", fontsize=10)
    for ax in (ax1, ax2):
        ax.set_aspect("equal")
        ax.set_xlim(-0.45, 1.6)
        ax.set_ylim(-0.3, 1.85)
        ax.set_xlabel("x [m] (forward from the rear contact point)")
        ax.set_ylabel("height [m] (-z)")
        ax.tick_params(labelsize=8)
    fig.suptitle(
        "Moore et al. (2009) measurements on the paper's Batavus Browser and rider, drawn from bikerider's grid points",
        fontsize=10,
    )
    fig.tight_layout()
    return fig


def main() -> None:
    logging.basicConfig(level=logging.ERROR)
    logging.getLogger("bikerider").setLevel(logging.ERROR)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig = draw()
    fig.savefig(OUT, dpi=90, metadata={"Software": "bikerider"})
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
