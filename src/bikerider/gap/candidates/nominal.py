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

A real rider differs from this default, so the default comes with stated standard uncertainties
(``*_SIGMA`` below, each with its source), which the fitted sizes' intervals of the candidates that use
the geometry carry (:meth:`bikerider.gap.inference.problem.GapProblem.geometry_jacobian`).  They are
chosen from the spread between people and between handlebars, not fitted to any case.
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

UPPER_BODY_FRACTION_SIGMA = 0.04
"""Standard uncertainty of :data:`UPPER_BODY_FRACTION`.  de Leva (1996) puts head, upper and middle
trunk and both arms at about 49 % of the mass for men and 46 % for women (Dempster's cadavers give
similar sums); where the lean pivots (hips or lumbar spine) moves part of the middle trunk (16 %) in or
out; and body build shifts the trunk's share by a few per cent between people.  0.04 covers the sexes'
difference and the pivot's ambiguity at about one sigma."""
UPPER_BODY_RADII_SIGMA = 0.15
"""Relative standard uncertainty of :data:`UPPER_BODY_RADII` (the moments of inertia move by twice
it): radii of gyration scale with stature (coefficient of variation about 4 %) and, more, with posture
(an upright trunk against one bent over the top tube) and where the arms are."""
UPPER_BODY_RISE_SIGMA = 0.05
"""Standard uncertainty of :data:`UPPER_BODY_RISE` [m]: the upper body's centre lies near the lower
chest, the whole rider's near the navel; their distance grows with trunk length (sitting height varies
by about 5 % between adults) and shrinks as the trunk bends forward (upright city bike against a road
bicycle's drops)."""
UPPER_BODY_REACH_SIGMA = 0.05
"""Standard uncertainty of the upper body centre's fore-aft place [m] (by default over the rider's
centre of mass): a trunk bent forward by 30-60 degrees puts it some centimetres ahead."""
HIP_DROP_SIGMA = 0.05
"""Standard uncertainty of :data:`HIP_DROP` [m]: the seated rider's centre of mass lies above the
saddle by an amount set by the legs' place (pedals low or high, a saddle set high or low) and the
trunk's angle; the hip joints lie some centimetres below and behind the top of the saddle, and a
lean about the lumbar spine pivots higher."""
GRIP_RISE_SIGMA = 0.10
"""Standard uncertainty of the grips' height [m] (by default at the handlebar-and-fork centre of
mass): that centre lies between the fork crown and the bar, the grips some centimetres to a few
decimetres above it with a tall stem; riser bars add 2-5 cm, swept-back city bars more, and a drop
bar's hoods and drops lie about 10-12 cm apart."""
GRIP_REACH_SIGMA = 0.05
"""Standard uncertainty of the grips' fore-aft place [m]: swept-back bars put the grips up to 0.1-0.2
m behind the stem's clamp, a drop bar's hoods 7-9 cm ahead of it."""
GRIP_HALF_WIDTH_SIGMA = 0.05
"""Standard uncertainty of :data:`GRIP_HALF_WIDTH` [m]: flat and riser bars are 0.56-0.80 m wide,
road drop bars 0.38-0.46 m (half-widths 0.19-0.40 m)."""

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
        """Upper body and grips from the rider's lumped body (or none without a rider), with the
        default's stated uncertainty (the module's ``*_SIGMA``, independent sources).

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
        uncertainty = {
            "grip height": {"z_grip": GRIP_RISE_SIGMA},
            "grip reach": {"x_grip": GRIP_REACH_SIGMA},
            "grip half-width": {"b_grip": GRIP_HALF_WIDTH_SIGMA},
        }
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
            mass_share = UPPER_BODY_FRACTION_SIGMA / UPPER_BODY_FRACTION  # relative, moving m_u and its inertia
            uncertainty.update(
                {
                    "upper-body mass fraction": {
                        "m_u": mass_share * m_u,
                        "IUxx": mass_share * upper["IUxx"],
                        "IUzz": mass_share * upper["IUzz"],
                    },
                    "upper-body radii of gyration": {
                        "IUxx": 2 * UPPER_BODY_RADII_SIGMA * upper["IUxx"],
                        "IUzz": 2 * UPPER_BODY_RADII_SIGMA * upper["IUzz"],
                    },
                    "upper-body centre height": {"z_u": UPPER_BODY_RISE_SIGMA},
                    "upper-body centre reach": {"x_u": UPPER_BODY_REACH_SIGMA},
                    "hip axis height": {"z_lean": HIP_DROP_SIGMA},
                }
            )
            notes.append(
                f"upper body: {UPPER_BODY_FRACTION:.0%} of the rider's {rider['mass']:.1f} kg, "
                f"{UPPER_BODY_RISE} m above the rider's centre of mass, hip axis {HIP_DROP} m below it (default)"
            )
        else:
            notes.append("no rider: rider_lean and passive_arms do not apply")
        return RiderGeometry(upper, grips, "; ".join(notes), uncertainty)
