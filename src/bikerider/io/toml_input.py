"""The project's own input files: TOML, SI units, angles in degrees under ``*_deg`` keys.

Every value may be a number, a ``"value +/- sigma"`` string or ``{ value = ..., sigma = ... }``.
``docs/input_format.md`` documents the layout; ``bikerider/data/paper/`` holds the paper's bicycle
and rider as examples.  Files are only read, never written.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path
from typing import Any

from bikerider.bicycle import pendulum
from bikerider.bicycle.bodies import SEATING_NAMES, BicycleBodies
from bikerider.errors import MISSING, FileFormatError, InputError
from bikerider.quantity import DEG, Quantity, parse_quantity
from bikerider.rider.measurements import DEFAULT_MASS_FRACTIONS, RiderMeasurements

_GEOMETRY_KEYS = ("w", "c", "rR", "rF", "h_bb", "l_cs", "l_f", "w_fh", "l_hb", "w_rh", "l_sp", "l_st", "l_s")
_GEOMETRY_ANGLES = ("lam_ht", "lam_st")
_RIDER_KEYS = ("c_ch", "c_h", "l_hh", "c_la", "l_la", "c_ll", "l_ll", "l_ss", "l_to", "c_ua", "l_ua", "c_ul", "l_ul")
_FRACTION_KEYS = {
    "head": "f_h",
    "lower_arm": "f_la",
    "lower_leg": "f_ll",
    "torso": "f_to",
    "upper_arm": "f_ua",
    "upper_leg": "f_ul",
}


def read_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML file; a syntax error or undecodable text names the file and line."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise FileFormatError(path, "no such file") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise FileFormatError(path, f"not UTF-8 text (byte {exc.start})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        # Python 3.11's tomllib gives the position only in the message: "... (at line 2, column 5)".
        match = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        line = int(match.group(1)) if match else None
        message = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        raise FileFormatError(path, f"not valid TOML: {message}", line) from None


def _join(section: str, key: str) -> str:
    return f"{section}.{key}" if section else key


class _Section:
    """A table of the file with strict key handling and qualified names in errors."""

    def __init__(self, data: dict[str, Any], name: str, source: str, allowed: set[str]):
        if not isinstance(data, dict):
            raise InputError(name, data, "a table", source)
        unknown = sorted(set(data) - allowed)
        if unknown:
            raise InputError(
                _join(name, unknown[0]), data[unknown[0]], f"one of the keys {', '.join(sorted(allowed))}", source
            )
        self.data, self.name, self.source = data, name, source

    def has(self, key: str) -> bool:
        return key in self.data

    def quantity(self, key: str, required: bool = True, scale: float = 1.0) -> Quantity | None:
        if key not in self.data:
            if required:
                raise InputError(_join(self.name, key), MISSING, "a value", self.source)
            return None
        return parse_quantity(self.data[key], _join(self.name, key), self.source).scaled(scale)

    def section(self, key: str, allowed: set[str]) -> _Section:
        if key not in self.data:
            raise InputError(_join(self.name, key), MISSING, "a table", self.source)
        return _Section(self.data[key], _join(self.name, key), self.source, allowed)

    def quantities(self, key: str, scale: float = 1.0) -> list[Quantity]:
        items = self.data.get(key)
        if not isinstance(items, list):
            raise InputError(_join(self.name, key), items, "a list of values", self.source)
        return [
            parse_quantity(x, f"{_join(self.name, key)}[{i}]", self.source).scaled(scale) for i, x in enumerate(items)
        ]


def _wheel(
    section: _Section, k_t: Quantity | None, g: Quantity, prefix: str, raw: dict[str, Quantity]
) -> dict[str, Quantity]:
    mass = section.quantity("mass")
    out = {f"m{prefix}": mass}
    source = section.source
    # I_xx = I_zz: given, or from a torsional period about a diameter (Eq. 1).
    if isinstance(section.data.get("Ixx"), dict) and "torsional_period" in section.data["Ixx"]:
        sub = section.section("Ixx", {"torsional_period"})
        if k_t is None:
            raise InputError(
                "torsional_pendulum.k_t", "missing", "the pendulum stiffness, to reduce torsional periods", source
            )
        raw[f"T_{prefix}xx"] = sub.quantity("torsional_period")  # type: ignore[assignment]
        out[f"I{prefix}xx"] = pendulum.torsional_inertia(
            k_t, raw[f"T_{prefix}xx"], f"{sub.name}.torsional_period", source
        )
    else:
        out[f"I{prefix}xx"] = section.quantity("Ixx")  # type: ignore[assignment]
    # I_yy: given, or from a compound pendulum (Eq. 7).
    if isinstance(section.data.get("Iyy"), dict) and "compound_period" in section.data["Iyy"]:
        sub = section.section("Iyy", {"compound_period", "pendulum_length"})
        raw[f"T_{prefix}yy"] = sub.quantity("compound_period")  # type: ignore[assignment]
        raw[f"l_p{prefix}"] = sub.quantity("pendulum_length")  # type: ignore[assignment]
        out[f"I{prefix}yy"] = pendulum.compound_inertia(
            raw[f"T_{prefix}yy"],
            mass,
            raw[f"l_p{prefix}"],
            g,
            f"{sub.name}.compound_period",
            source,
        )
    else:
        out[f"I{prefix}yy"] = section.quantity("Iyy")  # type: ignore[assignment]
    return out


def _com_from_lines(com: _Section) -> tuple[Quantity, Quantity]:
    """Centre of mass where three or more pendulum-axis lines meet (least squares).

    Each line is ``{ point = [x, z], angle_deg = ... }``: a point it passes through and its angle
    from the ground, rising from +x (the convention of ``alpha_deg``).
    """
    lines = com.data["lines"]
    if not isinstance(lines, list) or len(lines) < 3:
        raise InputError(
            _join(com.name, "lines"), lines, "a list of three or more {point = [x, z], angle_deg = ...}", com.source
        )
    points, angles = [], []
    for i, line in enumerate(lines):
        entry = _Section(line, f"{_join(com.name, 'lines')}[{i}]", com.source, {"point", "angle_deg"})
        point = entry.data.get("point")
        if not isinstance(point, list) or len(point) != 2:
            raise InputError(_join(entry.name, "point"), point, "[x, z] in metres", com.source)
        points.append(
            (
                parse_quantity(point[0], f"{entry.name}.point[0]", com.source),
                parse_quantity(point[1], f"{entry.name}.point[1]", com.source),
            )
        )
        angles.append(entry.quantity("angle_deg", scale=DEG))
    return pendulum.centre_of_mass_from_lines(points, angles, com.name, com.source)  # type: ignore[arg-type]


def _frame(section: _Section, k_t: Quantity | None, prefix: str, raw: dict[str, Quantity]) -> dict[str, Quantity]:
    out = {f"m{prefix}": section.quantity("mass")}
    com = section.section("com", {"x", "z", "lines"})
    if com.has("lines"):
        out[f"x{prefix}"], out[f"z{prefix}"] = _com_from_lines(com)
    else:
        out[f"x{prefix}"], out[f"z{prefix}"] = com.quantity("x"), com.quantity("z")  # type: ignore[assignment]
    inertia_raw = section.data.get("inertia")
    if isinstance(inertia_raw, dict) and "periods" in inertia_raw:
        sub = section.section("inertia", {"periods", "alpha_deg", "Iyy"})
        if k_t is None:
            raise InputError(
                "torsional_pendulum.k_t",
                "missing",
                "the pendulum stiffness, to reduce torsional periods",
                section.source,
            )
        periods, angles = sub.quantities("periods"), sub.quantities("alpha_deg", DEG)
        Ixx, Ixz, Izz = pendulum.inertia_from_orientations(k_t, periods, angles, section.name, section.source)
        if len(periods) == 3:  # the closed form of Eq. 6 the sensitivities differentiate
            for i, (period, angle) in enumerate(zip(periods, angles), start=1):
                raw[f"T_{prefix}{i}"], raw[f"alpha_{prefix}{i}"] = period, angle
    else:
        sub = section.section("inertia", {"Ixx", "Ixz", "Izz", "Iyy"})
        Ixx, Ixz, Izz = sub.quantity("Ixx"), sub.quantity("Ixz"), sub.quantity("Izz")  # type: ignore[assignment]
    out.update({f"I{prefix}xx": Ixx, f"I{prefix}xz": Ixz, f"I{prefix}zz": Izz})
    Iyy = sub.quantity("Iyy", required=False)
    if Iyy is not None:
        out[f"I{prefix}yy"] = Iyy
    return out


def load_bicycle_toml(path: str | Path) -> BicycleBodies:
    """Read a bicycle TOML file (see ``docs/input_format.md``).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    BicycleBodies
        Pendulum periods reduced (Eqs. 1-7) with first-order uncertainties; the raw measurements
        kept in ``raw_inputs`` for the estimate chain.

    Raises
    ------
    FileFormatError, InputError
    """
    source = str(path)
    data = read_toml(path)
    top = _Section(
        data,
        "",
        source,
        {
            "bicycle",
            "environment",
            "geometry",
            "torsional_pendulum",
            "rear_wheel",
            "front_wheel",
            "rear_frame",
            "handlebar_fork",
        },
    )
    meta = data.get("bicycle", {})
    name = meta.get("name", Path(path).stem) if isinstance(meta, dict) else Path(path).stem
    g = Quantity(9.81)
    if top.has("environment"):
        g = top.section("environment", {"g"}).quantity("g")  # type: ignore[assignment]
    values: dict[str, Quantity] = {"g": g}
    geometry = top.section("geometry", set(_GEOMETRY_KEYS) | {f"{a}_deg" for a in _GEOMETRY_ANGLES})
    for key in _GEOMETRY_KEYS:
        q = geometry.quantity(key, required=key not in SEATING_NAMES)
        if q is not None:
            values[key] = q
    for key in _GEOMETRY_ANGLES:
        q = geometry.quantity(f"{key}_deg", required=key not in SEATING_NAMES, scale=DEG)
        if q is not None:
            values[key] = q
    k_t = None
    if top.has("torsional_pendulum"):
        k_t = top.section("torsional_pendulum", {"k_t"}).quantity("k_t")
    raw: dict[str, Quantity] = {}
    values.update(_wheel(top.section("rear_wheel", {"mass", "Ixx", "Iyy"}), k_t, g, "R", raw))
    values.update(_wheel(top.section("front_wheel", {"mass", "Ixx", "Iyy"}), k_t, g, "F", raw))
    values.update(_frame(top.section("rear_frame", {"mass", "com", "inertia"}), k_t, "Bf", raw))
    values.update(_frame(top.section("handlebar_fork", {"mass", "com", "inertia"}), k_t, "H", raw))
    reduced = _reduced_names(raw)
    if raw and k_t is not None:
        raw["k_t"] = k_t
    return BicycleBodies(values, source, str(name), raw_inputs=raw, reduced=reduced)


def _reduced_names(raw: dict[str, Quantity]) -> tuple[str, ...]:
    """The values computed from the raw measurements in ``raw``."""
    names = []
    for w in ("R", "F"):
        if f"T_{w}xx" in raw:
            names.append(f"I{w}xx")
        if f"T_{w}yy" in raw:
            names.append(f"I{w}yy")
    for b in ("Bf", "H"):
        if f"T_{b}1" in raw:
            names += [f"I{b}xx", f"I{b}xz", f"I{b}zz"]
    return tuple(names)


def load_rider_toml(path: str | Path) -> RiderMeasurements:
    """Read a rider TOML file (see ``docs/input_format.md``).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    RiderMeasurements

    Raises
    ------
    FileFormatError, InputError
    """
    source = str(path)
    data = read_toml(path)
    top = _Section(data, "", source, {"rider", "measurements", "mass_fractions"})
    rider = top.section("rider", {"name", "mass", "source"})
    values = {"mBr": rider.quantity("mass")}
    measurements = top.section("measurements", set(_RIDER_KEYS) | {"lam_fl_deg"})
    for key in _RIDER_KEYS:
        values[key] = measurements.quantity(key)
    values["lam_fl"] = measurements.quantity("lam_fl_deg", scale=DEG)
    fractions = dict(DEFAULT_MASS_FRACTIONS)
    if top.has("mass_fractions"):
        section = top.section("mass_fractions", set(_FRACTION_KEYS))
        for key, symbol in _FRACTION_KEYS.items():
            q = section.quantity(key, required=False)
            if q is not None:
                fractions[symbol] = q.value
    name = rider.data.get("name", Path(path).stem)
    return RiderMeasurements(values, fractions, source, str(name))  # type: ignore[arg-type]
