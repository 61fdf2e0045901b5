"""Benchmark parameters of a bicycle alone, or with a rider lumped into one rigid body.

The benchmark's rear body B is the rear frame Bf, or the rear frame and a rigid rider Br combined
as the paper does (Moore et al. 2009, Eqs. 15-16 with the parallel axis theorem, Eq. 13), via the
generated ``combination.rear_body``.  The steer axis tilt is ``lam = pi/2 - lam_ht``; wheels and
the handlebar/fork pass through.  Uncertainties are propagated at first order
(:mod:`bikerider.bicycle.propagation`, all points of the Jacobian in one batched call), treating the
bodies' values as independent.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bikerider.benchmark.parameters import BENCHMARK_NAMES, BenchmarkParameters
from bikerider.bicycle.bodies import BicycleBodies
from bikerider.bicycle.propagation import propagate
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
_USED = (*_PASS_THROUGH, "lam_ht", "IHyy", *_FRAME, *RIDER_BODY_NAMES)
"""Every value :func:`_combine` reads (seating values, for one, do not enter the benchmark values)."""


def _combine(values: dict, with_rider: bool) -> dict:
    """The benchmark values from the bodies' values: floats, or 1-D arrays of points (they broadcast)."""
    out = {name: values[name] for name in _PASS_THROUGH}
    out["lam"] = np.pi / 2 - values["lam_ht"]
    out["IHyy"] = values.get("IHyy", math.nan)
    frame = {name: values[name] for name in _FRAME if name != "IBfyy"}
    frame["IBfyy"] = values.get("IBfyy", math.nan)
    if not with_rider:
        out.update(mB=frame["mBf"], xB=frame["xBf"], zB=frame["zBf"], IBxx=frame["IBfxx"], IByy=frame["IBfyy"],
                   IBzz=frame["IBfzz"], IBxz=frame["IBfxz"])
        return out
    rider = {k: values.get(k, math.nan) for k in RIDER_BODY_NAMES}
    mB, xB, zB, IB = gen_combination.rear_body(**frame, **rider)
    out.update(mB=mB, xB=xB, zB=zB, IBxx=IB[..., 0, 0], IByy=IB[..., 1, 1], IBzz=IB[..., 2, 2], IBxz=IB[..., 0, 2])
    return out


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
    inputs = {k: q for k, q in bodies.values.items() if k in _USED}
    if rider_body is not None:
        inputs.update(rider_body.values)
    result = propagate(lambda x: _combine(x, rider_body is not None), inputs, vectorized=True)
    mapping: dict[str, Quantity | None] = {}
    for name in BENCHMARK_NAMES:
        q = result[name]
        mapping[name] = q if math.isfinite(q.value) else None
    return BenchmarkParameters.from_mapping(mapping, source=bodies.source)
