"""Bicycle geometry from BicycleParameters' raw measurements (plain floats; uncertainty is
propagated by the caller, :mod:`bikerider.bicycle.raw_measurements`).

Coordinates are the benchmark's: origin at the rear contact point, x forward, z down; the rear
wheel centre is ``(0, -rR)`` and the front wheel centre ``(w, -rF)``.  ``lam`` is the steer axis
tilt from the vertical; the unit vector down the steer axis is ``s = (sin lam, cos lam)`` and the
forward normal to it is ``n = (cos lam, -sin lam)``.

Two ways of measuring the frame are supported:

* **wheelbase** ``w``, head tube angle ``gamma`` (degrees from the ground) and fork offset ``f``;
* **heights and diameters** (``h1..h5``, ``d1..d4``, ``d``), from which BicycleParameters forms the
  perpendicular distances of the wheel centres from the steer axis: the rear offset
  ``a = h1 + h2 - h3 + d1/2 - d2/2``, the fork offset ``b = h4 - d3/2 - h5 + d4/2`` and the distance
  along the steer axis between the feet of the two perpendiculars ``c = sqrt(D^2 - (a - b)^2)`` with
  ``D = d + (d2 + d3)/2``.  With the wheel centres ``a`` behind and ``b`` ahead of the axis,
  projecting the centre-to-centre vector ``(w, rR - rF)`` on ``n`` and ``s`` gives

      a + b = w cos(lam) + (rF - rR) sin(lam),     c = w sin(lam) + (rR - rF) cos(lam),

  hence ``(a + b) sin(lam) - c cos(lam) = rF - rR`` (solved in closed form here; BicycleParameters
  iterates) and ``w = (a + b) cos(lam) + c sin(lam)``.
"""
from __future__ import annotations

import math


def wheel_radius(rolled_distance: float, turns: float) -> float:
    """Radius of a wheel that rolled ``rolled_distance`` in ``turns`` full turns."""
    return rolled_distance / (2 * math.pi * turns)


def perpendicular_offsets(h: tuple[float, float, float, float, float],
                          d: tuple[float, float, float, float, float]) -> tuple[float, float, float]:
    """BicycleParameters' ``(a, b, c)``: rear wheel offset, fork offset and steer-axis distance.

    Parameters
    ----------
    h : (h1, h2, h3, h4, h5)
        Heights [m].
    d : (d1, d2, d3, d4, d)
        Diameters ``d1..d4`` and the distance ``d`` [m].

    Returns
    -------
    a, b, c : float
        ``c`` is NaN when ``D < |a - b|`` (the caller reports it).
    """
    h1, h2, h3, h4, h5 = h
    d1, d2, d3, d4, d_ = d
    a = h1 + h2 - h3 + 0.5 * d1 - 0.5 * d2
    b = h4 - 0.5 * d3 - h5 + 0.5 * d4
    span = d_ + 0.5 * (d2 + d3)
    square = span**2 - (a - b) ** 2
    return a, b, math.sqrt(square) if square >= 0 else math.nan


def steer_tilt_from_offsets(rF: float, rR: float, a: float, b: float, c: float) -> float:
    """Steer axis tilt from ``(a + b) sin(lam) - c cos(lam) = rF - rR`` (NaN when no solution).

    Writing the left side as ``R sin(lam - phi)`` with ``R = hypot(a + b, c)`` and
    ``phi = atan2(c, a + b)`` gives ``lam = phi + asin((rF - rR) / R)``: the root near ``phi``, which
    is the tilt for equal wheels.
    """
    span = math.hypot(a + b, c)
    ratio = (rF - rR) / span
    if abs(ratio) > 1:
        return math.nan
    return math.atan2(c, a + b) + math.asin(ratio)


def wheelbase_from_offsets(lam: float, a: float, b: float, c: float) -> float:
    """``w = (a + b) cos(lam) + c sin(lam)``."""
    return (a + b) * math.cos(lam) + c * math.sin(lam)


def trail(rF: float, lam: float, fork_offset: float) -> float:
    """Trail ``c = (rF sin(lam) - f) / cos(lam)`` (Meijaard et al. 2007 geometry)."""
    return (rF * math.sin(lam) - fork_offset) / math.cos(lam)


def handlebar_reference_offsets(h6: float, h7: float, d5: float, d6: float, length: float) -> tuple[float, float]:
    """Position of the handlebar reference point relative to the front wheel centre, for a fork
    and handlebar measured apart (BicycleParameters' ``l1, l2``).

    With the steer axis lying parallel to a table, ``h6`` is the height of the top of the front
    axle (diameter ``d5``) and ``h7`` that of the top of the handlebar reference circle (diameter
    ``d6``); ``length`` is the outer distance between axle and circle.

    Returns
    -------
    l1 : float
        Perpendicular to the steer axis, positive forward.
    l2 : float
        Along the steer axis, positive up (NaN when ``l1`` exceeds the centre distance).
    """
    l1 = (h7 - 0.5 * d6) - (h6 - 0.5 * d5)
    centre_distance = length - 0.5 * (d5 + d6)
    square = centre_distance**2 - l1**2
    return l1, math.sqrt(square) if square >= 0 else math.nan


def handlebar_reference_point(w: float, rF: float, lam: float, l1: float, l2: float) -> tuple[float, float]:
    """``(x, z)`` of the handlebar reference point: ``l2`` up the steer axis and ``l1`` forward of
    it from the front wheel centre."""
    x = w - l2 * math.sin(lam) + l1 * math.cos(lam)
    z = -rF - l2 * math.cos(lam) - l1 * math.sin(lam)
    return x, z


def rod_moment_of_inertia(mass: float, diameter: float, length: float) -> float:
    """Moment of inertia of a solid calibration rod about a transverse axis through its middle,
    ``m (3 r^2 + l^2) / 12``."""
    radius = 0.5 * diameter
    return mass * (3 * radius**2 + length**2) / 12


def torsional_stiffness(moment_of_inertia: float, period: float) -> float:
    """Stiffness of the torsional pendulum from a body of known inertia: ``k = 4 pi^2 I / T^2``
    (Eq. 1 inverted)."""
    return 4 * math.pi**2 * moment_of_inertia / period**2
