"""Where the shipped BicycleParameters parameter sets are, and their names (standard library only).

The data (``src/bikerider/data/bicycleparameters``, BSD-2-Clause, Moore and contributors) hold each
bicycle as ``bicycles/<Name>/Parameters/<Name>Benchmark.txt`` and each lumped rider as
``riders/<Rider>/Parameters/<Rider><Bicycle>Benchmark.txt`` (seated on that bicycle): the names are
those of the files, so a set added to the data is known without a list to edit.  Light enough for
the command line's ``--help`` (:mod:`bikerider.shipped` reads the files).
"""

from __future__ import annotations

from importlib import resources
from importlib.abc import Traversable


def data_folder() -> Traversable:
    """The shipped BicycleParameters data."""
    return resources.files("bikerider") / "data" / "bicycleparameters"


def bicycle_file(bicycle: str) -> Traversable:
    """``<Name>Benchmark.txt`` of a shipped bicycle."""
    return data_folder() / "bicycles" / bicycle / "Parameters" / f"{bicycle}Benchmark.txt"


def rider_file(rider: str, bicycle: str) -> Traversable:
    """``<Rider><Bicycle>Benchmark.txt``: a shipped lumped rider seated on a shipped bicycle."""
    return data_folder() / "riders" / rider / "Parameters" / f"{rider}{bicycle}Benchmark.txt"


def _bicycles() -> tuple[str, ...]:
    return tuple(sorted(f.name for f in (data_folder() / "bicycles").iterdir() if bicycle_file(f.name).is_file()))


def _riders() -> dict[str, tuple[str, ...]]:
    out = {}
    for folder in sorted((data_folder() / "riders").iterdir(), key=lambda f: f.name):
        seated = tuple(b for b in BICYCLES if rider_file(folder.name, b).is_file())
        if seated:
            out[folder.name] = seated
    return out


BICYCLES = _bicycles()
"""Names of the shipped bicycles."""
RIDERS = _riders()
"""Shipped lumped riders and the bicycles each has been seated on."""

__all__ = ["BICYCLES", "RIDERS", "bicycle_file", "data_folder", "rider_file"]
