"""Read an experiment as it was recorded: raw logs, windows of free decays, and a manifest.

Logs
    Delimited text (comma by default), one header line of column names, one row per sample;
    ``.gz`` files are read transparently.  A column map names the log's column of each signal the
    diagnosis uses (``roll_rate``, ``roll_angle``, ``steer_angle``, ``steer_rate``, ``speed``);
    the time comes from a time column or from the sampling rate (sample ``i`` at ``i / rate``).
    Empty cells are missing values: a record whose window holds one in a signal it uses is left
    out with that reason.

Manifest (TOML)
    Describes a whole experiment (``docs/gap.md`` has the full format)::

        [experiment]
        name = "..."
        sample_rate = 100.0              # Hz; or time_column = "t"
        logs = "logs"                    # folder of the logs, relative to the manifest
        windows = "windows.csv"          # file,start,end[,group,control,speed] (or [[file]] lists)
        control = "sil"                  # the law acting unless a file or window says otherwise
        group = "file"                   # the group of a record: its file (default) or a name
        fit = ["roll_rate"]              # signals the eigenvalue is fitted to

        [columns]                        # signal = column of the logs
        roll_rate = "lean_rate"
        speed = "speed"
        [columns.scale]                  # optional factors (units, sign conventions)
        steer_angle = -1.0

        [speed]
        source = "column"                # "column", "file_name" or "value"
        pattern = "_(?P<speed>[0-9.]+)kph"   # for "file_name"
        unit = "km/h"                    # of the pattern's number: "m/s" or "km/h"
        calibration = { gain = 1.0662, offset = -0.1276 }  # recorded = gain * true + offset

        [control.sil]                    # named laws (bikerider.gap.measured.control)
        k_phid = { K = 2.0, v0 = 6.5, when = "below" }

        [[file]]
        path = "run1.log.gz"
        windows = [[4486, 4775], [5420, 5668]]   # or detect = true
        group = "day 1"                  # optional
        control = "sil"                  # optional
        speed = 4.2                      # with source = "value"

Manifest (CSV)
    The windows alone, ``file, start, end`` and optional ``group, control, speed`` columns; the
    column map, sampling rate and control law then come from the command line.

Every error names the file, the line and the value: a malformed manifest, a window outside its
log, a column the log does not have, a control law that cannot be evaluated.
"""

from __future__ import annotations

import csv
import gzip
import io
import math
import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bikerider.errors import FileFormatError, InputError
from bikerider.gap.measured.control import GAIN_NAMES, MAX_MAGNITUDE, NO_CONTROL, ControlLaw, GainSchedule
from bikerider.gap.measured.records import (
    MAX_RECORD_SAMPLES,
    SIGNAL_UNITS,
    SIGNALS,
    DetectorSettings,
    Record,
)
from bikerider.io.input_file import checked_input_file
from bikerider.io.toml_input import read_toml

MAX_LOG_BYTES = 200_000_000
"""Largest log or windows file (CSV manifest) read [bytes, unpacked]: hours of a 100 Hz log with a
dozen columns (the project's eight SBW logs are about 0.7 MB each); a larger file is refused with its
size.  A TOML manifest is a TOML file: at most 1 MiB (:data:`bikerider.io.input_file.TEXT_LIMIT`)."""
MAX_RECORDS = 5_000
"""Most records of one run (all manifests' windows and detected decays together): each is fitted on
every fold, about 30-40 ms and 0.15 MB a record (4,000 records took 129 s and 0.68 GB), so a larger
set is refused with its count rather than left running for many minutes; free-decay experiments hold
tens to hundreds.  A manifest that repeats one window many times is almost surely a mistake."""
SAMPLE_RATES = (1e-3, 1e6)
"""Sampling rates [Hz] of a log: far beyond any data logger on a bicycle (100 Hz to a few kHz) either
way; a rate outside is a typing or unit slip (1e308 overflows the sample counts of the windows, a
denormal such as 5e-324 the sample times)."""
MAX_DETECTOR = {
    "threshold": 1e6,
    "min_rate": MAX_MAGNITUDE,
    "gap": 3600.0,
    "max_duration": 3600.0,
    "min_duration": 3600.0,
    "margin": 3600.0,
}
"""Largest value of each detector setting (noise levels, rad/s, seconds): a decay lasts seconds."""
BAD_DELIMITERS = '"#.+-\r\n'
"""Characters no log delimiter may be: quotes and comments, and the characters of numbers."""
COLUMN_KEYS = SIGNALS + ("speed", "time")
"""Keys of a column map: the state signals, the speed and the time."""
SPEED_SOURCES = ("column", "file_name", "value")
SPEED_UNITS = {"m/s": 1.0, "km/h": 1 / 3.6}
WINDOW_ALIASES = {
    "file": ("file", "path", "log"),
    "start": ("start", "start_sample"),
    "end": ("end", "end_sample"),
    "group": ("group",),
    "control": ("control", "law"),
    "speed": ("speed",),
}
"""Columns of a windows file (CSV manifest) and the names accepted for each."""


# ---------------------------------------------------------------------------------------------
# Logs
# ---------------------------------------------------------------------------------------------
@dataclass
class Log:
    """The columns a diagnosis needs from one log.

    Attributes
    ----------
    path : Path
    columns : dict
        Log column name to its samples (NaN where a cell is empty).
    n : int
        Number of samples.
    first_line : int
        File line of the first sample (for messages).
    """

    path: Path
    columns: dict[str, np.ndarray]
    n: int
    first_line: int


def read_text(path: str | Path) -> str:
    """The text of a file, gunzipped when it ends in ``.gz`` (at most :data:`MAX_LOG_BYTES` either way)."""
    path = checked_input_file(path, MAX_LOG_BYTES, "log or manifest")
    raw = path.read_bytes()
    if path.suffix == ".gz":
        try:
            with gzip.GzipFile(fileobj=io.BytesIO(raw)) as stream:
                raw = stream.read(MAX_LOG_BYTES + 1)
        except (OSError, EOFError) as exc:
            raise FileFormatError(path, f"not a readable gzip file ({exc})") from None
        if len(raw) > MAX_LOG_BYTES:
            raise FileFormatError(
                path, f"unpacks to more than {MAX_LOG_BYTES / 1e6:g} MB: expected a log of at most that size"
            )
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FileFormatError(path, f"not UTF-8 text (byte {exc.start})") from None


def read_log(path: str | Path, wanted: list[str], delimiter: str = ",") -> Log:
    """Read the columns ``wanted`` of a log (see the module docstring).

    Raises
    ------
    FileFormatError
        No header, a wanted column the log does not have (the message lists its columns), a row
        with too few cells, or a cell that is not a number.
    """
    path = Path(path)
    text = read_text(path)
    lines = text.splitlines()
    header_at = next((k for k, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")), None)
    if header_at is None:
        raise FileFormatError(path, "no header line (column names) found")
    names = _csv_cells(lines[header_at], path, header_at + 1, delimiter)
    for name in wanted:
        if name not in names:
            raise FileFormatError(path, f"no column {name!r}: the log's columns are {', '.join(names)}", header_at + 1)
    index = {name: names.index(name) for name in wanted}
    width = max(index.values(), default=-1) + 1
    values = {name: [] for name in wanted}
    first = header_at + 2
    for number, line in enumerate(lines[header_at + 1 :], start=header_at + 2):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        cells = line.split(delimiter)
        if len(cells) < width:
            raise FileFormatError(path, f"{len(cells)} cells: expected {len(names)} ({', '.join(names)})", number)
        for name, k in index.items():
            cell = cells[k].strip()
            if not cell:
                values[name].append(math.nan)
                continue
            try:
                x = float(cell)
            except ValueError:
                raise FileFormatError(path, f"{name} = {cell!r}: expected a number", number) from None
            if not math.isfinite(x):
                raise FileFormatError(path, f"{name} = {cell}: expected a finite number", number)
            values[name].append(x)
    n = len(values[wanted[0]]) if wanted else 0
    if n == 0:
        raise FileFormatError(path, "a header but no samples")
    return Log(path, {k: np.array(v) for k, v in values.items()}, n, first)


# ---------------------------------------------------------------------------------------------
# The settings of an experiment
# ---------------------------------------------------------------------------------------------
@dataclass
class ExperimentSettings:
    """How to read an experiment's logs (the manifest's tables, or the command line's options).

    Attributes
    ----------
    columns : dict
        Signal or ``speed``/``time`` to the log's column name.
    scale : dict
        Factors applied to signals (units, sign conventions).
    sample_rate : float or None
        Hz, when the logs have no time column.
    speed_source : str
        One of :data:`SPEED_SOURCES`.
    speed_pattern : re.Pattern or None
        For ``file_name``: a regular expression with a group named ``speed``.
    speed_unit : float
        Factor from the pattern's number to m/s.
    calibration : tuple of float or None
        ``(gain, offset)``: recorded speed = gain * true speed + offset.
    laws : dict
        Control laws by name.
    default_law : str or None
    group : str
        ``file`` (a record's group is its file) or a fixed group name.
    fit : tuple of str
    detector : DetectorSettings
    source : str
        The manifest (for messages).
    """

    columns: dict[str, str]
    scale: dict[str, float] = field(default_factory=dict)
    sample_rate: float | None = None
    speed_source: str = "column"
    speed_pattern: re.Pattern | None = None
    speed_unit: float = 1.0
    calibration: tuple[float, float] | None = None
    laws: dict[str, ControlLaw] = field(default_factory=dict)
    default_law: str | None = None
    group: str = "file"
    fit: tuple[str, ...] = ("roll_rate",)
    detector: DetectorSettings = field(default_factory=DetectorSettings)
    delimiter: str = ","
    source: str = ""
    files: tuple[Path, ...] = ()

    def check(self) -> None:
        where = self.source or None
        for key in self.columns:
            if key not in COLUMN_KEYS:
                raise InputError(
                    f"columns.{key}", self.columns[key], "one of the signals " + ", ".join(COLUMN_KEYS), where
                )
        if "roll_rate" not in self.columns:
            raise InputError("columns.roll_rate", "missing", "the log column of the roll rate", where)
        if "time" not in self.columns and self.sample_rate is None:
            raise InputError("sample_rate", "missing", "a sampling rate [Hz] or a time column (columns.time)", where)
        if self.sample_rate is not None:
            check_sample_rate(self.sample_rate, "sample_rate", where)
        check_delimiter(self.delimiter, where)
        if self.speed_source not in SPEED_SOURCES:
            raise InputError("speed.source", self.speed_source, "one of " + ", ".join(SPEED_SOURCES), where)
        if self.speed_source == "column" and "speed" not in self.columns:
            raise InputError("columns.speed", "missing", 'the log column of the speed (speed.source = "column")', where)
        if self.speed_source == "file_name" and self.speed_pattern is None:
            raise InputError("speed.pattern", "missing", "a regular expression with a group (?P<speed>...)", where)
        for name in self.fit:
            if name not in SIGNALS:
                raise InputError("fit", name, "signals among " + ", ".join(SIGNALS), where)
            if name not in self.columns:
                raise InputError("fit", name, "a signal the column map gives (columns." + name + ")", where)
        if self.default_law is not None and self.default_law not in self.laws:
            raise InputError(
                "control",
                self.default_law,
                "the name of a law defined under [control.<name>] (" + (", ".join(self.laws) or "none defined") + ")",
                where,
            )


@dataclass(frozen=True)
class Window:
    """One record to cut: a file, a sample window and what the manifest says about it."""

    file: Path
    start: int | None
    end: int | None
    source: str
    group: str | None = None
    law: str | None = None
    speed: float | None = None
    detect: bool = False


# ---------------------------------------------------------------------------------------------
# Manifests
# ---------------------------------------------------------------------------------------------
def _line_of(text: str, pattern: str, after: int = 0) -> int | None:
    """The first line (1-based, after line ``after``) matching a regular expression."""
    rx = re.compile(pattern)
    for number, line in enumerate(text.splitlines(), start=1):
        if number > after and rx.search(line):
            return number
    return None


def read_manifest(path: str | Path) -> tuple[ExperimentSettings, list[Window]]:
    """Read a TOML manifest (see the module docstring): the settings and the windows to cut."""

    path = Path(path)
    data = read_toml(path)  # checks the path first: a regular file of at most 1 MiB, as every TOML file
    text = read_text(path)

    def where(key: str, after: int = 0) -> str:
        line = _line_of(text, rf"^\s*\[*\s*{re.escape(key)}\b", after)
        return f"{path}:{line}" if line else str(path)

    allowed = {"experiment", "columns", "speed", "control", "file", "multisine"}  # multisine: bikerider.io.multisine
    for key in data:
        if key not in allowed:
            raise InputError(
                key, data[key], "one of the tables " + ", ".join(f"[{k}]" for k in sorted(allowed)), where(key)
            )
    exp = data.get("experiment", {})
    if not isinstance(exp, dict):
        raise InputError("experiment", exp, "a table", where("experiment"))
    exp_keys = {
        "name",
        "description",
        "sample_rate",
        "time_column",
        "logs",
        "windows",
        "control",
        "group",
        "fit",
        "delimiter",
        "detector",
    }
    for key in exp:
        if key not in exp_keys:
            raise InputError(f"experiment.{key}", exp[key], "one of " + ", ".join(sorted(exp_keys)), where(key))
    columns = data.get("columns")
    if not isinstance(columns, dict):
        raise InputError(
            "columns",
            columns if columns is not None else "missing",
            'a table mapping signals to the logs\' columns (roll_rate = "...")',
            where("columns"),
        )
    scale = columns.get("scale", {})
    columns = {k: v for k, v in columns.items() if k != "scale"}
    for key, value in columns.items():
        if not isinstance(value, str) or not value:
            raise InputError(f"columns.{key}", value, "a column name", where(key))
    if not isinstance(scale, dict):
        raise InputError("columns.scale", scale, "a table of factors", where("scale"))
    for key, value in scale.items():
        if key not in SIGNALS:
            raise InputError(f"columns.scale.{key}", value, "a factor for one of " + ", ".join(SIGNALS), where(key))
        if not _real(value):  # None (not a finite number) or zero
            raise InputError(f"columns.scale.{key}", _shown(value), "a finite, non-zero factor", where(key))
    settings = ExperimentSettings(dict(columns), {k: float(v) for k, v in scale.items()}, source=str(path))
    if "time_column" in exp:
        settings.columns["time"] = _text(exp["time_column"], "experiment.time_column", where("time_column"))
    if "sample_rate" in exp:
        settings.sample_rate = _number(exp["sample_rate"], "experiment.sample_rate", where("sample_rate"))
    if "delimiter" in exp:
        settings.delimiter = check_delimiter(
            _text(exp["delimiter"], "experiment.delimiter", where("delimiter")), where("delimiter")
        )
    if "group" in exp:
        settings.group = _text(exp["group"], "experiment.group", where("group"))
    if "fit" in exp:
        fit = exp["fit"]
        if not (isinstance(fit, list) and fit and all(isinstance(x, str) for x in fit)):
            raise InputError("experiment.fit", fit, "a list of signal names", where("fit"))
        settings.fit = tuple(fit)
    if "detector" in exp:
        settings.detector = _detector(exp["detector"], where("detector"))
    _read_speed(settings, data.get("speed", {}), where)
    settings.laws = read_laws(data.get("control", {}), path, text)
    if "control" in exp:
        settings.default_law = _text(exp["control"], "experiment.control", where("control"))
    settings.check()
    folder = path.parent / _text(exp.get("logs", "."), "experiment.logs", where("logs"))
    windows: list[Window] = []
    if "windows" in exp:
        windows_file = path.parent / _text(exp["windows"], "experiment.windows", where("windows"))
        settings.files += (windows_file,)
        windows += read_windows(windows_file, folder)
    files = data.get("file", [])
    if not isinstance(files, list):
        raise InputError("file", files, "[[file]] tables", where("file"))
    after = 0
    for entry in files:
        line = _line_of(text, r"^\s*\[\[\s*file\s*\]\]", after) or 0
        after = line
        here = f"{path}:{line}" if line else str(path)
        windows += _file_windows(entry, folder, here, text, line, path)
    if not windows and "multisine" not in data:  # multisine runs are read by bikerider.io.multisine
        raise FileFormatError(
            path,
            'no records: give [experiment] windows = "FILE", [[file]] tables with windows or [[multisine.run]] tables',
        )
    for w in windows:
        if w.law is not None and w.law not in settings.laws:
            raise InputError(
                "control",
                w.law,
                "the name of a law defined under [control.<name>] ("
                + (", ".join(settings.laws) or "none defined")
                + ")",
                w.source,
            )
    return settings, windows


def _file_windows(entry: object, folder: Path, here: str, text: str, line: int, manifest: Path) -> list[Window]:
    allowed = {"path", "windows", "detect", "group", "control", "speed"}
    if not isinstance(entry, dict):
        raise InputError("file", entry, "a table", here)
    for key in entry:
        if key not in allowed:
            raise InputError(f"file.{key}", entry[key], "one of " + ", ".join(sorted(allowed)), here)
    if "path" not in entry:
        raise InputError("file.path", "missing", "the log's path", here)
    file = folder / _text(entry["path"], "file.path", here)
    group = _text(entry["group"], "file.group", here) if "group" in entry else None
    law = _text(entry["control"], "file.control", here) if "control" in entry else None
    speed = _speed_value(entry["speed"], "file.speed", here) if "speed" in entry else None
    detect = entry.get("detect", False)
    if not isinstance(detect, bool):
        raise InputError("file.detect", detect, "true or false", here)
    windows = entry.get("windows")
    if detect:
        if windows is not None:
            raise InputError("file.windows", windows, "either windows or detect = true, not both", here)
        return [Window(file, None, None, here, group, law, speed, True)]
    if not isinstance(windows, list) or not windows:
        raise InputError(
            "file.windows",
            windows if windows is not None else "missing",
            "a list of [start, end] sample windows, or detect = true",
            here,
        )
    out = []
    for pair in windows:
        ok = (
            isinstance(pair, list)
            and len(pair) == 2
            and all(isinstance(x, int) and not isinstance(x, bool) for x in pair)
        )
        first = re.escape(str(pair[0])) if isinstance(pair, list) and pair else "windows"
        at = _line_of(text, rf"\[\s*{first}\s*,", line) or _line_of(text, r"^\s*windows\s*=", line)
        where = f"{manifest}:{at}" if at else here
        if not ok:
            raise InputError("file.windows", pair, "a window [start, end] of two whole sample numbers", where)
        out.append(Window(file, pair[0], pair[1], where, group, law, speed))
    return out


def read_experiment(
    path: str | Path,
    columns: str | None = None,
    sample_rate: float | None = None,
    laws: dict[str, ControlLaw] | None = None,
) -> tuple[ExperimentSettings, list[Window]]:
    """A manifest: TOML (everything in it), or a CSV of windows with the settings given here.

    ``columns`` is the column map as ``signal=column,...`` (``--columns``); ``laws`` the laws of
    ``--control`` (one law acts in every window that names none).
    """
    if str(path) == "":  # Path("") is the current folder, which would be taken for a CSV manifest
        raise InputError("path", "", "the path of a file (an empty path names no file, and never the default one)")
    path = Path(path)
    if path.suffix.lower() == ".toml":
        if columns is not None or sample_rate is not None:
            raise InputError(
                "--columns/--sample-rate",
                "given",
                "no column map or sampling rate on the command line with a TOML manifest (it holds its own)",
                str(path),
            )
        settings, windows = read_manifest(path)
        for name, law in (laws or {}).items():
            settings.laws.setdefault(name, law)
        return settings, windows
    if columns is None:
        raise InputError(
            "--columns",
            "missing",
            "the log columns of the signals (roll_rate=...,speed=...) for a CSV manifest",
            str(path),
        )
    settings = ExperimentSettings(
        parse_columns(columns), sample_rate=sample_rate, laws=dict(laws or {}), source=str(path)
    )
    if len(settings.laws) == 1:
        settings.default_law = next(iter(settings.laws))
    if "speed" not in settings.columns:
        settings.speed_source = "value"
    settings.check()
    windows = read_windows(path)
    for w in windows:
        if w.law is not None and w.law not in settings.laws:
            raise InputError(
                "control",
                w.law,
                "the name of a law given with --control (" + (", ".join(settings.laws) or "none given") + ")",
                w.source,
            )
        if settings.speed_source == "value" and w.speed is None:
            raise InputError(
                "speed", "missing", "a speed column in the manifest or a speed column map (speed=...)", w.source
            )
    return settings, windows


def parse_columns(text: str) -> dict[str, str]:
    """``roll_rate=lean_rate,speed=speed`` -> a column map."""
    out = {}
    for part in text.split(","):
        key, sep, value = (x.strip() for x in part.partition("="))
        if not sep or not key or not value:
            raise InputError("--columns", text, "signal=column pairs separated by commas (roll_rate=lean_rate,...)")
        if key not in COLUMN_KEYS:
            raise InputError("--columns", key, "signals among " + ", ".join(COLUMN_KEYS))
        out[key] = value
    return out


def read_windows(path: str | Path, folder: Path | None = None) -> list[Window]:
    """A windows file (CSV manifest): ``file, start, end`` and optional ``group, control, speed``.

    Other columns (e.g. a nominal speed in km/h kept for the experimenter's own use) are ignored.
    """
    path = Path(path)
    folder = path.parent if folder is None else folder
    text = read_text(path)
    rows = [
        (n, line)
        for n, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not rows:
        raise FileFormatError(path, "no header line (column names) found")
    header_line, header = rows[0]
    names = _csv_cells(header, path, header_line)
    cols = {}
    for key, aliases in WINDOW_ALIASES.items():
        found = [a for a in aliases if a in names]
        if found:
            cols[key] = names.index(found[0])
    for key in ("file", "start", "end"):
        if key not in cols:
            raise FileFormatError(
                path,
                f"missing column {key!r} (accepted: {', '.join(WINDOW_ALIASES[key])}; columns are {', '.join(names)})",
                header_line,
            )
    out = []
    for number, line in rows[1:]:
        cells = _csv_cells(line, path, number)
        if len(cells) != len(names):
            raise FileFormatError(
                path, f"expected {len(names)} comma-separated values ({', '.join(names)}), got {len(cells)}", number
            )
        start, end = (_whole(cells[cols[k]], k, path, number) for k in ("start", "end"))
        speed = None
        if "speed" in cols and cells[cols["speed"]]:
            try:
                speed = float(cells[cols["speed"]])
            except ValueError:
                raise FileFormatError(
                    path, f"speed = {cells[cols['speed']]!r}: expected a number [m/s]", number
                ) from None
            if not (0 < speed <= MAX_MAGNITUDE):  # also NaN
                raise FileFormatError(
                    path,
                    f"speed = {cells[cols['speed']]}: expected a positive speed of at most {MAX_MAGNITUDE:g} m/s",
                    number,
                )
        group = cells[cols["group"]] if "group" in cols and cells[cols["group"]] else None
        law = cells[cols["control"]] if "control" in cols and cells[cols["control"]] else None
        if not cells[cols["file"]]:
            raise FileFormatError(path, "file is empty: expected the log's name", number)
        out.append(Window(folder / cells[cols["file"]], start, end, f"{path}:{number}", group, law, speed))
    if not out:
        raise FileFormatError(path, "no windows (a header but no rows)")
    return out


def _whole(cell: str, name: str, path: Path, line: int) -> int:
    try:
        value = float(cell)
    except ValueError:
        raise FileFormatError(path, f"{name} = {cell!r}: expected a sample number", line) from None
    if not (math.isfinite(value) and value == int(value)):
        raise FileFormatError(path, f"{name} = {cell}: expected a whole sample number", line)
    return int(value)


def read_laws(table: object, path: Path | str, text: str | None = None) -> dict[str, ControlLaw]:
    """``[control.<name>]`` tables: gains as numbers, ``{ speed = [...], gain = [...] }`` or ramps."""
    path = str(path)
    if not isinstance(table, dict):
        raise InputError("control", table, "tables [control.<name>] of gains", path)
    laws = {}
    for name, entry in table.items():
        line = _line_of(text, rf"^\s*\[\s*control\.{re.escape(name)}\s*\]") if text else None
        where = f"{path}:{line}" if line else path
        if not isinstance(entry, dict):
            raise InputError(
                f"control.{name}", entry, "a table [control.<name>] of gains " + ", ".join(GAIN_NAMES), where
            )
        gains = {}
        description = ""
        for key, raw in entry.items():
            at = _line_of(text, rf"^\s*{re.escape(key)}\s*=", line or 0) if text else None
            here = f"{path}:{at}" if at else where
            if key == "description":
                description = _text(raw, f"control.{name}.description", here)
                continue
            if key not in GAIN_NAMES:
                raise InputError(
                    f"control.{name}.{key}", raw, "one of the gains " + ", ".join(GAIN_NAMES) + " or description", here
                )
            gains[key] = _schedule(raw, f"control.{name}.{key}", here)
        law = ControlLaw(name, gains, description, where)
        _check_law(law, where)
        laws[name] = law
    return laws


def _schedule(raw: object, name: str, where: str) -> GainSchedule:
    if isinstance(raw, dict):
        keys = set(raw)
        if keys == {"speed", "gain"}:
            return GainSchedule.piecewise(raw["speed"], raw["gain"], name, where)
        if keys == {"K", "v0", "when"}:
            return GainSchedule.make_ramp(raw["K"], raw["v0"], raw["when"], name, where)
        raise InputError(
            name, raw, 'a number, { speed = [...], gain = [...] } or { K = ..., v0 = ..., when = "below" }', where
        )
    return GainSchedule.constant(raw, name, where)  # type: ignore[arg-type]


def _check_law(law: ControlLaw, where: str) -> None:
    """Evaluate a law over 0-30 m/s: every gain must come out finite."""
    speeds = np.linspace(0.0, 30.0, 61)
    values = law(speeds)
    if not np.all(np.isfinite(values)):
        k = int(np.flatnonzero(~np.all(np.isfinite(values), axis=1))[0])
        raise InputError(
            f"control.{law.name}", law.describe(), f"finite gains at every speed (not at {speeds[k]:g} m/s)", where
        )


def _read_speed(settings: ExperimentSettings, table: object, where) -> None:
    if not isinstance(table, dict):
        raise InputError("speed", table, "a table [speed]", where("speed"))
    allowed = {"source", "pattern", "unit", "calibration"}
    for key in table:
        if key not in allowed:
            raise InputError(f"speed.{key}", table[key], "one of " + ", ".join(sorted(allowed)), where(key))
    if "source" in table:
        settings.speed_source = _text(table["source"], "speed.source", where("source"))
    if "pattern" in table:
        raw = _text(table["pattern"], "speed.pattern", where("pattern"))
        try:
            settings.speed_pattern = re.compile(raw)
        except re.error as exc:
            raise InputError("speed.pattern", raw, f"a regular expression ({exc})", where("pattern")) from None
        if "speed" not in settings.speed_pattern.groupindex:
            raise InputError("speed.pattern", raw, "a regular expression with a group (?P<speed>...)", where("pattern"))
    if "unit" in table:
        unit = _text(table["unit"], "speed.unit", where("unit"))
        if unit not in SPEED_UNITS:
            raise InputError("speed.unit", unit, "one of " + ", ".join(SPEED_UNITS), where("unit"))
        settings.speed_unit = SPEED_UNITS[unit]
    if "calibration" in table:
        cal = table["calibration"]
        if not (isinstance(cal, dict) and set(cal) == {"gain", "offset"}):
            raise InputError(
                "speed.calibration",
                cal,
                "{ gain = ..., offset = ... } (recorded = gain * true + offset)",
                where("calibration"),
            )
        gain = _number(cal["gain"], "speed.calibration.gain", where("calibration"))
        offset = _real(cal["offset"])
        if offset is None or abs(offset) > MAX_MAGNITUDE:
            raise InputError(
                "speed.calibration.offset",
                _shown(cal["offset"]),
                f"a finite number of at most {MAX_MAGNITUDE:g} m/s",
                where("calibration"),
            )
        settings.calibration = (gain, offset)


def _detector(table: object, where: str) -> DetectorSettings:
    if not isinstance(table, dict):
        raise InputError("experiment.detector", table, "a table of detector settings", where)
    fields = DetectorSettings.__dataclass_fields__
    for key, value in table.items():
        if key not in fields:
            raise InputError(f"experiment.detector.{key}", value, "one of " + ", ".join(fields), where)
        x = _number(value, f"experiment.detector.{key}", where)
        if x > MAX_DETECTOR[key]:
            raise InputError(f"experiment.detector.{key}", _shown(value), f"at most {MAX_DETECTOR[key]:g}", where)
    return DetectorSettings(**{k: float(v) for k, v in table.items()})


def _text(value: object, name: str, where: str) -> str:
    if not isinstance(value, str) or not value:
        raise InputError(name, value, "a text", where)
    return value


def check_delimiter(value: str, where: str | None = None) -> str:
    """A log delimiter: one character that is not a quote, a comment, a line end or part of a number."""
    if len(value) != 1 or value in BAD_DELIMITERS or value.isalnum():
        raise InputError(
            "experiment.delimiter",
            value,
            "one character that separates cells, such as ',', ';', a tab or a space (not a quote, '#', a line "
            "end, a letter, a digit or a sign)",
            where,
        )
    return value


def check_sample_rate(rate: float, name: str, where: str | None = None) -> None:
    """A sampling rate within :data:`SAMPLE_RATES` (``name``: the option or key, for the message)."""
    low, high = SAMPLE_RATES
    if not (math.isfinite(rate) and low <= rate <= high):  # also NaN
        raise InputError(name, rate, f"a sampling rate from {low:g} to {high:g} Hz", where)


def check_record_count(count: int, where: str) -> None:
    """Refuse more than :data:`MAX_RECORDS` records (``where``: the manifests, for the message)."""
    if count > MAX_RECORDS:
        raise InputError(
            "records",
            f"{count:,}",
            f"at most {MAX_RECORDS:,} records in one run (each is fitted on every fold: about 30 ms and 0.15 MB "
            "a record); check the windows for repeats, or split the experiment",
            where,
        )


def experiment_files(settings: ExperimentSettings, windows: list[Window]) -> list[Path]:
    """The files a manifest makes the run read besides itself: its windows file and every log (plain
    and ``.gz``): inputs of the run, which no output may overwrite or remove."""
    out = list(settings.files)
    for w in windows:
        out += [w.file, w.file.with_name(w.file.name + ".gz")]
    return list(dict.fromkeys(out))


def _number(value: object, name: str, where: str) -> float:
    x = _real(value)
    if x is None or x <= 0:
        raise InputError(name, _shown(value), "a positive number", where)
    return x


def _speed_value(value: object, name: str, where: str) -> float:
    x = _real(value)
    if x is None or not 0 < x <= MAX_MAGNITUDE:
        raise InputError(name, _shown(value), f"a positive speed of at most {MAX_MAGNITUDE:g} m/s", where)
    return x


def _real(value: object) -> float | None:
    """A TOML number as a float; ``None`` for anything else (a bool, a text, NaN, infinity, or an
    integer too large for a float)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    try:
        x = float(value)
    except OverflowError:
        return None
    return x if math.isfinite(x) else None


def _shown(value: object) -> object:
    """A value for a message: an integer of many digits shortened."""
    if isinstance(value, int) and not isinstance(value, bool) and len(str(abs(value))) > 20:
        return f"{str(value)[:8]}... ({len(str(abs(value)))} digits)"
    return value


# ---------------------------------------------------------------------------------------------
# Cutting the records
# ---------------------------------------------------------------------------------------------
def window_logs(settings: ExperimentSettings, windows: list[Window]) -> Iterator[tuple[Window, Log]]:
    """Each window with its log, every log read once, when its first window comes.

    The pipeline (:func:`bikerider.diagnose.load_records`) cuts the records from them, finding the
    decays of a ``detect = true`` file in :func:`detection_signal` first.

    Raises
    ------
    FileFormatError
        A log that cannot be read or lacks a column (naming the manifest's line, too).
    """
    settings.check()
    wanted = sorted({c for k, c in settings.columns.items()})
    logs: dict[Path, Log] = {}
    for window in windows:
        if window.file not in logs:
            try:
                logs[window.file] = read_log(_find(window.file), wanted, settings.delimiter)
            except FileFormatError as exc:  # say where the log was named, too
                where = exc.path if exc.line is None else f"{exc.path}:{exc.line}"
                detail = str(exc).removeprefix(f"{where}: ")
                raise FileFormatError(exc.path, f"{detail} (the log of {window.source})", exc.line) from None
        yield window, logs[window.file]


def detection_signal(log: Log, settings: ExperimentSettings) -> tuple[np.ndarray, float]:
    """The roll rate [rad/s] a log's decays are detected in, and the log's sampling rate [Hz]."""
    rate = settings.sample_rate or _rate_of(log, settings)
    return log.columns[settings.columns["roll_rate"]] * settings.scale.get("roll_rate", 1.0), rate


def _find(path: Path) -> Path:
    """A log, or its compressed copy (``.gz``) when the plain file is not there."""
    if not path.exists():
        packed = path.with_name(path.name + ".gz")
        if packed.exists():
            return packed
    return path


def _rate_of(log: Log, settings: ExperimentSettings) -> float:
    """The log's sampling rate: one over the median forward step of its time column (cached per log)."""
    cached = getattr(log, "_rate", None)
    if cached is not None:
        return cached
    t = log.columns[settings.columns["time"]]
    steps = np.diff(t[np.isfinite(t)])
    steps = steps[steps > 0]  # repeated stamps and clock resets are not the rate
    rate = 1.0 / float(np.median(steps)) if steps.size else 1.0
    log._rate = rate  # type: ignore[attr-defined]
    return rate


def cut_record(log: Log, start: int, end: int, window: Window, settings: ExperimentSettings) -> Record:
    """The record of samples ``start .. end`` of ``log`` (a window, or a decay detected in it).

    Raises
    ------
    FileFormatError
        A window that is empty, outside its log or longer than one decay (naming the manifest's
        line).
    """
    where = window.source
    if not (0 <= start < end):
        raise FileFormatError(
            where.rsplit(":", 1)[0],
            f"window [{start}, {end}] of {log.path.name}: expected 0 <= start < end",
            _line(where),
        )
    if end > log.n:
        raise FileFormatError(
            where.rsplit(":", 1)[0],
            f"window [{start}, {end}] ends after the last sample of {log.path.name} ({log.n} samples)",
            _line(where),
        )
    if end - start > MAX_RECORD_SAMPLES:
        raise FileFormatError(
            where.rsplit(":", 1)[0],
            f"window [{start}, {end}] of {log.path.name} holds {end - start} samples: expected one free decay "
            f"of at most {MAX_RECORD_SAMPLES}",
            _line(where),
        )
    name = f"{log.path.name}[{start}:{end}]"
    if "time" in settings.columns:
        t = log.columns[settings.columns["time"]][start:end]
        first = np.flatnonzero(np.isfinite(t))
        time = t - t[first[0]] if first.size else np.full(end - start, np.nan)  # stamps repaired when fitted
    else:
        step = 1.0 / float(settings.sample_rate) if float(settings.sample_rate) > 1e-300 else math.inf  # type: ignore[arg-type]
        time = np.arange(end - start) * step if math.isfinite(step) else np.full(end - start, np.nan)
    signals = {}
    problem = (
        None
        if np.any(np.isfinite(time)) or "time" in settings.columns
        else (f"sample_rate = {settings.sample_rate:g} Hz gives no finite sample times")
    )
    for signal in SIGNALS:
        if signal in settings.columns:
            values = log.columns[settings.columns[signal]][start:end] * settings.scale.get(signal, 1.0)
            signals[signal] = values
            # missing values are repaired (or the record left out) when it is fitted: bikerider.gap.measured.repair
            huge = np.flatnonzero(np.abs(values) > MAX_MAGNITUDE)
            if huge.size and problem is None:
                problem = (
                    f"{signal} ({settings.columns[signal]}) = {values[huge[0]]:g} at sample {start + int(huge[0])}: "
                    f"above {MAX_MAGNITUDE:g} {SIGNAL_UNITS[signal]} (check the column and its units)"
                )
    if problem is None and not np.any(np.isfinite(time)):
        problem = "the time column has no value in the window"
    speed, speed_sigma, controller = _speed(log, start, end, window, settings)
    if problem is None and not (math.isfinite(speed) and speed > 0):
        problem = f"no positive speed in the window (speed {speed:g} m/s)"
    elif problem is None and not (speed <= MAX_MAGNITUDE and abs(controller) <= MAX_MAGNITUDE):
        problem = f"speed {speed:g} m/s in the window: above {MAX_MAGNITUDE:g} m/s (check the speed column's units)"
    law_name = window.law or settings.default_law
    law = settings.laws[law_name] if law_name else NO_CONTROL
    group = window.group or (log.path.name.removesuffix(".gz") if settings.group == "file" else settings.group)
    measured = window.speed is None and settings.speed_source == "column"
    step = (
        1.0 / _rate_of(log, settings)
        if "time" in settings.columns
        else float(time[1] - time[0])
        if time.size > 1
        else None
    )
    return Record(
        name,
        where,
        time,
        signals,
        speed,
        speed_sigma,
        group,
        law,
        controller,
        (start, end),
        problem,
        tuple(settings.fit),
        measured,
        step=step,
    )


def _line(where: str) -> int | None:
    tail = where.rsplit(":", 1)
    return int(tail[1]) if len(tail) == 2 and tail[1].isdigit() else None


def _speed(log: Log, start: int, end: int, window: Window, settings: ExperimentSettings) -> tuple[float, float, float]:
    """Plant speed, its scatter and the controller's speed over a window."""
    if window.speed is not None:
        return window.speed, 0.0, window.speed
    if settings.speed_source == "column":
        values = log.columns[settings.columns["speed"]][start:end]
        values = values[np.isfinite(values)]
        if values.size == 0:
            return math.nan, 0.0, math.nan
        huge = values[np.abs(values) > MAX_MAGNITUDE]
        if huge.size:  # the record is left out naming it (its mean and scatter would overflow)
            return float(huge[0]), 0.0, float(huge[0])
        recorded = float(np.mean(values))
        scatter = float(np.std(values))
        if settings.calibration is not None:
            gain, offset = settings.calibration
            return (recorded - offset) / gain, scatter / abs(gain), recorded
        return recorded, scatter, recorded
    if settings.speed_source == "file_name":
        match = settings.speed_pattern.search(log.path.name)  # type: ignore[union-attr]
        if match is None:
            raise FileFormatError(
                window.source.rsplit(":", 1)[0],
                f"speed.pattern {settings.speed_pattern.pattern!r} does not match the file name {log.path.name}",
                _line(window.source),
            )
        try:
            value = float(match.group("speed")) * settings.speed_unit
        except ValueError:
            raise FileFormatError(
                window.source.rsplit(":", 1)[0],
                f"speed {match.group('speed')!r} in the file name {log.path.name}: expected a number",
                _line(window.source),
            ) from None
        return value, 0.0, value
    raise InputError(
        "speed", "missing", 'a speed for the file (speed.source = "value" needs file.speed)', window.source
    )


def _csv_cells(line: str, path, number: int, delimiter: str = ",") -> list[str]:
    """The stripped cells of one line of a windows file or of a log's header; a line the csv module
    cannot split (a cell beyond its field limit, an unclosed quote) is an error naming the line."""
    try:
        return [c.strip() for c in next(csv.reader(io.StringIO(line), delimiter=delimiter))]
    except csv.Error as exc:
        kind = "comma" if delimiter == "," else repr(delimiter)
        raise FileFormatError(path, f"not a {kind}-separated line ({str(exc)[:60]})", number) from None
