"""Measured data for the gap diagnosis: eigenvalues, perturbation time series, identified matrices.

Formats (comma-separated, a header line of column names; lines starting with ``#`` are comments;
a comment ``# key = value`` sets a file-wide value, e.g. ``# speed = 4.2``, ``# group = run3`` or a
control gain ``# k_phid = 1.5``):

Eigenvalues against speed
    Columns ``speed, real, imag`` [m/s, 1/s, 1/s]; optional ``real_sigma, imag_sigma`` (standard
    uncertainties, > 0), ``speed_sigma``, ``group`` (a run, a rider, a day: the unit the diagnosis
    holds out), ``mode`` (``weave``, ``capsize``, ``castor``; default ``weave`` when ``imag != 0``,
    otherwise the nearer real mode of the model), and the control gains ``k_phi, k_phid, k_delta,
    k_deltad`` (see :class:`~bikerider.gap.models.Control`).
Perturbation time series (one run per file)
    Columns ``time`` [s] and ``roll_rate`` [rad/s]; optional ``steer_angle`` [rad], ``steer_rate``
    [rad/s] and ``speed`` [m/s].  The speed comes from a ``speed`` column (its mean; its scatter is
    the speed uncertainty), a ``# speed = ...`` comment or the caller.  The file should hold the free
    decay after the perturbation.  The weave eigenvalue is fitted to the roll rate (and to the steer
    rate when given, the two combined by inverse-variance weighting when they agree) with
    :func:`bikerider.gap.extraction.weave_eigenvalue` (a
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
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bikerider.errors import FileFormatError, FitError, InputError
from bikerider.gap.models import GAIN_NAMES
from bikerider.generated.manifest import MATRIX_NAMES

LOG = logging.getLogger(__name__)

MODES = ("weave", "capsize", "castor")
EIGENVALUE_COLUMNS = ("speed", "real", "imag", "real_sigma", "imag_sigma", "speed_sigma", "group", "mode") + GAIN_NAMES
TIME_SERIES_COLUMNS = ("time", "roll_rate", "steer_angle", "steer_rate", "speed")
CANONICAL_ENTRIES = (
    "M_phidelta",
    "C1_phidelta",
    "K0_phidelta",
    "M_deltadelta",
    "C1_deltaphi",
    "C1_deltadelta",
    "K0_deltadelta",
    "K2_deltadelta",
)
"""The canonical-matrix entries an identification may report (Moore 2012's free entries)."""
_COORDS = {"phi": "phi", "delta": "delta"}


@dataclass
class EigenvalueData:
    """Measured eigenvalues, one row per measurement.

    Attributes
    ----------
    speed, speed_sigma : ndarray
    value : ndarray of complex
        Measured eigenvalue (imaginary part >= 0).
    real_sigma, imag_sigma : ndarray
        Standard uncertainties; NaN where the file gives none.
    mode : list of str
        ``weave``, ``capsize``, ``castor`` or ``auto`` (decided against the model).
    group : list of str
    gains : ndarray, shape (n, 4)
    source : list of str
        ``file:line`` of each row.
    """

    speed: np.ndarray
    value: np.ndarray
    real_sigma: np.ndarray
    imag_sigma: np.ndarray
    speed_sigma: np.ndarray
    mode: list[str]
    group: list[str]
    gains: np.ndarray
    source: list[str]

    def __len__(self) -> int:
        return int(self.speed.size)

    @staticmethod
    def concatenate(parts: list[EigenvalueData]) -> EigenvalueData:
        if not parts:
            return EigenvalueData(
                np.empty(0), np.empty(0, complex), np.empty(0), np.empty(0), np.empty(0), [], [], np.empty((0, 4)), []
            )
        return EigenvalueData(
            np.concatenate([p.speed for p in parts]),
            np.concatenate([p.value for p in parts]),
            np.concatenate([p.real_sigma for p in parts]),
            np.concatenate([p.imag_sigma for p in parts]),
            np.concatenate([p.speed_sigma for p in parts]),
            sum((p.mode for p in parts), []),
            sum((p.group for p in parts), []),
            np.concatenate([p.gains for p in parts]),
            sum((p.source for p in parts), []),
        )


@dataclass
class CanonicalData:
    """Identified canonical-matrix entries, one row per (group, entry)."""

    entry: list[str]
    value: np.ndarray
    sigma: np.ndarray
    group: list[str]
    speed_range: dict[str, tuple[float, float]] = field(default_factory=dict)
    source: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.entry)

    @staticmethod
    def concatenate(parts: list[CanonicalData]) -> CanonicalData:
        out = CanonicalData([], np.empty(0), np.empty(0), [], {}, [])
        for p in parts:
            out.entry += p.entry
            out.group += p.group
            out.source += p.source
            out.value = np.concatenate([out.value, p.value])
            out.sigma = np.concatenate([out.sigma, p.sigma])
            for g, r in p.speed_range.items():
                if g in out.speed_range and out.speed_range[g] != r:
                    raise InputError(
                        f"speed range of group {g}", r, f"the same range in every file ({out.speed_range[g]})"
                    )
                out.speed_range[g] = r
        return out


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
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except FileNotFoundError:
        raise FileFormatError(path, "no such file") from None
    except IsADirectoryError:
        raise FileFormatError(path, "is a folder, not a data file") from None
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
    return _Table(path, columns, rows, meta)


MAX_MAGNITUDE = 1e6
"""Largest magnitude of a number in a data file (speeds in m/s, eigenvalues in 1/s, times in s, gains)."""


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


def _file_gains(table: _Table) -> np.ndarray:
    return np.array([_meta_number(table, k) or 0.0 for k in GAIN_NAMES])


# ---------------------------------------------------------------------------------------------
# Readers
# ---------------------------------------------------------------------------------------------
def read_eigenvalues(path: str | Path, gains=None) -> EigenvalueData:
    """Read measured eigenvalues against speed (format in the module docstring).

    Parameters
    ----------
    path : path
    gains : array_like of 4, optional
        Control gains for rows that give none (overridden by ``# k_... =`` comments and columns).
    """
    table = _read_table(path)
    _check_columns(table, EIGENVALUE_COLUMNS, ("speed", "real", "imag"))
    default_gains = np.zeros(4) if gains is None else np.asarray(gains, dtype=float)
    meta_gains = {k: _meta_number(table, k) for k in GAIN_NAMES}
    file_group = table.meta.get("group", (0, table.path.stem))[1]
    cols = {name: i for i, name in enumerate(table.columns)}
    out = {k: [] for k in ("speed", "value", "rs", "is", "ss", "mode", "group", "gains", "source")}
    if not table.rows:
        raise FileFormatError(table.path, "no data rows")
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
        row_gains = default_gains.copy()
        for k, name in enumerate(GAIN_NAMES):
            if meta_gains[name] is not None:
                row_gains[k] = meta_gains[name]
            if name in cols and cells[cols[name]] != "":
                row_gains[k] = _number(table, line, name, cells[cols[name]])
        out["speed"].append(speed)
        out["value"].append(complex(real, abs(imag)))
        out["rs"].append(rs)
        out["is"].append(is_)
        out["ss"].append(0.0 if math.isnan(ss) else ss)
        out["mode"].append(mode)
        out["group"].append(cells[cols["group"]] if "group" in cols and cells[cols["group"]] else file_group)
        out["gains"].append(row_gains)
        out["source"].append(f"{table.path}:{line}")
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
    )


@dataclass(frozen=True)
class PerturbationRun:
    """A perturbation run read and fitted: the weave eigenvalue with its standard errors."""

    eigenvalues: EigenvalueData
    fits: dict[str, object]
    time: np.ndarray
    signals: dict[str, np.ndarray]


def read_perturbation(
    path: str | Path, speed: float | None = None, gains=None, group: str | None = None
) -> PerturbationRun:
    """Read one perturbation run and fit the weave eigenvalue (format in the module docstring).

    Raises
    ------
    FileFormatError
        Malformed file, no speed anywhere, or a non-positive speed.
    FitError
        No damped oscillation can be fitted to the roll rate (the message names the file).
    """
    from bikerider.gap.extraction import weave_eigenvalue

    table = _read_table(path)
    _check_columns(table, TIME_SERIES_COLUMNS, ("time", "roll_rate"))
    cols = {name: i for i, name in enumerate(table.columns)}
    data = {name: np.empty(len(table.rows)) for name in table.columns}
    for k, (line, cells) in enumerate(table.rows):
        for name in table.columns:
            data[name][k] = _number(table, line, name, cells[cols[name]], positive=(name == "speed"))
    if len(table.rows) < 2:
        raise FileFormatError(table.path, f"{len(table.rows)} samples: a time series needs many")
    steps = np.diff(data["time"])
    if np.any(steps <= 0):
        k = int(np.flatnonzero(steps <= 0)[0])
        raise FileFormatError(table.path, f"time = {data['time'][k + 1]:g} does not increase", table.rows[k + 1][0])
    if "speed" in data:
        v, v_sigma = float(np.mean(data["speed"])), float(np.std(data["speed"]))
    elif speed is not None:
        if not (isinstance(speed, (int, float)) and math.isfinite(speed) and speed > 0):
            raise InputError("speed", speed, "a finite, positive speed [m/s]", str(table.path))
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
    fits: dict[str, object] = {}
    try:
        fits["roll_rate"] = weave_eigenvalue(data["time"], data["roll_rate"])
    except FitError as exc:
        raise FitError(f"{table.path}: roll_rate: {exc}") from None
    estimates = [fits["roll_rate"]]
    if "steer_rate" in data:
        try:
            fits["steer_rate"] = weave_eigenvalue(data["time"], data["steer_rate"])
            estimates.append(fits["steer_rate"])
        except FitError as exc:
            LOG.info("%s: steer_rate not fitted (%s); roll rate alone", table.path, exc)
    value, real_sigma, imag_sigma = _combine_fits(estimates)
    row_gains = np.zeros(4) if gains is None else np.asarray(gains, float).copy()
    for k, name in enumerate(GAIN_NAMES):
        meta = _meta_number(table, name)
        if meta is not None:
            row_gains[k] = meta
    file_group = group or table.meta.get("group", (0, table.path.stem))[1]
    eig = EigenvalueData(
        np.array([v]),
        np.array([value]),
        np.array([real_sigma]),
        np.array([imag_sigma]),
        np.array([v_sigma]),
        ["weave"],
        [file_group],
        row_gains[None, :],
        [str(table.path)],
    )
    return PerturbationRun(eig, fits, data["time"], {k: data[k] for k in data if k != "time"})


def _combine_fits(fits: list) -> tuple[complex, float, float]:
    """Inverse-variance mean of consistent fits (within 3 combined sigma); else the first alone."""
    values = [f.eigenvalue for f in fits]
    rs = [max(f.real_sigma, 1e-12) for f in fits]
    is_ = [max(f.imag_sigma, 1e-12) for f in fits]
    if len(fits) == 2:
        d_r = abs(values[0].real - values[1].real) / math.hypot(rs[0], rs[1])
        d_i = abs(values[0].imag - values[1].imag) / math.hypot(is_[0], is_[1])
        if d_r < 3 and d_i < 3:
            wr = np.array([1 / s**2 for s in rs])
            wi = np.array([1 / s**2 for s in is_])
            real = float(np.sum(wr * [v.real for v in values]) / wr.sum())
            imag = float(np.sum(wi * [v.imag for v in values]) / wi.sum())
            return complex(real, imag), float(1 / math.sqrt(wr.sum())), float(1 / math.sqrt(wi.sum()))
        LOG.warning("roll-rate and steer-rate fits disagree (%.1f, %.1f sigma); using the roll rate", d_r, d_i)
    return values[0], rs[0], is_[0]


def _entry_name(raw: str) -> str | None:
    """``Mphidelta`` -> ``M_phidelta``; ``None`` for entries that are not canonical-matrix entries."""
    raw = raw.strip()
    for prefix in MATRIX_NAMES:
        if raw.startswith(prefix):
            rest = raw[len(prefix) :].lstrip("_")
            name = f"{prefix}_{rest}"
            return name if name in CANONICAL_ENTRIES else None
    return None


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
        name = _entry_name(cells[cols["coefficient"]])
        if name is None:
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


def read_control(path: str | Path) -> np.ndarray:
    """Control gains from a TOML file with a ``[control]`` table (or top-level ``k_phi`` ...)."""
    from bikerider.io.toml_input import read_toml
    from bikerider.quantity import parse_quantity

    data = read_toml(path)
    table = data.get("control", data)
    if not isinstance(table, dict):
        raise InputError("control", table, "a table of gains " + ", ".join(GAIN_NAMES), str(path))
    unknown = sorted(set(table) - set(GAIN_NAMES))
    if unknown:
        raise InputError(unknown[0], table[unknown[0]], "one of the gains " + ", ".join(GAIN_NAMES), str(path))
    return np.array([parse_quantity(table.get(k, 0.0), k, str(path)).value for k in GAIN_NAMES])


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
