"""Measurements as the chain's nodes, with where each uncertainty comes from.

:func:`chain_raw_inputs` keeps every pendulum period, axis angle and the pendulum stiffness of a
bicycle as inputs in their own right, so the correlations the reductions create (one ``k_t`` in
every torsional inertia, one set of periods in all three rear-frame tensor entries, the wheel's
mass in its compound pendulum) survive into the propagation.  Where a file states no accuracy (the
paper's rider, Table 7) :func:`with_assumed_rider_sigmas` gives the assumed sigmas of
:data:`ASSUMED_RIDER_SIGMAS`, every one reported with its source.  Reading the files is
:mod:`bikerider.io.chain_inputs`' job (``paper_inputs``, ``raw_inputs_from_toml``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from bikerider.quantity import DEG, Quantity
from bikerider.rider.measurements import RIDER_NAMES

ASSUMED_RIDER_SIGMAS: dict[str, tuple[float, str]] = {
    # The paper states no accuracy for Table 7 ("measured as accurately as possible with basic
    # tools"); these are assumptions, reported as such wherever they are used.
    **{
        name: (0.01, "assumed: one unit of the last digit Table 7 prints (0.01 m)")
        for name in RIDER_NAMES
        if name not in ("mBr", "lam_fl")
    },
    "lam_fl": (1.0 * DEG, "assumed: 1 deg, the accuracy Table 4 states for angles read off photographs"),
    "mBr": (0.1, "assumed: one unit of the last digit Table 8 prints (0.1 kg)"),
}


@dataclass(frozen=True)
class InputSet:
    """Chain inputs with uncertainties and where each uncertainty comes from.

    Attributes
    ----------
    quantities : dict of str to Quantity
        Node name to value and standard uncertainty (SI, radians).
    sources : dict of str to str
        Node name to a note on where its sigma comes from.
    name : str
        A human name, for reports.
    """

    quantities: dict[str, Quantity]
    sources: dict[str, str]
    name: str = "inputs"


NO_RIDER: dict[str, Quantity] = {
    name: Quantity(0.0) for name in ("mBr_sum", "xBr", "zBr", "IBrxx", "IBryy", "IBrzz", "IBrxz")
}
"""The rear body's rider nodes for a bicycle alone: a rider of no mass (the rear body is the frame)."""


def chain_raw_inputs(bicycle, rider=None) -> dict[str, Quantity]:
    """Chain inputs of a bicycle (:class:`~bikerider.bicycle.BicycleBodies`) and a rider
    (:class:`~bikerider.rider.RiderMeasurements`, or None for the bicycle alone), with every
    reduced value replaced by the raw measurements it came from (``BicycleBodies.raw_inputs``)."""
    out = {name: q for name, q in bicycle.values.items() if name not in bicycle.reduced}
    out.update(bicycle.raw_inputs)
    if rider is None:
        out.update(NO_RIDER)
        return out
    out.update(rider.values)
    out.update({name: Quantity(value) for name, value in rider.fractions.items()})
    return out


def benchmark_inputs(parameters) -> dict[str, Quantity]:
    """The benchmark parameters (a :class:`bikerider.benchmark.BenchmarkParameters`) as chain inputs,
    each with its sigma; undetermined values (``IByy``/``IHyy`` = None) are left out."""
    return {
        name: Quantity(float(value), float(parameters.sigmas.get(name, 0.0)))
        for name, value in parameters.values.items()
        if value is not None
    }


def with_assumed_rider_sigmas(quantities: Mapping[str, Quantity], sources: dict[str, str]) -> dict[str, Quantity]:
    """Give rider measurements without a sigma the assumed one (and say so in ``sources``)."""
    out = dict(quantities)
    for name, (sigma, note) in ASSUMED_RIDER_SIGMAS.items():
        if name in out and out[name].sigma == 0:
            out[name] = Quantity(out[name].value, sigma)
            sources[name] = note
    return out
