"""Check an input path before reading it: a regular file, of a size the reader can handle in bounded time.

A FIFO, socket or device given as an input would block a reader (or never end); a file far larger
than its kind ever is would take unbounded time.  Both are refused up front with
:class:`~bikerider.errors.FileFormatError`, naming the file, what it is or its size, and the limit.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from bikerider.errors import FileFormatError


def checked_input_file(path: str | os.PathLike, max_bytes: int | None = None, kind: str = "input file") -> Path:
    """``path`` when it names a regular file of at most ``max_bytes`` bytes (symbolic links followed).

    Parameters
    ----------
    path : path-like
    max_bytes : int, optional
        Largest size accepted; no limit when ``None``.
    kind : str
        What the file is, for the message (e.g. ``"eigenvalue table"``).

    Raises
    ------
    FileFormatError
        No such file, a folder, not a regular file (FIFO, socket, device), or larger than ``max_bytes``.
    """
    if os.fspath(path) == "":  # Path("") would be the current folder
        raise FileFormatError("''", f"empty path: expected the path of the {kind}")
    path = Path(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise FileFormatError(path, "no such file") from None
    except OSError as exc:
        raise FileFormatError(path, f"cannot be read ({exc.strerror or exc})") from None
    except ValueError:  # a NUL byte in the path
        raise FileFormatError(repr(str(path)), "not a valid path (it holds a NUL byte)") from None
    if stat.S_ISDIR(info.st_mode):
        raise FileFormatError(path, f"is a folder: expected the {kind}")
    if not stat.S_ISREG(info.st_mode):
        raise FileFormatError(
            path, f"is {_special_kind(info.st_mode)}, not a regular file: expected the {kind} as a file"
        )
    if max_bytes is not None and info.st_size > max_bytes:
        raise FileFormatError(
            path,
            f"{_size(info.st_size)} ({info.st_size} bytes): expected a {kind} of at most {_size(max_bytes)}",
        )
    return path


def _special_kind(mode: int) -> str:
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "a special file"


def _size(n: int) -> str:
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n} bytes"
