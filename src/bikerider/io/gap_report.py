"""Write a gap diagnosis's report: ``report.md`` and its PNG figures (see :mod:`bikerider.gap.report`).

A report folder holds one run's report and nothing stale: the figures a previous report in the
folder linked and this one does not are removed (other files are left alone).  No output may
replace an input: :func:`check_report_folder` refuses a folder where the report would write over,
or remove, one of the run's input files (the command checks before it runs the diagnosis).
"""

from __future__ import annotations

import logging
import os
import re
from collections.abc import Iterable
from pathlib import Path

from bikerider.errors import InputError
from bikerider.gap.report import figures, markdown, pyplot
from bikerider.io.atomic import atomic_write_bytes, atomic_write_text, figure_bytes

LOG = logging.getLogger(__name__)

REPORT_NAME = "report.md"
FIGURE_LINK = re.compile(r"!\[[^\]]*\]\(([^()/\\]+\.png)\)")
"""A figure link of a report (a file in the report's own folder)."""


def write_report(
    diagnosis,
    folder: str | Path,
    title: str = "Sim-to-real gap diagnosis",
    inputs: Iterable[str | os.PathLike] = (),
    plan=None,
) -> Path:
    """Write ``report.md`` and the figures into ``folder`` (created if needed); return the report path.

    Figures of a previous report in the folder that this one does not link are removed.  With
    ``plan`` (:class:`bikerider.gap.plan.ranking.NextExperiment`), also the next experiment's
    plan and its figure of the rivals' predictions diverging over speed.

    Raises
    ------
    InputError
        A file the report would write or remove is one of ``inputs`` (:func:`check_report_folder`).
    """
    folder = Path(folder)
    check_report_folder(folder, inputs)
    folder.mkdir(parents=True, exist_ok=True)
    result = diagnosis.as_dict()
    previous = linked_figures(folder / REPORT_NAME)
    written = []
    plt = pyplot()
    pictures = list(figures(diagnosis, result))
    if plan is not None:
        from bikerider.gap.next_report import plot_next

        result["next"] = plan.as_dict()
        pictures.append(("next.png", "Next experiment: where the rivals disagree", plot_next(plan, result["next"])))
    for name, caption, fig in pictures:
        _refuse_inputs([folder / name], inputs)
        try:
            atomic_write_bytes(folder / name, figure_bytes(fig, dpi=110, format="png"))
        finally:
            plt.close(fig)
        written.append((name, caption))
    path = folder / REPORT_NAME
    atomic_write_text(path, markdown(result, title, written))
    stale = [folder / name for name in sorted(previous - {name for name, _ in written})]
    for old in stale:
        if old.is_file() and not _is_any(old, inputs):
            old.unlink()
            LOG.info("%s: removed, a figure of the previous report that this one does not have", old)
    return path


def check_report_folder(folder: str | Path, inputs: Iterable[str | os.PathLike]) -> None:
    """Refuse a report folder where the report would replace or remove one of the run's inputs.

    The report writes ``report.md`` and removes the previous report's figures: an input that is the
    folder's ``report.md`` or a figure the previous report links would be lost.  (Each figure is
    checked again when it is written, see :func:`write_report`.)
    """
    folder = Path(folder)
    if not folder.is_dir():
        return
    _refuse_inputs([folder / REPORT_NAME, *(folder / n for n in linked_figures(folder / REPORT_NAME))], inputs)


def linked_figures(report: Path) -> set[str]:
    """File names of the figures a report links (none when there is no readable report)."""
    try:
        text = report.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return set()
    return set(FIGURE_LINK.findall(text))


def _refuse_inputs(outputs: Iterable[Path], inputs: Iterable[str | os.PathLike]) -> None:
    for out in outputs:
        if _is_any(out, inputs):
            raise InputError(
                "--report",
                str(out.parent),
                f"a folder where the report does not replace an input ({out} is one of the inputs; "
                "give another --report folder)",
            )


def _is_any(path: Path, inputs: Iterable[str | os.PathLike]) -> bool:
    if not path.exists():
        return False
    for other in inputs:
        try:
            if os.path.samefile(path, other):
                return True
        except OSError:  # an input that does not exist (yet) cannot be replaced
            continue
    return False
