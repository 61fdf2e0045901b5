"""Run a design space chunk by chunk into a store: resumable, with a progress bar, memory flat.

:func:`explore` evaluates the chunks a store does not hold yet (all of them for a new store) with
:func:`bikerider.design.engine.evaluate` and writes each to the store as soon as it is done, so
the memory a run needs is that of a chunk or two whatever the number of designs, and a run that
is stopped resumes where it stopped.  The next chunk is computed while the previous one is
written (one writer thread).  ``scheduler`` sends the chunks to a Dask cluster instead
(:mod:`bikerider.design.distributed`).
"""

from __future__ import annotations

import logging
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from bikerider.design import engine as engines
from bikerider.design.distributed import run_on_dask
from bikerider.design.progress import Progress
from bikerider.design.space import DesignSpace
from bikerider.design.store import DesignStore, RunSpec
from bikerider.errors import InputError

LOG = logging.getLogger(__name__)

DEFAULT_CHUNK = 1 << 18
"""Designs per chunk: about 60 MB of inputs, temporaries and outputs, a few tenths of a second."""
MAX_CHUNK = 1 << 22


def check_speeds(speeds, option: str) -> np.ndarray:
    """Ascending, finite, non-negative speeds, or an error naming the option."""
    v = np.atleast_1d(np.asarray(speeds, dtype=float)) if np.size(speeds) else np.empty(0)
    if v.ndim != 1 or not np.all(np.isfinite(v)) or np.any(v < 0) or np.any(np.diff(v) <= 0):
        raise InputError(
            option,
            v.tolist() if v.size < 10 else f"{v.size} speeds",
            "finite, non-negative speeds [m/s] in ascending order",
        )
    return v


def run_spec(space: DesignSpace, speeds=(), weave_speeds=(), chunk_size: int | None = None) -> RunSpec:
    """The settings of a run, checked."""
    if chunk_size is None:
        chunk_size = max(1, min(DEFAULT_CHUNK, space.size))
    if not (isinstance(chunk_size, (int, np.integer)) and 1 <= chunk_size <= MAX_CHUNK):
        raise InputError("--chunk-size", chunk_size, f"a whole number of designs between 1 and {MAX_CHUNK}")
    return RunSpec(
        space, check_speeds(speeds, "--speeds"), check_speeds(weave_speeds, "--weave-speeds"), int(chunk_size)
    )


def explore(
    space: DesignSpace,
    store: str | Path | None = None,
    speeds=(),
    weave_speeds=(),
    *,
    chunk_size: int | None = None,
    engine: str = "auto",
    threads: int | None = None,
    restart: bool = False,
    quiet: bool = True,
    scheduler=None,
    workers: int | None = None,
    keep_lock: bool = False,
) -> DesignStore:
    """Evaluate every design of ``space`` into a store.

    Parameters
    ----------
    space : DesignSpace
        :func:`bikerider.design.grid`, :func:`~bikerider.design.random_designs` or
        :func:`~bikerider.design.monte_carlo`.
    store : str or Path, optional
        Folder of the Zarr store; a run into an existing store of the same run resumes it (only
        the chunks without a marker are computed).  None: in memory (small spaces).
    speeds : array_like
        Ascending speeds [m/s] of the stability map (self-stable or not at each).
    weave_speeds : array_like
        Speeds [m/s] at which to report the weave frequency and damping ratio.
    chunk_size : int, optional
        Designs per chunk (default :data:`DEFAULT_CHUNK`); a store keeps the size it was made with.
    engine : {"auto", "compiled", "numpy"}
        :func:`bikerider.design.engine.evaluate`.
    threads : int, optional
        Threads of the compiled engine (default every core).
    restart : bool
        Discard an existing store at ``store`` and start again.
    quiet : bool
        No progress bar (the command line shows one unless ``--quiet``).
    scheduler : str or "local", optional
        Run on Dask: ``"local"`` for a ``LocalCluster`` on this machine, or a scheduler address
        (``tcp://host:8786``) (:func:`bikerider.design.distributed.run_on_dask`).
    workers : int, optional
        Workers of the local cluster (default: one per core).
    keep_lock : bool
        Keep the store's lock after the run, for reading it back (a summary) before another run may open
        it with ``--restart`` and remove its files; the caller then releases it (``DesignStore.close``).

    Returns
    -------
    DesignStore
        The results (:mod:`bikerider.design.summary` summarises them).
    """
    spec = run_spec(space, speeds, weave_speeds, chunk_size)
    engine = engines.resolve_engine(engine)
    result = DesignStore.create_or_resume(store, spec, restart)
    pending = result.pending()
    done_before = space.size - sum(spec.chunk_range(k)[1] - spec.chunk_range(k)[0] for k in pending)
    progress = Progress(space.size - done_before, done_before, quiet)
    if done_before:
        text = f"resuming {store}: {spec.n_chunks - len(pending)} of {spec.n_chunks} chunks already stored, " + (
            f"{len(pending)} to compute" if pending else "nothing to compute"
        )
        LOG.info("%s", text)
        progress.note(text)
    if scheduler is not None:
        run_on_dask(result, pending, engine, scheduler, workers, progress)
    else:
        _run_local(result, pending, engine, threads, progress)
    progress.close()
    if not keep_lock:
        result.close()  # the run is done: its lock goes (a failed run's goes with the store object)
    return result


def _run_local(store: DesignStore, pending: list[int], engine: str, threads: int | None, progress: Progress) -> None:
    spec = store.spec
    with ThreadPoolExecutor(1, thread_name_prefix="bikerider-store") as writer:
        writing = None
        for k in pending:
            start, stop = spec.chunk_range(k)
            result = engines.evaluate(spec.space, start, stop, spec.speeds, spec.weave_speeds, engine, threads)
            if writing is not None:
                writing.result()
            writing = writer.submit(store.write, k, result)
            writing.add_done_callback(lambda f, n=stop - start: progress.update(n) if f.exception() is None else None)
        if writing is not None:
            writing.result()


__all__ = ["DEFAULT_CHUNK", "check_speeds", "explore", "run_spec"]
