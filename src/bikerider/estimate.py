"""The whole method: bicycle and rider measurements to the benchmark parameters and the model.

``estimate(bicycle, rider)`` seats the rider on the bicycle (``bikerider.rider``), combines rider and
rear frame into the rear body (Eqs. 15-16) and runs the estimate chain's stages
(``bikerider.uncertainty.stages``, the same stages the sensitivities and Monte Carlo use) to the
benchmark parameters, then builds the Whipple model.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters, WhippleModel
from bikerider.bicycle.bodies import BicycleBodies
from bikerider.bicycle.to_benchmark import LumpedRider, bicycle_benchmark_parameters
from bikerider.errors import InputError
from bikerider.io.bicycleparameters import detect_format, load_bicycle_file, merge_rider, read_lumped_rider
from bikerider.io.chain_inputs import paper_files
from bikerider.io.toml_input import load_rider_toml
from bikerider.quantity import Quantity
from bikerider.rider.measurements import RiderMeasurements
from bikerider.rider.model import (
    STRAIGHT_LIMB_TOLERANCE,
    RiderModel,
    model_arguments,
    seat_rider,
    straight_limb_lengths,
    straight_limbs,
)
from bikerider.uncertainty import UncertaintyResult, benchmark_inputs, propagate
from bikerider.uncertainty.chain import ESTIMATE_INPUTS, benchmark_values
from bikerider.uncertainty.headline import DEFAULT_SAMPLES, DEFAULT_SEED, HeadlineUncertainty, headline_uncertainty
from bikerider.uncertainty.inputs import chain_raw_inputs

LOG = logging.getLogger(__name__)

CHAIN_INPUTS = ESTIMATE_INPUTS
"""The estimate chain's inputs from the bicycle, the rider and the mass fractions."""


@dataclass(frozen=True)
class EstimateResult:
    """Everything the method produces for one bicycle and rider.

    Attributes
    ----------
    bicycle : BicycleBodies or None
        None when the bicycle came as benchmark parameters.
    rider : RiderMeasurements, LumpedRider or None
        The rider model's measurements, a rider as one rigid body, or no rider.
    rider_model : RiderModel or None
        Grid points and mass properties of the seated rider (rider model only).
    chain_inputs : dict of str to Quantity or None
        The inputs of the generated chain, with their uncertainties (rider model only).
    parameters : BenchmarkParameters
    model : WhippleModel
    """

    bicycle: BicycleBodies | None
    rider: RiderMeasurements | LumpedRider | None
    rider_model: RiderModel | None
    chain_inputs: dict[str, Quantity] | None
    parameters: BenchmarkParameters
    model: WhippleModel
    notes: list[str] = field(default_factory=list)


def chain_inputs(bicycle: BicycleBodies, rider: RiderMeasurements) -> dict[str, Quantity]:
    """The inputs of the estimate chain, as quantities, in the chain's order.

    A missing rear-frame or handlebar I_yy is passed as NaN; it reaches only I_Byy / I_Hyy,
    which are then reported as not determined (None).
    """
    out: dict[str, Quantity] = {}
    for name in CHAIN_INPUTS:
        if name in rider.fractions:
            out[name] = Quantity(rider.fractions[name])
        elif name in rider.values:
            out[name] = rider.values[name]
        else:
            q = bicycle.get(name)
            out[name] = q if q is not None else Quantity(math.nan)
    # A limb exactly at its limit of reach: the lengths that keep its closure real (as seat_rider).
    for name, value in straight_limb_lengths(model_arguments(bicycle, rider)).items():
        out[name] = Quantity(value, out[name].sigma)
    return out


def estimate(bicycle: BicycleBodies, rider: RiderMeasurements) -> EstimateResult:
    """Run the paper's method on ``bicycle`` with ``rider`` seated on it.

    Parameters
    ----------
    bicycle : BicycleBodies
        With every seating measurement of Table 1.
    rider : RiderMeasurements

    Returns
    -------
    EstimateResult

    Raises
    ------
    InputError
        Missing seating measurements, a rider who cannot reach pedals or grips, or benchmark
        parameters no real bicycle can have.
    """
    rider_model = seat_rider(bicycle, rider)
    inputs = chain_inputs(bicycle, rider)
    nodes = benchmark_values({k: q.value for k, q in inputs.items()})
    values: dict[str, float | None] = {}
    for name in BENCHMARK_NAMES:
        value = float(nodes[name])
        values[name] = value if math.isfinite(value) else None
    bad = [n for n, v in values.items() if v is None and n not in ("IByy", "IHyy")]
    if bad:  # pragma: no cover - every input was validated; this guards the chain
        raise RuntimeError(f"the estimate chain produced non-finite {bad}")
    sigmas = {f"I{w}{a}": inputs[f"I{w}{a}"] for w in "RF" for a in ("xx", "yy")}
    mapping = {k: (Quantity(v, sigmas[k].sigma) if k in sigmas and v is not None else v) for k, v in values.items()}
    params = BenchmarkParameters.from_mapping(mapping, source=f"{bicycle.source} + {rider.source}")
    notes = list(bicycle.notes)
    if rider_model.undetermined_points:
        notes.append(f"grid points {rider_model.undetermined_points} are not placed: the hub widths were not measured.")
    if values["IByy"] is None:
        notes.append("IByy is not determined: the rear frame's I_yy was not measured.")
    if values["IHyy"] is None:
        notes.append("IHyy is not determined: the handlebar/fork I_yy was not measured.")
    for limb in straight_limbs(model_arguments(bicycle, rider)):
        notes.append(
            f"the {limb}s are straight (as long as their span within {STRAIGHT_LIMB_TOLERANCE:g}): the "
            f"{'knee' if limb == 'leg' else 'elbow'} lies on the line through the limb's ends"
        )
    LOG.info("estimated %s with %s: mB = %.3f kg", bicycle.name, rider.name, values["mB"])
    return EstimateResult(bicycle, rider, rider_model, inputs, params, WhippleModel.from_parameters(params), notes)


default_files = paper_files
"""The paper's bicycle and rider files shipped with the package."""


def estimate_default() -> EstimateResult:
    """The method on the paper's own data (the 2008 Batavus Browser and the 72 kg rider).

    Returns
    -------
    EstimateResult
        The rider model seated on the bicycle, the benchmark parameters and the Whipple model.

    Examples
    --------
    >>> result = estimate_default()
    >>> round(result.model.critical_speeds().weave, 2)
    5.66
    """
    return estimate_from_files()


def estimate_from_files(
    bicycle_path: str | Path | None = None, rider_path: str | Path | None = None, with_rider: bool = True
) -> EstimateResult:
    """Run the method on files of any supported kind (defaults: the paper's bicycle and rider).

    Parameters
    ----------
    bicycle_path, rider_path : str or Path, optional
        The bicycle and the rider file (default: the paper's).
    with_rider : bool
        False for the bicycle alone.

    Returns
    -------
    EstimateResult

    Notes
    -----
    The bicycle may be a project TOML file, a BicycleParameters ``<Name>Measured.txt`` (raw
    measurements) or ``<Name>Benchmark.txt`` (benchmark parameters).  The rider may be a project
    TOML file (the paper's rider model, seated on the bicycle's geometry) or a BicycleParameters
    lumped rider ``<Rider><Bike>Benchmark.txt`` (one rigid body, merged into the rear frame).

    Raises
    ------
    InputError, FileFormatError
        Unreadable files, or a combination that cannot work (a rider model on a bicycle given only
        as benchmark parameters, which have no geometry to seat it on).
    """
    default_bicycle, default_rider = default_files()
    # None, not an empty path, means the default: an empty --bicycle "" is an error of the reader.
    bicycle = load_bicycle_file(default_bicycle if bicycle_path is None else bicycle_path)
    bodies = bicycle if isinstance(bicycle, BicycleBodies) else None
    notes = list(bodies.notes) if bodies is not None else []
    if not with_rider:
        params = bicycle if isinstance(bicycle, BenchmarkParameters) else bicycle_benchmark_parameters(bicycle)
        return EstimateResult(bodies, None, None, None, params, WhippleModel.from_parameters(params), notes)
    rider_file = default_rider if rider_path is None else rider_path
    if detect_format(rider_file) == "lumped_rider":
        rider = read_lumped_rider(rider_file)
        params = merge_rider(bicycle, rider)
        return EstimateResult(bodies, rider, None, None, params, WhippleModel.from_parameters(params), notes)
    rider_measurements = load_rider_toml(rider_file)
    if bodies is None:
        raise InputError(
            "--rider",
            str(rider_file),
            "a lumped rider file (mB, xB, zB, IBxx, ...) or --no-rider: the bicycle was given as benchmark "
            "parameters, which have no geometry to seat the rider model on",
            str(bicycle_path),
        )
    return estimate(bodies, rider_measurements)


def uncertainty_inputs(result: EstimateResult) -> dict[str, Quantity]:
    """The chain inputs, with their uncertainties, that :func:`estimate_uncertainty` propagates.

    With the rider model or a bicycle alone, the raw measurements (pendulum periods and angles
    kept unreduced, so their correlations survive; a straight limb at the lengths that keep its
    closure real, as :func:`estimate` uses); with a lumped rider or benchmark parameters, the
    benchmark parameters and their sigmas.
    """
    if result.rider_model is not None:
        out = chain_raw_inputs(result.bicycle, result.rider)
        for name, value in straight_limb_lengths(model_arguments(result.bicycle, result.rider)).items():
            out[name] = Quantity(value, out[name].sigma)
        return out
    if result.bicycle is not None and result.rider is None:
        return chain_raw_inputs(result.bicycle)
    return benchmark_inputs(result.parameters)


def estimate_uncertainty(result: EstimateResult, speeds=None) -> UncertaintyResult:
    """First-order uncertainty of every output of ``result`` (``bikerider.uncertainty.propagate``).

    The inputs are those of :func:`uncertainty_inputs`.  Only uncertainties the input files state
    are propagated.  Where a limb is straight the first-order sigmas of everything that depends on
    its closure are not given (None, with a note): the closure's derivative is unbounded there.

    Parameters
    ----------
    result : EstimateResult
    speeds : array_like, optional
        Speeds [m/s] at which the eigenvalues get sigmas too (``.eigenvalues``).

    Returns
    -------
    UncertaintyResult
    """
    uncertainty = propagate(uncertainty_inputs(result), speeds=speeds)
    if result.rider_model is None:
        return uncertainty
    lengths = straight_limb_lengths(model_arguments(result.bicycle, result.rider))
    return _without_first_order_through(uncertainty, tuple(lengths)) if lengths else uncertainty


def _without_first_order_through(uncertainty: UncertaintyResult, limb_lengths: tuple[str, ...]) -> UncertaintyResult:
    """``uncertainty`` with no first-order sigma for outputs that depend on ``limb_lengths``."""
    columns = [uncertainty.input_names.index(n) for n in limb_lengths if n in uncertainty.input_names]
    J = uncertainty.jacobian[:, columns]
    through = {
        name for name, row in zip(uncertainty.output_names, J) if not np.all(np.isfinite(row)) or np.any(row != 0)
    }
    sigmas = {name: (None if name in through else s) for name, s in uncertainty.sigmas.items()}
    eigenvalues = uncertainty.eigenvalues
    if eigenvalues is not None:
        nan = np.full_like(eigenvalues.sigma_real, np.nan)
        eigenvalues = replace(eigenvalues, sigma_real=nan, sigma_imag=nan.copy())
    note = (
        f"first order gives no sigma for the {len(through)} values that depend on a straight limb: the "
        "closure's derivative is unbounded at full stretch (Monte Carlo gives theirs)"
    )
    return replace(uncertainty, sigmas=sigmas, eigenvalues=eigenvalues, notes=[*uncertainty.notes, note])


def estimate_headline_uncertainty(
    result: EstimateResult,
    first_order: UncertaintyResult,
    samples: int = DEFAULT_SAMPLES,
    seed: int = DEFAULT_SEED,
) -> HeadlineUncertainty:
    """The Monte Carlo sigmas ``estimate`` reports first, with ``first_order`` beside them.

    Parameters
    ----------
    result : EstimateResult
    first_order : UncertaintyResult
        :func:`estimate_uncertainty` of ``result``.
    samples, seed : int
        Monte Carlo draws of the inputs of :func:`uncertainty_inputs` (0: first order alone).

    Returns
    -------
    HeadlineUncertainty
        See :mod:`bikerider.uncertainty.headline`.
    """
    return headline_uncertainty(uncertainty_inputs(result), first_order, samples=samples, seed=seed)
