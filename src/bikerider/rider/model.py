"""Seat the rider on the bicycle: grid points, closure checks, mass properties.

Wraps ``bikerider.generated.rider_model`` (derived in ``derive/rider_model.py``).  Before any
generated function runs, the closures' preconditions are checked so that an impossible rider gets
a message naming the measurement and the distance needed, never a NaN.  Those are the only
refusals: the knee and elbow bend naturally for every direction of the limb (hands behind the
shoulders included; derive/rider_model.py explains the branch), so a rider is refused only when a
limb cannot close at all.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bikerider.bicycle.bodies import BicycleBodies
from bikerider.engine import arguments
from bikerider.errors import MISSING, InputError, ReachError
from bikerider.generated import rider_model as gen
from bikerider.generated.manifest import GEOMETRY, RIDER_PLACEMENT, RIDER_SEGMENTS
from bikerider.inertia import check_inertia_tensor
from bikerider.rider.measurements import RiderMeasurements

_GRID = arguments("rider_model.grid_points")
_REACH = arguments("rider_model.limb_reach")
_MASS = arguments("rider_model.rider_mass_properties")
_HUB_WIDTHS = tuple(a for a in _GRID if a not in _REACH)
"""The hub widths: they place grid points only, no segment depends on them."""

STRAIGHT_LIMB_TOLERANCE = 1e-12
"""A limb whose span (hip to pedal axis, shoulder to grip) is within this relative distance of its
length is straight: accepted, with the knee or elbow on the line through the limb's ends.  The
reach check and the closure compute the span along different rounding paths; without the slack,
an exactly straight limb could give the square root of a negative rounding error (NaN)."""

_STRAIGHT_MARGIN = 1e-14
"""A straight limb's two lengths are scaled to sum to ``span * (1 + margin)``, which keeps the
closure real; the joint then lies within about ``span * sqrt(2 margin)`` (1e-7 of the span) of the
line through the limb's ends."""

_LIMB_LENGTHS = (("l_ll", "l_ul"), ("l_ua", "l_la"))
"""Legs then arms, the order of ``limb_reach``."""

SEGMENT_LINES: tuple[tuple[str, int, int], ...] = (
    ("torso", 13, 15),
    ("right lower leg", 26, 28),
    ("left lower leg", 27, 29),
    ("right upper leg", 28, 30),
    ("left upper leg", 29, 31),
    ("right upper arm", 21, 23),
    ("left upper arm", 22, 24),
    ("right lower arm", 19, 23),
    ("left lower arm", 20, 24),
)
"""Segments drawn as lines between grid points (1-based); the head is a sphere at point 25."""


@dataclass(frozen=True)
class RiderModel:
    """The seated rider: grid points and mass properties in the benchmark frame.

    Attributes
    ----------
    grid_points : ndarray, shape (31, 3)
        Grid points 1..31 (row ``i`` is point ``i + 1``) [m]; the hub points 3, 4, 8, 9 are NaN
        when the hub widths were not measured (see :attr:`undetermined_points`).
    mass : float
        Rider mass [kg].
    com : ndarray, shape (3,)
        Centre of mass (Eq. 8) [m].
    inertia : ndarray, shape (3, 3)
        Inertia tensor about the centre of mass (Eq. 14) [kg m^2].
    """

    grid_points: np.ndarray
    mass: float
    com: np.ndarray
    inertia: np.ndarray

    @property
    def undetermined_points(self) -> list[int]:
        """Grid point numbers (1-based) the inputs do not place."""
        return [i + 1 for i in range(len(self.grid_points)) if not np.all(np.isfinite(self.grid_points[i]))]


def model_arguments(bicycle: BicycleBodies, rider: RiderMeasurements) -> dict[str, float]:
    """Keyword arguments of the generated rider functions.

    The hub widths only place the hub grid points (3, 4, 8, 9); when they were not measured
    (BicycleParameters files have none) those points are NaN and every other result is unchanged.
    """
    missing = [k for k in bicycle.missing_seating() if k not in _HUB_WIDTHS]
    if missing:
        raise InputError(
            missing[0],
            MISSING,
            f"a value: seating the rider model needs every Table 1 measurement (missing: {', '.join(missing)})",
            bicycle.source,
        )
    args = {k: bicycle[k] if k in bicycle.values else math.nan for k in GEOMETRY}
    args.update({k: rider[k] for k in RIDER_PLACEMENT + RIDER_SEGMENTS if k not in rider.fractions})
    args.update(rider.fractions)
    return args


def check_closures(args: dict[str, float], bicycle_source: str, rider_source: str) -> None:
    """Raise a clear error when the skeleton cannot be built for these measurements."""
    if args["l_cs"] <= abs(args["rR"] - args["h_bb"]):
        raise InputError(
            "l_cs",
            args["l_cs"],
            f"more than |rR - h_bb| = {abs(args['rR'] - args['h_bb']):.3f} m (chain stay must reach the bottom bracket)",
            bicycle_source,
        )
    fork_offset = args["rF"] * math.cos(args["lam_ht"]) - args["c"] * math.sin(args["lam_ht"])
    if args["l_f"] <= abs(fork_offset):
        raise InputError(
            "l_f", args["l_f"], f"more than the fork offset |f_o| = {abs(fork_offset):.3f} m", bicycle_source
        )
    reach_args = {k: args[k] for k in _REACH}
    leg_span, leg_len, arm_span, arm_len = (float(x) for x in gen.limb_reach(**reach_args))
    if leg_span > leg_len * (1 + STRAIGHT_LIMB_TOLERANCE):
        raise ReachError(
            "l_ll + l_ul",
            round(leg_len, 4),
            f"at least {leg_span:.3f} m, the distance from the hip (top of the seat) to the pedal axis: "
            f"the legs are {leg_span - leg_len:.3f} m too short to reach the pedals "
            "(lower the seat post l_sp or check l_ll and l_ul)",
            rider_source,
        )
    if leg_span <= abs(args["l_ll"] - args["l_ul"]) * (1 + STRAIGHT_LIMB_TOLERANCE):
        raise ReachError(
            "|l_ll - l_ul|",
            round(abs(args["l_ll"] - args["l_ul"]), 4),
            f"at most {leg_span:.3f} m, the hip to pedal-axis distance (the knee cannot close)",
            rider_source,
        )
    if arm_span > arm_len * (1 + STRAIGHT_LIMB_TOLERANCE):
        raise ReachError(
            "l_ua + l_la",
            round(arm_len, 4),
            f"at least {arm_span:.3f} m, the distance from the shoulder to the handlebar grip: "
            f"the arms are {arm_span - arm_len:.3f} m too short to reach the grips "
            "(check l_ua, l_la, l_to, lam_fl, or the stem and handlebar lengths)",
            rider_source,
        )
    if arm_span <= abs(args["l_ua"] - args["l_la"]) * (1 + STRAIGHT_LIMB_TOLERANCE):
        raise ReachError(
            "|l_ua - l_la|",
            round(abs(args["l_ua"] - args["l_la"]), 4),
            f"at most {arm_span:.3f} m, the shoulder to grip distance (the elbow cannot close)",
            rider_source,
        )


def straight_limbs(args: dict[str, float]) -> list[str]:
    """``"leg"`` and/or ``"arm"``: the limbs straight within :data:`STRAIGHT_LIMB_TOLERANCE`."""
    lengths = straight_limb_lengths(args)
    return [limb for limb, (distal, _) in zip(("leg", "arm"), _LIMB_LENGTHS) if distal in lengths]


def straight_limb_lengths(args: dict[str, float]) -> dict[str, float]:
    """Limb lengths to use for limbs that are straight within :data:`STRAIGHT_LIMB_TOLERANCE`.

    Returns an empty dict when no limb is at its limit of reach; otherwise, for each straight limb,
    its two lengths scaled to sum to ``span * (1 + 1e-14)`` (see :data:`_STRAIGHT_MARGIN`).
    """
    reach_args = {k: args[k] for k in _REACH}
    reach = [float(x) for x in gen.limb_reach(**reach_args)]
    out: dict[str, float] = {}
    for (a, b), span, length in zip(_LIMB_LENGTHS, reach[0::2], reach[1::2]):
        if abs(span - length) <= STRAIGHT_LIMB_TOLERANCE * span:
            scale = span * (1 + _STRAIGHT_MARGIN) / length
            out[a], out[b] = args[a] * scale, args[b] * scale
    return out


def seat_rider(bicycle: BicycleBodies, rider: RiderMeasurements) -> RiderModel:
    """Build the seated rider model on ``bicycle``.

    Raises
    ------
    InputError, ReachError
        Missing seating measurements, a rider whose legs or arms cannot reach pedals or grips,
        or a skeleton the branch rule does not cover.
    """
    args = model_arguments(bicycle, rider)
    # Reach depends on both files (seat, stem and handlebar on the bicycle; limbs on the rider).
    check_closures(args, bicycle.source, f"{rider.source} seated on {bicycle.source}")
    args.update(straight_limb_lengths(args))
    points = gen.grid_points(**{k: args[k] for k in _GRID})
    mass, com, inertia = gen.rider_mass_properties(**{k: args[k] for k in _MASS})
    check_inertia_tensor("rider inertia", inertia, rider.source)
    return RiderModel(np.asarray(points), float(mass), np.asarray(com), np.asarray(inertia))
