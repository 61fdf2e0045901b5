"""The bicycle reduced to what the method needs: geometry and the four bodies' mass properties.

Every reader (the project's TOML files, BicycleParameters ``<Name>Measured.txt`` files) produces a
:class:`BicycleBodies`; the estimate pipeline takes it from there.  Names are those of the symbol
table (``derive/symbols.py``); angles are in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from bikerider.errors import MISSING, InputError
from bikerider.inertia import check_plane_symmetric_inertia
from bikerider.quantity import Quantity, check_degrees, check_magnitude

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
        """Raise :class:`InputError` on a missing required value or an impossible one."""
        for key in BODY_NAMES:
            if key not in self.values:
                raise InputError(key, MISSING, "a value: the benchmark model needs it", self.source)
        for key, q in self.values.items():
            if key in _POSITIVE and not q.value > 0:
                raise InputError(key, q.value, "a positive value", self.source)
            if key in _ANGLES:
                low, high = _ANGLES[key]
                if not low < q.value < high:
                    raise InputError(
                        f"{key}_deg", math.degrees(q.value), "an angle between 0 and 180 degrees", self.source
                    )
                check_degrees(f"{key}_deg", math.degrees(q.value), self.source)
            limit = _LIMITS.get(key)
            if limit is not None and not (abs(q.value) <= limit[0] and abs(q.sigma) <= limit[0]):
                check_magnitude(key, q.value, *limit, self.source)  # these pass only what is within the limit
                check_magnitude(f"{key} uncertainty", q.sigma, *limit, self.source)
            if key in ("w", "rR", "rF") and not q.value >= 1e-3:  # the model divides by these
                raise InputError(key, q.value, "at least 0.001 m (SI units: a length in metres)", self.source)
        for key in ("zBf", "zH"):
            if not self[key] < 0:
                raise InputError(
                    key,
                    self[key],
                    "a negative value: z points down in the benchmark frame, so a "
                    "centre of mass above the ground has z < 0",
                    self.source,
                )
        for body in ("Bf", "H"):
            yy = self.values.get(f"I{body}yy")
            check_plane_symmetric_inertia(
                f"I{body} (I{body}xx, I{body}yy, I{body}zz, I{body}xz)",
                self[f"I{body}xx"],
                None if yy is None else yy.value,
                self[f"I{body}zz"],
                self[f"I{body}xz"],
                self.source,
            )

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
