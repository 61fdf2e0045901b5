"""The 26 benchmark values (Meijaard et al. 2007, Table 1; 25 parameters plus gravity)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from bikerider.benchmark import rules
from bikerider.engine import arguments
from bikerider.errors import MISSING, ErrorCollector, InputError
from bikerider.generated.benchmark_model import canonical_matrices
from bikerider.generated.manifest import BENCHMARK_NAMES
from bikerider.inertia import TRIANGLE_TOLERANCE, check_plane_symmetric_inertia
from bikerider.notes import note
from bikerider.quantity import DEG, MAX_ANGLE_SIGMA, Quantity, check_magnitude, sigma_note

BENCHMARK_NAMES: tuple[str, ...] = BENCHMARK_NAMES
"""Names in the order of Meijaard et al. (2007), Table 1 (``derive/symbols.py``)."""

OPTIONAL_NAMES = frozenset({"IByy", "IHyy"})
"""Values the linear model does not need; ``None`` when the inputs do not determine them."""

_NAME_SET = frozenset(BENCHMARK_NAMES)
_CANONICAL_ARGS = arguments("benchmark_model.canonical_matrices")
_WHEEL_NAMES = tuple((w, (f"m{w}", f"r{w}", f"I{w}xx", f"I{w}yy")) for w in rules.WHEELS)


def _quick_ranges() -> tuple[tuple[str, float, float, float, bool], ...]:
    """Per value that rules 2-5 and 7 check on its own: ``(name, low, high, sigma_limit,
    may_be_none)``, such that a value in ``[low, high]`` with an uncertainty of at most
    ``sigma_limit`` breaks none of them (``may_be_none``: only rule 3 reads it, and it skips a
    ``None`` value, not its uncertainty)."""
    tiniest = math.ulp(0.0)  # v > 0 is v >= tiniest, v < 0 is v <= -tiniest
    names = set(rules.POSITIVE) | set(rules.LIMITS) | set(rules.SMALLEST) | set(rules.DIVISORS)
    names |= set(rules.BELOW_GROUND)
    ranges = []
    for name in (name for name in BENCHMARK_NAMES if name in names):
        low, high, sigma_limit = -math.inf, math.inf, math.inf
        if name in rules.POSITIVE:
            low = tiniest
        if name in rules.LIMITS:
            limit = rules.LIMITS[name][0]
            low, high, sigma_limit = max(low, -limit), limit, limit
        if name in rules.SMALLEST:
            low = max(low, rules.SMALLEST[name][0])
        if name in rules.DIVISORS:
            low = max(low, rules.MIN_DIVISOR)
        if name in rules.BELOW_GROUND:
            high = min(high, -tiniest)
        only_limits = name not in set(rules.POSITIVE) | set(rules.SMALLEST) | set(rules.DIVISORS)
        ranges.append((name, low, high, sigma_limit, only_limits and name not in rules.BELOW_GROUND))
    return tuple(ranges)


_QUICK = _quick_ranges()


def _well_inside(values: Mapping[str, float | None], sigmas: Mapping[str, float]) -> bool:
    """Whether every value of :data:`_QUICK` lies in its range (rules 2-5 and 7 then find nothing:
    :meth:`BenchmarkParameters._check` skips them; any other set takes every check)."""
    get = sigmas.get
    for name, low, high, sigma_limit, may_be_none in _QUICK:
        value = values[name]
        if value is None:
            if not may_be_none:
                return False
        elif not low <= value <= high:
            return False
        if not get(name, 0.0) <= sigma_limit:
            return False
    return True


@dataclass(frozen=True)
class BenchmarkParameters:
    """The benchmark values in SI units, with standard uncertainties.

    Attributes
    ----------
    values : dict
        Name to value; ``None`` for ``IByy``/``IHyy`` when not determined.
    sigmas : dict
        Name to standard uncertainty (0 when unknown).
    source : str or None
        Where the values came from, for error messages.
    """

    values: dict[str, float | None]
    sigmas: dict[str, float] = field(default_factory=dict)
    source: str | None = None

    @classmethod
    def from_mapping(cls, mapping: Mapping[str, object], source: str | None = None) -> BenchmarkParameters:
        """Build from a mapping of names to numbers or :class:`Quantity`; validate.

        Raises
        ------
        InputError
            A missing or unknown name, a non-finite value, a non-positive mass, length or wheel
            inertia, an impossible steer axis tilt, or an impossible inertia tensor; every one of
            them at once (:class:`~bikerider.errors.InputErrors`).
        """
        errors = ErrorCollector()
        failed: set[str] = set()
        unknown = () if _NAME_SET.issuperset(mapping) else sorted(set(mapping) - _NAME_SET)
        for name in unknown:
            errors.add(
                InputError(name, mapping[name], f"one of the benchmark names {', '.join(BENCHMARK_NAMES)}", source)
            )
        values: dict[str, float | None] = {}
        sigmas: dict[str, float] = {}
        get, isfinite = mapping.get, math.isfinite
        for name in BENCHMARK_NAMES:
            raw = get(name)
            if raw is None:
                if name in OPTIONAL_NAMES:
                    values[name], sigmas[name] = None, 0.0
                    continue
                if name == "g":
                    values[name], sigmas[name] = 9.81, 0.0
                    continue
                errors.add(InputError(name, MISSING, "a value (all 25 benchmark parameters are needed)", source))
                values[name], sigmas[name] = math.nan, 0.0
                failed.add(name)
                continue
            q = raw if isinstance(raw, Quantity) else Quantity(float(raw))  # type: ignore[arg-type]
            if not isfinite(q.value):
                errors.add(InputError(name, q.value, "a finite number", source))
                failed.add(name)
            values[name], sigmas[name] = q.value, q.sigma
        params = cls(values, sigmas, source)
        params._check(errors, failed)
        return params

    def validate(self) -> None:
        """Raise :class:`InputError` for values no real bicycle can have: the rules of
        :mod:`bikerider.benchmark.rules`, in their order, every broken rule at once
        (:class:`~bikerider.errors.InputErrors`; its first error is the first broken rule)."""
        self._check(ErrorCollector(), set())

    def _check(self, errors: ErrorCollector, failed: set[str]) -> None:
        """:meth:`validate`, adding to ``errors`` and skipping the names in ``failed`` (and every
        relation that involves one), then raising all that was collected."""
        v, src = self.values, self.source

        def fail(name: str, value: object, expected: str, names: tuple[str, ...] = ()) -> None:
            errors.add(InputError(name, value, expected, src))
            failed.update(names or (name,))

        # The common case: every value well inside its range skips rules 2-5 and 7 (none would fail).
        quick = not failed and _well_inside(v, self.sigmas)
        for name in () if quick else rules.POSITIVE:
            if name not in failed and v[name] <= 0:  # type: ignore[operator]
                fail(name, v[name], "a positive value")
        for name, (limit, unit) in () if quick else rules.LIMITS.items():
            if name not in failed and v[name] is not None and not abs(v[name]) <= limit:  # type: ignore[arg-type]
                with errors.check():
                    check_magnitude(name, v[name], limit, unit, src)  # type: ignore[arg-type]
                failed.add(name)
            elif name not in failed and not self.sigmas.get(name, 0.0) <= limit:
                fail(f"{name} uncertainty", self.sigmas[name], rules.limit_expected(limit, unit), (name,))
        if "lam" not in failed and not self.sigmas.get("lam", 0.0) <= MAX_ANGLE_SIGMA:
            fail(
                "lam uncertainty",
                self.sigmas["lam"],
                "at most pi rad (a larger uncertainty says nothing about the angle)",
                ("lam",),
            )
        for name, (smallest, unit) in () if quick else rules.SMALLEST.items():
            if name not in failed and v[name] < smallest:  # type: ignore[operator]
                fail(name, v[name], rules.smallest_expected(smallest, unit))
        for name in () if quick else rules.DIVISORS:  # the model divides by these
            if name not in failed and v[name] < rules.MIN_DIVISOR:  # type: ignore[operator]
                fail(name, v[name], rules.DIVISOR_EXPECTED)
        if "lam" not in failed and not -math.pi / 2 < v["lam"] < math.pi / 2:  # type: ignore[operator]
            hint = (
                f" ({v['lam']:g} looks like degrees: give lam_deg = {v['lam']:g} in a TOML file, "
                f"or {v['lam'] * DEG:.6g} rad)"
                if abs(v["lam"]) <= 90  # type: ignore[arg-type]
                else ""
            )
            fail("lam", v["lam"], f"{rules.TILT_EXPECTED}{hint}")
        for name in () if quick else rules.BELOW_GROUND:
            if name not in failed and not v[name] < 0:  # type: ignore[operator]
                fail(name, v[name], rules.BELOW_GROUND_EXPECTED)
        for body in rules.BODIES:
            entries = rules.tensor_entries(body)
            if not failed.intersection(entries):
                try:
                    check_plane_symmetric_inertia(rules.tensor_name(body), *(v[k] for k in entries), src)  # type: ignore[arg-type]
                except InputError as exc:
                    fail(exc.name, exc.value, exc.expected, entries)
        for wheel, names in _WHEEL_NAMES:
            if not failed.intersection(names):
                with errors.check():
                    check_wheel(wheel, *(Quantity(v[k], self.sigmas.get(k, 0.0)) for k in names), src)  # type: ignore[arg-type]
        errors.raise_any()

    def with_values(self, **changes: float | Quantity) -> BenchmarkParameters:
        """A copy with some values changed, validated; the others keep their values and uncertainties.

        Parameters
        ----------
        **changes : float or Quantity
            New values by benchmark name (SI units, ``lam`` in radians); a :class:`Quantity` sets
            the uncertainty too, a plain number makes it zero.

        Raises
        ------
        InputError
            An unknown name, or a changed set no bicycle can have (the message names the value).

        Examples
        --------
        >>> longer_trail = parameters.with_values(c=0.1)  # doctest: +SKIP
        """
        unknown = sorted(set(changes) - _NAME_SET)
        if unknown:
            raise InputError(
                unknown[0], changes[unknown[0]], f"one of the benchmark names {', '.join(BENCHMARK_NAMES)}", self.source
            )
        mapping: dict[str, object] = {
            name: (None if self.values[name] is None else Quantity(self.values[name], self.sigmas.get(name, 0.0)))  # type: ignore[arg-type]
            for name in BENCHMARK_NAMES
        }
        mapping.update(changes)
        changed = ", ".join(f"{k}={v.value if isinstance(v, Quantity) else v:g}" for k, v in changes.items())
        source = f"{self.source or 'parameters'} with {changed}" if changes else self.source
        return BenchmarkParameters.from_mapping({k: v for k, v in mapping.items() if v is not None}, source)

    def __getitem__(self, name: str) -> float | None:
        return self.values[name]

    def as_dict(self) -> dict[str, float | None]:
        """Name to value, in Table 1 order (``None`` where not determined)."""
        return {name: self.values[name] for name in BENCHMARK_NAMES}


def check_mass_matrix(parameters: BenchmarkParameters) -> None:
    """Rule 11 of :mod:`bikerider.benchmark.rules`: raise :class:`InputError` (naming the source)
    unless the mass matrix of ``parameters`` is positive definite.

    The readers of benchmark files call it once per file (and :class:`WhippleModel` checks every
    model it builds); :meth:`BenchmarkParameters.validate` leaves it out, since computing M would
    triple the cost of a sweep's ``with_values`` per design.
    """
    v = parameters.values
    M = canonical_matrices(**{k: v[k] for k in _CANONICAL_ARGS})[0]
    if rules.singular_mass_matrix(M):
        raise InputError("M", np.asarray(M).tolist(), rules.SINGULAR_MASS_EXPECTED, parameters.source)


def uncertainty_notes(parameters: BenchmarkParameters) -> list[str]:
    """Notes on the values that must be positive (:data:`rules.POSITIVE`) whose uncertainty is at
    least the value itself (:func:`bikerider.quantity.sigma_note`); the readers note them."""
    out = []
    for name in rules.POSITIVE:
        text = sigma_note(name, Quantity(parameters.values[name], parameters.sigmas.get(name, 0.0)), parameters.source)  # type: ignore[arg-type]
        if text:
            out.append(text)
    return out


def check_wheel(wheel: str, m: Quantity, r: Quantity, Ixx: Quantity, Iyy: Quantity, source: str | None = None) -> None:
    """The moments of an axisymmetric wheel of mass ``m`` and radius ``r`` (rules 9 and 10 of
    :mod:`bikerider.benchmark.rules`).

    * ``I_yy <= 2 I_xx``: the triangle inequality (``2 I_xx - I_yy = 2 int y^2 dm``);
    * ``I_yy <= m r^2``: all of the wheel's mass lies within its radius of the axle;
    * ``I_xx <= m r^2``: ``I_xx = I_yy / 2 + int y^2 dm <= m (r^2 / 2 + h^2)`` for a wheel of
      half-width ``h``, at most ``m r^2`` for any wheel narrower than ``1.4 r``.

    A violation within the combined standard uncertainty of the values is accepted with a note
    (printed values are rounded: the paper's I_Ryy = 0.16 with I_Rxx = 0.079); a larger one is an
    error.

    Raises
    ------
    InputError
        The first of the three a wheel breaks beyond its uncertainty.
    """
    mr2 = m.value * r.value**2
    slack = 1 + TRIANGLE_TOLERANCE
    if Iyy.value <= 2 * Ixx.value * slack and Iyy.value <= mr2 * slack and Ixx.value <= mr2 * slack:
        return  # the common case, without the uncertainties (their use is below)
    mr2_sigma = math.hypot(r.value**2 * m.sigma, 2 * m.value * r.value * r.sigma)
    bounds = (
        ("yy", Iyy, 2 * Ixx.value, math.hypot(Iyy.sigma, 2 * Ixx.sigma), f"2*I{wheel}xx", rules.WHEEL_TRIANGLE),
        ("yy", Iyy, mr2, math.hypot(Iyy.sigma, mr2_sigma), f"m{wheel}*r{wheel}^2", rules.WHEEL_EXTENT["yy"]),
        ("xx", Ixx, mr2, math.hypot(Ixx.sigma, mr2_sigma), f"m{wheel}*r{wheel}^2", rules.WHEEL_EXTENT["xx"]),
    )
    for axis, moment, bound, allowed, bound_name, why in bounds:
        excess = moment.value - bound
        if excess <= TRIANGLE_TOLERANCE * moment.value:
            continue
        message = (
            f"at most {bound_name} = {bound:.6g} ({why}; exceeded by {excess:.3g} kg m^2, "
            f"combined uncertainty {allowed:.3g})"
        )
        if excess > allowed:
            raise InputError(f"I{wheel}{axis}", moment.value, message, source)
        # Without the source: the same wheel is checked as read and again in the benchmark values.
        note(f"I{wheel}{axis} = {moment.value:.6g} is not {message}; accepted within its uncertainty")
