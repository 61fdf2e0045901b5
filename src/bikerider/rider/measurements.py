"""Rider measurements (Moore et al. 2009, Tables 7 and 8)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from bikerider.errors import MISSING, InputError
from bikerider.quantity import Quantity, check_degrees, check_magnitude

RIDER_NAMES: tuple[str, ...] = (
    "mBr",
    "c_ch",
    "lam_fl",
    "c_h",
    "l_hh",
    "c_la",
    "l_la",
    "c_ll",
    "l_ll",
    "l_ss",
    "l_to",
    "c_ua",
    "l_ua",
    "c_ul",
    "l_ul",
)
"""Rider mass and the 14 measurements of Table 7 (``lam_fl`` in radians)."""

DEFAULT_MASS_FRACTIONS: dict[str, float] = {
    # Moore et al. (2009) Table 8, from the cadaver data of Dempster as cited there ([8]).
    "f_h": 0.068,
    "f_la": 0.022,
    "f_ll": 0.061,
    "f_to": 0.510,
    "f_ua": 0.028,
    "f_ul": 0.100,
}
"""Segment mass fractions of the rider's mass; arms and legs are per side."""

FRACTION_COUNTS = {"f_h": 1, "f_la": 2, "f_ll": 2, "f_to": 1, "f_ua": 2, "f_ul": 2}
"""How many segments each fraction applies to."""


@dataclass(frozen=True)
class RiderMeasurements:
    """A rider's mass, body measurements and segment mass fractions.

    Attributes
    ----------
    values : dict of str to Quantity
        Every name of :data:`RIDER_NAMES` (SI units, ``lam_fl`` in radians).
    fractions : dict of str to float
        Segment mass fractions (defaults: Table 8).
    """

    values: dict[str, Quantity]
    fractions: dict[str, float] = field(default_factory=lambda: dict(DEFAULT_MASS_FRACTIONS))
    source: str = "<memory>"
    name: str = "rider"

    def __post_init__(self) -> None:
        for key in RIDER_NAMES:
            if key not in self.values:
                raise InputError(
                    key, MISSING, "a value: the rider model needs all 14 measurements and the mass", self.source
                )
            q = self.values[key]
            if key == "lam_fl":
                if not 0 < q.value < math.pi:
                    raise InputError(
                        "lam_fl_deg",
                        math.degrees(q.value),
                        "a forward lean angle between 0 and 180 degrees",
                        self.source,
                    )
                check_degrees("lam_fl_deg", math.degrees(q.value), self.source)
            elif not q.value > 0:
                raise InputError(key, q.value, "a positive value", self.source)
            else:  # the mass, or a length or circumference
                limit, unit = (500.0, "kg") if key == "mBr" else (3.0, "m")
                check_magnitude(key, q.value, limit, unit, self.source)
                check_magnitude(f"{key} uncertainty", q.sigma, limit, unit, self.source)
        unknown = set(self.fractions) - set(DEFAULT_MASS_FRACTIONS)
        if unknown:
            raise InputError(
                sorted(unknown)[0],
                self.fractions[sorted(unknown)[0]],
                f"one of the mass fractions {', '.join(DEFAULT_MASS_FRACTIONS)}",
                self.source,
            )
        for key, value in self.fractions.items():
            if not (math.isfinite(value) and 0 < value < 1):
                raise InputError(key, value, "a mass fraction between 0 and 1", self.source)
        total = sum(FRACTION_COUNTS[k] * v for k, v in self.fractions.items())
        if abs(total - 1.0) > 1e-3:
            raise InputError(
                "mass fractions",
                round(total, 6),
                "segment fractions summing to 1 (head + torso + 2 x each limb segment)",
                self.source,
            )
        c_ua, l_ss, c_ch = self["c_ua"], self["l_ss"], self["c_ch"]
        width = l_ss - c_ua / math.pi
        if width <= 0:
            raise InputError(
                "l_ss", l_ss, f"more than c_ua/pi = {c_ua / math.pi:.3f} m (torso width, Eq. 9)", self.source
            )
        if c_ch - 2 * width <= 0:
            raise InputError(
                "c_ch",
                c_ch,
                f"more than twice the torso width 2*(l_ss - c_ua/pi) = {2 * width:.3f} m (torso thickness, Eq. 10)",
                self.source,
            )

    def __getitem__(self, key: str) -> float:
        return self.values[key].value
