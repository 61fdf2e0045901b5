"""Checks that an inertia tensor can belong to a real body."""
from __future__ import annotations

import numpy as np

from bikerider.errors import InputError

#: Relative slack for the triangle inequality, for round-off in tensors computed from data.
TRIANGLE_TOLERANCE = 1e-9


def check_inertia_tensor(name: str, tensor: np.ndarray, source: str | None = None) -> None:
    """Raise :class:`InputError` unless ``tensor`` is symmetric, positive definite and its
    principal moments satisfy the triangle inequality (each at most the sum of the other two).

    A tensor with NaN in the yy entry (not measured) is checked in its xz block only.
    """
    t = np.asarray(tensor, dtype=float)
    if t.shape != (3, 3):
        raise InputError(name, t.shape, "a 3x3 inertia tensor", source)
    xz = t[np.ix_([0, 2], [0, 2])]
    if not np.all(np.isfinite(xz)):
        raise InputError(name, t.tolist(), "finite moments and products of inertia", source)
    if not np.allclose(t[np.isfinite(t)], t.T[np.isfinite(t)], rtol=1e-12, atol=1e-12):
        raise InputError(name, t.tolist(), "a symmetric tensor", source)
    # The checks below are scale invariant; on the tensor over its largest entry they cannot overflow.
    scale = float(np.abs(t[np.isfinite(t)]).max()) or 1.0
    b = xz / scale
    if b[0, 0] <= 0 or b[1, 1] <= 0 or b[0, 0] * b[1, 1] - b[0, 1] ** 2 <= 0:
        raise InputError(
            name,
            f"Ixx={xz[0, 0]:.6g}, Izz={xz[1, 1]:.6g}, Ixz={xz[0, 1]:.6g}",
            "positive moments with Ixx*Izz > Ixz^2 (a positive definite tensor)",
            source,
        )
    if np.isfinite(t[1, 1]):
        unit = np.linalg.eigvalsh(t / scale)
        principal = unit * scale
        if unit[0] <= 0:
            raise InputError(name, principal.tolist(), "positive principal moments of inertia", source)
        slack = TRIANGLE_TOLERANCE * unit.sum()
        if unit[2] > unit[0] + unit[1] + slack:
            raise InputError(
                name,
                f"principal moments {principal[0]:.6g}, {principal[1]:.6g}, {principal[2]:.6g}",
                "each principal moment at most the sum of the other two (triangle inequality)",
                source,
            )
