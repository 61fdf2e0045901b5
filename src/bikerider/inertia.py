"""The one check that an inertia tensor can belong to a real body.

A tensor of a real body is symmetric and positive definite, and its principal moments satisfy the
triangle inequality: each is at most the sum of the other two (``I_1 + I_2 - I_3 = 2 int x_3^2 dm
>= 0``).  Tensors computed from measurements carry round-off, so the triangle inequality is allowed
:data:`TRIANGLE_TOLERANCE` relative to the sum of the principal moments; every check of the project
(bodies, benchmark parameters, BicycleParameters files, a Measured file's compound-pendulum
``I_yy``, the rider) goes through :func:`inertia_problem`, so all use that one margin.

Every body of the benchmark is symmetric about its XZ plane: its tensor is
``[[xx, 0, xz], [0, yy, 0], [xz, 0, zz]]``, ``y`` is a principal axis, and the principal moments are
``yy`` and those of the xz block in closed form (:func:`plane_symmetric_principal_moments`), so
the check runs on plain floats.
"""

from __future__ import annotations

import math

import numpy as np

from bikerider.errors import InputError

#: Relative slack of the triangle inequality (of the sum of the principal moments), for round-off
#: in tensors computed from data.
TRIANGLE_TOLERANCE = 1e-9
#: Largest relative asymmetry ``|t_ij - t_ji|`` accepted (beyond an absolute 1e-12) in a general tensor.
SYMMETRY_TOLERANCE = 1e-12
#: What a plane-symmetric tensor of a real body must have, in the order checked: the ``expected``
#: of each :class:`InputError`, and the rules :func:`broken_rules` numbers from 1.
TENSOR_RULES = (
    "finite moments and products of inertia",
    "positive moments with Ixx*Izz > Ixz^2 (a positive definite tensor)",
    "positive principal moments of inertia",
    "each principal moment at most the sum of the other two (triangle inequality)",
)
FINITE, POSITIVE_DEFINITE, POSITIVE_PRINCIPAL, TRIANGLE = TENSOR_RULES


def plane_symmetric_principal_moments(xx: float, yy: float, zz: float, xz: float) -> list[float]:
    """Ascending principal moments of ``[[xx, 0, xz], [0, yy, 0], [xz, 0, zz]]``: ``yy`` and the two
    moments of the xz block, ``(xx + zz) / 2 -+ hypot((xx - zz) / 2, xz)``."""
    mean, radius = (xx + zz) / 2, math.hypot((xx - zz) / 2, xz)
    return sorted((mean - radius, yy, mean + radius))


def inertia_problem(xx: float, yy: float | None, zz: float, xz: float) -> tuple[object, str] | None:
    """Why a plane-symmetric tensor cannot belong to a real body, or ``None`` when it can.

    ``yy`` None or NaN: not determined, the xz block alone is checked.  Returns ``(value shown,
    what was expected)`` for an :class:`InputError`.
    """
    yy_known = yy is not None and math.isfinite(yy)
    if not (math.isfinite(xx) and math.isfinite(xz) and math.isfinite(zz)):
        return [[xx, 0.0, xz], [0.0, yy if yy_known else math.nan, 0.0], [xz, 0.0, zz]], FINITE
    # The checks below are scale invariant; on the tensor over its largest entry they cannot overflow.
    scale = max(abs(xx), abs(zz), abs(xz), abs(yy) if yy_known else 0.0) or 1.0
    b_xx, b_xz, b_zz = xx / scale, xz / scale, zz / scale
    if b_xx <= 0 or b_zz <= 0 or b_xx * b_zz - b_xz**2 <= 0:
        return f"Ixx={xx:.6g}, Izz={zz:.6g}, Ixz={xz:.6g}", POSITIVE_DEFINITE
    if not yy_known:
        return None
    unit = plane_symmetric_principal_moments(b_xx, yy / scale, b_zz, b_xz)  # type: ignore[operator]
    return _principal_problem(unit, scale)


def _principal_problem(unit: list[float], scale: float) -> tuple[object, str] | None:
    """The positivity and triangle checks on ascending principal moments of the scaled tensor."""
    principal = [p * scale for p in unit]
    if unit[0] <= 0:
        return principal, POSITIVE_PRINCIPAL
    if unit[2] > unit[0] + unit[1] + TRIANGLE_TOLERANCE * math.fsum(unit):
        return f"principal moments {principal[0]:.6g}, {principal[1]:.6g}, {principal[2]:.6g}", TRIANGLE
    return None


def broken_rules(xx, yy, zz, xz) -> np.ndarray:
    """:func:`inertia_problem` for arrays of plane-symmetric tensors (any broadcast shape): the number
    of the first of :data:`TENSOR_RULES` each breaks, from 1; 0 where it can belong to a real body.

    The same checks in the same order, without a Python call per tensor (design spaces check
    millions); ``yy`` NaN: not determined, the xz block alone is checked."""
    xx, yy, zz, xz = (np.asarray(a, dtype=float) for a in (xx, yy, zz, xz))
    out = np.zeros(np.broadcast_shapes(xx.shape, yy.shape, zz.shape, xz.shape), dtype=np.int8)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        has_yy = np.isfinite(yy)
        scale = np.maximum(
            np.maximum(np.abs(xx), np.abs(zz)), np.maximum(np.abs(xz), np.where(has_yy, np.abs(yy), 0.0))
        )
        scale = np.where(scale > 0, scale, 1.0)
        b_xx, b_xz, b_zz, b_yy = xx / scale, xz / scale, zz / scale, yy / scale
        mean, radius = (b_xx + b_zz) / 2, np.hypot((b_xx - b_zz) / 2, b_xz)
        first, third = mean - radius, mean + radius
        low = np.minimum(np.minimum(first, b_yy), third)
        high = np.maximum(np.maximum(first, b_yy), third)
        middle = first + b_yy + third - low - high
        broken = (
            ~(np.isfinite(xx) & np.isfinite(xz) & np.isfinite(zz)),
            (b_xx <= 0) | (b_zz <= 0) | (b_xx * b_zz - b_xz**2 <= 0),
            has_yy & (low <= 0),
            has_yy & (high > low + middle + TRIANGLE_TOLERANCE * (low + middle + high)),
        )
    for rule in range(len(broken), 0, -1):  # the first broken rule wins
        out = np.where(broken[rule - 1], rule, out)
    return out


def check_plane_symmetric_inertia(
    name: str, xx: float, yy: float | None, zz: float, xz: float, source: str | None = None
) -> None:
    """Raise :class:`InputError` naming ``name`` unless :func:`inertia_problem` finds nothing."""
    problem = inertia_problem(xx, yy, zz, xz)
    if problem is not None:
        raise InputError(name, problem[0], problem[1], source)


def check_inertia_tensor(name: str, tensor: np.ndarray, source: str | None = None) -> None:
    """Raise :class:`InputError` unless ``tensor`` is symmetric, positive definite and its
    principal moments satisfy the triangle inequality (each at most the sum of the other two).

    A tensor with NaN in the yy entry (not measured) is checked in its xz block only.  A tensor of
    a body symmetric about its XZ plane goes to :func:`inertia_problem`; any other to the same
    rules with ``numpy.linalg.eigvalsh``.
    """
    t = np.asarray(tensor, dtype=float)
    if t.shape != (3, 3):
        raise InputError(name, t.shape, "a 3x3 inertia tensor", source)
    rows = t.tolist()  # nine Python floats: far cheaper than NumPy calls on a 3x3
    xx, xz, zx, zz, yy = rows[0][0], rows[0][2], rows[2][0], rows[2][2], rows[1][1]
    if not all(math.isfinite(x) for x in (xx, xz, zx, zz)):
        raise InputError(name, rows, "finite moments and products of inertia", source)
    finite = [(i, j) for i in range(3) for j in range(3) if math.isfinite(rows[i][j]) and math.isfinite(rows[j][i])]
    if any(abs(rows[i][j] - rows[j][i]) > 1e-12 + SYMMETRY_TOLERANCE * abs(rows[j][i]) for i, j in finite):
        raise InputError(name, rows, "a symmetric tensor", source)
    if rows[0][1] == rows[1][0] == rows[1][2] == rows[2][1] == 0:
        check_plane_symmetric_inertia(name, xx, yy, zz, xz, source)
        return
    problem = inertia_problem(xx, None, zz, xz)  # the xz block first, as for a plane-symmetric body
    if problem is None and math.isfinite(yy):
        scale = max(abs(rows[i][j]) for i in range(3) for j in range(3))
        problem = _principal_problem(np.linalg.eigvalsh(t / scale).tolist(), scale)
    if problem is not None:
        raise InputError(name, problem[0], problem[1], source)
