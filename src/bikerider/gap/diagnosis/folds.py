"""The held-out folds of the diagnosis: the data's groups (runs, riders, environments), blocks of whole
groups when there are more than :data:`MAX_FOLDS`, or speed bands when there is one group."""

from __future__ import annotations

import numpy as np

N_SPEED_BANDS = 3
"""Speed bands: the folds of data in one group, and the gap map's bands of eigenvalue speeds."""
MAX_FOLDS = 12
"""Most folds: data in more groups are held out a block of whole groups at a time (a fold costs a fit of
every candidate, so the folds must not grow with the data)."""


def folds(obs) -> list[tuple[str, np.ndarray]]:
    """The held-out folds of the observations ``obs`` (:class:`bikerider.gap.inference.problem.GapProblem`'s
    ``obs``): ``(name, mask)`` of each, by group, by blocks of groups, or by speed band (none when the
    data have one group and one speed)."""
    groups, member = np.unique(np.asarray(obs.group, dtype=str), return_inverse=True)
    if groups.size > MAX_FOLDS:  # whole groups, consecutive in name order, share a fold
        blocks = np.array_split(np.arange(groups.size), MAX_FOLDS)
        return [
            (f"groups {groups[b[0]]} to {groups[b[-1]]} ({b.size})", (member >= b[0]) & (member <= b[-1]))
            for b in blocks
        ]
    if groups.size >= 2:
        return [(f"group {g}", member == k) for k, g in enumerate(groups)]
    speeds = np.unique(obs.speed)
    if speeds.size < 2:
        return []
    bands = np.array_split(speeds, min(N_SPEED_BANDS, speeds.size))
    return [(f"speeds {b[0]:.2f}-{b[-1]:.2f} m/s", (obs.speed >= b[0]) & (obs.speed <= b[-1])) for b in bands]
