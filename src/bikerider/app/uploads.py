"""Uploaded files: into private temporary folders, under the command line's size limits.

An upload never goes to a path the user named: each set of files (a bicycle and its rider, or an
experiment: model, manifest, windows and logs) gets its own folder made by
:func:`tempfile.mkdtemp` (readable by this user alone), and a file's name within it is the relative
path the browser gives (an experiment keeps its layout, so a manifest's relative paths hold),
checked part by part: no absolute path, no ``..``, no hidden tricks.  A file is created new
(``O_EXCL``, never following a link): nothing is ever overwritten.  Sizes are refused before they
are read: a bicycle or rider file above the readers' limit for files a person writes
(:data:`~bikerider.io.input_file.TEXT_LIMIT`), an experiment's file above the largest any gap
reader accepts (:data:`~bikerider.io.experiment.MAX_LOG_BYTES`); the readers then apply their own
limit for the kind of file, as on the command line.  The folders are removed when the server stops.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
import threading
import uuid
from pathlib import Path

from bikerider.errors import InputError
from bikerider.io.experiment import MAX_LOG_BYTES
from bikerider.io.input_file import TEXT_LIMIT

LIMITS = {"bicycle": TEXT_LIMIT, "experiment": MAX_LOG_BYTES}
"""Largest file of each kind of upload folder [bytes]."""
MAX_FOLDER_BYTES = 2 * MAX_LOG_BYTES
"""Largest total of one folder [bytes]."""
MAX_FILES = 500
"""Most files in one folder (the SBW experiment has 10)."""
MAX_FOLDERS = 50
"""Most upload folders one server keeps."""
_PART = re.compile(r"^[^/\\\x00-\x1f]{1,255}$")


def safe_relative_path(name: str) -> Path:
    """``name`` as a relative path inside an upload folder.

    Raises
    ------
    InputError
        An empty, absolute or over-long path, a part that is ``.``, ``..`` or holds a control
        character or a backslash.
    """
    parts = str(name).split("/")
    expected = "a file name or a relative path of at most 8 parts (no '..', no absolute path)"
    if not name or len(parts) > 8 or str(name).startswith("/"):
        raise InputError("upload", name, expected)
    for part in parts:
        if part in ("", ".", "..") or not _PART.match(part):
            raise InputError("upload", name, expected)
    return Path(*parts)


class UploadFolders:
    """The upload folders of one server, under one private parent folder."""

    def __init__(self, root: str | Path | None = None) -> None:
        self.root = Path(tempfile.mkdtemp(prefix="bikerider-serve-", dir=root))
        self._folders: dict[str, tuple[str, Path]] = {}
        self._sizes: dict[str, int] = {}
        self._lock = threading.Lock()

    def new(self, kind: str) -> str:
        """A new empty folder for an upload of ``kind`` (``"bicycle"`` or ``"experiment"``); its id."""
        if kind not in LIMITS:
            raise InputError("upload kind", kind, f"one of {', '.join(LIMITS)}")
        with self._lock:
            if len(self._folders) >= MAX_FOLDERS:
                raise InputError(
                    "uploads", len(self._folders), f"at most {MAX_FOLDERS} upload folders (restart bikerider serve)"
                )
            ident = uuid.uuid4().hex
            self._folders[ident] = (kind, Path(tempfile.mkdtemp(prefix=f"{kind}-", dir=self.root)))
            self._sizes[ident] = 0
            return ident

    def folder(self, ident: str) -> Path:
        """The folder of ``ident``."""
        try:
            return self._folders[ident][1]
        except KeyError:
            raise InputError("upload folder", ident, "the id of an upload folder of this page") from None

    def check_size(self, ident: str, name: str, size: int) -> None:
        """Refuse a file of ``size`` bytes before it is read (its kind's limit, the folder's total)."""
        kind = self._folders[ident][0] if ident in self._folders else None
        self.folder(ident)
        limit = LIMITS[kind]  # type: ignore[index]
        if size > limit:
            raise InputError(name, f"{size} bytes", f"an uploaded {kind} file of at most {limit} bytes")
        if self._sizes[ident] + size > MAX_FOLDER_BYTES or len(list(self.files(ident))) >= MAX_FILES:
            raise InputError(
                name, f"{size} bytes", f"an upload of at most {MAX_FILES} files and {MAX_FOLDER_BYTES} bytes in all"
            )

    def write(self, ident: str, name: str, stream, size: int) -> Path:
        """Write ``size`` bytes of ``stream`` (a file object) as ``name`` in folder ``ident``, new.

        Raises
        ------
        InputError
            A bad name, a file that exists already, too large a file, or fewer bytes than announced.
        """
        relative = safe_relative_path(name)
        self.check_size(ident, name, size)
        folder = self.folder(ident)
        path = folder / relative
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        if path.parent.resolve() != (folder / relative).parent.resolve() or not path.parent.resolve().is_relative_to(
            folder.resolve()
        ):  # pragma: no cover - the parts are checked; a link cannot be uploaded
            raise InputError("upload", name, "a path inside the upload folder")
        try:
            handle = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o600)
        except FileExistsError:
            raise InputError(
                "upload", name, "a file not uploaded before into this folder (nothing is overwritten)"
            ) from None
        written = 0
        try:
            with os.fdopen(handle, "wb") as out:
                while written < size:
                    chunk = stream.read(min(1 << 16, size - written))
                    if not chunk:
                        break
                    out.write(chunk)
                    written += len(chunk)
        except BaseException:
            path.unlink(missing_ok=True)
            raise
        if written != size:
            path.unlink(missing_ok=True)
            raise InputError(name, f"{written} bytes", f"the {size} bytes announced (the upload was cut short)")
        with self._lock:
            self._sizes[ident] += size
        return path

    def files(self, ident: str) -> list[str]:
        """The relative paths of the files in folder ``ident``, sorted."""
        folder = self.folder(ident)
        return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())

    def path(self, ident: str, name: str) -> Path:
        """The path of the uploaded file ``name`` of folder ``ident``.

        Raises
        ------
        InputError
            A name that is not a file of the folder.
        """
        relative = safe_relative_path(name)
        path = self.folder(ident) / relative
        if not path.is_file():
            raise InputError("file", name, f"one of the uploaded files: {', '.join(self.files(ident)) or 'none yet'}")
        return path

    def remove_all(self) -> None:
        """Remove every upload folder (when the server stops)."""
        shutil.rmtree(self.root, ignore_errors=True)


__all__ = ["LIMITS", "MAX_FILES", "MAX_FOLDER_BYTES", "UploadFolders", "safe_relative_path"]
