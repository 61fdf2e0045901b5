"""The front assembly in the steer-axis frame (BicycleParameters' users' request #65).

The benchmark frame has x forward, z down, its origin at the rear contact.  The steer-axis frame
is turned about y by the steer axis tilt ``lam``: ``z_s`` points down the steer axis,
``x_s = (cos lam, 0, -sin lam)`` forward and perpendicular to it.  The handlebar and fork H is then
given by

* ``dH``: its centre of mass ahead of the steer axis (along ``x_s``) [m];
* ``uH``: its centre of mass up the steer axis from the point where the axis meets the ground [m];
* ``IH11``, ``IH33``, ``IH13``: its inertia tensor about its centre of mass in that frame
  (``IH33`` about a line parallel to the steer axis) [kg m^2]; ``IHyy`` is the same in both frames.

:func:`to_steer_frame` and :func:`from_steer_frame` convert one way and the other (exactly inverse);
:func:`front_assembly` gives the whole front assembly (H and the front wheel F): its mass and its
moment of inertia about the steer axis itself.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

STEER_FRAME_NAMES = ("dH", "uH", "IH11", "IH33", "IH13")
"""The values of H in the steer-axis frame, in table order."""
STEER_FRAME_UNITS = {"dH": "m", "uH": "m", "IH11": "kg m^2", "IH33": "kg m^2", "IH13": "kg m^2"}
STEER_FRAME_INPUTS = ("w", "c", "lam", "xH", "zH", "IHxx", "IHzz", "IHxz")
"""The benchmark values the steer-frame values depend on."""
ASSEMBLY_INPUTS = STEER_FRAME_INPUTS + ("mH", "mF", "rF", "IFxx")


def _rotate(lam: float, xx: float, zz: float, xz: float) -> tuple[float, float, float]:
    """The xz entries of a plane-symmetric tensor in axes turned by ``lam`` about y."""
    c, s = math.cos(lam), math.sin(lam)
    return (
        c * c * xx - 2 * c * s * xz + s * s * zz,
        s * s * xx + 2 * c * s * xz + c * c * zz,
        c * s * (xx - zz) + (c * c - s * s) * xz,
    )


def to_steer_frame(v: Mapping[str, float]) -> dict[str, float]:
    """``dH, uH, IH11, IH33, IH13`` of the benchmark values ``v`` (SI units, ``lam`` in radians)."""
    lam = v["lam"]
    c, s = math.cos(lam), math.sin(lam)
    dx, dz = v["xH"] - v["w"] - v["c"], v["zH"]
    i11, i33, i13 = _rotate(lam, v["IHxx"], v["IHzz"], v["IHxz"])
    return {"dH": dx * c - dz * s, "uH": -(dx * s + dz * c), "IH11": i11, "IH33": i33, "IH13": i13}


def from_steer_frame(v: Mapping[str, float], steer: Mapping[str, float]) -> dict[str, float]:
    """``xH, zH, IHxx, IHzz, IHxz`` from the steer-frame values ``steer`` on the geometry of ``v``
    (``w``, ``c``, ``lam``): the inverse of :func:`to_steer_frame`."""
    lam = v["lam"]
    c, s = math.cos(lam), math.sin(lam)
    d, along = steer["dH"], -steer["uH"]
    xx, zz, xz = _rotate(-lam, steer["IH11"], steer["IH33"], steer["IH13"])
    return {"xH": v["w"] + v["c"] + d * c + along * s, "zH": -d * s + along * c, "IHxx": xx, "IHzz": zz, "IHxz": xz}


def front_assembly(v: Mapping[str, float]) -> dict[str, float]:
    """Mass [kg] and moment of inertia about the steer axis [kg m^2] of H and F together.

    The front wheel is axisymmetric (its inertia about any diameter is ``IFxx``); each body adds its
    own moment about a parallel line through its centre of mass and ``m d^2``, ``d`` its distance
    from the axis.
    """
    lam = v["lam"]
    steer = to_steer_frame(v)
    d_wheel = -v["c"] * math.cos(lam) + v["rF"] * math.sin(lam)
    moment = steer["IH33"] + v["mH"] * steer["dH"] ** 2 + v["IFxx"] + v["mF"] * d_wheel**2
    return {"mass": v["mH"] + v["mF"], "I_steer_axis": moment}


def first_order_sigmas(function, v: Mapping[str, float], sigmas: Mapping[str, float], inputs) -> dict[str, float]:
    """First-order standard uncertainties of the outputs of ``function(v)`` from independent
    ``sigmas`` of ``inputs`` (central differences, steps of a hundredth of a sigma)."""
    out = {name: 0.0 for name in function(v)}
    for name in inputs:
        sigma = float(sigmas.get(name, 0.0) or 0.0)
        if sigma <= 0:
            continue
        h = 0.01 * sigma
        up = function({**v, name: v[name] + h})
        down = function({**v, name: v[name] - h})
        for key in out:
            out[key] += ((up[key] - down[key]) / (2 * h) * sigma) ** 2
    return {key: math.sqrt(total) for key, total in out.items()}


__all__ = [
    "ASSEMBLY_INPUTS",
    "STEER_FRAME_INPUTS",
    "STEER_FRAME_NAMES",
    "STEER_FRAME_UNITS",
    "first_order_sigmas",
    "from_steer_frame",
    "front_assembly",
    "to_steer_frame",
]
