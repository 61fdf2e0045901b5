"""The page's bicycle: a shipped set or uploaded files, its parameter table, and edits of it.

Files go through the readers of the command line: a benchmark parameter file (TOML with the
Meijaard names, BicycleParameters ``<Name>Benchmark.txt``) as ``bikerider benchmark FILE`` reads
it, anything else (project TOML of raw measurements, ``<Name>Measured.txt``, with a rider file or
not) as ``bikerider estimate --bicycle FILE [--rider FILE]`` does, with the sigmas ``estimate``
reports.  From then on the page works on the 25 benchmark parameters and their sigmas (taken as
independent): the table shows them, every edit is checked by
:meth:`~bikerider.benchmark.BenchmarkParameters.from_mapping` and the mass-matrix rule, and each
error or note is placed next to the value it names, worded as the command line words it.
"""

from __future__ import annotations

import re
import threading
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from bikerider import notes
from bikerider.app.steer_frame import (
    ASSEMBLY_INPUTS,
    STEER_FRAME_INPUTS,
    STEER_FRAME_NAMES,
    STEER_FRAME_UNITS,
    first_order_sigmas,
    from_steer_frame,
    front_assembly,
    to_steer_frame,
)
from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters, rules
from bikerider.benchmark.parameters import check_mass_matrix, uncertainty_notes
from bikerider.errors import MISSING, BikeriderError, FileFormatError, InputError
from bikerider.io.input_file import read_input_text
from bikerider.io.shipped_files import BICYCLES, RIDERS
from bikerider.quantity import Quantity, parse_quantity

UNITS = {
    **{name: "kg m^2" for name in BENCHMARK_NAMES if name.startswith("I")},
    **{name: "kg" for name in ("mR", "mB", "mH", "mF")},
    **{name: "m" for name in ("w", "c", "rR", "rF", "xB", "zB", "xH", "zH")},
    "lam": "rad",
    "g": "m/s^2",
}
"""SI unit of each benchmark value."""
SECTIONS = {"R": "rear wheel R", "B": "rear body B", "H": "front assembly H", "F": "front wheel F"}


def _section(name: str) -> str:
    """The table section of a benchmark value: its body (the letter after ``m``, ``r``, ``x``, ``z``
    or ``I``), else the geometry."""
    return SECTIONS.get(name[1:2], "geometry") if name[0] in "mrxzI" and len(name) > 1 else "geometry"


GROUPS = {
    section: tuple(n for n in BENCHMARK_NAMES if _section(n) == section) for section in ("geometry", *SECTIONS.values())
}
"""The table's sections, each value once."""
TABLE_SOURCE = "the parameter table"
"""Where an edited value comes from, in messages."""
PAPER = "paper"
"""The choice of the paper's bicycle and rider (Moore et al. 2009), through the whole estimate."""

NOTES_LOCK = threading.Lock()
"""Notes are collected in one process-wide stack (:mod:`bikerider.notes`): one collection at a time."""


@dataclass(frozen=True)
class LoadedBicycle:
    """A bicycle as the page shows it: its benchmark parameters, a name and the readers' notes."""

    parameters: BenchmarkParameters
    name: str
    notes: list[str] = field(default_factory=list)


def shipped_choices() -> list[dict[str, str]]:
    """The bicycles the page offers without an upload: ``[{id, label}]``."""
    out = [{"id": PAPER, "label": "Batavus Browser + 72 kg rider (Moore et al. 2009, the whole estimate)"}]
    for bicycle in BICYCLES:
        out.append({"id": bicycle, "label": f"{bicycle} (BicycleParameters data)"})
        for rider, seated in RIDERS.items():
            if bicycle in seated:
                out.append({"id": f"{bicycle}+{rider}", "label": f"{bicycle} + {rider} (BicycleParameters data)"})
    return out


def load_shipped(choice: str) -> LoadedBicycle:
    """A bicycle of :func:`shipped_choices` by its id.

    Raises
    ------
    InputError
        An id that is none of them.
    """
    # bikerider.shipped and bikerider.estimate import the whole pipeline: imported when asked for.
    from bikerider.shipped import named

    if choice == PAPER:
        return _estimated(None, None, True)
    bicycle, _, rider = str(choice).partition("+")
    ids = [c["id"] for c in shipped_choices()]
    if choice not in ids:
        raise InputError("bicycle", choice, f"one of the shipped sets {', '.join(ids)}")
    with NOTES_LOCK, notes.collecting() as collection:
        parameters = named(bicycle, rider or None)
        return LoadedBicycle(parameters, parameters.source.split(" (")[0], list(collection.messages))


def is_benchmark_toml(path: str | Path) -> bool:
    """Whether a TOML file holds benchmark parameters (a ``[benchmark]`` table or the Meijaard names
    at top level) rather than the raw measurements ``estimate`` reads."""
    try:
        data = tomllib.loads(read_input_text(path))
    except tomllib.TOMLDecodeError:
        return False  # the estimate reader says what is wrong with it
    return "benchmark" in data or bool({"w", "c", "lam", "lam_deg"} & set(data))


def load_files(bicycle: str | Path, rider: str | Path | None = None, name: str | None = None) -> LoadedBicycle:
    """A bicycle (and rider) from files, read as the command line reads them (module docstring).

    Raises
    ------
    BikeriderError
        Whatever the readers raise (every error of a file at once).
    """
    from bikerider.io.benchmark_file import load_benchmark_parameters

    if Path(bicycle).suffix.lower() == ".toml" and rider is None and is_benchmark_toml(bicycle):
        with NOTES_LOCK, notes.collecting() as collection:
            parameters = load_benchmark_parameters(bicycle)
            return LoadedBicycle(parameters, name or Path(bicycle).name, list(collection.messages))
    return _estimated(bicycle, rider, rider is not None, name)


def _estimated(bicycle, rider, with_rider: bool, name: str | None = None) -> LoadedBicycle:
    """The estimate of ``bikerider estimate`` with the sigmas it reports for the benchmark values."""
    from bikerider import report
    from bikerider.estimate import estimate_from_files, estimate_headline_uncertainty, estimate_uncertainty

    with NOTES_LOCK, notes.collecting() as collection:
        result = estimate_from_files(bicycle, rider, with_rider=with_rider)
        uncertainty = estimate_uncertainty(result)
        headline = estimate_headline_uncertainty(result, uncertainty)
        sigmas = report.reported_sigmas(uncertainty, headline)
        parameters = replace(result.parameters, sigmas={**result.parameters.sigmas, **sigmas})
        messages = notes.shown_with([*result.notes, *uncertainty.notes, *headline.notes])
        collection.shown.update(collection.messages)
    bicycle_name = result.bicycle.name if result.bicycle is not None else (name or str(bicycle))
    rider_name = result.rider.name if result.rider is not None else "no rider"
    return LoadedBicycle(parameters, name or f"{bicycle_name} + {rider_name}", messages)


def parameter_table(parameters: BenchmarkParameters) -> dict:
    """The table the page shows: every value with its unit and sigma by section, the front
    assembly H in the steer-axis frame (first-order sigmas), and H and F about the steer axis."""
    v, s = parameters.values, parameters.sigmas
    rows = [
        {"name": n, "unit": UNITS[n], "value": v[n], "sigma": float(s.get(n, 0.0) or 0.0), "group": group}
        for group, names in GROUPS.items()
        for n in names
    ]
    floats = {n: float(v[n]) for n in ASSEMBLY_INPUTS}  # type: ignore[arg-type]
    steer = to_steer_frame(floats)
    steer_sigma = first_order_sigmas(to_steer_frame, floats, s, STEER_FRAME_INPUTS)
    assembly = front_assembly(floats)
    assembly_sigma = first_order_sigmas(front_assembly, floats, s, ASSEMBLY_INPUTS)
    return {
        "rows": rows,
        "principal": {body: principal_moments(parameters, body) for body in rules.BODIES},
        "steer_frame": [
            {"name": n, "unit": STEER_FRAME_UNITS[n], "value": steer[n], "sigma": steer_sigma[n]}
            for n in STEER_FRAME_NAMES
        ],
        "assembly": {
            "mass": assembly["mass"],
            "mass_sigma": assembly_sigma["mass"],
            "I_steer_axis": assembly["I_steer_axis"],
            "I_steer_axis_sigma": assembly_sigma["I_steer_axis"],
        },
    }


def principal_moments(parameters: BenchmarkParameters, body: str) -> dict:
    """The principal moments of inertia of body ``B`` or ``H`` about its centre of mass [kg m^2], the
    two in the XZ plane with the angle of the first principal axis from +x (downwards positive, the
    benchmark frame) [rad], and ``Iyy`` when the set determines it."""
    v = parameters.values
    xx, yy, zz, xz = (v[name] for name in rules.tensor_entries(body))
    moments, vectors = np.linalg.eigh(np.array([[xx, xz], [xz, zz]], dtype=float))
    return {
        "plane": [float(m) for m in moments],
        "angle": float(np.arctan2(vectors[1, 0], vectors[0, 0])),
        "yy": None if yy is None else float(yy),
    }


def _field_of(error: InputError) -> list[str]:
    """The table rows an error names (a tensor's entries for a tensor; none for the whole set)."""
    name = error.name.removesuffix(" uncertainty")
    if name in BENCHMARK_NAMES:
        return [name]
    for body in rules.BODIES:
        if name == rules.tensor_name(body):
            return list(rules.tensor_entries(body))
    mentioned = [n for n in BENCHMARK_NAMES if re.search(rf"\b{n}\b", error.name)]
    return mentioned


def note_field(message: str) -> str | None:
    """The benchmark value a note is about (where the page shows it): the first one it names as
    ``NAME =`` or ``NAME is``, if any."""
    match = re.search(r"\b(" + "|".join(BENCHMARK_NAMES) + r") (=|is)", message)
    return match.group(1) if match else None


def notes_by_field(messages: list[str]) -> dict[str, list[str]]:
    """``messages`` by the value each is about (``"*"`` for the others)."""
    out: dict[str, list[str]] = {}
    for message in messages:
        _add(out, note_field(message) or "*", message)
    return out


@dataclass
class EditResult:
    """An edited table: the parameters when they are valid, else the errors by row."""

    parameters: BenchmarkParameters | None
    errors: dict[str, list[str]]
    notes: dict[str, list[str]]

    def as_dict(self) -> dict:
        return {"ok": self.parameters is not None, "errors": self.errors, "notes": self.notes}


def _add(where: dict[str, list[str]], key: str, message: str) -> None:
    if message not in where.setdefault(key, []):
        where[key].append(message)


def edited_parameters(cells: dict, steer_frame: dict | None = None, source: str = TABLE_SOURCE) -> EditResult:
    """The benchmark parameters of the table's ``cells`` (``{name: [value, sigma]}``, numbers or the
    text typed), with ``steer_frame`` (``{dH: value, ...}``) replacing H's values when given.

    Every value that cannot be read and every rule a value breaks is an error of its row (``"*"``
    for errors of the whole set, such as a singular mass matrix); notes likewise.
    """
    errors: dict[str, list[str]] = {}
    found: dict[str, Quantity] = {}
    for name in BENCHMARK_NAMES:
        value, sigma = (list(cells.get(name, [None, None])) + [None, None])[:2]
        if value is None or value == "":
            if name in ("IByy", "IHyy", "g"):
                continue  # optional values, and gravity's default (as the readers take them)
            _add(
                errors,
                name,
                str(InputError(name, "missing", "a value (all 25 benchmark parameters are needed)", source)),
            )
            continue
        try:
            q = parse_quantity(_number(value), name, source)
            sq = parse_quantity(_number(sigma) if sigma not in (None, "") else 0.0, f"{name} uncertainty", source)
            found[name] = Quantity(q.value, sq.value)
            if sq.value < 0:
                raise InputError(f"{name} uncertainty", sq.value, "a non-negative standard uncertainty", source)
        except InputError as exc:
            _add(errors, name, str(exc))
    unknown = sorted(set(cells) - set(BENCHMARK_NAMES))
    for name in unknown:
        _add(
            errors,
            "*",
            str(InputError(name, cells[name], f"one of the benchmark names {', '.join(BENCHMARK_NAMES)}", source)),
        )
    if steer_frame and not errors:
        try:
            steer = {n: parse_quantity(_number(steer_frame[n]), n, source).value for n in STEER_FRAME_NAMES}
        except KeyError as exc:
            _add(
                errors,
                "*",
                str(InputError(str(exc.args[0]), "missing", "every value of H in the steer-axis frame", source)),
            )
        except InputError as exc:
            _add(errors, exc.name, str(exc))
        else:
            converted = from_steer_frame({k: q.value for k, q in found.items()}, steer)
            for name, value in converted.items():
                found[name] = Quantity(value, found[name].sigma)
    found_notes: dict[str, list[str]] = {}
    unreadable = set(errors)
    with NOTES_LOCK, notes.collecting() as collection:
        try:  # the rules on the values that could be read, even when others could not
            parameters = BenchmarkParameters.from_mapping(found, source)
            check_mass_matrix(parameters)
        except InputError as exc:
            for error in getattr(exc, "errors", [exc]):
                if error.name in unreadable and error.value == MISSING:
                    continue  # named already, as unreadable
                for row in _field_of(error) or ["*"]:
                    _add(errors, row, str(error))
        if errors:
            return EditResult(None, errors, found_notes)
        messages = [*collection.messages, *uncertainty_notes(parameters)]
    return EditResult(parameters, {}, notes_by_field(messages))


def _number(raw: object) -> object:
    """A cell as typed: numbers as they are, text stripped (parse_quantity reads ``"1.2"``)."""
    return raw.strip() if isinstance(raw, str) else raw


def cells_of(parameters: BenchmarkParameters) -> dict[str, list]:
    """``{name: [value, sigma]}`` of ``parameters`` (the form :func:`edited_parameters` reads)."""
    return {n: [parameters.values[n], float(parameters.sigmas.get(n, 0.0) or 0.0)] for n in BENCHMARK_NAMES}


def error_text(exc: BaseException) -> str:
    """An error as the command line prints it after ``error:`` (every error of a file at once)."""
    if isinstance(exc, (BikeriderError, FileFormatError)):
        return str(exc)
    if isinstance(exc, OSError):
        return f"{exc.strerror or exc}: {exc.filename or ''}".rstrip(": ")
    raise exc


__all__ = [
    "GROUPS",
    "LoadedBicycle",
    "PAPER",
    "UNITS",
    "cells_of",
    "edited_parameters",
    "error_text",
    "load_files",
    "load_shipped",
    "parameter_table",
    "shipped_choices",
]
