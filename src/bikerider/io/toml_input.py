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
from bikerider.bicycle.bodies import SEATING_NAMES, BicycleBodies, check_bicycle_values
from bikerider.errors import MISSING, ErrorCollector, FileFormatError, InputError
from bikerider.generated.manifest import STAGES
from bikerider.io.input_file import read_input_text
from bikerider.notes import note
from bikerider.quantity import DEG, Quantity, parse_quantity
from bikerider.rider.measurements import DEFAULT_MASS_FRACTIONS, RiderMeasurements, check_rider_values

_GEOMETRY_KEYS = ("w", "c", "rR", "rF", "h_bb", "l_cs", "l_f", "w_fh", "l_hb", "w_rh", "l_sp", "l_st", "l_s")
_GEOMETRY_ANGLES = ("lam_ht", "lam_st")
_RIDER_KEYS = ("c_ch", "c_h", "l_hh", "c_la", "l_la", "c_ll", "l_ll", "l_ss", "l_to", "c_ua", "l_ua", "c_ul", "l_ul")
_TENSOR_KEYS = STAGES["three_orientations"]["outputs"]
"""The in-plane tensor of a frame, as the keys of its ``inertia`` table: Ixx, Ixz, Izz."""
_FRACTION_KEYS = {
    "head": "f_h",
    "lower_arm": "f_la",
    "lower_leg": "f_ll",
    "torso": "f_to",
    "upper_arm": "f_ua",
    "upper_leg": "f_ul",
}


def read_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML input file; a syntax error or undecodable text names the file and line.

    The file is read through :func:`bikerider.io.input_file.read_input_text` (a regular file of
    bounded size).  A file without a single key (empty, or only comments) is refused: every TOML
    input of bikerider holds values, and an empty one is not a way to say "none".
    """
    text = read_input_text(path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        # Python 3.11's tomllib gives the position only in the message: "... (at line 2, column 5)".
        match = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        line = int(match.group(1)) if match else None
        message = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        raise FileFormatError(path, f"not valid TOML: {message}", line) from None
    except ValueError as exc:  # tomllib refuses integers of more than sys.get_int_max_str_digits() digits
        raise FileFormatError(path, f"not a number bikerider can read: {str(exc).split(';')[0]}") from None
    if not data:
        raise FileFormatError(path, "no values: the file is empty or holds only comments")
    return data


def _join(section: str, key: str) -> str:
    return f"{section}.{key}" if section else key


class _Reader:
    """What one file's reading has found wrong so far: every error is collected, and the file is
    refused once, with all of them (``errors``); ``unreadable`` names the values (by their node
    names) that could not be read, so that later checks neither call them missing nor use them."""

    def __init__(self, source: str):
        self.source = source
        self.errors = ErrorCollector()
        self.unreadable: set[str] = set()

    def fail(self, error: InputError, *nodes: str) -> None:
        self.errors.add(error)
        self.unreadable.update(nodes)


class _Section:
    """A table of the file with strict key handling and qualified names in errors.

    Problems are reported to the file's :class:`_Reader` and reading goes on: a table that is not
    a table is read as empty, an unknown key is named and skipped, a value that cannot be read is
    ``None``.  A section that is missing (``absent``) is reported once, not once per key.
    """

    def __init__(self, data: object, name: str, reader: _Reader, allowed: set[str], absent: bool = False):
        self.name, self.reader, self.source, self.absent = name, reader, reader.source, absent
        if not isinstance(data, dict):
            reader.fail(InputError(name, data, "a table", self.source))
            data, self.absent = {}, True
        for key in sorted(set(data) - allowed):
            reader.fail(
                InputError(_join(name, key), data[key], f"one of the keys {', '.join(sorted(allowed))}", self.source)
            )
        self.data = {k: v for k, v in data.items() if k in allowed}

    def has(self, key: str) -> bool:
        return key in self.data

    def quantity(self, key: str, required: bool = True, scale: float = 1.0, node: str | None = None) -> Quantity | None:
        """The value of ``key`` (``None`` when absent or unreadable, which is reported; ``node`` is
        the name the value goes by later)."""
        if key not in self.data:
            if required and not self.absent:
                self.reader.fail(InputError(_join(self.name, key), MISSING, "a value", self.source), node or key)
            elif required:
                self.reader.unreadable.add(node or key)
            return None
        try:
            return parse_quantity(self.data[key], _join(self.name, key), self.source).scaled(scale)
        except InputError as exc:
            self.reader.fail(exc, node or key)
            return None

    def section(self, key: str, allowed: set[str]) -> _Section:
        if key not in self.data:
            if not self.absent:
                self.reader.fail(InputError(_join(self.name, key), MISSING, "a table", self.source))
            return _Section({}, _join(self.name, key), self.reader, allowed, absent=True)
        return _Section(self.data[key], _join(self.name, key), self.reader, allowed)

    def quantities(self, key: str, scale: float = 1.0) -> list[Quantity] | None:
        """The values of the list ``key`` (``None`` when it is not a list, or one cannot be read)."""
        items = self.data.get(key)
        if not isinstance(items, list):
            if not self.absent:
                self.reader.fail(InputError(_join(self.name, key), items, "a list of values", self.source))
            return None
        out = []
        for i, x in enumerate(items):
            try:
                out.append(parse_quantity(x, f"{_join(self.name, key)}[{i}]", self.source).scaled(scale))
            except InputError as exc:
                self.reader.fail(exc)
        return out if len(out) == len(items) else None

    def reduce(self, nodes: tuple[str, ...], reduction, *args):
        """``reduction(*args)`` (a pendulum reduction), or ``None`` when an argument is missing or
        the reduction refuses its measurements (reported; ``nodes`` are then unreadable)."""
        if any(a is None for a in args):
            self.reader.unreadable.update(nodes)
            return None
        try:
            return reduction(*args)
        except InputError as exc:
            self.reader.fail(exc, *nodes)
            return None


def _k_t_missing(section: _Section, *nodes: str) -> None:
    section.reader.fail(
        InputError(
            "torsional_pendulum.k_t", MISSING, "the pendulum stiffness, to reduce torsional periods", section.source
        ),
        *nodes,
    )


def _wheel(
    section: _Section, k_t: Quantity | None, g: Quantity | None, prefix: str, raw: dict[str, Quantity]
) -> dict[str, Quantity | None]:
    mass = section.quantity("mass", node=f"m{prefix}")
    out: dict[str, Quantity | None] = {f"m{prefix}": mass}
    # I_xx = I_zz: given, or from a torsional period about a diameter (Eq. 1).
    if isinstance(section.data.get("Ixx"), dict) and "torsional_period" in section.data["Ixx"]:
        sub = section.section("Ixx", {"torsional_period"})
        period = sub.quantity("torsional_period", node=f"I{prefix}xx")
        if k_t is None and "k_t" not in section.reader.unreadable:
            _k_t_missing(section, f"I{prefix}xx")
        out[f"I{prefix}xx"] = sub.reduce(
            (f"I{prefix}xx",), pendulum.torsional_inertia, k_t, period, f"{sub.name}.torsional_period", section.source
        )
        if period is not None:
            raw[f"T_{prefix}xx"] = period
    else:
        out[f"I{prefix}xx"] = section.quantity("Ixx", node=f"I{prefix}xx")
    # I_yy: given, or from a compound pendulum (Eq. 7).
    if isinstance(section.data.get("Iyy"), dict) and "compound_period" in section.data["Iyy"]:
        sub = section.section("Iyy", {"compound_period", "pendulum_length"})
        period = sub.quantity("compound_period", node=f"I{prefix}yy")
        length = sub.quantity("pendulum_length", node=f"I{prefix}yy")
        out[f"I{prefix}yy"] = sub.reduce(
            (f"I{prefix}yy",),
            pendulum.compound_inertia,
            period,
            mass,
            length,
            g,
            f"{sub.name}.compound_period",
            section.source,
        )
        if period is not None and length is not None:
            raw[f"T_{prefix}yy"], raw[f"l_p{prefix}"] = period, length
    else:
        out[f"I{prefix}yy"] = section.quantity("Iyy", node=f"I{prefix}yy")
    return out


def _com_from_lines(com: _Section, prefix: str) -> tuple[Quantity | None, Quantity | None]:
    """Centre of mass where three or more pendulum-axis lines meet (least squares).

    Each line is ``{ point = [x, z], angle_deg = ... }``: a point it passes through and its angle
    from the ground, rising from +x (the convention of ``alpha_deg``).
    """
    nodes = (f"x{prefix}", f"z{prefix}")
    lines = com.data["lines"]
    if not isinstance(lines, list) or len(lines) < 3:
        com.reader.fail(
            InputError(
                _join(com.name, "lines"), lines, "a list of three or more {point = [x, z], angle_deg = ...}", com.source
            ),
            *nodes,
        )
        return None, None
    points, angles = [], []
    for i, line in enumerate(lines):
        entry = _Section(line, f"{_join(com.name, 'lines')}[{i}]", com.reader, {"point", "angle_deg"})
        point = entry.data.get("point")
        if not isinstance(point, list) or len(point) != 2:
            com.reader.fail(InputError(_join(entry.name, "point"), point, "[x, z] in metres", com.source), *nodes)
            continue
        xz = []
        for k, (coordinate, node) in enumerate(zip(point, nodes)):
            try:
                xz.append(parse_quantity(coordinate, f"{entry.name}.point[{k}]", com.source))
            except InputError as exc:
                com.reader.fail(exc, node)
        points.append(tuple(xz))
        angles.append(entry.quantity("angle_deg", scale=DEG, node=nodes[0]))
    if com.reader.unreadable.intersection(nodes):
        return None, None
    try:
        return pendulum.centre_of_mass_from_lines(points, angles, com.name, com.source)  # type: ignore[arg-type]
    except InputError as exc:
        com.reader.fail(exc, *nodes)
        return None, None


def _frame(
    section: _Section, k_t: Quantity | None, prefix: str, raw: dict[str, Quantity]
) -> dict[str, Quantity | None]:
    out: dict[str, Quantity | None] = {f"m{prefix}": section.quantity("mass", node=f"m{prefix}")}
    com = section.section("com", {"x", "z", "lines"})
    if com.has("lines") and (com.has("x") or com.has("z")):
        # Two measurements of one point: taking either silently would hide a disagreement.
        com.reader.fail(
            InputError(
                com.name,
                "x, z and lines",
                "either x and z or the hanging lines (one measurement of the centre of mass)",
                com.source,
            ),
            f"x{prefix}",
            f"z{prefix}",
        )
        out[f"x{prefix}"] = out[f"z{prefix}"] = None
    elif com.has("lines"):
        out[f"x{prefix}"], out[f"z{prefix}"] = _com_from_lines(com, prefix)
    else:
        out[f"x{prefix}"] = com.quantity("x", node=f"x{prefix}")
        out[f"z{prefix}"] = com.quantity("z", node=f"z{prefix}")
    tensor = tuple(f"I{prefix}{key[1:]}" for key in _TENSOR_KEYS)  # IBfxx, IBfxz, IBfzz
    inertia_raw = section.data.get("inertia")
    if isinstance(inertia_raw, dict) and "periods" in inertia_raw:
        sub = section.section("inertia", {"periods", "alpha_deg", "Iyy"})
        if k_t is None and "k_t" not in section.reader.unreadable:
            _k_t_missing(section, *tensor)
        periods, angles = sub.quantities("periods"), sub.quantities("alpha_deg", DEG)
        reduced = sub.reduce(
            tensor, pendulum.inertia_from_orientations, k_t, periods, angles, section.name, section.source
        )
        out.update(zip(tensor, reduced or (None, None, None)))
        if reduced is not None and len(periods) == 3:  # the closed form of Eq. 6 the sensitivities differentiate
            for i, (period, angle) in enumerate(zip(periods, angles), start=1):  # type: ignore[arg-type]
                raw[f"T_{prefix}{i}"], raw[f"alpha_{prefix}{i}"] = period, angle
    else:
        sub = section.section("inertia", {"Ixx", "Ixz", "Izz", "Iyy"})
        for node, key in zip(tensor, _TENSOR_KEYS):
            out[node] = sub.quantity(key, node=node)
    Iyy = sub.quantity("Iyy", required=False, node=f"I{prefix}yy")
    if Iyy is not None:
        out[f"I{prefix}yy"] = Iyy
    return out


EARTH_G = 9.81
"""Gravity where pendulums swing unless a file says otherwise [m/s^2] (the paper's, Table 12)."""


def _on_earth(g: Quantity) -> bool:
    return pendulum.EARTH_GRAVITY[0] <= g.value <= pendulum.EARTH_GRAVITY[1]


def _has_compound_period(data: dict[str, Any]) -> bool:
    """Whether a wheel of the file gives its I_yy as a compound pendulum period."""
    for wheel in ("rear_wheel", "front_wheel"):
        table = data.get(wheel)
        if isinstance(table, dict) and isinstance(table.get("Iyy"), dict) and "compound_period" in table["Iyy"]:
            return True
    return False


def _present(values: dict[str, Quantity | None]) -> dict[str, Quantity]:
    return {k: q for k, q in values.items() if q is not None}


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
        An unreadable file; otherwise every error of the file at once (unknown tables and keys,
        values that cannot be read, missing ones, impossible ones): :class:`~bikerider.errors.InputErrors`
        when there are several.
    """
    source = str(path)
    data = read_toml(path)
    reader = _Reader(source)
    top = _Section(
        data,
        "",
        reader,
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
    meta = top.section("bicycle", {"name", "source", "notes"}) if top.has("bicycle") else None
    name = meta.data.get("name", Path(path).stem) if meta is not None else Path(path).stem
    g: Quantity | None = Quantity(9.81)
    g_lab: Quantity | None = None
    if top.has("environment"):
        environment = top.section("environment", {"g", "g_lab"})
        g = environment.quantity("g", required=False) or (None if "g" in reader.unreadable else g)
        g_lab = environment.quantity("g_lab", required=False)
    # Gravity where the compound pendulums swung: g_lab; by default the bicycle's g when that is a
    # gravity of the Earth's surface, else the Earth's (a bicycle modelled on the Moon was measured here).
    pendulum_g = None if "g_lab" in reader.unreadable else (g_lab or g)
    if g_lab is None and g is not None and not _on_earth(g) and _has_compound_period(data):
        pendulum_g = Quantity(EARTH_G)
        note(
            f"{source}: the compound pendulum periods are reduced at g_lab = {EARTH_G} m/s^2 (on Earth): "
            f"[environment] g = {g} is where the bicycle rides; give g_lab if the pendulum swung elsewhere"
        )
    values: dict[str, Quantity | None] = {"g": g}
    geometry = top.section("geometry", set(_GEOMETRY_KEYS) | {f"{a}_deg" for a in _GEOMETRY_ANGLES})
    for key in _GEOMETRY_KEYS:
        values[key] = geometry.quantity(key, required=key not in SEATING_NAMES)
    for key in _GEOMETRY_ANGLES:
        values[key] = geometry.quantity(f"{key}_deg", required=key not in SEATING_NAMES, scale=DEG, node=key)
    k_t = None
    if top.has("torsional_pendulum"):
        k_t = top.section("torsional_pendulum", {"k_t"}).quantity("k_t")
    raw: dict[str, Quantity] = {}
    values.update(_wheel(top.section("rear_wheel", {"mass", "Ixx", "Iyy"}), k_t, pendulum_g, "R", raw))
    values.update(_wheel(top.section("front_wheel", {"mass", "Ixx", "Iyy"}), k_t, pendulum_g, "F", raw))
    values.update(_frame(top.section("rear_frame", {"mass", "com", "inertia"}), k_t, "Bf", raw))
    values.update(_frame(top.section("handlebar_fork", {"mass", "com", "inertia"}), k_t, "H", raw))
    present = _present(values)
    if reader.errors:
        check_bicycle_values(present, source, reader.errors, [], reader.unreadable)
        reader.errors.raise_any()
    if g_lab is not None and not any(name_.startswith("T_") and name_.endswith("yy") for name_ in raw):
        note(f"{source}: [environment] g_lab = {g_lab} not used: no compound pendulum period is given")
    if g is not None and pendulum_g is not None and pendulum_g.value != g.value:
        # The chain's compound-pendulum stage takes the bicycle's g: with another gravity at the
        # pendulum, its reduced I_yy enters the sensitivities as a measured value.
        for name_ in ("T_Ryy", "l_pR", "T_Fyy", "l_pF"):
            raw.pop(name_, None)
    reduced = _reduced_names(raw)
    if raw and k_t is not None:
        raw["k_t"] = k_t
    return BicycleBodies(present, source, str(name), raw_inputs=raw, reduced=reduced)


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
        An unreadable file; otherwise every error of the file at once.

    Notes
    -----
    Mass fractions are taken as exact: they must sum to 1, so they cannot vary independently.  An
    uncertainty given on one is not used, and a note says so.
    """
    source = str(path)
    data = read_toml(path)
    reader = _Reader(source)
    top = _Section(data, "", reader, {"rider", "measurements", "mass_fractions"})
    rider = top.section("rider", {"name", "mass", "source"})
    values: dict[str, Quantity | None] = {"mBr": rider.quantity("mass", node="mBr")}
    measurements = top.section("measurements", set(_RIDER_KEYS) | {"lam_fl_deg"})
    for key in _RIDER_KEYS:
        values[key] = measurements.quantity(key)
    values["lam_fl"] = measurements.quantity("lam_fl_deg", scale=DEG, node="lam_fl")
    fractions = dict(DEFAULT_MASS_FRACTIONS)
    if top.has("mass_fractions"):
        section = top.section("mass_fractions", set(_FRACTION_KEYS))
        for key, symbol in _FRACTION_KEYS.items():
            q = section.quantity(key, required=False, node=symbol)
            if q is not None:
                fractions[symbol] = q.value
                if q.sigma:
                    note(
                        f"{source}: mass_fractions.{key} = {q}: its uncertainty is not used (the mass fractions "
                        "must sum to 1, so they cannot vary independently; they are taken as exact)"
                    )
    name = rider.data.get("name", Path(path).stem)
    present = _present(values)
    if reader.errors:
        check_rider_values(present, fractions, source, reader.errors, reader.unreadable)
        reader.errors.raise_any()
    return RiderMeasurements(present, fractions, source, str(name))
