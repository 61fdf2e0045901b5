"""A gap report's folder: what it links, and that writing it replaces no input.

The report itself (``report.md`` and its PNG figures) is written by
:func:`bikerider.diagnose.write_report`.

A report folder holds one run's report and nothing stale: the figures a previous report in the
folder linked and this one does not are removed (other files are left alone).  No output may
replace an input: :func:`check_report_folder` refuses a folder where the report would write over,
or remove, one of the run's input files (the command checks before it runs the diagnosis).
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable
from pathlib import Path

from bikerider.errors import InputError

REPORT_NAME = "report.md"
FIGURE_LINK = re.compile(r"!\[[^\]]*\]\(([^()/\\]+\.png)\)")
"""A figure link of a report (a file in the report's own folder)."""


def check_report_folder(folder: str | Path, inputs: Iterable[str | os.PathLike]) -> None:
    """Refuse a report folder where the report would replace or remove one of the run's inputs.

    The report writes ``report.md`` and removes the previous report's figures: an input that is the
    folder's ``report.md`` or a figure the previous report links would be lost.  (Each figure is
    checked again when it is written, see :func:`bikerider.diagnose.write_report`.)
    """
    folder = Path(folder)
    if not folder.is_dir():
        return
    refuse_inputs([folder / REPORT_NAME, *(folder / n for n in linked_figures(folder / REPORT_NAME))], inputs)


def linked_figures(report: Path) -> set[str]:
    """File names of the figures a report links (none when there is no readable report)."""
    try:
        text = report.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return set()
    return set(FIGURE_LINK.findall(text))


def refuse_inputs(outputs: Iterable[Path], inputs: Iterable[str | os.PathLike]) -> None:
    """Refuse (``InputError`` naming ``--report``) an output that is one of the run's inputs."""
    for out in outputs:
        if is_input(out, inputs):
            raise InputError(
                "--report",
                str(out.parent),
                f"a folder where the report does not replace an input ({out} is one of the inputs; "
                "give another --report folder)",
            )


def is_input(path: Path, inputs: Iterable[str | os.PathLike]) -> bool:
    """Whether ``path`` exists and is the same file as one of ``inputs``."""
    if not path.exists():
        return False
    for other in inputs:
        try:
            if os.path.samefile(path, other):
                return True
        except OSError:  # an input that does not exist (yet) cannot be replaced
            continue
    return False
