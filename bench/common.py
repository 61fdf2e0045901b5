"""Shared pieces of the benchmarks: timing, result rows, the BicycleParameters baseline, machine facts.

Timing.  :func:`measure` calls a function in loops long enough to read a clock well (at least
:data:`MIN_SAMPLE` seconds a loop), repeats that, and reports the median time per call over the
repeats (with the repeat and loop counts).  Baselines and bikerider are always measured in the
same run; :func:`measure_together` interleaves their timed loops round by round, so a change of
load during the run slows all of them alike.  (On a shared virtual machine the speed can change by
a factor of two from one second to the next; where a ratio is close to its goal, BicycleParameters
is timed in rounds interleaved with bikerider's too, through :class:`BaselineServer`.)

BicycleParameters cannot share the project's virtual environment (it pins its own dependencies),
so it lives in ``bench/.venv-baseline`` (``make bench`` creates it) and runs in a subprocess,
:file:`bench/bp_worker.py`, which times itself and prints JSON.
"""

from __future__ import annotations

import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BENCH = ROOT / "bench"
BASELINE_VENV = BENCH / ".venv-baseline"
BASELINE_PYTHON = BASELINE_VENV / "bin" / "python"
DATA = ROOT / "src" / "bikerider" / "data" / "bicycleparameters"
MIN_SAMPLE = 0.05
"""Seconds one timed loop lasts at least."""

if str(ROOT) not in sys.path:  # derive/ is imported from the repository root
    sys.path.insert(0, str(ROOT))


@dataclass(frozen=True)
class Timing:
    """Median seconds per call over ``repeats`` loops of ``loops`` calls."""

    median: float
    repeats: int
    loops: int

    def text(self) -> str:
        return f"{fmt_time(self.median)} (median of {self.repeats}x{self.loops})"


@dataclass
class Row:
    """One line of the results table."""

    item: str
    bikerider: str
    baselines: list[tuple[str, str]] = field(default_factory=list)
    ratio: str = "-"
    goal: str = "-"
    met: bool | None = None
    notes: list[str] = field(default_factory=list)


@dataclass
class Context:
    """What every benchmark module receives."""

    quick: bool = False
    repeats: int = 7
    only: tuple[str, ...] = ()
    """The modules named with ``--only`` (a long item runs only when named)."""
    _bp: dict = field(default_factory=dict)
    _tmp: Path | None = None

    def tmpdir(self) -> Path:
        if self._tmp is None:
            self._tmp = Path(tempfile.mkdtemp(prefix="bikerider-bench-"))
        return self._tmp

    def bp_data(self) -> Path:
        """A private copy of the BicycleParameters data (BicycleParameters may write into it)."""
        target = self.tmpdir() / "bpdata"
        if not target.exists():
            shutil.copytree(DATA, target)
        return target

    def bp(self, task: str, **params) -> dict:
        """Run a task of ``bench/bp_worker.py`` in the baseline environment (cached per task+params).

        Returns ``{"error": message}`` when the baseline is not available.
        """
        key = json.dumps([task, params], sort_keys=True)
        if key not in self._bp:
            self._bp[key] = run_bp_worker(task, {"data": str(self.bp_data()), **params})
        return self._bp[key]

    def bp_server(self) -> BaselineServer | str:
        """A running :class:`BaselineServer`, or why there is none."""
        if not BASELINE_PYTHON.exists():
            return (
                f"BicycleParameters baseline not installed ({BASELINE_VENV.relative_to(ROOT)} missing; "
                "`make bench` creates it with pip install bicycleparameters)"
            )
        return BaselineServer(self.bp_data())

    def cleanup(self) -> None:
        if self._tmp is not None:
            shutil.rmtree(self._tmp, ignore_errors=True)


def fmt_time(seconds: float) -> str:
    """``1.23 ms`` style."""
    if seconds != seconds:  # NaN
        return "n/a"
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6), ("ns", 1e-9)):
        if seconds >= scale:
            return f"{seconds / scale:.3g} {unit}"
    return f"{seconds / 1e-9:.3g} ns"


def loops_for(fn: Callable[[], object], min_sample: float = MIN_SAMPLE) -> int:
    """How many calls of ``fn`` one timed loop needs to last at least ``min_sample`` seconds (``fn``
    is called once first, to warm up)."""
    fn()
    loops = 1
    while True:
        start = time.perf_counter()
        for _ in range(loops):
            fn()
        elapsed = time.perf_counter() - start
        if elapsed >= min_sample or loops >= 1_000_000:
            return loops
        loops *= max(2, min(10, int(min_sample / max(elapsed, 1e-9)) + 1))


def time_loop(fn: Callable[[], object], loops: int) -> float:
    """Seconds per call of ``fn`` over one loop of ``loops`` calls."""
    start = time.perf_counter()
    for _ in range(loops):
        fn()
    return (time.perf_counter() - start) / loops


def measure(fn: Callable[[], object], repeats: int = 7, min_sample: float = MIN_SAMPLE) -> Timing:
    """Median seconds per call of ``fn`` (one warm-up call first)."""
    loops = loops_for(fn, min_sample)
    return Timing(statistics.median(time_loop(fn, loops) for _ in range(repeats)), repeats, loops)


def measure_together(
    fns: dict[str, Callable[[], object]], repeats: int = 7, min_sample: float = MIN_SAMPLE
) -> dict[str, Timing]:
    """:func:`measure` for several functions, their timed loops interleaved round by round, so a
    change in the machine's load during the run affects all of them alike."""
    loops = {name: loops_for(fn, min_sample) for name, fn in fns.items()}
    samples: dict[str, list[float]] = {name: [] for name in fns}
    for _ in range(repeats):
        for name, fn in fns.items():
            samples[name].append(time_loop(fn, loops[name]))
    return {name: Timing(statistics.median(samples[name]), repeats, loops[name]) for name in fns}


def ratio_text(baseline: float, ours: float) -> str:
    return f"{baseline / ours:.1f}x" if ours > 0 and baseline == baseline else "n/a"


def run_bp_worker(task: str, params: dict, timeout: float = 600) -> dict:
    """Run ``bench/bp_worker.py TASK JSON`` with the baseline interpreter; parse its JSON output."""
    if not BASELINE_PYTHON.exists():
        return {
            "error": f"BicycleParameters baseline not installed ({BASELINE_VENV.relative_to(ROOT)} missing; "
            "`make bench` creates it with pip install bicycleparameters)"
        }
    try:
        proc = subprocess.run(
            [str(BASELINE_PYTHON), str(BENCH / "bp_worker.py"), task, json.dumps(params)],
            capture_output=True,
            text=True,
            timeout=timeout,
            cwd=str(ROOT),
        )
    except subprocess.TimeoutExpired:
        return {"error": f"BicycleParameters worker timed out after {timeout:.0f} s ({task})"}
    if proc.returncode != 0:
        tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        return {"error": f"BicycleParameters worker failed ({task}): {tail}"}
    try:
        return json.loads(proc.stdout.strip().splitlines()[-1])
    except (json.JSONDecodeError, IndexError):
        return {"error": f"BicycleParameters worker printed no JSON ({task})"}


class BaselineServer:
    """``bench/bp_worker.py serve`` kept running, so BicycleParameters can be timed in rounds
    interleaved with bikerider's (the machine's speed may change between two separate runs).

    Use as a context manager; :meth:`call` sends one task and returns its JSON reply.
    """

    def __init__(self, data: Path, timeout: float = 600):
        self.data, self.timeout = data, timeout
        self.process: subprocess.Popen | None = None

    def __enter__(self) -> BaselineServer:
        self.process = subprocess.Popen(
            [str(BASELINE_PYTHON), str(BENCH / "bp_worker.py"), "serve"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=str(ROOT),
        )
        return self

    def call(self, task: str, **params) -> dict:
        assert self.process is not None and self.process.stdin is not None and self.process.stdout is not None
        self.process.stdin.write(f"{task} {json.dumps({'data': str(self.data), **params})}\n")
        self.process.stdin.flush()
        line = self.process.stdout.readline()
        if not line:
            tail = (self.process.stderr.read().strip().splitlines() or ["no output"])[-1] if self.process.stderr else ""
            return {"error": f"BicycleParameters worker stopped ({task}): {tail}"}
        return json.loads(line)

    def __exit__(self, *exc) -> None:
        if self.process is not None:
            self.process.stdin.close()  # type: ignore[union-attr]
            try:
                self.process.wait(timeout=self.timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
            for stream in (self.process.stdout, self.process.stderr):
                if stream is not None:
                    stream.close()


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine_facts(ctx: Context) -> dict[str, str]:
    """CPU, cores, load, and the versions of everything measured."""
    import numpy
    import scipy
    import sympy

    facts = {
        "CPU": cpu_model(),
        "cores": str(os.cpu_count()),
        "load average at start (1/5/15 min)": " / ".join(f"{x:.2f}" for x in os.getloadavg()),
        "OS": platform.platform(),
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "sympy": sympy.__version__,
    }
    versions = ctx.bp("versions")
    if "error" in versions:
        facts["bicycleparameters"] = versions["error"]
    else:
        facts["bicycleparameters"] = (
            f"{versions['bicycleparameters']} (own venv: python {versions['python']}, "
            f"numpy {versions['numpy']}, uncertainties {versions['uncertainties']})"
        )
    return facts
