"""An independent NumPy re-implementation of the Measured-file reduction: the tests' oracle.

``bikerider.bicycle.raw_measurements`` reduces a BicycleParameters Measured file through generated
stages (``derive/measured_reduction.py``) and exact Jacobians.  This module does the same chain
written by hand with NumPy, on arrays of points, and propagates uncertainties by central
differences (:func:`propagate`), as the project's reduction did before the stages; it uses no
generated code, so agreement between the two checks both.  Values agree to rounding; uncertainties
to the central differences' truncation and round-off error (relative step 1e-6: about 1e-8 of a
sigma, held to 1e-6).

Line convention.  In the bicycle's XZ plane a line is ``n . p = d`` with the unit normal
``n = (sin(beta), cos(beta))`` and ``beta = lam - alpha`` the pendulum axis angle.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping

import numpy as np

from bikerider.bicycle.pendulum import (
    DEFAULT_LINE_TOLERANCE,
    PARALLEL_CONDITIONING,
    SINGULAR_DETERMINANT,
    LineIntersection,
    check_lines_meet,
)
from bikerider.bicycle.raw_measurements import BODIES, MeasuredLayout
from bikerider.errors import FitError, InputError
from bikerider.quantity import Quantity

RELATIVE_STEP = 1e-6
"""Step of the central difference, relative to ``max(|x|, sigma)`` of each input."""
KNOWN_EXTRAS = {"xcl", "zcl", "ds1", "ds3"}
_HEIGHTS = ("h1", "h2", "h3", "h4", "h5", "d1", "d2", "d3", "d4", "d")
_HANDLEBAR_REFERENCE = ("h6", "h7", "d5", "d6", "l")


# ---------------------------------------------------------------------------------------------
# Central differences
# ---------------------------------------------------------------------------------------------
def perturbed_points(inputs: Mapping[str, Quantity]):
    """Nominal values (column 0) and each uncertain input stepped up and down; the indices of the
    uncertain inputs, their steps and their sigmas."""
    quantities = inputs.values()
    nominal = np.array([q.value for q in quantities], dtype=float)
    sigma = np.array([q.sigma for q in quantities], dtype=float)
    varied = np.flatnonzero(sigma > 0)
    sigma = sigma[varied]
    steps = RELATIVE_STEP * np.maximum(np.abs(nominal[varied]), sigma)
    k = len(varied)
    points = np.repeat(nominal[:, None], 2 * k + 1, axis=1)
    columns = np.arange(k)
    points[varied, 2 * columns + 1] += steps
    points[varied, 2 * columns + 2] -= steps
    return points, varied, steps, sigma


def propagate(
    function: Callable[[dict], dict], inputs: Mapping[str, Quantity], *, vectorized: bool = False
) -> dict[str, Quantity]:
    """``function``'s outputs with first-order sigmas from central differences (inputs independent;
    a slope that is not finite contributes nothing; an output NaN at the nominal point keeps sigma 0).
    ``vectorized``: every point in one call, each input a 1-D array of the points."""
    names = list(inputs)
    points, _, steps, sigma = perturbed_points(inputs)
    n_points = points.shape[1]
    if vectorized:
        outputs = function(dict(zip(names, points)))
        keys = list(outputs)
        table = np.empty((len(keys), n_points))
        for row, key in zip(table, keys):
            row[...] = outputs[key]
    else:
        evaluations = [function(dict(zip(names, column))) for column in points.T.tolist()]
        keys = list(evaluations[0])
        table = np.array([[float(e[key]) for key in keys] for e in evaluations]).T.reshape(len(keys), n_points)
    centre = table[:, 0].tolist()
    with np.errstate(over="ignore", invalid="ignore"):
        slopes = (table[:, 1::2] - table[:, 2::2]) / (2 * steps)
        terms = slopes * sigma
        sigmas = np.sqrt(np.where(np.isfinite(slopes), terms * terms, 0.0).sum(axis=1)).tolist()
    return {key: Quantity(value, s if math.isfinite(value) else 0.0) for key, value, s in zip(keys, centre, sigmas)}


# ---------------------------------------------------------------------------------------------
# Geometry, pendulums, lines (floats or arrays of points)
# ---------------------------------------------------------------------------------------------
def sqrt_or_nan(square):
    return np.sqrt(np.where(square >= 0, square, np.nan))


def torsional(k, T):
    """Eq. 1."""
    return k * T**2 / (4 * math.pi**2)


def compound(T, m, g, length):
    """Eq. 7."""
    return (T / (2 * math.pi)) ** 2 * m * g * length - m * length**2


def orientation_rows(beta):
    """Rows of Eq. 6 in the benchmark convention: ``J = cos^2 Ixx - 2 sin cos Ixz + sin^2 Izz``."""
    s, c = np.sin(beta), np.cos(beta)
    return np.stack([c * c, -2 * s * c, s * s], axis=-1)


def least_squares_point(sin, cos, distances, axis=-1):
    """Least-squares meeting points of batches of lines (normal equations, Cramer's rule), and the
    smallest over largest singular value of the normals."""
    ss, cc = (sin * sin).sum(axis=axis), (cos * cos).sum(axis=axis)
    sc, sd, cd = (sin * cos).sum(axis=axis), (sin * distances).sum(axis=axis), (cos * distances).sum(axis=axis)
    det = ss * cc - sc * sc
    trace = ss + cc
    with np.errstate(divide="ignore", invalid="ignore"):
        root = np.sqrt(np.maximum(trace * trace - 4 * det, 0.0))
        return (
            (cc * sd - sc * cd) / det,
            (ss * cd - sc * sd) / det,
            np.sqrt(np.maximum(trace - root, 0.0) / (trace + root)),
        )


def pairwise_mean_point(sin, cos, distances, axis=-1):
    """The mean of the intersections of every pair of lines."""
    first, second = (list(i) for i in zip(*itertools.combinations(range(distances.shape[axis]), 2)))
    s1, c1, d1 = (np.take(a, first, axis=axis) for a in (sin, cos, distances))
    s2, c2, d2 = (np.take(a, second, axis=axis) for a in (sin, cos, distances))
    with np.errstate(divide="ignore", invalid="ignore"):
        det = s1 * c2 - s2 * c1
        return ((d1 * c2 - d2 * c1) / det).mean(axis=axis), ((s1 * d2 - s2 * d1) / det).mean(axis=axis)


def grip_position(w, rF, rR, whb, LhbF, LhbR):
    """``(x, z)`` of a handlebar grip from its distances to the wheel centres (NaN if none)."""
    half = 0.5 * whb
    front = sqrt_or_nan(np.where(LhbF > half, LhbF**2 - half**2, np.nan))
    rear = sqrt_or_nan(np.where(LhbR > half, LhbR**2 - half**2, np.nan))
    ex, ez = w, rR - rF
    span = np.hypot(ex, ez)
    along = (rear**2 - front**2 + span**2) / (2 * span)
    height = sqrt_or_nan(rear**2 - along**2)
    ex, ez = ex / span, ez / span
    return along * ex + height * ez, -rR + along * ez - height * ex


def _combine(m1, x1, z1, I1, m2, x2, z2, I2):
    """Two plane-symmetric bodies as one (Eqs. 15-16 and the parallel axis theorem); ``I`` are
    ``(xx, yy, zz, xz)``."""
    m = m1 + m2
    x, z = (m1 * x1 + m2 * x2) / m, (m1 * z1 + m2 * z2) / m
    out = []
    for k, (a, b) in enumerate(zip(I1, I2)):
        dx1, dz1, dx2, dz2 = x1 - x, z1 - z, x2 - x, z2 - z
        shift = [dz1**2, dx1**2 + dz1**2, dx1**2, -dx1 * dz1][k] * m1 + [dz2**2, dx2**2 + dz2**2, dx2**2, -dx2 * dz2][
            k
        ] * m2
        out.append(a + b + shift)
    return m, x, z, out


# ---------------------------------------------------------------------------------------------
# The reduction on arrays of points
# ---------------------------------------------------------------------------------------------
def _first(value) -> float:
    return float(value[0]) if np.ndim(value) else float(value)


def _check_compound(name, inertia, period, length, g, source):
    if not inertia[0] > 0:
        shortest = 2 * math.pi * math.sqrt(length / g[0])
        raise InputError(
            name,
            float(period[0]),
            f"a compound pendulum period above {shortest:.4f} s, that of a point mass {length:.4f} m "
            "from the pivot (a shorter one gives a negative moment of inertia)",
            source,
        )


def evaluate_measured(
    x: Mapping[str, object],
    layout: MeasuredLayout,
    *,
    com_method: str = "least_squares",
    check: bool = False,
    line_tolerance: float = DEFAULT_LINE_TOLERANCE,
    source: str = "<memory>",
    lines: dict | None = None,
) -> dict:
    """The whole reduction, without uncertainty, at one point (floats) or a batch (1-D arrays of
    equal length, nominal point first): the reduction's outputs by name, NaN where not determined.
    With ``check``, the reduction's errors at the first point."""
    batch = np.ndim(next(iter(x.values()))) > 0
    points = x if batch else {k: np.array([v], dtype=float) for k, v in x.items()}
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        out = _evaluate(points, layout, com_method, check, line_tolerance, source, lines)
    return out if batch else {k: float(v[0]) for k, v in out.items()}


def _evaluate(x, layout, com_method, check, line_tolerance, source, lines) -> dict:
    rF = x["dF"] / (2 * math.pi * x["nF"])
    rR = x["dR"] / (2 * math.pi * x["nR"])
    if layout.geometry == "wheelbase":
        lam = np.radians(90.0 - x["gamma"])
        w, fork_offset = x["w"], x["f"]
    else:
        h1, h2, h3, h4, h5, d1, d2, d3, d4, d = (x[k] for k in _HEIGHTS)
        a = h1 + h2 - h3 + 0.5 * d1 - 0.5 * d2
        b = h4 - 0.5 * d3 - h5 + 0.5 * d4
        e = sqrt_or_nan((d + 0.5 * (d2 + d3)) ** 2 - (a - b) ** 2)
        ratio = (rF - rR) / np.hypot(a + b, e)
        lam = np.arctan2(e, a + b) + np.arcsin(np.where(np.abs(ratio) <= 1, ratio, np.nan))
        if check and not math.isfinite(lam[0]):
            raise InputError(
                "d",
                _first(x["d"]),
                "heights and diameters that close into a frame: "
                f"offsets a = {_first(a):.4f} m, b = {_first(b):.4f} m give no steer axis tilt",
                source,
            )
        w, fork_offset = (a + b) * np.cos(lam) + e * np.sin(lam), b
    if check and not 0 < lam[0] < math.pi / 2:
        raise InputError(
            "gamma" if layout.geometry == "wheelbase" else "h1",
            math.degrees(math.pi / 2 - lam[0]),
            "a head tube angle between 0 and 90 degrees",
            source,
        )
    out = {
        "w": w,
        "c": (rF * np.sin(lam) - fork_offset) / np.cos(lam),
        "lam_ht": np.pi / 2 - lam,
        "g": x["g"],
        "rR": rR,
        "rF": rF,
        "lam": lam,
        "f": fork_offset,
    }
    k_t = 4 * math.pi**2 * (x["mP"] * (3 * (0.5 * x["dP"]) ** 2 + x["lP"] ** 2) / 12) / x["TtP1"] ** 2
    out["k_t"] = k_t
    for wheel in ("R", "F"):
        yy = compound(x[f"Tc{wheel}1"], x[f"m{wheel}"], x["g"], x[f"l{wheel}"])
        if check:
            _check_compound(f"Tc{wheel}1", yy, x[f"Tc{wheel}1"], float(x[f"l{wheel}"][0]), x["g"], source)
        out.update({f"m{wheel}": x[f"m{wheel}"], f"I{wheel}xx": torsional(k_t, x[f"Tt{wheel}1"]), f"I{wheel}yy": yy})
    references = {"B": (np.zeros_like(rR), -rR), "H": (w, -rF), "S": (w, -rF)}
    if layout.split_fork:
        h6, h7, d5, d6, length = (x[k] for k in _HANDLEBAR_REFERENCE)
        l1 = (h7 - 0.5 * d6) - (h6 - 0.5 * d5)
        l2 = sqrt_or_nan((length - 0.5 * (d5 + d6)) ** 2 - l1**2)
        if check and not math.isfinite(l2[0]):
            raise InputError(
                "l",
                _first(x["l"]),
                f"an axle-to-reference-circle distance longer than the height difference l1 = {_first(l1):.4f} m",
                source,
            )
        references["G"] = (w - l2 * np.sin(lam) + l1 * np.cos(lam), -rF - l2 * np.cos(lam) - l1 * np.sin(lam))
    for body, indices in layout.orientations.items():
        name = "Bf" if body == "B" else body
        betas = lam - np.radians(np.array([x[f"alpha{body}{i}"] for i in indices]))  # (m, points)
        sin, cos = np.sin(betas), np.cos(betas)
        ref_x, ref_z = references[body]
        offsets = sin * ref_x + cos * ref_z - np.array([x[f"a{body}{i}"] for i in indices])
        ls_x, ls_z, conditioning = least_squares_point(sin, cos, offsets, axis=0)
        px, pz = (ls_x, ls_z) if com_method == "least_squares" else pairwise_mean_point(sin, cos, offsets, axis=0)
        rows = np.moveaxis(orientation_rows(betas), 0, 1)  # (points, m, 3)
        moments = torsional(k_t, np.array([x[f"Tt{body}{i}"] for i in indices])).T[..., None]  # (points, m, 1)
        inertia = (np.linalg.pinv(rows) @ moments)[..., 0]
        miss = sin[:, 0] * ls_x[0] + cos[:, 0] * ls_z[0] - offsets[:, 0]
        fit = LineIntersection(
            np.array([ls_x[0], ls_z[0]]), miss, math.sqrt(math.fsum(d * d for d in miss) / len(miss))
        )
        if lines is not None:
            lines[body] = fit
        if check:
            if not np.all(conditioning >= PARALLEL_CONDITIONING):
                raise FitError("the hanging lines are parallel: the orientations do not locate the centre of mass")
            check_lines_meet(f"the {BODIES[body]} ({body})", fit, line_tolerance, source)
            if not (math.isfinite(px[0]) and math.isfinite(pz[0])):
                raise FitError(
                    f"{source}: the hanging lines are parallel: two lines of the {BODIES[body]} ({body}) "
                    "meet nowhere, so the mean of their pairwise intersections is not defined"
                )
            singular = (
                abs(np.linalg.det(rows[0])) if len(indices) == 3 else np.linalg.svd(rows[0], compute_uv=False)[-1]
            )
            if singular < SINGULAR_DETERMINANT:
                raise InputError(f"alpha{body}", "coinciding pendulum axes", "Eq. 6 is singular", source)
        out.update(
            {
                f"m{name}": x[f"m{body}"],
                f"x{name}": px,
                f"z{name}": pz,
                f"I{name}xx": inertia[:, 0],
                f"I{name}xz": inertia[:, 1],
                f"I{name}zz": inertia[:, 2],
                f"I{name}yy": np.full_like(lam, np.nan),
            }
        )
        if layout.compound[body]:
            length = np.hypot(px - ref_x, pz - ref_z)
            yy = compound(x[f"Tc{body}1"], x[f"m{body}"], x["g"], length)
            if check:
                _check_compound(f"Tc{body}1", yy, x[f"Tc{body}1"], float(length[0]), x["g"], source)
            out[f"I{name}yy"] = yy
    if layout.split_fork:
        inertia = lambda b: tuple(out[f"I{b}{a}"] for a in ("xx", "yy", "zz", "xz"))  # noqa: E731
        m, xh, zh, IH = _combine(
            out["mG"], out["xG"], out["zG"], inertia("G"), out["mS"], out["xS"], out["zS"], inertia("S")
        )
        out.update(mH=m, xH=xh, zH=zh, IHxx=IH[0], IHyy=IH[1], IHzz=IH[2], IHxz=IH[3])
    if layout.seating:
        x_hand, z_hand = grip_position(w, rF, rR, x["whb"], x["LhbF"], x["LhbR"])
        z10 = -x["hbb"] - x["lst"] * np.sin(x["lamst"])
        x12 = w + out["c"] + z10 * np.tan(lam)
        lam_ht = np.pi / 2 - lam
        l_s = (z10 - z_hand) / np.sin(lam_ht)
        out.update(
            {
                "h_bb": x["hbb"],
                "l_cs": x["lcs"],
                "l_sp": x["lsp"],
                "l_st": x["lst"],
                "lam_st": x["lamst"],
                "l_s": l_s,
                "l_hb": x12 - l_s * np.cos(lam_ht) - x_hand,
                "l_f": np.hypot(x12 - w, z10 + rF),
                "x_hand": x_hand,
                "z_hand": z_hand,
            }
        )
    return out


def reduce(
    values: Mapping[str, Quantity], layout: MeasuredLayout, com_method: str = "least_squares", vectorized: bool = True
) -> dict[str, Quantity]:
    """The oracle's reduction with central-difference sigmas: every output that is finite."""
    used = {k: q for k, q in values.items() if k not in KNOWN_EXTRAS}
    result = propagate(
        lambda x: evaluate_measured(x, layout, com_method=com_method, check=True), used, vectorized=vectorized
    )
    return {k: q for k, q in result.items() if math.isfinite(q.value)}
