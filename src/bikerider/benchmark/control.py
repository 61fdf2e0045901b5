"""Control laws on the steer torque, with gains that may change with speed.

A control law gives the steer torque a controller (a steer-by-wire motor, a robot rider, a rider's
balance model) applies, in the benchmark sign convention (positive torque turns the handlebar to positive steer)::

    T_delta = k_phi(v) phi + k_phid(v) phid + k_delta(v) delta + k_deltad(v) deltad

Each gain is a :class:`GainSchedule` of the speed ``v`` the controller uses:

``constant``
    one number (the gain does not change with speed);
``piecewise linear``
    values at increasing speeds, linear in between and held at the end values beyond them
    (``{ speed = [0.0, 6.5], gain = [13.0, 0.0] }``);
``ramp``
    ``K (v0 - v)`` below ``v0`` and zero above (``{ K = 2.0, v0 = 6.5, when = "below" }``), or
    ``K (v - v0)`` above ``v0`` and zero below (``when = "above"``): the steer-into-lean and
    balance-assist controllers of the literature (e.g. Schwab et al. 2008; Pasma 2024).

The speed a law is evaluated at is the controller's own speed: for the gap's records, the speed
recorded in the log (the controller reads the same sensor); for its tables, the row's speed.  A law
has a name, used in every table and figure legend.  :mod:`bikerider.benchmark.closed_loop` applies
a law to a bicycle; the gap (:mod:`bikerider.gap`) reads laws from its data files.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bikerider.errors import InputError

GAIN_NAMES = ("k_phi", "k_phid", "k_delta", "k_deltad")
"""The gains of a law, in the order of their arrays: roll angle, roll rate, steer angle, steer rate."""
GAIN_UNITS = {"k_phi": "N m/rad", "k_phid": "N m s/rad", "k_delta": "N m/rad", "k_deltad": "N m s/rad"}
MAX_MAGNITUDE = 1e6
"""Largest magnitude of a gain (SI units) or a speed [m/s] in a control law, and of any number in a
data table (:mod:`bikerider.io.gap_data`).  No controller of a bicycle applies a thousand N m at a
milliradian, and no bicycle test runs at a thousand km/s: a larger value is a unit or column mistake,
and would overflow the closed-loop model."""


@dataclass(frozen=True)
class GainSchedule:
    """One gain as a function of speed: piecewise linear, held constant beyond its end points.

    Attributes
    ----------
    speeds : tuple of float
        Increasing break speeds [m/s] (one for a constant).
    values : tuple of float
        The gain at each break speed.
    text : str
        How the gain was written, for reports (``"2 (6.5 - v) below 6.5 m/s"``).
    """

    speeds: tuple[float, ...]
    values: tuple[float, ...]
    text: str = ""
    ramp: tuple[float, float, str] | None = None
    """``(K, v0, side)`` for a ramp (unbounded on its side, so not held at an end point)."""

    @staticmethod
    def constant(value: float, name: str = "gain", source: str | None = None) -> GainSchedule:
        value = _finite(value, name, source, "gain")
        return GainSchedule((0.0,), (value,), f"{value:g}")

    @staticmethod
    def piecewise(speeds, values, name: str = "gain", source: str | None = None) -> GainSchedule:
        """Values at increasing speeds (at least two), linear in between, held beyond the ends."""
        if not isinstance(speeds, (list, tuple)) or not isinstance(values, (list, tuple)):
            raise InputError(name, {"speed": speeds, "gain": values}, "lists speed = [...] and gain = [...]", source)
        if len(speeds) != len(values) or len(speeds) < 2:
            raise InputError(
                name, {"speed": speeds, "gain": values}, "as many gains as speeds, at least two of each", source
            )
        s = [_finite(x, f"{name}.speed", source, "speed") for x in speeds]
        g = [_finite(x, f"{name}.gain", source, "gain") for x in values]
        if any(b <= a for a, b in zip(s, s[1:])):
            raise InputError(f"{name}.speed", speeds, "increasing speeds", source)
        if s[0] < 0:
            raise InputError(f"{name}.speed", speeds, "speeds of at least 0 m/s", source)
        text = "piecewise linear " + ", ".join(f"{gv:g} at {sv:g}" for sv, gv in zip(s, g)) + " m/s"
        return GainSchedule(tuple(s), tuple(g), text)

    @staticmethod
    def make_ramp(K, v0, side: str, name: str = "gain", source: str | None = None) -> GainSchedule:
        """``K (v0 - v)`` for ``v < v0`` (``side = "below"``) or ``K (v - v0)`` for ``v > v0`` (``"above"``)."""
        K = _finite(K, f"{name}.K", source, "gain")
        v0 = _finite(v0, f"{name}.v0", source, "speed")
        if v0 <= 0:
            raise InputError(f"{name}.v0", v0, "a positive speed [m/s]", source)
        if side not in ("below", "above"):
            raise InputError(f"{name}.when", side, '"below" or "above" (the side of v0 where the gain acts)', source)
        text = f"{K:g} ({v0:g} - v) below {v0:g} m/s" if side == "below" else f"{K:g} (v - {v0:g}) above {v0:g} m/s"
        return GainSchedule((v0,), (0.0,), text, (K, v0, side))

    @property
    def is_constant(self) -> bool:
        return self.ramp is None and len(set(self.values)) == 1

    def scaled(self, factor: float) -> GainSchedule:
        """The same schedule with every gain multiplied by ``factor`` (a controller's gain turned up or down)."""
        if self.ramp is not None:
            K, v0, side = self.ramp
            return GainSchedule.make_ramp(K * factor, v0, side)
        if len(self.speeds) == 1:
            return GainSchedule.constant(self.values[0] * factor)
        return GainSchedule.piecewise(list(self.speeds), [g * factor for g in self.values])

    def __call__(self, speed) -> np.ndarray:
        """The gain at ``speed`` [m/s] (any shape)."""
        v = np.asarray(speed, dtype=float)
        if self.ramp is not None:
            K, v0, side = self.ramp
            return K * np.maximum(v0 - v, 0.0) if side == "below" else K * np.maximum(v - v0, 0.0)
        if len(self.speeds) == 1:
            return np.full(v.shape, self.values[0])
        return np.interp(v, self.speeds, self.values)


@dataclass(frozen=True)
class ControlLaw:
    """A named control law: one :class:`GainSchedule` per gain (missing gains are zero).

    Attributes
    ----------
    name : str
        Shown in reports and legends.
    gains : dict
        Gain name (:data:`GAIN_NAMES`) to schedule.
    description : str
    source : str
        Where the law was read.
    """

    name: str
    gains: dict[str, GainSchedule] = field(default_factory=dict)
    description: str = ""
    source: str = ""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.strip():
            raise InputError("control law name", self.name, "a non-empty name", self.source or None)
        for key in self.gains:
            if key not in GAIN_NAMES:
                raise InputError(
                    f"control.{self.name}.{key}",
                    "given",
                    "one of the gains " + ", ".join(GAIN_NAMES),
                    self.source or None,
                )

    @staticmethod
    def constant(gains, name: str | None = None) -> ControlLaw:
        """A law of constant gains ``[k_phi, k_phid, k_delta, k_deltad]``, named by its gains unless named."""
        values = np.asarray(gains, dtype=float).reshape(-1)
        if values.size != 4:
            raise InputError("control gains", values.tolist(), "four gains k_phi, k_phid, k_delta, k_deltad")
        schedules = {k: GainSchedule.constant(float(x), k) for k, x in zip(GAIN_NAMES, values) if x != 0}
        return ControlLaw(name or constant_law_name(values), schedules)

    def scaled(self, factor: float, name: str | None = None) -> ControlLaw:
        """The same controller with every gain multiplied by ``factor``, named ``<name> x<factor>``."""
        return ControlLaw(
            name or f"{self.name} x{factor:g}",
            {k: s.scaled(factor) for k, s in self.gains.items()},
            f"{self.name} with its gains times {factor:g}",
            self.source,
        )

    @property
    def is_zero(self) -> bool:
        return not self.gains or all(s.is_constant and s.values[0] == 0 for s in self.gains.values())

    def __call__(self, speeds) -> np.ndarray:
        """Gains ``(..., 4)`` at the controller's speeds ``(...)`` (order :data:`GAIN_NAMES`)."""
        v = np.asarray(speeds, dtype=float)
        out = np.zeros(v.shape + (4,))
        for k, name in enumerate(GAIN_NAMES):
            if name in self.gains:
                out[..., k] = self.gains[name](v)
        return out

    def describe(self) -> str:
        """``T_delta = ...`` in words, for reports."""
        if self.is_zero:
            return "no control"
        parts = [f"k_{n[2:]} = {s.text}" for n, s in self.gains.items()]
        return "; ".join(parts)


NO_CONTROL = ControlLaw("no control")
"""The law of an uncontrolled test."""


def constant_law_name(gains) -> str:
    """A name for constant gains: ``no control`` or ``k_phid = 5, k_delta = -2``."""
    values = np.asarray(gains, dtype=float).reshape(-1)
    parts = [f"{n} = {x:g}" for n, x in zip(GAIN_NAMES, values) if x != 0]
    return ", ".join(parts) if parts else "no control"


def _finite(value, name: str, source: str | None, kind: str) -> float:
    """``value`` as a float: a finite number (a ``kind``, gain or speed) of magnitude at most :data:`MAX_MAGNITUDE`."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(name, value, "a finite number", source)
    if isinstance(value, int) and abs(value) > MAX_MAGNITUDE:  # also ints too large for a float
        digits = len(str(abs(value)))
        shown = f"{str(value)[:8]}... ({digits} digits)" if digits > 20 else value
        raise InputError(name, shown, _limit_text(kind), source)
    if not math.isfinite(value):
        raise InputError(name, value, "a finite number", source)
    if abs(value) > MAX_MAGNITUDE:
        raise InputError(name, float(value), _limit_text(kind), source)
    return float(value)


def _limit_text(kind: str) -> str:
    unit = "m/s" if kind == "speed" else "SI units (N m/rad, N m s/rad)"
    return f"a {kind} of magnitude at most {MAX_MAGNITUDE:g} {unit} (check the units)"
