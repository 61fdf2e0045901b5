"""Rider measurements (Moore et al. 2009, Tables 7 and 8)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from bikerider.errors import MISSING, ErrorCollector, InputError
from bikerider.notes import note
from bikerider.quantity import Quantity, check_angle_sigma, check_degrees, check_positive, sigma_note

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
        errors = ErrorCollector()
        check_rider_values(self.values, self.fractions, self.source, errors)
        errors.raise_any()

    def __getitem__(self, key: str) -> float:
        return self.values[key].value


def check_rider_values(
    values: dict[str, Quantity],
    fractions: dict[str, float],
    source: str,
    errors: ErrorCollector,
    unreadable: frozenset[str] | set[str] = frozenset(),
) -> None:
    """Check a rider's measurements and mass fractions, adding every problem to ``errors``.

    ``unreadable`` names values a reader could not read (and has reported): they are not called
    missing, and no relation with them is checked.  Each value is checked once (its first problem):
    present; the mass and lengths positive, within their limits (500 kg, 3 m; so are their
    uncertainties) and at least :data:`bikerider.quantity.SMALLEST`; the forward lean between 0 and
    180 degrees, not in radians, uncertainty at most 180 degrees; the fractions between 0 and 1,
    summing to 1; the torso's cross-section possible (Eqs. 9, 10).  A value whose uncertainty is at
    least the value itself gets a note.
    """
    failed = set(unreadable)
    for key in RIDER_NAMES:
        if key in failed:
            continue
        if key not in values:
            errors.add(
                InputError(key, MISSING, "a value: the rider model needs all 14 measurements and the mass", source)
            )
            failed.add(key)
            continue
        q = values[key]
        try:
            if key == "lam_fl":
                degrees = math.degrees(q.value)
                if not 0 < q.value < math.pi:
                    raise InputError("lam_fl_deg", degrees, "a forward lean angle between 0 and 180 degrees", source)
                check_degrees("lam_fl_deg", degrees, source)
                check_angle_sigma("lam_fl_deg", q, source)
                message = sigma_note("lam_fl_deg", q, source, f"{degrees:g} +/- {math.degrees(q.sigma):.2g}")
            else:  # the mass, or a length or circumference
                limit, unit = (500.0, "kg") if key == "mBr" else (3.0, "m")
                message = check_positive(key, q, limit, unit, source)
        except InputError as exc:
            errors.add(exc)
            failed.add(key)
            continue
        if message:
            note(message)
    unknown = sorted(set(fractions) - set(DEFAULT_MASS_FRACTIONS))
    for key in unknown:
        errors.add(
            InputError(key, fractions[key], f"one of the mass fractions {', '.join(DEFAULT_MASS_FRACTIONS)}", source)
        )
    bad = [
        key for key, value in fractions.items() if key not in unknown and not (math.isfinite(value) and 0 < value < 1)
    ]
    for key in bad:
        errors.add(InputError(key, fractions[key], "a mass fraction between 0 and 1", source))
    if not (unknown or bad or failed & set(FRACTION_COUNTS)):
        total = sum(FRACTION_COUNTS[k] * v for k, v in fractions.items())
        if abs(total - 1.0) > 1e-3:
            errors.add(
                InputError(
                    "mass fractions",
                    round(total, 6),
                    "segment fractions summing to 1 (head + torso + 2 x each limb segment)",
                    source,
                )
            )
    if failed & {"c_ua", "l_ss", "c_ch"}:
        return
    c_ua, l_ss, c_ch = values["c_ua"].value, values["l_ss"].value, values["c_ch"].value
    width = l_ss - c_ua / math.pi
    if width <= 0:
        errors.add(InputError("l_ss", l_ss, f"more than c_ua/pi = {c_ua / math.pi:.3f} m (torso width, Eq. 9)", source))
    elif c_ch - 2 * width <= 0:
        errors.add(
            InputError(
                "c_ch",
                c_ch,
                f"more than twice the torso width 2*(l_ss - c_ua/pi) = {2 * width:.3f} m (torso thickness, Eq. 10)",
                source,
            )
        )
