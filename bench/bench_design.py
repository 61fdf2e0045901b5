"""Design-space exploration (issue 16): fused kernels, designs per second per core, peak memory.

Designs: 2**18 random benchmark parameter sets (each parameter within +/-50 % of Meijaard et al.
2007), 100 map speeds 0-10 m/s, one thread (per-core figures).

* fused kernel (``bikerider.design.compiled.stability``: canonical matrices, critical-speed
  polynomials, every stable interval, critical speeds, stability at the 100 speeds) against the
  current NumPy path on the same designs: the generated ``canonical_matrices`` and
  ``stability_batch`` plus ``is_stable`` at the speeds, (a) in chunks of 8192 designs, its best size
  (``bikerider.design.engine.numpy_stability``), and (b) in one batch, as ``sweep`` and
  ``stability_map`` evaluate a grid;
* weave eigenvalue at 4 speeds (``compiled.weave_eigenvalues``: characteristic coefficients,
  closed-form quartic, labels) against the NumPy quartic (``engine.numpy_weave``);
* designs per second per core through to the stable intervals, the whole evaluation of a chunk
  (``engine.evaluate``: designs of a grid, vectorised validity, kernel, masks) against a plain
  NumPy user: ``numpy.linalg.eigvals`` of the stacked state matrices at the 100 speeds (on 2000
  designs; its rate is per design), stable where every real part is negative;
* peak memory: a fresh process runs a grid of N designs into a Zarr store (compiled engine,
  default chunks), for N = 1e5, 1e6 and 4e6; its peak resident set size (``ru_maxrss``).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
from common import Context, Row, fmt_time, measure_together, ratio_text

N_DESIGNS = 1 << 18
SPEEDS = np.linspace(0.0, 10.0, 100)
GOAL_KERNEL = 10.0
GOAL_MEMORY_MB = 100.0
"""Largest growth of the peak memory from 1e5 to 4e6 designs."""


def _designs(n: int, seed: int = 11) -> dict[str, np.ndarray]:
    from bikerider.design.compiled import ARGUMENTS
    from bikerider.shipped import named

    base = named("Benchmark")
    rng = np.random.default_rng(seed)
    out = {k: float(base.values[k]) * (1 + 0.5 * rng.uniform(-1, 1, n)) for k in ARGUMENTS if k != "g"}
    out["g"] = np.asarray(9.81)
    return out


def _numpy_one_batch(args: dict[str, np.ndarray], speeds: np.ndarray):
    """What ``sweep``/``stability_map`` do: every design in one batch."""
    from bikerider.generated import benchmark_model as gen

    from bikerider.benchmark.model import matrix_entries
    from bikerider.benchmark.stability import stability_batch

    result = stability_batch(
        matrix_entries(*gen.canonical_matrices(**{k: v for k, v in args.items() if k != "g"})), 9.81
    )
    return result.is_stable(speeds)


def _eigvals_user(args: dict[str, np.ndarray], speeds: np.ndarray) -> np.ndarray:
    """A plain NumPy user: state matrices at every speed, eigvals, all real parts negative."""
    from bench_toolbox import numpy_state_matrices
    from bikerider.generated import benchmark_model as gen

    M, C1, K0, K2 = gen.canonical_matrices(**{k: v for k, v in args.items() if k != "g"})
    return (np.linalg.eigvals(numpy_state_matrices(M, C1, K0, K2, 9.81, speeds)).real < 0).all(axis=-1)


MEMORY_SCRIPT = textwrap.dedent("""
    import resource, sys, tempfile
    import numpy as np
    from bikerider import design
    from bikerider.shipped import named
    n = int(sys.argv[1])
    space = design.grid(named("Benchmark"), {"c": np.linspace(-0.02, 0.2, n // 1000), "lam": np.linspace(0, 0.6, 10),
                                             "mB": np.linspace(40, 120, 100)})
    with tempfile.TemporaryDirectory() as folder:
        design.explore(space, folder + "/store", np.linspace(0, 10, 100), [5.0], engine="compiled")
    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
""")


def run(ctx: Context) -> list[Row]:
    from bikerider import design
    from bikerider.design import compiled, engine
    from bikerider.shipped import named

    compiled.library()
    n = N_DESIGNS // 8 if ctx.quick else N_DESIGNS
    args = _designs(n)
    repeats = 2 if ctx.quick else 5
    rows = []
    buffers = compiled.stability_outputs(n, SPEEDS.size)
    t = measure_together(
        {
            "kernel": lambda: compiled.stability(args, n, SPEEDS, threads=1, out=buffers),
            "kernel_fresh": lambda: compiled.stability(args, n, SPEEDS, threads=1),
            "numpy_chunks": lambda: engine.numpy_stability(args, n, SPEEDS),
            "numpy_batch": lambda: _numpy_one_batch(args, SPEEDS),
        },
        repeats,
        min_sample=0.0,
    )
    got = compiled.stability(args, n, SPEEDS, threads=1)
    want = engine.numpy_stability(args, n, SPEEDS)
    same_bits = int((got["stable_bits"] != want["stable_bits"]).any(axis=-1).sum())
    per = {k: v.median / n for k, v in t.items()}
    ratio = per["numpy_chunks"] / per["kernel"]
    rows.append(
        Row(
            f"fused kernel, {n:,} designs to stable intervals + 100-speed map, one core",
            f"{fmt_time(per['kernel'])}/design = {1 / per['kernel']:,.0f} designs/s ({t['kernel'].text()} per batch)",
            [
                (
                    "current NumPy path in chunks of 8192 (generated functions + stability_batch + is_stable)",
                    f"{fmt_time(per['numpy_chunks'])}/design",
                ),
                ("current NumPy path in one batch (as sweep/stability_map)", f"{fmt_time(per['numpy_batch'])}/design"),
            ],
            f"{ratio:.1f}x vs NumPy in chunks; {per['numpy_batch'] / per['kernel']:.1f}x vs one batch",
            f">= {GOAL_KERNEL:g}x the NumPy path per core",
            ratio >= GOAL_KERNEL,
            [
                f"designs whose 100 stability bits differ between kernel and NumPy: {same_bits} of {n:,}",
                "kernel: one thread, its outputs in arrays reused from call to call (stability(..., out=...)); with new "
                f"arrays each call it takes {fmt_time(per['kernel_fresh'])}/design "
                f"({per['numpy_chunks'] / per['kernel_fresh']:.1f}x): the first touch of fresh memory faults a page per 4 KB; "
                "the NumPy path is single-threaded",
            ],
        )
    )
    weave_speeds = np.array([2.0, 4.0, 6.0, 8.0])
    m = n // 8
    small = {k: (v[:m] if np.ndim(v) else v) for k, v in args.items()}
    t = measure_together(
        {
            "kernel": lambda: compiled.weave_eigenvalues(small, m, weave_speeds, threads=1),
            "numpy": lambda: engine.numpy_weave(small, m, weave_speeds),
        },
        repeats,
        min_sample=0.0,
    )
    diff = np.abs(compiled.weave_eigenvalues(small, m, weave_speeds) - engine.numpy_weave(small, m, weave_speeds))
    pairs = m * weave_speeds.size
    rows.append(
        Row(
            f"weave eigenvalue, {pairs:,} (design, speed) pairs, one core",
            f"{fmt_time(t['kernel'].median / pairs)}/pair",
            [
                (
                    "NumPy: generated coefficients + closed-form quartic + labels",
                    f"{fmt_time(t['numpy'].median / pairs)}/pair",
                )
            ],
            ratio_text(t["numpy"].median, t["kernel"].median) + " vs NumPy",
            "-",
            None,
            [f"largest difference to NumPy: {diff.max():.1e} 1/s"],
        )
    )
    # designs per second per core through to stable intervals: the whole evaluation of a chunk
    space = design.grid(
        named("Benchmark"),
        {"c": np.linspace(-0.02, 0.2, 64), "lam": np.linspace(0.0, 0.6, 64), "mB": np.linspace(40.0, 120.0, 64)},
    )
    size = space.size if not ctx.quick else space.size // 8
    sample = 500 if ctx.quick else 2000
    user_args = {k: (v[:sample] if np.ndim(v) else v) for k, v in args.items()}
    t = measure_together(
        {
            "ours": lambda: engine.evaluate(space, 0, size, SPEEDS, (), "compiled", threads=1),
            "eigvals": lambda: _eigvals_user(user_args, SPEEDS),
        },
        max(2, repeats - 2),
        min_sample=0.0,
    )
    ours, theirs = t["ours"].median / size, t["eigvals"].median / sample
    rows.append(
        Row(
            "designs per second per core, to stable intervals and a 100-speed map",
            f"{1 / ours:,.0f} designs/s (engine.evaluate of {size:,} grid designs: validity, kernel, masks)",
            [("plain NumPy: eigvals of stacked state matrices at 100 speeds", f"{1 / theirs:,.0f} designs/s")],
            ratio_text(theirs, ours) + " vs eigvals",
            "-",
            None,
            ["the eigvals route gives stability at the 100 speeds only; ours also every stable interval exactly"],
        )
    )
    # peak memory against the number of designs
    peaks = {}
    for count in (100_000, 1_000_000) if ctx.quick else (100_000, 1_000_000, 4_000_000):
        proc = subprocess.run(
            [sys.executable, "-c", MEMORY_SCRIPT, str(count)], capture_output=True, text=True, timeout=1800
        )
        peaks[count] = float(proc.stdout.split()[-1]) if proc.returncode == 0 else float("nan")
    growth = max(peaks.values()) - min(peaks.values())
    rows.append(
        Row(
            "peak memory of a run into a store against the number of designs",
            "; ".join(f"{c:.0e} designs: {p:.0f} MiB" for c, p in peaks.items()),
            [],
            f"+{growth:.0f} MiB from {min(peaks):.0e} to {max(peaks):.0e} designs",
            f"flat: < {GOAL_MEMORY_MB:g} MiB growth",
            growth < GOAL_MEMORY_MB,
            [
                "peak resident set of a fresh process (interpreter, NumPy, Zarr and the compiled kernels included), "
                "chunks of 262144 designs; the NumPy path in one batch needs about 1.8 KB per design (1.8 GB per 1e6)"
            ],
        )
    )
    return rows
