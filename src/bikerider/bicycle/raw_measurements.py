"""Reduce BicycleParameters raw measurements (a ``<Name>Measured.txt`` file's values) to
:class:`BicycleBodies`.

The chain, each step a generated stage (``derive/measured_reduction.py``, where each formula is
written down) run by the uncertainty engine (:mod:`bikerider.engine`):

1. wheel radii from the distance rolled in a number of turns, and the frame geometry either from
   wheelbase ``w``, head tube angle ``gamma`` and fork offset ``f``, or from the heights and
   diameters ``h1..h5``, ``d1..d4``, ``d``;
2. the torsional pendulum stiffness from the calibration rod (mass ``mP``, diameter ``dP``, length
   ``lP``, period ``TtP1``);
3. centres of mass of the rear frame ``B`` and the handlebar/fork ``H`` (or, measured apart, the
   handlebar ``G`` and the fork ``S``) from the hanging angles ``alphaXi`` and distances ``aXi``, and
   their in-plane inertia from the torsional periods ``TtXi`` (Eq. 6): in closed form for three
   orientations, by the numeric least-squares stage (:class:`bikerider.engine.LeastSquaresStage`)
   for more, or for BicycleParameters' centre-of-mass method (the mean of the pairwise
   intersections of the lines);
4. wheel moments ``IRxx``/``IFxx`` from one torsional period each, and ``I_yy`` of wheels and
   bodies from compound-pendulum periods ``TcX1`` (Eq. 7) about the wheel axle (``B``, ``H``,
   ``S``) or the handlebar reference point (``G``);
5. ``G`` and ``S`` combined into ``H`` (mass, centre of mass, parallel axis: the generated
   ``combination.rear_body``);
6. the seating measurements when the file has them (see "Seating" below).

Units are those of BicycleParameters: metres, kilograms, seconds; ``gamma`` and ``alphaXi`` in
degrees (converted to radians once, here); ``lamst`` in radians.

Uncertainty.  The whole chain is one set of stages: every output's standard uncertainty is
propagated from every input's at first order with the stages' exact Jacobians, so shared inputs
(stiffness, steer axis tilt) are handled consistently.

Checks (on the nominal values).  A missing field raises :class:`InputError` naming it and saying
what it is for.  Periods, masses and lengths must be positive.  Repeated trials of a period (comma
separated in the file) must agree: any trial more than :data:`PERIOD_TRIAL_TOLERANCE` (relative)
from the median is an error, since it points at a mislabelled trial or a slipping clamp, not at
random timing error; agreement within that is absorbed into the uncertainty (see
:mod:`bikerider.io.name_value_file`).  Hanging lines that miss their common point by more than the
line tolerance raise :class:`FitError`; orientations that leave Eq. 6 singular raise
:class:`InputError`.

Hanging angles.  Each hanging photograph gives ``alpha``, the angle (degrees, counter-clockwise
seen from the bicycle's right side) of the upward steer-axis direction from the photograph's
horizontal, and ``a``, the perpendicular distance from the vertical pendulum axis to a reference
point on the body (a wheel centre or the handlebar reference point), positive when the reference
point is left of the axis in the photograph.  Turning the photograph back so the bicycle is upright
carries the vertical axis to the angle ``beta = lam - alpha`` (``lam`` the steer axis tilt; modulo
180 degrees, which a line does not notice), and "left of the upward axis" becomes the side the
line's normal ``n = (sin(beta), cos(beta))`` points to, so the line is ``n . p = n . p_ref - a``.

Seating.  BicycleParameters' Measured files describe where a rider sits with eight numbers (used by
its ``rider.py`` to pose a Yeadon human):

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
two circles about ``(w, -rF)`` and ``(0, -rR)`` meet above the wheel centres.  The paper's model
(Table 10) places the hands differently: from the top of the head tube ``r12`` (the steer axis at
the height of the top of the seat tube ``r10``) up the head tube by the stem length ``l_s`` to
``r16``, then back by the handlebar length ``l_hb``.  So the grip position gives the *equivalent*
stem and handlebar lengths that put the model's hands where the grips are (the generated
``seating`` stage).  Two differences remain and are documented, not hidden: the model's hands are
``l_ss/2`` (the rider's half shoulder width) from the mid-plane, not ``whb/2``; and the fork length
``l_f`` is not measured.  ``l_f`` only places the bottom of the head tube ``r11``, which no segment
of the rider uses (``r12`` depends only on the steer axis and ``r10``), so it drops out of every
rider output; we give the distance from the front wheel centre to ``r12`` (a head tube of zero
length), which always exceeds the fork offset as the model requires.  The hub widths ``w_fh`` and
``w_rh`` are not measured either; they place only the hub grid points, which no segment uses, and
are left out.
"""

from __future__ import annotations

import functools
import logging
import math
import re
import statistics
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass, field

import numpy as np

from bikerider.bicycle.bodies import BODY_NAMES, OPTIONAL_BODY_NAMES, BicycleBodies
from bikerider.bicycle.pendulum import (
    DEFAULT_LINE_TOLERANCE,
    PARALLEL,
    PARALLEL_CONDITIONING,
    SINGULAR_DETERMINANT,
    LineIntersection,
    check_lines_meet,
)
from bikerider.engine import GeneratedStage, LeastSquaresStage, Stage, arguments, conditioning_2x2, first_order
from bikerider.errors import ErrorCollector, FitError, InputError
from bikerider.fitting import PERIOD_TRIAL_TOLERANCE
from bikerider.generated.manifest import STAGES
from bikerider.inertia import inertia_problem, plane_symmetric_principal_moments
from bikerider.notes import note
from bikerider.quantity import DEG, SMALLEST, Quantity, check_degrees, check_magnitude, smallest_expected

LOG = logging.getLogger(__name__)

BODIES = {
    "B": "rear frame",
    "H": "handlebar and fork",
    "G": "handlebar (measured apart from the fork)",
    "S": "fork (measured apart from the handlebar)",
}
_REFERENCE = {
    "B": "rear wheel centre",
    "H": "front wheel centre",
    "S": "front wheel centre",
    "G": "handlebar reference point",
}

FIELD_PURPOSES: dict[str, str] = {
    "dF": "distance rolled by the front wheel in nF turns, for its radius rF",
    "nF": "number of front wheel turns rolled over dF, for its radius rF",
    "dR": "distance rolled by the rear wheel in nR turns, for its radius rR",
    "nR": "number of rear wheel turns rolled over dR, for its radius rR",
    "mR": "rear wheel mass",
    "mF": "front wheel mass",
    "mB": "rear frame mass",
    "mH": "handlebar and fork mass",
    "mG": "handlebar mass (fork measured apart)",
    "mS": "fork mass (handlebar measured apart)",
    "g": "acceleration due to gravity, for the compound pendulum inertias",
    "lF": "front wheel compound pendulum length (pivot to wheel centre), for IFyy",
    "lR": "rear wheel compound pendulum length (pivot to wheel centre), for IRyy",
    "TcF1": "front wheel compound pendulum period, for IFyy",
    "TcR1": "rear wheel compound pendulum period, for IRyy",
    "TtF1": "front wheel torsional pendulum period, for IFxx",
    "TtR1": "rear wheel torsional pendulum period, for IRxx",
    "mP": "calibration rod mass, for the torsional pendulum stiffness",
    "dP": "calibration rod diameter, for the torsional pendulum stiffness",
    "lP": "calibration rod length, for the torsional pendulum stiffness",
    "TtP1": "calibration rod torsional period, for the torsional pendulum stiffness",
    "w": "wheelbase",
    "gamma": "head tube angle from the ground in degrees (with w and f)",
    "f": "fork offset (with w and gamma), for the trail",
    **{
        f"h{i}": "a height of the heights-and-diameters frame geometry (steer axis tilt, wheelbase, trail)"
        for i in range(1, 6)
    },
    **{
        f"d{i}": "a diameter of the heights-and-diameters frame geometry (steer axis tilt, wheelbase, trail)"
        for i in range(1, 5)
    },
    "d": "the axle distance of the heights-and-diameters frame geometry (steer axis tilt, wheelbase, trail)",
    "h6": "height of the front axle top, for the handlebar reference point (fork measured apart)",
    "h7": "height of the handlebar reference circle top, for the handlebar reference point",
    "d5": "front axle diameter, for the handlebar reference point",
    "d6": "handlebar reference circle diameter, for the handlebar reference point",
    "l": "outer distance from front axle to handlebar reference circle, for the handlebar reference point",
}

_WHEELS = ("dF", "nF", "dR", "nR", "mR", "mF", "g", "lF", "lR", "TcF1", "TcR1", "TtF1", "TtR1")
_ROD = arguments("measured_reduction.wheels")[:4]
"""The calibration rod's fields (``mP, dP, lP, TtP1``): the first inputs of the ``wheels`` stage."""
_WHEELBASE_GEOMETRY = ("w", "gamma", "f")
_HEIGHTS_GEOMETRY = tuple(a for a in arguments("measured_reduction.frame_from_heights") if a not in ("rF", "rR"))
_HANDLEBAR_REFERENCE = tuple(
    a for a in arguments("measured_reduction.handlebar_reference") if a not in ("w", "rF", "lam")
)
_POSITIVE = ("dF", "nF", "dR", "nR", "mR", "mF", "mB", "mH", "mG", "mS", "g", "lF", "lR", "mP", "dP", "lP", "w")
_INDEXED = re.compile(r"^(alpha|a|Tt|Tc)([BHGS])(\d{1,3})$")
_KNOWN_EXTRAS = {"xcl", "zcl", "ds1", "ds3"}
"""Names BicycleParameters files carry that the benchmark bodies do not use (lateral force point,
extra frame distances); listed in the notes, not errors."""


@dataclass(frozen=True)
class MeasuredLayout:
    """What a Measured file contains: which geometry, which bodies and their orientations."""

    geometry: str
    """``"wheelbase"`` (w, gamma, f) or ``"heights"`` (h1..h5, d1..d4, d)."""
    split_fork: bool
    """Handlebar G and fork S measured apart (combined into H)."""
    orientations: dict[str, tuple[int, ...]]
    """Orientation numbers of each hung body (``B``, ``H`` or ``G`` and ``S``)."""
    compound: dict[str, bool]
    """Whether the body's compound-pendulum period ``TcX1`` is there (for its I_yy)."""
    seating: bool
    """Whether every BicycleParameters seating measurement is there."""


@dataclass(frozen=True)
class MeasuredReduction:
    """The result of reducing a Measured file.

    Attributes
    ----------
    bodies : BicycleBodies
        The four bodies and geometry, each value with its propagated uncertainty.
    extras : dict of str to Quantity
        Intermediate values: ``k_t`` (pendulum stiffness), ``lam`` (steer axis tilt), fork offset
        ``f``, and for a split fork the handlebar ``G`` and fork ``S`` bodies (``mG, xG, zG, IGxx,
        IGxz, IGzz, IGyy`` and the same for ``S``).
    lines : dict of str to LineIntersection
        The centre-of-mass line fit of each hung body, with its residual.
    layout : MeasuredLayout
    notes : list of str
        Fields ignored, values not determined.
    """

    bodies: BicycleBodies
    extras: dict[str, Quantity]
    lines: dict[str, LineIntersection]
    layout: MeasuredLayout
    notes: list[str] = field(default_factory=list)


def _purpose(name: str) -> str:
    match = _INDEXED.match(name)
    if match:
        kind, body, index = match.groups()
        what = BODIES[body]
        return {
            "alpha": f"hanging angle of the {what} in orientation {index} (degrees, steer axis from the horizontal)",
            "a": f"distance from the pendulum axis to the {_REFERENCE[body]} with the {what} hung in orientation {index}",
            "Tt": f"torsional pendulum period of the {what} in orientation {index}",
            "Tc": f"compound pendulum period of the {what}, for its I_yy",
        }[kind]
    return FIELD_PURPOSES.get(name, "a measurement of the bicycle")


def _require(values: Collection[str], names, source: str) -> None:
    for name in names:
        if name not in values:
            raise InputError(name, "missing", f"a value: {_purpose(name)}", source)


def detect_layout(values: Mapping[str, Quantity], source: str = "<memory>") -> MeasuredLayout:
    """Find out which measurements a file holds and check that each set is complete.

    The layout depends on the names alone, so complete layouts are remembered by name set (files of
    one template share it); an incomplete one is looked at afresh, to name ``source`` in the error.

    Raises
    ------
    InputError
        A required field is missing (the message names it and what it is for), or a body was hung
        in fewer than three orientations.
    """
    try:
        return _layout_of_names(frozenset(values))
    except InputError:
        return _detect_layout(values, source)


@functools.lru_cache(maxsize=256)
def _layout_of_names(names: frozenset[str]) -> MeasuredLayout:
    return _detect_layout(names, "<memory>")


def _detect_layout(values: Collection[str], source: str) -> MeasuredLayout:
    """:func:`detect_layout` on the names (membership and iteration only)."""
    _require(values, _WHEELS + _ROD + ("mB",), source)
    if "w" in values or not any(k in values for k in _HEIGHTS_GEOMETRY):
        geometry = "wheelbase"
        _require(values, _WHEELBASE_GEOMETRY, source)
    else:
        geometry = "heights"
        _require(values, _HEIGHTS_GEOMETRY, source)
    hung_in: dict[str, set[int]] = {}  # orientations of each body with an angle, distance or period
    split = "mG" in values or "mS" in values
    for key in values:
        match = _INDEXED.match(key)
        if match:
            kind, body, index = match.groups()
            split = split or body in "GS"
            if kind != "Tc":
                hung_in.setdefault(body, set()).add(int(index))
    hung = ("B", "G", "S") if split else ("B", "H")
    _require(values, [f"m{b}" for b in hung[1:]], source)
    if split:
        _require(values, _HANDLEBAR_REFERENCE, source)
    orientations: dict[str, tuple[int, ...]] = {}
    for body in hung:
        indices = hung_in.get(body, set())
        ordered = tuple(sorted(indices))
        for i in ordered:
            _require(values, (f"alpha{body}{i}", f"a{body}{i}", f"Tt{body}{i}"), source)
        if len(ordered) < 3:
            missing = next(i for i in range(1, 4) if i not in indices)
            raise InputError(
                f"alpha{body}{missing}",
                "missing",
                f"a value: the {BODIES[body]} must be hung in at least three orientations (alpha{body}i, "
                f"a{body}i, Tt{body}i) to locate its centre of mass and in-plane inertia; "
                f"found {len(ordered)}",
                source,
            )
        orientations[body] = ordered
    compound = {body: f"Tc{body}1" in values for body in hung}
    return MeasuredLayout(geometry, split, orientations, compound, all(k in values for k in SEATING_FIELDS))


@functools.lru_cache(maxsize=1024)
def _raw_limit(name: str) -> tuple[float, str]:
    """Largest plausible magnitude of a Measured-file value, in its BicycleParameters unit."""
    if name.startswith(("Tt", "Tc")):
        return 100.0, "s"
    if name.startswith("alpha") or name == "gamma":
        return 360.0, "deg"
    if name == "lamst":
        return 2 * math.pi, "rad"
    if name in ("nF", "nR"):
        return 1000.0, "turns"
    if name in ("dF", "dR"):
        return 1000.0, "m"
    if name == "g":
        return 100.0, "m/s^2"
    if re.match(r"^m[A-Z]$", name):
        return 500.0, "kg"
    return 10.0, "m"  # every other value of a Measured file is a length


@functools.lru_cache(maxsize=1024)
def is_known_field(name: str) -> bool:
    """Whether ``name`` is a field of a BicycleParameters Measured file that bikerider knows."""
    return name in FIELD_PURPOSES or name in SEATING_FIELDS or name in _KNOWN_EXTRAS or bool(_INDEXED.match(name))


_POSITIVE_SMALLEST = tuple((name, SMALLEST.get(_raw_limit(name)[1], 0.0), _raw_limit(name)[1]) for name in _POSITIVE)
"""Each of :data:`_POSITIVE` with its smallest value (:data:`bikerider.quantity.SMALLEST`) and unit."""


@functools.lru_cache(maxsize=1024)
def _field_limit(name: str) -> tuple[float, str] | None:
    """:func:`_raw_limit` of a field :func:`is_known_field` knows, ``None`` for any other."""
    return _raw_limit(name) if is_known_field(name) else None


def _check_values(
    values: Mapping[str, Quantity],
    where: Callable[[str], str],
    repeats: Mapping[str, tuple[Quantity, ...]],
    errors: ErrorCollector | None = None,
) -> None:
    """Each value of a Measured file on its own: known, within its limit, positive where it must
    be (lengths and masses at least :data:`bikerider.quantity.SMALLEST`), periods above 1 ms and
    repeated trials that agree; every problem goes to ``errors`` (each value's first), or is
    raised at the end when no collector is given."""
    if errors is None:
        errors = ErrorCollector()
        _check_values(values, where, repeats, errors)
        errors.raise_any()
        return
    failed: set[str] = set()

    def fail(error: InputError) -> None:
        errors.add(error)
        failed.add(error.name.removesuffix(" uncertainty"))

    periods = []  # the known periods, in file order
    for name, q in values.items():
        rule = _field_limit(name)
        if rule is None:
            fail(
                InputError(
                    name,
                    q.value,
                    "a field of a BicycleParameters Measured file (rolled distances dF, nF, masses mB, mH, ..., "
                    "pendulum periods TtB1, TcF1, ..., angles alphaB1, ..., geometry w, gamma, f or h1..h5, d1..d4, "
                    "seating lcs, hbb, ...): a field bikerider does not know is not dropped silently",
                    where(name),
                )
            )
            continue
        limit, unit = rule
        if unit == "s":  # (exactly the known names that start with Tt or Tc)
            periods.append(name)
        if not (abs(q.value) <= limit and abs(q.sigma) <= limit):  # check_magnitude passes these
            with errors.check():
                check_magnitude(name, q.value, limit, unit, where(name))
                check_magnitude(f"{name} uncertainty", q.sigma, limit, unit, where(name))
            failed.add(name)
    if "gamma" in values and "gamma" not in failed:
        try:
            check_degrees("gamma", values["gamma"].value, where("gamma"))
        except InputError as exc:
            fail(exc)
    for name, smallest, unit in _POSITIVE_SMALLEST:
        if name in values and name not in failed:
            value = values[name].value
            if not value > 0:
                fail(InputError(name, value, f"a positive value ({_purpose(name)})", where(name)))
            elif value < smallest:
                fail(InputError(name, value, smallest_expected(smallest, unit), where(name)))
    for name in periods:
        value = values[name].value
        if not value > 1e-3 and name not in failed:  # 1 ms: squares underflow
            fail(
                InputError(name, value, f"a positive period in seconds, above 0.001 s ({_purpose(name)})", where(name))
            )
    for name, trials in repeats.items():
        if len(trials) < 2 or name in failed or not name.startswith(("Tt", "Tc")):
            continue
        median = statistics.median(t.value for t in trials)
        worst = max(trials, key=lambda t: abs(t.value - median))
        if abs(worst.value - median) > PERIOD_TRIAL_TOLERANCE * median:
            shown = ", ".join(f"{t.value:.6g}" for t in trials)
            fail(
                InputError(
                    name,
                    f"[{shown}] s",
                    f"repeated trials within {PERIOD_TRIAL_TOLERANCE:.0%} of their median {median:.6g} s "
                    f"(trial {worst.value:.6g} s is {abs(worst.value - median) / median:.1%} off: a trial of "
                    "another orientation or body, or a slipping clamp?)",
                    where(name),
                )
            )


SEATING_FIELDS: tuple[str, ...] = ("lcs", "hbb", "lsp", "lst", "lamst", "whb", "LhbF", "LhbR")
"""BicycleParameters' seating measurements (see the module docstring)."""

SEATING_OUTPUTS: tuple[str, ...] = ("h_bb", "l_cs", "l_f", "l_hb", "lam_st", "l_st", "l_s", "l_sp")
"""The paper's seating measurements (Table 1) derived from them; ``w_fh`` and ``w_rh`` are not."""

HAND_OUTPUTS: tuple[str, ...] = ("x_hand", "z_hand")
"""The grip position in the benchmark frame [m] (an extra, for plots and checks)."""

SEATING_NOTE = (
    "seating: l_s and l_hb are equivalent lengths that put the model's hands on the grips "
    "(LhbF, LhbR); l_f drops out of the rider model; hub widths w_fh, w_rh not measured"
)

_REAR_BODY = STAGES["rear_body"]["outputs"]
_HANDLEBAR = [name.replace("B", "H", 1) for name in _REAR_BODY]
"""The handlebar/fork H: the second body that the rear_body stage combines G and S into."""
_SEATING_NODES = tuple(
    a
    for a in arguments("measured_reduction.seating")
    if a not in arguments("measured_reduction.frame_from_wheelbase")
    and a not in STAGES["frame_from_wheelbase"]["outputs"]
)
"""The seating stage's own inputs (``whb, LhbF, LhbR, h_bb, l_st, lam_st``)."""
NODES = {"gamma": "lam_ht", "mB": "mBf", "lcs": "l_cs", "hbb": "h_bb", "lsp": "l_sp", "lst": "l_st", "lamst": "lam_st"}
"""The reduction's node names (the symbol table's) of the file's fields that differ from them."""
_IN_DEGREES = re.compile(r"^(gamma|alpha[A-Z]\d+)$")
"""Fields the file gives in degrees (their nodes are in radians)."""


def _node_name(body: str) -> str:
    return "Bf" if body == "B" else body


def _layout_key(layout: MeasuredLayout, com_method: str) -> tuple:
    return (
        layout.geometry,
        layout.split_fork,
        tuple(layout.orientations.items()),
        tuple(layout.compound.items()),
        layout.seating,
        com_method,
    )


def _is_standard(key: tuple) -> bool:
    """Whether a layout is BicycleParameters' template (the generated ``standard_layout`` stage):
    wheelbase geometry, the rear frame and handlebar/fork each hung in three orientations with their
    compound periods, and the least-squares centre of mass."""
    geometry, split_fork, orientations, compound, _, com_method = key
    return (
        geometry == "wheelbase"
        and not split_fork
        and orientations == (("B", (1, 2, 3)), ("H", (1, 2, 3)))
        and compound == (("B", True), ("H", True))
        and com_method == "least_squares"
    )


@functools.lru_cache(maxsize=64)
def _stages(key: tuple) -> tuple[Stage, ...]:
    """The stages of a layout (cached: files of one template share them)."""
    geometry, split_fork, orientations, compound, seating, com_method = key
    if _is_standard(key):  # every step in one generated stage: one call for the common layout
        checks = {
            f"{body}_{check}": f"{body}.{check}"
            for body in "BH"
            for check in ("miss_1", "miss_2", "miss_3", "lines_det", "eq6_det")
        }
        checks.update({f"{body}_l_p": f"{body}.compound.l_p" for body in "BH"})
        return (GeneratedStage("standard_layout", "standard_layout", checks=checks),)
    compound = dict(compound)
    stages: list[Stage] = [
        GeneratedStage("frame_from_wheelbase" if geometry == "wheelbase" else "frame_from_heights", "frame"),
        GeneratedStage("wheels"),
    ]
    references = {
        "B": ("x_rear", "z_rear"),
        "H": ("x_front", "z_front"),
        "S": ("x_front", "z_front"),
        "G": ("x_refG", "z_refG"),
    }
    if split_fork:
        stages.append(
            GeneratedStage("handlebar_reference", "G_reference", outputs={"x_ref": "x_refG", "z_ref": "z_refG"})
        )
    for body, indices in orientations:
        name = _node_name(body)
        x_ref, z_ref = references[body]
        shared = {"x_ref": x_ref, "z_ref": z_ref}
        point = _least_squares_point(body, com_method)
        if len(indices) == 3:
            hung = {
                **{f"hang_{k}": f"alpha{body}{i}" for k, i in enumerate(indices, start=1)},
                **{f"off_{k}": f"a{body}{i}" for k, i in enumerate(indices, start=1)},
                **{f"T_{k}": f"Tt{body}{i}" for k, i in enumerate(indices, start=1)},
            }
            stages.append(
                GeneratedStage(
                    "hung_body_3",
                    body,
                    {**shared, **hung},
                    {"x": point[0], "z": point[1], **{f"I{a}": f"I{name}{a}" for a in ("xx", "xz", "zz")}},
                )
            )
        else:
            lines = [{"hang": f"alpha{body}{i}", "off": f"a{body}{i}", **shared} for i in indices]
            stages += [
                LeastSquaresStage(f"{body}.lines", "hanging_line", lines, ("s", "c"), "d", point),
                LeastSquaresStage(
                    f"{body}.tensor",
                    "hung_orientation_equation",
                    [{"hang": f"alpha{body}{i}", "T": f"Tt{body}{i}"} for i in indices],
                    ("r_xx", "r_xz", "r_zz"),
                    "J",
                    tuple(f"I{name}{a}" for a in ("xx", "xz", "zz")),
                ),
            ]
        if com_method == "pairwise_mean":
            lines = [{"hang": f"alpha{body}{i}", "off": f"a{body}{i}", **shared} for i in indices]
            stages.append(
                LeastSquaresStage(
                    f"{body}.pairwise",
                    "hanging_line",
                    lines,
                    ("s", "c"),
                    "d",
                    (f"x{name}", f"z{name}"),
                    method="pairwise_mean",
                )
            )
        if compound[body]:
            stages.append(
                GeneratedStage(
                    "compound_about_point",
                    f"{body}.compound",
                    {"T": f"Tc{body}1", "m_p": f"m{name}", "x_c": f"x{name}", "z_c": f"z{name}", **shared},
                    {"Iyy": f"I{name}yy"},
                )
            )
    if split_fork:
        frame = {f"{p}Bf": f"{p}G" for p in ("m", "x", "z")} | {f"IBf{a}": f"IG{a}" for a in ("xx", "yy", "zz", "xz")}
        rider = {f"{p}Br": f"{p}S" for p in ("m", "x", "z")} | {f"IBr{a}": f"IS{a}" for a in ("xx", "yy", "zz", "xz")}
        stages.append(GeneratedStage("rear_body", "H_from_G_and_S", frame | rider, dict(zip(_REAR_BODY, _HANDLEBAR))))
    if seating:
        stages.append(GeneratedStage("seating"))
    return tuple(stages)


@functools.lru_cache(maxsize=1024)
def _node_of_field(field_name: str) -> tuple[str | None, float]:
    """The node of a file's field and the factor to SI (``None``: a field the bodies do not use)."""
    if field_name in _KNOWN_EXTRAS:
        return None, 1.0
    return NODES.get(field_name, field_name), DEG if _IN_DEGREES.match(field_name) else 1.0


def measured_inputs(values: Mapping[str, Quantity], layout: MeasuredLayout) -> dict[str, Quantity]:
    """The file's values as the reduction's input nodes: SI units (degrees to radians, once) and the
    symbol table's names; an ``I_yy`` the file gives no compound period for is NaN."""
    inputs = {}
    for field_name, q in values.items():
        node, factor = _node_of_field(field_name)
        if node is None:
            continue
        inputs[node] = q if factor == 1.0 else Quantity(q.value * factor, q.sigma * factor)
    for body, measured in layout.compound.items():
        if not measured:
            inputs[f"I{_node_name(body)}yy"] = Quantity(math.nan)
    if not layout.seating:  # the seating stage's inputs; NaN reaches the seating outputs alone
        for name in _SEATING_NODES:
            inputs.setdefault(name, Quantity(math.nan))
    return inputs


def _line_fit(nodes: Mapping[str, object], point: tuple[str, str], misses: list[str]) -> LineIntersection:
    """The least-squares line fit of a hung body: point, signed distances and rms."""
    distances = np.array([float(nodes[m]) for m in misses])  # type: ignore[arg-type]
    return LineIntersection(
        np.array([float(nodes[point[0]]), float(nodes[point[1]])]),
        distances,  # type: ignore[arg-type]
        math.sqrt(math.fsum(d * d for d in distances.tolist()) / len(misses)),
    )


def _least_squares_point(body: str, com_method: str) -> tuple[str, str]:
    """The nodes of a hung body's least-squares point (its centre of mass unless the pairwise
    mean is asked for)."""
    name = _node_name(body)
    return (f"x{name}", f"z{name}") if com_method == "least_squares" else (f"{body}.x", f"{body}.z")


def _check(
    nodes: Mapping[str, object],
    layout: MeasuredLayout,
    com_method: str,
    line_tolerance: float,
    source: str,
    lines: dict[str, LineIntersection],
) -> None:
    """The checks of the reduction at the nominal point, in the order of its steps; fills ``lines``."""
    lam = float(nodes["lam"])  # type: ignore[arg-type]
    if layout.geometry == "heights" and not math.isfinite(lam):
        a, b = float(nodes["frame.a"]), float(nodes["frame.b"])  # type: ignore[arg-type]
        raise InputError(
            "d",
            float(nodes["d"]),
            "heights and diameters that close into a frame: "  # type: ignore[arg-type]
            f"offsets a = {a:.4f} m, b = {b:.4f} m give no steer axis tilt",
            source,
        )
    if not 0 < lam < math.pi / 2:
        raise InputError(
            "gamma" if layout.geometry == "wheelbase" else "h1",
            math.degrees(math.pi / 2 - lam),
            "a head tube angle between 0 and 90 degrees",
            source,
        )
    for wheel in ("R", "F"):
        _check_compound(
            f"Tc{wheel}1", nodes[f"I{wheel}yy"], nodes[f"Tc{wheel}1"], nodes[f"l{wheel}"], nodes["g"], source
        )
    if layout.split_fork and not math.isfinite(float(nodes["G_reference.l2"])):  # type: ignore[arg-type]
        raise InputError(
            "l",
            float(nodes["l"]),
            "an axle-to-reference-circle distance longer than the height "  # type: ignore[arg-type]
            f"difference l1 = {float(nodes['G_reference.l1']):.4f} m",
            source,
        )  # type: ignore[arg-type]
    for body, indices in layout.orientations.items():
        name, m = _node_name(body), len(indices)
        point = _least_squares_point(body, com_method)
        if m == 3:
            fit = _line_fit(nodes, point, [f"{body}.miss_{i}" for i in (1, 2, 3)])
            conditioning = conditioning_2x2(float(nodes[f"{body}.lines_det"]), 3.0)  # type: ignore[arg-type]
            singularity = abs(float(nodes[f"{body}.eq6_det"]))  # type: ignore[arg-type]
        else:
            fit = _line_fit(nodes, point, [f"{body}.lines.miss_{i}" for i in range(1, m + 1)])
            conditioning = float(nodes[f"{body}.lines.conditioning"])  # type: ignore[arg-type]
            singularity = float(nodes[f"{body}.tensor.smallest_singular"])  # type: ignore[arg-type]
        betas = [lam - float(nodes[f"alpha{body}{i}"]) for i in indices]  # type: ignore[arg-type]
        lines[body] = fit
        if not conditioning >= PARALLEL_CONDITIONING:
            raise FitError(PARALLEL)
        check_lines_meet(f"the {BODIES[body]} ({body})", fit, line_tolerance, source)
        if not (math.isfinite(float(nodes[f"x{name}"])) and math.isfinite(float(nodes[f"z{name}"]))):  # type: ignore[arg-type]
            raise FitError(
                f"{source}: the hanging lines are parallel: two lines of the {BODIES[body]} ({body}) "
                "meet nowhere, so the mean of their pairwise intersections is not defined"
            )
        if singularity < SINGULAR_DETERMINANT:
            shown = ", ".join(f"{math.degrees(b) % 180:.1f}" for b in betas)
            raise InputError(
                f"alpha{body}",
                f"pendulum axes at [{shown}] deg from +x",
                f"orientations of the {BODIES[body]} whose pendulum axes differ pairwise by more than a few "
                f"degrees modulo 180 (Eq. 6 is singular for these: determinant {singularity:.2g})",
                source,
            )
        if layout.compound[body]:
            _check_compound(
                f"Tc{body}1",
                nodes[f"I{name}yy"],
                nodes[f"Tc{body}1"],
                nodes[f"{body}.compound.l_p"],
                nodes["g"],
                source,
            )


def _check_compound(name: str, inertia, period, length, g, source: str) -> None:
    """A compound pendulum period too short for its length gives a negative I_yy: name it."""
    if not float(inertia) > 0:
        shortest = 2 * math.pi * math.sqrt(float(length) / float(g))
        raise InputError(
            name,
            float(period),
            f"a compound pendulum period above {shortest:.4f} s, that of a point mass {float(length):.4f} m "
            "from the pivot (a shorter one gives a negative moment of inertia)",
            source,
        )


@functools.lru_cache(maxsize=64)
def _outputs(key: tuple) -> tuple[str, ...]:
    """The reduction's outputs of a layout (:func:`_layout_key`), in the order
    :class:`MeasuredReduction` reports them (worked out once per layout)."""
    _, split_fork, orientations, _, seating, _ = key
    out = ["w", "c", "lam_ht", "g", "rR", "rF", "lam", "f", "k_t"]
    for wheel in ("R", "F"):
        out += [f"m{wheel}", f"I{wheel}xx", f"I{wheel}yy"]
    for body, _ in orientations:
        name = _node_name(body)
        out += [f"m{name}", f"x{name}", f"z{name}", f"I{name}xx", f"I{name}xz", f"I{name}zz", f"I{name}yy"]
    if split_fork:
        out += _HANDLEBAR
    if seating:
        out += ["h_bb", "l_cs", "l_sp", "l_st", "lam_st", "l_s", "l_hb", "l_f", "x_hand", "z_hand"]
    return tuple(out)


_BODY_OUTPUTS = BODY_NAMES + OPTIONAL_BODY_NAMES


def reduce_values(
    values: Mapping[str, Quantity],
    layout: MeasuredLayout,
    *,
    com_method: str = "least_squares",
    line_tolerance: float = DEFAULT_LINE_TOLERANCE,
    source: str = "<memory>",
) -> tuple[dict[str, Quantity], dict[str, LineIntersection]]:
    """The reduction's outputs with first-order uncertainties (NaN where the file does not determine
    them), in the order of :func:`_outputs`, and each hung body's line fit; the checks of the
    reduction raise on the way (see :func:`reduce_measured`)."""
    inputs = measured_inputs(values, layout)
    key = _layout_key(layout, com_method)
    result = first_order(_stages(key), inputs)
    lines: dict[str, LineIntersection] = {}
    _check(result.nodes, layout, com_method, line_tolerance, source, lines)
    outputs = _outputs(key)
    computed = result.quantities([name for name in outputs if name not in inputs])
    reduced = {name: inputs[name] if name in inputs else computed[name] for name in outputs}
    return reduced, lines


def reduce_measured(
    values: Mapping[str, Quantity],
    *,
    source: object = "<memory>",
    name: str = "bicycle",
    line_tolerance: float = DEFAULT_LINE_TOLERANCE,
    com_method: str = "least_squares",
) -> MeasuredReduction:
    """Reduce BicycleParameters measurements to the bodies, with first-order uncertainties.

    Parameters
    ----------
    values : mapping of str to Quantity
        The Measured file's values, by the file's names.
    source : str, or a read file
        Where the values came from: a name, or an object with ``path``, ``where(name)`` (the file
        and line of a value) and ``entries`` (each value's repeated trials, ``repeats``), as
        :func:`bikerider.io.name_value_file.read_name_value_file` returns; then messages give line
        numbers and repeated period trials are checked.
    name : str
        Name of the bicycle.
    line_tolerance : float
        Largest rms distance [m] of a body's hanging lines from their common point.
    com_method : {"least_squares", "pairwise_mean"}
        How to locate a centre of mass from its lines: the least-squares point (ours) or the mean
        of the pairwise intersections (BicycleParameters').

    Raises
    ------
    InputError
        Missing or impossible measurements (named, with what they are for).
    FitError
        Hanging lines that do not meet within ``line_tolerance``.
    """
    if com_method not in ("least_squares", "pairwise_mean"):
        raise ValueError(f"com_method must be 'least_squares' or 'pairwise_mean', not {com_method!r}")
    label = str(getattr(source, "path", source))
    where = getattr(source, "where", None) or (lambda _name: label)
    repeats = {k: e.repeats for k, e in getattr(source, "entries", {}).items()}
    values = values.as_dict() if hasattr(values, "as_dict") else dict(values)  # fast lookups
    errors = ErrorCollector()
    _check_values(values, where, repeats, errors)
    layout = None
    with errors.check():
        layout = detect_layout(values, label)
    errors.raise_any()
    reduced, lines = reduce_values(values, layout, com_method=com_method, line_tolerance=line_tolerance, source=label)
    notes = _notes(values, layout)
    body_values = {k: reduced[k] for k in _BODY_OUTPUTS if math.isfinite(reduced[k].value)}
    if layout.seating:
        problem = seating_problem({k: q.value for k, q in reduced.items()}, reduced["rR"].value)
        if problem is None:
            body_values.update({k: reduced[k] for k in SEATING_OUTPUTS})
            notes.append(SEATING_NOTE)
        else:
            notes.append(f"seating measurements not usable: {problem}")
    _drop_inconsistent_yy(body_values, notes, label)
    extras = {k: q for k, q in reduced.items() if k not in body_values and math.isfinite(q.value)}
    for message in notes:
        note(f"{label}: {message}")
    bodies = BicycleBodies(body_values, source=label, name=name, notes=notes)
    return MeasuredReduction(bodies, extras, lines, layout, notes)


def seating_problem(values: Mapping[str, float], rR: float) -> str | None:
    """Why derived seating values cannot be used (``None`` when they can)."""
    if not all(math.isfinite(values[k]) for k in ("x_hand", "z_hand")):
        return (
            "the grips cannot be located: LhbF and LhbR must each exceed whb/2 and the two "
            "in-plane distances must reach each other across the wheelbase"
        )
    if not values["l_s"] > 0:
        return (
            f"the grips (z = {values['z_hand']:.3f} m) are not above the top of the seat tube, so the "
            f"paper's stem length would be {values['l_s']:.3f} m (it must be positive)"
        )
    if not values["l_hb"] > 0:
        return (
            f"the grips (x = {values['x_hand']:.3f} m) are ahead of the equivalent stem top, so the "
            f"paper's handlebar length would be {values['l_hb']:.3f} m (it must be positive)"
        )
    if not values["l_cs"] > abs(rR - values["h_bb"]):
        return (
            f"the chain stay lcs = {values['l_cs']:.3f} m does not reach from the rear axle to the "
            f"bottom bracket (height difference {abs(rR - values['h_bb']):.3f} m)"
        )
    return None


def _drop_inconsistent_yy(body_values: dict[str, Quantity], notes: list[str], source: str) -> None:
    """Leave out an ``I_yy`` that cannot belong to one body with the in-plane moments.

    ``IBfyy`` and ``IHyy`` come from a compound pendulum, the in-plane moments from the torsional
    pendulum; when they cannot belong to one body the linear model (which does not use ``I_yy``)
    is still served, and the value stays in :attr:`MeasuredReduction.extras` with a note.
    """
    for body in ("Bf", "H"):
        yy = body_values.get(f"I{body}yy")
        if yy is None:
            continue
        xx, xz, zz = (body_values[f"I{body}{axes}"].value for axes in ("xx", "xz", "zz"))
        if inertia_problem(xx, yy.value, zz, xz) is not None:
            del body_values[f"I{body}yy"]
            principal = ", ".join(f"{p:.4g}" for p in plane_symmetric_principal_moments(xx, yy.value, zz, xz))
            message = (
                f"I{body}yy = {yy} (compound pendulum) left out: with the torsional-pendulum "
                f"I{body}xx, I{body}xz, I{body}zz its principal moments {principal} break the triangle "
                "inequality (the linear model does not use it)"
            )
            notes.append(message)


def _notes(values: Mapping[str, Quantity], layout: MeasuredLayout) -> list[str]:
    notes = []
    if not layout.compound.get("B", False):
        notes.append("TcB1 missing: the rear frame's IBfyy is not determined (the linear model does not need it)")
    if not layout.split_fork and not layout.compound.get("H", False):
        notes.append("TcH1 missing: IHyy is not determined (the linear model does not need it)")
    if layout.split_fork and not (layout.compound["G"] and layout.compound["S"]):
        notes.append("TcG1 or TcS1 missing: IHyy is not determined (the linear model does not need it)")
    if layout.split_fork:
        ignored_h = sorted(k for k in values if k == "mH" or ((m := _INDEXED.match(k)) and m.group(2) == "H"))
        if ignored_h:
            notes.append("fork and handlebar measured apart; ignored the combined-body fields " + ", ".join(ignored_h))
    present = [k for k in SEATING_FIELDS if k in values]
    if present and not layout.seating:
        missing = [k for k in SEATING_FIELDS if k not in values]
        notes.append("seating measurements incomplete (missing " + ", ".join(missing) + "): the rider cannot be seated")
    extras = sorted(k for k in values if k in _KNOWN_EXTRAS)
    if extras:
        notes.append("not used by the benchmark bodies: " + ", ".join(extras))
    return notes


__all__ = [
    "BODIES",
    "FIELD_PURPOSES",
    "PERIOD_TRIAL_TOLERANCE",
    "SEATING_FIELDS",
    "SEATING_OUTPUTS",
    "MeasuredLayout",
    "MeasuredReduction",
    "detect_layout",
    "measured_inputs",
    "reduce_measured",
    "reduce_values",
    "seating_problem",
]
