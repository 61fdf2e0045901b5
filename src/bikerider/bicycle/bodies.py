"""The bicycle reduced to what the method needs: geometry and the four bodies' mass properties.

Every reader (the project's TOML files, BicycleParameters ``<Name>Measured.txt`` files) produces a
:class:`BicycleBodies`; the estimate pipeline takes it from there.  Names are those of the symbol
table (``derive/symbols.py``); angles are in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from bikerider.benchmark.parameters import check_wheel
from bikerider.errors import MISSING, ErrorCollector, InputError
from bikerider.inertia import check_plane_symmetric_inertia
from bikerider.notes import add as add_to_notes
from bikerider.notes import note
from bikerider.quantity import (
    SMALLEST,
    Quantity,
    check_angle_sigma,
    check_degrees,
    check_magnitude,
    check_positive,
    sigma_note,
)

BODY_NAMES: tuple[str, ...] = (
    "w",
    "c",
    "lam_ht",
    "g",
    "rR",
    "mR",
    "IRxx",
    "IRyy",
    "rF",
    "mF",
    "IFxx",
    "IFyy",
    "mBf",
    "xBf",
    "zBf",
    "IBfxx",
    "IBfzz",
    "IBfxz",
    "mH",
    "xH",
    "zH",
    "IHxx",
    "IHzz",
    "IHxz",
)
"""Needed for the benchmark parameters of the bicycle (with or without a rider)."""

OPTIONAL_BODY_NAMES: tuple[str, ...] = ("IBfyy", "IHyy")
"""Not needed by the linear model; reported when measured."""

SEATING_NAMES: tuple[str, ...] = (
    "h_bb",
    "l_cs",
    "l_f",
    "w_fh",
    "l_hb",
    "w_rh",
    "l_sp",
    "lam_st",
    "l_st",
    "l_s",
)
"""The rest of Table 1: needed only to seat the paper's rider model on the bicycle."""

_POSITIVE = {
    "w",
    "g",
    "rR",
    "mR",
    "IRxx",
    "IRyy",
    "rF",
    "mF",
    "IFxx",
    "IFyy",
    "mBf",
    "mH",
    "IBfyy",
    "IHyy",
    "h_bb",
    "l_cs",
    "l_f",
    "w_fh",
    "l_hb",
    "w_rh",
    "l_sp",
    "l_st",
    "l_s",
}
_ANGLES = {"lam_ht": (0.0, math.pi), "lam_st": (0.0, math.pi)}
_LIMITS: dict[str, tuple[float, str]] = {
    "w": (5.0, "m"),
    "c": (1.0, "m"),
    "g": (100.0, "m/s^2"),
    **{k: (3.0, "m") for k in ("rR", "rF", "h_bb", "l_cs", "l_f", "w_fh", "l_hb", "w_rh", "l_sp", "l_st", "l_s")},
    **{k: (5.0, "m") for k in ("xBf", "zBf", "xH", "zH")},
    **{k: (500.0, "kg") for k in ("mR", "mF", "mBf", "mH")},
    **{f"I{b}{a}": (1e4, "kg m^2") for b in ("R", "F") for a in ("xx", "yy")},
    **{f"I{b}{a}": (1e4, "kg m^2") for b in ("Bf", "H") for a in ("xx", "yy", "zz", "xz")},
}
"""Largest plausible magnitudes: far beyond any bicycle, so a larger value is a unit slip."""

_QUICK: dict[str, tuple[float, float, bool]] = {
    key: (
        max(SMALLEST.get(unit, 0.0), 1e-3 if key in ("w", "rR", "rF") else 0.0) if key in _POSITIVE else -limit,
        limit,
        key in _POSITIVE,
    )
    for key, (limit, unit) in _LIMITS.items()
    if key not in _ANGLES
}
"""Per value with a limit: ``(low, limit, positive)`` such that a value in ``[low, limit]`` with an
uncertainty of at most ``limit`` (and, if ``positive``, below the value or zero) passes every check
of :func:`check_bicycle_values` on its own without a note; any other value takes the checks."""


@dataclass(frozen=True)
class BicycleBodies:
    """Geometry and mass properties of the four rigid bodies of a bicycle.

    Attributes
    ----------
    values : dict of str to Quantity
        Every name in :data:`BODY_NAMES`, optionally those in :data:`OPTIONAL_BODY_NAMES` and
        :data:`SEATING_NAMES`.
    source : str
        Where the values came from (a file name), for messages.
    name : str
        A human name for the bicycle.
    """

    values: dict[str, Quantity]
    source: str = "<memory>"
    name: str = "bicycle"
    notes: list[str] = field(default_factory=list)
    raw_inputs: dict[str, Quantity] = field(default_factory=dict)
    """Measurements before their reduction to ``values`` (pendulum periods, axis angles, the pendulum
    stiffness and length), keyed by the input names of the sensitivity chain (``derive/sensitivities.py``:
    ``k_t``, ``T_Rxx``, ``T_Fyy``, ``l_pF``, ``T_Bf1``, ``alpha_Bf1``, ...), so that uncertainty
    propagation keeps the correlations the reductions create."""
    reduced: tuple[str, ...] = ()
    """Names of ``values`` computed from ``raw_inputs``."""

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raise :class:`InputError` on missing required values and impossible ones, every one at
        once (:class:`~bikerider.errors.InputErrors`); note the unusual ones (``notes``)."""
        errors = ErrorCollector()
        check_bicycle_values(self.values, self.source, errors, self.notes)
        errors.raise_any()

    def __getitem__(self, key: str) -> float:
        return self.values[key].value

    def get(self, key: str) -> Quantity | None:
        return self.values.get(key)

    @property
    def can_seat_rider(self) -> bool:
        """Whether every seating measurement (Table 1) is present."""
        return all(k in self.values for k in SEATING_NAMES)

    def missing_seating(self) -> list[str]:
        return [k for k in SEATING_NAMES if k not in self.values]


USUAL_ANGLES_DEG = (45.0, 90.0)
"""Head tube and seat tube angles [deg] of the bicycles measured so far lie within these; an angle
outside them is possible (a chopper, a steer axis tilted forward) and accepted with a note."""


def check_bicycle_values(
    values: dict[str, Quantity],
    source: str,
    errors: ErrorCollector,
    notes: list[str] | None = None,
    unreadable: frozenset[str] | set[str] = frozenset(),
) -> None:
    """Check a bicycle's values, adding every problem to ``errors`` and every note to ``notes``.

    ``unreadable`` names values a reader could not read (and has reported): they are not called
    missing, and no relation with them is checked.  The checks, each value once (its first problem):

    * every name of :data:`BODY_NAMES` present;
    * positive values (masses, lengths, wheel inertias, ``g``) via
      :func:`bikerider.quantity.check_positive`: finite, within :data:`_LIMITS` (so are their
      uncertainties) and at least :data:`bikerider.quantity.SMALLEST` for lengths and masses;
      signed values (trail, centres of mass, products of inertia) within :data:`_LIMITS`;
    * ``w``, ``rR``, ``rF`` at least 0.001 m (the model divides by them);
    * head tube and seat tube angles between 0 and 180 degrees, not in radians, uncertainty at
      most 180 degrees; outside :data:`USUAL_ANGLES_DEG`, a note;
    * ``zBf``, ``zH`` negative (z points down);
    * the rear frame's and handlebar's inertia tensors (:mod:`bikerider.inertia`);
    * each wheel's moments (:func:`bikerider.benchmark.parameters.check_wheel`).

    A positive value whose uncertainty is at least the value gets a note.
    """
    failed = set(unreadable)

    def add_note(message: str | None) -> None:
        if message and notes is not None:
            add_to_notes(notes, message)
        elif message:
            note(message)

    for key in BODY_NAMES:
        if key not in values and key not in failed:
            errors.add(InputError(key, MISSING, "a value: the benchmark model needs it", source))
            failed.add(key)
    quick_checks = _QUICK.get
    for key, q in values.items():
        if key in failed:
            continue
        quick = quick_checks(key)
        if quick is not None:  # the common case first: a value well inside its limits, no note
            low, limit, positive = quick
            value, sigma = q.value, q.sigma
            if low <= value <= limit and abs(sigma) <= limit:
                if not positive or (value > 0 and (sigma < value or sigma == 0)):
                    continue
        try:
            if key in _ANGLES:
                low, high = _ANGLES[key]
                degrees = math.degrees(q.value)
                if not low < q.value < high:
                    raise InputError(f"{key}_deg", degrees, "an angle between 0 and 180 degrees", source)
                check_degrees(f"{key}_deg", degrees, source)
                check_angle_sigma(f"{key}_deg", q, source)
                if not USUAL_ANGLES_DEG[0] <= degrees <= USUAL_ANGLES_DEG[1]:
                    tilt = 90.0 - degrees
                    steer = f" (a steer axis {abs(tilt):g} deg {'back' if tilt > 0 else 'forward'} of vertical)"
                    add_note(
                        f"{source}: {key}_deg = {degrees:g}{steer if key == 'lam_ht' else ''}: outside the "
                        f"{USUAL_ANGLES_DEG[0]:g} to {USUAL_ANGLES_DEG[1]:g} degrees of the bicycles measured "
                        "so far; accepted, check the value"
                    )
                add_note(sigma_note(f"{key}_deg", q, source, f"{degrees:g} +/- {math.degrees(q.sigma):.2g}"))
                continue
            limit = _LIMITS.get(key)
            if key in _POSITIVE:  # every one has a limit
                add_note(check_positive(key, q, *_LIMITS[key], source))
            elif limit is not None:
                check_magnitude(key, q.value, *limit, source)
                check_magnitude(f"{key} uncertainty", q.sigma, *limit, source)
            if key in ("w", "rR", "rF") and not q.value >= 1e-3:  # the model divides by these
                raise InputError(key, q.value, "at least 0.001 m (SI units: a length in metres)", source)
        except InputError as exc:
            errors.add(exc)
            failed.add(key)
    for key in ("zBf", "zH"):
        if key not in failed and key in values and not values[key].value < 0:
            errors.add(
                InputError(
                    key,
                    values[key].value,
                    "a negative value: z points down in the benchmark frame, so a "
                    "centre of mass above the ground has z < 0",
                    source,
                )
            )
    for body in ("Bf", "H"):
        entries = (f"I{body}xx", f"I{body}zz", f"I{body}xz")
        if failed.intersection(entries) or f"I{body}yy" in failed or not all(k in values for k in entries):
            continue
        yy = values.get(f"I{body}yy")
        with errors.check():
            check_plane_symmetric_inertia(
                f"I{body} (I{body}xx, I{body}yy, I{body}zz, I{body}xz)",
                values[f"I{body}xx"].value,
                None if yy is None else yy.value,
                values[f"I{body}zz"].value,
                values[f"I{body}xz"].value,
                source,
            )
    for wheel in ("R", "F"):
        names = (f"m{wheel}", f"r{wheel}", f"I{wheel}xx", f"I{wheel}yy")
        if not failed.intersection(names) and all(k in values for k in names):
            with errors.check():
                check_wheel(wheel, *(values[k] for k in names), source)
