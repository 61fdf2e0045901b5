"""Independent pieces of the diagnosis and the plan at once, one per core (forked worker processes).

The diagnosis cross-validates every candidate, then every pair, each on its own: a fit to all the
data and one per held-out fold.  Those are independent of each other, so
:func:`cross_validate_all` hands them to worker processes, forked from the process that holds the
diagnosis (the data, the fitted nominal model and the fits made so far are shared, not copied),
and takes back each one's :class:`~bikerider.gap.diagnosis.fits.CrossValidation` and the full-data fits
it made.  Every computation is the same as in one process (the order of the work changes nothing:
each fit depends only on its own candidate), so the results are identical; the time is shared
among the cores.

:func:`map_forked` does the same for any list of independent tasks (the plan's record fits and its
rivals' predictions).

Workers: one per core the process may use, or ``$BIKERIDER_GAP_WORKERS`` (``1``: everything in the
one process).  Worker processes are used only where ``fork`` exists (Linux) and not from inside a
worker process of another pool.
"""

from __future__ import annotations

import gc
import logging
import multiprocessing
import os
import queue
import signal
import sys

from bikerider import progress
from bikerider.errors import InputError
from bikerider.gap.blas_threads import limit_to_one_thread

LOG = logging.getLogger(__name__)
WORKERS_ENV = "BIKERIDER_GAP_WORKERS"
"""Environment variable: how many worker processes the diagnosis may use (``1``: none)."""

MIN_OBSERVATIONS = 100
"""Without records, the fewest observations for which the candidates are cross-validated on workers
(below it a candidate takes about as long as starting the workers)."""
MIN_RECORDS = 8
"""The fewest records fitted on workers (a record fit takes a few hundredths of a second)."""

_FITS = None
"""The diagnosis's fits the forked workers work on (set just before they are forked)."""
_TASK = None
"""The function :func:`map_forked`'s workers call (set just before they are forked)."""


def workers() -> int:
    """Worker processes to use: ``$BIKERIDER_GAP_WORKERS`` or the cores this process may run on."""
    value = os.environ.get(WORKERS_ENV, "").strip()
    if value:
        try:
            count = int(value)
        except ValueError:
            count = 0
        if count < 1:
            raise InputError(WORKERS_ENV, value, "a whole number of worker processes, 1 or more (1: no workers)")
        return count
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _can_fork(count: int) -> bool:
    return (
        count >= 2
        and sys.platform.startswith("linux")
        and "fork" in multiprocessing.get_all_start_methods()
        and not multiprocessing.current_process().daemon
    )


def _call(item):
    return _TASK(item)


def map_forked(function, items, min_items: int = 2) -> list:
    """``[function(item) for item in items]``, the calls shared among worker processes (forked, so
    ``function`` may be any callable, a closure included; the items and results are pickled).

    In the one process when there are fewer than two workers, fewer than ``min_items`` items (work
    too small to pay for starting the workers, about a tenth of a second), or no ``fork``.
    """
    global _TASK
    items = list(items)
    count = min(workers(), len(items))
    if len(items) < min_items or not _can_fork(count):
        return [function(item) for item in items]
    _TASK = function
    try:
        pool = _pool(count)
        if pool is None:
            return [function(item) for item in items]
        with pool:
            return pool.map(_call, items, chunksize=1)
    finally:
        _TASK = None
        gc.unfreeze()


def _start_worker() -> None:
    # the parent process handles Ctrl-C (and ends the workers); a worker stops without a traceback
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    limit_to_one_thread()  # one BLAS thread per worker: the workers share the cores


def _pool(count: int):
    """A pool of ``count`` forked workers, or ``None`` where the system cannot make one (no shared
    memory for its locks, a process limit): the work then runs in this process."""
    try:
        # the objects made so far stay out of the workers' garbage collection: it would touch (and so
        # copy) every page they share with this process
        gc.freeze()
        return multiprocessing.get_context("fork").Pool(count, initializer=_start_worker)
    except OSError as exc:
        LOG.info("no worker processes (%s): working in one process", exc)
        return None


def _caches(fits) -> tuple[dict, ...]:
    """The caches of a diagnosis's fits a worker fills and hands back."""
    return fits.full, fits.bias_corrected, fits.time_domain_full, fits.corner_shares


def _merge(fits, entries: list[dict]) -> None:
    """Cache entries made elsewhere (one dictionary per cache of :func:`_caches`) added to ``fits``'s."""
    for cache, new in zip(_caches(fits), entries):
        for key, value in new.items():
            cache.setdefault(key, value)


def _work(task):
    effects, given = task
    fits = _FITS
    _merge(fits, given)  # what the parent has learnt since this worker was forked
    caches = _caches(fits)
    known = [set(cache) for cache in caches]
    result = fits.cross_validate(effects)
    if effects in fits.time_domain_full:  # its interval's friction corner: refits of its own, on this worker too
        fits.corner_share(effects, fits.time_domain_full[effects].values)
    return effects, result, [{k: v for k, v in cache.items() if k not in old} for cache, old in zip(caches, known)]


def _given(fits, effects: tuple[str, ...]) -> list[dict]:
    """The parent's cache entries of a set's single effects (a pair's fit starts from its singles' fits):
    handed to the worker with the task, so it need not fit them again."""
    singles = {(e,) for e in effects} if len(effects) > 1 else set()
    return [{k: v for k, v in cache.items() if k in singles} for cache in _caches(fits)]


def cross_validate_all(fits, effect_sets, cost=len, then=None) -> None:
    """Cross-validate ``effect_sets`` (tuples of effect names) of a diagnosis's fits on worker processes.

    Fills the caches of ``fits`` (a :class:`~bikerider.gap.diagnosis.fits.Fits`: its cross-validations,
    its fits to all the data and their bias-corrected starts, its time-domain fits and their friction
    corners' shares) as its own ``cross_validate`` would; with fewer than two workers or sets to do, does
    nothing (the diagnosis then works them out one by one when it asks for them).  ``cost`` ranks a set's
    expected cost (the costliest start first).

    Each worker gets one set at a time, the costliest waiting.  ``then()``, called in this process after
    each set is done, may name further sets (those whose inputs are now known, e.g. the pairs of two
    candidates done): they wait with the rest for the same workers, so no worker idles while the last of
    ``effect_sets`` finish, and are cross-validated as well (not counted in the progress: their own stage
    counts them when it asks for them).
    """
    global _FITS
    todo = [tuple(e) for e in dict.fromkeys(tuple(e) for e in effect_sets) if tuple(e) not in fits.cv]
    count = min(workers(), len(todo))
    # workers pay where the candidates are costly: records (each fit simulates them) or many observations
    if not _can_fork(count) or not (fits.record_rows or len(fits.problem.obs) >= MIN_OBSERVATIONS):
        return
    todo.sort(key=cost, reverse=True)  # the costliest first: the pool ends together
    LOG.debug("cross-validating %d candidate sets on %d worker processes", len(todo), count)
    _FITS = fits
    try:
        pool = _pool(count)
        if pool is None:
            return
        with pool:
            done: queue.SimpleQueue = queue.SimpleQueue()
            waiting, running, counted = list(todo), set(), set(todo)

            def dispatch() -> None:
                # one set per free worker, the costliest waiting first (so a costly set found late starts
                # before cheap ones found early: the workers end together)
                while waiting and len(running) < count:
                    effects = max(waiting, key=cost)
                    waiting.remove(effects)
                    running.add(effects)
                    task = ((effects, _given(fits, effects)),)
                    pool.apply_async(_work, task, callback=done.put, error_callback=done.put)

            dispatch()
            while running:
                item = done.get()
                if isinstance(item, BaseException):  # a worker's error reaches the caller, as in one process
                    raise item
                effects, result, made = item
                running.discard(effects)
                fits.cv[effects] = result
                if effects in counted:  # in the parent: the workers' own counts are not seen
                    progress.advance(len(result.folds))
                _merge(fits, made)
                if then is not None:
                    known = set(fits.cv) | running | set(waiting)
                    waiting += [e for e in dict.fromkeys(tuple(e) for e in then()) if e not in known]
                dispatch()
    finally:
        _FITS = None
        gc.unfreeze()
