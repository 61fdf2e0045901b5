"""The model a diagnosis starts from: benchmark parameters with uncertainties, and where the rider is.

``--model`` takes either

* a TOML file with the 25 benchmark parameters (plus ``g``) at top level or under ``[benchmark]``,
  values as numbers or ``"value +/- sigma"``; optional tables ``[rider]`` (the rider contained in
  the rear body: ``mass, x, z, Ixx, Ixz, Izz``, benchmark frame), ``[upper_body]`` (``m_u, x_u,
  z_u, IUxx, IUxz, IUzz, z_lean``) and ``[grips]`` (``x_grip, z_grip, b_grip``); or
* a BicycleParameters ``<Name>Benchmark.txt`` (``name = value+/-sigma``).

``--rider`` adds a BicycleParameters lumped rider (``riders/<Rider>/Parameters/<Rider><Bike>
Benchmark.txt``) to the rear body (Moore et al. 2009, Eqs. 15-16).

Default geometry, used when a file does not give it (documented approximations, see
:func:`default_geometry`): the upper body that can lean is half the rider's mass, its centre
0.2 m above the rider's centre of mass, the hip axis 0.1 m below it; the grips sit at the
handlebar-and-fork centre of mass, 0.29 m either side of the bicycle's plane.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from bikerider.benchmark import BenchmarkParameters
from bikerider.errors import FileFormatError, InputError
from bikerider.gap.models import GRIP_KEYS, UPPER_BODY_KEYS, RiderGeometry
from bikerider.quantity import parse_quantity

UPPER_BODY_FRACTION = 0.5
"""Share of the rider's mass above the hips (head, trunk above the pelvis, arms).  de Leva (1996)
segment fractions give head 6.9 %, arms 9.9 % and trunk 43.5 % of which the pelvis is about a
quarter: about 0.5."""
UPPER_BODY_RISE = 0.20
"""Height of the upper body's centre above the whole rider's centre [m] (seated rider, approx.)."""
HIP_DROP = 0.10
"""Depth of the hip (lean) axis below the whole rider's centre [m] (seated rider, approx.)."""
UPPER_BODY_RADII = (0.22, 0.15)
"""Radii of gyration of the upper body about its roll (x) and yaw (z) axes [m] (approx.)."""
GRIP_HALF_WIDTH = 0.29
"""Half the grip-to-grip distance of a typical flat handlebar [m]."""

RIDER_KEYS = ("mass", "x", "z", "Ixx", "Ixz", "Izz")


@dataclass(frozen=True)
class GapModelInput:
    """Benchmark parameters (rider included), rider geometry, and the rider itself if known."""

    parameters: BenchmarkParameters
    geometry: RiderGeometry
    rider: dict[str, float] | None
    source: str


def default_geometry(parameters: BenchmarkParameters, rider: dict[str, float] | None) -> RiderGeometry:
    """Upper body and grips from the rider's lumped body (or none without a rider).

    Parameters
    ----------
    parameters : BenchmarkParameters
        With the rider included in the rear body.
    rider : dict or None
        ``mass, x, z, Ixx, Ixz, Izz`` of the rider (benchmark frame), or ``None``.
    """
    v = parameters.values
    grips = {"x_grip": float(v["xH"]), "z_grip": float(v["zH"]), "b_grip": GRIP_HALF_WIDTH}
    notes = ["grips at the handlebar-and-fork centre of mass, 0.29 m either side (default)"]
    upper = None
    if rider is not None:
        m_u = UPPER_BODY_FRACTION * rider["mass"]
        kx, kz = UPPER_BODY_RADII
        upper = {
            "m_u": m_u,
            "x_u": rider["x"],
            "z_u": rider["z"] - UPPER_BODY_RISE,
            "IUxx": m_u * kx**2,
            "IUxz": 0.0,
            "IUzz": m_u * kz**2,
            "z_lean": rider["z"] + HIP_DROP,
        }
        notes.append(
            f"upper body: {UPPER_BODY_FRACTION:.0%} of the rider's {rider['mass']:.1f} kg, "
            f"{UPPER_BODY_RISE} m above the rider's centre of mass, hip axis {HIP_DROP} m below it (default)"
        )
    else:
        notes.append("no rider: rider_lean and passive_arms do not apply")
    return RiderGeometry(upper, grips, "; ".join(notes))


def _table_numbers(table: object, name: str, keys: tuple[str, ...], source: str) -> dict[str, float]:
    if not isinstance(table, dict):
        raise InputError(name, table, "a table", source)
    unknown = sorted(set(table) - set(keys))
    if unknown:
        raise InputError(f"{name}.{unknown[0]}", table[unknown[0]], "one of " + ", ".join(keys), source)
    out = {}
    for key in keys:
        if key not in table:
            raise InputError(f"{name}.{key}", "missing", "a value", source)
        out[key] = parse_quantity(table[key], f"{name}.{key}", source).value
    return out


def load_model(
    path: str | Path, rider_path: str | Path | None = None, *, rider_rel_sigma: float = 0.0
) -> GapModelInput:
    """Read the model file (and a lumped rider); build the default geometry where none is given.

    ``rider_rel_sigma`` gives the lumped rider's values a relative standard uncertainty where its
    file states none (BicycleParameters rider files state none).

    Raises
    ------
    FileFormatError
        Unreadable file.
    InputError
        A missing or impossible value (names the file, the key and what was expected).
    """
    from bikerider.io.benchmark_file import load_benchmark_parameters, parameters_from_table

    path = Path(path)
    if not path.exists():
        raise FileFormatError(path, "no such file")
    source = str(path)
    tables: dict[str, object] = {}
    if path.suffix.lower() == ".toml":
        from bikerider.io.toml_input import read_toml

        data = read_toml(path)
        extra = {k: data[k] for k in ("rider", "upper_body", "grips") if k in data}
        if extra and "benchmark" not in data:
            raise InputError(
                "benchmark",
                "missing",
                "a [benchmark] table when the file also has " + ", ".join(f"[{k}]" for k in extra),
                source,
            )
        tables = extra
        parameters = parameters_from_table(data.get("benchmark", data), source)
    else:
        parameters = load_benchmark_parameters(path)
    rider = _table_numbers(tables["rider"], "rider", RIDER_KEYS, source) if "rider" in tables else None
    if rider_path is not None:
        if rider is not None:
            raise InputError("rider", str(rider_path), "one rider: the model file already has a [rider] table", source)
        parameters, rider = _merge_rider(parameters, Path(rider_path), rider_rel_sigma)
    if rider is not None and not (rider["mass"] > 0 and rider["mass"] < float(parameters["mB"])):  # type: ignore[operator]
        raise InputError(
            "rider.mass", rider["mass"], f"a positive mass below the rear body's {parameters['mB']} kg", source
        )
    geometry = default_geometry(parameters, rider)
    if "upper_body" in tables:
        geometry = RiderGeometry(
            _table_numbers(tables["upper_body"], "upper_body", UPPER_BODY_KEYS, source),
            geometry.grips,
            geometry.notes + "; upper body from the model file",
        )
    if "grips" in tables:
        geometry = RiderGeometry(
            geometry.upper_body,
            _table_numbers(tables["grips"], "grips", GRIP_KEYS, source),
            geometry.notes + "; grips from the model file",
        )
    return GapModelInput(parameters, geometry, rider, source + (f" + rider {rider_path}" if rider_path else ""))


def _merge_rider(
    parameters: BenchmarkParameters, rider_path: Path, rel_sigma: float = 0.0
) -> tuple[BenchmarkParameters, dict[str, float]]:
    from dataclasses import replace

    from bikerider.io.bicycleparameters import merge_rider, read_lumped_rider
    from bikerider.quantity import Quantity

    if not rider_path.exists():
        raise FileFormatError(rider_path, "no such file")
    lumped = read_lumped_rider(rider_path)
    if rel_sigma > 0:
        lumped = replace(
            lumped,
            values={
                k: q if q.sigma > 0 else Quantity(q.value, rel_sigma * abs(q.value)) for k, q in lumped.values.items()
            },
        )
    values = {k: q.value for k, q in lumped.values.items()}
    rider = {
        "mass": values["mBr"],
        "x": values["xBr"],
        "z": values["zBr"],
        "Ixx": values["IBrxx"],
        "Ixz": values["IBrxz"],
        "Izz": values["IBrzz"],
    }
    return merge_rider(parameters, lumped), rider
