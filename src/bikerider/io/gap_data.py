"""Read the tables of the gap diagnosis: eigenvalues, perturbation time series, identified matrices.

Raw logs cut into records by a manifest are read by :mod:`bikerider.io.experiment`; the data
classes these readers build are in :mod:`bikerider.gap.measured.tables` and :mod:`bikerider.gap.measured.records`.

Formats (comma-separated, a header line of column names; lines starting with ``#`` are comments;
a comment ``# key = value`` sets a file-wide value, e.g. ``# speed = 4.2``, ``# group = run3`` or a
control gain ``# k_phid = 1.5``):

Eigenvalues against speed
    Columns ``speed, real, imag`` [m/s, 1/s, 1/s]; optional ``real_sigma, imag_sigma`` (standard
    uncertainties, > 0), ``speed_sigma``, ``group`` (a run, a rider, a day: the unit the diagnosis
    holds out), ``mode`` (``weave``, ``capsize``, ``castor``; default ``weave`` when ``imag != 0``,
    otherwise the nearer real mode of the model), the control gains ``k_phi, k_phid, k_delta,
    k_deltad`` (see :mod:`bikerider.gap.measured.control`) or ``control``, the name of a law given with
    the data (its gains evaluated at the row's speed).
Perturbation time series (one run per file)
    Columns ``time`` [s] and ``roll_rate`` [rad/s]; optional ``steer_angle`` [rad], ``steer_rate``
    [rad/s] and ``speed`` [m/s].  The speed comes from a ``speed`` column (its mean; its scatter is
    the speed uncertainty), a ``# speed = ...`` comment or the caller.  The file should hold the free
    decay after the perturbation.  The weave eigenvalue is fitted to the roll rate (and to the steer
    rate when given, the two combined by inverse-variance weighting when they agree) with
    :func:`bikerider.gap.measured.extraction.weave_eigenvalue` (a
    :func:`~bikerider.fitting.damped_oscillation.fit_damped_oscillation` fit refined with the slow
    capsize mode).
Identified canonical-matrix entries
    Columns ``rider, environment, coefficient, identified, sigma`` as in Moore (2012) Tables
    11.2-11.9; ``coefficient`` is e.g. ``Mphidelta`` or ``K2deltadelta``; other columns are
    ignored.  ``group`` is ``rider-environment``.  The speed range of the runs behind each subset is
    given by ``speed_min, speed_max`` columns or ``# speed_min = ...`` comments.

Every reader raises :class:`~bikerider.errors.FileFormatError` naming the file and line for a
malformed line, and for a non-finite number or a speed that is not positive.
"""

from __future__ import annotations

import csv
import io
import logging
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bikerider.errors import FileFormatError, InputError
from bikerider.gap.measured.control import GAIN_NAMES, MAX_MAGNITUDE, ControlLaw, GainSchedule
from bikerider.gap.measured.records import MAX_RECORD_SAMPLES, Record
from bikerider.gap.measured.tables import CANONICAL_ENTRIES, MODES, CanonicalData, EigenvalueData, entry_name
from bikerider.generated.manifest import MATRIX_NAMES
from bikerider.io.experiment import read_laws, read_text
from bikerider.io.input_file import checked_input_file
from bikerider.io.toml_input import read_toml
from bikerider.quantity import parse_quantity

LOG = logging.getLogger(__name__)

EIGENVALUE_COLUMNS = (
    "speed",
    "real",
    "imag",
    "real_sigma",
    "imag_sigma",
    "speed_sigma",
    "group",
    "mode",
    "control",
) + GAIN_NAMES
TIME_SERIES_COLUMNS = ("time", "roll_rate", "roll_angle", "steer_angle", "steer_rate", "speed")


MAX_CONTROL_BYTES = 1_000_000
"""Largest control file read [bytes] (a few laws of four gains: a few kB)."""
MAX_EIGENVALUE_ROWS = 10_000
"""Most rows of one eigenvalue table: one row per test run is a few hundred at most; the diagnosis
fits every candidate to every row on every fold (about a tenth of a second per row with all the
candidates), so a larger table is refused rather than left running for hours."""
MAX_TABLE_BYTES = 16_000_000
"""Largest data table read [bytes]: far above any table of measured eigenvalues or identified entries
(:data:`MAX_EIGENVALUE_ROWS` rows take about 1 MB) or a perturbation run of
:data:`~bikerider.gap.measured.records.MAX_RECORD_SAMPLES` samples (a few MB); a larger file is refused with its
size before it is read."""


# ---------------------------------------------------------------------------------------------
# CSV plumbing
# ---------------------------------------------------------------------------------------------
@dataclass
class _Table:
    path: Path
    columns: list[str]
    rows: list[tuple[int, list[str]]]
    meta: dict[str, tuple[int, str]]


def _read_table(path: str | Path) -> _Table:
    path = checked_input_file(path, MAX_TABLE_BYTES, "data table")
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FileFormatError(path, f"not UTF-8 text (byte {exc.start})") from None
    meta: dict[str, tuple[int, str]] = {}
    columns: list[str] | None = None
    rows: list[tuple[int, list[str]]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            body = stripped.lstrip("#").strip()
            if "=" in body:
                key, value = (part.strip() for part in body.split("=", 1))
                if key.isidentifier():
                    meta[key] = (number, value)
            continue
        try:
            cells = next(csv.reader(io.StringIO(line)))
        except csv.Error as exc:
            raise FileFormatError(path, f"not a comma-separated line ({exc})", number) from None
        cells = [c.strip() for c in cells]
        if columns is None:
            columns = cells
            if len(set(columns)) != len(columns):
                raise FileFormatError(path, f"repeated column name in header {columns}", number)
            continue
        if len(cells) != len(columns):
            raise FileFormatError(
                path, f"expected {len(columns)} comma-separated values ({', '.join(columns)}), got {len(cells)}", number
            )
        rows.append((number, cells))
    if columns is None:
        raise FileFormatError(path, "no header line (column names) found")
    table = _Table(path, columns, rows, meta)
    _check_meta_numbers(table)
    return table


META_NUMBERS = {"speed": "positive", "speed_sigma": "nonnegative", "speed_min": "positive", "speed_max": "positive"}
"""The ``# key = value`` comments that hold numbers (with the gains), and the sign they need."""


def _check_meta_numbers(table: _Table) -> None:
    """Every numeric ``# key = value`` comment is a number, whether or not a column makes it unused
    (a ``# speed = abc`` beside a speed column is a mistake, not a comment to skip)."""
    for key in (*META_NUMBERS, *GAIN_NAMES):
        sign = META_NUMBERS.get(key)
        _meta_number(table, key, positive=sign == "positive", nonnegative=sign == "nonnegative")


def _number(
    table: _Table,
    line: int,
    column: str,
    raw: str,
    *,
    positive: bool = False,
    nonnegative: bool = False,
    optional: bool = False,
) -> float:
    if raw == "":
        if optional:
            return math.nan
        raise FileFormatError(table.path, f"{column} is empty: expected a number", line)
    try:
        value = float(raw)
    except ValueError:
        raise FileFormatError(table.path, f"{column} = {raw!r}: expected a number", line) from None
    if not math.isfinite(value):
        raise FileFormatError(table.path, f"{column} = {raw}: expected a finite number", line)
    if abs(value) > MAX_MAGNITUDE:  # no speed, eigenvalue, gain or time of a bicycle test; overflows later
        raise FileFormatError(
            table.path,
            f"{column} = {raw}: expected a magnitude of at most {MAX_MAGNITUDE:g} (check the units and the column)",
            line,
        )
    if positive and not value > 0:
        raise FileFormatError(table.path, f"{column} = {raw}: expected a positive number", line)
    if nonnegative and value < 0:
        raise FileFormatError(table.path, f"{column} = {raw}: expected a number >= 0", line)
    return value


def _meta_number(table: _Table, key: str, *, positive: bool = False, nonnegative: bool = False) -> float | None:
    if key not in table.meta:
        return None
    line, raw = table.meta[key]
    return _number(table, line, key, raw, positive=positive, nonnegative=nonnegative)


def _check_columns(
    table: _Table, allowed: tuple[str, ...], required: tuple[str, ...], ignored: tuple[str, ...] = ()
) -> None:
    header_line = min((n for n, _ in table.rows), default=2) - 1
    for name in table.columns:
        if name not in allowed and name not in ignored:
            raise FileFormatError(
                table.path, f"unknown column {name!r}: expected some of {', '.join(allowed)}", header_line
            )
    for name in required:
        if name not in table.columns:
            raise FileFormatError(
                table.path, f"missing column {name!r} (columns are {', '.join(table.columns)})", header_line
            )


def _row_law(
    table: _Table,
    line: int,
    cells: list[str],
    cols: dict[str, int],
    speed: float,
    default: ControlLaw | None,
    laws: dict[str, ControlLaw],
) -> tuple[np.ndarray, ControlLaw]:
    """The control law of a row and its gains at the row's speed.

    A ``control`` column (or ``# control = NAME`` comment) names a law given with the data; gain
    columns or ``# k_... =`` comments give constant gains; otherwise the default law (``--control``)
    acts, or none.
    """
    name = cells[cols["control"]].strip() if "control" in cols else ""
    if not name and "control" in table.meta:
        line, name = table.meta["control"]
    if name:
        if name not in laws:
            raise FileFormatError(
                table.path,
                f"control = {name!r}: expected the name of a law given with --control "
                f"({', '.join(laws) or 'none given'})",
                line,
            )
        law = laws[name]
        return law(speed), law
    given = {}
    for name in GAIN_NAMES:
        meta = _meta_number(table, name)
        if meta is not None:
            given[name] = meta
        if name in cols and cells[cols[name]] != "":
            given[name] = _number(table, line, name, cells[cols[name]])
    if given:
        gains = np.array([given.get(k, 0.0) for k in GAIN_NAMES])
        return gains, ControlLaw.constant(gains)
    if default is not None:
        return default(speed), default
    return np.zeros(4), ControlLaw.constant(np.zeros(4))


# ---------------------------------------------------------------------------------------------
# Readers
# ---------------------------------------------------------------------------------------------
def read_eigenvalues(
    path: str | Path, law: ControlLaw | None = None, laws: dict[str, ControlLaw] | None = None
) -> EigenvalueData:
    """Read measured eigenvalues against speed (format in the module docstring).

    Parameters
    ----------
    path : path
    law : ControlLaw, optional
        The law acting in rows that name none and give no gains.
    laws : dict, optional
        Laws a ``control`` column or comment may name.
    """
    table = _read_table(path)
    _check_columns(table, EIGENVALUE_COLUMNS, ("speed", "real", "imag"))
    laws = dict(laws or {})
    if law is not None:
        laws.setdefault(law.name, law)
    file_group = table.meta.get("group", (0, table.path.stem))[1]
    cols = {name: i for i, name in enumerate(table.columns)}
    out = {k: [] for k in ("speed", "value", "rs", "is", "ss", "mode", "group", "gains", "source", "law")}
    used_laws: dict[str, ControlLaw] = {}
    if not table.rows:
        raise FileFormatError(table.path, "no data rows")
    if len(table.rows) > MAX_EIGENVALUE_ROWS:
        raise FileFormatError(
            table.path,
            f"{len(table.rows)} rows: expected at most {MAX_EIGENVALUE_ROWS} measured eigenvalues in one table "
            "(a row per test run; is this a time series? give it as a perturbation run or a log)",
        )
    for line, cells in table.rows:

        def get(name, **kw):
            return _number(table, line, name, cells[cols[name]], **kw) if name in cols else math.nan

        speed = get("speed", positive=True)
        real, imag = get("real"), get("imag")
        rs = get("real_sigma", positive=True, optional=True) if "real_sigma" in cols else math.nan
        is_ = get("imag_sigma", positive=True, optional=True) if "imag_sigma" in cols else math.nan
        ss = get("speed_sigma", nonnegative=True, optional=True) if "speed_sigma" in cols else math.nan
        if ss >= speed:  # the diagnosis evaluates the model at speed +/- speed_sigma
            raise FileFormatError(
                table.path,
                f"speed_sigma = {ss:g}: expected a standard uncertainty below the speed ({speed:g} m/s)",
                line,
            )
        mode = (
            cells[cols["mode"]].strip().lower()
            if "mode" in cols and cells[cols["mode"]].strip()
            else ("weave" if imag != 0 else "auto")
        )
        if mode not in MODES and mode != "auto":
            raise FileFormatError(table.path, f"mode = {mode!r}: expected one of {', '.join(MODES)}", line)
        if mode != "weave" and imag != 0:
            raise FileFormatError(table.path, f"mode = {mode} with imag = {imag}: only the weave mode oscillates", line)
        gains, row_law = _row_law(table, line, cells, cols, speed, law, laws)
        if row_law.name in used_laws and used_laws[row_law.name] != row_law:
            raise FileFormatError(table.path, f"two control laws named {row_law.name!r}", line)
        used_laws[row_law.name] = row_law
        out["speed"].append(speed)
        out["value"].append(complex(real, abs(imag)))
        out["rs"].append(rs)
        out["is"].append(is_)
        out["ss"].append(0.0 if math.isnan(ss) else ss)
        out["mode"].append(mode)
        out["group"].append(cells[cols["group"]] if "group" in cols and cells[cols["group"]] else file_group)
        out["gains"].append(gains)
        out["source"].append(f"{table.path}:{line}")
        out["law"].append(row_law.name)
    return EigenvalueData(
        np.array(out["speed"]),
        np.array(out["value"], complex),
        np.array(out["rs"]),
        np.array(out["is"]),
        np.array(out["ss"]),
        out["mode"],
        out["group"],
        np.array(out["gains"]),
        out["source"],
        out["law"],
        used_laws,
    )


def read_perturbation(
    path: str | Path, speed: float | None = None, law: ControlLaw | None = None, group: str | None = None
) -> Record:
    """Read one perturbation run as a record (format in the module docstring).

    Raises
    ------
    FileFormatError
        Malformed file, no speed anywhere, or a non-positive speed.
    """
    table = _read_table(path)
    _check_columns(table, TIME_SERIES_COLUMNS, ("time", "roll_rate"))
    if len(table.rows) > MAX_RECORD_SAMPLES:
        raise FileFormatError(
            table.path,
            f"{len(table.rows)} samples: expected one free decay of at most {MAX_RECORD_SAMPLES} samples "
            "(cut the decay after the perturbation out, or give the log with a manifest of windows)",
        )
    cols = {name: i for i, name in enumerate(table.columns)}
    data = {name: np.empty(len(table.rows)) for name in table.columns}
    for k, (line, cells) in enumerate(table.rows):
        for name in table.columns:
            data[name][k] = _number(table, line, name, cells[cols[name]], positive=(name == "speed"))
    if len(table.rows) < 2:
        raise FileFormatError(table.path, f"{len(table.rows)} samples: a time series needs many")
    # stamps that repeat, go back or jump (a logger's clock) are repaired when the record is fitted,
    # each repair said (bikerider.gap.measured.repair); only a run whose time never advances is refused
    if not np.any(np.diff(data["time"]) > 0):
        raise FileFormatError(table.path, f"time = {data['time'][0]:g} throughout: expected increasing time stamps")
    if "speed" in data:
        v, v_sigma = float(np.mean(data["speed"])), float(np.std(data["speed"]))
    elif speed is not None:
        if not (isinstance(speed, (int, float)) and not isinstance(speed, bool) and 0 < speed <= MAX_MAGNITUDE):
            raise InputError(
                "speed", speed, f"a positive speed of at most {MAX_MAGNITUDE:g} m/s (check the units)", str(table.path)
            )
        v, v_sigma = float(speed), 0.0
    else:
        v_meta = _meta_number(table, "speed", positive=True)
        if v_meta is None:
            raise FileFormatError(
                table.path, "no speed: give a 'speed' column, a '# speed = ...' comment or the speed argument"
            )
        v, v_sigma = v_meta, 0.0
    meta_sigma = _meta_number(table, "speed_sigma", nonnegative=True)
    if meta_sigma is not None:
        v_sigma = max(v_sigma, meta_sigma)
    if v_sigma >= v:  # the diagnosis evaluates the model at speed +/- its uncertainty
        raise FileFormatError(
            table.path,
            f"speed {v:g} m/s with uncertainty {v_sigma:g} m/s: expected an "
            "uncertainty below the speed (a run whose speed varies this much has no one weave eigenvalue)",
        )
    meta_gains = {k: _meta_number(table, k) for k in GAIN_NAMES}
    if any(g is not None for g in meta_gains.values()):
        run_law = ControlLaw.constant([meta_gains[k] or 0.0 for k in GAIN_NAMES])
    elif law is not None:
        run_law = law
    else:
        run_law = ControlLaw.constant(np.zeros(4))
    file_group = group or table.meta.get("group", (0, table.path.stem))[1]
    time = data.pop("time")
    signals = {k: data[k] for k in ("roll_rate", "roll_angle", "steer_angle", "steer_rate") if k in data}
    fit = ("roll_rate", "steer_rate") if "steer_rate" in signals else ("roll_rate",)
    return Record(
        table.path.name,
        str(table.path),
        time - time[0],
        signals,
        v,
        v_sigma,
        file_group,
        run_law,
        v,
        None,
        None,
        fit,
        "speed" in data,
    )


def read_canonical(path: str | Path, groups: list[str] | None = None) -> CanonicalData:
    """Read identified canonical-matrix entries (format in the module docstring).

    Parameters
    ----------
    groups : list of str, optional
        Keep only these ``rider-environment`` groups.
    """
    table = _read_table(path)
    required = ("rider", "environment", "coefficient", "identified", "sigma")
    _check_columns(
        table,
        required + ("speed_min", "speed_max"),
        required,
        ignored=tuple(c for c in table.columns if c not in required + ("speed_min", "speed_max")),
    )
    cols = {name: i for i, name in enumerate(table.columns)}
    v_min = _meta_number(table, "speed_min", positive=True)
    v_max = _meta_number(table, "speed_max", positive=True)
    out = CanonicalData([], np.empty(0), np.empty(0), [], {}, [])
    values, sigmas = [], []
    skipped = set()
    for line, cells in table.rows:
        group = f"{cells[cols['rider']]}-{cells[cols['environment']]}"
        if groups is not None and group not in groups:
            continue
        name = entry_name(cells[cols["coefficient"]])
        if name is None:
            _check_not_a_matrix_typo(table, line, cells[cols["coefficient"]])
            skipped.add(cells[cols["coefficient"]])
            continue
        values.append(_number(table, line, "identified", cells[cols["identified"]]))
        sigmas.append(_number(table, line, "sigma", cells[cols["sigma"]], positive=True))
        lo = (
            _number(table, line, "speed_min", cells[cols["speed_min"]], positive=True) if "speed_min" in cols else v_min
        )
        hi = (
            _number(table, line, "speed_max", cells[cols["speed_max"]], positive=True) if "speed_max" in cols else v_max
        )
        if lo is None or hi is None:
            raise FileFormatError(table.path, "no speed range: give speed_min and speed_max columns or comments", line)
        if not hi > lo:
            raise FileFormatError(table.path, f"speed_max = {hi} is not above speed_min = {lo}", line)
        if group in out.speed_range and out.speed_range[group] != (lo, hi):
            raise FileFormatError(table.path, f"group {group} has two speed ranges", line)
        out.speed_range[group] = (lo, hi)
        out.entry.append(name)
        out.group.append(group)
        out.source.append(f"{table.path}:{line}")
    if skipped:
        LOG.info("%s: not canonical-matrix entries, left out: %s", table.path, ", ".join(sorted(skipped)))
    if not out.entry:
        raise FileFormatError(table.path, "no canonical-matrix entries" + (f" in groups {groups}" if groups else ""))
    out.value, out.sigma = np.array(values), np.array(sigmas)
    return out


def _check_not_a_matrix_typo(table: _Table, line: int, raw: str) -> None:
    """A coefficient named like a canonical-matrix entry (``M``, ``C1``, ``K0``, ``K2`` and more) that
    is none of them is a typo, not a row of another matrix to leave out (``HdeltaF`` is left out)."""
    text = raw.strip()
    if any(text.startswith(prefix) for prefix in MATRIX_NAMES):
        raise FileFormatError(
            table.path,
            f"coefficient = {text!r}: expected one of the canonical-matrix entries "
            f"{', '.join(n.replace('_', '') for n in CANONICAL_ENTRIES)} (a typing slip?)",
            line,
        )


def read_control(path: str | Path) -> dict[str, ControlLaw]:
    """Control laws from a TOML file.

    ``[control]`` with constant gains ``k_phi, k_phid, k_delta, k_deltad`` (one law, named by its
    gains), or named laws ``[control.<name>]`` whose gains may be schedules in speed (see
    :mod:`bikerider.gap.measured.control`).
    """

    data = read_toml(checked_input_file(path, MAX_CONTROL_BYTES, "control file"))
    table = data.get("control", data)
    if not isinstance(table, dict) or not table:
        raise InputError(
            "control", table, "a table of gains " + ", ".join(GAIN_NAMES) + " or laws [control.<name>]", str(path)
        )
    if all(isinstance(v, dict) and "value" not in v for v in table.values()):
        return read_laws(table, path, read_text(path))
    unknown = sorted(set(table) - set(GAIN_NAMES))
    if unknown:
        raise InputError(unknown[0], table[unknown[0]], "one of the gains " + ", ".join(GAIN_NAMES), str(path))
    gains = []
    for k in GAIN_NAMES:
        raw = table.get(k, 0.0)
        if isinstance(raw, str):  # "5.0 +/- 0.1": the value (a known controller's gains are exact)
            raw = parse_quantity(raw, k, str(path)).value
        gains.append(GainSchedule.constant(raw, f"control.{k}", str(path)).values[0])  # finite, within bounds
    law = ControlLaw.constant(gains)
    return {law.name: law}


def detect_kind(path: str | Path) -> str:
    """``eigenvalues``, ``perturbation`` or ``canonical`` from the header of a data file."""
    table = _read_table(path)
    names = set(table.columns)
    if {"time", "roll_rate"} <= names:
        return "perturbation"
    if {"speed", "real", "imag"} <= names:
        return "eigenvalues"
    if {"coefficient", "identified"} <= names:
        return "canonical"
    raise FileFormatError(
        table.path,
        "cannot tell the kind of data: expected columns speed, real, imag "
        "(eigenvalues), time, roll_rate (perturbation run) or rider, environment, coefficient, "
        f"identified, sigma (identified matrices); found {', '.join(table.columns)}",
    )
