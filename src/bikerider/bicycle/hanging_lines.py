"""Centres of mass from hanging a body at several orientations (the lines through the pendulum axis).

A body hung from the torsional pendulum has its centre of mass on the (vertical) pendulum axis.
Each orientation gives one line in the body's plane of symmetry; the centre of mass is where the
lines meet.  With three or more lines, measured with error, they do not meet in one point: we take
the point that minimises the sum of squared perpendicular distances to the lines and report how
far the lines are from it.  :func:`least_squares_point` and :func:`pairwise_mean_point` work on
whole batches of line sets at once (closed-form 2 x 2 solutions, no per-set solver call), which is
what lets the raw-measurement reduction evaluate every point of its numerical Jacobian in one call.

Line convention.  In the bicycle's XZ plane (x forward, z down) a line is written in normal form
``n . p = d`` with the unit normal ``n = (sin(beta), cos(beta))`` and ``beta`` the angle of the
line rising from +x (the pendulum axis angle of ``derive/pendulum.py``).  The signed perpendicular
distance of a point ``p`` from the line is ``n . p - d``.

BicycleParameters' measurement.  Each hanging photograph gives ``alpha``, the angle (degrees,
counter-clockwise seen from the bicycle's right side) of the upward steer-axis direction from the
photograph's horizontal, and ``a``, the perpendicular distance from the vertical pendulum axis to a
reference point on the body (a wheel centre or the handlebar reference point), positive when the
reference point is left of the axis in the photograph.  Turning the photograph back so the
bicycle is upright carries the vertical axis to the angle ``beta = lam - alpha`` (``lam`` the steer
axis tilt; modulo 180 degrees, which a line does not notice), and "left of the upward axis"
becomes the side the normal ``n`` points to, so the line is ``n . p = n . p_ref - a``.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from bikerider.errors import FitError

#: Lines whose root-mean-square distance from the fitted centre of mass exceeds this are rejected:
#: the paper locates centres of mass to +/- 0.02 m (Moore et al. 2009, Table 3 caption), so lines
#: that miss their common point by more than that contain a wrong angle or distance.
DEFAULT_LINE_TOLERANCE = 0.02


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


def line_from_hanging(beta: float, offset: float, reference: tuple[float, float]) -> tuple[np.ndarray, float]:
    """Normal form ``(n, d)`` of the line at angle ``beta`` whose perpendicular distance to
    ``reference`` is ``offset`` (positive on the side ``n`` points to)."""
    normal = np.array([math.sin(beta), math.cos(beta)])
    return normal, float(normal @ np.asarray(reference, dtype=float) - offset)


#: Smallest over largest singular value of the line normals below which the lines count as parallel.
PARALLEL_CONDITIONING = 1e-3

_PARALLEL = "the hanging lines are parallel: the orientations do not locate the centre of mass"


def least_squares_point(sin: np.ndarray, cos: np.ndarray, distances: np.ndarray, axis: int = -1):
    """Least-squares meeting points of batches of lines ``sin x + cos z = d``, in closed form.

    The normal equations of ``min |N p - d|`` (``N`` the unit normals ``(sin, cos)`` as rows) are a
    2 x 2 system, solved by Cramer's rule.  With unit normals ``N^T N`` has trace ``m`` (the number
    of lines), so its eigenvalues, the squared singular values of ``N``, follow from its
    determinant alone.

    Parameters
    ----------
    sin, cos, distances : ndarray
        Normals and distances of the lines, the lines along ``axis``, any other batch axes.
    axis : int
        The axis of the lines.

    Returns
    -------
    x, z : ndarray
        The points, without the lines axis; not finite where the lines are parallel.
    conditioning : ndarray
        Smallest over largest singular value of ``N`` (0 for parallel lines), without the lines axis.
    """
    ss = (sin * sin).sum(axis=axis)
    cc = (cos * cos).sum(axis=axis)
    sc = (sin * cos).sum(axis=axis)
    sd = (sin * distances).sum(axis=axis)
    cd = (cos * distances).sum(axis=axis)
    det = ss * cc - sc * sc
    trace = ss + cc
    with np.errstate(divide="ignore", invalid="ignore"):
        root = np.sqrt(np.maximum(trace * trace - 4 * det, 0.0))
        return ((cc * sd - sc * cd) / det, (ss * cd - sc * sd) / det,
                np.sqrt(np.maximum(trace - root, 0.0) / (trace + root)))


def pairwise_mean_point(sin: np.ndarray, cos: np.ndarray, distances: np.ndarray, axis: int = -1):
    """The mean of the intersection points of every pair of lines, for batches of lines (the lines
    along ``axis``; each pair solved by Cramer's rule).  Returns ``x, z`` without the lines axis.

    This is how BicycleParameters locates a centre of mass; it is not the least-squares point
    (a pair of nearly parallel lines pulls it far).  Kept to reproduce BicycleParameters' values.
    """
    first, second = (list(index) for index in zip(*itertools.combinations(range(distances.shape[axis]), 2)))
    s1, c1, d1 = (np.take(a, first, axis=axis) for a in (sin, cos, distances))
    s2, c2, d2 = (np.take(a, second, axis=axis) for a in (sin, cos, distances))
    with np.errstate(divide="ignore", invalid="ignore"):
        det = s1 * c2 - s2 * c1
        return ((d1 * c2 - d2 * c1) / det).mean(axis=axis), ((s1 * d2 - s2 * d1) / det).mean(axis=axis)


def intersect_lines(normals: np.ndarray, distances: np.ndarray) -> LineIntersection:
    """Least-squares meeting point of lines ``normals[i] . p = distances[i]`` (unit normals).

    Raises
    ------
    FitError
        Fewer than two lines, or lines that are (nearly) parallel so that no point is determined.
    """
    normals = np.asarray(normals, dtype=float)
    distances = np.asarray(distances, dtype=float)
    if normals.shape[0] < 2:
        raise FitError(f"need at least two lines to locate a centre of mass, got {normals.shape[0]}")
    x, z, conditioning = least_squares_point(normals[:, 0], normals[:, 1], distances)
    check_not_parallel(conditioning)
    point = np.array([x, z])
    miss = normals @ point - distances
    return LineIntersection(point, miss, float(np.sqrt(np.mean(miss**2))))


def check_not_parallel(conditioning: np.ndarray) -> None:
    """Raise :class:`FitError` when any of a batch of line sets is (nearly) parallel
    (``conditioning`` from :func:`least_squares_point`)."""
    if not np.all(conditioning >= PARALLEL_CONDITIONING):
        raise FitError(_PARALLEL)


def mean_of_pairwise_intersections(normals: np.ndarray, distances: np.ndarray) -> np.ndarray:
    """The mean of the intersection points of every pair of lines ``normals[i] . p = distances[i]``
    (see :func:`pairwise_mean_point`), as ``(x, z)``."""
    normals = np.asarray(normals, dtype=float)
    x, z = pairwise_mean_point(normals[:, 0], normals[:, 1], np.asarray(distances, dtype=float))
    return np.array([x, z])


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
