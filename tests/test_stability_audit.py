"""The audit of issue 14, reproduced: weave and capsize speeds against a dense eigenvalue scan.

The audit found that the weave speed was the first root of the stability boundary whatever the
direction of the crossing (on 2704 random bicycles, each benchmark parameter within +/-50 %, the
weave pair became *unstable* there for 190 of them) and that ``stable_range`` was None for 32
bicycles stable above their weave speed without a capsize speed.  Only the public API of 780e89d is
used here, so this file runs on the code before the fix (780e89d): with the bicycles of
:func:`random_bicycles.random_parameters` (seed 0; 1624 of the 2704 are stable somewhere below
20 m/s by the scan) it fails there with 167 bicycles whose weave pair does not turn stable at the
reported weave speed, 45 whose capsize eigenvalue does not turn unstable at the reported capsize
speed, and 25 stable bicycles (stable above their weave speed, no capsize speed) whose stable
range was None.  It passes now.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bikerider.benchmark import WhippleModel

GRID = np.linspace(0.0, 20.0, 401)
STEP = GRID[1] - GRID[0]


def _unstable_count(model: WhippleModel, speeds) -> np.ndarray:
    return (np.linalg.eigvals(model.state_matrix(np.asarray(speeds, dtype=float))).real > 0).sum(axis=-1)


def scan_stability(models: list[WhippleModel]) -> np.ndarray:
    """Stable (every eigenvalue with a negative real part) at each speed of GRID, per model."""
    out = []
    for k in range(0, len(models), 400):
        values = np.linalg.eigvals(np.stack([m.state_matrix(GRID) for m in models[k : k + 400]]))
        out.append((values.real < 0).all(axis=-1))
    return np.concatenate(out)


def _intervals_from_scan(stable: np.ndarray) -> list[tuple[float, float]]:
    """Stable runs of the grid as ``(first stable speed, first unstable speed after it or inf)``."""
    out, k = [], 0
    while k < stable.size:
        if stable[k]:
            j = k
            while j + 1 < stable.size and stable[j + 1]:
                j += 1
            out.append((GRID[k], GRID[j + 1] if j + 1 < stable.size else math.inf))
            k = j + 1
        else:
            k += 1
    return out


@pytest.mark.slow
def test_audit_weave_and_capsize_speeds_bound_the_stable_interval_of_a_dense_scan(random_models, random_scan):
    wrong_direction = wrong_capsize = missing_range = unbounded = checked = 0
    for model, stable in zip(random_models, random_scan):
        speeds = model.critical_speeds()
        if speeds.weave is not None:
            eps = 1e-6 * speeds.weave
            below, above = _unstable_count(model, [speeds.weave - eps, speeds.weave + eps])
            wrong_direction += above - below != -2  # the weave pair must turn stable there
        if speeds.capsize is not None:
            eps = 1e-6 * speeds.capsize
            below, above = _unstable_count(model, [speeds.capsize - eps, speeds.capsize + eps])
            wrong_capsize += above - below != 1  # the capsize eigenvalue must turn unstable there
        scanned = _intervals_from_scan(stable)
        if speeds.stable_range is not None and speeds.stable_range[1] - speeds.stable_range[0] < 2 * STEP:
            continue  # narrower than the grid resolves (the next test checks it point by point)
        if not scanned:
            assert speeds.stable_range is None or speeds.stable_range[0] > GRID[-1] - STEP
            continue
        missing_range += speeds.stable_range is None
        if speeds.stable_range is None:
            continue
        lower, upper = speeds.stable_range
        assert scanned[0][0] - STEP <= lower <= scanned[0][0]
        if math.isinf(scanned[0][1]):
            assert upper > GRID[-1]
            unbounded += math.isinf(upper)
        else:
            assert scanned[0][1] - STEP <= upper <= scanned[0][1]
        checked += 1
    assert (wrong_direction, wrong_capsize, missing_range) == (0, 0, 0), (
        f"weave pair not turning stable at the weave speed: {wrong_direction}, capsize eigenvalue not turning "
        f"unstable at the capsize speed: {wrong_capsize}, stable but no stable range: {missing_range}"
    )
    assert checked > 1500 and unbounded > 10  # 1617 checked, 25 of them stable at every speed above weave
