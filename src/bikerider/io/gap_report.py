"""Write a gap diagnosis's report: ``report.md`` and its PNG figures (see :mod:`bikerider.gap.report`)."""

from __future__ import annotations

from pathlib import Path

from bikerider.gap.report import figures, markdown, pyplot
from bikerider.io.atomic import atomic_write_bytes, atomic_write_text, figure_bytes


def write_report(diagnosis, folder: str | Path, title: str = "Sim-to-real gap diagnosis") -> Path:
    """Write ``report.md`` and the figures into ``folder`` (created if needed); return the report path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    result = diagnosis.as_dict()
    written = []
    plt = pyplot()
    for name, caption, fig in figures(diagnosis, result):
        try:
            atomic_write_bytes(folder / name, figure_bytes(fig, dpi=110, format="png"))
        finally:
            plt.close(fig)
        written.append((name, caption))
    path = folder / "report.md"
    atomic_write_text(path, markdown(result, title, written))
    return path
