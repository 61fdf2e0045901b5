"""Trust in a design store on disk: its files are what a run wrote, and one run holds it at a time.

A store folder outlives the run that wrote it, so a later run (resuming it) or reader (summarising
it) meets whatever happened to it meanwhile.  This module checks, before zarr reads a byte:

* **the kinds of its files**: every entry is a folder or a regular file (a FIFO would block the
  reader for ever, ``/dev/zero`` would fill the memory), :func:`check_files`;
* **its metadata**: the group's and every array's ``zarr.json`` is JSON of bounded size, every
  array of the run is there with the shape, chunks and type the run gives it,
  :func:`check_metadata`;
* **its finished chunks**: the marker of a finished chunk records a checksum of each array's
  values (:func:`chunk_digest`), and :func:`verify_chunks` reads every finished chunk back and
  compares: a chunk deleted, garbled or truncated after its marker was written is found (zarr
  itself would read a deleted chunk as fill values, silently);

and refuses a damaged store with :func:`damaged`: what is damaged, and ``--restart``.

**One run at a time.**  :class:`StoreLock` holds an exclusive ``fcntl.flock`` on the store's lock
file (:data:`LOCK_NAME`, inside the folder, kept by ``--restart``) for as long as the run holds
the store; a second run is refused at once, naming the process that holds it.  The lock goes with
the process that holds it (a killed run leaves no stale lock).
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import stat
import zlib
from pathlib import Path

import numpy as np

from bikerider.errors import BikeriderError, InputError
from bikerider.io.input_file import read_input_bytes

LOCK_NAME = ".bikerider-lock"
"""The lock file in a store folder (holds the id of the process that last held the store)."""
MAX_METADATA = 16 << 20
"""Largest ``zarr.json`` read [bytes]: a store's attributes hold its space (axes or draws), a few kB."""
RESTART = "give --restart to discard it and compute the run again"


def damaged(path: Path | str, what: str) -> InputError:
    """The error of a damaged store: what is damaged and how to recover."""
    return InputError("--store", str(path), f"an undamaged design store ({what}); {RESTART}")


def check_files(path: Path) -> None:
    """Every entry of the store folder is a folder or a regular file (symbolic links followed)."""
    for root, folders, files in os.walk(path):
        for name in folders + files:
            entry = Path(root) / name
            try:
                mode = os.stat(entry).st_mode
            except OSError as exc:
                raise damaged(path, f"{entry} cannot be read: {exc.strerror}") from None
            if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
                raise damaged(path, f"{entry} is not a regular file (a pipe or a device; zarr would block on it)")
        folders[:] = [f for f in folders if not os.path.islink(Path(root) / f)]  # do not follow links out


def read_metadata(path: Path, file: Path) -> dict:
    """The JSON object of a ``zarr.json``, or the error naming it as damaged."""
    try:
        raw = read_input_bytes(file, MAX_METADATA)
    except BikeriderError as exc:
        raise damaged(path, f"{file}: {_plain(exc, file)}") from None
    if not raw.strip():
        raise damaged(path, f"{file} is empty")
    try:
        data = json.loads(raw)
    except (ValueError, RecursionError) as exc:
        raise damaged(path, f"{file} is not valid JSON: {str(exc)[:80]}") from None
    if not isinstance(data, dict):
        raise damaged(path, f"{file} is not a JSON object")
    return data


def _plain(exc: Exception, file: Path) -> str:
    return str(exc).removeprefix(f"{file}: ")


def group_attributes(path: Path) -> dict:
    """The attributes of the store's group, checked to be readable (not that they are this run's)."""
    data = read_metadata(path, path / "zarr.json")
    attrs = data.get("attributes")
    if data.get("node_type") != "group" or not isinstance(attrs, dict):
        raise damaged(path, f"{path / 'zarr.json'} is not the metadata of a group")
    return attrs


def check_metadata(path: Path, arrays: dict[str, tuple[tuple[int, ...], tuple[int, ...], str]]) -> None:
    """Every array ``name -> (shape, chunks, dtype)`` of the run is in the store as the run made it."""
    for name, (shape, chunks, dtype) in arrays.items():
        file = path / name / "zarr.json"
        if not file.exists():
            raise damaged(path, f"the array {name} is missing ({file} does not exist)")
        data = read_metadata(path, file)
        try:
            found_shape = tuple(data["shape"])
            found_chunks = tuple(data["chunk_grid"]["configuration"]["chunk_shape"])
            found_type = data["data_type"]
        except (KeyError, TypeError):
            raise damaged(path, f"{file} is not the metadata of an array") from None
        if (found_shape, found_chunks, found_type) != (shape, chunks, dtype):
            raise damaged(
                path,
                f"the array {name} has shape {list(found_shape)}, chunks {list(found_chunks)}, type {found_type}; "
                f"the run wrote shape {list(shape)}, chunks {list(chunks)}, type {dtype}",
            )


def chunk_digest(result: dict[str, np.ndarray]) -> dict[str, int]:
    """A checksum (CRC-32) of each array's values of one chunk: what its done-marker records."""
    return {name: zlib.crc32(np.ascontiguousarray(array).tobytes()) for name, array in sorted(result.items())}


def read_marker(path: Path, marker: Path) -> dict[str, int] | None:
    """The checksums a done-marker records (None: a marker of a store written before they were)."""
    try:
        raw = read_input_bytes(marker, 1 << 16)
    except BikeriderError as exc:
        raise damaged(path, f"the marker {marker}: {_plain(exc, marker)}") from None
    if not raw.strip():
        return None
    try:
        data = json.loads(raw)
    except ValueError:
        data = None
    if not (isinstance(data, dict) and all(isinstance(v, int) for v in data.values())):
        raise damaged(path, f"the marker {marker} is garbled")
    return data


def verify_chunk(path: Path, k: int, read) -> bool:
    """Chunk ``k`` reads back to the checksums of its marker (``read(name)``: its values); ``False`` for a
    marker without checksums (one written before markers held them, or emptied since), whose chunk is
    only checked to decode: its values cannot be checked (a resuming run computes it again)."""
    marker = path / "done" / str(k)
    expected = read_marker(path, marker)
    if expected is None:
        try:
            read(None)
        except BikeriderError:
            raise
        except Exception as exc:  # zarr's codecs raise what their libraries raise
            raise damaged(path, f"chunk {k} cannot be read ({type(exc).__name__}: {str(exc)[:80]})") from None
        return False
    names = list(expected)
    try:
        found = chunk_digest({name: read(name) for name in names})
    except BikeriderError:
        raise
    except Exception as exc:  # zarr's codecs raise what their libraries raise (RuntimeError, ValueError, ...)
        raise damaged(path, f"chunk {k} cannot be read ({type(exc).__name__}: {str(exc)[:80]})") from None
    for name in names:
        if found.get(name) != expected[name]:
            raise damaged(
                path,
                f"chunk {k} of the array {name} is not what the run wrote (deleted, truncated or changed "
                "after it was finished)",
            )
    return True


class StoreLock:
    """An exclusive lock on a store folder for one run (see the module docstring)."""

    def __init__(self, folder: Path):
        self.file = folder / LOCK_NAME
        self.fd: int | None = None

    def acquire(self) -> StoreLock:
        fd = os.open(self.file, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK, 0o644)
        try:
            if not stat.S_ISREG(os.fstat(fd).st_mode):
                raise damaged(self.file.parent, f"{self.file} is not a regular file")
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                if exc.errno not in (errno.EWOULDBLOCK, errno.EACCES):
                    raise
                raise InputError(
                    "--store",
                    str(self.file.parent),
                    f"a store no other run is writing ({self._holder(fd)} holds it: wait for it to finish, or "
                    "give another folder)",
                ) from None
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()}\n".encode())
        except BaseException:
            os.close(fd)
            raise
        self.fd = fd
        return self

    @staticmethod
    def _holder(fd: int) -> str:
        try:
            text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
        except OSError:
            text = ""
        return f"the process {text}" if text.isdigit() else "another run"

    def release(self) -> None:
        if self.fd is not None:
            os.close(self.fd)  # closing the descriptor releases the flock
            self.fd = None

    def __del__(self):
        self.release()


__all__ = [
    "LOCK_NAME",
    "MAX_METADATA",
    "StoreLock",
    "check_files",
    "check_metadata",
    "chunk_digest",
    "damaged",
    "group_attributes",
    "read_marker",
    "verify_chunk",
]
