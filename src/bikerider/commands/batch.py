"""``bikerider batch``: every bicycle of a BicycleParameters data folder in one table.

For each ``bicycles/<Name>/`` the raw measurements ``RawData/<Name>Measured.txt`` are reduced
(bicycle alone, no rider); when that file is missing or lacks the measurements the reduction needs,
``Parameters/<Name>Benchmark.txt`` is read instead.  Any other error in a raw file is reported as a
failure of that bicycle, not papered over with the Parameters file.  The table holds the 26
benchmark values and the weave and capsize speeds; a bicycle that fails is listed with its error
and the others still finish.  Input files are only read; outputs are written atomically.
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from bikerider import notes
from bikerider.errors import BikeriderError, InputError
from bikerider.generated.manifest import BENCHMARK_NAMES
from bikerider.io.atomic import atomic_write_text
from bikerider.io.output_guard import add_inputs, file_output, refuse_inputs

PROGRESS_AFTER = 1.0
"""Seconds after which progress lines appear on stderr."""


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "batch",
        help="benchmark values and critical speeds of every bicycle in a BicycleParameters folder",
        description="Run every bicycle of a BicycleParameters data folder (bicycles/*/RawData/*Measured.txt, "
        "else bicycles/*/Parameters/*Benchmark.txt) and tabulate the 26 benchmark values with the weave "
        "and capsize speeds. Exit status 1 when some bicycle failed (the table still lists the others).",
    )
    parser.add_argument(
        "directory",
        type=Path,
        metavar="DIR",
        help="a BicycleParameters data folder (holding bicycles/) or its bicycles/ folder",
    )
    parser.add_argument("--out", metavar="PREFIX", help="write PREFIX.csv and PREFIX.txt (else print the table)")
    parser.set_defaults(run=run)


@dataclass
class BatchRow:
    """One bicycle's outcome."""

    name: str
    source: str = ""
    """``"raw"`` or ``"parameters"`` (what the values come from); empty on failure."""
    path: str = ""
    values: dict[str, float | None] = field(default_factory=dict)
    sigmas: dict[str, float] = field(default_factory=dict)
    weave: float | None = None
    capsize: float | None = None
    error: str = ""
    notes: list[str] = field(default_factory=list)


def bicycle_folders(directory: Path) -> list[Path]:
    """The bicycle folders under ``directory`` (or ``directory/bicycles``), sorted by name."""
    root = directory / "bicycles" if (directory / "bicycles").is_dir() else directory
    if not root.is_dir():
        raise InputError("DIR", str(directory), "a BicycleParameters data folder (with bicycles/<Name>/ inside)")
    folders = sorted(
        p for p in root.iterdir() if p.is_dir() and ((p / "RawData").is_dir() or (p / "Parameters").is_dir())
    )
    if not folders:
        raise InputError(
            "DIR",
            str(directory),
            "a BicycleParameters data folder with bicycles/<Name>/RawData or bicycles/<Name>/Parameters inside",
        )
    return folders


def input_files(folder: Path) -> tuple[Path | None, Path | None]:
    """``(Measured file, Benchmark file)`` of one bicycle folder; ``None`` where absent."""
    name = folder.name
    measured = folder / "RawData" / f"{name}Measured.txt"
    benchmark = folder / "Parameters" / f"{name}Benchmark.txt"
    return (measured if measured.is_file() else None, benchmark if benchmark.is_file() else None)


def _raw_is_incomplete(error: Exception) -> bool:
    """Whether a raw file's error is only that measurements are missing (every one of its errors)."""
    return isinstance(error, InputError) and all(e.value == "missing" for e in getattr(error, "errors", [error]))


def process_bicycle(folder: Path) -> BatchRow:
    """Benchmark values and critical speeds of one bicycle folder (never raises for bad data).

    The notes of its files (what was left out or changed) go to the row, each once, not to the
    end of the run.
    """
    row = BatchRow(folder.name)
    with notes.collecting() as collection:
        _process(folder, row)
    prefixes = tuple(f"{path}: " for path in input_files(folder) if path)  # the row names the bicycle
    for message in collection.messages:
        short = next((message[len(p) :] for p in prefixes if message.startswith(p)), message)
        if short not in row.notes:
            row.notes.append(short)
    return row


def _process(folder: Path, row: BatchRow) -> None:
    # The pipeline (NumPy, the generated code) is imported when the command runs: `bikerider --help`
    # and the other commands start in 0.06 s instead of 0.4 s (python -X importtime).
    from bikerider.benchmark import WhippleModel
    from bikerider.bicycle.to_benchmark import bicycle_benchmark_parameters
    from bikerider.io.bicycleparameters import read_benchmark_file, read_measured_file

    measured, benchmark = input_files(folder)
    parameters = None
    try:
        if measured is not None:
            try:
                reduction = read_measured_file(measured)
                parameters = bicycle_benchmark_parameters(reduction.bodies)
                row.source, row.path, row.notes = "raw", str(measured), list(reduction.notes)
            except BikeriderError as exc:
                if not (_raw_is_incomplete(exc) and benchmark is not None):
                    raise
                row.notes.append(f"raw data not usable ({exc}); values from the Parameters file")
        if parameters is None:
            if benchmark is None:
                row.error = "no RawData/<Name>Measured.txt or Parameters/<Name>Benchmark.txt"
                return
            read = read_benchmark_file(benchmark)
            parameters = read.parameters
            row.source, row.path = "parameters", str(benchmark)
            row.notes.extend(read.notes)
        row.values, row.sigmas = parameters.as_dict(), dict(parameters.sigmas)
        speeds = WhippleModel.from_parameters(parameters).critical_speeds()
        row.weave, row.capsize = speeds.weave, speeds.capsize
    except (BikeriderError, OSError) as exc:
        row.error = str(exc)
        row.source = ""


def run_batch(directory: Path, progress=None) -> list[BatchRow]:
    """Process every bicycle folder; ``progress(i, n, name)`` is called before each."""
    folders = bicycle_folders(directory)
    rows = []
    for i, folder in enumerate(folders, start=1):
        if progress is not None:
            progress(i, len(folders), folder.name)
        rows.append(process_bicycle(folder))
    return rows


def _number(value: float | None, digits: int = 6) -> str:
    return "" if value is None or not math.isfinite(value) else f"{value:.{digits}g}"


def csv_text(rows: list[BatchRow]) -> str:
    """One line per bicycle: name, source, each benchmark value and its sigma, speeds, error."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    header = ["bicycle", "source"]
    for name in BENCHMARK_NAMES:
        header += [name, f"{name}_sigma"]
    writer.writerow(header + ["weave_speed", "capsize_speed", "error"])
    for row in rows:
        line = [row.name, row.source]
        for name in BENCHMARK_NAMES:
            line += [
                _number(row.values.get(name), 10),
                _number(row.sigmas.get(name) if row.values.get(name) is not None else None, 3),
            ]
        writer.writerow(line + [_number(row.weave, 8), _number(row.capsize, 8), row.error])
    return buffer.getvalue()


def text_table(rows: list[BatchRow]) -> str:
    """Parameters down, bicycles across, aligned; failures and notes listed below."""
    done = [r for r in rows if not r.error]
    lines = []
    if done:
        labels = ["", "source"] + list(BENCHMARK_NAMES) + ["weave [m/s]", "capsize [m/s]"]
        columns = [labels]
        for row in done:
            cells = [row.name, row.source]
            cells += [_number(row.values.get(n), 5) or "-" for n in BENCHMARK_NAMES]
            cells += [_number(row.weave, 4) or "none", _number(row.capsize, 4) or "none"]
            columns.append(cells)
        widths = [max(len(c) for c in col) for col in columns]
        for k in range(len(labels)):
            first = columns[0][k].ljust(widths[0])
            rest = "  ".join(col[k].rjust(width) for col, width in zip(columns[1:], widths[1:]))
            lines.append(f"{first}  {rest}".rstrip())
    failed = [r for r in rows if r.error]
    if failed:
        lines.append("")
        lines.append("failed:")
        lines.extend(f"  {r.name}: {r.error}" for r in failed)
    noted = [r for r in done if r.notes]
    if noted:
        lines.append("")
        lines.append("notes:")
        for r in noted:
            lines.extend(f"  {r.name}: {note}" for note in r.notes)
    return "\n".join(lines) + "\n"


def write_atomically(path: Path, text: str) -> None:
    """Write ``text`` to a temporary file beside ``path``, then rename it over ``path``."""
    atomic_write_text(path, text)


def run(args: argparse.Namespace) -> int:
    started = time.monotonic()

    def progress(i: int, n: int, name: str) -> None:
        if time.monotonic() - started > PROGRESS_AFTER:
            print(f"batch: [{i}/{n}] {name}", file=sys.stderr, flush=True)

    targets: list[Path] = []
    if args.out is not None:
        if not args.out or args.out.endswith(("/", os.sep)) or Path(args.out).name in ("", ".", ".."):
            raise InputError("--out", args.out, "a prefix for PREFIX.csv and PREFIX.txt (a path that ends in a name)")
        prefix = Path(args.out)
        if not prefix.parent.is_dir():
            raise InputError("--out", args.out, f"a prefix in an existing folder ({prefix.parent} does not exist)")
        targets = [prefix.with_name(prefix.name + ".csv"), prefix.with_name(prefix.name + ".txt")]
        for target in targets:
            file_output("--out", str(target))
        add_inputs(p for folder in bicycle_folders(args.directory) for p in input_files(folder) if p)
        refuse_inputs("--out", args.out, targets)
    rows = run_batch(args.directory, progress)
    table = text_table(rows)
    if targets:
        write_atomically(targets[0], csv_text(rows))
        write_atomically(targets[1], table)
        print(f"wrote {targets[0]} and {targets[1]}", file=sys.stderr)
    else:
        sys.stdout.write(table)
    if time.monotonic() - started > PROGRESS_AFTER:
        print(f"batch: done, {len(rows)} bicycles in {time.monotonic() - started:.1f} s", file=sys.stderr)
    failed = [r.name for r in rows if r.error]
    for name in failed:
        print(f"bikerider batch: {name} failed (see the table)", file=sys.stderr)
    return 1 if failed else 0
