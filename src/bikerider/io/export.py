"""Benchmark parameters written out: a project TOML file, a BicycleParameters ``<Name>Benchmark.txt``
and JSON, each read back unchanged by :func:`bikerider.io.benchmark_file.load_benchmark_parameters`.

Every value and every standard uncertainty is written with Python's shortest round-trip form
(``repr``), so reading a file back gives the same floats bit for bit.  ``lam`` is written in
radians (a conversion to degrees and back could change its last bit); the TOML file gives the
degrees in a comment.  ``IByy`` and ``IHyy`` are left out when the parameter set does not determine
them (``None``), as the readers expect.  Eigenvalues as CSV: :func:`eigenvalue_rows` and
:func:`rows_to_csv` (``bikerider convert --to eigenvalues``; sweeps: ``bikerider sweep``).
"""

from __future__ import annotations

import csv
import io
import json
import math
import re

import numpy as np

from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters, ModalEigenvalues
from bikerider.errors import InputError

JSON_FORMAT = "bikerider.benchmark_parameters"
"""The ``format`` entry of a JSON parameter file."""
JSON_VERSION = 1
_BICYCLE_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")


def _number(x: float) -> str:
    if not math.isfinite(x):
        raise InputError("value", x, "a finite number (benchmark parameters are finite)")
    return repr(float(x))


def _present(params: BenchmarkParameters):
    """``(name, value, sigma)`` of every value the set determines, in the order of Table 1."""
    for name in BENCHMARK_NAMES:
        value = params.values.get(name)
        if value is not None:
            yield name, float(value), float(params.sigmas.get(name, 0.0))


def _toml_string(text: str) -> str:
    return json.dumps(text, ensure_ascii=False)  # a JSON string is a valid TOML basic string


def parameters_to_toml(params: BenchmarkParameters, name: str | None = None) -> str:
    """A project TOML file (``[benchmark]`` table, SI units, ``"value +/- sigma"`` where the
    uncertainty is not zero) of ``params``."""
    lines = ["# Benchmark parameters (Meijaard et al. 2007, Table 1), SI units, lam in radians.", ""]
    lines.append("[benchmark]")
    if name:
        lines.append(f"name = {_toml_string(name)}")
    if params.source:
        lines.append(f"source = {_toml_string(str(params.source))}")
    for key, value, sigma in _present(params):
        text = f'"{_number(value)} +/- {_number(sigma)}"' if sigma else _number(value)
        comment = f"  # {math.degrees(value):.6g} deg" if key == "lam" else ""
        lines.append(f"{key} = {text}{comment}")
    return "\n".join(lines) + "\n"


def benchmark_txt_filename(name: str) -> str:
    """``<Name>Benchmark.txt``, BicycleParameters' file name for the bicycle ``name``."""
    check_bicycle_name(name)
    return f"{name}Benchmark.txt"


def check_bicycle_name(name: str) -> str:
    """``name`` if it can name a BicycleParameters bicycle (a letter, then letters, digits, ``_``)."""
    if not isinstance(name, str) or not _BICYCLE_NAME.match(name):
        raise InputError(
            "bicycle name", name, "a name of letters, digits and _ starting with a letter (BicycleParameters)"
        )
    return name


def parameters_to_benchmark_txt(params: BenchmarkParameters, name: str) -> str:
    """A BicycleParameters ``<Name>Benchmark.txt`` of ``params``: one ``name = value+/-sigma`` per
    line, sorted by name as BicycleParameters writes them.

    ``name`` is the bicycle's name (checked; the file itself carries no header, as BicycleParameters
    reads none: write it to :func:`benchmark_txt_filename` of the name).
    """
    check_bicycle_name(name)
    rows = sorted(_present(params), key=lambda row: row[0])
    return "".join(f"{key} = {_number(value)}+/-{_number(sigma)}\n" for key, value, sigma in rows)


def parameters_to_json(params: BenchmarkParameters) -> str:
    """JSON of ``params``: ``{"format", "version", "units", "source", "values", "sigmas"}``, the
    values by Meijaard name (``null`` for ``IByy``/``IHyy`` when not determined)."""
    values = {k: (None if params.values.get(k) is None else float(params.values[k])) for k in BENCHMARK_NAMES}
    for key, value in values.items():
        if value is not None:
            _number(value)
    sigmas = {k: float(params.sigmas.get(k, 0.0)) for k in BENCHMARK_NAMES}
    document = {
        "format": JSON_FORMAT,
        "version": JSON_VERSION,
        "units": "SI (lam in rad)",
        "source": params.source,
        "values": values,
        "sigmas": sigmas,
    }
    return json.dumps(document, indent=2) + "\n"


EIGENVALUE_COLUMNS = ("weave", "weave2", "capsize", "castor")
"""Column stems of :func:`eigenvalue_rows`, in the order of
:data:`bikerider.benchmark.mode_labels.MODES` (as ``bikerider sweep --rows speeds`` writes them)."""


def eigenvalue_rows(eigenvalues: ModalEigenvalues) -> list[dict]:
    """One record per speed of one bicycle's eigenvalues: ``speed``, ``<column>_real`` and
    ``<column>_imag`` of each column of :data:`EIGENVALUE_COLUMNS`, and ``modes`` (the name of
    each of the four: ``weave``, ``capsize``, ``castor`` or ``other``)."""
    values = np.asarray(eigenvalues.values)
    if values.ndim != 2:
        raise InputError("eigenvalues", values.shape, "the eigenvalues of one bicycle, shape (n speeds, 4)")
    rows = []
    for k, speed in enumerate(np.asarray(eigenvalues.speeds, dtype=float)):
        row: dict[str, object] = {"speed": float(speed)}
        for column, z in zip(EIGENVALUE_COLUMNS, values[k]):
            row[f"{column}_real"] = float(z.real)
            row[f"{column}_imag"] = float(z.imag)
        row["modes"] = " ".join(str(x) for x in eigenvalues.labels[k])
        rows.append(row)
    return rows


def rows_to_csv(rows: list[dict], columns: list[str] | None = None) -> str:
    """Tidy records as CSV text (floats in round-trip form, ``None`` empty)."""
    columns = columns or (list(rows[0]) if rows else [])
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow(
            ["" if row.get(c) is None else (repr(row[c]) if isinstance(row[c], float) else row[c]) for c in columns]
        )
    return out.getvalue()


__all__ = [
    "JSON_FORMAT",
    "benchmark_txt_filename",
    "EIGENVALUE_COLUMNS",
    "check_bicycle_name",
    "eigenvalue_rows",
    "parameters_to_benchmark_txt",
    "parameters_to_json",
    "parameters_to_toml",
    "rows_to_csv",
]
