"""Seating measurements of the paper's rider model from BicycleParameters' measurements.

BicycleParameters' Measured files describe where a rider sits with eight numbers (used by its
``rider.py`` to pose a Yeadon human):

========  ===================================================================================
``lcs``   chain stay length, rear axle to bottom bracket [m] -- the paper's ``l_cs``
``hbb``   bottom bracket height above the ground [m] -- ``h_bb``
``lst``   seat tube length, bottom bracket to top of the seat tube [m] -- ``l_st``
``lsp``   seat post length, top of the seat tube to the top of the seat [m] -- ``l_sp``
``lamst`` seat tube angle from the ground, **radians** -- ``lam_st``
``whb``   handlebar width, between the two grips [m]
``LhbF``  distance from the front wheel centre (on the mid-plane) to a handlebar grip [m]
``LhbR``  distance from the rear wheel centre (on the mid-plane) to a handlebar grip [m]
========  ===================================================================================

The last three come from the closure equations of BicycleParameters' ``rider.py``: the grip lies
``whb/2`` to the side of the mid-plane, so its in-plane distances from the wheel centres are
``sqrt(LhbF^2 - (whb/2)^2)`` and ``sqrt(LhbR^2 - (whb/2)^2)``; the grip's ``(x, z)`` is where those
two circles about ``(w, -rF)`` and ``(0, -rR)`` meet above the wheel centres.

The paper's model (Table 10) places the hands differently: from the top of the head tube ``r12``
(the steer axis at the height of the top of the seat tube ``r10``) up the head tube by the stem
length ``l_s`` to ``r16``, then back by the handlebar length ``l_hb``.  So the grip position gives

    l_s  = (z10 - z_hand) / sin(lam_ht),      l_hb = x12 - l_s cos(lam_ht) - x_hand,

the *equivalent* stem and handlebar lengths that put the model's hands where the grips are.
Two differences remain and are documented, not hidden: the model's hands are ``l_ss/2`` (the
rider's half shoulder width) from the mid-plane, not ``whb/2``; and the fork length ``l_f`` is not
measured.  ``l_f`` only places the bottom of the head tube ``r11``, which no segment of the rider
uses (``r12`` depends only on the steer axis and ``r10``), so it drops out of every rider output;
we give the distance from the front wheel centre to ``r12`` (a head tube of zero length), which
always exceeds the fork offset as the model requires.  The hub widths ``w_fh`` and ``w_rh`` are
not measured either; they place only the hub grid points, which no segment uses, and are left out.
"""
from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from bikerider.bicycle.measured_geometry import sqrt_or_nan

MEASURED_NAMES: tuple[str, ...] = ("lcs", "hbb", "lsp", "lst", "lamst", "whb", "LhbF", "LhbR")
"""BicycleParameters' seating measurements."""

SEATING_OUTPUTS: tuple[str, ...] = ("h_bb", "l_cs", "l_f", "l_hb", "lam_st", "l_st", "l_s", "l_sp")
"""The paper's seating measurements (Table 1) derived here; ``w_fh`` and ``w_rh`` are not."""

HAND_OUTPUTS: tuple[str, ...] = ("x_hand", "z_hand")
"""The grip position in the benchmark frame [m] (an extra, for plots and checks)."""

NOTE = ("seating: l_s and l_hb are equivalent lengths that put the model's hands on the grips "
        "(LhbF, LhbR); l_f drops out of the rider model; hub widths w_fh, w_rh not measured")


def grip_position(w, rF, rR, whb, LhbF, LhbR):
    """``(x, z)`` of a handlebar grip from its distances to the wheel centres (NaN if none).

    The in-plane distances are the 3-D ones with the grip's ``whb/2`` lateral offset removed; of
    the two intersections of the circles about the wheel centres the upper one is taken.  Every
    argument is a float or an array of points (they broadcast).
    """
    half = 0.5 * whb
    front = sqrt_or_nan(np.where(LhbF > half, LhbF**2 - half**2, np.nan))
    rear = sqrt_or_nan(np.where(LhbR > half, LhbR**2 - half**2, np.nan))
    ex, ez = w, rR - rF  # rear centre (0, -rR) to front centre (w, -rF)
    span = np.hypot(ex, ez)
    along = (rear**2 - front**2 + span**2) / (2 * span)
    height = sqrt_or_nan(rear**2 - along**2)
    ex, ez = ex / span, ez / span
    # normal (ez, -ex) points up (-z) for a roughly horizontal centre line
    return along * ex + height * ez, -rR + along * ez - height * ex


def seating_from_measured(x: Mapping[str, float], *, rR, rF, w, lam, trail) -> dict[str, float]:
    """The paper's seating measurements from BicycleParameters' (see the module docstring).

    Parameters
    ----------
    x : mapping
        Must hold :data:`MEASURED_NAMES`; floats or arrays of points.
    rR, rF, w, lam, trail : float or ndarray
        Wheel radii, wheelbase, steer axis tilt (from the vertical) and trail of the bicycle.

    Returns
    -------
    dict
        :data:`SEATING_OUTPUTS` and :data:`HAND_OUTPUTS`; NaN where the grips cannot be located.
        ``l_s`` or ``l_hb`` may come out negative (grips below the top of the seat tube, or ahead of
        the stem top); the caller decides.
    """
    x_hand, z_hand = grip_position(w, rF, rR, x["whb"], x["LhbF"], x["LhbR"])
    z10 = -x["hbb"] - x["lst"] * np.sin(x["lamst"])
    x12 = w + trail + z10 * np.tan(lam)  # steer axis (through the ground at w + c) at height z10
    lam_ht = np.pi / 2 - lam
    l_s = (z10 - z_hand) / np.sin(lam_ht)
    l_hb = x12 - l_s * np.cos(lam_ht) - x_hand
    l_f = np.hypot(x12 - w, z10 + rF)
    return {
        "h_bb": x["hbb"], "l_cs": x["lcs"], "l_sp": x["lsp"], "l_st": x["lst"], "lam_st": x["lamst"],
        "l_s": l_s, "l_hb": l_hb, "l_f": l_f, "x_hand": x_hand, "z_hand": z_hand,
    }


def seating_problem(values: Mapping[str, float], rR: float) -> str | None:
    """Why derived seating values cannot be used (``None`` when they can)."""
    if not all(math.isfinite(values[k]) for k in ("x_hand", "z_hand")):
        return ("the grips cannot be located: LhbF and LhbR must each exceed whb/2 and the two "
                "in-plane distances must reach each other across the wheelbase")
    if not values["l_s"] > 0:
        return (f"the grips (z = {values['z_hand']:.3f} m) are not above the top of the seat tube, so the "
                f"paper's stem length would be {values['l_s']:.3f} m (it must be positive)")
    if not values["l_hb"] > 0:
        return (f"the grips (x = {values['x_hand']:.3f} m) are ahead of the equivalent stem top, so the "
                f"paper's handlebar length would be {values['l_hb']:.3f} m (it must be positive)")
    if not values["l_cs"] > abs(rR - values["h_bb"]):
        return (f"the chain stay lcs = {values['l_cs']:.3f} m does not reach from the rear axle to the "
                f"bottom bracket (height difference {abs(rR - values['h_bb']):.3f} m)")
    return None
