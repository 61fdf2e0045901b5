"""Read the 25 benchmark parameters from a TOML file or a ``name = value+/-sigma`` text file."""

from __future__ import annotations

import json
import math
from pathlib import Path

from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters
from bikerider.benchmark.parameters import check_mass_matrix, uncertainty_notes
from bikerider.errors import MISSING, ErrorCollector, FileFormatError, InputError
from bikerider.io.bicycleparameters import read_benchmark_file
from bikerider.io.export import JSON_FORMAT
from bikerider.io.input_file import read_input_text
from bikerider.io.toml_input import read_toml
from bikerider.notes import note
from bikerider.quantity import DEG, Quantity, parse_quantity

DESCRIPTIVE_KEYS = ("name", "source", "notes")
"""Keys of a benchmark table that describe it and are not read."""
GAP_TABLES = ("rider", "upper_body", "grips", "plausible")
"""Tables of a ``bikerider gap --model`` file beside ``[benchmark]``: read by ``gap``, left out
(with a note) where only the benchmark parameters are read."""


def load_benchmark_parameters(path: str | Path) -> BenchmarkParameters:
    """Benchmark parameters from ``path``.

    TOML: the Meijaard names at top level or under ``[benchmark]``; ``lam_deg`` may replace ``lam``.
    JSON: the document :func:`bikerider.io.export.parameters_to_json` writes (``values`` and
    ``sigmas`` by Meijaard name, SI units).
    Text: one ``name = value+/-sigma`` per line (BicycleParameters ``<Name>Benchmark.txt``), read by
    :func:`bikerider.io.bicycleparameters.read_benchmark_file`, which explains what it does with the
    extra entries BicycleParameters writes.

    Raises
    ------
    FileFormatError, InputError
        An unreadable file; unknown tables or names, ``lam`` beside ``lam_deg``, missing or
        impossible values: every one of them at once.
    """
    if Path(path).suffix.lower() == ".json":
        return read_parameters_json(path)
    if Path(path).suffix.lower() == ".toml":
        data = read_toml(path)
        if "benchmark" not in data:
            return parameters_from_table(data, str(path))
        errors = ErrorCollector()
        for key, value in data.items():
            if key in GAP_TABLES:
                note(f"{path}: [{key}] left out: only [benchmark] is read here (bikerider gap --model reads it)")
            elif key != "benchmark" and key not in DESCRIPTIVE_KEYS:
                errors.add(
                    InputError(
                        key,
                        value,
                        "[benchmark] beside "
                        + ", ".join(DESCRIPTIVE_KEYS + GAP_TABLES)
                        + " (no other table or key in a benchmark parameter file)",
                        str(path),
                    )
                )
        parameters = None
        with errors.check():
            parameters = parameters_from_table(data["benchmark"], str(path))
        errors.raise_any()
        return parameters  # type: ignore[return-value]
    return read_benchmark_file(path).parameters


def read_parameters_json(path: str | Path) -> BenchmarkParameters:
    """Benchmark parameters from the JSON :func:`bikerider.io.export.parameters_to_json` writes.

    Raises
    ------
    FileFormatError, InputError
        Not JSON, not that document, or values no bicycle can have (every one at once).
    """
    text = read_input_text(path)
    try:
        document = json.loads(text)
    except json.JSONDecodeError as exc:
        raise FileFormatError(str(path), f"not JSON: {exc.msg}", exc.lineno) from None
    if not isinstance(document, dict) or document.get("format") != JSON_FORMAT:
        raise FileFormatError(
            str(path),
            f'not a parameter file: expected a JSON object with "format": "{JSON_FORMAT}" (bikerider convert)',
        )
    values, sigmas = document.get("values"), document.get("sigmas", {})
    if not isinstance(values, dict) or not isinstance(sigmas, dict):
        raise FileFormatError(str(path), 'expected "values" and "sigmas" objects of benchmark names')
    errors = ErrorCollector()
    table: dict[str, object] = {}
    for key in sorted(set(sigmas) - set(values)):
        errors.add(InputError(f"sigmas.{key}", sigmas[key], "a sigma of a name in values", str(path)))
    for key, value in values.items():
        if value is None:
            continue
        table[key] = {"value": value, "sigma": sigmas.get(key, 0.0)}
    parameters = None
    with errors.check():
        parameters = parameters_from_table(table, str(path))
    errors.raise_any()
    return parameters  # type: ignore[return-value]


def parameters_from_table(table: object, source: str) -> BenchmarkParameters:
    """Benchmark parameters from a TOML table of Meijaard names (``lam_deg`` may replace ``lam``;
    ``name``, ``source`` and ``notes`` are descriptive and skipped).

    Every error of the table is reported at once: unknown keys, values that cannot be read, both
    ``lam`` and ``lam_deg``, and the values no bicycle can have.  A ``lam_deg`` that looks like
    radians (0 < lam_deg <= pi: a steer axis tilt of at most 3.14 degrees) is accepted with a note.
    """
    if not isinstance(table, dict):
        raise InputError("benchmark", table, "a table of benchmark parameters", source)
    errors = ErrorCollector()
    unreadable: set[str] = set()
    values: dict[str, Quantity] = {}
    if "lam" in table and "lam_deg" in table:
        errors.add(
            InputError(
                "lam_deg",
                table["lam_deg"],
                f"either lam (radians) or lam_deg (degrees), not both (lam = {table['lam']})",
                source,
            )
        )
        unreadable.add("lam")
    for key, raw in table.items():
        if key in DESCRIPTIVE_KEYS:
            continue
        name = "lam" if key == "lam_deg" else key
        if name not in BENCHMARK_NAMES:
            errors.add(
                InputError(key, raw, f"one of the benchmark names {', '.join(BENCHMARK_NAMES)} (or lam_deg)", source)
            )
            continue
        if name in unreadable:
            continue
        try:
            q = parse_quantity(raw, key, source)
        except InputError as exc:
            errors.add(exc)
            unreadable.add(name)
            continue
        if key == "lam_deg":
            if 0 < q.value <= math.pi:
                note(
                    f"{source}: lam_deg = {q.value:g} looks like radians ({q.value:g} rad = "
                    f"{math.degrees(q.value):.4g} deg); taken as degrees, a steer axis tilt of {q.value:g} deg"
                )
            q = q.scaled(DEG)
        values[name] = q
    try:
        parameters = BenchmarkParameters.from_mapping(values, source)
        check_mass_matrix(parameters)
    except InputError as exc:
        for error in getattr(exc, "errors", [exc]):
            if not (error.name in unreadable and error.value == MISSING):  # named already, as unreadable
                errors.add(error)
    errors.raise_any()
    for message in uncertainty_notes(parameters):
        note(message)
    return parameters
