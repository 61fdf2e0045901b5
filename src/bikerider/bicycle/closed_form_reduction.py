"""The standard layout of a Measured file reduced in closed form, with exact first-order uncertainties.

Most BicycleParameters Measured files follow its template: geometry from wheelbase, head tube
angle and fork offset; the rear frame and the handlebar/fork each hung in three orientations; all
four compound-pendulum periods.  For those, the whole reduction and every output's first-order
standard uncertainty come from one generated plain-float function
(:func:`bikerider.generated.measured_reduction.standard_layout_scalar`, derived in
``derive/measured_reduction.py`` with exact derivatives), instead of the batched numerical
Jacobian of :func:`bikerider.bicycle.raw_measurements.evaluate_measured`.  The two give the same
values (to rounding) and the same uncertainties (to the central-difference truncation error of the
numerical route, about 1e-9 relative); ``tests/test_closed_form_reduction.py`` holds them to that.

The closed form never decides anything the general reduction would decide differently: it is used
only when every check the general reduction makes passes at the nominal point (head tube angle,
positive compound-pendulum inertias, lines that are not parallel and meet within the tolerance,
orientations that determine Eq. 6, finite results).  Anything else -- another layout, a failed
check, a seating measurement that cannot be met, a math domain error -- returns ``None`` and the
general reduction takes over, raising its error or writing its note.
"""
from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from bikerider.bicycle.hanging_lines import PARALLEL_CONDITIONING, LineIntersection
from bikerider.bicycle.pendulum import SINGULAR_DETERMINANT
from bikerider.generated import measured_reduction as gen
from bikerider.quantity import Quantity

_FILE_NAMES = {"mBf": "mB", "lam_ht": "gamma", "l_cs": "lcs", "h_bb": "hbb", "l_sp": "lsp", "l_st": "lst",
               "lam_st": "lamst"}
"""Argument names of the generated function that differ from the file's field names."""
_DEGREES = frozenset(name for name in gen.ARGS if name == "lam_ht" or name.startswith("alpha"))
"""Arguments the file gives in degrees (converted to radians here, once)."""
_ARGUMENT_FIELDS = tuple((_FILE_NAMES.get(name, name), math.pi / 180 if name in _DEGREES else 1.0)
                         for name in gen.ARGS)
"""Each argument's field in the file and the factor to SI."""
_SEATING_VALUES = ("l_s", "l_hb", "l_f", "x_hand", "z_hand")
_VALUE_INDEX = {name: i for i, name in enumerate(gen.VALUE_NAMES)}
_CHECK_INDEX = {name: i for i, name in enumerate(gen.CHECK_NAMES)}


def is_standard_layout(layout) -> bool:
    """Whether a :class:`~bikerider.bicycle.raw_measurements.MeasuredLayout` is the one the closed
    form covers."""
    return (layout.geometry == "wheelbase" and not layout.split_fork
            and layout.orientations == {"B": (1, 2, 3), "H": (1, 2, 3)}
            and layout.compound == {"B": True, "H": True})


def _conditioning(lines_det: float) -> float:
    """Smallest over largest singular value of three unit line normals from the determinant of
    their normal equations: :func:`~bikerider.bicycle.hanging_lines.least_squares_point`'s formula
    with the trace, 3, known, on one float."""
    root = math.sqrt(max(9.0 - 4.0 * lines_det, 0.0))
    return math.sqrt(max(3.0 - root, 0.0) / (3.0 + root))


def reduce_standard_layout(values: Mapping[str, Quantity], layout,
                           line_tolerance: float) -> tuple[dict[str, Quantity], dict[str, LineIntersection]] | None:
    """Reduce a standard-layout Measured file in closed form.

    Parameters
    ----------
    values : mapping of str to Quantity
        The file's values (BicycleParameters units: degrees for ``gamma`` and ``alpha*``).
    layout : MeasuredLayout
    line_tolerance : float
        Largest rms distance [m] of a body's hanging lines from their common point.

    Returns
    -------
    (result, lines) or None
        ``result`` has the keys, in the order, of the general reduction's outputs, each with its
        first-order uncertainty; ``lines`` each body's line fit.  ``None`` when the layout is not
        the standard one or a check of the general reduction would not pass (that reduction then
        runs and reports).
    """
    if not is_standard_layout(layout):
        return None
    arguments, sigmas = [], []
    for field, factor in _ARGUMENT_FIELDS:
        q = values.get(field)
        if q is None:  # only seating measurements may be missing (layout.seating is False)
            arguments.append(math.nan)
            sigmas.append(0.0)
        else:
            arguments.append(q.value * factor)
            sigmas.append(q.sigma * factor)
    try:
        computed, uncertainties, checks = gen.standard_layout_scalar(*arguments, *sigmas)
    except (ValueError, ZeroDivisionError, OverflowError):
        return None
    lines = _lines(computed, checks)
    if not _checks_pass(computed, uncertainties, checks, lines, layout.seating, line_tolerance):
        return None
    return _result(values, computed, uncertainties, layout.seating), lines


def _checks_pass(computed, uncertainties, checks, lines: dict[str, LineIntersection], seating: bool,
                 line_tolerance: float) -> bool:
    """Every check :func:`~bikerider.bicycle.raw_measurements.evaluate_measured` makes, at the nominal point."""
    n = len(gen.VALUE_NAMES) - (0 if seating else len(_SEATING_VALUES))
    if not math.isfinite(sum(computed[:n]) + sum(uncertainties[:n]) + sum(checks)):
        return False  # a NaN or an infinity among them (or finite values whose sum overflows: harmless)
    if not 0 < computed[_VALUE_INDEX["lam"]] < math.pi / 2:
        return False
    if not all(computed[_VALUE_INDEX[name]] > 0 for name in ("IRyy", "IFyy", "IBfyy", "IHyy")):
        return False
    for body in ("B", "H"):
        if _conditioning(checks[_CHECK_INDEX[f"lines_det_{body}"]]) < PARALLEL_CONDITIONING:
            return False
        if abs(checks[_CHECK_INDEX[f"eq6_det_{body}"]]) < SINGULAR_DETERMINANT:
            return False
        if lines[body].rms > line_tolerance:
            return False
    return True


def _result(values: Mapping[str, Quantity], computed, uncertainties, seating: bool) -> dict[str, Quantity]:
    """The outputs in the order of the general reduction's, computed ones from the closed form and
    pass-through ones from the file."""
    def out(name: str) -> Quantity:
        i = _VALUE_INDEX[name]
        return Quantity(computed[i], uncertainties[i])

    gamma = values["gamma"]
    result = {
        "w": values["w"], "c": out("c"), "lam_ht": Quantity(math.radians(gamma.value), math.radians(gamma.sigma)),
        "g": values["g"], "rR": out("rR"), "rF": out("rF"), "lam": out("lam"), "f": values["f"], "k_t": out("k_t"),
    }
    for wheel in ("R", "F"):
        result.update({f"m{wheel}": values[f"m{wheel}"], f"I{wheel}xx": out(f"I{wheel}xx"),
                       f"I{wheel}yy": out(f"I{wheel}yy")})
    for body, name in (("B", "Bf"), ("H", "H")):
        result[f"m{name}"] = values[f"m{body}"]
        for entry in ("x", "z"):
            result[f"{entry}{name}"] = out(f"{entry}{name}")
        for axes in ("xx", "xz", "zz", "yy"):
            result[f"I{name}{axes}"] = out(f"I{name}{axes}")
    if seating:
        for name in ("h_bb", "l_cs", "l_sp", "l_st", "lam_st"):
            result[name] = values[_FILE_NAMES[name]]
        result.update({name: out(name) for name in _SEATING_VALUES})
    return result


def _lines(computed, checks) -> dict[str, LineIntersection]:
    """Each body's centre of mass and its signed distances from the body's three hanging lines."""
    lines = {}
    for body, name in (("B", "Bf"), ("H", "H")):
        misses = np.array([checks[_CHECK_INDEX[f"miss{body}{i}"]] for i in (1, 2, 3)])
        point = np.array([computed[_VALUE_INDEX[f"x{name}"]], computed[_VALUE_INDEX[f"z{name}"]]])
        lines[body] = LineIntersection(point, misses, math.sqrt(math.fsum(d * d for d in misses.tolist()) / 3))
    return lines


__all__ = ["is_standard_layout", "reduce_standard_layout"]
