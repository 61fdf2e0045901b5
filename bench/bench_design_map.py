"""The 6.4e7-design stability map (issue 16): six parameters at 20 values, 100 speeds, two cores.

Run alone (minutes, both cores): ``.venv/bin/python bench/run.py --only design_map``; ``make bench``
lists it without running it.  The design space: the benchmark bicycle (Meijaard et al. 2007) with
trail ``c`` 0-0.15 m, steer axis tilt ``lam`` 0-36 deg, wheelbase ``w`` 0.8-1.3 m, front-assembly
inertia ``IHzz`` 0.002-0.03 kg m^2, front-wheel spin inertia ``IFyy`` 0.1-0.28 kg m^2 and the
rear body's (rider's) centre of mass ``xB`` 0.1-0.6 m, 20 values each: 6.4e7 designs, each
self-stable or not at 100 speeds 0-10 m/s (6.4e9 points), and every stable interval, weave and
capsize speed, written chunk by chunk to a Zarr store (``bikerider.design.explore``, compiled
engine, every core).  Timed: the whole run, wall clock, with the machine's load average before
and after.  Checked: 2000 designs drawn at random from the store against a dense eigenvalue scan
(``numpy.linalg.eigvals`` of the state matrices at the same 100 speeds).
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
from common import Context, Row

GOAL_SECONDS = 600.0
SAMPLE = 2000
AXES = {
    "c": (0.0, 0.15),
    "lam": (0.0, np.radians(36.0)),
    "w": (0.8, 1.3),
    "IHzz": (0.002, 0.03),
    "IFyy": (0.1, 0.28),
    "xB": (0.1, 0.6),
}


def run(ctx: Context) -> list[Row]:
    side = 8 if ctx.quick else 20
    item = f"stability map: {side**6:.2g} designs (6 parameters x {side} values) x 100 speeds, into a Zarr store"
    if "design_map" not in ctx.only:
        return [Row(item, "not run (minutes on both cores): python bench/run.py --only design_map", met=None)]
    from bikerider import design
    from bikerider.design import compiled
    from bikerider.shipped import named

    compiled.library()
    base = named("Benchmark")
    space = design.grid(base, {k: np.linspace(lo, hi, side) for k, (lo, hi) in AXES.items()})
    speeds = np.linspace(0.0, 10.0, 100)
    folder = tempfile.mkdtemp(prefix="bikerider-map-")
    try:
        load_before = os.getloadavg()
        start = time.perf_counter()
        store = design.explore(space, os.path.join(folder, "map"), speeds, engine="compiled", quiet=False)
        seconds = time.perf_counter() - start
        load_after = os.getloadavg()
        size = sum(f.stat().st_size for f in Path(folder).rglob("*") if f.is_file())
        disagree, near, checked = _check_sample(store, space, base, speeds)
        valid = int(sum(chunk["valid"].sum() for _, _, chunk in store.chunks(("valid",))))
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return [
        Row(
            item,
            f"{seconds:.0f} s wall ({space.size / seconds:,.0f} designs/s, "
            f"{space.size * speeds.size / seconds:,.0f} (design, speed) points/s)",
            [
                (
                    "dense eigenvalue scan of a sample",
                    f"{checked} designs x 100 speeds: {disagree} points differ "
                    f"({near} within 1e-6 m/s of an interval end)",
                )
            ],
            "-",
            f"< {GOAL_SECONDS:.0f} s on 2 cores; identical to the scan",
            seconds < GOAL_SECONDS and disagree == 0,
            [
                f"{space.size:,} designs ({valid:,} valid), {speeds.size} speeds; store {size / 2**30:.2f} GiB on disk",
                f"load average (1/5/15 min) before {' / '.join(f'{x:.2f}' for x in load_before)}, "
                f"after {' / '.join(f'{x:.2f}' for x in load_after)}; {os.cpu_count()} cores",
                f"compiled engine, {compiled.default_threads()} threads, chunks of 262144 designs, computing "
                "overlapped with writing",
            ],
        )
    ]


def _check_sample(store, space, base, speeds):
    """Stability at the 100 speeds of random stored designs against eigvals of their state matrices."""
    from bikerider.generated import benchmark_model as gen

    from bikerider.benchmark import WhippleModel

    rng = np.random.default_rng(16)
    index = np.sort(rng.choice(space.size, SAMPLE, replace=False))
    valid = store.take("valid", index)
    index = index[valid]
    stable = np.unpackbits(store.take("stable", index), axis=-1, count=speeds.size, bitorder="little").astype(bool)
    lower, upper = store.take("lower", index), store.take("upper", index)
    coordinates = np.unravel_index(index, space.shape)
    drawn = {axis.name: axis.values[k] for axis, k in zip(space.axes, coordinates)}
    from bikerider.design.compiled import ARGUMENTS  # canonical_matrices' arguments, then g

    args = {k: drawn.get(k, float(base.values[k])) for k in ARGUMENTS if k != "g"}
    model = WhippleModel(*gen.canonical_matrices(**args), g=float(base.values["g"]))
    scan = (np.linalg.eigvals(model.state_matrix(speeds)).real < 0).all(axis=-1)
    ends = np.concatenate([lower, upper], axis=-1)
    near_end = (np.abs(speeds[None, :, None] - ends[:, None, :]) < 1e-6).any(axis=-1)
    differ = stable != scan
    return int((differ & ~near_end).sum()), int((differ & near_end).sum()), int(index.size)
