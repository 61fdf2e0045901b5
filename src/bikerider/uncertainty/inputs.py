"""Measurements as the chain's nodes: read from the project's TOML files without reducing them.

:func:`raw_inputs_from_toml` keeps every pendulum period, axis angle and the pendulum stiffness
as inputs in their own right, so the correlations the reductions create (one ``k_t`` in every
torsional inertia, one set of periods in all three rear-frame tensor entries, the wheel's mass in
its compound pendulum) survive into the propagation.  :func:`paper_inputs` is the paper's bicycle
and rider with the accuracies the paper states, and - where it states none (the rider, Table 7) -
the assumed sigmas of :data:`ASSUMED_RIDER_SIGMAS`, every one reported with its source.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from bikerider.errors import InputError
from bikerider.quantity import Quantity, parse_quantity

DEG = math.pi / 180

ASSUMED_RIDER_SIGMAS: dict[str, tuple[float, str]] = {
    # The paper states no accuracy for Table 7 ("measured as accurately as possible with basic
    # tools"); these are assumptions, reported as such wherever they are used.
    **{name: (0.01, "assumed: one unit of the last digit Table 7 prints (0.01 m)") for name in (
        "c_ch", "c_h", "l_hh", "c_la", "l_la", "c_ll", "l_ll", "l_ss", "l_to", "c_ua", "l_ua", "c_ul", "l_ul")},
    "lam_fl": (1.0 * DEG, "assumed: 1 deg, the accuracy Table 4 states for angles read off photographs"),
    "mBr": (0.1, "assumed: one unit of the last digit Table 8 prints (0.1 kg)"),
}

_GEOMETRY = ("w", "c", "rR", "rF", "h_bb", "l_cs", "l_f", "w_fh", "l_hb", "w_rh", "l_sp", "l_st", "l_s")
_RIDER = ("c_ch", "c_h", "l_hh", "c_la", "l_la", "c_ll", "l_ll", "l_ss", "l_to", "c_ua", "l_ua", "c_ul", "l_ul")
_FRACTIONS = {"head": "f_h", "lower_arm": "f_la", "lower_leg": "f_ll", "torso": "f_to",
              "upper_arm": "f_ua", "upper_leg": "f_ul"}


@dataclass(frozen=True)
class InputSet:
    """Chain inputs with uncertainties and where each uncertainty comes from.

    Attributes
    ----------
    quantities : dict of str to Quantity
        Node name to value and standard uncertainty (SI, radians).
    sources : dict of str to str
        Node name to a note on where its sigma comes from.
    name : str
        A human name, for reports.
    """

    quantities: dict[str, Quantity]
    sources: dict[str, str]
    name: str = "inputs"


def _q(table: Mapping[str, object], key: str, where: str, source: str, scale: float = 1.0) -> Quantity:
    if key not in table:
        raise InputError(f"{where}.{key}", "missing", "a value", source)
    return parse_quantity(table[key], f"{where}.{key}", source).scaled(scale)


def _table(data: Mapping[str, object], key: str, source: str) -> Mapping[str, object]:
    value = data.get(key)
    if not isinstance(value, Mapping):
        raise InputError(key, value, "a table", source)
    return value


def _wheel(data: Mapping[str, object], key: str, w: str, source: str, out: dict[str, Quantity]) -> None:
    wheel = _table(data, key, source)
    out[f"m{w}"] = _q(wheel, "mass", key, source)
    ixx = wheel.get("Ixx")
    if isinstance(ixx, Mapping) and "torsional_period" in ixx:
        out[f"T_{w}xx"] = _q(ixx, "torsional_period", f"{key}.Ixx", source)
    else:
        out[f"I{w}xx"] = _q(wheel, "Ixx", key, source)
    iyy = wheel.get("Iyy")
    if isinstance(iyy, Mapping) and "compound_period" in iyy:
        out[f"T_{w}yy"] = _q(iyy, "compound_period", f"{key}.Iyy", source)
        out[f"l_p{w}"] = _q(iyy, "pendulum_length", f"{key}.Iyy", source)
    else:
        out[f"I{w}yy"] = _q(wheel, "Iyy", key, source)


def _frame(data: Mapping[str, object], key: str, b: str, source: str, out: dict[str, Quantity]) -> None:
    frame = _table(data, key, source)
    out[f"m{b}"] = _q(frame, "mass", key, source)
    com = _table(frame, "com", source)
    out[f"x{b}"], out[f"z{b}"] = _q(com, "x", f"{key}.com", source), _q(com, "z", f"{key}.com", source)
    inertia = _table(frame, "inertia", source)
    if "periods" in inertia:
        periods, angles = inertia.get("periods"), inertia.get("alpha_deg")
        if not (isinstance(periods, list) and isinstance(angles, list) and len(periods) == len(angles) == 3):
            raise InputError(f"{key}.inertia.periods", periods,
                             "exactly three periods and three alpha_deg for the closed-form sensitivities", source)
        prefix = "Bf" if b == "Bf" else "H"
        for i, (t, a) in enumerate(zip(periods, angles), start=1):
            out[f"T_{prefix}{i}"] = parse_quantity(t, f"{key}.inertia.periods[{i - 1}]", source)
            out[f"alpha_{prefix}{i}"] = parse_quantity(a, f"{key}.inertia.alpha_deg[{i - 1}]", source).scaled(DEG)
    else:
        for axes in ("xx", "xz", "zz"):
            out[f"I{b}{axes}"] = _q(inertia, f"I{axes}", f"{key}.inertia", source)
    if "Iyy" in inertia:
        out[f"I{b}yy"] = _q(inertia, "Iyy", f"{key}.inertia", source)


def raw_inputs_from_toml(bicycle: str | Path, rider: str | Path) -> dict[str, Quantity]:
    """Every measurement of a bicycle and a rider TOML file as a chain input, unreduced.

    Raises
    ------
    FileFormatError, InputError
        An unreadable file, a missing or malformed value (named with its table and key).
    """
    from bikerider.io.toml_input import read_toml

    src = str(bicycle)
    data = read_toml(bicycle)
    out: dict[str, Quantity] = {"g": Quantity(9.81)}
    if "environment" in data:
        out["g"] = _q(_table(data, "environment", src), "g", "environment", src)
    geometry = _table(data, "geometry", src)
    for key in _GEOMETRY:
        if key in geometry:
            out[key] = _q(geometry, key, "geometry", src)
    for key in ("lam_ht", "lam_st"):
        if f"{key}_deg" in geometry:
            out[key] = _q(geometry, f"{key}_deg", "geometry", src, DEG)
    if "torsional_pendulum" in data:
        out["k_t"] = _q(_table(data, "torsional_pendulum", src), "k_t", "torsional_pendulum", src)
    _wheel(data, "rear_wheel", "R", src, out)
    _wheel(data, "front_wheel", "F", src, out)
    _frame(data, "rear_frame", "Bf", src, out)
    _frame(data, "handlebar_fork", "H", src, out)
    src = str(rider)
    data = read_toml(rider)
    out["mBr"] = _q(_table(data, "rider", src), "mass", "rider", src)
    measurements = _table(data, "measurements", src)
    for key in _RIDER:
        out[key] = _q(measurements, key, "measurements", src)
    out["lam_fl"] = _q(measurements, "lam_fl_deg", "measurements", src, DEG)
    fractions = _table(data, "mass_fractions", src) if "mass_fractions" in data else {}
    for key, name in _FRACTIONS.items():
        if key not in fractions:
            raise InputError(f"mass_fractions.{key}", "missing", "a mass fraction (the sensitivities need all six)", src)
        out[name] = _q(fractions, key, "mass_fractions", src)
    return out


def benchmark_inputs(parameters) -> dict[str, Quantity]:
    """The benchmark parameters (a :class:`bikerider.benchmark.BenchmarkParameters`) as chain inputs,
    each with its sigma; undetermined values (``IByy``/``IHyy`` = None) are left out."""
    return {name: Quantity(float(value), float(parameters.sigmas.get(name, 0.0)))
            for name, value in parameters.values.items() if value is not None}


def paper_files() -> tuple[Path, Path]:
    """The paper's bicycle and rider files shipped with the package."""
    base = resources.files("bikerider") / "data" / "paper"
    return Path(str(base / "browser_bicycle.toml")), Path(str(base / "jason_rider.toml"))


def with_assumed_rider_sigmas(quantities: Mapping[str, Quantity], sources: dict[str, str]) -> dict[str, Quantity]:
    """Give rider measurements without a sigma the assumed one (and say so in ``sources``)."""
    out = dict(quantities)
    for name, (sigma, note) in ASSUMED_RIDER_SIGMAS.items():
        if name in out and out[name].sigma == 0:
            out[name] = Quantity(out[name].value, sigma)
            sources[name] = note
    return out


def paper_inputs(assume_rider_sigmas: bool = True) -> InputSet:
    """The paper's bicycle and rider, raw measurements, with the paper's stated accuracies.

    Parameters
    ----------
    assume_rider_sigmas : bool
        Give the rider's measurements the sigmas of :data:`ASSUMED_RIDER_SIGMAS` (the paper
        states none); otherwise they are exact.
    """
    bicycle, rider = paper_files()
    quantities = raw_inputs_from_toml(bicycle, rider)
    sources = {name: (f"stated: {bicycle.name}" if q.sigma else "exact (no sigma given)") for name, q in quantities.items()}
    for name in _RIDER + ("lam_fl", "mBr") + tuple(_FRACTIONS.values()):
        sources[name] = "exact (no sigma given)" if quantities[name].sigma == 0 else f"stated: {rider.name}"
    if assume_rider_sigmas:
        quantities = with_assumed_rider_sigmas(quantities, sources)
    return InputSet(quantities, sources, "Batavus Browser and rider (Moore et al. 2009)")
