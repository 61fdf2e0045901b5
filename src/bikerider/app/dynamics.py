"""The computations behind the page's figures, each run once per change of its own inputs.

Every figure of the page comes from one of the functions of :data:`COMPUTATIONS`, each a plain
function of the benchmark parameters (and of the speed or the map it needs).  :class:`Dynamics`
keeps the last results of each, keyed by its inputs: an edit of a parameter runs each
computation once, a new speed runs the Bode diagram alone, and :attr:`Dynamics.calls` counts the
runs (the tests hold the page to it).  Speeds are those of the issue's target: 0 to 10 m/s in steps
of 0.1 m/s (:data:`SPEEDS`).  The eigenvalues come from the package's NumPy functions
(:func:`~bikerider.benchmark.mode_shapes.mode_shapes`, which tracks each mode over speed), the
uncertainty band and the first-order sigmas of the weave and capsize speeds from
:func:`~bikerider.uncertainty.propagate`, and their Monte Carlo sigmas from
:func:`~bikerider.uncertainty.headline.headline_uncertainty` (:data:`MONTE_CARLO_SAMPLES` draws),
which the page asks for apart, once the edits pause, so that the figures follow an edit at once.
"""

from __future__ import annotations

import math
import threading
import time
from collections import Counter, OrderedDict
from collections.abc import Callable

import numpy as np

from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters, WhippleModel
from bikerider.benchmark.closed_loop import closed_loop
from bikerider.benchmark.control import GAIN_NAMES, GAIN_UNITS, MAX_MAGNITUDE
from bikerider.benchmark.frequency_response import frequency_response
from bikerider.benchmark.mode_shapes import ModeShapes, mode_shapes
from bikerider.benchmark.state_space import LateralForce
from bikerider.benchmark.sweep import Sweep, sweep
from bikerider.errors import InputError
from bikerider.plotting.side_view import inertia_ellipse
from bikerider.uncertainty import benchmark_inputs, propagate
from bikerider.uncertainty.headline import headline_uncertainty

SPEEDS = np.round(np.arange(101) * 0.1, 10)
"""Speeds of the eigenvalue figure and the maps [m/s]: 0 to 10 in steps of 0.1."""
MONTE_CARLO_SAMPLES = 2000
"""Seeded draws behind the page's Monte Carlo sigmas of the weave and capsize speeds (``estimate``
draws 10,000; the page says how many)."""
FREQUENCIES = np.logspace(-1, 2, 160)
"""Angular frequencies of the Bode diagram [rad/s]."""
MAP_POINTS = {1: 41, 2: 25}
"""Grid points per axis of a one- and a two-parameter stability map."""
MAP_PARAMETERS = tuple(n for n in BENCHMARK_NAMES if n not in ("IByy", "IHyy", "g"))
"""Parameters a map may vary."""
CACHE_SIZE = 8
"""Results kept per computation (a few recent states: undo and redo are free)."""


def _finite(x) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _list(array: np.ndarray) -> list:
    """A float array as nested lists, non-finite values as None (JSON has no NaN)."""
    return [_finite(x) for x in array] if array.ndim == 1 else [_list(row) for row in array]


def parameters_key(parameters: BenchmarkParameters) -> tuple:
    """The values and sigmas of ``parameters``, hashable: the inputs every computation shares."""
    v, s = parameters.values, parameters.sigmas
    return tuple((n, v[n], float(s.get(n, 0.0) or 0.0)) for n in BENCHMARK_NAMES)


def tracked_modes(parameters: BenchmarkParameters) -> dict:
    """Eigenvalues against :data:`SPEEDS` by tracked mode, the critical speeds and the mode shapes
    at every speed (``|roll|``, ``|steer|``, the steer's phase from the roll)."""
    model = WhippleModel.from_parameters(parameters)
    shapes: ModeShapes = mode_shapes(model, SPEEDS)
    critical = model.critical_speeds()
    return {
        "speeds": SPEEDS.tolist(),
        "names": list(shapes.names),
        "real": _list(shapes.eigenvalues.real),
        "imag": _list(shapes.eigenvalues.imag),
        "roll": _list(shapes.amplitude[..., 0]),
        "steer": _list(shapes.amplitude[..., 1]),
        "steer_phase_deg": _list(np.degrees(shapes.steer_phase)),
        "weave": _finite(critical.weave) if critical.weave is not None else None,
        "capsize": _finite(critical.capsize) if critical.capsize is not None else None,
        "weave_frequency": _finite(critical.weave_frequency) if critical.weave_frequency is not None else None,
        "stable_intervals": [[lo, hi if math.isfinite(hi) else None] for lo, hi in critical.stable_intervals],
    }


def uncertainty(parameters: BenchmarkParameters) -> dict:
    """The one-sigma band of each labelled mode and the sigmas of the weave and capsize speeds,
    first order (at :data:`SPEEDS`)."""
    first_order = propagate(benchmark_inputs(parameters), speeds=SPEEDS)
    band = {}
    e = first_order.eigenvalues
    if e is not None:
        s = e.sensitivity
        values, labels = np.asarray(s.values), np.asarray(s.labels)
        for name in ("weave", "capsize", "castor"):
            mine = (labels == name) & ((values.imag >= 0) if name == "weave" else True)
            index = np.argmax(mine, axis=1)  # one value per speed (weave: the upper one)
            has = mine.any(axis=1)
            rows = np.arange(len(SPEEDS))
            band[name] = {
                "present": has.tolist(),
                "real": _list(np.where(has, values[rows, index].real, np.nan)),
                "imag": _list(np.where(has, np.abs(values[rows, index].imag), np.nan)),
                "sigma_real": _list(np.where(has, e.sigma_real[rows, index], np.nan)),
                "sigma_imag": _list(np.where(has, e.sigma_imag[rows, index], np.nan)),
            }
    speeds = {name: (None if sigma is None else _finite(sigma)) for name, sigma in first_order.speeds.items()}
    return {"band": band, "speeds": speeds, "notes": list(first_order.notes)}


def monte_carlo(parameters: BenchmarkParameters) -> dict:
    """The sigmas of the weave and capsize speeds from :data:`MONTE_CARLO_SAMPLES` seeded draws
    (:func:`~bikerider.uncertainty.headline.headline_uncertainty`: half the central 68 % of the
    samples, the interval, and the first order beside)."""
    inputs = benchmark_inputs(parameters)
    headline = headline_uncertainty(inputs, propagate(inputs), samples=MONTE_CARLO_SAMPLES, seed=0)
    speeds = {}
    for name, sigma in headline.speeds.items():
        speeds[name] = {
            "monte_carlo": _finite(sigma.monte_carlo) if sigma.monte_carlo is not None else None,
            "first_order": _finite(sigma.first_order) if sigma.first_order is not None else None,
            "interval": [_finite(x) for x in sigma.interval] if sigma.interval is not None else None,
            "valid": sigma.valid,
        }
    return {"speeds": speeds, "samples": headline.samples, "notes": list(headline.notes)}


def side_view(parameters: BenchmarkParameters) -> dict:
    """What the side view draws, in (x forward, height up) [m]: wheels, the steer axis, the centres
    of mass of R, B, H, F and the whole bicycle, and the inertia ellipses of B and H
    (:func:`bikerider.plotting.side_view.inertia_ellipse`)."""
    p = {k: v for k, v in parameters.values.items()}
    w, c, lam, rR, rF = (float(p[k]) for k in ("w", "c", "lam", "rR", "rF"))  # type: ignore[arg-type]
    bodies = {
        "R": (float(p["mR"]), 0.0, rR),  # type: ignore[arg-type]
        "B": (float(p["mB"]), float(p["xB"]), -float(p["zB"])),  # type: ignore[arg-type]
        "H": (float(p["mH"]), float(p["xH"]), -float(p["zH"])),  # type: ignore[arg-type]
        "F": (float(p["mF"]), w, rF),  # type: ignore[arg-type]
    }
    mass = sum(m for m, _, _ in bodies.values())
    total = (mass, sum(m * x for m, x, _ in bodies.values()) / mass, sum(m * y for m, _, y in bodies.values()) / mass)
    ellipses = {}
    for body in ("B", "H"):
        yy = p[f"I{body}yy"]
        a, b, angle = inertia_ellipse(
            float(p[f"m{body}"]),  # type: ignore[arg-type]
            float(p[f"I{body}xx"]),  # type: ignore[arg-type]
            float(p[f"I{body}zz"]),  # type: ignore[arg-type]
            float(p[f"I{body}xz"]),  # type: ignore[arg-type]
            None if yy is None else float(yy),
        )
        ellipses[body] = {"a": a, "b": b, "angle": angle}
    return {
        "w": w,
        "c": c,
        "lam": lam,
        "rR": rR,
        "rF": rF,
        "bodies": {k: {"mass": m, "x": x, "y": y} for k, (m, x, y) in {**bodies, "T": total}.items()},
        "ellipses": ellipses,
    }


def bode(parameters: BenchmarkParameters, speed: float) -> dict:
    """Steer torque to roll and steer angle at ``speed``: magnitude [dB] and phase [deg]."""
    model = WhippleModel.from_parameters(parameters)
    response = frequency_response(model, [speed], FREQUENCIES, inputs=("T_delta",), outputs=("phi", "delta"))
    out = {"speed": speed, "frequencies": FREQUENCIES.tolist()}
    for output in ("phi", "delta"):
        out[output] = {
            "magnitude_db": _list(response.magnitude_db(output, "T_delta")[0]),
            "phase_deg": _list(response.phase_deg(output, "T_delta")[0]),
        }
    return out


def check_map(spec: dict, parameters: BenchmarkParameters) -> tuple[tuple[str, float, float], ...]:
    """The map's axes ``((name, low, high), ...)`` from the page's ``spec`` (``x``, ``x_range``,
    optional ``y``, ``y_range``); a missing range is half to one and a half times the value.

    Raises
    ------
    InputError
        An unknown parameter, the same one twice, or a range that is not two finite numbers, low < high.
    """
    axes = []
    for axis in ("x", "y"):
        name = spec.get(axis)
        if name in (None, ""):
            if axis == "x":
                raise InputError("map x", name, f"one of {', '.join(MAP_PARAMETERS)}", "the stability map")
            continue
        if name not in MAP_PARAMETERS:
            raise InputError(f"map {axis}", name, f"one of {', '.join(MAP_PARAMETERS)}", "the stability map")
        value = float(parameters.values[name])  # type: ignore[arg-type]
        default = sorted((0.5 * value, 1.5 * value)) if value != 0 else [-0.1, 0.1]
        raw = spec.get(f"{axis}_range") or default
        try:
            low, high = (float(x) for x in raw)
        except (TypeError, ValueError):
            raise InputError(f"map {axis} range", raw, "two numbers LOW, HIGH", "the stability map") from None
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise InputError(
                f"map {axis} range", [low, high], "two finite numbers with LOW < HIGH", "the stability map"
            )
        axes.append((name, low, high))
    if len(axes) == 2 and axes[0][0] == axes[1][0]:
        raise InputError("map y", axes[1][0], "a parameter other than the map's x", "the stability map")
    return tuple(axes)


def map_sweep(parameters: BenchmarkParameters, axes: tuple[tuple[str, float, float], ...]) -> Sweep:
    """:func:`bikerider.benchmark.sweep.sweep` over the map's axes, stability at :data:`SPEEDS`."""
    n = MAP_POINTS[len(axes)]
    return sweep(parameters, {name: np.linspace(lo, hi, n) for name, lo, hi in axes}, SPEEDS, eigenvalues=False)


def stability_map(parameters: BenchmarkParameters, axes: tuple[tuple[str, float, float], ...]) -> dict:
    """Self-stable speed intervals over one parameter, or the first interval's ends over two."""
    result = map_sweep(parameters, axes)
    s = result.stability
    out = {
        "names": list(result.names),
        "values": [v.tolist() for v in result.values],
        "base": [float(parameters.values[n]) for n in result.names],  # type: ignore[arg-type]
        "valid": result.valid.tolist(),
        "reasons": [str(r) for r in np.asarray(result.reasons).ravel() if str(r)][:5],
    }
    if len(axes) == 1:
        out["lower"] = _list(s.lower)
        out["upper"] = [[None if np.isinf(x) else _finite(x) for x in row] for row in s.upper]
        out["upper_infinite"] = np.isinf(s.upper).tolist()
    else:
        out["lower"] = _list(s.lower[..., 0])
        out["upper"] = [[None if np.isinf(x) else _finite(x) for x in row] for row in s.upper[..., 0]]
    return out


def check_gains(raw: dict) -> tuple[float, ...]:
    """The closed loop's constant gains ``(k_phi, k_phid, k_delta, k_deltad)`` from the page.

    Raises
    ------
    InputError
        A gain that is not a finite number of magnitude at most 10^6 (as control files).
    """
    out = []
    for name in GAIN_NAMES:
        value = raw.get(name, 0.0)
        try:
            number = float(value if value not in (None, "") else 0.0)
        except (TypeError, ValueError):
            number = math.nan
        if not (math.isfinite(number) and abs(number) <= MAX_MAGNITUDE):
            raise InputError(
                name,
                value,
                f"a finite gain [{GAIN_UNITS[name]}] of magnitude at most {MAX_MAGNITUDE:g}",
                "the closed loop",
            )
        out.append(number)
    return tuple(out)


def closed_loop_modes(parameters: BenchmarkParameters, gains: tuple[float, ...]) -> dict:
    """Eigenvalues against :data:`SPEEDS` under the steer torque ``T = k_phi phi + k_phid phi' +
    k_delta delta + k_deltad delta'`` (:func:`bikerider.benchmark.closed_loop.closed_loop`), labelled
    as the open loop's where the closed loop keeps that structure, and its stable intervals."""
    loop = closed_loop(WhippleModel.from_parameters(parameters), dict(zip(GAIN_NAMES, gains)))
    modal = loop.eigenvalues(SPEEDS)
    critical = loop.critical_speeds()
    return {
        "gains": dict(zip(GAIN_NAMES, gains)),
        "speeds": SPEEDS.tolist(),
        "labels": modal.labels.tolist(),
        "real": _list(modal.values.real),
        "imag": _list(modal.values.imag),
        "weave": critical.weave,
        "capsize": critical.capsize,
        "stable_intervals": [[lo, hi if math.isfinite(hi) else None] for lo, hi in critical.stable_intervals],
    }


COMPUTATIONS: dict[str, Callable] = {
    "eigenvalues": tracked_modes,
    "uncertainty": uncertainty,
    "side_view": side_view,
    "bode": bode,
    "map": stability_map,
    "closed_loop": closed_loop_modes,
    "monte_carlo": monte_carlo,
}
"""The computations, by the name of the figure they feed."""


class Dynamics:
    """The results of :data:`COMPUTATIONS` for the latest inputs (thread-safe; see the module docstring)."""

    def __init__(self) -> None:
        self.calls: Counter[str] = Counter()
        self._cache: dict[str, OrderedDict] = {name: OrderedDict() for name in COMPUTATIONS}
        self._locks = {name: threading.Lock() for name in COMPUTATIONS}  # one run of each at a time

    def result(self, name: str, parameters: BenchmarkParameters, *extra) -> tuple[dict, float]:
        """The result of computation ``name`` and the seconds it took (0 when kept from before)."""
        key = (parameters_key(parameters), *extra)
        with self._locks[name]:
            cache = self._cache[name]
            if key in cache:
                cache.move_to_end(key)
                return cache[key], 0.0
            start = time.perf_counter()
            value = COMPUTATIONS[name](parameters, *extra)
            self.calls[name] += 1
            cache[key] = value
            if len(cache) > CACHE_SIZE:
                cache.popitem(last=False)
            return value, time.perf_counter() - start

    def all(self, parameters: BenchmarkParameters, speed: float, axes, gains=None) -> tuple[dict, dict]:
        """Every figure's data for one state of the page (no map without ``axes``, no closed loop
        without ``gains``), and the milliseconds each took.  The Monte Carlo sigmas of the speeds
        are not among them: the page asks for them once the edits pause (``monte_carlo``), and
        shows the first-order sigmas meanwhile."""
        out, timing = {}, {}
        for name, extra in (
            ("eigenvalues", ()),
            ("uncertainty", ()),
            ("side_view", ()),
            ("bode", (speed,)),
            ("map", (axes,)),
            ("closed_loop", (gains,)),
        ):
            if extra == (None,):
                out[name] = None
                continue
            out[name], seconds = self.result(name, parameters, *extra)
            timing[name] = round(1000 * seconds, 2)
        return out, timing


def lateral_force(parameters: BenchmarkParameters) -> LateralForce:
    """The lateral force of the figures' Bode diagram: at the rear body's centre of mass (as ``--plot``)."""
    return LateralForce(parameters.values["xB"], parameters.values["zB"])  # type: ignore[arg-type]


__all__ = [
    "COMPUTATIONS",
    "Dynamics",
    "MAP_PARAMETERS",
    "MONTE_CARLO_SAMPLES",
    "SPEEDS",
    "bode",
    "check_gains",
    "check_map",
    "closed_loop_modes",
    "map_sweep",
    "monte_carlo",
    "side_view",
    "stability_map",
    "tracked_modes",
    "uncertainty",
]
