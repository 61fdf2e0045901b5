"""Read a sampled signal (time and angular rate) from a CSV file.

Columns are found by their header, case-insensitively and ignoring a unit in brackets or
parentheses (``time [s]``, ``rate (rad/s)``):

* time: ``time``, ``t``, ``time_s``, ``seconds``;
* signal: ``rate``, ``angular_rate``, ``omega``, ``gyro``, ``angular_velocity``, ``rate_z``.

Other columns are ignored.  A file without a header row is read as two columns, time then
signal.  Separators ``,``, ``;`` or tab; lines starting with ``#`` are comments.
"""

from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path

import numpy as np

from bikerider.errors import FileFormatError

TIME_NAMES = ("time", "t", "time_s", "seconds")
SIGNAL_NAMES = ("rate", "angular_rate", "omega", "gyro", "angular_velocity", "rate_z")
_UNIT = re.compile(r"[\[(].*?[\])]")


def _normalise(header: str) -> str:
    return _UNIT.sub("", header).strip().lower().replace(" ", "_").replace("-", "_")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_signal_csv(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Time [s] and signal columns of a CSV file.

    Raises
    ------
    FileFormatError
        Not UTF-8, no recognisable columns, a cell that is not a number (named by line), or no
        data rows.
    """
    path = Path(path)
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FileFormatError(
            path,
            f"not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start})",
            raw.count(b"\n", 0, exc.start) + 1,
        ) from None
    lines = [
        (n, line)
        for n, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not lines:
        raise FileFormatError(path, "no data: expected columns time and rate")
    sample = lines[0][1]
    delimiter = max((",", ";", "\t"), key=sample.count) if any(d in sample for d in ",;\t") else None
    rows = [
        (
            n,
            [
                c.strip()
                for c in (next(csv.reader(io.StringIO(line), delimiter=delimiter)) if delimiter else line.split())
            ],
        )
        for n, line in lines
    ]
    first_line, first = rows[0]
    if all(_is_number(c) for c in first if c):
        time_col, signal_col, data = 0, 1, rows
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
        data = rows[1:]
    if not data:
        raise FileFormatError(path, "a header but no data rows")
    time = np.empty(len(data))
    signal = np.empty(len(data))
    for k, (number, cells) in enumerate(data):
        if max(time_col, signal_col) >= len(cells):
            raise FileFormatError(
                path, f"{len(cells)} columns, expected at least {max(time_col, signal_col) + 1}", number
            )
        for target, col, what in ((time, time_col, "time"), (signal, signal_col, "rate")):
            try:
                value = float(cells[col])
            except ValueError:
                raise FileFormatError(path, f"{what} {cells[col]!r} is not a number", number) from None
            if not math.isfinite(value):
                raise FileFormatError(path, f"{what} {cells[col]!r} is not a finite number", number)
            target[k] = value
    return time, signal
