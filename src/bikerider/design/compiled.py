"""The fused C kernels of ``generated/design_kernels.py``: compiled at first use, called through ctypes.

The C source is emitted by ``derive/kernels.py`` from the same SymPy expressions as the NumPy
functions.  It is compiled once per machine with the C compiler found on ``PATH`` (``$CC``, else
``cc``, ``gcc`` or ``clang``) and kept in a cache folder (``$BIKERIDER_CACHE``, else
``$XDG_CACHE_HOME/bikerider``, else ``~/.cache/bikerider``) under a name that hashes the source,
the compiler, the flags and the processor's instruction set, so a changed kernel, compiler or
processor compiles anew and concurrent processes (Dask workers) never load a half-written
library (it is written elsewhere and renamed into place).  Flags: ``-O3 -ffp-contract=off`` (no fused
multiply-add contraction and no ``-ffast-math``: the kernels round as NumPy does) and
``-march=native`` where the compiler accepts it.

Every core: a call splits its designs into one contiguous range per thread and runs the ranges
on a :class:`concurrent.futures.ThreadPoolExecutor`; ctypes releases the GIL during a foreign call,
so the threads run in parallel.
"""

from __future__ import annotations

import ctypes
import hashlib
import logging
import os
import platform
import shutil
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache
from pathlib import Path

import numpy as np

from bikerider.benchmark.stability import MAX_INTERVALS
from bikerider.errors import BikeriderError
from bikerider.generated import design_kernels as source
from bikerider.generated.manifest import KERNELS

LOG = logging.getLogger(__name__)

BASE_FLAGS = ("-O3", "-ffp-contract=off", "-fno-math-errno", "-fno-trapping-math", "-fPIC", "-shared")
"""Compiler flags.  No ``-ffast-math`` and no contraction into fused multiply-adds, so every
operation rounds as in NumPy; ``-fno-math-errno`` and ``-fno-trapping-math`` only drop ``errno``
and floating-point traps (``sqrt`` becomes one instruction, selects need no branches): they change
no result."""
_STABILITY = KERNELS["design_kernels.bikerider_stability"]
_WEAVE = KERNELS["design_kernels.bikerider_weave"]
ARGUMENTS = _STABILITY["args"]
"""The kernels' inputs, in order (from the manifest; both kernels take the same)."""


class KernelUnavailable(BikeriderError):
    """The fused kernels cannot be built on this machine (no C compiler, or it failed)."""


def cache_dir() -> Path:
    """Where compiled kernels are kept."""
    if os.environ.get("BIKERIDER_CACHE"):
        return Path(os.environ["BIKERIDER_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "bikerider"


def find_compiler() -> str | None:
    """The C compiler: ``$CC`` or the first of cc, gcc, clang on ``PATH``."""
    for name in ([os.environ["CC"]] if os.environ.get("CC") else []) + ["cc", "gcc", "clang"]:
        path = shutil.which(name.split()[0])
        if path:
            return path
    return None


def _compiler_version(compiler: str) -> str:
    try:
        proc = subprocess.run([compiler, "--version"], capture_output=True, text=True, timeout=30)
        return proc.stdout.splitlines()[0] if proc.stdout else compiler
    except (OSError, subprocess.SubprocessError):
        return compiler


def _cpu() -> str:
    """What ``-march=native`` depends on: the processor's instruction-set flags (a cache shared by
    machines of different processors keeps one library for each)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith(("flags", "Features")):
                return line
    except OSError:
        pass
    return platform.machine() + platform.processor()


def _compile(compiler: str, c_file: Path, target: Path, flags: tuple[str, ...]) -> subprocess.CompletedProcess:
    return subprocess.run(
        [compiler, *flags, "-o", str(target), str(c_file), "-lm"], capture_output=True, text=True, timeout=600
    )


@lru_cache(maxsize=1)
def library() -> ctypes.CDLL:
    """The compiled kernels (compiled now if the cache has none for this source and compiler).

    Raises
    ------
    KernelUnavailable
        No C compiler on ``PATH``, or the compiler failed (its message is included).
    """
    compiler = find_compiler()
    if compiler is None:
        raise KernelUnavailable(
            "the fused kernels need a C compiler (cc, gcc or clang on PATH, or $CC); "
            "without one use engine='numpy' (the same results, slower)"
        )
    version = _compiler_version(compiler)
    folder = cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    for flags in (BASE_FLAGS + ("-march=native",), BASE_FLAGS):
        key = hashlib.sha256("\0".join([source.C_SOURCE, version, _cpu(), *flags]).encode()).hexdigest()[:20]
        target = folder / f"design_kernels-{key}.so"
        if not target.exists():
            with tempfile.TemporaryDirectory(dir=folder) as tmp:
                c_file = Path(tmp) / "design_kernels.c"
                c_file.write_text(source.C_SOURCE, encoding="utf-8")
                built = Path(tmp) / target.name
                LOG.info("compiling the fused kernels with %s (once per machine)", compiler)
                proc = _compile(compiler, c_file, built, flags)
                if proc.returncode != 0:
                    LOG.debug("compiler failed with %s: %s", flags, proc.stderr[-2000:])
                    error = proc.stderr.strip().splitlines()[-1:] or ["no message"]
                    continue
                os.replace(built, target)  # atomic: other processes see the whole library or none
        lib = ctypes.CDLL(str(target))
        _declare(lib)
        return lib
    raise KernelUnavailable(
        f"the C compiler {compiler} could not build the fused kernels ({error[0]}); "
        "use engine='numpy' (the same results, slower)"
    )


def available() -> bool:
    """Whether the fused kernels can be used here (compiles them on first call)."""
    try:
        library()
    except KernelUnavailable as exc:
        LOG.warning("%s", exc)
        return False
    return True


def _declare(lib: ctypes.CDLL) -> None:
    p, i64 = ctypes.c_void_p, ctypes.c_int64
    lib.bikerider_stability.restype = i64
    lib.bikerider_stability.argtypes = [i64, i64, p, p, p, p, p, p, p, p, p, p, i64, p, p]
    lib.bikerider_weave.restype = i64
    lib.bikerider_weave.argtypes = [i64, i64, p, p, i64, p, p, p]


def default_threads() -> int:
    """Cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def _inputs(arguments: dict[str, np.ndarray], n: int):
    """Pointer and stride arrays for the kernels' inputs (a scalar broadcasts with stride 0)."""
    keep, pointers, strides = [], (ctypes.c_void_p * len(ARGUMENTS))(), (ctypes.c_int64 * len(ARGUMENTS))()
    for k, name in enumerate(ARGUMENTS):
        array = np.ascontiguousarray(arguments[name], dtype=float).reshape(-1)
        if array.size not in (1, n):
            raise ValueError(f"{name}: {array.size} values for {n} designs")
        keep.append(array)
        pointers[k] = array.ctypes.data
        strides[k] = 0 if array.size == 1 and n != 1 else 1
    return keep, pointers, strides


def _ranges(n: int, threads: int) -> list[tuple[int, int]]:
    block = source.BLOCK
    per = -(-n // max(1, threads))
    per = -(-per // block) * block
    return [(start, min(n, start + per)) for start in range(0, n, per)] or [(0, 0)]


def _run(call, n: int, threads: int | None) -> None:
    if n == 0:
        return
    ranges = _ranges(n, threads or default_threads())
    if len(ranges) == 1:
        call(*ranges[0])
        return
    with ThreadPoolExecutor(len(ranges)) as pool:
        list(pool.map(lambda r: call(*r), ranges))


def _ptr(array: np.ndarray):
    return array.ctypes.data


def _shape(width: str, n: int, n_speeds: int) -> tuple[int, ...]:
    """The shape of an output of ``n`` designs from its width in the manifest."""
    return {"": (n,), "3": (n, MAX_INTERVALS), "bits": (n, (n_speeds + 7) // 8), "speeds": (n, n_speeds)}[width]


def stability_outputs(n: int, n_speeds: int) -> dict[str, np.ndarray]:
    """Empty output arrays of :func:`stability` for ``n`` designs (to reuse across calls; the
    stability bits zeroed, as the kernel sets only the stable ones)."""
    return {
        name: np.zeros(_shape(width, n, n_speeds), dtype=dtype)
        if width == "bits"
        else np.empty(_shape(width, n, n_speeds), dtype=dtype)
        for name, dtype, width in _STABILITY["outputs"]
    }


def stability(
    arguments: dict[str, np.ndarray],
    n: int,
    speeds=(),
    threads: int | None = None,
    out: dict[str, np.ndarray] | None = None,
) -> dict[str, np.ndarray]:
    """Stable intervals, crossing kinds, critical speeds, mass-matrix check and stability bits at
    the ascending ``speeds`` of ``n`` designs (the outputs of ``bikerider_stability``, as
    :func:`bikerider.design.engine.numpy_stability` returns them).

    ``arguments`` maps every name of :data:`ARGUMENTS` to ``n`` values or one (broadcast).  ``out``
    (from :func:`stability_outputs`) is filled instead of new arrays: fresh memory costs a page
    fault per 4 KB on first touch, about a third of the kernel's time."""
    lib = library()
    keep, pointers, strides = _inputs(arguments, n)
    v = np.ascontiguousarray(speeds, dtype=float).reshape(-1)
    if v.size > 1 and not np.all(np.diff(v) > 0):
        raise ValueError("the map speeds must be ascending (the kernel bisects them)")
    if out is None:
        out = stability_outputs(n, v.size)
    elif out["mass_ok"].dtype != np.int8 or out["stable_bits"].shape != (n, (v.size + 7) // 8):
        raise ValueError("out: arrays of stability_outputs(n, len(speeds))")
    *per_design, bits = (name for name, _, _ in _STABILITY["outputs"])  # the bits follow the speeds

    def call(start: int, stop: int) -> None:
        lib.bikerider_stability(
            start,
            stop,
            ctypes.addressof(pointers),
            ctypes.addressof(strides),
            *(_ptr(out[name]) for name in per_design),
            v.size,
            _ptr(v),
            _ptr(out[bits]),
        )

    _run(call, n, threads)
    del keep
    return {**out, "mass_ok": out["mass_ok"].astype(bool)}


def weave_eigenvalues(arguments: dict[str, np.ndarray], n: int, speeds, threads: int | None = None) -> np.ndarray:
    """The labelled weave eigenvalue (positive imaginary part) of ``n`` designs at each speed, ``(n, k)``."""
    lib = library()
    keep, pointers, strides = _inputs(arguments, n)
    v = np.ascontiguousarray(speeds, dtype=float).reshape(-1)
    out = {name: np.empty(_shape(width, n, v.size), dtype=dtype) for name, dtype, width in _WEAVE["outputs"]}

    def call(start: int, stop: int) -> None:
        lib.bikerider_weave(
            start,
            stop,
            ctypes.addressof(pointers),
            ctypes.addressof(strides),
            v.size,
            _ptr(v),
            *(_ptr(out[name]) for name, _, _ in _WEAVE["outputs"]),
        )

    _run(call, n, threads)
    del keep
    return out["real"] + 1j * out["imag"]


__all__ = [
    "ARGUMENTS",
    "KernelUnavailable",
    "available",
    "cache_dir",
    "default_threads",
    "find_compiler",
    "library",
    "stability",
    "stability_outputs",
    "weave_eigenvalues",
]
