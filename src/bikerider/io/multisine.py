"""Steer-torque multisine runs declared in an experiment manifest (``[multisine]``).

The manifest's ``[multisine]`` table names the log column of the applied steer torque and the runs;
the column map, the sampling rate or time column, the speed source, the groups and the control laws
are the manifest's own (:mod:`bikerider.io.experiment`)::

    [multisine]
    torque = "steer_torque"               # the logs' column of the applied steer torque [N m] (required)
    outputs = ["roll_rate", "steer_angle"] # signals compared (default: roll rate, steer angle, steer rate given)
    settle = 2.0                          # seconds at the start of each run left out (transient), default 0
    logs = "multisine"                    # folder of the runs' logs (default: the experiment's logs)
    torque_scale = 1.0                    # optional factor (units, sign convention)

    [[multisine.run]]
    path = "ms_3.00.csv"                  # one run per log, or a window of it
    window = [0, 1000]                    # optional sample window [start, end)
    lines = [0.1, 0.2]                    # optional: the lines [Hz]; default found in the torque
    group = "day 3"                       # optional, as for decays
    control = "sil"                       # optional
    speed = 3.0                           # optional (speed.source = "value")

Every error names the manifest's line, the key, its value and what was expected; a log's errors
name the log, its line and the column.  A run that can be read but not used (missing values
throughout, no positive speed) keeps the reason and is left out by the diagnosis.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from bikerider.errors import FileFormatError, InputError
from bikerider.gap.measured.control import NO_CONTROL
from bikerider.gap.measured.multisine import MAX_LINES, MultisineRecord
from bikerider.gap.measured.records import MAX_RECORD_SAMPLES, SIGNALS
from bikerider.io.experiment import (
    ExperimentSettings,
    Window,
    _find,
    _line_of,
    _real,
    _shown,
    _speed,
    _speed_value,
    _text,
    read_log,
    read_text,
)
from bikerider.io.toml_input import read_toml

MAX_MULTISINE_SAMPLES = 10 * MAX_RECORD_SAMPLES
"""Most samples of one multisine run (a run of minutes at 1 kHz)."""
MAX_TORQUE = 1e3
"""Largest steer torque a log may hold [N m]: no steer actuator applies a kilonewton metre."""
DEFAULT_OUTPUTS = ("roll_rate", "steer_angle", "steer_rate")
RUN_KEYS = {"path", "window", "lines", "group", "control", "speed"}
TABLE_KEYS = {"torque", "outputs", "settle", "logs", "torque_scale", "run"}


def read_multisines(path: str | Path, settings: ExperimentSettings) -> list[MultisineRecord]:
    """The multisine runs of a TOML manifest (none when it has no ``[multisine]`` table), read from
    their logs with the manifest's ``settings`` (:func:`bikerider.io.experiment.read_manifest`)."""
    path = Path(path)
    if path.suffix.lower() != ".toml":
        return []
    data = read_toml(path)
    table = data.get("multisine")
    if table is None:
        return []
    text = read_text(path)

    def where(key: str, after: int = 0) -> str:
        line = _line_of(text, rf"^\s*\[*\s*{key}\b", after)
        return f"{path}:{line}" if line else str(path)

    here = where(r"multisine")
    if not isinstance(table, dict):
        raise InputError("multisine", table, "a table [multisine]", here)
    for key in table:
        if key not in TABLE_KEYS:
            raise InputError(f"multisine.{key}", table[key], "one of " + ", ".join(sorted(TABLE_KEYS)), where(key))
    if "torque" not in table:
        raise InputError("multisine.torque", "missing", "the logs' column of the applied steer torque [N m]", here)
    torque_column = _text(table["torque"], "multisine.torque", where("torque"))
    scale = 1.0
    if "torque_scale" in table:
        x = _real(table["torque_scale"])
        if not x:
            raise InputError(
                "multisine.torque_scale",
                _shown(table["torque_scale"]),
                "a finite, non-zero factor",
                where("torque_scale"),
            )
        scale = x
    outputs = tuple(o for o in DEFAULT_OUTPUTS if o in settings.columns)
    if "outputs" in table:
        raw = table["outputs"]
        if not (isinstance(raw, list) and raw and all(isinstance(x, str) for x in raw)):
            raise InputError("multisine.outputs", raw, "a list of signal names", where("outputs"))
        for name in raw:
            if name not in SIGNALS:
                raise InputError("multisine.outputs", name, "signals among " + ", ".join(SIGNALS), where("outputs"))
            if name not in settings.columns:
                raise InputError(
                    "multisine.outputs", name, f"a signal the column map gives (columns.{name})", where("outputs")
                )
        outputs = tuple(raw)
    settle = 0.0
    if "settle" in table:
        x = _real(table["settle"])
        if x is None or not 0 <= x <= 3600:
            raise InputError("multisine.settle", _shown(table["settle"]), "a time from 0 to 3600 s", where("settle"))
        settle = x
    folder = path.parent / _text(table.get("logs", "."), "multisine.logs", where("logs"))
    runs = table.get("run", [])
    if not isinstance(runs, list) or not runs:
        raise InputError("multisine.run", runs if runs else "missing", "[[multisine.run]] tables, one per run", here)
    wanted = sorted({c for k, c in settings.columns.items()} | {torque_column})
    out = []
    after = 0
    for entry in runs:
        line = _line_of(text, r"^\s*\[\[\s*multisine\.run\s*\]\]", after) or 0
        after = line
        at = f"{path}:{line}" if line else str(path)
        out.append(_run(entry, at, folder, settings, wanted, torque_column, scale, outputs, settle))
    return out


def _run(entry, at, folder, settings, wanted, torque_column, scale, outputs, settle) -> MultisineRecord:
    if not isinstance(entry, dict):
        raise InputError("multisine.run", entry, "a table", at)
    for key in entry:
        if key not in RUN_KEYS:
            raise InputError(f"multisine.run.{key}", entry[key], "one of " + ", ".join(sorted(RUN_KEYS)), at)
    if "path" not in entry:
        raise InputError("multisine.run.path", "missing", "the run's log", at)
    file = folder / _text(entry["path"], "multisine.run.path", at)
    group = _text(entry["group"], "multisine.run.group", at) if "group" in entry else None
    law_name = _text(entry["control"], "multisine.run.control", at) if "control" in entry else None
    if law_name is not None and law_name not in settings.laws:
        raise InputError(
            "multisine.run.control",
            law_name,
            "the name of a law defined under [control.<name>] (" + (", ".join(settings.laws) or "none defined") + ")",
            at,
        )
    speed = _speed_value(entry["speed"], "multisine.run.speed", at) if "speed" in entry else None
    if speed is None and settings.speed_source == "value":
        raise InputError("multisine.run.speed", "missing", 'the run\'s speed (speed.source = "value")', at)
    lines = None
    if "lines" in entry:
        raw = entry["lines"]
        values = [_real(x) for x in raw] if isinstance(raw, list) else [None]
        if not values or len(values) > MAX_LINES or any(x is None or x <= 0 for x in values):
            raise InputError("multisine.run.lines", raw, f"a list of 1 to {MAX_LINES} positive frequencies [Hz]", at)
        lines = tuple(sorted(float(x) for x in values))  # type: ignore[arg-type]
    try:
        log = read_log(_find(file), wanted, settings.delimiter)
    except FileFormatError as exc:
        spot = exc.path if exc.line is None else f"{exc.path}:{exc.line}"
        raise FileFormatError(
            exc.path, f"{str(exc).removeprefix(f'{spot}: ')} (the multisine run of {at})", exc.line
        ) from None
    start, end = 0, log.n
    if "window" in entry:
        w = entry["window"]
        ok = isinstance(w, list) and len(w) == 2 and all(isinstance(x, int) and not isinstance(x, bool) for x in w)
        if not ok or not 0 <= w[0] < w[1] <= log.n:
            raise InputError(
                "multisine.run.window", w, f"[start, end] sample numbers with 0 <= start < end <= {log.n}", at
            )
        start, end = w
    if end - start > MAX_MULTISINE_SAMPLES:
        raise FileFormatError(
            file, f"{end - start} samples in the run: expected at most {MAX_MULTISINE_SAMPLES} (give a window)"
        )
    name = file.name if (start, end) == (0, log.n) else f"{file.name}[{start}:{end}]"
    torque = log.columns[torque_column][start:end] * scale
    huge = np.flatnonzero(np.abs(torque) > MAX_TORQUE)
    if huge.size:
        raise FileFormatError(
            file,
            f"{torque_column} = {torque[huge[0]] / scale:g} at sample {start + int(huge[0])}: above {MAX_TORQUE:g} N m "
            "(check the torque column and multisine.torque_scale)",
            log.first_line + start + int(huge[0]),
        )
    if "time" in settings.columns:
        t = log.columns[settings.columns["time"]][start:end]
        first = np.flatnonzero(np.isfinite(t))
        time = t - t[first[0]] if first.size else np.full(end - start, np.nan)
    else:
        time = np.arange(end - start) / float(settings.sample_rate)  # type: ignore[arg-type]
    signals = {}
    problem = None
    for signal in SIGNALS:
        if signal in settings.columns:
            values = log.columns[settings.columns[signal]][start:end] * settings.scale.get(signal, 1.0)
            signals[signal] = values
            bad = np.flatnonzero(np.abs(values) > 1e6)
            if bad.size and problem is None:
                problem = f"{signal} ({settings.columns[signal]}) = {values[bad[0]]:g} at sample {start + int(bad[0])}: above 1e6 (check the column and its units)"
    window = Window(file, start, end, at, group, law_name, speed)
    v, v_sigma, controller = _speed(log, start, end, window, settings)
    if problem is None and not (math.isfinite(v) and v > 0):
        problem = f"no positive speed in the run (speed {v:g} m/s)"
    law = settings.laws[law_name or settings.default_law] if (law_name or settings.default_law) else NO_CONTROL
    grp = group or (file.name.removesuffix(".gz") if settings.group == "file" else settings.group)
    return MultisineRecord(
        name,
        at,
        time,
        torque,
        signals,
        v,
        v_sigma,
        grp,
        law,
        controller,
        outputs=outputs,
        lines=lines,
        settle=settle,
        problem=problem,
        speed_measured=speed is None and settings.speed_source == "column",
        window=(start, end),
    )


def multisine_files(path: str | Path) -> list[Path]:
    """The logs the ``[multisine]`` runs of a TOML manifest name (inputs of the run, never overwritten)."""
    path = Path(path)
    if path.suffix.lower() != ".toml":
        return []
    data = read_toml(path)
    table = data.get("multisine")
    if not isinstance(table, dict):
        return []
    folder = path.parent / str(table.get("logs", "."))
    out = []
    for entry in table.get("run", []) if isinstance(table.get("run"), list) else []:
        if isinstance(entry, dict) and isinstance(entry.get("path"), str):
            file = folder / entry["path"]
            out += [file, file.with_name(file.name + ".gz")]
    return out
