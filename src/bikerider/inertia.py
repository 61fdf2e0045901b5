"""Checks that an inertia tensor can belong to a real body."""
from __future__ import annotations

import math

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
    rows = t.tolist()  # nine Python floats: far cheaper than NumPy calls on a 3x3
    xx, xz, zx, zz = rows[0][0], rows[0][2], rows[2][0], rows[2][2]
    if not all(math.isfinite(x) for x in (xx, xz, zx, zz)):
        raise InputError(name, rows, "finite moments and products of inertia", source)
    finite = [(i, j) for i in range(3) for j in range(3) if math.isfinite(rows[i][j]) and math.isfinite(rows[j][i])]
    if any(abs(rows[i][j] - rows[j][i]) > 1e-12 + 1e-12 * abs(rows[j][i]) for i, j in finite):
        raise InputError(name, rows, "a symmetric tensor", source)
    # The checks below are scale invariant; on the tensor over its largest entry they cannot overflow.
    scale = max(abs(rows[i][j]) for i in range(3) for j in range(3) if math.isfinite(rows[i][j])) or 1.0
    b_xx, b_xz, b_zz = xx / scale, xz / scale, zz / scale
    if b_xx <= 0 or b_zz <= 0 or b_xx * b_zz - b_xz**2 <= 0:
        raise InputError(
            name,
            f"Ixx={xx:.6g}, Izz={zz:.6g}, Ixz={xz:.6g}",
            "positive moments with Ixx*Izz > Ixz^2 (a positive definite tensor)",
            source,
        )
    if math.isfinite(rows[1][1]):
        unit = _principal_moments(t / scale)
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


#: Margin, relative to the tensor's largest entry, by which :func:`clearly_valid_plane_symmetric`
#: wants each test passed (far above the round-off of the few operations either check does).
_CLEAR_MARGIN = 1e-12


def clearly_valid_plane_symmetric(xx: float, yy: float | None, zz: float, xz: float) -> bool:
    """Whether :func:`check_inertia_tensor` certainly accepts the tensor of a body symmetric about
    its XZ plane, ``[[xx, 0, xz], [0, yy, 0], [xz, 0, zz]]`` (``yy`` None: not determined, the xz
    block alone is checked).

    The same tests on the same scaled entries in plain floats (positive definite xz block, positive
    principal moments, triangle inequality), each passed by :data:`_CLEAR_MARGIN` and the triangle
    inequality without the full check's slack.  ``False`` means only "not shown here": the caller
    then runs the full check, which raises with its own message or accepts a borderline tensor.
    Non-finite entries give ``False`` (every comparison with NaN fails).
    """
    if yy is not None and not math.isfinite(yy):
        return False
    scale = max(abs(xx), abs(zz), abs(xz), 0.0 if yy is None else abs(yy))
    if not 0.0 < scale < math.inf:
        return False
    b_xx, b_zz, b_xz = xx / scale, zz / scale, xz / scale
    if not (b_xx > _CLEAR_MARGIN and b_zz > _CLEAR_MARGIN and b_xx * b_zz - b_xz * b_xz > _CLEAR_MARGIN):
        return False
    if yy is None:
        return True
    mean, radius = (b_xx + b_zz) / 2, math.hypot((b_xx - b_zz) / 2, b_xz)
    low, middle, high = sorted((mean - radius, yy / scale, mean + radius))
    return low > _CLEAR_MARGIN and high + _CLEAR_MARGIN <= low + middle


def check_plane_symmetric_inertia(name: str, xx: float, yy: float | None, zz: float, xz: float,
                                  source: str | None = None) -> None:
    """:func:`check_inertia_tensor` of ``[[xx, 0, xz], [0, yy, 0], [xz, 0, zz]]`` (``yy`` None: not
    determined), with the clear cases decided in plain floats (:func:`clearly_valid_plane_symmetric`)
    and the rest, with every error message, left to the full check."""
    if clearly_valid_plane_symmetric(xx, yy, zz, xz):
        return
    tensor = np.array([[xx, 0.0, xz], [0.0, math.nan if yy is None else yy, 0.0], [xz, 0.0, zz]], dtype=float)
    check_inertia_tensor(name, tensor, source)


def plane_symmetric_principal_moments(xx: float, yy: float, zz: float, xz: float) -> list[float]:
    """Ascending principal moments of ``[[xx, 0, xz], [0, yy, 0], [xz, 0, zz]]``: ``yy`` and the two
    moments of the xz block, ``(xx + zz) / 2 -+ hypot((xx - zz) / 2, xz)``."""
    mean, radius = (xx + zz) / 2, math.hypot((xx - zz) / 2, xz)
    return sorted((mean - radius, yy, mean + radius))


def _principal_moments(t: np.ndarray) -> np.ndarray:
    """Ascending principal moments.  A body symmetric about its XZ plane (zero xy and yz entries,
    every body of the benchmark) has them in closed form; any other tensor goes to ``eigvalsh``."""
    if t[0, 1] == 0 and t[1, 0] == 0 and t[1, 2] == 0 and t[2, 1] == 0:
        return np.array(plane_symmetric_principal_moments(float(t[0, 0]), float(t[1, 1]), float(t[2, 2]),
                                                          float(t[0, 2])))
    return np.linalg.eigvalsh(t)
