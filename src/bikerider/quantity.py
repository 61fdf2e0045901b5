"""Measured values with a standard uncertainty: ``value +/- sigma``."""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

from bikerider.errors import InputError

_PLUS_MINUS = re.compile(r"^\s*([^\s+/]+(?:[eE][+-]?\d+)?)\s*(?:\+/-|±)\s*(\S+)\s*$")


@dataclass(frozen=True)
class Quantity:
    """A value and its standard uncertainty (``sigma = 0`` when none was given)."""

    value: float
    sigma: float = 0.0

    def __float__(self) -> float:
        return self.value

    def __str__(self) -> str:
        return f"{self.value:.6g} +/- {self.sigma:.2g}" if self.sigma else f"{self.value:.6g}"

    def scaled(self, factor: float) -> "Quantity":
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
    value, sigma = float(value), float(sigma)
    if not math.isfinite(value):
        raise InputError(name, value, "a finite number", source)
    if not math.isfinite(sigma) or sigma < 0:
        raise InputError(f"{name} uncertainty", sigma, "a finite, non-negative standard uncertainty", source)
    return Quantity(value, sigma)

