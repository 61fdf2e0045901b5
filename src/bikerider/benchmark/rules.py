"""The rules a set of benchmark values must satisfy, as one table.

Two checks read it: :meth:`bikerider.benchmark.BenchmarkParameters.validate` (one set, raising on
the first rule it breaks) and :func:`bikerider.design.validity.benchmark_reasons` (batches of
millions of designs, a reason code per design), in the same order:

1. finite values (``IByy``, ``IHyy`` may be left undetermined);
2. :data:`POSITIVE`: masses, radii, wheel inertias, the wheelbase and gravity;
3. :data:`LIMITS`: magnitudes beyond any bicycle and rider (a larger value is a unit slip), of the
   values and (``validate`` only: design spaces vary values, not uncertainties) of their
   uncertainties; the steer axis tilt's uncertainty at most pi;
4. :data:`SMALLEST`: masses of at least a milligram, gravity of at least 1e-6 m/s^2 (a smaller
   one is a typing slip, such as a denormal 5e-324);
5. :data:`DIVISORS`: the lengths the model divides by, at least :data:`MIN_DIVISOR`;
6. the steer axis tilt between -pi/2 and pi/2;
7. :data:`BELOW_GROUND`: centres of mass above the ground (``z < 0``, z points down);
8. the inertia tensor of each of :data:`BODIES` (:mod:`bikerider.inertia`, the one tensor check);
9. the triangle inequality of each of :data:`WHEELS`: ``I_yy <= 2 I_xx``;
10. the extent of each of :data:`WHEELS`: ``I_yy <= m r^2`` (all its mass lies within its radius)
    and ``I_xx <= m r^2`` (true of any wheel narrower than 1.4 times its radius);
11. a positive definite mass matrix ``M`` (:func:`singular_mass_matrix`): checked by the readers
    of benchmark files (:func:`bikerider.benchmark.parameters.check_mass_matrix`), by every
    :class:`~bikerider.benchmark.WhippleModel`, and by design spaces on the matrices their kernels
    compute; not by ``validate``, whose every call would then cost a model.

Rules 9 and 10 allow a violation within the values' combined standard uncertainty (printed values
are rounded), with a note.  ``validate`` reports every rule broken, each value once (the first
rule it breaks); a relation is not checked when one of its values already broke a rule.

The limits describe what no bicycle can have, not what is unusual: a bicycle on the Moon
(``g = 1.62``) or a steer axis tilted forward are modelled, not refused.
"""

from __future__ import annotations

import numpy as np

from bikerider.generated.manifest import BENCHMARK_NAMES
from bikerider.quantity import smallest_expected as quantity_smallest_expected

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
SMALLEST: dict[str, tuple[float, str]] = {**{k: (1e-6, "kg") for k in ("mR", "mB", "mH", "mF")}, "g": (1e-6, "m/s^2")}
"""Smallest positive values with their SI units (:data:`bikerider.quantity.SMALLEST`)."""
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


def smallest_expected(smallest: float, unit: str) -> str:
    """What a positive value below its :data:`SMALLEST` entry was expected to be."""
    return quantity_smallest_expected(smallest, unit)


def tensor_entries(body: str) -> tuple[str, str, str, str]:
    """The names of ``body``'s tensor entries: xx, yy, zz, xz."""
    return f"I{body}xx", f"I{body}yy", f"I{body}zz", f"I{body}xz"


def tensor_name(body: str) -> str:
    """How messages name ``body``'s inertia tensor."""
    return f"I{body} ({', '.join(tensor_entries(body))})"


WHEEL_TRIANGLE = "triangle inequality of an axisymmetric wheel"
"""Why a wheel's ``I_yy`` is at most ``2 I_xx`` (rule 9)."""


def wheel_expected(wheel: str) -> str:
    """What a wheel's ``I_yy`` was expected to be (rule 9)."""
    return f"at most 2*I{wheel}xx ({WHEEL_TRIANGLE})"


WHEEL_EXTENT = {
    "yy": "all of a wheel's mass lies within its radius",
    "xx": "the moment about a diameter of any wheel narrower than 1.4 times its radius",
}
"""Why each moment of a wheel is at most ``m r^2`` (rule 10), by axis."""


def wheel_extent_expected(wheel: str, axis: str) -> str:
    """What a wheel's ``I_yy`` (``axis = "yy"``) or ``I_xx`` was expected to be (rule 10)."""
    return f"at most m{wheel}*r{wheel}^2 ({WHEEL_EXTENT[axis]})"


SINGULAR_MASS_EXPECTED = "a positive definite mass matrix (the model is singular otherwise)"
"""What a mass matrix that is not positive definite was expected to be (rule 11)."""
MASS_MATRIX_TOLERANCE = 1e-12
"""``det M`` must exceed this times the square of M's largest entry: below, M is singular to
within the rounding of its entries."""


def singular_mass_matrix(M) -> np.ndarray:
    """Whether each 2x2 mass matrix of ``M`` (shape ``(..., 2, 2)``) fails to be positive definite
    by more than rounding (rule 11): ``M_00 > 0`` and ``det M > MASS_MATRIX_TOLERANCE max|M|^2``."""
    M = np.asarray(M, dtype=float)
    det = M[..., 0, 0] * M[..., 1, 1] - M[..., 0, 1] * M[..., 1, 0]
    return ~((M[..., 0, 0] > 0) & (det > MASS_MATRIX_TOLERANCE * np.abs(M).max(axis=(-2, -1)) ** 2))


TIED = tuple(frozenset(tensor_entries(body)) for body in BODIES) + tuple(
    frozenset((f"m{wheel}", f"r{wheel}", f"I{wheel}xx", f"I{wheel}yy")) for wheel in WHEELS
)
"""Values rules check together (each body's tensor; each wheel's mass, radius and two moments)."""

__all__ = [
    "BELOW_GROUND",
    "BELOW_GROUND_EXPECTED",
    "BODIES",
    "DIVISORS",
    "DIVISOR_EXPECTED",
    "LIMITS",
    "MASS_MATRIX_TOLERANCE",
    "MIN_DIVISOR",
    "POSITIVE",
    "SINGULAR_MASS_EXPECTED",
    "SMALLEST",
    "TIED",
    "TILT_EXPECTED",
    "WHEELS",
    "WHEEL_EXTENT",
    "WHEEL_TRIANGLE",
    "limit_expected",
    "singular_mass_matrix",
    "smallest_expected",
    "tensor_entries",
    "tensor_name",
    "wheel_expected",
    "wheel_extent_expected",
]
