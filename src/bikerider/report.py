"""Text and JSON renderings of model results, shared by the ``estimate`` and ``benchmark`` commands."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters, ModalEigenvalues, WhippleModel
from bikerider.benchmark.mode_labels import MODES
from bikerider.errors import InputError
from bikerider.generated.manifest import MATRIX_NAMES


def parse_speeds(text: str) -> np.ndarray:
    """``START:STOP:N`` (inclusive, N points) to an array of speeds in m/s."""
    parts = text.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        start, stop, n = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise InputError("--speeds", text, "START:STOP:N, e.g. 0:10:101 (m/s, N points)") from None
    if not (math.isfinite(start) and math.isfinite(stop)) or n < 1 or n > 1_000_000 or start < 0 or stop < start:
        raise InputError("--speeds", text, "0 <= START <= STOP (finite, m/s) and 1 <= N <= 1000000")
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


def model_text(
    parameters: BenchmarkParameters,
    model: WhippleModel,
    eig: ModalEigenvalues,
    speed_sigmas: dict[str, float | None] | None = None,
) -> str:
    """Readable text: parameters (with sigmas), matrices, critical speeds, eigenvalue table."""
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
    lines.append(f"Weave speed   {_speed(speeds.weave, sig.get('weave'))}")
    lines.append(f"Capsize speed {_speed(speeds.capsize, sig.get('capsize'))}")
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


def _speed(v: float | None, sigma: float | None = None) -> str:
    if v is None:
        return "none at positive speed"
    return f"{v:.4f} +/- {sigma:.2g} m/s (first order)" if sigma else f"{v:.4f} m/s"
