"""Benchmark parameters of a bicycle alone, or with a rider lumped into one rigid body.

The benchmark's rear body B is the rear frame Bf, or the rear frame and a rigid rider Br combined
as the paper does (Moore et al. 2009, Eqs. 15-16 with the parallel axis theorem, Eq. 13), via the
generated ``combination.rear_body``.  The steer axis tilt is ``lam = pi/2 - lam_ht``; wheels and
the handlebar/fork pass through.

Uncertainties are first order, treating the bodies' values as independent.  Every value but the
rear body's passes through with its own sigma (``lam`` takes that of ``lam_ht``: the slope is -1).
The rear body's sigmas come from the closed-form Jacobian of Eqs. 15-16 (the generated
``sensitivities.rear_body_jacobian``, the one the uncertainty stages use; its plain-float twin, as
for ``rear_body``, since one bicycle is merged at a time) at the nominal point:
``sigma_i = sqrt(sum_j (J_ij sigma_j)^2)``.  That is what
:func:`bikerider.bicycle.propagation.propagate` approximates by central differences, without its
``2 k + 1`` evaluations; ``tests/test_to_benchmark.py`` checks the two against each other.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from bikerider.benchmark.parameters import BenchmarkParameters
from bikerider.bicycle.bodies import BicycleBodies
from bikerider.errors import InputError
from bikerider.generated import combination as gen_combination
from bikerider.quantity import Quantity, check_magnitude

RIDER_BODY_NAMES: tuple[str, ...] = ("mBr", "xBr", "zBr", "IBrxx", "IBryy", "IBrzz", "IBrxz")
"""A rigid rider: mass, centre of mass and inertia tensor (benchmark frame, tensor entry Ixz)."""

_LIMITS: dict[str, tuple[float, str]] = {
    "mBr": (500.0, "kg"), "xBr": (5.0, "m"), "zBr": (5.0, "m"),
    **{k: (1e4, "kg m^2") for k in ("IBrxx", "IBryy", "IBrzz", "IBrxz")},
}
"""Largest plausible magnitudes of a rigid rider: a larger value is a unit slip."""

_PASS_THROUGH = ("w", "c", "g", "rR", "mR", "IRxx", "IRyy", "xH", "zH", "mH", "IHxx", "IHzz", "IHxz",
                 "rF", "mF", "IFxx", "IFyy")


@dataclass(frozen=True)
class LumpedRider:
    """A rider as one rigid body in the benchmark frame.

    Attributes
    ----------
    values : dict of str to Quantity
        :data:`RIDER_BODY_NAMES` (``IBryy`` may be missing: then the combined ``IByy`` is not
        determined).
    source : str
    name : str
    """

    values: dict[str, Quantity]
    source: str = "<memory>"
    name: str = "rider"

    def __post_init__(self) -> None:
        for key in RIDER_BODY_NAMES:
            if key not in self.values and key != "IBryy":
                raise InputError(key, "missing", "a value: the lumped rider needs its mass, centre of mass "
                                 "and in-plane inertia", self.source)
        for key in ("mBr", "IBrxx", "IBrzz", "IBryy"):
            if key in self.values and not self.values[key].value > 0:
                raise InputError(key, self.values[key].value, "a positive value", self.source)
        for key, (limit, unit) in _LIMITS.items():
            q = self.values.get(key)
            if q is not None and not (abs(q.value) <= limit and abs(q.sigma) <= limit):  # else both pass
                check_magnitude(key, self.values[key].value, limit, unit, self.source)
                check_magnitude(f"{key} uncertainty", self.values[key].sigma, limit, unit, self.source)
        if not self.values["zBr"].value < 0:
            raise InputError("zBr", self.values["zBr"].value, "a negative value: z points down in the benchmark "
                             "frame, so a centre of mass above the ground has z < 0", self.source)
        xx, zz, xz = (self.values[k].value for k in ("IBrxx", "IBrzz", "IBrxz"))
        if xx * zz - xz**2 <= 0:
            raise InputError("IBrxz", xz, f"|IBrxz| < sqrt(IBrxx * IBrzz) = {math.sqrt(xx * zz):.6g} "
                             "(a positive definite inertia tensor)", self.source)


_FRAME = ("mBf", "xBf", "zBf", "IBfxx", "IBfyy", "IBfzz", "IBfxz")
"""The rear frame; with :data:`RIDER_BODY_NAMES` the arguments of the generated ``rear_body``, in the
order of the columns of ``rear_body_jacobian``."""
_REAR_BODY = ("mB", "xB", "zB", "IBxx", "IByy", "IBzz", "IBxz")
"""Outputs of the rear body, in the order of the rows of ``rear_body_jacobian``."""


def _rear_body(frame: Mapping[str, Quantity], rider: Mapping[str, Quantity]) -> dict[str, Quantity | None]:
    """The rear body B of the rear frame in ``frame`` and the rider in ``rider``, with first-order sigmas.

    ``IBfyy`` or ``IBryy`` may be missing: they enter ``IByy`` alone, which is then ``None``; the
    Jacobian's other rows do not involve them.
    """
    from bikerider.generated import sensitivities as gen_sensitivities  # large: imported when a rider is merged

    nominal: dict[str, float] = {}
    sigma: list[float] = []
    for names, source in ((_FRAME, frame), (RIDER_BODY_NAMES, rider)):
        for name in names:
            q = source.get(name)
            nominal[name] = math.nan if q is None else q.value
            sigma.append(q.sigma if q is not None and q.sigma > 0 else 0.0)
    # One bicycle: the plain-float twins of the generated functions (NumPy's per-call overhead
    # would be most of the time on single values).
    mB, xB, zB, IB = gen_combination.rear_body_scalar(**nominal)
    jacobian = gen_sensitivities.rear_body_jacobian_scalar(**nominal)
    values = (mB, xB, zB, IB[0][0], IB[1][1], IB[2][2], IB[0][2])
    result: dict[str, Quantity | None] = {}
    for name, value, row in zip(_REAR_BODY, values, jacobian):
        # As propagate does, a slope that is not finite contributes nothing (none is for real bodies).
        terms = [d * s for d, s in zip(row, sigma) if s and math.isfinite(d)]
        variance = math.fsum(t * t for t in terms)  # t * t, not t ** 2: inf rather than OverflowError
        result[name] = Quantity(value, math.sqrt(variance)) if math.isfinite(value) else None
    return result


def bicycle_benchmark_parameters(bodies: BicycleBodies, rider_body: LumpedRider | None = None) -> BenchmarkParameters:
    """The 26 benchmark values of ``bodies``, with ``rider_body`` merged into the rear body.

    Parameters
    ----------
    bodies : BicycleBodies
    rider_body : LumpedRider, optional
        A rigid rider; ``None`` for the bicycle alone (B is the rear frame).

    Returns
    -------
    BenchmarkParameters
        With first-order standard uncertainties; ``IByy``/``IHyy`` are ``None`` when not
        determined.
    """
    values = bodies.values
    mapping: dict[str, Quantity | None] = {name: values[name] for name in _PASS_THROUGH}
    lam_ht = values["lam_ht"]
    mapping["lam"] = Quantity(math.pi / 2 - lam_ht.value, lam_ht.sigma)
    mapping["IHyy"] = values.get("IHyy")
    if rider_body is None:
        mapping.update(zip(_REAR_BODY, (values.get(name) for name in _FRAME)))
    else:
        mapping.update(_rear_body(values, rider_body.values))
    return BenchmarkParameters.from_mapping(mapping, source=bodies.source)
