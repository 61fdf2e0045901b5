"""Evaluate a range of designs: validity, stable intervals, critical speeds, stability and weave.

One call evaluates designs ``start .. stop - 1`` of a :class:`~bikerider.design.space.DesignSpace`
and returns plain arrays (:data:`FIELDS`), the same whichever engine computes them:

``"compiled"``
    the fused C kernels of ``generated/design_kernels.py`` (:mod:`bikerider.design.compiled`),
    every core;
``"numpy"``
    the generated NumPy functions (``canonical_matrices``, ``critical_speed_polynomials``,
    ``characteristic_coefficients``) with :func:`bikerider.benchmark.stability.stability_batch` and
    the closed-form quartic of :mod:`bikerider.benchmark.quartic`: the reference;
``"auto"``
    compiled where a C compiler is found, else NumPy (with a warning).

Designs over raw measurements go through the estimate chain's generated stages first
(:func:`bikerider.uncertainty.chain.benchmark_values`, a whole chunk at once).  A design no bicycle can have keeps its place with
``valid = False``, a reason code (:mod:`bikerider.design.validity`) and NaN results: a run never
stops on one.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from bikerider.benchmark.mode_labels import label_modes
from bikerider.benchmark.model import matrix_entries
from bikerider.benchmark.parameters import BENCHMARK_NAMES, OPTIONAL_NAMES
from bikerider.benchmark.quartic import quartic_roots
from bikerider.benchmark.stability import stability_batch
from bikerider.design import compiled, validity
from bikerider.design.space import DesignSpace
from bikerider.engine import arguments
from bikerider.errors import InputError
from bikerider.generated import benchmark_model as gen
from bikerider.generated import rider_model
from bikerider.rider.model import STRAIGHT_LIMB_TOLERANCE
from bikerider.uncertainty.chain import benchmark_values

LOG = logging.getLogger(__name__)

ENGINES = ("auto", "compiled", "numpy")
NUMPY_CHUNK = 8192
"""Designs the NumPy engine evaluates at once: its temporaries (about 2 KB a design) stay in cache."""


@dataclass(frozen=True)
class Field:
    """One output of every design: its dtype and the shape of one design's value."""

    name: str
    dtype: str
    width: str = ""
    """``""``: one value; ``"3"``: one per stable interval; ``"speeds"``: one per weave speed;
    ``"bits"``: the packed stability bits of the map speeds."""
    doc: str = ""


FIELDS = (
    Field("valid", "bool", "", "whether a bicycle can have the design"),
    Field("reason", "int16", "", "why not: a code of bikerider.design.validity.REASONS (0: valid)"),
    Field("lower", "float64", "3", "lower ends of the stable speed intervals [m/s], NaN-padded"),
    Field("upper", "float64", "3", "upper ends [m/s] (inf: stable at every higher speed)"),
    Field("lower_kind", "int8", "3", "crossing at each lower end: 1 real, 2 oscillatory, 0 none"),
    Field("upper_kind", "int8", "3", "crossing at each upper end"),
    Field("weave_speed", "float64", "", "weave speed [m/s] (NaN: none)"),
    Field("capsize_speed", "float64", "", "capsize speed [m/s] (NaN: none)"),
    Field("weave_frequency", "float64", "", "angular frequency of the weave pair at the weave speed [rad/s]"),
    Field("stable", "uint8", "bits", "self-stable at each map speed, packed (bit k % 8 of byte k // 8)"),
    Field(
        "weave_frequency_at",
        "float64",
        "speeds",
        "imaginary part of the weave eigenvalue at each weave speed [rad/s] (0: the weave pair is real there)",
    ),
    Field(
        "weave_damping_at",
        "float64",
        "speeds",
        "damping ratio -Re/|lambda| of the weave eigenvalue at each weave speed (negative: unstable)",
    ),
)
"""Every output of a design, in the store's order."""
_FIELD_NAMES = {"weave": "weave_speed", "capsize": "capsize_speed", "stable_bits": "stable"}
"""The fields of the stability kernel's outputs whose names differ (the others keep theirs)."""


def resolve_engine(engine: str) -> str:
    """``"compiled"`` or ``"numpy"`` for a requested engine."""
    if engine not in ENGINES:
        raise InputError("--engine", engine, f"one of {', '.join(ENGINES)}")
    if engine != "auto":
        return engine
    return "compiled" if compiled.available() else "numpy"


# -- kernels ------------------------------------------------------------------------------------
def numpy_stability(arguments: dict[str, np.ndarray], n: int, speeds=()) -> dict[str, np.ndarray]:
    """The reference for :func:`bikerider.design.compiled.stability`, from the generated NumPy
    functions and ``stability_batch``, in chunks of :data:`NUMPY_CHUNK` designs."""
    v = np.asarray(speeds, dtype=float).reshape(-1)
    out = compiled.stability_outputs(n, v.size)
    names = [k for k in arguments if k != "g"]
    for start in range(0, n, NUMPY_CHUNK):
        stop = min(n, start + NUMPY_CHUNK)
        part = {k: _part(arguments[k], start, stop) for k in names}
        M, C1, K0, K2 = gen.canonical_matrices(**part)
        M = np.broadcast_to(M, (stop - start, 2, 2))
        det = M[:, 0, 0] * M[:, 1, 1] - M[:, 0, 1] * M[:, 1, 0]
        out["mass_ok"][start:stop] = (M[:, 0, 0] > 0) & (det > 1e-12 * np.abs(M).max(axis=(-2, -1)) ** 2)
        result = stability_batch(matrix_entries(M, C1, K0, K2), _part(arguments["g"], start, stop))
        for key, array in (
            ("lower", result.lower),
            ("upper", result.upper),
            ("lower_kind", result.lower_kind),
            ("upper_kind", result.upper_kind),
            ("weave", result.weave),
            ("capsize", result.capsize),
            ("weave_frequency", result.weave_frequency),
        ):
            out[key][start:stop] = array
        if v.size:
            out["stable_bits"][start:stop] = np.packbits(result.is_stable(v), axis=-1, bitorder="little")
    return {**out, "mass_ok": out["mass_ok"].astype(bool)}


def numpy_weave(arguments: dict[str, np.ndarray], n: int, speeds) -> np.ndarray:
    """The reference for :func:`bikerider.design.compiled.weave_eigenvalues`: generated
    characteristic coefficients, closed-form quartic, mode labels (``WhippleModel.eigenvalues``)."""
    v = np.asarray(speeds, dtype=float).reshape(-1)
    out = np.empty((n, v.size), dtype=complex)
    names = [k for k in arguments if k != "g"]
    step = max(1, NUMPY_CHUNK // max(1, v.size))
    for start in range(0, n, step):
        stop = min(n, start + step)
        mats = gen.canonical_matrices(**{k: _part(arguments[k], start, stop) for k in names})
        entries = {k: np.broadcast_to(x, (stop - start,))[:, None] for k, x in matrix_entries(*mats).items()}
        g = np.asarray(_part(arguments["g"], start, stop))
        coefficients = gen.characteristic_coefficients(**entries, g=g[..., None] if g.ndim else g, v=v)
        values, _ = label_modes(quartic_roots(coefficients).reshape(-1, 4))
        out[start:stop] = values[:, 0].reshape(stop - start, v.size)
    return out


def _part(array, start: int, stop: int):
    array = np.asarray(array, dtype=float)
    return array if array.ndim == 0 else array[start:stop]


# -- one range of designs ---------------------------------------------------------------------------
def _benchmark_values(space: DesignSpace, inputs: dict[str, np.ndarray], n: int) -> tuple[dict, np.ndarray]:
    """The benchmark values of every design and the reason codes of the measurement checks."""
    codes = np.zeros(n, dtype=np.int16)
    if space.kind == "benchmark":
        return inputs, codes
    varied = set(space.names)
    validity.measurement_reasons(codes, {k: inputs[k] for k in varied})
    with np.errstate(invalid="ignore", divide="ignore"):
        reach = rider_model.limb_reach(**{k: inputs[k] for k in arguments("rider_model.limb_reach")})
        validity.rider_reasons(codes, np.broadcast_to(reach, (n, 4)), inputs, STRAIGHT_LIMB_TOLERANCE)
        values = benchmark_values(inputs)
    bench = {name: np.broadcast_to(values[name], (n,)) for name in BENCHMARK_NAMES}
    required = [k for k in BENCHMARK_NAMES if k not in OPTIONAL_NAMES]
    missing = ~np.all(np.isfinite(np.stack([bench[k] for k in required], axis=-1)), axis=-1)
    np.copyto(codes, validity.NOT_COMPUTED, where=missing & (codes == 0))
    return bench, codes


def evaluate(
    space: DesignSpace,
    start: int,
    stop: int,
    speeds=(),
    weave_speeds=(),
    engine: str = "auto",
    threads: int | None = None,
) -> dict[str, np.ndarray]:
    """Every output of :data:`FIELDS` for designs ``start .. stop - 1`` of ``space``.

    Parameters
    ----------
    speeds : array_like
        Ascending speeds [m/s] of the stability map (``stable`` bits).
    weave_speeds : array_like
        Speeds [m/s] at which the weave frequency and damping ratio are reported.
    engine : {"auto", "compiled", "numpy"}
    threads : int, optional
        Threads of the compiled engine (default: every core this process may use).

    Returns
    -------
    dict of str to numpy.ndarray
        One array per field, first dimension ``stop - start``; for a random space also the drawn
        values of each varied parameter.
    """
    engine = resolve_engine(engine)
    n = stop - start
    inputs = space.inputs(start, stop)
    bench, codes = _benchmark_values(space, inputs, n)
    sigmas = {k: (0.0 if k in space.names else s) for k, s in space.sigmas.items()}  # a value set exactly has none
    codes_bench = validity.benchmark_reasons(bench, sigmas)
    np.copyto(codes, np.broadcast_to(codes_bench, (n,)), where=codes == 0)
    valid = codes == 0
    arguments = _kernel_arguments(space, bench, valid)
    v = np.asarray(speeds, dtype=float).reshape(-1)
    if engine == "compiled":
        result = compiled.stability(arguments, n, v, threads)
    else:
        result = numpy_stability(arguments, n, v)
    validity.mass_matrix_reasons(codes, result["mass_ok"])
    valid = codes == 0
    invalid = ~valid
    out = {"valid": valid, "reason": codes}
    for key, array in result.items():  # the kernel's outputs (manifest.KERNELS), as the store's fields
        if key == "mass_ok":
            continue
        array[invalid] = np.nan if array.dtype.kind == "f" else 0  # results of the base design stood in for them
        out[_FIELD_NAMES.get(key, key)] = array
    w = np.asarray(weave_speeds, dtype=float).reshape(-1)
    if w.size:
        if engine == "compiled":
            eig = compiled.weave_eigenvalues(arguments, n, w, threads)
        else:
            eig = numpy_weave(arguments, n, w)
        with np.errstate(invalid="ignore", divide="ignore"):
            damping = -eig.real / np.abs(eig)
        frequency = eig.imag.copy()
        frequency[invalid] = damping[invalid] = np.nan
        out["weave_frequency_at"], out["weave_damping_at"] = frequency, damping
    else:
        out["weave_frequency_at"] = out["weave_damping_at"] = np.empty((n, 0))
    if not space.is_grid:
        for name, values in space.values(start, stop).items():
            out[f"value:{name}"] = values
    return out


def _kernel_arguments(space: DesignSpace, bench: dict[str, np.ndarray], valid: np.ndarray) -> dict[str, np.ndarray]:
    """The kernels' inputs; an invalid design is replaced by the base (its results are masked)."""
    base = base_benchmark_values(space)
    out = {}
    for name in compiled.ARGUMENTS:
        value = np.asarray(bench[name], dtype=float)
        if value.ndim:
            value = np.where(valid, value, base[name])
        out[name] = value
    return out


def base_benchmark_values(space: DesignSpace) -> dict[str, float]:
    """The benchmark values of the base design."""
    if space.kind == "benchmark":
        return dict(space.base)
    with np.errstate(invalid="ignore"):
        values = benchmark_values({k: float(v) for k, v in space.base.items()})
    return {name: float(values[name]) for name in BENCHMARK_NAMES}


__all__ = ["ENGINES", "FIELDS", "Field", "evaluate", "numpy_stability", "numpy_weave", "resolve_engine"]
