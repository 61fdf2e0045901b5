"""Measured values with a standard uncertainty: ``value +/- sigma``."""

from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass

from bikerider.errors import InputError

DEG = math.pi / 180
"""One degree in radians: angles are given in degrees only at the input boundary and converted there,
once, by this factor (``math.radians`` multiplies by the same number)."""

_LARGEST_INTEGER = int(sys.float_info.max)
"""The largest integer a float holds; TOML integers beyond it cannot be measurements."""

SPEED_OF_LIGHT = 299_792_458.0
"""m/s.  No speed a command takes reaches it: the Whipple model is Newtonian (and below it ``v^2``
and the state matrices stay far inside floating point)."""

_PLUS_MINUS = re.compile(r"^\s*([^\s+/]+(?:[eE][+-]?\d+)?)\s*(?:\+/-|±)\s*(\S+)\s*$")


@dataclass(frozen=True, init=False)
class Quantity:
    """A value and its standard uncertainty (``sigma = 0`` when none was given)."""

    value: float
    sigma: float = 0.0

    def __init__(self, value: float, sigma: float = 0.0) -> None:
        # What the frozen dataclass __init__ does (it sets the fields through object.__setattr__),
        # at half the cost: one reading builds hundreds of these.
        fields = self.__dict__
        fields["value"] = value
        fields["sigma"] = sigma

    def __float__(self) -> float:
        return self.value

    def __str__(self) -> str:
        return f"{self.value:.6g} +/- {self.sigma:.2g}" if self.sigma else f"{self.value:.6g}"

    def scaled(self, factor: float) -> Quantity:
        """The same quantity in other units (e.g. degrees to radians)."""
        return Quantity(self.value * factor, self.sigma * abs(factor))


def parse_quantity(raw: object, name: str, source: str | None = None) -> Quantity:
    """Read a number, a ``"value +/- sigma"`` string or a ``{value, sigma}`` table.

    Raises
    ------
    InputError
        When the value is not a finite number or the uncertainty is negative or not finite.
    """
    value: object
    sigma: object = 0.0
    if isinstance(raw, bool):
        raise InputError(name, raw, "a number, not true/false", source)
    if isinstance(raw, (int, float)):
        value = raw
    elif isinstance(raw, str):
        match = _PLUS_MINUS.match(raw)
        text_value, text_sigma = (match.group(1), match.group(2)) if match else (raw.strip(), "0")
        try:
            value, sigma = float(text_value), float(text_sigma)
        except ValueError:
            raise InputError(name, raw, 'a number or "value +/- sigma"', source) from None
    elif isinstance(raw, dict) and "value" in raw:
        unknown = set(raw) - {"value", "sigma"}
        if unknown:
            raise InputError(name, raw, f"only the keys value and sigma (got {sorted(unknown)})", source)
        value, sigma = raw["value"], raw.get("sigma", 0.0)
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            raise InputError(name, value, "a number", source)
        if not isinstance(sigma, (int, float)) or isinstance(sigma, bool):
            raise InputError(f"{name}.sigma", sigma, "a number", source)
    else:
        raise InputError(name, raw, 'a number, "value +/- sigma" or {value = ..., sigma = ...}', source)
    for part, number in ((name, value), (f"{name} uncertainty", sigma)):
        if isinstance(number, int) and not -_LARGEST_INTEGER <= number <= _LARGEST_INTEGER:
            raise InputError(
                part,
                f"an integer of about {int(number.bit_length() * math.log10(2)) + 1} digits",
                "a number within floating-point range",
                source,
            )
    value, sigma = float(value), float(sigma)
    if not math.isfinite(value):
        raise InputError(name, value, "a finite number", source)
    if not math.isfinite(sigma) or sigma < 0:
        raise InputError(f"{name} uncertainty", sigma, "a finite, non-negative standard uncertainty", source)
    return Quantity(value, sigma)


#: Unit slips worth suggesting when a value is too large for its SI unit: (factor to SI, unit).
UNIT_SLIPS: dict[str, tuple[tuple[float, str], ...]] = {
    "m": ((1e-3, "mm"), (1e-2, "cm")),
    "kg": ((1e-3, "g"),),
    "s": ((1e-3, "ms"),),
    "m/s^2": ((1e-2, "cm/s^2"),),
}


def check_magnitude(name: str, value: float, limit: float, unit: str, source: str | None = None) -> None:
    """Raise :class:`InputError` when ``|value|`` exceeds ``limit`` (in the SI ``unit``).

    The limits are far beyond any bicycle or rider, so a value above one is a unit slip (a
    wheelbase in millimetres) or a typing error; the message suggests the slip when dividing by
    it gives a plausible value.
    """
    if abs(value) <= limit:
        return
    if not math.isfinite(value):
        raise InputError(name, value, "a finite number", source)
    slips = [(f, u) for f, u in UNIT_SLIPS.get(unit, ()) if abs(value * f) <= limit]
    hint = "".join(f"; if this is in {u}, give {value * f:.6g} {unit}" for f, u in slips)
    raise InputError(name, value, f"at most {limit:g} {unit} in magnitude (SI units{hint})", source)


def check_degrees(name: str, degrees: float, source: str | None = None) -> None:
    """Raise :class:`InputError` for an angle under a ``_deg`` key that looks like radians.

    Every angle the method reads in degrees (head tube, seat tube, forward lean) is far above
    pi degrees on any bicycle or rider; a value in (0, pi] was almost surely given in radians.
    """
    if 0 < degrees <= math.pi:
        raise InputError(
            name,
            degrees,
            f"an angle in degrees ({degrees:g} looks like radians: {degrees:g} rad = {math.degrees(degrees):.4g} deg)",
            source,
        )


SMALLEST: dict[str, float] = {"m": 1e-6, "kg": 1e-6, "m/s^2": 1e-6}
"""Smallest positive length [m] and mass [kg] of a bicycle's or rider's part, and smallest gravity
[m/s^2] (a millionth of the Earth's is already deep space).  A smaller positive value (a denormal
such as 5e-324) is a typing slip, and the formulas that square or divide by it would overflow."""


def smallest_expected(smallest: float, unit: str) -> str:
    """What a positive value below its :data:`SMALLEST` was expected to be."""
    return f"at least {smallest:g} {unit} (a smaller positive value is a typing slip, such as a denormal 5e-324)"


def check_positive(name: str, q: Quantity, limit: float, unit: str, source: str | None = None) -> str | None:
    """Check a measurement that must be positive (a length, a mass, a moment of inertia, a period).

    Raises :class:`InputError` when the value is not positive, beyond ``limit`` in magnitude (so is
    its uncertainty), or below :data:`SMALLEST` for its unit; returns the text of a note when the
    value is possible but its uncertainty is not smaller than the value itself (:func:`sigma_note`).
    """
    if not q.value > 0:
        raise InputError(name, q.value, "a positive value", source)
    check_magnitude(name, q.value, limit, unit, source)
    check_magnitude(f"{name} uncertainty", q.sigma, limit, unit, source)
    smallest = SMALLEST.get(unit)
    if smallest is not None and q.value < smallest:
        raise InputError(name, q.value, smallest_expected(smallest, unit), source)
    return sigma_note(name, q, source)


def sigma_note(name: str, q: Quantity, source: str | None = None, shown: str | None = None) -> str | None:
    """A note when the uncertainty of a positive value is at least the value itself.

    Such an uncertainty does not even fix the sign; first-order propagation, which assumes the
    outputs linear over a few sigmas, means little at that size.  It is accepted (a rough guess
    may be all a user has), but never silently.  ``shown`` is the value as the user wrote it
    (e.g. in degrees), when ``q`` is converted.
    """
    if not q.sigma >= abs(q.value) or q.sigma == 0:
        return None
    where = f"{source}: " if source else ""
    return (
        f"{where}{name} = {shown or q}: its uncertainty is {q.sigma / abs(q.value):.3g} times the value "
        "(first-order sigmas mean little at that size; check the value and its uncertainty)"
    )


MAX_ANGLE_SIGMA = math.pi
"""Largest uncertainty of an angle [rad] (180 degrees): a larger one says nothing about the angle."""


def check_angle_sigma(name: str, q: Quantity, source: str | None = None) -> None:
    """Raise :class:`InputError` when the uncertainty of the angle ``q`` (radians; ``name`` its
    ``_deg`` key) exceeds :data:`MAX_ANGLE_SIGMA`."""
    if not q.sigma <= MAX_ANGLE_SIGMA:
        raise InputError(
            f"{name} uncertainty",
            math.degrees(q.sigma) if math.isfinite(q.sigma) else q.sigma,
            "at most 180 degrees (a larger uncertainty says nothing about the angle)",
            source,
        )
