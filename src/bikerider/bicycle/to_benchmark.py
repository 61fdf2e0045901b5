"""Benchmark parameters of a bicycle alone, or with a rider lumped into one rigid body.

The benchmark's rear body B is the rear frame Bf, or the rear frame and a rigid rider Br combined
as the paper does (Moore et al. 2009, Eqs. 15-16 with the parallel axis theorem, Eq. 13): the
generated stage ``rear_body``.  The steer axis tilt is ``lam = pi/2 - lam_ht`` (the stage
``steer_axis``); wheels and the handlebar/fork pass through.

Uncertainties are first order, treating the bodies' values as independent, through the stages'
generated Jacobians (the uncertainty engine, :mod:`bikerider.engine`): every value but the rear
body's passes through with its own sigma (``lam`` takes that of ``lam_ht``: the slope is -1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from bikerider.benchmark.parameters import BENCHMARK_NAMES, BenchmarkParameters
from bikerider.bicycle.bodies import BicycleBodies
from bikerider.engine import GeneratedStage, arguments, first_order
from bikerider.errors import ErrorCollector, InputError
from bikerider.generated.manifest import STAGES
from bikerider.inertia import inertia_problem
from bikerider.notes import note
from bikerider.quantity import Quantity, check_magnitude, check_positive

_FRAME = tuple(a for a in arguments("combination.rear_body") if "Bf" in a)
"""The rear frame (``mBf, xBf, zBf, IBfxx, ...``): the first body of the generated ``rear_body``."""
RIDER_BODY_NAMES: tuple[str, ...] = tuple(a for a in arguments("combination.rear_body") if "Br" in a)
"""A rigid rider: mass, centre of mass and inertia tensor (benchmark frame, tensor entry Ixz)."""
_REAR_BODY = STAGES["rear_body"]["outputs"]
"""The rear body B (``mB, xB, zB, IBxx, IByy, IBzz, IBxz``)."""
_STAGES = (GeneratedStage("rear_body"), GeneratedStage("steer_axis"))

_LIMITS: dict[str, tuple[float, str]] = {
    "mBr": (500.0, "kg"),
    "xBr": (5.0, "m"),
    "zBr": (5.0, "m"),
    **{k: (1e4, "kg m^2") for k in RIDER_BODY_NAMES if k.startswith("I")},
}
"""Largest plausible magnitudes of a rigid rider: a larger value is a unit slip."""


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
        errors = ErrorCollector()
        failed: set[str] = set()
        for key in RIDER_BODY_NAMES:
            if key not in self.values and key != "IBryy":
                errors.add(
                    InputError(
                        key,
                        "missing",
                        "a value: the lumped rider needs its mass, centre of mass and in-plane inertia",
                        self.source,
                    )
                )
                failed.add(key)
        for key, q in self.values.items():
            limit = _LIMITS.get(key)
            try:
                if key in ("mBr", "IBrxx", "IBrzz", "IBryy"):
                    message = check_positive(key, q, *limit, self.source)  # type: ignore[misc]
                    if message:
                        note(message)
                elif limit is not None:
                    check_magnitude(key, q.value, *limit, self.source)
                    check_magnitude(f"{key} uncertainty", q.sigma, *limit, self.source)
            except InputError as exc:
                errors.add(exc)
                failed.add(key)
        if "zBr" not in failed and not self.values["zBr"].value < 0:
            errors.add(
                InputError(
                    "zBr",
                    self.values["zBr"].value,
                    "a negative value: z points down in the benchmark "
                    "frame, so a centre of mass above the ground has z < 0",
                    self.source,
                )
            )
        if not failed.intersection(("IBrxx", "IBrzz", "IBrxz")):
            xx, zz, xz = (self.values[k].value for k in ("IBrxx", "IBrzz", "IBrxz"))
            if inertia_problem(xx, None, zz, xz) is not None:  # the in-plane block, without IBryy
                errors.add(
                    InputError(
                        "IBrxz",
                        xz,
                        f"|IBrxz| < sqrt(IBrxx * IBrzz) = {math.sqrt(xx * zz):.6g} (a positive definite inertia tensor)",
                        self.source,
                    )
                )
        errors.raise_any()


_PASS_THROUGH = tuple(name for name in BENCHMARK_NAMES if name not in _REAR_BODY and name != "lam")
"""Benchmark values a bicycle's bodies give as they are (the wheels, the handlebar/fork, g)."""


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
    mapping: dict[str, Quantity | None] = {name: values.get(name) for name in _PASS_THROUGH}
    if rider_body is None:
        mapping.update(zip(_REAR_BODY, (values.get(name) for name in _FRAME)))
        mapping["lam"] = first_order(_STAGES[1:], {"lam_ht": values["lam_ht"]}).quantity("lam")
    else:
        # IBfyy or IBryy may be missing: they enter IByy alone, which is then not determined.
        inputs = {name: values.get(name) or Quantity(math.nan) for name in _FRAME}
        inputs.update({name: rider_body.values.get(name) or Quantity(math.nan) for name in RIDER_BODY_NAMES})
        inputs["lam_ht"] = values["lam_ht"]
        for name, q in first_order(_STAGES, inputs).quantities((*_REAR_BODY, "lam")).items():
            mapping[name] = q if math.isfinite(q.value) else None
    return BenchmarkParameters.from_mapping(mapping, source=bodies.source)


def bodies_from_benchmark(parameters: BenchmarkParameters) -> BicycleBodies:
    """The benchmark parameters read back as :class:`BicycleBodies` (rear body B as the frame)."""
    v, s = parameters.values, parameters.sigmas
    renames = dict(zip(_REAR_BODY, _FRAME))
    values: dict[str, Quantity] = {}
    for name in BENCHMARK_NAMES:
        if v[name] is None:
            continue
        values[renames.get(name, name)] = Quantity(float(v[name]), s.get(name, 0.0))  # type: ignore[arg-type]
    lam = values.pop("lam")
    values["lam_ht"] = Quantity(math.pi / 2 - lam.value, lam.sigma)
    return BicycleBodies(values, source=parameters.source or "<memory>")


def merge_rider(bicycle: BicycleBodies | BenchmarkParameters, rider: LumpedRider) -> BenchmarkParameters:
    """Benchmark parameters with the lumped ``rider`` merged into the rear body (Eqs. 15-16).

    Parameters
    ----------
    bicycle : BicycleBodies or BenchmarkParameters
        For benchmark parameters, their rear body B is taken as the rear frame.
    rider : LumpedRider
    """
    if isinstance(bicycle, BicycleBodies):
        return bicycle_benchmark_parameters(bicycle, rider)
    return bicycle_benchmark_parameters(bodies_from_benchmark(bicycle), rider)
