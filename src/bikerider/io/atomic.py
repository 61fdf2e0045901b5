"""Atomic file output: a reader of the target sees the old file or the whole new one, never a part.

Every output bikerider writes (figures, tables) goes through :func:`atomic_write_bytes` or
:func:`atomic_write_text`: the data are written to a temporary file in the target's own folder
(so the final rename stays on one file system), flushed to disk, and renamed over the target with
:func:`os.replace`.  If anything fails before the rename, the temporary file is removed and the
target is left as it was.

Before anything is written, :func:`bikerider.io.output_guard.check_output` refuses a target that is
one of the current run's inputs: no command writes over what it reads.
"""

from __future__ import annotations

import io
import os
import tempfile
from pathlib import Path

from bikerider.io.output_guard import check_output


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; return the path.

    Raises
    ------
    OSError
        The folder does not exist or cannot be written (the target is then unchanged).
    InputError
        ``path`` is one of the current run's inputs (:mod:`bikerider.io.output_guard`).
    """
    path = Path(path)
    check_output(path)
    try:
        handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as exc:  # name the file asked for, not the temporary one
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        if path.exists():  # keep the permissions of the file being replaced
            os.chmod(temporary, path.stat().st_mode & 0o7777)
        else:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(temporary, 0o666 & ~umask)
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.unlink(temporary)
    return path


def atomic_write_text(path: str | Path, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically (newlines as given); return the path."""
    return atomic_write_bytes(path, text.encode(encoding))


def figure_bytes(figure, **savefig_options) -> bytes:
    """A matplotlib figure rendered to bytes (PNG unless ``format`` says otherwise)."""
    buffer = io.BytesIO()
    savefig_options.setdefault("format", "png")
    figure.savefig(buffer, **savefig_options)
    return buffer.getvalue()
