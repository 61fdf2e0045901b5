"""What ``bikerider sweep`` and its design-space runs share: ``--vary`` ranges and CSV cells."""

from __future__ import annotations

import math

from bikerider.errors import InputError


def parse_vary(text: str):
    """``NAME=START:STOP:N`` to ``(name, values)`` in SI units (``NAME_deg``: degrees to radians)."""
    import numpy as np  # heavy: imported when a command runs (cli.py)

    name, _, span = text.partition("=")
    parts = span.split(":")
    try:
        if not name or len(parts) != 3:
            raise ValueError
        start, stop, n = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise InputError("--vary", text, "NAME=START:STOP:N, e.g. c=0.02:0.12:51 (N values, SI units)") from None
    if not (math.isfinite(start) and math.isfinite(stop)) or not 1 <= n <= 100_000 or stop < start:
        raise InputError("--vary", text, "a finite range START <= STOP and 1 <= N <= 100000 values")
    values = np.linspace(start, stop, n)
    if name.endswith("_deg"):
        name, values = name[: -len("_deg")], np.radians(values)
    return name.strip(), values


def cell(value) -> str:
    """CSV text of a value: floats to 10 significant digits, None empty, infinity ``inf``."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:.10g}"
    return str(value)


__all__ = ["cell", "parse_vary"]
