"""Benchmark parameter sets of the bicycles shipped with bikerider, by name.

The BicycleParameters data (``src/bikerider/data/bicycleparameters``, BSD-2-Clause, Moore and
contributors; :mod:`bikerider.io.shipped_files` finds them) hold seven bicycles as
``<Name>Benchmark.txt``: the Meijaard et al. (2007) ``Benchmark`` bicycle and six measured ones (``Browser``, ``Browserins``, ``Fisher``, ``Rigid``,
``Silver``, ``Yellow``), and the rider ``Jason`` of Moore et al. (2009) as one rigid body seated on
the ``Browser`` and the ``Rigid``.  ::

    from bikerider.shipped import named
    browser = named("Browser")                  # the bicycle alone
    browser_jason = named("Browser", rider="Jason")
"""

from __future__ import annotations

from importlib import resources

from bikerider.benchmark import BenchmarkParameters
from bikerider.errors import InputError
from bikerider.io.benchmark_file import load_benchmark_parameters
from bikerider.io.bicycleparameters import merge_rider, read_lumped_rider
from bikerider.io.shipped_files import BICYCLES, RIDERS, bicycle_file, rider_file


def _match(name: str, choices, what: str) -> str:
    for choice in choices:
        if choice.lower() == str(name).lower():
            return choice
    raise InputError(what, name, f"one of the shipped {what}s: {', '.join(choices)}")


def named(bicycle: str, rider: str | None = None) -> BenchmarkParameters:
    """The benchmark parameters of a shipped bicycle, with a shipped rider merged in if asked.

    Parameters
    ----------
    bicycle : str
        One of :data:`BICYCLES` (case does not matter).
    rider : str, optional
        One of :data:`RIDERS`, on a bicycle it was seated on.

    Returns
    -------
    BenchmarkParameters
        With the uncertainties the files give; ``source`` names the set.

    Raises
    ------
    InputError
        An unknown name, or a rider never seated on that bicycle.
    """
    bicycle = _match(bicycle, BICYCLES, "bicycle")
    with resources.as_file(bicycle_file(bicycle)) as path:
        parameters = load_benchmark_parameters(path)
    if rider is None:
        return BenchmarkParameters(parameters.values, parameters.sigmas, f"{bicycle} (shipped BicycleParameters data)")
    rider = _match(rider, tuple(RIDERS), "rider")
    if bicycle not in RIDERS[rider]:
        raise InputError(
            "rider",
            rider,
            f"a rider seated on the {bicycle} (the shipped {rider} sits on {' and '.join(RIDERS[rider])})",
        )
    with resources.as_file(rider_file(rider, bicycle)) as path:
        lumped = read_lumped_rider(path)
    merged = merge_rider(parameters, lumped)
    return BenchmarkParameters(merged.values, merged.sigmas, f"{bicycle} + {rider} (shipped BicycleParameters data)")


__all__ = ["BICYCLES", "RIDERS", "named"]
