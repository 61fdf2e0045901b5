"""The estimate chain's inputs read from the project's TOML files without reducing them, and the
paper's own inputs with the accuracies it states.

:func:`raw_inputs_from_toml` keeps every pendulum period, axis angle and the pendulum stiffness as
inputs in their own right (:func:`bikerider.uncertainty.inputs.chain_raw_inputs`), so the
correlations the reductions create survive into the propagation.  :func:`paper_inputs` is the
paper's bicycle and rider with the accuracies the paper states, and - where it states none (the
rider, Table 7) - the assumed sigmas of :data:`bikerider.uncertainty.inputs.ASSUMED_RIDER_SIGMAS`,
every one reported with its source.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from bikerider.io.toml_input import load_bicycle_toml, load_rider_toml
from bikerider.quantity import Quantity
from bikerider.rider.model import seat_rider
from bikerider.uncertainty.inputs import InputSet, chain_raw_inputs, with_assumed_rider_sigmas


def paper_files() -> tuple[Path, Path]:
    """The paper's bicycle and rider files shipped with the package."""
    base = resources.files("bikerider") / "data" / "paper"
    return Path(str(base / "browser_bicycle.toml")), Path(str(base / "jason_rider.toml"))


def raw_inputs_from_toml(bicycle: str | Path, rider: str | Path | None) -> dict[str, Quantity]:
    """Every measurement of a bicycle and a rider TOML file as a chain input, unreduced (``rider``
    None: the bicycle alone, a rider of no mass; :data:`bikerider.uncertainty.inputs.NO_RIDER`).

    The rider is seated on the bicycle first (:func:`bikerider.rider.model.seat_rider`), so a
    rider who cannot reach, a knee that cannot close or a chain stay too short is refused here as
    by ``bikerider estimate``.

    Raises
    ------
    FileFormatError, InputError
        An unreadable file, a missing, malformed or impossible value (named with its table and
        key), a rider who cannot be seated.
    """
    bodies = load_bicycle_toml(bicycle)
    if rider is None:
        return chain_raw_inputs(bodies, None)
    measurements = load_rider_toml(rider)
    seat_rider(bodies, measurements)
    return chain_raw_inputs(bodies, measurements)


def paper_inputs(assume_rider_sigmas: bool = True) -> InputSet:
    """The paper's bicycle and rider, raw measurements, with the paper's stated accuracies.

    Parameters
    ----------
    assume_rider_sigmas : bool
        Give the rider's measurements the sigmas of
        :data:`~bikerider.uncertainty.inputs.ASSUMED_RIDER_SIGMAS` (the paper states none);
        otherwise they are exact.
    """
    bicycle_file, rider_file = paper_files()
    rider = load_rider_toml(rider_file)
    quantities = chain_raw_inputs(load_bicycle_toml(bicycle_file), rider)
    sources = {
        name: (f"stated: {bicycle_file.name}" if q.sigma else "exact (no sigma given)")
        for name, q in quantities.items()
    }
    for name in (*rider.values, *rider.fractions):
        sources[name] = "exact (no sigma given)" if quantities[name].sigma == 0 else f"stated: {rider_file.name}"
    if assume_rider_sigmas:
        quantities = with_assumed_rider_sigmas(quantities, sources)
    return InputSet(quantities, sources, "Batavus Browser and rider (Moore et al. 2009)")


__all__ = ["paper_files", "paper_inputs", "raw_inputs_from_toml"]
