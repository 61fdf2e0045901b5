"""Read the model of a gap diagnosis: benchmark parameters, the rider, and what is plausible.

``--model`` takes a TOML file (``[benchmark]`` with optional ``[rider]``, ``[upper_body]``,
``[grips]`` and ``[plausible]`` tables) or a BicycleParameters ``<Name>Benchmark.txt``; ``--rider``
adds a lumped rider.  :mod:`bikerider.gap.candidates.nominal` describes the tables and the default rider
geometry.

``[plausible]`` states what this bicycle's own knowledge says a candidate's parameter may be,
replacing the literature range of :mod:`bikerider.gap.candidates.effects` for this bicycle::

    [plausible]
    I_steer = { range = [0.0, 0.1], why = "motor rotor through the gearbox; front-assembly inertia 0-0.1 kg m^2" }
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

from bikerider.benchmark import BenchmarkParameters
from bikerider.errors import InputError
from bikerider.gap.candidates.effect_model import GRIP_KEYS, UPPER_BODY_KEYS, RiderGeometry
from bikerider.gap.candidates.effects import EFFECTS
from bikerider.gap.candidates.nominal import RIDER_KEYS, GapModelInput
from bikerider.io.benchmark_file import load_benchmark_parameters, parameters_from_table
from bikerider.io.bicycleparameters import merge_rider, read_lumped_rider
from bikerider.io.input_file import checked_input_file
from bikerider.io.toml_input import read_toml
from bikerider.quantity import Quantity, parse_quantity

MAX_MODEL_BYTES = 1_000_000
"""Largest model or rider file read [bytes] (they hold a few dozen values: a few kB)."""


def load_model(
    path: str | Path, rider_path: str | Path | None = None, *, rider_rel_sigma: float = 0.0
) -> GapModelInput:
    """Read the model file (and a lumped rider); build the default geometry where none is given.

    ``rider_rel_sigma`` gives the lumped rider's values a relative standard uncertainty where its
    file states none (BicycleParameters rider files state none).

    Raises
    ------
    FileFormatError
        Unreadable file.
    InputError
        A missing or impossible value (names the file, the key and what was expected).
    """

    path = checked_input_file(path, MAX_MODEL_BYTES, "model file")
    source = str(path)
    tables: dict[str, object] = {}
    if path.suffix.lower() == ".toml":
        data = read_toml(path)
        _check_tables(data, source)
        extra = {k: data[k] for k in MODEL_TABLES[1:] if k in data}
        if extra and "benchmark" not in data:
            raise InputError(
                "benchmark",
                "missing",
                "a [benchmark] table when the file also has " + ", ".join(f"[{k}]" for k in extra),
                source,
            )
        tables = extra
        parameters = parameters_from_table(data.get("benchmark", data), source)
    else:
        parameters = load_benchmark_parameters(path)
    rider = _table_numbers(tables["rider"], "rider", RIDER_KEYS, source) if "rider" in tables else None
    if rider_path is not None:
        if rider is not None:
            raise InputError("rider", str(rider_path), "one rider: the model file already has a [rider] table", source)
        rider_path = checked_input_file(rider_path, MAX_MODEL_BYTES, "rider file")
        parameters, rider = _merge_rider(parameters, rider_path, rider_rel_sigma)
    if rider is not None and not (rider["mass"] > 0 and rider["mass"] < float(parameters["mB"])):  # type: ignore[operator]
        raise InputError(
            "rider.mass", rider["mass"], f"a positive mass below the rear body's {parameters['mB']} kg", source
        )
    geometry = GapModelInput.default_geometry(parameters, rider)
    if "upper_body" in tables:
        upper = _table_quantities(tables["upper_body"], "upper_body", UPPER_BODY_KEYS, source)
        geometry = RiderGeometry(
            {k: q.value for k, q in upper.items()},
            geometry.grips,
            geometry.notes + "; upper body from the model file",
            _given_uncertainty(geometry.uncertainty, "upper_body", upper),
        )
    if "grips" in tables:
        grips = _table_quantities(tables["grips"], "grips", GRIP_KEYS, source)
        geometry = RiderGeometry(
            geometry.upper_body,
            {k: q.value for k, q in grips.items()},
            geometry.notes + "; grips from the model file",
            _given_uncertainty(geometry.uncertainty, "grips", grips),
        )
    plausible = _plausible(tables["plausible"], source) if "plausible" in tables else {}
    return GapModelInput(
        parameters, geometry, rider, source + (f" + rider {rider_path}" if rider_path else ""), plausible
    )


MODEL_TABLES = ("benchmark", "rider", "upper_body", "grips", "plausible")
"""The tables of a TOML model file."""


def _check_tables(data: dict, source: str) -> None:
    """With a ``[benchmark]`` table, every other top-level key is one of :data:`MODEL_TABLES` (a
    file without one is a flat table of benchmark names, checked name by name)."""
    if "benchmark" not in data:
        return
    for key, value in data.items():
        if key not in MODEL_TABLES:
            raise InputError(key, value, "one of the tables " + ", ".join(f"[{k}]" for k in MODEL_TABLES), source)


def _plausible(table: object, source: str) -> dict[str, tuple[float, float, str]]:
    """``[plausible]``: ``name = { range = [lo, hi], why = "..." }`` for candidate parameters."""

    known = {p.name for e in EFFECTS.values() for p in e.parameters}
    if not isinstance(table, dict):
        raise InputError("plausible", table, "a table of parameter = { range = [low, high], why = ... }", source)
    out = {}
    for name, entry in table.items():
        if name not in known:
            raise InputError(
                f"plausible.{name}",
                entry,
                "a fitted parameter of a candidate (" + ", ".join(sorted(known)) + ")",
                source,
            )
        if not (isinstance(entry, dict) and set(entry) <= {"range", "why"} and "range" in entry):
            raise InputError(f"plausible.{name}", entry, '{ range = [low, high], why = "..." }', source)
        rng = entry["range"]
        if not (
            isinstance(rng, list)
            and len(rng) == 2
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in rng)
            and rng[0] <= rng[1]
        ):
            raise InputError(f"plausible.{name}.range", rng, "two finite numbers [low, high] with low <= high", source)
        why = entry.get("why", "")
        if not isinstance(why, str):
            raise InputError(f"plausible.{name}.why", why, "a text", source)
        out[name] = (float(rng[0]), float(rng[1]), why or f"{source} [plausible]")
    return out


def _merge_rider(
    parameters: BenchmarkParameters, rider_path: Path, rel_sigma: float = 0.0
) -> tuple[BenchmarkParameters, dict[str, float]]:

    lumped = read_lumped_rider(rider_path)
    if rel_sigma > 0:
        lumped = replace(
            lumped,
            values={
                k: q if q.sigma > 0 else Quantity(q.value, rel_sigma * abs(q.value)) for k, q in lumped.values.items()
            },
        )
    values = {k: q.value for k, q in lumped.values.items()}
    rider = {
        "mass": values["mBr"],
        "x": values["xBr"],
        "z": values["zBr"],
        "Ixx": values["IBrxx"],
        "Ixz": values["IBrxz"],
        "Izz": values["IBrzz"],
    }
    return merge_rider(parameters, lumped), rider


def _given_uncertainty(
    default: dict[str, dict[str, float]], table: str, given: dict[str, Quantity]
) -> dict[str, dict[str, float]]:
    """The geometry's sources of uncertainty once a model file gives table ``[table]``: the default's
    sources that move its values are dropped, and each value the file gives as ``"value +/- sigma"`` is
    a source of its own (``"upper_body.z_lean"``); a plain number is taken as known."""
    out = {name: shift for name, shift in default.items() if not set(shift) & set(given)}
    out.update({f"{table}.{key}": {key: q.sigma} for key, q in given.items() if q.sigma > 0})
    return out


def _table_numbers(table: object, name: str, keys: tuple[str, ...], source: str) -> dict[str, float]:
    """The numbers of a model file's table ``[name]`` (their values; see :func:`_table_quantities`)."""
    return {key: q.value for key, q in _table_quantities(table, name, keys, source).items()}


def _table_quantities(table: object, name: str, keys: tuple[str, ...], source: str) -> dict[str, Quantity]:
    """The numbers of a model file's table ``[name]``: exactly ``keys``, each a number or ``"v +/- sigma"``."""
    if not isinstance(table, dict):
        raise InputError(name, table, "a table", source)
    unknown = sorted(set(table) - set(keys))
    if unknown:
        raise InputError(f"{name}.{unknown[0]}", table[unknown[0]], "one of " + ", ".join(keys), source)
    out = {}
    for key in keys:
        if key not in table:
            raise InputError(f"{name}.{key}", "missing", "a value", source)
        out[key] = parse_quantity(table[key], f"{name}.{key}", source)
    return out
