"""Figures: eigenvalues against speed (the paper's Fig. 5) and a side view of bicycle and rider
(the paper's Fig. 4).  matplotlib is imported here only, with the non-interactive Agg backend."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from bikerider.benchmark import ModalEigenvalues, WhippleModel

_COLOURS = {"weave": "tab:blue", "capsize": "tab:orange", "castor": "tab:green", "other": "tab:gray"}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> None:
    """Write atomically: a partial figure never replaces a good one."""
    from bikerider.io.atomic import atomic_write_bytes, figure_bytes

    atomic_write_bytes(path, figure_bytes(fig, dpi=120, format="png"))


def eigenvalue_figure(model: WhippleModel, eig: ModalEigenvalues, title: str = ""):
    """Real and imaginary parts of the eigenvalues against speed, weave and capsize speeds marked."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for k in range(4):
        labels = eig.labels[:, k]
        for mode in ("weave", "capsize", "castor", "other"):
            mask = labels == mode
            if mask.any():
                ax.plot(eig.speeds[mask], eig.values[mask, k].real, ".", ms=3, color=_COLOURS[mode],
                        label=f"{mode} (real)" if k in (0, 2, 3) else None)
    imag = np.abs(eig.values[:, 0].imag)
    ax.plot(eig.speeds[imag > 0], imag[imag > 0], "--", color=_COLOURS["weave"], lw=1, label="weave |imag|")
    speeds = model.critical_speeds()
    for v, name in ((speeds.weave, "weave speed"), (speeds.capsize, "capsize speed")):
        if v is not None and eig.speeds.min() <= v <= eig.speeds.max():
            ax.axvline(v, color="k", lw=0.8, ls=":")
            ax.annotate(f"{name}\n{v:.2f} m/s", (v, ax.get_ylim()[1]), ha="center", va="top", fontsize=8)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_ylim(max(ax.get_ylim()[0], -12), min(ax.get_ylim()[1], 12))
    ax.set_xlabel("speed v [m/s]")
    ax.set_ylabel("eigenvalue [1/s]")
    ax.set_title(title or "Eigenvalues against speed")
    handles, labels = ax.get_legend_handles_labels()
    unique = dict(zip(labels, handles))
    ax.legend(unique.values(), unique.keys(), fontsize=8, loc="lower left")
    fig.tight_layout()
    return fig


def side_view_figure(grid_points: np.ndarray, title: str = ""):
    """Side view (XZ plane, z up on the page) of the grid points and segments of bicycle and rider."""
    from bikerider.rider.model import SEGMENT_LINES

    plt = _pyplot()
    p = np.asarray(grid_points)
    fig, ax = plt.subplots(figsize=(6, 6))
    for centre in (2, 7):  # wheel centres; each wheel touches the ground (z = 0)
        r = abs(p[centre - 1, 2])
        ax.add_patch(plt.Circle((p[centre - 1, 0], -p[centre - 1, 2]), r, fill=False, color="0.4"))
    frame = [(2, 5), (5, 10), (10, 2), (10, 12), (12, 11), (11, 7), (10, 13), (12, 16), (16, 17), (17, 19)]
    for a, b in frame:
        ax.plot(p[[a - 1, b - 1], 0], -p[[a - 1, b - 1], 2], color="0.3", lw=2)
    for name, a, b in SEGMENT_LINES:
        if "left" in name:
            continue
        ax.plot(p[[a - 1, b - 1], 0], -p[[a - 1, b - 1], 2], color="tab:red", lw=4, alpha=0.7, solid_capstyle="round")
    head = p[24]
    ax.add_patch(plt.Circle((head[0], -head[2]), np.linalg.norm(p[24] - p[14]), color="tab:red", alpha=0.5))
    ax.plot(p[:, 0], -p[:, 2], "k.", ms=4)
    for i, (x, _, z) in enumerate(p):
        if p[i, 1] >= 0:
            ax.annotate(str(i + 1), (x, -z), fontsize=6, xytext=(2, 2), textcoords="offset points")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("-z (height) [m]")
    ax.set_title(title or "Grid points and segments")
    fig.tight_layout()
    return fig


def write_figures(directory: str | Path, model: WhippleModel, eig: ModalEigenvalues,
                  grid_points: np.ndarray | None, title: str = "") -> list[Path]:
    """Write ``eigenvalues.png`` (and ``side_view.png`` when grid points are given) into ``directory``."""
    plt = _pyplot()
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    fig = eigenvalue_figure(model, eig, title)
    _save(fig, out / "eigenvalues.png")
    plt.close(fig)
    written.append(out / "eigenvalues.png")
    if grid_points is not None:
        fig = side_view_figure(grid_points, title)
        _save(fig, out / "side_view.png")
        plt.close(fig)
        written.append(out / "side_view.png")
    return written
