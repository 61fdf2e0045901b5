"""Which designs a bicycle can have, for whole batches at once, and why the others cannot.

:meth:`bikerider.benchmark.BenchmarkParameters.validate` checks one parameter set and raises on
the first problem; a design space needs the same verdict for millions of designs without a Python
call per design.  :func:`benchmark_reasons` applies the same rules (the one table of
:mod:`bikerider.benchmark.rules`, the tensor check of :mod:`bikerider.inertia`), in the same order, to arrays
and returns for each design the code of the first check it fails (0: valid); :data:`REASONS` turns
a code into the ``(name, expected)`` pair that ``validate`` would have raised (the tests hold the
two equal on random designs).  :func:`rider_reasons` adds the checks of seating a rider (limbs that
reach the pedals and grips) for designs over raw measurements.
"""

from __future__ import annotations

import math

import numpy as np

from bikerider.benchmark import rules
from bikerider.benchmark.parameters import BENCHMARK_NAMES, OPTIONAL_NAMES
from bikerider.design.space import measurement_names
from bikerider.inertia import TENSOR_RULES, TRIANGLE_TOLERANCE, broken_rules

REASONS: list[tuple[str, str]] = [("", "")]
"""``(name, expected)`` of each reason code; code 0 is a valid design."""
_CODES: dict[tuple[str, str], int] = {}


def _register(name: str, expected: str) -> int:
    key = (name, expected)
    if key not in _CODES:
        _CODES[key] = len(REASONS)
        REASONS.append(key)
    return _CODES[key]


def _code(name: str, expected: str) -> int:
    """The code of a reason registered at import (codes are stored: they must not depend on the
    order in which a process meets them)."""
    return _CODES[(name, expected)]


_LEGS_CLOSE = "at most the hip to pedal-axis distance apart (the knee cannot close otherwise)"
_ARMS_CLOSE = "at most the shoulder to grip distance apart (the elbow cannot close otherwise)"
for _name in BENCHMARK_NAMES:
    _register(_name, "a finite number")
for _name in rules.POSITIVE:
    _register(_name, "a positive value")
for _name, (_limit, _unit) in rules.LIMITS.items():
    _register(_name, rules.limit_expected(_limit, _unit))
for _name, (_smallest, _unit) in rules.SMALLEST.items():
    _register(_name, rules.smallest_expected(_smallest, _unit))
for _name in rules.DIVISORS:
    _register(_name, rules.DIVISOR_EXPECTED)
_register("lam", rules.TILT_EXPECTED)
for _name in rules.BELOW_GROUND:
    _register(_name, rules.BELOW_GROUND_EXPECTED)
for _body in rules.BODIES:
    for _rule in TENSOR_RULES:
        _register(rules.tensor_name(_body), _rule)
for _wheel in rules.WHEELS:
    _register(f"I{_wheel}yy", rules.wheel_expected(_wheel))
    for _axis in ("yy", "xx"):
        _register(f"I{_wheel}{_axis}", rules.wheel_extent_expected(_wheel, _axis))
SINGULAR = _register("M", rules.SINGULAR_MASS_EXPECTED)
NOT_COMPUTED = _register(
    "benchmark parameters", "finite values from the estimate chain (the measured geometry does not close)"
)
_SIGNED = frozenset({"c", "xH", "zH", "xBf", "zBf", "IHxz", "IBfxz", "IHyy", "IBfyy"})
"""Measurements of the estimate chain that may be zero or negative (trail, coordinates, products of
inertia; the I_yy that may be left undetermined)."""
_ANGLES = frozenset({"lam_ht", "lam_st", "lam_fl"})
_FRACTIONS = frozenset({"f_h", "f_la", "f_ll", "f_to", "f_ua", "f_ul"})


def _measurement_check(name: str) -> str:
    if name in _ANGLES:
        return "an angle between 0 and 180 degrees"
    if name in _FRACTIONS:
        return "a mass fraction between 0 and 1"
    return "a positive value"


for _name in measurement_names():
    if _name not in _SIGNED:
        _register(_name, _measurement_check(_name))
CHAIN_STAY = _register("l_cs", "more than |rR - h_bb| (chain stay must reach the bottom bracket)")
FORK = _register("l_f", "more than the fork offset |f_o|")
LEGS_SHORT = _register("l_ll + l_ul", "at least the distance from the hip (top of the seat) to the pedal axis")
LEGS_CLOSE = _register("|l_ll - l_ul|", _LEGS_CLOSE)
ARMS_SHORT = _register("l_ua + l_la", "at least the distance from the shoulder to the handlebar grip")
ARMS_CLOSE = _register("|l_ua - l_la|", _ARMS_CLOSE)


def _assign(codes: np.ndarray, failed: np.ndarray, code: int) -> None:
    """Give ``code`` to the designs that fail now and passed every earlier check (a check of values
    that do not vary costs one comparison, not one per design)."""
    failed = np.asarray(failed)
    if failed.ndim == 0:
        if failed:
            codes[codes == 0] = code
        return
    np.copyto(codes, code, where=failed & (codes == 0))


def benchmark_reasons(values: dict[str, np.ndarray], sigmas: dict[str, float] | None = None) -> np.ndarray:
    """Reason codes (0: valid) of designs given as benchmark values, by the rules and in the order of
    :meth:`BenchmarkParameters.validate`.

    Parameters
    ----------
    values : dict
        Every benchmark name to an array (or scalar) broadcasting to the batch; ``IByy``/``IHyy``
        may be NaN (not determined: only the xz block of that tensor is checked).
    sigmas : dict, optional
        Standard uncertainties of the wheels' masses, radii and inertias that were not varied (a
        wheel may break rules 9 and 10 within their combined uncertainty, as ``validate`` allows).

    Returns
    -------
    numpy.ndarray of int16
        One code per design; ``REASONS[code]`` is ``(name, expected)``.
    """
    sigmas = sigmas or {}
    v = {k: np.asarray(x, dtype=float) for k, x in values.items()}
    shape = np.broadcast_shapes(*(x.shape for x in v.values()))
    codes = np.zeros(shape, dtype=np.int16)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for name, x in v.items():
            if name not in OPTIONAL_NAMES:
                _assign(codes, ~np.isfinite(x), _code(name, "a finite number"))
        for name in rules.POSITIVE:
            _assign(codes, v[name] <= 0, _code(name, "a positive value"))
        for name, (limit, unit) in rules.LIMITS.items():
            _assign(codes, np.abs(v[name]) > limit, _code(name, rules.limit_expected(limit, unit)))
        for name, (smallest, unit) in rules.SMALLEST.items():
            _assign(codes, v[name] < smallest, _code(name, rules.smallest_expected(smallest, unit)))
        for name in rules.DIVISORS:
            _assign(codes, v[name] < rules.MIN_DIVISOR, _code(name, rules.DIVISOR_EXPECTED))
        lam = v["lam"]
        _assign(codes, ~((-math.pi / 2 < lam) & (lam < math.pi / 2)), _code("lam", rules.TILT_EXPECTED))
        for name in rules.BELOW_GROUND:
            _assign(codes, ~(v[name] < 0), _code(name, rules.BELOW_GROUND_EXPECTED))
        for body in rules.BODIES:
            broken = broken_rules(*(v[k] for k in rules.tensor_entries(body)))
            for number, rule in enumerate(TENSOR_RULES, start=1):
                _assign(codes, broken == number, _code(rules.tensor_name(body), rule))
        for wheel in rules.WHEELS:
            xx, yy = v[f"I{wheel}xx"], v[f"I{wheel}yy"]
            excess = yy - 2 * xx
            allowed = math.hypot(sigmas.get(f"I{wheel}yy", 0.0), 2 * sigmas.get(f"I{wheel}xx", 0.0))
            _assign(
                codes,
                (excess > TRIANGLE_TOLERANCE * yy) & (excess > allowed),
                _code(f"I{wheel}yy", rules.wheel_expected(wheel)),
            )
            m, r = v[f"m{wheel}"], v[f"r{wheel}"]
            mr2 = m * r**2
            mr2_sigma = np.hypot(r**2 * sigmas.get(f"m{wheel}", 0.0), 2 * m * r * sigmas.get(f"r{wheel}", 0.0))
            for axis, moment in (("yy", yy), ("xx", xx)):
                excess = moment - mr2
                allowed = np.hypot(sigmas.get(f"I{wheel}{axis}", 0.0), mr2_sigma)
                _assign(
                    codes,
                    (excess > TRIANGLE_TOLERANCE * moment) & (excess > allowed),
                    _code(f"I{wheel}{axis}", rules.wheel_extent_expected(wheel, axis)),
                )
    return codes


def mass_matrix_reasons(codes: np.ndarray, mass_ok: np.ndarray) -> None:
    """Mark designs whose mass matrix is not positive definite (``WhippleModel``'s check)."""
    _assign(codes, ~mass_ok, SINGULAR)


def measurement_reasons(codes: np.ndarray, values: dict[str, np.ndarray]) -> None:
    """The readers' checks of single measurements (positive lengths, masses and inertias; angles in
    (0, 180) degrees; mass fractions in (0, 1)) on the varied measurements."""
    with np.errstate(invalid="ignore"):
        for name, x in values.items():
            if name in _SIGNED:
                continue
            if name in _ANGLES:
                bad = ~((x > 0) & (x < math.pi))
            elif name in _FRACTIONS:
                bad = ~((x > 0) & (x < 1))
            else:
                bad = ~(x > 0)
            _assign(codes, bad, _code(name, _measurement_check(name)))


def rider_reasons(codes: np.ndarray, reach: np.ndarray, values: dict[str, np.ndarray], tolerance: float) -> None:
    """The seating checks of ``bikerider.rider.model.seat_rider``, in its order, from the generated
    ``limb_reach`` (``[leg span, leg length, arm span, arm length]``) and the limb lengths."""
    leg_span, leg_length, arm_span, arm_length = (reach[..., k] for k in range(4))
    v = values
    with np.errstate(invalid="ignore"):
        _assign(codes, v["l_cs"] <= np.abs(v["rR"] - v["h_bb"]), CHAIN_STAY)
        fork_offset = v["rF"] * np.cos(v["lam_ht"]) - v["c"] * np.sin(v["lam_ht"])
        _assign(codes, v["l_f"] <= np.abs(fork_offset), FORK)
        _assign(codes, ~(np.isfinite(leg_span) & np.isfinite(arm_span)), NOT_COMPUTED)
        _assign(codes, leg_span > leg_length * (1 + tolerance), LEGS_SHORT)
        _assign(codes, leg_span <= np.abs(v["l_ll"] - v["l_ul"]) * (1 + tolerance), LEGS_CLOSE)
        _assign(codes, arm_span > arm_length * (1 + tolerance), ARMS_SHORT)
        _assign(codes, arm_span <= np.abs(v["l_ua"] - v["l_la"]) * (1 + tolerance), ARMS_CLOSE)


def reason_text(code: int) -> str:
    """``"name: expected ..."`` of a code (``""`` for a valid design)."""
    name, expected = REASONS[int(code)]
    return f"{name}: expected {expected}" if name else ""


__all__ = [
    "NOT_COMPUTED",
    "REASONS",
    "SINGULAR",
    "benchmark_reasons",
    "mass_matrix_reasons",
    "measurement_reasons",
    "reason_text",
    "rider_reasons",
]
