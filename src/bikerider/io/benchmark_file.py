"""Read the 25 benchmark parameters from a TOML file or a ``name = value+/-sigma`` text file."""

from __future__ import annotations

from pathlib import Path

from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters
from bikerider.errors import InputError
from bikerider.io.bicycleparameters import read_benchmark_file
from bikerider.io.toml_input import read_toml
from bikerider.quantity import DEG, Quantity, parse_quantity


def load_benchmark_parameters(path: str | Path) -> BenchmarkParameters:
    """Benchmark parameters from ``path``.

    TOML: the Meijaard names at top level or under ``[benchmark]``; ``lam_deg`` may replace ``lam``.
    Text: one ``name = value+/-sigma`` per line (BicycleParameters ``<Name>Benchmark.txt``), read by
    :func:`bikerider.io.bicycleparameters.read_benchmark_file`, which explains what it does with the
    extra entries BicycleParameters writes.
    """
    path = Path(path)
    if path.suffix.lower() == ".toml":
        data = read_toml(path)
        return parameters_from_table(data.get("benchmark", data), str(path))
    return read_benchmark_file(path).parameters


def parameters_from_table(table: object, source: str) -> BenchmarkParameters:
    """Benchmark parameters from a TOML table of Meijaard names (``lam_deg`` may replace ``lam``;
    ``name``, ``source`` and ``notes`` are descriptive and skipped)."""
    if not isinstance(table, dict):
        raise InputError("benchmark", table, "a table of benchmark parameters", source)
    values: dict[str, Quantity] = {}
    for key, raw in table.items():
        if key in ("name", "source", "notes"):
            continue
        if key == "lam_deg":
            values["lam"] = parse_quantity(raw, key, source).scaled(DEG)
        elif key in BENCHMARK_NAMES:
            values[key] = parse_quantity(raw, key, source)
        else:
            raise InputError(key, raw, f"one of the benchmark names {', '.join(BENCHMARK_NAMES)} (or lam_deg)", source)
    return BenchmarkParameters.from_mapping(values, source)
