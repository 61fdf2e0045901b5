"""Moments of inertia from pendulum periods (Moore et al. 2009, Eqs. 1-7), with uncertainty.

Wraps ``bikerider.generated.pendulum``; uncertainties are propagated at first order.
"""
from __future__ import annotations

import math

import numpy as np

from bikerider.errors import InputError
from bikerider.generated import pendulum as gen
from bikerider.bicycle.propagation import propagate
from bikerider.quantity import Quantity, check_magnitude

#: Below this |determinant| of Eq. 6 (which is 2 sin(a1-a2) sin(a1-a3) sin(a2-a3)) the
#: orientations do not determine the tensor: two axes are within about a degree of each other.
SINGULAR_DETERMINANT = 1e-3


def _check_period(name: str, period: Quantity, source: str | None) -> None:
    if not period.value > 0:
        raise InputError(name, period.value, "a positive period in seconds", source)
    check_magnitude(name, period.value, 100.0, "s", source)
    check_magnitude(f"{name} uncertainty", period.sigma, 100.0, "s", source)


def _check_stiffness(k_t: Quantity, source: str | None) -> None:
    if not k_t.value > 0:
        raise InputError("k_t", k_t.value, "a positive torsional stiffness in N m/rad", source)
    check_magnitude("k_t", k_t.value, 1e6, "N m/rad", source)
    check_magnitude("k_t uncertainty", k_t.sigma, 1e6, "N m/rad", source)


def torsional_inertia(k_t: Quantity, period: Quantity, name: str = "period", source: str | None = None) -> Quantity:
    """Eq. 1: ``J = k T^2 / (4 pi^2)``."""
    _check_period(name, period, source)
    _check_stiffness(k_t, source)
    out = propagate(lambda x: {"J": float(gen.torsional_inertia(k_t=x["k_t"], T=x["T"]))}, {"k_t": k_t, "T": period})
    return out["J"]


def compound_inertia(period: Quantity, mass: Quantity, length: Quantity, g: Quantity,
                     name: str = "compound_period", source: str | None = None) -> Quantity:
    """Eq. 7: ``I = (T / 2 pi)^2 m g l - m l^2`` about the wheel axle."""
    _check_period(name, period, source)
    if not length.value > 0:
        raise InputError("pendulum_length", length.value, "a positive pendulum length in metres", source)
    check_magnitude("pendulum_length", length.value, 10.0, "m", source)
    check_magnitude("pendulum_length uncertainty", length.sigma, 10.0, "m", source)
    if not mass.value > 0:
        raise InputError("mass", mass.value, "a positive mass in kg (of the body on the compound pendulum)", source)
    check_magnitude("mass", mass.value, 500.0, "kg", source)
    check_magnitude("mass uncertainty", mass.sigma, 500.0, "kg", source)
    if not g.value > 0:
        raise InputError("g", g.value, "a positive acceleration due to gravity in m/s^2", source)
    check_magnitude("g", g.value, 100.0, "m/s^2", source)
    check_magnitude("g uncertainty", g.sigma, 100.0, "m/s^2", source)
    value = float(gen.compound_inertia(T=period.value, m_p=mass.value, g=g.value, l_p=length.value))
    if not value > 0:
        shortest = 2 * math.pi * math.sqrt(length.value / g.value)
        raise InputError(name, period.value,
                         f"more than {shortest:.4f} s, the period of a point mass on a {length.value} m pendulum "
                         "(a shorter period gives a negative moment of inertia)", source)
    out = propagate(lambda x: {"I": float(gen.compound_inertia(**x))},
                    {"T": period, "m_p": mass, "g": g, "l_p": length})
    return out["I"]


def _solve_orientations(values: dict[str, float]) -> dict[str, float]:
    n = sum(1 for key in values if key.startswith("T_"))
    k = values["k_t"]
    periods = np.array([values[f"T_{i}"] for i in range(n)])
    angles = np.array([values[f"alpha_{i}"] for i in range(n)])
    if n == 3:
        inertia, _ = gen.inertia_from_three_orientations(
            k_t=k, T_1=periods[0], T_2=periods[1], T_3=periods[2],
            alpha_1=angles[0], alpha_2=angles[1], alpha_3=angles[2],
        )
    else:
        rows = gen.orientation_row(alpha=angles)
        inertia, *_ = np.linalg.lstsq(rows, gen.torsional_inertia(k_t=k, T=periods), rcond=None)
    return {"Ixx": float(inertia[0]), "Ixz": float(inertia[1]), "Izz": float(inertia[2])}


def inertia_from_orientations(k_t: Quantity, periods: list[Quantity], angles: list[Quantity],
                              body: str, source: str | None = None) -> tuple[Quantity, Quantity, Quantity]:
    """Eqs. 2-6: ``(Ixx, Ixz, Izz)`` (benchmark convention) from torsional periods at three or more
    pendulum-axis angles (radians); least squares for more than three.

    Raises
    ------
    InputError
        Fewer than three orientations, mismatched lists, non-positive periods, or angles that leave
        Eq. 6 singular (two axes that coincide modulo 180 degrees).
    """
    if len(periods) != len(angles):
        raise InputError(f"{body}.inertia", f"{len(periods)} periods, {len(angles)} angles",
                         "one pendulum angle per period", source)
    if len(periods) < 3:
        raise InputError(f"{body}.inertia.periods", len(periods),
                         "at least three pendulum orientations (Eq. 6 has three unknowns)", source)
    for i, p in enumerate(periods):
        _check_period(f"{body}.inertia.periods[{i}]", p, source)
    _check_stiffness(k_t, source)
    a = np.array([q.value for q in angles])
    if len(angles) == 3:
        det = abs(2 * np.sin(a[0] - a[1]) * np.sin(a[0] - a[2]) * np.sin(a[1] - a[2]))
    else:
        rows = gen.orientation_row(alpha=a)
        det = np.linalg.svd(rows, compute_uv=False)[-1]
    if det < SINGULAR_DETERMINANT:
        shown = ", ".join(f"{math.degrees(x):.1f}" for x in a)
        raise InputError(
            f"{body}.inertia.alpha_deg", f"[{shown}]",
            "three pendulum axes that differ pairwise by more than a few degrees modulo 180 "
            "(these leave Eq. 6 singular: two axes coincide)", source,
        )
    inputs = {"k_t": k_t, **{f"T_{i}": p for i, p in enumerate(periods)}, **{f"alpha_{i}": a for i, a in enumerate(angles)}}
    out = propagate(_solve_orientations, inputs)
    return out["Ixx"], out["Ixz"], out["Izz"]
