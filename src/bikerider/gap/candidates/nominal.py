"""The model a diagnosis starts from: benchmark parameters with uncertainties, and where the rider is.

The files are read by :func:`bikerider.io.gap_model.load_model`; ``--model`` takes either

* a TOML file with the 25 benchmark parameters (plus ``g``) at top level or under ``[benchmark]``,
  values as numbers or ``"value +/- sigma"``; optional tables ``[rider]`` (the rider contained in
  the rear body: ``mass, x, z, Ixx, Ixz, Izz``, benchmark frame), ``[upper_body]`` (``m_u, x_u,
  z_u, IUxx, IUxz, IUzz, z_lean``) and ``[grips]`` (``x_grip, z_grip, b_grip``); or
* a BicycleParameters ``<Name>Benchmark.txt`` (``name = value+/-sigma``).

``--rider`` adds a BicycleParameters lumped rider (``riders/<Rider>/Parameters/<Rider><Bike>
Benchmark.txt``) to the rear body (Moore et al. 2009, Eqs. 15-16).

Default geometry, used when a file does not give it (documented approximations, see
:meth:`GapModelInput.default_geometry`): the upper body that can lean is half the rider's mass, its centre
0.2 m above the rider's centre of mass, the hip axis 0.1 m below it; the grips sit at the
handlebar-and-fork centre of mass, 0.29 m either side of the bicycle's plane.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from bikerider.benchmark import BenchmarkParameters
from bikerider.gap.candidates.effect_model import RiderGeometry

UPPER_BODY_FRACTION = 0.5
"""Share of the rider's mass above the hips (head, trunk above the pelvis, arms).  de Leva (1996)
segment fractions give head 6.9 %, arms 9.9 % and trunk 43.5 % of which the pelvis is about a
quarter: about 0.5."""
UPPER_BODY_RISE = 0.20
"""Height of the upper body's centre above the whole rider's centre [m] (seated rider, approx.)."""
HIP_DROP = 0.10
"""Depth of the hip (lean) axis below the whole rider's centre [m] (seated rider, approx.)."""
UPPER_BODY_RADII = (0.22, 0.15)
"""Radii of gyration of the upper body about its roll (x) and yaw (z) axes [m] (approx.)."""
GRIP_HALF_WIDTH = 0.29
"""Half the grip-to-grip distance of a typical flat handlebar [m]."""

RIDER_KEYS = ("mass", "x", "z", "Ixx", "Ixz", "Izz")


@dataclass(frozen=True)
class GapModelInput:
    """Benchmark parameters (rider included), rider geometry, and the rider itself if known."""

    parameters: BenchmarkParameters
    geometry: RiderGeometry
    rider: dict[str, float] | None
    source: str
    plausible: dict[str, tuple[float, float, str]] = field(default_factory=dict)
    """What this bicycle's own knowledge says is plausible for a candidate's parameter:
    ``{parameter: (low, high, why)}``, replacing the literature range (``[plausible]`` in a TOML
    model file)."""

    @staticmethod
    def default_geometry(parameters: BenchmarkParameters, rider: dict[str, float] | None) -> RiderGeometry:
        """Upper body and grips from the rider's lumped body (or none without a rider).

        Parameters
        ----------
        parameters : BenchmarkParameters
            With the rider included in the rear body.
        rider : dict or None
            ``mass, x, z, Ixx, Ixz, Izz`` of the rider (benchmark frame), or ``None``.
        """
        v = parameters.values
        grips = {"x_grip": float(v["xH"]), "z_grip": float(v["zH"]), "b_grip": GRIP_HALF_WIDTH}
        notes = ["grips at the handlebar-and-fork centre of mass, 0.29 m either side (default)"]
        upper = None
        if rider is not None:
            m_u = UPPER_BODY_FRACTION * rider["mass"]
            kx, kz = UPPER_BODY_RADII
            upper = {
                "m_u": m_u,
                "x_u": rider["x"],
                "z_u": rider["z"] - UPPER_BODY_RISE,
                "IUxx": m_u * kx**2,
                "IUxz": 0.0,
                "IUzz": m_u * kz**2,
                "z_lean": rider["z"] + HIP_DROP,
            }
            notes.append(
                f"upper body: {UPPER_BODY_FRACTION:.0%} of the rider's {rider['mass']:.1f} kg, "
                f"{UPPER_BODY_RISE} m above the rider's centre of mass, hip axis {HIP_DROP} m below it (default)"
            )
        else:
            notes.append("no rider: rider_lean and passive_arms do not apply")
        return RiderGeometry(upper, grips, "; ".join(notes))
