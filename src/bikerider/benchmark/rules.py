"""The rules a set of benchmark values must satisfy, as one table.

Two checks read it: :meth:`bikerider.benchmark.BenchmarkParameters.validate` (one set, raising on
the first rule it breaks) and :func:`bikerider.design.validity.benchmark_reasons` (batches of
millions of designs, a reason code per design), in the same order:

1. finite values (``IByy``, ``IHyy`` may be left undetermined);
2. :data:`POSITIVE`: masses, radii, wheel inertias, the wheelbase and gravity;
3. :data:`LIMITS`: magnitudes beyond any bicycle and rider (a larger value is a unit slip);
4. :data:`DIVISORS`: the lengths the model divides by, at least :data:`MIN_DIVISOR`;
5. the steer axis tilt between -pi/2 and pi/2;
6. :data:`BELOW_GROUND`: centres of mass above the ground (``z < 0``, z points down);
7. the inertia tensor of each of :data:`BODIES` (:mod:`bikerider.inertia`, the one tensor check);
8. the triangle inequality of each of :data:`WHEELS`: ``I_yy <= 2 I_xx``.
"""

from __future__ import annotations

from bikerider.generated.manifest import BENCHMARK_NAMES

POSITIVE = ("w", "g", "rR", "mR", "IRxx", "IRyy", "mB", "mH", "rF", "mF", "IFxx", "IFyy")
"""Values that must be positive."""
LIMITS: dict[str, tuple[float, str]] = {
    "w": (5.0, "m"),
    "c": (1.0, "m"),
    "rR": (3.0, "m"),
    "rF": (3.0, "m"),
    "g": (100.0, "m/s^2"),
    **{k: (5.0, "m") for k in ("xB", "zB", "xH", "zH")},
    **{k: (1000.0, "kg") for k in ("mR", "mB", "mH", "mF")},
    **{k: (1e4, "kg m^2") for k in BENCHMARK_NAMES if k.startswith("I")},
}
"""Largest plausible magnitudes with their SI units (the rear body may hold riders)."""
DIVISORS = ("w", "rR", "rF")
"""Lengths the model divides by."""
MIN_DIVISOR = 1e-3
"""The smallest of :data:`DIVISORS` [m]."""
DIVISOR_EXPECTED = "at least 0.001 m (SI units: a length in metres)"
TILT_EXPECTED = "a steer axis tilt between -pi/2 and pi/2 rad"
BELOW_GROUND = ("zB", "zH")
"""Centres of mass that must lie above the ground."""
BELOW_GROUND_EXPECTED = (
    "a negative value: z points down in the benchmark frame, so a centre of mass above the ground has z < 0"
)
BODIES = ("B", "H")
"""The bodies whose plane-symmetric inertia tensors are checked: rear frame (with rider), front assembly."""
WHEELS = ("R", "F")
"""The wheels whose two moments of inertia are checked together."""


def limit_expected(limit: float, unit: str) -> str:
    """What a value beyond its :data:`LIMITS` entry was expected to be."""
    return f"at most {limit:g} {unit} in magnitude (SI units)"


def tensor_entries(body: str) -> tuple[str, str, str, str]:
    """The names of ``body``'s tensor entries: xx, yy, zz, xz."""
    return f"I{body}xx", f"I{body}yy", f"I{body}zz", f"I{body}xz"


def tensor_name(body: str) -> str:
    """How messages name ``body``'s inertia tensor."""
    return f"I{body} ({', '.join(tensor_entries(body))})"


def wheel_expected(wheel: str) -> str:
    """What a wheel's ``I_yy`` was expected to be."""
    return f"at most 2*I{wheel}xx (triangle inequality of an axisymmetric wheel)"


TIED = tuple(frozenset(tensor_entries(body)) for body in BODIES) + tuple(
    frozenset((f"I{wheel}xx", f"I{wheel}yy")) for wheel in WHEELS
)
"""Values one rule checks together (each body's tensor, each wheel's two moments)."""

__all__ = [
    "BELOW_GROUND",
    "BELOW_GROUND_EXPECTED",
    "BODIES",
    "DIVISORS",
    "DIVISOR_EXPECTED",
    "LIMITS",
    "MIN_DIVISOR",
    "POSITIVE",
    "TIED",
    "TILT_EXPECTED",
    "WHEELS",
    "limit_expected",
    "tensor_entries",
    "tensor_name",
    "wheel_expected",
]
