"""Run the gap diagnosis's linear algebra on one BLAS thread.

The diagnosis does many thousands of small products (4x4 to 10x10 matrices, least-squares
Jacobians of a few columns).  OpenBLAS splits a product over every core once it passes a size
threshold, and its threads then wait for each other on every call; on a machine whose cores are
busy with other work a call can wait a whole scheduler time slice.  On a shared 2-core machine the
SBW diagnosis took about a quarter more processor time with the default threads than with one, and
a third more wall time; its products are too small for a second thread to help.

:func:`one_blas_thread` limits the OpenBLAS libraries loaded in the process (NumPy's and SciPy's,
found in ``/proc/self/maps``) to one thread for the duration of a block and restores their counts
after it.  The results are the same: OpenBLAS computes a product the same way whatever its thread
count.  Where the libraries cannot be found (another BLAS, another operating system) it does nothing.
"""

from __future__ import annotations

import ctypes
import functools
import logging
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import scipy.linalg  # noqa: F401  (loads SciPy's own OpenBLAS, so that it is limited too)

LOG = logging.getLogger(__name__)

_SYMBOLS = (
    ("scipy_openblas_get_num_threads64_", "scipy_openblas_set_num_threads64_"),
    ("scipy_openblas_get_num_threads", "scipy_openblas_set_num_threads"),
    ("openblas_get_num_threads64_", "openblas_set_num_threads64_"),
    ("openblas_get_num_threads", "openblas_set_num_threads"),
)
"""(get, set) thread-count functions of the OpenBLAS builds NumPy and SciPy ship or link."""


@functools.lru_cache(maxsize=1)
def _controls() -> tuple[tuple[Callable[[], int], Callable[[int], None]], ...]:
    """The thread-count functions of every OpenBLAS library loaded in the process."""
    try:
        maps = Path("/proc/self/maps").read_text()
    except OSError:
        return ()
    paths = dict.fromkeys(
        line.split()[-1]
        for line in maps.splitlines()
        if "openblas" in line.lower() and line.split()[-1].startswith("/")
    )
    out = []
    for path in paths:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for get_name, set_name in _SYMBOLS:
            get, put = getattr(lib, get_name, None), getattr(lib, set_name, None)
            if get is not None and put is not None:
                get.restype, get.argtypes = ctypes.c_int, []
                put.restype, put.argtypes = None, [ctypes.c_int]
                out.append((get, put))
                break
    LOG.debug("OpenBLAS thread controls found: %d", len(out))
    return tuple(out)


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Limit OpenBLAS to one thread inside the block (nested blocks are fine)."""
    controls = _controls()
    before = [get() for get, _ in controls]
    try:
        for (_, put), count in zip(controls, before):
            if count != 1:
                put(1)
        yield
    finally:
        for (_, put), count in zip(controls, before):
            if count != 1:
                put(count)


def limit_to_one_thread() -> None:
    """Limit OpenBLAS to one thread for the rest of the process (a worker process of
    :mod:`bikerider.gap.parallel`: its siblings use the other cores)."""
    for get, put in _controls():
        if get() != 1:
            put(1)


def single_blas_thread(function):
    """Decorator: run ``function`` inside :func:`one_blas_thread`."""

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        with one_blas_thread():
            return function(*args, **kwargs)

    return wrapper
