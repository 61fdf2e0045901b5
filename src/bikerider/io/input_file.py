"""The one way bikerider opens an input file: a regular file of bounded size, read once.

Every reader (TOML, ``name = value`` text, CSV records) gets its bytes or text from
:func:`read_input_bytes` or :func:`read_input_text`, which refuse, before reading anything:

* an empty path (it names no file; it never stands for a default);
* a missing file, a folder, and anything that is not a regular file: a FIFO or a device would block
  the reader, or never end (the file is opened without blocking and checked on the open handle,
  so it cannot be swapped between the check and the read);
* a file larger than the reader's limit, naming its size: :data:`TEXT_LIMIT` for files a person
  writes (measurements, parameters, control gains), :data:`DATA_LIMIT` for recorded data (CSV).

Within its limit a file is read in one pass, so reading takes a time bounded by the limit.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from bikerider.errors import FileFormatError, InputError

TEXT_LIMIT = 1 << 20
"""Largest input file a person writes, in bytes (1 MiB; BicycleParameters' Measured files have
about 2 kB, the project's TOML files 3 kB)."""

DATA_LIMIT = 64 << 20
"""Largest recorded data file (CSV), in bytes (64 MiB: an hour of a 1 kHz rate gyro in a
two-column CSV is about 60 MB)."""

_KINDS = (
    (stat.S_ISDIR, "a folder"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def _size_text(size: int) -> str:
    return f"{size / (1 << 20):.1f} MiB" if size >= 1 << 20 else f"{size} bytes"


def read_input_bytes(path: str | Path, limit: int = TEXT_LIMIT) -> bytes:
    """The bytes of the input file ``path``: a regular file of at most ``limit`` bytes.

    Parameters
    ----------
    path : str or Path
    limit : int
        Largest size accepted, in bytes (:data:`TEXT_LIMIT` or :data:`DATA_LIMIT`).

    Raises
    ------
    InputError
        An empty path.
    FileFormatError
        No such file; a folder, FIFO, device or socket; a file larger than ``limit`` (the
        message gives its size).
    OSError
        The file exists but cannot be opened or read (permissions).
    """
    if str(path) == "":
        raise InputError("path", "", "the path of a file (an empty path names no file, and never the default one)")
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        handle = os.open(path, flags)
    except FileNotFoundError:
        raise FileFormatError(path, "no such file") from None
    except IsADirectoryError:
        raise FileFormatError(path, "is a folder, not a regular file: expected a file to read") from None
    except OSError as exc:
        if exc.errno in (errno.ENXIO, errno.ENODEV):  # a socket or device that cannot be opened
            raise FileFormatError(path, "not a regular file: expected a file to read") from None
        raise
    try:
        info = os.fstat(handle)  # on the open handle: what is read is what was checked
        if not stat.S_ISREG(info.st_mode):  # name the kind of file when it is one of _KINDS
            for is_kind, kind in _KINDS:
                if is_kind(info.st_mode):
                    raise FileFormatError(path, f"is {kind}, not a regular file: expected a file to read")
            raise FileFormatError(path, "not a regular file: expected a file to read")
        if info.st_size > limit:
            raise FileFormatError(
                path, f"{_size_text(info.st_size)}: expected an input file of at most {_size_text(limit)}"
            )
        data = _read_to_end(handle, info.st_size, limit + 1)  # a file that grew since fstat: bounded too
    finally:
        os.close(handle)
    if len(data) > limit:
        raise FileFormatError(
            path, f"more than {_size_text(limit)}: expected an input file of at most {_size_text(limit)}"
        )
    return data


def _read_to_end(handle: int, size: int, most: int) -> bytes:
    """The bytes of ``handle`` to its end, at most ``most`` of them.

    The first read asks for one byte more than the file's size (so a file that has not grown
    is read at once), later ones for at most 64 KiB: no read allocates a buffer of ``most`` bytes
    for a file of a few kilobytes (a 1 MiB buffer per file cost more than reading it).
    """
    parts = []
    total = 0
    want = min(size + 1, most)
    while total < most:
        chunk = os.read(handle, min(want, most - total))
        if not chunk:  # the end of the file
            break
        parts.append(chunk)
        total += len(chunk)
        want = 1 << 16
    return parts[0] if len(parts) == 1 else b"".join(parts)


def decode_text(data: bytes, path: str | Path) -> str:
    """``data`` as UTF-8 text (a byte-order mark dropped).

    Raises
    ------
    FileFormatError
        Bytes that are not UTF-8 (the message gives the byte, its offset and its line).
    """
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FileFormatError(
            path,
            f"not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); save the file as UTF-8 or plain ASCII",
            data.count(b"\n", 0, exc.start) + 1,
        ) from None


def read_input_text(path: str | Path, limit: int = TEXT_LIMIT) -> str:
    """The text of the input file ``path`` (:func:`read_input_bytes`, then :func:`decode_text`)."""
    return decode_text(read_input_bytes(path, limit), path)


__all__ = ["DATA_LIMIT", "TEXT_LIMIT", "checked_input_file", "decode_text", "read_input_bytes", "read_input_text"]


def checked_input_file(path: str | os.PathLike, max_bytes: int | None = None, kind: str = "input file") -> Path:
    """``path`` when it names a regular file of at most ``max_bytes`` bytes (symbolic links followed),
    for readers that stream a file themselves (gzip logs, large CSV tables) rather than take its bytes
    from :func:`read_input_bytes`; the same refusals, checked on the path.

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
        An empty path, no such file, a folder, not a regular file (FIFO, socket, device), or larger
        than ``max_bytes``.
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
    for is_kind, what in _KINDS:
        if is_kind(info.st_mode):
            raise FileFormatError(path, f"is {what}, not a regular file: expected the {kind} as a file")
    if not stat.S_ISREG(info.st_mode):
        raise FileFormatError(path, f"not a regular file: expected the {kind} as a file")
    if max_bytes is not None and info.st_size > max_bytes:
        raise FileFormatError(
            path,
            f"{_size_text(info.st_size)} ({info.st_size} bytes): expected a {kind} of at most {_size_text(max_bytes)}",
        )
    return path
