"""Reduce a BicycleParameters ``<Name>Measured.txt`` file to :class:`BicycleBodies`.

The chain, each step in its own module:

1. wheel radii from the distance rolled in a number of turns, and the frame geometry either from
   wheelbase, head tube angle and fork offset or from the heights-and-diameters measurements
   (:mod:`bikerider.bicycle.measured_geometry`);
2. the torsional pendulum stiffness from the calibration rod (mass ``mP``, diameter ``dP``,
   length ``lP``, period ``TtP1``);
3. centres of mass of the rear frame ``B`` and the handlebar/fork ``H`` (or, measured apart, the
   handlebar ``G`` and the fork ``S``) from the hanging angles ``alphaXi`` and distances ``aXi``
   (:mod:`bikerider.bicycle.hanging_lines`);
4. wheel moments ``IRxx``/``IFxx`` from one torsional period each, in-plane inertia of B, H (or G
   and S) from the torsional periods ``TtXi`` at the hanging orientations (Eq. 6, least squares for
   more than three), and ``I_yy`` of wheels and bodies from compound-pendulum periods ``TcX1``
   (Eq. 7) about the wheel axle (``B``, ``H``, ``S``) or the handlebar reference point (``G``);
5. ``G`` and ``S`` combined into ``H`` (mass, centre of mass, parallel axis);
6. seating measurements when the file has them (:mod:`bikerider.bicycle.seating`).

Units are those of BicycleParameters: metres, kilograms, seconds; ``gamma`` and ``alphaXi`` in
degrees; ``lamst`` in radians.

Uncertainty.  The whole chain is one function of the file's values; every output's standard
uncertainty is propagated from every input's at first order, so shared inputs (stiffness, steer
axis tilt) are handled consistently.  For the template's layout (wheelbase geometry, rear frame and
handlebar/fork each hung in three orientations, all compound periods) the values and exact
uncertainties come from a generated closed form (:mod:`bikerider.bicycle.closed_form_reduction`)
whenever every check below passes.  Every other layout, every other centre-of-mass method, and every
file a check rejects goes through the general route: a numerical Jacobian
(:mod:`bikerider.bicycle.propagation`) of the chain written with NumPy on arrays of points, the
nominal point and all ``2 k + 1`` perturbed points in one call (:func:`evaluate_measured`; bodies
hung in the same number of orientations reduced together), which raises the errors.

Checks (on the nominal values).  A missing field raises :class:`InputError` naming it and saying
what it is for.  Periods, masses and lengths must be positive.  Repeated trials of a period (comma
separated in the file) must agree: any trial more than :data:`PERIOD_TRIAL_TOLERANCE` (relative)
from the median is an error, since it points at a mislabelled trial or a slipping clamp, not at
random timing error; agreement within that is absorbed into the uncertainty (see
:mod:`bikerider.io.name_value_file`).  Hanging lines that miss their common point by more than the
line tolerance raise :class:`FitError`; orientations that leave Eq. 6 singular raise
:class:`InputError`.
"""
from __future__ import annotations

import functools
import logging
import math
import re
import statistics
from collections.abc import Collection, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bikerider.bicycle import measured_geometry as geo
from bikerider.bicycle import seating
from bikerider.bicycle.bodies import BicycleBodies
from bikerider.bicycle.closed_form_reduction import reduce_standard_layout
from bikerider.bicycle.hanging_lines import (
    DEFAULT_LINE_TOLERANCE, LineIntersection, check_lines_meet, check_not_parallel,
    least_squares_point, pairwise_mean_point,
)
from bikerider.bicycle.pendulum import SINGULAR_DETERMINANT
from bikerider.bicycle.propagation import propagate
from bikerider.errors import FitError, InputError
from bikerider.fitting import PERIOD_TRIAL_TOLERANCE
from bikerider.generated import combination as gen_combination
from bikerider.generated import pendulum as gen_pendulum
from bikerider.inertia import check_inertia_tensor, plane_symmetric_principal_moments
from bikerider.io.name_value_file import NameValueFile, read_name_value_file
from bikerider.quantity import Quantity, check_degrees, check_magnitude

LOG = logging.getLogger(__name__)


#: Below this |determinant| of Eq. 6 for three orientations (``2 sin(b1-b2) sin(b1-b3) sin(b2-b3)``),
#: or this smallest singular value for more, the pendulum axes nearly coincide and the in-plane
#: inertia is not determined (the threshold of :mod:`bikerider.bicycle.pendulum`).
SINGULAR_ORIENTATIONS = SINGULAR_DETERMINANT

BODIES = {
    "B": "rear frame",
    "H": "handlebar and fork",
    "G": "handlebar (measured apart from the fork)",
    "S": "fork (measured apart from the handlebar)",
}
_REFERENCE = {"B": "rear wheel centre", "H": "front wheel centre", "S": "front wheel centre",
              "G": "handlebar reference point"}

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
    **{f"h{i}": "a height of the heights-and-diameters frame geometry (steer axis tilt, wheelbase, trail)"
       for i in range(1, 6)},
    **{f"d{i}": "a diameter of the heights-and-diameters frame geometry (steer axis tilt, wheelbase, trail)"
       for i in range(1, 5)},
    "d": "the axle distance of the heights-and-diameters frame geometry (steer axis tilt, wheelbase, trail)",
    "h6": "height of the front axle top, for the handlebar reference point (fork measured apart)",
    "h7": "height of the handlebar reference circle top, for the handlebar reference point",
    "d5": "front axle diameter, for the handlebar reference point",
    "d6": "handlebar reference circle diameter, for the handlebar reference point",
    "l": "outer distance from front axle to handlebar reference circle, for the handlebar reference point",
}

_WHEELS = ("dF", "nF", "dR", "nR", "mR", "mF", "g", "lF", "lR", "TcF1", "TcR1", "TtF1", "TtR1")
_ROD = ("mP", "dP", "lP", "TtP1")
_WHEELBASE_GEOMETRY = ("w", "gamma", "f")
_HEIGHTS_GEOMETRY = ("h1", "h2", "h3", "h4", "h5", "d1", "d2", "d3", "d4", "d")
_HANDLEBAR_REFERENCE = ("h6", "h7", "d5", "d6", "l")
_POSITIVE = ("dF", "nF", "dR", "nR", "mR", "mF", "mB", "mH", "mG", "mS", "g", "lF", "lR", "mP", "dP", "lP", "w")
_INDEXED = re.compile(r"^(alpha|a|Tt|Tc)([BHGS])(\d+)$")
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
                f"alpha{body}{missing}", "missing",
                f"a value: the {BODIES[body]} must be hung in at least three orientations (alpha{body}i, "
                f"a{body}i, Tt{body}i) to locate its centre of mass and in-plane inertia; "
                f"found {len(ordered)}", source,
            )
        orientations[body] = ordered
    compound = {body: f"Tc{body}1" in values for body in hung}
    return MeasuredLayout(geometry, split, orientations, compound, all(k in values for k in seating.MEASURED_NAMES))


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


def _check_values(values: Mapping[str, Quantity], layout: MeasuredLayout, source: NameValueFile | str,
                  repeats: Mapping[str, tuple[Quantity, ...]]) -> None:
    where = source.where if isinstance(source, NameValueFile) else (lambda name: str(source))
    for name, q in values.items():
        limit, unit = _raw_limit(name)
        if not (abs(q.value) <= limit and abs(q.sigma) <= limit):  # check_magnitude passes these
            check_magnitude(name, q.value, limit, unit, where(name))
            check_magnitude(f"{name} uncertainty", q.sigma, limit, unit, where(name))
    if "gamma" in values:
        check_degrees("gamma", values["gamma"].value, where("gamma"))
    for name in _POSITIVE:
        if name in values and not values[name].value > 0:
            raise InputError(name, values[name].value, f"a positive value ({_purpose(name)})", where(name))
    for name, q in values.items():
        if name.startswith(("Tt", "Tc")) and not q.value > 1e-3:  # 1 ms: below, squares underflow
            raise InputError(name, q.value, f"a positive period in seconds, above 0.001 s ({_purpose(name)})",
                             where(name))
    for name, trials in repeats.items():
        if not name.startswith(("Tt", "Tc")) or len(trials) < 2:
            continue
        median = statistics.median(t.value for t in trials)
        worst = max(trials, key=lambda t: abs(t.value - median))
        if abs(worst.value - median) > PERIOD_TRIAL_TOLERANCE * median:
            shown = ", ".join(f"{t.value:.6g}" for t in trials)
            raise InputError(
                name, f"[{shown}] s",
                f"repeated trials within {PERIOD_TRIAL_TOLERANCE:.0%} of their median {median:.6g} s "
                f"(trial {worst.value:.6g} s is {abs(worst.value - median) / median:.1%} off: a trial of "
                "another orientation or body, or a slipping clamp?)", where(name),
            )


def _first(value) -> float:
    """The value at the first point of a batch (the nominal point; see :func:`evaluate_measured`)."""
    return float(value[0]) if np.ndim(value) else float(value)


@dataclass
class _Hung:
    """One hung body at every point of a batch (see :func:`_hang`)."""

    x: np.ndarray
    z: np.ndarray
    inertia: np.ndarray
    """``[Ixx, Ixz, Izz]`` at every point, shape (points, 3)."""
    fit: LineIntersection
    """The least-squares line fit at the first point."""
    conditioning: np.ndarray
    """Of the lines at every point (:func:`~bikerider.bicycle.hanging_lines.least_squares_point`)."""
    betas: np.ndarray
    """Pendulum axis angles at the first point [rad]."""
    singularity: float
    """|determinant| of Eq. 6 (three orientations) or the smallest singular value of its rows (more),
    at the first point; ``inf`` when not computed."""
    yy: np.ndarray | float = math.nan
    length: float = math.nan
    """Compound pendulum length at the first point."""


def _hang(x: Mapping[str, np.ndarray], layout: MeasuredLayout, lam: np.ndarray, k_t: np.ndarray,
          references: dict, com_method: str, check: bool) -> dict[str, _Hung]:
    """Centres of mass (hanging lines), in-plane inertia (Eq. 6) and I_yy (Eq. 7) of every hung body.

    Bodies hung in the same number of orientations are reduced together: arrays are (orientations,
    bodies, points), so each step is one array operation for them all and every point.
    """
    groups: dict[int, list[str]] = {}
    for body, indices in layout.orientations.items():
        groups.setdefault(len(indices), []).append(body)
    hung: dict[str, _Hung] = {}
    for m, bodies in groups.items():
        names = [list(zip(bodies, slot)) for slot in zip(*(layout.orientations[b] for b in bodies))]

        def gather(prefix: str, names=names) -> np.ndarray:
            return np.array([[x[f"{prefix}{b}{i}"] for b, i in row] for row in names])

        betas = lam - np.radians(gather("alpha"))
        sin, cos = np.sin(betas), np.cos(betas)
        ref_x = np.array([references[b][0] for b in bodies])
        ref_z = np.array([references[b][1] for b in bodies])
        offsets = sin * ref_x + cos * ref_z - gather("a")
        ls_x, ls_z, conditioning = least_squares_point(sin, cos, offsets, axis=0)
        px, pz = (ls_x, ls_z) if com_method == "least_squares" else pairwise_mean_point(sin, cos, offsets, axis=0)
        periods = gather("Tt")
        if m == 3:
            inertia, det = gen_pendulum.inertia_from_three_orientations(
                k_t=k_t, T_1=periods[0], T_2=periods[1], T_3=periods[2],
                alpha_1=betas[0], alpha_2=betas[1], alpha_3=betas[2])  # (bodies, points, 3)
            singularity = np.abs(det[:, 0])
        else:  # least squares, one small SVD per point
            rows = np.moveaxis(gen_pendulum.orientation_row(alpha=betas), 0, 2)  # (bodies, points, m, 3)
            moments = np.moveaxis(gen_pendulum.torsional_inertia(k_t=k_t, T=periods), 0, 2)[..., None]
            inertia = (np.linalg.pinv(rows) @ moments)[..., 0]
            singularity = (np.linalg.svd(rows[:, 0], compute_uv=False)[:, -1] if check
                           else np.full(len(bodies), math.inf))
        # The line fit at the first (nominal) point, for the check and the report.
        sin0, cos0, offsets0 = sin[:, :, 0].T.tolist(), cos[:, :, 0].T.tolist(), offsets[:, :, 0].T.tolist()
        for j, body in enumerate(bodies):
            x0, z0 = float(ls_x[j, 0]), float(ls_z[j, 0])
            miss = [s_ * x0 + c_ * z0 - d_ for s_, c_, d_ in zip(sin0[j], cos0[j], offsets0[j])]
            fit = LineIntersection(np.array([x0, z0]), np.array(miss), math.sqrt(math.fsum(d * d for d in miss) / m))
            hung[body] = _Hung(px[j], pz[j], inertia[j], fit, conditioning[j], betas[:, j, 0], float(singularity[j]))
    compound = [b for b in layout.orientations if layout.compound[b]]
    if compound:
        lengths = np.array([np.hypot(hung[b].x - references[b][0], hung[b].z - references[b][1]) for b in compound])
        yy = gen_pendulum.compound_inertia(T=np.array([x[f"Tc{b}1"] for b in compound]),
                                           m_p=np.array([x[f"m{b}"] for b in compound]), g=x["g"], l_p=lengths)
        for j, body in enumerate(compound):
            hung[body].yy, hung[body].length = yy[j], float(lengths[j, 0])
    return {body: hung[body] for body in layout.orientations}


def _check_hung(body: str, hung: _Hung, x: Mapping[str, np.ndarray], check: bool, line_tolerance: float,
                source: str) -> None:
    """The checks of one hung body, in the order of the reduction's steps."""
    check_not_parallel(hung.conditioning)
    if not check:
        return
    check_lines_meet(f"the {BODIES[body]} ({body})", hung.fit, line_tolerance, source)
    if not (math.isfinite(hung.x[0]) and math.isfinite(hung.z[0])):
        raise FitError(f"{source}: the hanging lines are parallel: two lines of the {BODIES[body]} ({body}) "
                       "meet nowhere, so the mean of their pairwise intersections is not defined")
    if hung.singularity < SINGULAR_ORIENTATIONS:
        shown = ", ".join(f"{math.degrees(b) % 180:.1f}" for b in hung.betas)
        raise InputError(
            f"alpha{body}", f"pendulum axes at [{shown}] deg from +x",
            f"orientations of the {BODIES[body]} whose pendulum axes differ pairwise by more than a few "
            f"degrees modulo 180 (Eq. 6 is singular for these: determinant {hung.singularity:.2g})", source,
        )
    if np.ndim(hung.yy):
        _check_compound(f"Tc{body}1", hung.yy, x[f"Tc{body}1"], hung.length, x["g"], source)


def _check_compound(name: str, inertia: np.ndarray, period: np.ndarray, length: float, g: np.ndarray,
                    source: str) -> None:
    """A compound pendulum period too short for its length gives a negative I_yy: name it."""
    if not inertia[0] > 0:
        shortest = 2 * math.pi * math.sqrt(length / g[0])
        raise InputError(
            name, float(period[0]),
            f"a compound pendulum period above {shortest:.4f} s, that of a point mass {length:.4f} m "
            "from the pivot (a shorter one gives a negative moment of inertia)", source,
        )


def evaluate_measured(x: Mapping[str, float], layout: MeasuredLayout, *, com_method: str = "least_squares",
                      check: bool = False, line_tolerance: float = DEFAULT_LINE_TOLERANCE,
                      source: str = "<memory>", lines: dict | None = None) -> dict:
    """The whole reduction, without uncertainty, at one point or at a batch of points.

    Parameters
    ----------
    x : mapping of str to float, or of str to 1-D array
        The file's values (BicycleParameters units): floats for one point, or arrays of equal
        length for a batch of points (as :func:`bikerider.bicycle.propagation.propagate` passes
        with ``vectorized=True``, nominal point first).
    layout : MeasuredLayout
    com_method : {"least_squares", "pairwise_mean"}
        How to locate a centre of mass from its lines: the least-squares point (ours) or the mean
        of the pairwise intersections (BicycleParameters').
    check : bool
        Raise on lines that do not meet, singular orientations, non-physical results at the first
        point.  Nearly parallel hanging lines raise :class:`FitError` at any point.
    lines : dict, optional
        Filled with each body's :class:`LineIntersection` at the first point.

    Returns
    -------
    dict of str to float, or of str to array
        BicycleBodies names, seating names when derivable, and the extras of
        :class:`MeasuredReduction`: floats for one point, arrays over the batch for a batch.
        NaN for what the file does not determine.
    """
    batch = np.ndim(next(iter(x.values()))) > 0
    points = x if batch else {k: np.array([v], dtype=float) for k, v in x.items()}
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        out = _evaluate(points, layout, com_method, check, line_tolerance, source, lines)
    if batch:
        return out
    return {k: float(v[0]) for k, v in out.items()}


def _evaluate(x: Mapping[str, np.ndarray], layout: MeasuredLayout, com_method: str, check: bool,
              line_tolerance: float, source: str, lines: dict | None) -> dict[str, np.ndarray]:
    rF = geo.wheel_radius(x["dF"], x["nF"])
    rR = geo.wheel_radius(x["dR"], x["nR"])
    if layout.geometry == "wheelbase":
        lam = np.radians(90.0 - x["gamma"])
        w, fork_offset = x["w"], x["f"]
    else:
        a, b, c_axis = geo.perpendicular_offsets(
            tuple(x[k] for k in _HEIGHTS_GEOMETRY[:5]), tuple(x[k] for k in _HEIGHTS_GEOMETRY[5:]))
        lam = geo.steer_tilt_from_offsets(rF, rR, a, b, c_axis)
        if check and not math.isfinite(lam[0]):
            raise InputError("d", _first(x["d"]), "heights and diameters that close into a frame: "
                             f"offsets a = {_first(a):.4f} m, b = {_first(b):.4f} m give no steer axis tilt", source)
        w, fork_offset = geo.wheelbase_from_offsets(lam, a, b, c_axis), b
    if check and not 0 < lam[0] < math.pi / 2:
        raise InputError("gamma" if layout.geometry == "wheelbase" else "h1", math.degrees(math.pi / 2 - lam[0]),
                         "a head tube angle between 0 and 90 degrees", source)
    out = {"w": w, "c": geo.trail(rF, lam, fork_offset), "lam_ht": np.pi / 2 - lam, "g": x["g"], "rR": rR, "rF": rF,
           "lam": lam, "f": fork_offset}

    k_t = geo.torsional_stiffness(geo.rod_moment_of_inertia(x["mP"], x["dP"], x["lP"]), x["TtP1"])
    out["k_t"] = k_t
    wheel_xx = gen_pendulum.torsional_inertia(k_t=k_t, T=np.array([x["TtR1"], x["TtF1"]]))
    wheel_yy = gen_pendulum.compound_inertia(T=np.array([x["TcR1"], x["TcF1"]]), m_p=np.array([x["mR"], x["mF"]]),
                                             g=x["g"], l_p=np.array([x["lR"], x["lF"]]))
    for j, wheel in enumerate(("R", "F")):
        if check:
            _check_compound(f"Tc{wheel}1", wheel_yy[j], x[f"Tc{wheel}1"], float(x[f"l{wheel}"][0]), x["g"], source)
        out.update({f"m{wheel}": x[f"m{wheel}"], f"I{wheel}xx": wheel_xx[j], f"I{wheel}yy": wheel_yy[j]})

    references = {"B": (np.zeros_like(rR), -rR), "H": (w, -rF), "S": (w, -rF)}
    if layout.split_fork:
        l1, l2 = geo.handlebar_reference_offsets(*(x[k] for k in _HANDLEBAR_REFERENCE))
        if check and not math.isfinite(l2[0]):
            raise InputError("l", _first(x["l"]), "an axle-to-reference-circle distance longer than the height "
                             f"difference l1 = {_first(l1):.4f} m", source)
        references["G"] = geo.handlebar_reference_point(w, rF, lam, l1, l2)
    nan = np.full_like(lam, math.nan)
    for body, hung in _hang(x, layout, lam, k_t, references, com_method, check).items():
        _check_hung(body, hung, x, check, line_tolerance, source)
        if lines is not None:
            lines[body] = hung.fit
        name = "Bf" if body == "B" else body
        out.update({f"m{name}": x[f"m{body}"], f"x{name}": hung.x, f"z{name}": hung.z,
                    f"I{name}xx": hung.inertia[:, 0], f"I{name}xz": hung.inertia[:, 1], f"I{name}zz": hung.inertia[:, 2],
                    f"I{name}yy": hung.yy if np.ndim(hung.yy) else nan})
    if layout.split_fork:
        mH, xH, zH, IH = gen_combination.rear_body(
            **{f"{p}Bf": out[f"{p}G"] for p in ("m", "x", "z")},
            **{f"IBf{ax}": out[f"IG{ax}"] for ax in ("xx", "yy", "zz", "xz")},
            **{f"{p}Br": out[f"{p}S"] for p in ("m", "x", "z")},
            **{f"IBr{ax}": out[f"IS{ax}"] for ax in ("xx", "yy", "zz", "xz")},
        )
        out.update(mH=mH, xH=xH, zH=zH, IHxx=IH[..., 0, 0], IHyy=IH[..., 1, 1], IHzz=IH[..., 2, 2], IHxz=IH[..., 0, 2])
    if layout.seating:
        out.update(seating.seating_from_measured(x, rR=rR, rF=rF, w=w, lam=lam, trail=out["c"]))
    return out


_BODY_OUTPUTS = ("w", "c", "lam_ht", "g", "rR", "mR", "IRxx", "IRyy", "rF", "mF", "IFxx", "IFyy",
                 "mBf", "xBf", "zBf", "IBfxx", "IBfzz", "IBfxz", "IBfyy",
                 "mH", "xH", "zH", "IHxx", "IHzz", "IHxz", "IHyy")


def reduce_measured(values: Mapping[str, Quantity], *, source: NameValueFile | str = "<memory>",
                    name: str = "bicycle", line_tolerance: float = DEFAULT_LINE_TOLERANCE,
                    com_method: str = "least_squares") -> MeasuredReduction:
    """Reduce BicycleParameters measurements to the bodies, with first-order uncertainties.

    Parameters
    ----------
    values : mapping of str to Quantity
        The Measured file's values (a :class:`NameValueFile` gives messages line numbers).
    source : NameValueFile or str
        Where the values came from.
    name : str
        Name of the bicycle.
    line_tolerance : float
        Largest rms distance [m] of a body's hanging lines from their common point.
    com_method : {"least_squares", "pairwise_mean"}
        See :func:`evaluate_measured`.

    Raises
    ------
    InputError
        Missing or impossible measurements (named, with what they are for).
    FitError
        Hanging lines that do not meet within ``line_tolerance``.
    """
    if com_method not in ("least_squares", "pairwise_mean"):
        raise ValueError(f"com_method must be 'least_squares' or 'pairwise_mean', not {com_method!r}")
    label = source.path if isinstance(source, NameValueFile) else str(source)
    repeats = ({k: e.repeats for k, e in source.entries.items()} if isinstance(source, NameValueFile) else {})
    values = values.as_dict() if isinstance(values, NameValueFile) else dict(values)  # fast lookups
    layout = detect_layout(values, label)
    _check_values(values, layout, source, repeats)
    closed_form = reduce_standard_layout(values, layout, line_tolerance) if com_method == "least_squares" else None
    if closed_form is not None:  # the template's layout, every check passed: exact uncertainties
        result, lines = closed_form
    else:  # one batched pass over the nominal point (checked) and every perturbed point of the Jacobian
        lines = {}
        used = {k: q for k, q in values.items() if k not in _KNOWN_EXTRAS}
        result = propagate(lambda x: evaluate_measured(x, layout, com_method=com_method, check=True,
                                                       line_tolerance=line_tolerance, source=label, lines=lines),
                           used, vectorized=True)
    notes = _notes(values, layout)
    body_values = {k: result[k] for k in _BODY_OUTPUTS if math.isfinite(result[k].value)}
    if layout.seating:
        problem = seating.seating_problem({k: q.value for k, q in result.items()}, result["rR"].value)
        if problem is None:
            body_values.update({k: result[k] for k in seating.SEATING_OUTPUTS})
            notes.append(seating.NOTE)
        else:
            notes.append(f"seating measurements not usable: {problem}")
    _drop_inconsistent_yy(body_values, notes, label)
    extras = {k: q for k, q in result.items() if k not in body_values and math.isfinite(q.value)}
    bodies = BicycleBodies(body_values, source=label, name=name, notes=notes)
    return MeasuredReduction(bodies, extras, lines, layout, notes)


def _drop_inconsistent_yy(body_values: dict[str, Quantity], notes: list[str], source: str) -> None:
    """Leave out an ``I_yy`` that breaks the triangle inequality with the in-plane moments.

    ``IBfyy`` and ``IHyy`` come from a compound pendulum, the in-plane moments from the torsional
    pendulum; when they cannot belong to one body the linear model (which does not use ``I_yy``)
    is still served, and the value stays in :attr:`MeasuredReduction.extras` with a note.
    """
    for body in ("Bf", "H"):
        yy = body_values.get(f"I{body}yy")
        if yy is None:
            continue
        xx, xz, zz = (body_values[f"I{body}{axes}"].value for axes in ("xx", "xz", "zz"))
        verdict = _triangle_verdict(xx, xz, zz, yy.value)
        if verdict is None:  # close to a limit: let the full check decide
            try:
                check_inertia_tensor(f"I{body}", np.array([[xx, 0.0, xz], [0.0, yy.value, 0.0], [xz, 0.0, zz]]), source)
                consistent = True
            except InputError:
                consistent = False
        else:
            consistent = verdict > 0
        if not consistent:
            del body_values[f"I{body}yy"]
            principal = ", ".join(f"{p:.4g}" for p in plane_symmetric_principal_moments(xx, yy.value, zz, xz))
            message = (f"I{body}yy = {yy} (compound pendulum) left out: with the torsional-pendulum "
                       f"I{body}xx, I{body}xz, I{body}zz its principal moments {principal} break the triangle "
                       "inequality (the linear model does not use it)")
            LOG.info("%s: %s", source, message)
            notes.append(message)


#: Relative margin beyond which :func:`_triangle_verdict` decides without the full tensor check.
_CLEAR_MARGIN = 1e-6


def _triangle_verdict(xx: float, xz: float, zz: float, yy: float) -> float | None:
    """Whether a tensor with in-plane moments ``xx, xz, zz`` and ``yy`` clearly passes (+1) or
    clearly fails (-1) :func:`~bikerider.inertia.check_inertia_tensor`; ``None`` when it is within
    :data:`_CLEAR_MARGIN` of a limit (then the full check decides).

    ``y`` is a principal axis, so the principal moments are ``yy`` and those of the xz block
    (:func:`~bikerider.inertia.plane_symmetric_principal_moments`).  Deciding the clear cases in
    closed form spares the eigenvalue solver and the raised error on every reduction.
    """
    if not (xx > 0 and zz > 0 and yy > 0 and xx * zz - xz * xz > _CLEAR_MARGIN * xx * zz):
        return None
    low, mid, high = plane_symmetric_principal_moments(xx, yy, zz, xz)
    margin = (low + mid - high) / (low + mid + high)
    if abs(margin) <= _CLEAR_MARGIN:
        return None
    return math.copysign(1.0, margin)


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
    present = [k for k in seating.MEASURED_NAMES if k in values]
    if present and not layout.seating:
        missing = [k for k in seating.MEASURED_NAMES if k not in values]
        notes.append("seating measurements incomplete (missing " + ", ".join(missing) + "): the rider cannot be seated")
    extras = sorted(k for k in values if k in _KNOWN_EXTRAS)
    if extras:
        notes.append("not used by the benchmark bodies: " + ", ".join(extras))
    return notes


def read_measured_file(path: str | Path, *, line_tolerance: float = DEFAULT_LINE_TOLERANCE,
                       com_method: str = "least_squares") -> MeasuredReduction:
    """Read and reduce a ``<Name>Measured.txt`` file (see :func:`reduce_measured`).

    The bicycle is named after the file (``BrowserMeasured.txt`` gives ``Browser``).
    """
    data = read_name_value_file(path)
    stem = Path(path).stem
    name = stem[: -len("Measured")] if stem.endswith("Measured") and len(stem) > len("Measured") else stem
    return reduce_measured(data, source=data, name=name, line_tolerance=line_tolerance, com_method=com_method)


def load_measured_bicycle(path: str | Path) -> BicycleBodies:
    """The :class:`BicycleBodies` of a ``<Name>Measured.txt`` file."""
    return read_measured_file(path).bodies


__all__ = [
    "BODIES", "FIELD_PURPOSES", "PERIOD_TRIAL_TOLERANCE", "MeasuredLayout", "MeasuredReduction",
    "detect_layout", "evaluate_measured", "load_measured_bicycle", "read_measured_file", "reduce_measured",
]
