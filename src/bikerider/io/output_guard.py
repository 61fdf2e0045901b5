"""No command writes over one of its own inputs; a report folder holds one run's report.

Two rules, one module, used by every command's every output path:

* **Inputs are never overwritten.**  The command line registers the files a run reads
  (:func:`run_inputs`; a command that finds more of them, like ``batch`` in a data folder, adds
  them with :func:`add_inputs`).  Each command checks its output paths before it computes anything
  (:func:`refuse_inputs`, naming the option), and :mod:`bikerider.io.atomic`, through which every
  file bikerider writes goes, checks again at the moment of writing (:func:`check_output`).  Two
  paths are the same file when they resolve to the same path or, both existing, to the same inode
  (a symbolic or hard link to an input is an input).
* **A report folder holds one run's report and nothing stale.**  :class:`ReportFolder` builds the
  report in a new folder beside the target and, once it is complete, renames it into the target's
  place: files an earlier report wrote and this one does not cannot survive, and a run that fails
  leaves the earlier report as it was.  It replaces only a folder that is new, empty, or marked
  (:data:`REPORT_MARKER`) as written by an earlier report, and never one that holds an input.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from contextvars import ContextVar
from pathlib import Path

from bikerider.errors import InputError

PathLike = str | os.PathLike

_INPUTS: ContextVar[tuple[Path, ...]] = ContextVar("bikerider_run_inputs", default=())

REPORT_MARKER = ".bikerider-report"
"""The file that marks a folder as a report folder bikerider wrote (and may replace)."""


@contextlib.contextmanager
def run_inputs(paths: Iterable[PathLike | None]) -> Iterator[None]:
    """Within the block, ``paths`` (and whatever :func:`add_inputs` adds) are the run's inputs."""
    token = _INPUTS.set(tuple(Path(p) for p in paths if p))
    try:
        yield
    finally:
        _INPUTS.reset(token)


def add_inputs(paths: Iterable[PathLike]) -> None:
    """Register more input files of the current run (e.g. the files found in an input folder)."""
    _INPUTS.set(_INPUTS.get() + tuple(Path(p) for p in paths))


def inputs() -> tuple[Path, ...]:
    """The current run's registered inputs."""
    return _INPUTS.get()


def same_file(a: PathLike, b: PathLike) -> bool:
    """Whether ``a`` and ``b`` name the same file (same resolved path, or the same existing inode)."""
    a, b = Path(a), Path(b)
    try:
        if a.resolve() == b.resolve():
            return True
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except (OSError, RuntimeError, ValueError):  # unresolvable (a symlink loop, a NUL byte): not provably one file
        return False


def input_at(path: PathLike) -> Path | None:
    """The registered input that ``path`` would overwrite, or None."""
    return next((p for p in _INPUTS.get() if same_file(path, p)), None)


def refuse_inputs(option: str, value: object, outputs: Iterable[PathLike]) -> None:
    """:class:`InputError` naming ``option`` when one of ``outputs`` is one of the run's inputs.

    Parameters
    ----------
    option : str
        The option that names the outputs (``--plot``, ``--out``, ``--report``).
    value : object
        The option's value as given (shown in the message).
    outputs : iterable of path-like
        Every file the option makes the command write.
    """
    for output in outputs:
        hit = input_at(output)
        if hit is not None:
            raise InputError(
                option, str(value), f"an output that is not one of the command's inputs ({_is_input(output, hit)})"
            )


def file_output(option: str, value: str) -> Path:
    """The path of a file option (``--out FILE``, ``period --plot PNG``), checked: not empty, not a
    folder, in a folder that exists.

    Raises
    ------
    InputError
        Naming ``option`` and its value.
    """
    if not value:
        raise InputError(option, value, "a file to write (an empty path names none)")
    path = Path(value)
    if path.is_dir() or not path.name or path.name in (".", ".."):
        raise InputError(option, value, "a file to write, not a folder")
    if not path.parent.is_dir():
        raise InputError(option, value, f"a file in an existing folder ({path.parent} does not exist)")
    return path


def folder_output(option: str, value: str) -> Path:
    """The path of a folder option (``--plot DIR``, ``--report DIR``, ``--store DIR``), checked: not
    empty, not an existing file (it is created when missing).

    Raises
    ------
    InputError
        Naming ``option`` and its value.
    """
    if not value:
        raise InputError(option, value, "a folder to write into (an empty path names none)")
    path = Path(value)
    if path.exists() and not path.is_dir():
        raise InputError(option, value, "a folder to write into (this is a file)")
    return path


def check_output(path: PathLike) -> None:
    """Called by :mod:`bikerider.io.atomic` before it replaces ``path``: refuse an input."""
    hit = input_at(path)
    if hit is not None:
        raise InputError(
            "output file", str(path), f"a file that is not one of this run's inputs ({_is_input(path, hit)})"
        )


def _is_input(output: PathLike, hit: Path) -> str:
    if os.fspath(output) == os.fspath(hit):
        return f"{output} is an input of this run"
    return f"{output} is the input {hit}"


def refuse_inputs_within(option: str, folder: PathLike) -> None:
    """:class:`InputError` when an input of the run lies inside ``folder`` (which is to be replaced)."""
    root = Path(folder)
    try:
        root = root.resolve()
    except (OSError, RuntimeError):
        return
    for p in _INPUTS.get():
        try:
            inside = p.resolve().is_relative_to(root)
        except (OSError, RuntimeError, ValueError):
            continue
        if inside:
            raise InputError(
                option, str(folder), f"a folder that holds none of the command's inputs (it holds the input {p})"
            )


class ReportFolder:
    """Write a report into a new folder, then put it in place of ``path`` (two renames: the old
    folder aside, the new one in; readers never see a half-written report).

    Use as a context manager: the ``with`` block writes into the returned staging folder; on
    success the staging folder replaces ``path`` (an earlier report there is removed whole), on an
    exception it is removed and ``path`` is left as it was.

    Parameters
    ----------
    path : path-like
        The report folder.  It must not exist, be empty, or hold an earlier report
        (:data:`REPORT_MARKER`); it must not hold an input of the run.
    option : str
        The option that named it, for messages.

    Raises
    ------
    InputError
        ``path`` is a file, a folder with files no report wrote, or holds one of the run's inputs.

    Examples
    --------
    >>> with ReportFolder("out/report") as staging:          # doctest: +SKIP
    ...     (staging / "report.md").write_text("# Report")
    """

    def __init__(self, path: PathLike, option: str = "--report"):
        self.path, self.option = Path(path), option
        self.staging: Path | None = None
        self._root: Path | None = None

    def check(self) -> None:
        """Refuse a target that is not a folder this class may replace."""
        path = self.path
        if path.exists() and not path.is_dir():
            raise InputError(self.option, str(path), "a folder for the report (this is a file)")
        refuse_inputs_within(self.option, path)
        if path.is_dir():
            entries = sorted(p.name for p in path.iterdir())
            if entries and REPORT_MARKER not in entries:
                shown = ", ".join(entries[:4]) + (", ..." if len(entries) > 4 else "")
                raise InputError(
                    self.option,
                    str(path),
                    f"a new or empty folder, or one an earlier report wrote (it holds {shown}, "
                    f"and no {REPORT_MARKER}); the report replaces the folder's whole content",
                )
        if not path.parent.is_dir():
            raise InputError(self.option, str(path), f"a folder in an existing folder ({path.parent} does not exist)")

    def __enter__(self) -> Path:
        self.check()
        self.staging = Path(tempfile.mkdtemp(dir=self.path.parent, prefix=f".{self.path.name}.", suffix=".new"))
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(self.staging, 0o777 & ~umask)
        (self.staging / REPORT_MARKER).write_text("written by bikerider; the next report replaces this folder\n")
        self._root = self.staging
        return self.staging

    def final(self, staged: PathLike) -> Path:
        """Where a file written into the staging folder ends up."""
        assert self._root is not None, "final() maps files of a folder entered with `with`"
        return self.path / Path(staged).relative_to(self._root)

    def __exit__(self, exc_type, exc, tb) -> bool:
        staging, self.staging = self.staging, None
        assert staging is not None
        if exc_type is not None:
            shutil.rmtree(staging, ignore_errors=True)
            return False
        old = None
        if self.path.exists():
            old = Path(tempfile.mkdtemp(dir=self.path.parent, prefix=f".{self.path.name}.", suffix=".old"))
            os.replace(self.path, old / "report")
        os.replace(staging, self.path)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return False


__all__ = [
    "REPORT_MARKER",
    "ReportFolder",
    "add_inputs",
    "check_output",
    "file_output",
    "folder_output",
    "input_at",
    "inputs",
    "refuse_inputs",
    "refuse_inputs_within",
    "run_inputs",
    "same_file",
]
