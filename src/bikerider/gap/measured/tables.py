"""Measured data of the gap diagnosis: eigenvalues against speed and identified canonical entries.

The readers of the files these come from are in :mod:`bikerider.io.gap_data` (tables) and
:mod:`bikerider.io.experiment` (raw records and the manifests that describe them); records become
eigenvalue rows through :mod:`bikerider.gap.measured.records`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bikerider.errors import InputError
from bikerider.gap.measured.control import ControlLaw, constant_law_name
from bikerider.generated.manifest import MATRIX_NAMES

MODES = ("weave", "capsize", "castor")
CANONICAL_ENTRIES = (
    "M_phidelta",
    "C1_phidelta",
    "K0_phidelta",
    "M_deltadelta",
    "C1_deltaphi",
    "C1_deltadelta",
    "K0_deltadelta",
    "K2_deltadelta",
)
"""The canonical-matrix entries an identification may report (Moore 2012's free entries)."""
SIGMA_SOURCES = ("stated", "record", "none")
"""Where a row's standard uncertainty comes from: the file states it, the fit of the row's own record
gives it (standard errors), or nothing gives one (the diagnosis estimates it from replicates)."""


@dataclass
class EigenvalueData:
    """Measured eigenvalues, one row per measurement.

    Attributes
    ----------
    speed, speed_sigma : ndarray
        The speed the bicycle ran at and its standard uncertainty [m/s].
    value : ndarray of complex
        Measured eigenvalue (imaginary part >= 0).
    real_sigma, imag_sigma : ndarray
        Standard uncertainties; NaN where none is known.
    mode : list of str
        ``weave``, ``capsize``, ``castor`` or ``auto`` (decided against the model).
    group : list of str
    gains : ndarray, shape (n, 4)
        The control gains acting during the row's test, at the controller's speed.
    source : list of str
        ``file:line`` of each row, or the record it was fitted from.
    law : list of str
        Name of the control law of each row (a key of ``laws``).
    laws : dict
        The control laws by name.
    sigma_source : list of str
        One of :data:`SIGMA_SOURCES` per row.
    speed_sensor : ndarray of bool
        Rows whose speed a sensor read during the test (a log's speed column): the rows the
        ``speed_sensor`` candidate may rescale.
    """

    speed: np.ndarray
    value: np.ndarray
    real_sigma: np.ndarray
    imag_sigma: np.ndarray
    speed_sigma: np.ndarray
    mode: list[str]
    group: list[str]
    gains: np.ndarray
    source: list[str]
    law: list[str] = field(default_factory=list)
    laws: dict[str, ControlLaw] = field(default_factory=dict)
    sigma_source: list[str] = field(default_factory=list)
    speed_sensor: np.ndarray | None = None

    def __post_init__(self):
        n = int(np.asarray(self.speed).size)
        self.speed_sensor = np.zeros(n, bool) if self.speed_sensor is None else np.asarray(self.speed_sensor, bool)
        self.gains = np.asarray(self.gains, dtype=float).reshape(n, 4)
        if not self.law:  # constant gains given per row: each distinct set is a law of its own
            self.law = [constant_law_name(g) for g in self.gains]
            for g, name in zip(self.gains, self.law):
                self.laws.setdefault(name, ControlLaw.constant(g, name))
        if not self.sigma_source:
            self.sigma_source = [
                "stated" if np.isfinite(r) and np.isfinite(i) else "none"
                for r, i in zip(np.atleast_1d(self.real_sigma), np.atleast_1d(self.imag_sigma))
            ]
        missing = sorted(set(self.law) - set(self.laws))
        if missing:
            raise InputError("control law", missing[0], "a law defined for the data (" + ", ".join(self.laws) + ")")

    def __len__(self) -> int:
        return int(self.speed.size)

    @staticmethod
    def empty() -> EigenvalueData:
        return EigenvalueData(
            np.empty(0), np.empty(0, complex), np.empty(0), np.empty(0), np.empty(0), [], [], np.empty((0, 4)), []
        )

    @staticmethod
    def concatenate(parts: list[EigenvalueData]) -> EigenvalueData:
        parts = [p for p in parts if len(p)]
        if not parts:
            return EigenvalueData.empty()
        laws: dict[str, ControlLaw] = {}
        for p in parts:
            for name, law in p.laws.items():
                if name in laws and laws[name] != law:
                    raise InputError("control law", name, "one definition of each law name across the data")
                laws[name] = law
        return EigenvalueData(
            np.concatenate([p.speed for p in parts]),
            np.concatenate([p.value for p in parts]),
            np.concatenate([p.real_sigma for p in parts]),
            np.concatenate([p.imag_sigma for p in parts]),
            np.concatenate([p.speed_sigma for p in parts]),
            sum((p.mode for p in parts), []),
            sum((p.group for p in parts), []),
            np.concatenate([p.gains for p in parts]),
            sum((p.source for p in parts), []),
            sum((p.law for p in parts), []),
            laws,
            sum((p.sigma_source for p in parts), []),
            np.concatenate([p.speed_sensor for p in parts]),
        )

    def subset(self, rows) -> EigenvalueData:
        """The rows ``rows`` (indices or a boolean mask)."""
        idx = np.arange(len(self))[rows]
        return EigenvalueData(
            self.speed[idx],
            self.value[idx],
            self.real_sigma[idx],
            self.imag_sigma[idx],
            self.speed_sigma[idx],
            [self.mode[i] for i in idx],
            [self.group[i] for i in idx],
            self.gains[idx],
            [self.source[i] for i in idx],
            [self.law[i] for i in idx],
            {k: v for k, v in self.laws.items() if k in {self.law[i] for i in idx}},
            [self.sigma_source[i] for i in idx],
            self.speed_sensor[idx],
        )


@dataclass
class CanonicalData:
    """Identified canonical-matrix entries, one row per (group, entry)."""

    entry: list[str]
    value: np.ndarray
    sigma: np.ndarray
    group: list[str]
    speed_range: dict[str, tuple[float, float]] = field(default_factory=dict)
    source: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.entry)

    @staticmethod
    def empty() -> CanonicalData:
        return CanonicalData([], np.empty(0), np.empty(0), [], {}, [])

    @staticmethod
    def concatenate(parts: list[CanonicalData]) -> CanonicalData:
        out = CanonicalData.empty()
        for p in parts:
            out.entry += p.entry
            out.group += p.group
            out.source += p.source
            out.value = np.concatenate([out.value, p.value])
            out.sigma = np.concatenate([out.sigma, p.sigma])
            for g, r in p.speed_range.items():
                if g in out.speed_range and out.speed_range[g] != r:
                    raise InputError(
                        f"speed range of group {g}", r, f"the same range in every file ({out.speed_range[g]})"
                    )
                out.speed_range[g] = r
        return out


def entry_name(raw: str) -> str | None:
    """``Mphidelta`` -> ``M_phidelta``; ``None`` for entries that are not canonical-matrix entries."""
    raw = raw.strip()
    for prefix in MATRIX_NAMES:
        if raw.startswith(prefix):
            rest = raw[len(prefix) :].lstrip("_")
            name = f"{prefix}_{rest}"
            return name if name in CANONICAL_ENTRIES else None
    return None
