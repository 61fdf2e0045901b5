"""Shared pieces of the figures: the pyplot import (Agg backend), colours, sizes, saving.

Figures are sized for a journal page (``WIDTH`` inches wide, two columns) and use 9 pt text; they
are saved with ``bbox_inches="tight"`` so that a legend or a key placed outside the axes is kept,
and written atomically (a partial file never replaces a good one).
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.lines import Line2D

from bikerider.errors import InputError
from bikerider.io.atomic import atomic_write_bytes, figure_bytes

FORMATS = ("png", "pdf", "svg")
"""File formats the figures are written in."""
DEFAULT_DPI = 200
"""Resolution of PNG figures (PDF and SVG are vector graphics)."""
WIDTH = 7.0
"""Width of a full-width figure [in] (a two-column journal page)."""
MODE_COLOURS = {"weave": "#1f77b4", "capsize": "#d62728", "castor": "#2ca02c", "other": "#7f7f7f"}
"""One colour per mode, the same in every figure."""
BODY_COLOURS = {"B": "#1f77b4", "H": "#ff7f0e", "R": "#555555", "F": "#555555", "T": "#000000"}
"""Rear body, front assembly, wheels, whole bicycle."""
CYCLE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf")
"""Colours for several bicycles or speeds on one figure."""
STABLE_SHADE = "#e8f3e8"
"""Background of the self-stable speed intervals."""
RC = {
    "font.size": 9,
    "axes.titlesize": 9,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "figure.dpi": 100,
    "savefig.dpi": DEFAULT_DPI,
    "lines.linewidth": 1.4,
    "legend.frameon": False,
    "svg.fonttype": "none",
    "pdf.fonttype": 42,
    "svg.hashsalt": "bikerider",
}
"""matplotlib settings of every bikerider figure."""


def pyplot():
    """``matplotlib.pyplot`` with the non-interactive Agg backend and the bikerider style."""
    import matplotlib  # here, not at the top: the backend must be chosen before pyplot is first imported

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update(RC)
    return plt


def new_figure(width: float = WIDTH, height: float = 3.6, **subplots):
    """A figure and its axes (``pyplot.subplots`` keywords), in the bikerider style."""
    plt = pyplot()
    return plt.subplots(figsize=(width, height), **subplots)


def check_format(fmt: str, dpi: float | None = None) -> None:
    """:class:`InputError` unless ``fmt`` is one of :data:`FORMATS` and ``dpi`` a sensible resolution."""
    if fmt not in FORMATS:
        raise InputError("--format", fmt, f"one of {', '.join(FORMATS)}")
    if dpi is not None and not 20 <= dpi <= 2400:
        raise InputError("--dpi", dpi, "a resolution between 20 and 2400 dots per inch")


def save_figure(fig, path: str | Path, fmt: str | None = None, dpi: float | None = None) -> Path:
    """Write ``fig`` to ``path`` (format from ``fmt`` or the suffix) atomically and close it."""
    path = Path(path)
    fmt = fmt or path.suffix.lstrip(".") or "png"
    check_format(fmt, dpi)
    try:
        data = figure_bytes(
            fig, format=fmt, dpi=dpi or DEFAULT_DPI, bbox_inches="tight", pad_inches=0.04, metadata=_metadata(fmt)
        )
    finally:
        pyplot().close(fig)
    atomic_write_bytes(path, data)
    return path


def _metadata(fmt: str) -> dict:
    """No creation date in PDF and SVG, so that a figure made twice is the same file."""
    if fmt == "pdf":
        return {"CreationDate": None, "Creator": "bikerider"}
    if fmt == "svg":
        return {"Date": None, "Creator": "bikerider"}
    return {"Software": "bikerider"}


def legend_outside(ax, handles=None, labels=None, title: str | None = None, anchor=(1.02, 1.0), notes=()):
    """A legend to the right of ``ax``, clear of the data; ``notes`` (lines of text) follow the
    entries inside it, so they never overlap it."""
    if handles is None:
        handles, labels = ax.get_legend_handles_labels()
    unique = dict(zip(labels, handles))
    if notes:
        unique["\n".join(notes)] = Line2D([], [], ls="none")
    legend = ax.legend(
        unique.values(),
        unique.keys(),
        loc="upper left",
        bbox_to_anchor=anchor,
        borderaxespad=0.0,
        title=title,
        alignment="left",
    )
    if notes:
        text = legend.get_texts()[-1]
        text.set_fontsize(7)
        text.set_fontstyle("italic")
        text.set_color("0.25")
    return legend
