"""Moments of inertia and centres of mass from pendulum measurements (Moore et al. 2009, Eqs. 1-7).

Each reduction is a stage of the manifest run by the uncertainty engine (:mod:`bikerider.engine`),
so its first-order uncertainty is exact and every output shares the derivative of the inputs it
has in common.  The checks here come first, so that impossible measurements get a message naming
them rather than a NaN.

Hanging lines.  A body hung from the torsional pendulum has its centre of mass on the (vertical)
pendulum axis.  Each orientation gives one line in the body's plane of symmetry; with three or
more lines, measured with error, the centre of mass is the point that minimises the sum of
squared perpendicular distances to them, and how far the lines miss it says how far to trust
them.  In the bicycle's XZ plane (x forward, z down) a line is ``n . p = d`` with the unit normal
``n = (sin(beta), cos(beta))``, ``beta`` the angle of the line rising from +x (the pendulum axis
angle of ``derive/pendulum.py``); the signed distance of a point ``p`` from it is ``n . p - d``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bikerider.engine import GeneratedStage, LeastSquaresStage, first_order
from bikerider.errors import FitError, InputError
from bikerider.generated.manifest import STAGES
from bikerider.notes import note
from bikerider.quantity import Quantity, check_magnitude, check_positive, sigma_note

#: Below this |determinant| of Eq. 6 for three orientations (``2 sin(a1-a2) sin(a1-a3) sin(a2-a3)``),
#: or this smallest singular value of its rows for more, the orientations do not determine the
#: tensor: two pendulum axes are within about a degree of each other.
SINGULAR_DETERMINANT = 1e-3

#: Gravity at the Earth's surface [m/s^2], poles to equator and mountains included: a compound
#: pendulum that cannot have swung at another gravity is asked whether it swung on Earth.
EARTH_GRAVITY = (9.76, 9.84)

#: Lines whose root-mean-square distance from the fitted centre of mass exceeds this are rejected:
#: the paper locates centres of mass to +/- 0.02 m (Moore et al. 2009, Table 3 caption), so lines
#: that miss their common point by more than that contain a wrong angle or distance.
DEFAULT_LINE_TOLERANCE = 0.02

#: Smallest over largest singular value of the line normals below which the lines count as parallel.
PARALLEL_CONDITIONING = 1e-3

PARALLEL = "the hanging lines are parallel: the orientations do not locate the centre of mass"

_TORSIONAL = (GeneratedStage("torsional"),)
_COMPOUND = (GeneratedStage("compound"),)


@dataclass(frozen=True)
class LineIntersection:
    """Where three or more lines (nearly) meet.

    Attributes
    ----------
    point : ndarray, shape (2,)
        ``(x, z)`` of the least-squares meeting point [m].
    distances : ndarray, shape (n,)
        Signed perpendicular distance of the point from each line [m].
    rms : float
        Root-mean-square of ``distances`` [m]: how well the lines meet (0 when exactly).
    """

    point: np.ndarray
    distances: np.ndarray
    rms: float


def check_lines_meet(body: str, fit: LineIntersection, tolerance: float, source: str | None = None) -> None:
    """Raise :class:`FitError` naming the body when its lines miss their meeting point by more
    than ``tolerance`` (root mean square)."""
    if fit.rms > tolerance:
        worst = int(np.argmax(np.abs(fit.distances)))
        where = f"{source}: " if source else ""
        raise FitError(
            f"{where}the hanging lines of {body} do not meet: they miss their best common point "
            f"({fit.point[0]:.4f}, {fit.point[1]:.4f}) m by {fit.rms:.4f} m (rms), line {worst + 1} by "
            f"{abs(fit.distances[worst]):.4f} m; expected at most {tolerance:.4f} m. "
            "Check that orientation's angle and distance."
        )


def _check_period(name: str, period: Quantity, source: str | None) -> None:
    if not period.value > 0:
        raise InputError(name, period.value, "a positive period in seconds", source)
    check_magnitude(name, period.value, 100.0, "s", source)
    check_magnitude(f"{name} uncertainty", period.sigma, 100.0, "s", source)
    if not period.value > 1e-3:  # 1 ms: below, squares underflow
        raise InputError(name, period.value, "a positive period in seconds, above 0.001 s", source)
    message = sigma_note(name, period, source)
    if message:
        note(message)


def _check_stiffness(k_t: Quantity, source: str | None) -> None:
    if not k_t.value > 0:
        raise InputError("k_t", k_t.value, "a positive torsional stiffness in N m/rad", source)
    check_magnitude("k_t", k_t.value, 1e6, "N m/rad", source)
    check_magnitude("k_t uncertainty", k_t.sigma, 1e6, "N m/rad", source)


def torsional_inertia(k_t: Quantity, period: Quantity, name: str = "period", source: str | None = None) -> Quantity:
    """Eq. 1: ``J = k T^2 / (4 pi^2)``."""
    _check_period(name, period, source)
    _check_stiffness(k_t, source)
    return first_order(_TORSIONAL, {"k_t": k_t, "T": period}).quantity("J")


def compound_inertia(
    period: Quantity,
    mass: Quantity,
    length: Quantity,
    g: Quantity,
    name: str = "compound_period",
    source: str | None = None,
) -> Quantity:
    """Eq. 7: ``I = (T / 2 pi)^2 m g l - m l^2`` about the wheel axle."""
    _check_period(name, period, source)
    if not length.value > 0:
        raise InputError("pendulum_length", length.value, "a positive pendulum length in metres", source)
    message = check_positive("pendulum_length", length, 10.0, "m", source)
    if message:
        note(message)
    if not mass.value > 0:
        raise InputError("mass", mass.value, "a positive mass in kg (of the body on the compound pendulum)", source)
    check_positive("mass", mass, 500.0, "kg", source)  # the wheel's checks note its uncertainty
    if not g.value > 0:
        raise InputError("g", g.value, "a positive acceleration due to gravity in m/s^2", source)
    check_magnitude("g", g.value, 100.0, "m/s^2", source)
    check_magnitude("g uncertainty", g.sigma, 100.0, "m/s^2", source)
    result = first_order(_COMPOUND, {"T": period, "m_p": mass, "g": g, "l_p": length})
    value = result.quantity("Iyy")
    if not value.value > 0:
        shortest = 2 * math.pi * math.sqrt(length.value / g.value)
        earth = EARTH_GRAVITY[0] <= g.value <= EARTH_GRAVITY[1]
        raise InputError(
            name,
            period.value,
            f"more than {shortest:.4f} s, the period of a point mass on a {length.value} m pendulum "
            f"at g = {g.value:g} m/s^2 (a shorter period gives a negative moment of inertia"
            + ("" if earth else "; if the pendulum swung on Earth, give the gravity there as [environment] g_lab")
            + ")",
            source,
        )
    return value


@functools.lru_cache(maxsize=16)
def _orientation_stage(n: int, name: str = "orientations") -> GeneratedStage | LeastSquaresStage:
    """Eq. 6 for ``n`` orientations with inputs ``k_t``, ``T_i``, ``alpha_i`` (``i = 1..n``) and
    outputs ``Ixx, Ixz, Izz``: the closed form for three, least squares for more (the check
    ``<name>.determinant`` or ``<name>.smallest_singular`` says whether they determine the tensor)."""
    if n == 3:
        return GeneratedStage("three_orientations", name, checks={"determinant": f"{name}.determinant"})
    rows = [{"alpha": f"alpha_{i}", "T": f"T_{i}"} for i in range(1, n + 1)]
    return LeastSquaresStage(
        name, "orientation_equation", rows, ("r_xx", "r_xz", "r_zz"), "J", STAGES["three_orientations"]["outputs"]
    )


def inertia_from_orientations(
    k_t: Quantity, periods: list[Quantity], angles: list[Quantity], body: str, source: str | None = None
) -> tuple[Quantity, Quantity, Quantity]:
    """Eqs. 2-6: ``(Ixx, Ixz, Izz)`` (benchmark convention) from torsional periods at three or more
    pendulum-axis angles (radians); least squares for more than three.

    Raises
    ------
    InputError
        Fewer than three orientations, mismatched lists, non-positive periods, or angles that leave
        Eq. 6 singular (two axes that coincide modulo 180 degrees).
    """
    if len(periods) != len(angles):
        raise InputError(
            f"{body}.inertia", f"{len(periods)} periods, {len(angles)} angles", "one pendulum angle per period", source
        )
    if len(periods) < 3:
        raise InputError(
            f"{body}.inertia.periods",
            len(periods),
            "at least three pendulum orientations (Eq. 6 has three unknowns)",
            source,
        )
    for i, p in enumerate(periods):
        _check_period(f"{body}.inertia.periods[{i}]", p, source)
    _check_stiffness(k_t, source)
    n = len(periods)
    stage = _orientation_stage(n)
    inputs = {
        "k_t": k_t,
        **{f"T_{i}": p for i, p in enumerate(periods, start=1)},
        **{f"alpha_{i}": a for i, a in enumerate(angles, start=1)},
    }
    result = first_order((stage,), inputs)
    check = "orientations.determinant" if n == 3 else "orientations.smallest_singular"
    if not abs(float(result.nodes[check])) >= SINGULAR_DETERMINANT:
        shown = ", ".join(f"{math.degrees(a.value):.1f}" for a in angles)
        raise InputError(
            f"{body}.inertia.alpha_deg",
            f"[{shown}]",
            "three pendulum axes that differ pairwise by more than a few degrees modulo 180 "
            "(these leave Eq. 6 singular: two axes coincide)",
            source,
        )
    return result.quantity("Ixx"), result.quantity("Ixz"), result.quantity("Izz")


@functools.lru_cache(maxsize=16)
def _lines_stage(n: int) -> LeastSquaresStage:
    """The least-squares point of ``n`` lines through points ``(x_i, z_i)`` at angles ``alpha_i``."""
    rows = [{"alpha": f"alpha_{i}", "x_p": f"x_{i}", "z_p": f"z_{i}"} for i in range(1, n + 1)]
    return LeastSquaresStage("lines", "line_through_point", rows, ("s", "c"), "d", ("x", "z"))


def centre_of_mass_from_lines(
    points: Sequence[tuple[Quantity, Quantity]],
    angles: Sequence[Quantity],
    name: str,
    source: str | None = None,
    tolerance: float = DEFAULT_LINE_TOLERANCE,
) -> tuple[Quantity, Quantity]:
    """The least-squares meeting point of pendulum-axis lines, each through a point at an angle
    (radians, rising from +x), with its first-order uncertainty.

    Raises
    ------
    FitError
        Lines that are (nearly) parallel, or that miss their common point by more than
        ``tolerance`` (root mean square).
    """
    stage = _lines_stage(len(points))
    inputs: dict[str, Quantity] = {}
    for i, ((x, z), angle) in enumerate(zip(points, angles), start=1):
        inputs.update({f"alpha_{i}": angle, f"x_{i}": x, f"z_{i}": z})
    result = first_order((stage,), inputs)
    if not result.nodes["lines.conditioning"] >= PARALLEL_CONDITIONING:
        raise FitError(PARALLEL)
    rms = float(result.nodes["lines.rms"])
    point = np.array([float(result.nodes["x"]), float(result.nodes["z"])])
    check_lines_meet(name, LineIntersection(point, np.array([rms]), rms), tolerance, source)
    return result.quantity("x"), result.quantity("z")
