"""What ``bikerider sweep`` and its design-space runs share: ``--vary`` ranges and CSV cells."""

from __future__ import annotations

import math

from bikerider.errors import InputError

ANGLES = ("lam", "lam_ht", "lam_st", "lam_fl")
"""The angles a sweep varies (benchmark ``lam``, measured tube and lean angles): the only names
``--vary NAME_deg=...`` may give in degrees."""


def angle_name(name: str, text: str) -> str:
    """The angle a ``NAME_deg`` of ``--vary`` names; an error for ``_deg`` on a length, a mass, ...

    Parameters
    ----------
    name : str
        The name as given, ending in ``_deg``.
    text : str
        The whole ``--vary`` value (for the message).
    """
    angle = name.strip()[: -len("_deg")]
    if angle not in ANGLES:
        raise InputError(
            "--vary",
            text,
            f"_deg only on an angle ({', '.join(a + '_deg' for a in ANGLES)}); {angle} is not one: give it in SI units",
        )
    return angle


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
    if name.strip().endswith("_deg"):
        name, values = angle_name(name, text), np.radians(values)
    return name.strip(), values


def degree_names(texts) -> frozenset[str]:
    """The parameters a list of ``--vary`` texts gives in degrees (``lam`` for ``lam_deg=...``)."""
    out = set()
    for text in texts or ():
        name = text.partition("=")[0].strip()
        if name.endswith("_deg"):
            out.add(name[: -len("_deg")].strip())
    return frozenset(out)


def in_degrees(row: dict, degrees: frozenset[str]) -> dict:
    """``row`` with each value named in ``degrees`` shown as ``<name>_deg`` in degrees, in place of
    the radians (degrees in, degrees out), keeping the column order."""
    if not degrees:
        return row
    return {
        (f"{k}_deg" if k in degrees else k): (to_degrees(v) if k in degrees and isinstance(v, float) else v)
        for k, v in row.items()
    }


def to_degrees(radians: float) -> float:
    """Radians to degrees, rounded to 12 significant digits: the degrees a user gave come back as
    given (30, not the 29.999999999999996 of the round trip through radians)."""
    return float(f"{math.degrees(radians):.12g}")


def cell(value) -> str:
    """CSV text of a value: floats to 10 significant digits, None empty, infinity ``inf``."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:.10g}"
    return str(value)


__all__ = ["ANGLES", "angle_name", "cell", "degree_names", "in_degrees", "parse_vary", "to_degrees"]
