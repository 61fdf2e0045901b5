"""Design-space runs on a Dask cluster (``dask.distributed``), for users who outgrow one machine.

The cluster evaluates chunks, the client writes them: each pending chunk becomes one task that
runs :func:`bikerider.design.engine.evaluate` (the generated batched functions, or the fused
kernels, on that chunk) on a worker and returns its arrays; the client writes each result to the
store as it arrives (so the store needs no shared file system, and resuming works as for a local
run).  At most :data:`IN_FLIGHT` tasks per worker are submitted at once, so the client's memory
stays that of a few chunks.  ``scheduler="local"`` starts a ``LocalCluster`` on this machine (one
single-threaded worker process per core); any other value is the address of a running scheduler.
"""

from __future__ import annotations

import logging

from bikerider.design.compiled import default_threads
from bikerider.design.engine import evaluate
from bikerider.errors import InputError

LOG = logging.getLogger(__name__)

IN_FLIGHT = 2
"""Tasks submitted per worker ahead of the results."""
CONNECT_TIMEOUT = "20s"
"""How long to wait for a scheduler at an address."""


def dask_distributed():
    """``dask.distributed``, or an error that names the extra to install."""
    try:  # an optional extra: imported when a run asks for Dask
        import dask.distributed
    except ImportError:
        raise InputError(
            "--dask", "dask.distributed not installed", "pip install 'bikerider[distributed]' (runs on a Dask cluster)"
        ) from None
    return dask.distributed


def quiet_dask_logs() -> None:
    """Dask's own log lines (cluster start, worker start, ...) only when bikerider logs at INFO (``-v``).

    ``dask.distributed`` logs at INFO to stderr by default, in this process and in the worker
    processes it starts (which take the configuration at start-up).
    """
    import dask  # with dask.distributed, imported by the caller: an optional extra

    level = "info" if logging.getLogger("bikerider").getEffectiveLevel() <= logging.INFO else "warning"
    dask.config.set({"logging.distributed": level, "distributed.logging.distributed": level})
    for name in ("distributed", "distributed.nanny", "distributed.scheduler", "distributed.worker"):
        logging.getLogger(name).setLevel(level.upper())


def evaluate_chunk(space, start: int, stop: int, speeds, weave_speeds, engine: str):
    """The task a worker runs: one chunk, single-threaded (the cluster provides the parallelism)."""
    return evaluate(space, start, stop, speeds, weave_speeds, engine, threads=1)


def run_on_dask(store, pending: list[int], engine: str, scheduler, workers: int | None, progress) -> None:
    """Evaluate the ``pending`` chunks of ``store`` on Dask and write them (see the module docstring)."""
    distributed = dask_distributed()
    quiet_dask_logs()
    spec = store.spec
    cluster = None
    if scheduler == "local":
        cluster = distributed.LocalCluster(
            n_workers=workers or default_threads(), threads_per_worker=1, processes=True, dashboard_address=None
        )
        address = cluster
    else:
        address = scheduler
    try:
        client = distributed.Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:  # ValueError: an address Dask cannot parse
        if cluster is not None:
            cluster.close()
        raise InputError("--dask", str(scheduler), f"the address of a running Dask scheduler ({exc})") from None
    try:
        n_workers = max(1, len(client.scheduler_info().get("workers", {})))
        queue = list(pending)
        futures = {}

        def submit():
            k = queue.pop(0)
            start, stop = spec.chunk_range(k)
            future = client.submit(
                evaluate_chunk, space, start, stop, spec.speeds, spec.weave_speeds, engine, pure=False
            )
            futures[future] = k
            return future

        space = client.scatter(spec.space, broadcast=True)
        finished = distributed.as_completed([submit() for _ in range(min(len(queue), IN_FLIGHT * n_workers))])
        for future in finished:
            k = futures.pop(future)
            store.write(k, future.result())
            start, stop = spec.chunk_range(k)
            progress.update(stop - start)
            future.release()
            if queue:
                finished.add(submit())
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


__all__ = ["IN_FLIGHT", "dask_distributed", "evaluate_chunk", "run_on_dask"]
