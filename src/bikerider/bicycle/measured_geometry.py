"""Bicycle geometry from BicycleParameters' raw measurements (floats or NumPy arrays of points,
which broadcast; uncertainty is propagated by the caller, :mod:`bikerider.bicycle.raw_measurements`).

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

import numpy as np

Value = float | np.ndarray
"""A float, or an array of points of a batch (see :func:`bikerider.bicycle.propagation.propagate`)."""


def sqrt_or_nan(square: Value) -> Value:
    """``sqrt(square)``, NaN (without a floating-point warning) where ``square`` is negative or NaN."""
    return np.sqrt(np.where(square >= 0, square, np.nan))


def wheel_radius(rolled_distance: Value, turns: Value) -> Value:
    """Radius of a wheel that rolled ``rolled_distance`` in ``turns`` full turns."""
    return rolled_distance / (2 * math.pi * turns)


def perpendicular_offsets(h: tuple[Value, Value, Value, Value, Value],
                          d: tuple[Value, Value, Value, Value, Value]) -> tuple[Value, Value, Value]:
    """BicycleParameters' ``(a, b, c)``: rear wheel offset, fork offset and steer-axis distance.

    Parameters
    ----------
    h : (h1, h2, h3, h4, h5)
        Heights [m].
    d : (d1, d2, d3, d4, d)
        Diameters ``d1..d4`` and the distance ``d`` [m].

    Returns
    -------
    a, b, c : float or ndarray
        ``c`` is NaN when ``D < |a - b|`` (the caller reports it).
    """
    h1, h2, h3, h4, h5 = h
    d1, d2, d3, d4, d_ = d
    a = h1 + h2 - h3 + 0.5 * d1 - 0.5 * d2
    b = h4 - 0.5 * d3 - h5 + 0.5 * d4
    span = d_ + 0.5 * (d2 + d3)
    square = span**2 - (a - b) ** 2
    return a, b, sqrt_or_nan(square)


def steer_tilt_from_offsets(rF: Value, rR: Value, a: Value, b: Value, c: Value) -> Value:
    """Steer axis tilt from ``(a + b) sin(lam) - c cos(lam) = rF - rR`` (NaN when no solution).

    Writing the left side as ``R sin(lam - phi)`` with ``R = hypot(a + b, c)`` and
    ``phi = atan2(c, a + b)`` gives ``lam = phi + asin((rF - rR) / R)``: the root near ``phi``, which
    is the tilt for equal wheels.
    """
    span = np.hypot(a + b, c)
    ratio = (rF - rR) / span
    return np.arctan2(c, a + b) + np.arcsin(np.where(np.abs(ratio) <= 1, ratio, np.nan))


def wheelbase_from_offsets(lam: Value, a: Value, b: Value, c: Value) -> Value:
    """``w = (a + b) cos(lam) + c sin(lam)``."""
    return (a + b) * np.cos(lam) + c * np.sin(lam)


def trail(rF: Value, lam: Value, fork_offset: Value) -> Value:
    """Trail ``c = (rF sin(lam) - f) / cos(lam)`` (Meijaard et al. 2007 geometry)."""
    return (rF * np.sin(lam) - fork_offset) / np.cos(lam)


def handlebar_reference_offsets(h6: Value, h7: Value, d5: Value, d6: Value, length: Value) -> tuple[Value, Value]:
    """Position of the handlebar reference point relative to the front wheel centre, for a fork
    and handlebar measured apart (BicycleParameters' ``l1, l2``).

    With the steer axis lying parallel to a table, ``h6`` is the height of the top of the front
    axle (diameter ``d5``) and ``h7`` that of the top of the handlebar reference circle (diameter
    ``d6``); ``length`` is the outer distance between axle and circle.

    Returns
    -------
    l1 : float or ndarray
        Perpendicular to the steer axis, positive forward.
    l2 : float or ndarray
        Along the steer axis, positive up (NaN when ``l1`` exceeds the centre distance).
    """
    l1 = (h7 - 0.5 * d6) - (h6 - 0.5 * d5)
    centre_distance = length - 0.5 * (d5 + d6)
    square = centre_distance**2 - l1**2
    return l1, sqrt_or_nan(square)


def handlebar_reference_point(w: Value, rF: Value, lam: Value, l1: Value, l2: Value) -> tuple[Value, Value]:
    """``(x, z)`` of the handlebar reference point: ``l2`` up the steer axis and ``l1`` forward of
    it from the front wheel centre."""
    sin, cos = np.sin(lam), np.cos(lam)
    x = w - l2 * sin + l1 * cos
    z = -rF - l2 * cos - l1 * sin
    return x, z


def rod_moment_of_inertia(mass: Value, diameter: Value, length: Value) -> Value:
    """Moment of inertia of a solid calibration rod about a transverse axis through its middle,
    ``m (3 r^2 + l^2) / 12``."""
    radius = 0.5 * diameter
    return mass * (3 * radius**2 + length**2) / 12


def torsional_stiffness(moment_of_inertia: Value, period: Value) -> Value:
    """Stiffness of the torsional pendulum from a body of known inertia: ``k = 4 pi^2 I / T^2``
    (Eq. 1 inverted)."""
    return 4 * math.pi**2 * moment_of_inertia / period**2
