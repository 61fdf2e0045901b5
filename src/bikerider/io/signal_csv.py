"""Read a sampled signal (time and angular rate) from a CSV file.

Columns are found by their header, case-insensitively and ignoring a unit in brackets or
parentheses (``time [s]``, ``rate (rad/s)``):

* time: ``time``, ``t``, ``time_s``, ``seconds``;
* signal: ``rate``, ``angular_rate``, ``omega``, ``gyro``, ``angular_velocity``, ``rate_z``.

Other columns are ignored.  A file without a header row is read as two columns, time then
signal.  Separators ``,``, ``;`` or tab; lines starting with ``#`` are comments.  The file is read
through :func:`bikerider.io.input_file.read_input_bytes` (a regular file of at most
:data:`~bikerider.io.input_file.DATA_LIMIT` bytes); a cell longer than :data:`MAX_CELL` characters
is refused, naming its line.
"""

from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path

import numpy as np

from bikerider.errors import FileFormatError
from bikerider.io.input_file import DATA_LIMIT, decode_text, read_input_bytes

TIME_NAMES = ("time", "t", "time_s", "seconds")
SIGNAL_NAMES = ("rate", "angular_rate", "omega", "gyro", "angular_velocity", "rate_z")
_UNIT = re.compile(r"[\[(].*?[\])]")
MAX_CELL = 1000
"""Longest cell, in characters: a number or a column name is far shorter; a longer cell is a
damaged file (and would take Python's CSV and float readers long to refuse)."""


def _normalise(header: str) -> str:
    return _UNIT.sub("", header).strip().lower().replace(" ", "_").replace("-", "_")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _cells(path: Path, number: int, line: str, delimiter: str | None) -> list[str]:
    """The cells of one line (stripped); a line that is not CSV or has an overlong cell is an error.

    A line without quotes is split on the delimiter (what the CSV reader would give, at a fraction
    of its cost per line); a quoted one goes through :mod:`csv`."""
    if delimiter is None:
        cells = line.split()
    elif '"' not in line:
        cells = line.split(delimiter)
    else:
        try:
            cells = next(csv.reader(io.StringIO(line), delimiter=delimiter))
        except csv.Error as exc:
            raise FileFormatError(
                path, f"not a line of comma-, semicolon- or tab-separated values ({exc})", number
            ) from None
    if len(line) > MAX_CELL:
        for cell in cells:
            if len(cell) > MAX_CELL:
                raise FileFormatError(
                    path, f"a cell of {len(cell)} characters ({cell[:20]!r}...): expected at most {MAX_CELL}", number
                )
    return [c.strip() for c in cells]


def _column(path: Path, data: list[tuple[int, list[str]]], col: int, what: str) -> np.ndarray:
    """Column ``col`` of the data rows as floats; the first cell that is not a finite number is
    named by its line."""
    cells = [cells[col] for _, cells in data]
    try:
        values = np.array(cells, dtype=float)  # NumPy's conversion of the strings, in one call
    except ValueError:
        values = None
    if values is not None and np.isfinite(values).all():
        return values
    values = np.empty(len(cells))
    for k, ((number, _), cell) in enumerate(zip(data, cells)):
        try:
            value = float(cell)
        except ValueError:
            raise FileFormatError(path, f"{what} {cell!r} is not a number", number) from None
        if not math.isfinite(value):
            raise FileFormatError(path, f"{what} {cell!r} is not a finite number", number)
        values[k] = value
    return values


def read_signal_csv(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Time [s] and signal columns of a CSV file.

    Raises
    ------
    FileFormatError
        Not a regular file, too large, not UTF-8, no recognisable columns, a cell that is not a
        number or is overlong (named by line), or no data rows.
    """
    text = decode_text(read_input_bytes(path, DATA_LIMIT), path)  # the path as given: "" is no file
    path = Path(path)
    lines = [
        (n, line)
        for n, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not lines:
        raise FileFormatError(path, "no data: expected columns time and rate")
    sample = lines[0][1]
    delimiter = max((",", ";", "\t"), key=sample.count) if any(d in sample for d in ",;\t") else None
    first_line, first = lines[0][0], _cells(path, lines[0][0], sample, delimiter)
    if all(_is_number(c) for c in first if c):
        time_col, signal_col, body = 0, 1, lines
        if len(first) < 2:
            raise FileFormatError(path, "expected two columns (time, rate) or a header row naming them", first_line)
    else:
        headers = [_normalise(c) for c in first]
        time_col = next((i for i, h in enumerate(headers) if h in TIME_NAMES), None)
        signal_col = next((i for i, h in enumerate(headers) if h in SIGNAL_NAMES), None)
        if time_col is None or signal_col is None:
            raise FileFormatError(
                path,
                f"header {first!r} has no {'time' if time_col is None else 'rate'} column; accepted names: "
                f"time: {', '.join(TIME_NAMES)}; rate: {', '.join(SIGNAL_NAMES)}",
                first_line,
            )
        body = lines[1:]
    if not body:
        raise FileFormatError(path, "a header but no data rows")
    fast = _fast_columns([line for _, line in body], delimiter, time_col, signal_col)
    if fast is not None:
        return fast
    data = [(n, _cells(path, n, line, delimiter)) for n, line in body]  # line by line, to name the bad one
    width = max(time_col, signal_col) + 1
    for number, cells in data:
        if len(cells) < width:
            raise FileFormatError(path, f"{len(cells)} columns, expected at least {width}", number)
    return _column(path, data, time_col, "time"), _column(path, data, signal_col, "rate")


def signal_unit(path: str | Path) -> str | None:
    """The unit in brackets of the rate column's header (``rate (deg/s)``: ``deg/s``), or None (no
    header, or none given there).  For labels: the fit does not depend on it."""
    text = decode_text(read_input_bytes(path, DATA_LIMIT), path)
    first = next((line for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")), "")
    delimiter = max((",", ";", "\t"), key=first.count) if any(d in first for d in ",;\t") else None
    cells = [c.strip() for c in (first.split(delimiter) if delimiter else first.split())]
    for cell in cells:
        if _normalise(cell) in SIGNAL_NAMES:
            unit = _UNIT.search(cell)
            return unit.group(0)[1:-1].strip() or None if unit else None
    return None


def _fast_columns(
    lines: list[str], delimiter: str | None, time_col: int, signal_col: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """The two columns of a well-formed record in a few whole-array operations (a 2.5-million-row
    record in about a second), or ``None`` when any line needs the careful reading: quotes, rows of
    different widths, an overlong line, a cell that is not a finite number."""
    if not lines or max(map(len, lines)) > MAX_CELL:
        return None
    if delimiter is None:
        rows = [line.split() for line in lines]
        widths = set(map(len, rows))
        tokens = [cell for row in rows for cell in row]
    else:
        joined = delimiter.join(lines)
        if '"' in joined:
            return None
        widths = {line.count(delimiter) + 1 for line in lines}
        tokens = joined.split(delimiter)
    if len(widths) != 1 or widths.pop() <= max(time_col, signal_col):
        return None
    width = len(tokens) // len(lines)
    try:
        table = np.array(tokens, dtype=float).reshape(len(lines), width)
    except ValueError:
        return None
    time, signal = table[:, time_col].copy(), table[:, signal_col].copy()
    if not (np.isfinite(time).all() and np.isfinite(signal).all()):
        return None
    return time, signal
