"""BicycleParameters data files: ``<Name>Benchmark.txt``, ``<Rider><Bike>Benchmark.txt`` (a lumped
rider) and ``<Name>Measured.txt``; and a format detector for the ``estimate`` command.

Benchmark files hold the 25 benchmark parameters and ``g`` as ``name = value+/-sigma``.  Some carry
more, handled so:

* ``yB``, ``yH`` (lateral centre of mass): must be 0 within :data:`LATERAL_TOLERANCE` (the
  benchmark bodies are symmetric about the XZ plane); dropped.
* ``IRzz``, ``IFzz`` (wheel moment about z): must equal ``IRxx``/``IFxx`` within their
  uncertainties or 1e-9 relative (the benchmark's wheels are axisymmetric); dropped.
* ``mG, xG, zG, IGxx, IGxz, IGyy, IGzz`` and the same for ``S`` (handlebar and fork measured apart,
  as in BicycleParameters' Rigid): kept in :attr:`BenchmarkFile.extras`; the file's ``H`` values
  are the combined body the benchmark uses.
* ``IByy``/``IHyy`` that break the triangle inequality with the body's in-plane moments (BicycleParameters'
  own Browser, Fisher and Yellow files do: their compound-pendulum ``I_yy`` cannot belong to one
  body with their torsional-pendulum ``Ixx, Ixz, Izz``) are left out, with a note: the linear
  model does not use them.
* flywheel entries (``mD``, ``IDxx``, ...) and anything else: an error, since silently dropping a
  body would give a wrong model.

A lumped rider file gives the rider as one rigid body (``mB, xB, yB, zB, IBxx, IBxz, IByy, IBzz``,
benchmark frame, ``IBxz`` the tensor entry); :func:`merge_rider` combines it with the bicycle's rear
body as the paper does (Eqs. 15-16, generated ``combination.rear_body``).
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path, PurePath

from bikerider.benchmark.parameters import BENCHMARK_NAMES, BenchmarkParameters, check_mass_matrix, uncertainty_notes
from bikerider.benchmark.rules import LIMITS
from bikerider.bicycle.bodies import BicycleBodies
from bikerider.bicycle.raw_measurements import DEFAULT_LINE_TOLERANCE, MeasuredReduction, reduce_measured
from bikerider.bicycle.to_benchmark import LumpedRider, bodies_from_benchmark, merge_rider
from bikerider.errors import ErrorCollector, FileFormatError, InputError
from bikerider.inertia import TRIANGLE, inertia_problem, plane_symmetric_principal_moments
from bikerider.io.input_file import read_input_text
from bikerider.io.name_value_file import NameValueFile, parse_name_value_text, read_name_value_file
from bikerider.io.toml_input import load_bicycle_toml
from bikerider.notes import add as add_note
from bikerider.notes import note
from bikerider.quantity import Quantity

#: Largest lateral centre-of-mass offset [m] accepted (and dropped) for a body of the symmetric model.
LATERAL_TOLERANCE = 1e-3

SPLIT_FORK_NAMES = tuple(f"{p}{b}" for b in "GS" for p in ("m", "x", "z")) + tuple(
    f"I{b}{ax}" for b in "GS" for ax in ("xx", "xz", "yy", "zz")
)
"""Handlebar (G) and fork (S) measured apart: kept as extras."""

LUMPED_RIDER_NAMES = ("mB", "xB", "yB", "zB", "IBxx", "IBxz", "IByy", "IBzz")
"""Names of a lumped rider file."""
_LUMPED_RIDER_SET = frozenset(LUMPED_RIDER_NAMES)
_RIDER_BODY_NAME = {
    name: f"{name}r" if name in ("mB", "xB", "zB") else name.replace("IB", "IBr")
    for name in LUMPED_RIDER_NAMES
    if name != "yB"
}
"""A lumped rider file's name to the rider's in :data:`bikerider.bicycle.to_benchmark.RIDER_BODY_NAMES`."""

BENCHMARK_EXTRAS = ("yB", "yH", "IRzz", "IFzz", *SPLIT_FORK_NAMES)
"""The entries of a benchmark file beyond the benchmark parameters that :func:`benchmark_from_values`
knows (and drops or keeps as extras, with a note)."""

_MEASURED_MARKERS = re.compile(
    r"^(Tt|Tc|alpha|a)[A-Z]\d+$|^(dF|dR|nF|nR|mP|dP|lP|lF|lR|gamma|h\d|d\d|LhbF|LhbR|lamst|whb|lcs|hbb|lsp|lst)$"
)
_FLYWHEEL = re.compile(r"^(m|x|z|I)D")


@dataclass(frozen=True)
class BenchmarkFile:
    """A BicycleParameters benchmark file, read.

    Attributes
    ----------
    parameters : BenchmarkParameters
    extras : dict of str to Quantity
        Entries beyond the benchmark's (split handlebar and fork), and any ``I_yy`` left out.
    notes : list of str
        What was dropped or left out, and why.
    """

    parameters: BenchmarkParameters
    extras: dict[str, Quantity] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


def _triangle_problem(values: dict[str, Quantity], body: str) -> bool:
    """Whether ``body``'s tensor breaks the triangle inequality (and nothing else)."""
    xx, yy, zz, xz = (values[f"I{body}{ax}"].value for ax in ("xx", "yy", "zz", "xz"))
    problem = inertia_problem(xx, yy, zz, xz)
    return problem is not None and problem[1] == TRIANGLE


def _tensor_problem(values: dict[str, Quantity], yy: Quantity, body: str) -> str:
    xx, zz, xz = (values[f"I{body}{ax}"].value for ax in ("xx", "zz", "xz"))
    principal = ", ".join(f"{p:.4g}" for p in plane_symmetric_principal_moments(xx, yy.value, zz, xz))
    return f"with I{body}xx, I{body}xz, I{body}zz its principal moments {principal} break the triangle inequality"


def benchmark_from_values(data: NameValueFile) -> BenchmarkFile:
    """Build :class:`BenchmarkFile` from a parsed benchmark file (see the module docstring).

    Raises
    ------
    InputError
        A missing benchmark parameter, an unknown or flywheel entry, a lateral centre of mass or a
        non-axisymmetric wheel, or values no bicycle can have: every one of them at once.
    """
    values = data.as_dict()
    mapping: dict[str, Quantity] = {}
    extras: dict[str, Quantity] = {}
    notes: list[str] = []
    errors = ErrorCollector()
    for name, q in values.items():
        where = data.where(name)
        if name in BENCHMARK_NAMES:
            mapping[name] = q
        elif name in SPLIT_FORK_NAMES:
            extras[name] = q
        elif name in ("yB", "yH"):
            if abs(q.value) > LATERAL_TOLERANCE:
                errors.add(
                    InputError(
                        name,
                        q.value,
                        f"0 within {LATERAL_TOLERANCE} m: the benchmark bodies are symmetric about the bicycle's XZ plane",
                        where,
                    )
                )
            else:
                notes.append(f"{name} = {q.value:g} m dropped (the benchmark bodies lie in the XZ plane)")
        elif name in ("IRzz", "IFzz"):
            xx = values.get(f"I{name[1]}xx")
            if xx is not None:
                allowed = max(math.hypot(q.sigma, xx.sigma), 1e-9 * abs(xx.value))
                if abs(q.value - xx.value) > allowed:
                    errors.add(
                        InputError(
                            name,
                            q.value,
                            f"equal to I{name[1]}xx = {xx.value:g}: the benchmark's wheels are axisymmetric",
                            where,
                        )
                    )
                    continue
            notes.append(f"{name} dropped (equal to I{name[1]}xx for the benchmark's axisymmetric wheel)")
        elif _FLYWHEEL.match(name):
            errors.add(
                InputError(
                    name,
                    q.value,
                    "no flywheel body: the Whipple benchmark model has four bodies "
                    "(R, B, H, F), and leaving the flywheel out would give a wrong model",
                    where,
                )
            )
        else:
            errors.add(
                InputError(
                    name,
                    q.value,
                    "a benchmark parameter ("
                    + ", ".join(BENCHMARK_NAMES)
                    + ") or a known BicycleParameters extra (yB, yH, IRzz, IFzz, G and S bodies)",
                    where,
                )
            )
    split = [name for name in SPLIT_FORK_NAMES if name in extras]
    if split:
        notes.append(
            f"handlebar (G) and fork (S) measured apart ({', '.join(split)}): not used; the model takes the "
            "combined handlebar and fork H of the file"
        )
    for body in ("B", "H"):
        if all(f"I{body}{ax}" in mapping for ax in ("xx", "yy", "zz", "xz")):
            yy = mapping[f"I{body}yy"]
            if 0 < yy.value <= LIMITS[f"I{body}yy"][0] and _triangle_problem(mapping, body):
                # Possible on its own but not with the body's in-plane moments: a compound-pendulum
                # I_yy measured apart from the torsional ones; the linear model does not use it.
                extras[f"I{body}yy"] = mapping.pop(f"I{body}yy")
                notes.append(
                    f"I{body}yy = {yy} left out: {_tensor_problem(mapping, yy, body)} (the linear model does not use it)"
                )
    try:
        parameters = BenchmarkParameters.from_mapping(mapping, source=data.path)
        check_mass_matrix(parameters)
    except InputError as exc:
        errors.add(exc)
    errors.raise_any()
    for message in notes:
        note(f"{data.path}: {message}")
    for message in uncertainty_notes(parameters):
        add_note(notes, message)
    return BenchmarkFile(parameters, extras, notes)


def read_benchmark_file(path: str | Path) -> BenchmarkFile:
    """Read a BicycleParameters ``<Name>Benchmark.txt``."""
    return benchmark_from_values(read_name_value_file(path))


def read_lumped_rider(path: str | Path) -> LumpedRider:
    """Read a BicycleParameters lumped rider file (``riders/<Rider>/Parameters/<Rider><Bike>Benchmark.txt``).

    Raises
    ------
    InputError
        A missing or unknown entry, or a lateral centre of mass beyond :data:`LATERAL_TOLERANCE`.
    """
    data = read_name_value_file(path)
    values = data.as_dict()
    errors = ErrorCollector()
    for name in [name for name in values if name not in _LUMPED_RIDER_SET]:  # in file order
        errors.add(
            InputError(
                name,
                values.pop(name).value,
                "one of the lumped rider entries " + ", ".join(LUMPED_RIDER_NAMES),
                data.where(name),
            )
        )
    y = values.pop("yB", None)
    if y is not None and abs(y.value) > LATERAL_TOLERANCE:
        errors.add(
            InputError(
                "yB",
                y.value,
                f"0 within {LATERAL_TOLERANCE} m: a rider centred on the bicycle's XZ plane",
                data.where("yB"),
            )
        )
    renamed = {_RIDER_BODY_NAME[name]: q for name, q in values.items()}
    stem = (path if isinstance(path, PurePath) else PurePath(path)).stem
    rider = None
    with errors.check():
        rider = LumpedRider(
            renamed, source=str(path), name=stem[: -len("Benchmark")] if stem.endswith("Benchmark") else stem
        )
    errors.raise_any()
    if y is not None:
        note(f"{path}: yB = {y.value:g} m dropped (the rider is centred on the bicycle's XZ plane)")
    return rider  # type: ignore[return-value]


def read_measured_file(
    path: str | Path, *, line_tolerance: float = DEFAULT_LINE_TOLERANCE, com_method: str = "least_squares"
) -> MeasuredReduction:
    """Read and reduce a ``<Name>Measured.txt`` file (messages name its lines).

    Parameters
    ----------
    path : str or Path
    line_tolerance, com_method
        See :func:`bikerider.bicycle.raw_measurements.reduce_measured`.

    Returns
    -------
    MeasuredReduction
        The bicycle's bodies with first-order uncertainties (named after the file:
        ``BrowserMeasured.txt`` gives ``Browser``), the extras, the line fits and the notes.

    Raises
    ------
    FileFormatError, InputError, FitError
        An unreadable file, a missing or impossible measurement, hanging lines that do not meet.
    """
    data = read_name_value_file(path)
    stem = (path if isinstance(path, PurePath) else PurePath(path)).stem
    name = stem[: -len("Measured")] if stem.endswith("Measured") and len(stem) > len("Measured") else stem
    return reduce_measured(data, source=data, name=name, line_tolerance=line_tolerance, com_method=com_method)


def load_measured_bicycle(path: str | Path) -> BicycleBodies:
    """The :class:`BicycleBodies` of a ``<Name>Measured.txt`` file."""
    return read_measured_file(path).bodies


def detect_format(path: str | Path) -> str:
    """Which kind of input file ``path`` is: ``"toml"``, ``"measured"``, ``"benchmark"`` or ``"lumped_rider"``.

    A ``.toml`` suffix means the project's TOML format: ``"benchmark"`` when it holds benchmark
    parameters (a ``[benchmark]`` table or Meijaard names at top level), else ``"toml"`` (raw
    measurements); ``.json`` is the parameter JSON of ``bikerider convert`` (``"benchmark"``).  Otherwise the file is read as
    ``name = value`` lines and told apart by its names: raw measurements (periods ``Tt*``/``Tc*``,
    hanging angles, rolled distances, seating measurements) make a Measured file; the benchmark
    parameters (``w``, ``c``, ``lam``, ...) a Benchmark file; only ``mB, xB, yB, zB, IBxx, IBxz,
    IByy, IBzz`` a lumped rider.

    Raises
    ------
    FileFormatError
        A file that is none of these (the message says what was found).
    """
    text = read_input_text(path)  # refuses an empty path, a FIFO, a folder, a huge file
    suffix = Path(path).suffix.lower()
    if suffix == ".json":
        return "benchmark"
    if suffix == ".toml":
        return _toml_kind(text)
    try:
        data = parse_name_value_text(text, str(path))
    except FileFormatError as exc:
        try:
            tomllib.loads(text)
        except (tomllib.TOMLDecodeError, ValueError):  # ValueError: an integer too long to convert
            raise exc from None
        return _toml_kind(text)
    names = set(data)
    if not names:
        raise FileFormatError(path, "no 'name = value' entries: the file is empty or holds only comments")
    if any(_MEASURED_MARKERS.match(n) for n in names):
        return "measured"
    if names <= set(LUMPED_RIDER_NAMES) and "w" not in names:
        return "lumped_rider"
    if names & {"w", "c", "lam", "rR", "rF"}:
        return "benchmark"
    raise FileFormatError(
        path,
        "cannot tell the kind of file: expected raw measurements (e.g. TtP1, dF, alphaB1), "
        "benchmark parameters (w, c, lam, ...) or a lumped rider (mB, xB, zB, IBxx, ...); found "
        + ", ".join(sorted(names)[:8]),
    )


_BENCHMARK_TOML_KEYS = frozenset({"benchmark", "w", "c", "lam", "lam_deg", "rR", "rF"})


def _toml_kind(text: str) -> str:
    """``"benchmark"`` for a TOML file of benchmark parameters (a ``[benchmark]`` table, as a gap
    model file has, or Meijaard names at top level), else ``"toml"`` (raw measurements; an
    unreadable file is left to the TOML reader, which says why)."""
    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, ValueError):  # ValueError: an integer too long to convert
        return "toml"
    return "benchmark" if _BENCHMARK_TOML_KEYS.intersection(data) else "toml"


def load_bicycle_file(path: str | Path) -> BicycleBodies | BenchmarkParameters:
    """Load a bicycle from any supported file.

    Returns
    -------
    BicycleBodies
        For a project TOML file or a BicycleParameters Measured file (raw measurements reduced,
        seating measurements included when the file has them).
    BenchmarkParameters
        For a BicycleParameters Benchmark file, a TOML file of benchmark parameters (a gap model
        file too: its other tables are left out with a note) or the JSON of ``bikerider convert``.

    Raises
    ------
    FileFormatError
        A lumped rider file (not a bicycle) or an unrecognised file.
    """
    kind = detect_format(path)
    if kind == "toml":
        return load_bicycle_toml(path)
    if kind == "measured":
        return load_measured_bicycle(path)
    if kind == "benchmark" and Path(path).suffix.lower() in (".toml", ".json"):
        # io.benchmark_file imports this module (its text reader): imported here to avoid the cycle
        from bikerider.io.benchmark_file import load_benchmark_parameters

        return load_benchmark_parameters(path)
    if kind == "benchmark":
        return read_benchmark_file(path).parameters
    raise FileFormatError(
        path, "this is a lumped rider file (mB, xB, zB, IBxx, ...), not a bicycle; give it as the rider"
    )


__all__ = [
    "BENCHMARK_EXTRAS",
    "BenchmarkFile",
    "LATERAL_TOLERANCE",
    "benchmark_from_values",
    "bodies_from_benchmark",
    "detect_format",
    "load_bicycle_file",
    "load_measured_bicycle",
    "merge_rider",
    "parse_name_value_text",
    "read_benchmark_file",
    "read_lumped_rider",
    "read_measured_file",
]
