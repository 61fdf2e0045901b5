"""Hypothesis strategies: random but physical bicycles, riders and benchmark parameter sets.

Each strategy perturbs a published starting point within physical ranges:

* :func:`bicycles` and :func:`riders` perturb the paper's 2008 Batavus Browser and 72 kg rider
  (``src/bikerider/data/paper/*.toml``, read with :mod:`bikerider.io.toml_input`);
* :func:`benchmark_mappings` perturbs the Meijaard et al. (2007) benchmark bicycle
  (``tests/data/meijaard2007.json``, Table 1).

Inertia tensors are perturbed by a rotation in the XZ plane and a positive scale, which keeps them
symmetric, positive definite and within the triangle inequality by construction; a given ``I_yy``
is drawn between the bounds the in-plane principal moments allow.  A wheel's moments are drawn
within what a wheel of its mass and radius can have (:func:`wheel_moments`).  :func:`seated_pairs`
draws a bicycle and a rider and rejects (``hypothesis.reject``) the pairs the project itself
refuses to seat (:class:`bikerider.errors.ReachError`, or a forward lean with the shoulders ahead
of the hands).
"""

from __future__ import annotations

import contextlib
import functools
import io
import json
import math
import re
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from hypothesis import reject
from hypothesis import strategies as st

from bikerider.bicycle.bodies import BicycleBodies
from bikerider.errors import InputError
from bikerider.quantity import Quantity
from bikerider.rider.measurements import DEFAULT_MASS_FRACTIONS, FRACTION_COUNTS, RiderMeasurements

DATA = Path(__file__).parent / "data"

BICYCLE_LENGTHS = ("w", "rR", "rF", "h_bb", "l_cs", "l_f", "w_fh", "l_hb", "w_rh", "l_sp", "l_st", "l_s")
RIDER_LENGTHS = ("c_ch", "c_h", "l_hh", "c_la", "l_la", "c_ll", "l_ll", "l_ss", "l_to", "c_ua", "l_ua", "c_ul", "l_ul")


@functools.lru_cache(maxsize=1)
def paper_inputs() -> tuple[BicycleBodies, RiderMeasurements]:
    """The paper's bicycle and rider, read from the package's own TOML files."""
    from bikerider.estimate import default_files
    from bikerider.io.toml_input import load_bicycle_toml, load_rider_toml

    bicycle_path, rider_path = default_files()
    return load_bicycle_toml(bicycle_path), load_rider_toml(rider_path)


@functools.lru_cache(maxsize=1)
def meijaard_values() -> dict[str, float]:
    """Meijaard et al. (2007) Table 1, with ``lam`` for the JSON's ``lambda``."""
    values = dict(json.loads((DATA / "meijaard2007.json").read_text())["parameters"]["values"])
    values["lam"] = values.pop("lambda")
    return values


def factor(low: float, high: float) -> st.SearchStrategy[float]:
    return st.floats(low, high, allow_nan=False, allow_infinity=False)


def rotate_xz(xx: float, zz: float, xz: float, angle: float, scale: float) -> tuple[float, float, float]:
    """The xz block of an inertia tensor seen in axes turned by ``angle`` about y, times ``scale``."""
    c, s = math.cos(angle), math.sin(angle)
    rotation = np.array([[c, -s], [s, c]])
    block = rotation @ np.array([[xx, xz], [xz, zz]]) @ rotation.T * scale
    return float(block[0, 0]), float(block[1, 1]), float(0.5 * (block[0, 1] + block[1, 0]))


def yy_between(xx: float, zz: float, xz: float, t: float) -> float:
    """An ``I_yy`` a fraction ``t`` of the way between the triangle-inequality bounds of the xz block."""
    p = np.linalg.eigvalsh(np.array([[xx, xz], [xz, zz]]))
    low, high = p[1] - p[0], p[1] + p[0]
    return float(low + t * (high - low))


@st.composite
def tensor_perturbation(draw) -> tuple[float, float, float | None]:
    """``(angle, scale, yy_fraction or None)`` for :func:`rotate_xz` and :func:`yy_between`."""
    angle = draw(factor(-0.5, 0.5))
    scale = draw(factor(0.6, 1.5))
    yy = draw(st.one_of(st.none(), factor(0.05, 0.95)))
    return angle, scale, yy


@st.composite
def wheel_moments(draw, mass: float, radius: float, lowest_ratio: float) -> tuple[float, float]:
    """``(I_yy, I_xx)`` a wheel of this mass and radius can have: ``I_yy`` between 0.3 and 0.95 of
    ``m r^2`` (the paper's wheels: 0.44; Meijaard's: 0.67, 0.76), ``I_xx`` between ``I_yy / 1.98``
    and ``I_yy / lowest_ratio`` (the triangle inequality ``I_yy <= 2 I_xx``)."""
    yy = mass * radius**2 * draw(factor(0.3, 0.95))
    return yy, yy / draw(factor(lowest_ratio, 1.98))


@st.composite
def bicycles(draw) -> BicycleBodies:
    """The paper's Browser with every length, angle, mass and inertia perturbed physically."""
    base, _ = paper_inputs()
    v = {k: q.value for k, q in base.values.items()}
    out = dict(v)
    for key in BICYCLE_LENGTHS:
        out[key] = v[key] * draw(factor(0.92, 1.08))
    out["c"] = draw(factor(0.02, 0.10))
    out["lam_ht"] = v["lam_ht"] + math.radians(draw(factor(-4.0, 4.0)))
    out["lam_st"] = v["lam_st"] + math.radians(draw(factor(-4.0, 4.0)))
    for key in ("mR", "mF", "mBf", "mH"):
        out[key] = v[key] * draw(factor(0.6, 1.5))
    for wheel in ("R", "F"):
        out[f"I{wheel}yy"], out[f"I{wheel}xx"] = draw(wheel_moments(out[f"m{wheel}"], out[f"r{wheel}"], 1.1))
    for body in ("Bf", "H"):
        out[f"x{body}"] = v[f"x{body}"] + draw(factor(-0.05, 0.05))
        out[f"z{body}"] = v[f"z{body}"] + draw(factor(-0.05, 0.05))
        angle, scale, yy = draw(tensor_perturbation())
        xx, zz, xz = rotate_xz(v[f"I{body}xx"], v[f"I{body}zz"], v[f"I{body}xz"], angle, scale)
        out.update({f"I{body}xx": xx, f"I{body}zz": zz, f"I{body}xz": xz})
        if yy is not None:
            out[f"I{body}yy"] = yy_between(xx, zz, xz, yy)
    return BicycleBodies({k: Quantity(x) for k, x in out.items()}, "<hypothesis bicycle>", "perturbed Browser")


@st.composite
def mass_fractions(draw) -> dict[str, float]:
    """Table 8's fractions, each scaled by up to 15 %, renormalised to sum to one."""
    raw = {k: f * draw(factor(0.85, 1.15)) for k, f in DEFAULT_MASS_FRACTIONS.items()}
    total = sum(FRACTION_COUNTS[k] * f for k, f in raw.items())
    return {k: f / total for k, f in raw.items()}


@st.composite
def riders(draw) -> RiderMeasurements:
    """The paper's rider with every measurement, the mass and the fractions perturbed."""
    _, base = paper_inputs()
    values = {k: Quantity(q.value * draw(factor(0.92, 1.08))) for k, q in base.values.items() if k in RIDER_LENGTHS}
    values["mBr"] = Quantity(draw(factor(45.0, 120.0)))
    values["lam_fl"] = Quantity(math.radians(draw(factor(65.0, 90.0))))
    return RiderMeasurements(values, draw(mass_fractions()), "<hypothesis rider>", "perturbed rider")


@st.composite
def seated_pairs(draw):
    """``(bicycle, rider, rider_model)``; pairs the project refuses to seat are rejected (a ReachError,
    or a forward lean that puts the shoulders ahead of the hands)."""
    from bikerider.rider.model import seat_rider

    bicycle, rider = draw(bicycles()), draw(riders())
    try:
        model = seat_rider(bicycle, rider)
    except InputError:  # ReachError is one
        reject()
    return bicycle, rider, model


@st.composite
def benchmark_mappings(draw) -> dict[str, float]:
    """Meijaard's benchmark bicycle perturbed within physical ranges (a plain name -> value dict)."""
    v = meijaard_values()
    out = dict(v)
    for key in ("w", "rR", "rF"):
        out[key] = v[key] * draw(factor(0.8, 1.25))
    out["c"] = draw(factor(0.02, 0.15))
    out["lam"] = draw(factor(0.05, 0.5))
    for key in ("mR", "mB", "mH", "mF"):
        out[key] = v[key] * draw(factor(0.5, 1.5))
    for key in ("xB", "zB", "xH", "zH"):
        out[key] = v[key] * draw(factor(0.85, 1.15))
    for wheel in ("R", "F"):
        out[f"I{wheel}yy"], out[f"I{wheel}xx"] = draw(wheel_moments(out[f"m{wheel}"], out[f"r{wheel}"], 1.2))
    for body in ("B", "H"):
        angle, scale, yy = draw(tensor_perturbation())
        xx, zz, xz = rotate_xz(v[f"I{body}xx"], v[f"I{body}zz"], v[f"I{body}xz"], angle, scale)
        out.update(
            {
                f"I{body}xx": xx,
                f"I{body}zz": zz,
                f"I{body}xz": xz,
                f"I{body}yy": yy_between(xx, zz, xz, 0.5 if yy is None else yy),
            }
        )
    return out


@st.composite
def inertia_tensors(draw) -> np.ndarray:
    """A physical 3x3 tensor symmetric about the XZ plane (principal moments obeying the triangle inequality)."""
    a = draw(factor(0.05, 3.0))
    b = a * draw(factor(0.05, 1.0))
    xx, zz, xz = rotate_xz(a, b, 0.0, draw(factor(-math.pi, math.pi)), 1.0)
    yy = yy_between(xx, zz, xz, draw(factor(0.02, 0.98)))
    return np.array([[xx, 0.0, xz], [0.0, yy, 0.0], [xz, 0.0, zz]])


# =============================================================================================
# Hostile input (tests/test_fuzz_*.py): byte-level mutations of valid input files, and the
# contract every reader must keep on them.  A reader either returns values that are all finite
# (or None where a value is documented as not determined), or raises a BikeriderError whose
# message names the file.  Any other exception - a NumPy or Python traceback - breaks it, and so
# does any RuntimeWarning, which pytest turns into an error (filterwarnings = error::RuntimeWarning).
# =============================================================================================

BAD_NUMBERS = (
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e-308",
    "1e400",
    "-1",
    "0",
    "-0.5",
    "1120",
    "1e6",
    "abc",
    "true",
    "",
    "1,2",
    "+/-",
    "1+/-nan",
    "1 +/- 1e308",
    "1+/--1",
    "0x10",
    "1_000",
    "٣",
    "1e",
    "--1",
    "1" * 400,
    "5e-324",
    "1e-320",
    "1e300",
    "0.3665",
    "179",
    "2000",
)
"""Replacements for one number: non-finite, huge, tiny, negative, zero, unit slips, not numbers;
and those of issue 12: an integer of 400 digits (beyond floating point), denormals, a sigma of 1e300
(``"68.5 +/- 1e300"`` once it replaces a sigma), radians under a degree key, an angle of 179 deg, a
sigma a thousand times its value."""

_NUMBER = re.compile(rb"-?\d+\.?\d*(?:[eE][+-]?\d+)?")

MUTATIONS = (
    "number",
    "number",
    "number",
    "truncate",
    "byte",
    "delete_line",
    "duplicate_line",
    "swap_lines",
    "junk_line",
    "not_utf8",
    "long_number",
)
LONG_NUMBER = 1 << 19
"""Digits of the number a ``long_number`` mutation writes: half a megabyte in one cell or value (a
megabyte CSV cell once ended the period command in a traceback), within the text readers' limit."""


@st.composite
def mutated(draw, data: bytes) -> tuple[str, bytes]:
    """``(description, mutated bytes)`` of ``data``: one hostile change."""
    kind = draw(st.sampled_from(MUTATIONS))
    lines = data.split(b"\n")
    if kind in ("number", "long_number"):
        candidates = [i for i, line in enumerate(lines) if _NUMBER.search(line.split(b"#")[0])]
        i = draw(st.sampled_from(candidates))
        code, hash_, comment = lines[i].partition(b"#")
        matches = list(_NUMBER.finditer(code))
        m = matches[draw(st.integers(0, len(matches) - 1))]
        bad = draw(st.sampled_from(BAD_NUMBERS)).encode() if kind == "number" else b"7" * LONG_NUMBER
        lines[i] = code[: m.start()] + bad + code[m.end() :] + hash_ + comment
        return f"line {i + 1}: {m.group().decode()} -> {bad[:40].decode()!r} ({len(bad)} chars)", b"\n".join(lines)
    if kind == "truncate":
        k = draw(st.integers(0, len(data) - 1))
        return f"truncated at byte {k}", data[:k]
    if kind == "byte":
        k = draw(st.integers(0, len(data) - 1))
        b = draw(st.integers(0, 255))
        return f"byte {k} -> {b:#x}", data[:k] + bytes([b]) + data[k + 1 :]
    if kind == "not_utf8":
        k = draw(st.integers(0, len(data)))
        return f"\\xff\\xfe at byte {k}", data[:k] + b"\xff\xfe" + data[k:]
    i = draw(st.integers(0, len(lines) - 1))
    if kind == "delete_line":
        return f"line {i + 1} deleted", b"\n".join(lines[:i] + lines[i + 1 :])
    if kind == "duplicate_line":
        return f"line {i + 1} doubled", b"\n".join(lines[: i + 1] + lines[i:])
    if kind == "swap_lines":
        j = draw(st.integers(0, len(lines) - 1))
        lines[i], lines[j] = lines[j], lines[i]
        return f"lines {i + 1} and {j + 1} swapped", b"\n".join(lines)
    junk = draw(st.text(max_size=40)).encode("utf-8", "surrogatepass")
    return f"junk line {junk!r} before line {i + 1}", b"\n".join(lines[:i] + [junk] + lines[i:])


def finite_numbers(value: object) -> Iterable[float]:
    """Every float (or int) inside nested dicts, lists, tuples and dataclass-like ``values`` maps."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return
    if isinstance(value, (int, float)):
        yield float(value)
    elif isinstance(value, dict):
        for v in value.values():
            yield from finite_numbers(v)
    elif isinstance(value, (list, tuple)):
        for v in value:
            yield from finite_numbers(v)
    elif hasattr(value, "value") and hasattr(value, "sigma"):  # Quantity
        yield float(value.value)
        yield float(value.sigma)
    elif hasattr(value, "tolist"):
        yield from finite_numbers(value.tolist())
    elif isinstance(value, complex):
        yield value.real
        yield value.imag


def assert_all_finite(value: object, what: str) -> None:
    bad = [x for x in finite_numbers(value) if not math.isfinite(x)]
    assert not bad, f"{what}: non-finite numbers {bad[:5]} reached the output"


def assert_names_file(exc: BaseException, *paths: Path) -> None:
    """The message names one of ``paths`` (by its full path as given, or at least its name)."""
    message = str(exc)
    assert any(str(p) in message or p.name in message for p in paths), (
        f"error does not name the file ({', '.join(p.name for p in paths)}): {message}"
    )
    assert "Traceback" not in message


def run_cli(argv: list[str]) -> tuple[int, str, str]:
    """``bikerider.cli.main(argv)`` with stdout and stderr captured; argparse exits become codes."""
    from bikerider.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse: usage errors exit 2, --help and --version exit 0
            code = exc.code if isinstance(exc.code, int) else 2
    return code, out.getvalue(), err.getvalue()


def check_json_output(stdout: str, what: str) -> object:
    """Parse ``--json`` output; every number must be finite (``null`` for what is not determined)."""
    data = json.loads(stdout, parse_constant=lambda name: math.nan)  # NaN/Infinity would be caught below
    assert_all_finite(data, what)
    return data


def signal_csv(period: float = 1.37, decay: float = 0.3, seconds: float = 6.0) -> bytes:
    """A rate-gyro record of a damped oscillation with a little noise, as the period command reads it."""
    t = np.arange(0, seconds, 0.01)
    omega = 2 * np.pi / period
    rate = 0.02 + np.exp(-decay * t) * (1.2 * np.sin(omega * t) + 0.3 * np.cos(omega * t))
    rate += np.random.default_rng(7).normal(0, 0.005, t.size)
    return ("time [s],rate [rad/s]\n" + "".join(f"{a:.3f},{b:.6f}\n" for a, b in zip(t, rate))).encode()
