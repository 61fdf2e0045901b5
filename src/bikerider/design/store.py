"""Results of a design-space run, written chunk by chunk to a Zarr store, and read back.

Layout of a store folder (a Zarr v3 group; any Zarr reader opens it, e.g. ``zarr.open_group`` or
``xarray.open_zarr``):

* one array per output of :data:`bikerider.design.engine.FIELDS`, first dimension the design (flat
  index; for a grid, C order over the axes), chunked like the run;
* for a random space, ``value:<name>``: the drawn value of each varied parameter;
* attributes: the design space (``space``, JSON: base, axes or draws, seed), the map speeds, the
  weave speeds, the chunk size, the table of reason codes and the version that wrote it;
* ``done/<k>``: an empty file per finished chunk, created after its arrays are written.

A chunk is finished exactly when its marker exists: a run that is stopped (killed, interrupted)
leaves at most the chunks being written without markers, and the next run with the same store
redoes those and only those.  A store is tied to its run: opening it for a different space, speeds
or chunk size is an error, never a silent mix.  Without a folder the store lives in memory.
"""

from __future__ import annotations

import json
import logging
import math
import os
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bikerider import __version__
from bikerider.design import store_check
from bikerider.design.engine import FIELDS
from bikerider.design.space import DesignSpace
from bikerider.design.validity import REASONS
from bikerider.errors import InputError

LOG = logging.getLogger(__name__)

FORMAT = "bikerider design store 1"


def zarr_module():
    """``zarr``, or an error that names the extra to install."""
    try:  # an optional extra: imported when a run asks for a store
        import zarr
    except ImportError:
        raise InputError(
            "--store", "zarr not installed", "pip install 'bikerider[design]' (the Zarr store of a design-space run)"
        ) from None
    return zarr


@dataclass(frozen=True)
class RunSpec:
    """What a store holds: the space and the settings that shape its arrays."""

    space: DesignSpace
    speeds: np.ndarray
    weave_speeds: np.ndarray
    chunk_size: int

    @property
    def n_chunks(self) -> int:
        return -(-self.space.size // self.chunk_size)

    def chunk_range(self, k: int) -> tuple[int, int]:
        start = k * self.chunk_size
        return start, min(self.space.size, start + self.chunk_size)

    def attributes(self) -> dict:
        return {
            "format": FORMAT,
            "space": self.space.to_json(),
            "speeds": self.speeds.tolist(),
            "weave_speeds": self.weave_speeds.tolist(),
            "chunk_size": self.chunk_size,
            "reasons": [list(r) for r in REASONS],
            "fields": {f.name: f.doc for f in FIELDS},
            "bikerider": __version__,
        }


def _width(field, spec: RunSpec) -> tuple[int, ...]:
    if field.width == "3":
        return (3,)
    if field.width == "speeds":
        return (spec.weave_speeds.size,)
    if field.width == "bits":
        return ((spec.speeds.size + 7) // 8,)
    return ()


_FILL = {"bool": False, "int16": 0, "int8": 0, "uint8": 0, "float64": math.nan}


class DesignStore:
    """A Zarr store of one run: create or resume, write chunks, read outputs.

    Use :func:`open_store` to read a finished (or partial) run.
    """

    def __init__(self, group, spec: RunSpec, path: Path | None):
        self.group, self.spec, self.path = group, spec, path
        self._done_memory: set[int] = set()
        self._lock: store_check.StoreLock | None = None

    # -- creation ----------------------------------------------------------------------------
    @classmethod
    def create_or_resume(cls, path: str | Path | None, spec: RunSpec, restart: bool = False) -> DesignStore:
        """Open the store of ``spec`` at ``path`` (created when missing; in memory when None).

        The run holds the store's lock (:class:`bikerider.design.store_check.StoreLock`) until
        :meth:`close` (or the end of the process); a store being resumed is checked first
        (:meth:`verify`).

        Raises
        ------
        InputError
            ``path`` holds another run (a different space, speeds or chunk size), is not a store,
            is damaged (naming what, and ``--restart``), or another run holds it.
        """
        zarr = zarr_module()
        if path is None:
            group = zarr.open_group(zarr.storage.MemoryStore(), mode="w")
            store = cls(group, spec, None)
            store._create()
            return store
        path = Path(path)
        _check_folder(path, restart)
        path.mkdir(exist_ok=True)
        lock = store_check.StoreLock(path).acquire()
        try:
            _check_locked_folder(path, restart)
            if restart:
                _clear(path)
            if os.path.lexists(path / "zarr.json"):
                store = cls._resume(path, spec)
            else:
                store = cls(zarr.open_group(str(path), mode="a"), spec, path)  # "w" would remove the lock
                store._create()
        except BaseException:
            lock.release()
            raise
        store._lock = lock
        return store

    @classmethod
    def _resume(cls, path: Path, spec: RunSpec) -> DesignStore:
        """The store of this run at ``path``, checked (files, metadata, finished chunks)."""
        attrs = _checked_attributes(path)
        mine = spec.attributes()
        for key in ("space", "speeds", "weave_speeds", "chunk_size"):
            if attrs.get(key) != mine[key]:
                raise InputError(
                    "--store",
                    str(path),
                    f"a new folder, or the same run to resume (its {key} {'differ' if key.endswith('s') else 'differs'}"
                    "; remove the folder or give --restart to start again)",
                )
        store = cls(_open_group(path, spec, "a"), spec, path)
        store.verify(recompute_unchecked=True)
        return store

    def expected_arrays(self) -> dict[str, tuple[tuple[int, ...], tuple[int, ...], str]]:
        """Every array of the run: ``name -> (shape, chunks, dtype)``."""
        return _expected_arrays(self.spec)

    def verify(self, recompute_unchecked: bool = False) -> None:
        """Check that every finished chunk reads back to what the run wrote (its marker's checksums).

        A chunk whose marker holds no checksums (written before markers held them, or emptied since) is
        only checked to decode; with ``recompute_unchecked`` (a run resuming the store) its marker is
        removed, so the run computes the chunk again (a changed value in it would otherwise go unseen),
        otherwise (a reader) it is read as it is, with a warning.

        Raises
        ------
        InputError
            Naming the damaged chunk and array, and ``--restart``.
        """
        if self.path is None:
            return
        done = self.path / "done"
        if not done.is_dir():
            raise store_check.damaged(self.path, f"the folder of finished-chunk markers {done} is missing")
        for marker in sorted(done.iterdir()):
            if not (marker.name.isdigit() and int(marker.name) < self.spec.n_chunks):
                raise store_check.damaged(
                    self.path, f"{marker} marks no chunk of this run (chunks 0 to {self.spec.n_chunks - 1})"
                )
            k = int(marker.name)
            start, stop = self.spec.chunk_range(k)

            def read(name, start=start, stop=stop):
                if name is None:
                    return [self.read(n, start, stop) for n in self.expected_arrays()]
                return self.read(name, start, stop)

            if store_check.verify_chunk(self.path, k, read):
                continue
            if recompute_unchecked:
                marker.unlink()
                LOG.info("%s: chunk %d has a marker without checksums: computed again", self.path, k)
            else:
                LOG.warning("%s: chunk %d has a marker without checksums: its values cannot be checked", self.path, k)

    def close(self) -> None:
        """Release the store's lock (another run may then open it)."""
        lock, self._lock = self._lock, None
        if lock is not None:
            lock.release()

    def _create(self) -> None:
        n, chunk = self.spec.space.size, self.spec.chunk_size
        for field in FIELDS:
            width = _width(field, self.spec)
            self.group.create_array(
                field.name,
                shape=(n,) + width,
                chunks=(chunk,) + width,
                dtype=field.dtype,
                fill_value=_FILL[field.dtype],
            )
        if not self.spec.space.is_grid:
            for name in self.spec.space.names:
                self.group.create_array(
                    f"value:{name}", shape=(n,), chunks=(chunk,), dtype="float64", fill_value=math.nan
                )
        self.group.attrs.update(self.spec.attributes())
        if self.path is not None:
            (self.path / "done").mkdir(exist_ok=True)

    # -- progress of the run ----------------------------------------------------------------------
    def is_done(self, k: int) -> bool:
        if self.path is None:
            return k in self._done_memory
        return (self.path / "done" / str(k)).exists()

    def pending(self) -> list[int]:
        """Chunks without a marker, in order."""
        if self.path is None:
            return [k for k in range(self.spec.n_chunks) if k not in self._done_memory]
        done = {int(p.name) for p in (self.path / "done").iterdir() if p.name.isdigit()}
        return [k for k in range(self.spec.n_chunks) if k not in done]

    def write(self, k: int, result: dict[str, np.ndarray]) -> None:
        """Write chunk ``k`` (every array), then its marker."""
        start, stop = self.spec.chunk_range(k)
        stored = {}
        for name, array in result.items():
            target = self.group[name]
            stored[name] = np.asarray(array).astype(target.dtype, copy=False)
            target[start:stop] = stored[name]
        if self.path is None:
            self._done_memory.add(k)
        else:  # the marker records what was written, so that a later run can check it (store_check)
            marker = self.path / "done" / str(k)
            with open(marker, "w", encoding="utf-8") as stream:
                json.dump(store_check.chunk_digest(stored), stream)

    # -- reading ------------------------------------------------------------------------------
    @property
    def complete(self) -> bool:
        return not self.pending()

    def read(self, name: str, start: int = 0, stop: int | None = None) -> np.ndarray:
        """Output ``name`` of designs ``start .. stop - 1``."""
        return np.asarray(self.group[name][start : stop if stop is not None else self.spec.space.size])

    def take(self, name: str, index: np.ndarray) -> np.ndarray:
        """Output ``name`` of the designs at flat indices ``index`` (any order)."""
        index = np.asarray(index, dtype=np.int64)
        order = np.argsort(index, kind="stable")
        array = self.group[name]
        selection = (index[order],) + (slice(None),) * (array.ndim - 1)
        values = np.asarray(array.get_orthogonal_selection(selection))
        out = np.empty_like(values)
        out[order] = values
        return out

    def chunks(self, names: tuple[str, ...] = ()) -> Iterator[tuple[int, int, dict[str, np.ndarray]]]:
        """``(start, stop, {name: array})`` for every finished chunk, in order (memory: one chunk)."""
        for k in range(self.spec.n_chunks):
            if not self.is_done(k):
                continue
            start, stop = self.spec.chunk_range(k)
            yield start, stop, {name: self.read(name, start, stop) for name in names}

    def stable(self, start: int = 0, stop: int | None = None) -> np.ndarray:
        """Self-stability of designs ``start .. stop - 1`` at each map speed, ``(n, speeds)`` bools."""
        bits = self.read("stable", start, stop)
        return np.unpackbits(bits, axis=-1, count=self.spec.speeds.size, bitorder="little").astype(bool)

    def varied_values(self, start: int, stop: int) -> dict[str, np.ndarray]:
        """The varied parameters of designs ``start .. stop - 1`` (grid: from the axes)."""
        if self.spec.space.is_grid:
            return self.spec.space.values(start, stop)
        return {name: self.read(f"value:{name}", start, stop) for name in self.spec.space.names}

    def reason_texts(self, codes: np.ndarray) -> list[str]:
        """``"name: expected ..."`` for reason codes, from the table stored with the run."""
        table = self.group.attrs["reasons"]
        return [f"{table[c][0]}: expected {table[c][1]}" if c else "" for c in np.asarray(codes).tolist()]


def open_store(path: str | Path) -> DesignStore:
    """Open the store of a run (finished or not) for reading.

    Parameters
    ----------
    path : str or Path
        The folder a run wrote (``explore(space, path, ...)`` or ``bikerider sweep --store``).

    Returns
    -------
    DesignStore
        Its space, speeds and every output (``read``, ``stable``, ``reason_texts``).

    Raises
    ------
    InputError
        ``path`` is not a bikerider design store.
    """
    zarr_module()
    path = Path(path)
    if not (path.is_dir() and os.path.lexists(path / "zarr.json")):
        raise InputError("--store", str(path), "the folder of a design-space run (bikerider sweep --store)")
    attrs = _checked_attributes(path)
    try:
        spec = RunSpec(
            DesignSpace.from_json(attrs["space"]),
            np.asarray(attrs["speeds"], dtype=float),
            np.asarray(attrs["weave_speeds"], dtype=float),
            int(attrs["chunk_size"]),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise store_check.damaged(path, f"its attributes (space, speeds, chunk size) cannot be read: {exc}") from None
    store = DesignStore(_open_group(path, spec, "r"), spec, path)
    store.verify()
    return store


# -- the folder of a store ------------------------------------------------------------------------
def _expected_arrays(spec: RunSpec) -> dict[str, tuple[tuple[int, ...], tuple[int, ...], str]]:
    n, chunk = spec.space.size, spec.chunk_size
    out = {}
    for field in FIELDS:
        width = _width(field, spec)
        out[field.name] = ((n,) + width, (chunk,) + width, field.dtype)
    if not spec.space.is_grid:
        for name in spec.space.names:
            out[f"value:{name}"] = ((n,), (chunk,), "float64")
    return out


def _check_folder(path: Path, restart: bool) -> None:
    """Refuse a ``--store`` folder that is not new, empty, or a design store (damaged or not)."""
    if os.path.lexists(path) and not path.is_dir():
        raise InputError("--store", str(path), "a folder for the store (this is a file)")
    if not path.is_dir():
        return
    names = {p.name for p in path.iterdir()}
    if names and not ({"zarr.json", "done", store_check.LOCK_NAME} & names):
        shown = ", ".join(sorted(names)[:4]) + (", ..." if len(names) > 4 else "")
        raise InputError(
            "--store",
            str(path),
            "a new or empty folder, or the store of this run"
            + (" (--restart removes the store's files)" if restart else "")
            + f"; this folder holds {shown} and is not a bikerider design store",
        )


def _check_locked_folder(path: Path, restart: bool) -> None:
    """Under the store's lock: a folder with files but no metadata is a damaged store."""
    names = {p.name for p in path.iterdir()} - {store_check.LOCK_NAME}
    if not restart and names and "zarr.json" not in names:
        raise store_check.damaged(path, f"{path / 'zarr.json'}, the store's metadata, is missing")


def _clear(path: Path) -> None:
    """Remove the files of a store (``--restart``), keeping the folder and its lock."""
    for entry in path.iterdir():
        if entry.name == store_check.LOCK_NAME:
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry)
        else:
            entry.unlink()


def _checked_attributes(path: Path) -> dict:
    """The group attributes of a store whose files and metadata are sound."""
    store_check.check_files(path)
    attrs = store_check.group_attributes(path)
    if attrs.get("format") != FORMAT:
        raise InputError("--store", str(path), "a new folder or the store of this run (not a bikerider design store)")
    return attrs


def _open_group(path: Path, spec: RunSpec, mode: str):
    """The zarr group of a store whose arrays are those of ``spec``."""
    store_check.check_metadata(path, _expected_arrays(spec))
    try:
        return zarr_module().open_group(str(path), mode=mode)
    except Exception as exc:  # zarr raises what its parsers raise on metadata it cannot take
        raise store_check.damaged(path, f"zarr cannot open it ({type(exc).__name__}: {str(exc)[:80]})") from None


__all__ = ["DesignStore", "RunSpec", "open_store", "zarr_module"]
