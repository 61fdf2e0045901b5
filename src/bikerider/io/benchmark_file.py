"""Read the 25 benchmark parameters from a TOML file or a ``name = value+/-sigma`` text file."""
from __future__ import annotations

import math
from pathlib import Path

from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters
from bikerider.errors import FileFormatError, InputError
from bikerider.quantity import Quantity, parse_quantity


def load_benchmark_parameters(path: str | Path) -> BenchmarkParameters:
    """Benchmark parameters from ``path``.

    TOML: the Meijaard names at top level or under ``[benchmark]``; ``lam_deg`` may replace ``lam``.
    Text: one ``name = value+/-sigma`` per line (BicycleParameters ``<Name>Benchmark.txt``); names
    BicycleParameters adds for other bodies or the y coordinates (``yB``, ``IRzz``, ``IGxx``, ...)
    are ignored.
    """
    path = Path(path)
    if path.suffix.lower() == ".toml":
        from bikerider.io.toml_input import read_toml

        data = read_toml(path)
        table = data.get("benchmark", data)
        if not isinstance(table, dict):
            raise InputError("benchmark", table, "a table of benchmark parameters", str(path))
        values: dict[str, Quantity] = {}
        for key, raw in table.items():
            if key in ("name", "source"):
                continue
            if key == "lam_deg":
                values["lam"] = parse_quantity(raw, key, str(path)).scaled(math.pi / 180)
            elif key in BENCHMARK_NAMES:
                values[key] = parse_quantity(raw, key, str(path))
            else:
                raise InputError(key, raw, f"one of the benchmark names {', '.join(BENCHMARK_NAMES)} (or lam_deg)", str(path))
        return BenchmarkParameters.from_mapping(values, str(path))
    return BenchmarkParameters.from_mapping(_read_text(path), str(path))


def _read_text(path: Path) -> dict[str, Quantity]:
    try:
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise FileFormatError(path, "no such file") from None
    except UnicodeDecodeError as exc:
        raise FileFormatError(path, f"not UTF-8 text (byte {exc.start})") from None
    values: dict[str, Quantity] = {}
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.split("#", 1)[0].strip()
        if not stripped:
            continue
        if "=" not in stripped:
            raise FileFormatError(path, f"expected 'name = value+/-sigma', got {line.strip()!r}", number)
        name, raw = (part.strip() for part in stripped.split("=", 1))
        if name not in BENCHMARK_NAMES:
            continue
        if name in values:
            raise FileFormatError(path, f"{name} is given twice", number)
        values[name] = parse_quantity(raw, name, f"{path}:{number}")
    return values
