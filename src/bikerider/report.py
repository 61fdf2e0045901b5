"""Text and JSON renderings of model results, shared by the ``estimate`` and ``benchmark`` commands."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters, ModalEigenvalues, WhippleModel
from bikerider.benchmark.mode_labels import MODES
from bikerider.errors import InputError
from bikerider.generated.manifest import MATRIX_NAMES
from bikerider.quantity import SPEED_OF_LIGHT
from bikerider.uncertainty import UncertaintyResult
from bikerider.uncertainty.headline import HeadlineUncertainty, Sigma


def parse_speeds(text: str, option: str = "--speeds") -> np.ndarray:
    """``START:STOP:N`` (inclusive, N points) to an array of speeds in m/s (``option`` names it in errors)."""
    parts = text.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        start, stop, n = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise InputError(option, text, "START:STOP:N, e.g. 0:10:101 (m/s, N points)") from None
    if not (0 <= start <= stop < SPEED_OF_LIGHT) or not 1 <= n <= 1_000_000:
        raise InputError(
            option, text, "0 <= START <= STOP < 2.998e8 (m/s, below the speed of light) and 1 <= N <= 1000000"
        )
    return np.linspace(start, stop, n)


def model_json(parameters: BenchmarkParameters, model: WhippleModel, eig: ModalEigenvalues) -> dict[str, Any]:
    """The ``benchmark``, ``matrices``, ``speeds`` and ``eigenvalues`` keys of ``--json``."""
    speeds = model.critical_speeds()
    return {
        "benchmark": parameters.as_dict(),
        "matrices": {name: getattr(model, name).tolist() for name in MATRIX_NAMES},
        "speeds": {
            "weave": speeds.weave,
            "capsize": speeds.capsize,
            "stable_intervals": [[lo, hi if math.isfinite(hi) else None] for lo, hi in speeds.stable_intervals],
        },
        "eigenvalues": {
            "speeds": eig.speeds.tolist(),
            "modes": list(MODES),
            "values": [[[float(z.real), float(z.imag)] for z in row] for row in eig.values],
            "labels": eig.labels.tolist(),
        },
    }


def _matrix_text(name: str, m: np.ndarray) -> list[str]:
    return [f"  {name:3s} = [[{m[0, 0]:12.6f} {m[0, 1]:12.6f}]", f"         [{m[1, 0]:12.6f} {m[1, 1]:12.6f}]]"]


def reported_sigmas(first_order: UncertaintyResult, headline: HeadlineUncertainty) -> dict[str, float | None]:
    """The sigma of each benchmark parameter a report shows: first order where it holds (exact for
    the parameters that are inputs, free of sampling noise), Monte Carlo where it does not."""
    out = {}
    for name, sigma in first_order.benchmark.items():
        sampled = headline.sigmas.get(name)
        out[name] = sampled.monte_carlo if sampled is not None and not sampled.first_order_holds else sigma
    return {k: v for k, v in out.items() if v is not None}


def uncertainty_json(first_order: UncertaintyResult, headline: HeadlineUncertainty) -> dict[str, Any]:
    """The ``uncertainty`` object of ``--json``: the sigmas reported (Monte Carlo for the speeds),
    first order beside them, the Monte Carlo draw, and the eigenvalues' first-order sigmas."""
    sampled = headline.speeds
    out: dict[str, Any] = {
        "method": (
            f"speeds: Monte Carlo ({headline.samples} samples, seed {headline.seed}) with first order beside; "
            "benchmark values: first order where it holds, else Monte Carlo; eigenvalues: first order"
            if headline.samples
            else "first-order propagation of the uncertainties stated in the input files"
        ),
        "benchmark": {**first_order.benchmark, **reported_sigmas(first_order, headline)},
        "speeds": {key: sampled[key].headline if key in sampled else None for key in first_order.speeds},
        "first_order": {"benchmark": first_order.benchmark, "speeds": first_order.speeds},
        "monte_carlo": headline.as_dict() if headline.samples else None,
        "eigenvalues": first_order.eigenvalues.as_list() if first_order.eigenvalues is not None else [],
    }
    return out


def model_text(
    parameters: BenchmarkParameters,
    model: WhippleModel,
    eig: ModalEigenvalues,
    speed_sigmas: Mapping[str, Sigma | float | None] | None = None,
    samples: int = 0,
) -> str:
    """Readable text: parameters (with sigmas), matrices, critical speeds, eigenvalue table.

    ``speed_sigmas`` holds, for ``weave`` and ``capsize``, a first-order sigma or a
    :class:`~bikerider.uncertainty.headline.Sigma` (Monte Carlo from ``samples`` draws, with first
    order beside it)."""
    lines = ["Benchmark parameters (Meijaard et al. 2007, Table 1 names; SI units)"]
    for name in BENCHMARK_NAMES:
        value, sigma = parameters.values[name], parameters.sigmas.get(name, 0.0)
        shown = "not determined" if value is None else (f"{value:.6g}" + (f" +/- {sigma:.2g}" if sigma else ""))
        lines.append(f"  {name:5s} {shown}")
    lines.append("")
    lines.append("Canonical matrices: M q'' + v C1 q' + (g K0 + v^2 K2) q = f, q = [roll, steer]")
    for name in MATRIX_NAMES:
        lines.extend(_matrix_text(name, getattr(model, name)))
    speeds = model.critical_speeds()
    lines.append("")
    sig = speed_sigmas or {}
    lines.append(f"Weave speed   {_speed(speeds.weave, sig.get('weave'), samples)}")
    lines.append(f"Capsize speed {_speed(speeds.capsize, sig.get('capsize'), samples)}")
    if speeds.stable_intervals:
        shown = [
            f"from {lo:.4f} to {hi:.4f} m/s" if math.isfinite(hi) else f"above {lo:.4f} m/s"
            for lo, hi in speeds.stable_intervals
        ]
        lines.append("Self-stable " + ", and ".join(shown))
    else:
        lines.append("No self-stable speed range")
    lines.append("")
    lines.append("Eigenvalues [1/s] against speed")
    lines.append(f"  {'v [m/s]':>8s} {'weave':>26s} {'capsize':>12s} {'castor':>12s}")
    for v, row, labels in zip(eig.speeds, eig.values, eig.labels):
        weave = (
            f"{row[0].real:.4f} +/- {abs(row[0].imag):.4f}i" if row[0].imag else f"{row[0].real:.4f}, {row[1].real:.4f}"
        )
        if labels[2] == "other":  # capsize and castor have met, or a second complex pair
            lines.append(f"  {v:8.3f} {weave:>26s}   other pair {row[2].real:.4f} +/- {abs(row[2].imag):.4f}i")
            continue
        lines.append(f"  {v:8.3f} {weave:>26s} {row[2].real:12.4f} {row[3].real:12.4f}")
    return "\n".join(lines)


def _speed(v: float | None, sigma: Sigma | float | None = None, samples: int = 0) -> str:
    if v is None:
        return "none at positive speed"
    if isinstance(sigma, Sigma):
        if sigma.monte_carlo is None:
            return _speed(v, sigma.first_order)
        if sigma.monte_carlo == 0 and not sigma.first_order:
            return f"{v:.4f} m/s"
        if sigma.first_order is None:
            fo = "first order: not defined here"
        else:
            fo = f"first order +/- {_digits(sigma.first_order)}" + (
                "" if sigma.first_order_holds else ", which does not hold"
            )
        low, high = sigma.interval or (math.nan, math.nan)
        return (
            f"{v:.4f} +/- {_digits(sigma.monte_carlo)} m/s (Monte Carlo, {samples} samples: 68 % within "
            f"{low:.2f}-{high:.2f}; {fo})"
        )
    return f"{v:.4f} +/- {_digits(sigma)} m/s (first order)" if sigma else f"{v:.4f} m/s"


def _digits(x: float) -> str:
    """Two significant digits, trailing zeros kept: 0.60, 1.5, 23, 2.6e+02."""
    return format(x, "#.2g").rstrip(".")
