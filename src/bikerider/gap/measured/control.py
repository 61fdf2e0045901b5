"""The control laws of the gap diagnosis: those of :mod:`bikerider.benchmark.control`.

A control law belongs to the model (:mod:`bikerider.benchmark.closed_loop` applies one to any
bicycle); the gap reads them from its data files and manifests and imports them from here.
"""

from __future__ import annotations

from bikerider.benchmark.control import (
    GAIN_NAMES,
    GAIN_UNITS,
    MAX_MAGNITUDE,
    NO_CONTROL,
    ControlLaw,
    GainSchedule,
    constant_law_name,
)

__all__ = [
    "GAIN_NAMES",
    "GAIN_UNITS",
    "MAX_MAGNITUDE",
    "NO_CONTROL",
    "ControlLaw",
    "GainSchedule",
    "constant_law_name",
]
