"""The candidate unmodelled effects: their physical parameters, units and literature ranges.

Each effect names the parameters the diagnosis fits, their bounds (what is physically possible)
and their literature range (what is typical).  A fitted value whose 95 % confidence interval does
not reach the literature range is flagged implausible.  Ranges are from the table in
``data/gap/README.md`` of the reference material (sources quoted per parameter); the models
themselves are derived in ``derive/gap_effects.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

EFFECT_NAMES = (
    "parameters",
    "steer_damping",
    "steer_inertia",
    "steer_stiffness",
    "passive_arms",
    "rider_lean",
    "tyre_slip",
    "speed_sensor",
    "steer_friction",
)
"""Every candidate, in the order reports list them."""
OBSERVATION_EFFECTS = ("speed_sensor",)
"""Candidates that change how the data were taken rather than the bicycle (no model parameter)."""
TIME_DOMAIN_EFFECTS = ("steer_friction",)
"""Nonlinear candidates fitted in the time domain to records (:mod:`bikerider.gap.timedomain`)."""
COULOMB_RANGE = (0.02, 0.15)
"""Steer Coulomb friction of the literature [N m] (data/gap/README.md table; Davis bicycle 0.15 +/-
0.05, Moore 2012)."""


@dataclass(frozen=True)
class EffectParameter:
    """One fitted parameter of an effect.

    Attributes
    ----------
    name : str
        Symbol name (as in ``derive/symbols.py``).
    unit : str
    bounds : tuple of float
        Physically possible values (the fit stays inside).
    literature : tuple of float
        Typical range from the literature.
    start : float
        Starting value of the fit (inside the literature range).
    source : str
        Where the literature range comes from.
    """

    name: str
    unit: str
    bounds: tuple[float, float]
    literature: tuple[float, float]
    start: float
    source: str


@dataclass(frozen=True)
class Effect:
    """A candidate effect: what it is, what it fits and what it holds fixed.

    Attributes
    ----------
    name : str
    description : str
    parameters : tuple of EffectParameter
        The fitted parameters (empty for ``parameters``, whose fitted values are the benchmark
        parameters themselves).
    fixed : dict
        Parameters the effect needs but does not fit, at literature mid values.
    needs_rider : bool
        Only meaningful with a rider on the bicycle.
    """

    name: str
    description: str
    parameters: tuple[EffectParameter, ...]
    fixed: dict[str, float] = field(default_factory=dict)
    needs_rider: bool = False
    needs_records: bool = False


_TABLE = "data/gap/README.md literature table"

EFFECTS: dict[str, Effect] = {
    "parameters": Effect(
        "parameters",
        "the benchmark parameters moved within their stated uncertainty (Gaussian prior); no new physics",
        (),
    ),
    "steer_damping": Effect(
        "steer_damping",
        "viscous damping between front and rear frame about the steer axis (bearing, rider's hands)",
        (
            EffectParameter(
                "c_steer",
                "N m s/rad",
                (0.0, 20.0),
                (0.05, 0.5),
                0.3,
                f"{_TABLE}: steer viscous damping 0.05-0.5 N m s/rad (Davis bicycle 0.34, Moore 2012)",
            ),
        ),
    ),
    "steer_inertia": Effect(
        "steer_inertia",
        "extra moment of inertia carried by the front frame about the steer axis (hands, accessories)",
        (
            EffectParameter(
                "I_steer",
                "kg m^2",
                (0.0, 2.0),
                (0.05, 0.3),
                0.15,
                f"{_TABLE}: passive arms, inertia about the steer axis 0.05-0.3 kg m^2",
            ),
        ),
    ),
    "steer_stiffness": Effect(
        "steer_stiffness",
        "a spring between front and rear frame about the steer axis (cables, the rider's arms)",
        (
            EffectParameter(
                "k_steer",
                "N m/rad",
                (0.0, 100.0),
                (0.0, 10.0),
                3.0,
                f"{_TABLE}: passive arms, steer stiffness 0-10 N m/rad",
            ),
        ),
    ),
    "passive_arms": Effect(
        "passive_arms",
        "the rider's arms: mass at the grips moving with the handlebar (taken from the rear body), "
        "a spring and a damper about the steer axis between handlebar and upper body",
        (
            EffectParameter(
                "m_arm",
                "kg",
                (0.0, 15.0),
                (0.6, 3.5),
                2.0,
                f"{_TABLE}: inertia about the steer axis 0.05-0.3 kg m^2, i.e. about 0.6-3.5 kg "
                "at grips 0.29 m from the bicycle's plane (checked on the inertia, see plausibility)",
            ),
            EffectParameter(
                "k_arm",
                "N m/rad",
                (0.0, 100.0),
                (0.0, 10.0),
                3.0,
                f"{_TABLE}: passive arms, steer stiffness 0-10 N m/rad",
            ),
            EffectParameter(
                "c_arm",
                "N m s/rad",
                (0.0, 30.0),
                (0.5, 3.0),
                1.0,
                f"{_TABLE}: passive arms, steer damping 0.5-3 N m s/rad",
            ),
        ),
        needs_rider=True,
    ),
    "rider_lean": Effect(
        "rider_lean",
        "the rider's upper body leaning about a longitudinal hip axis with passive stiffness and damping "
        "(a third degree of freedom)",
        (
            EffectParameter(
                "k_lean",
                "N m/rad",
                (1.0, 3000.0),
                (64.0, 256.0),
                128.0,
                f"{_TABLE}: about 128 N m/rad (Moore 2012); range taken as half to twice that value",
            ),
            EffectParameter(
                "c_lean",
                "N m s/rad",
                (0.1, 1000.0),
                (25.0, 100.0),
                50.0,
                f"{_TABLE}: about 50 N m s/rad (Moore 2012); range taken as half to twice that value",
            ),
        ),
        needs_rider=True,
    ),
    "tyre_slip": Effect(
        "tyre_slip",
        "lateral tyre forces from cornering and camber stiffness, with relaxation length and pneumatic "
        "trail, instead of rolling without slip",
        (
            EffectParameter(
                "c_alpha",
                "1/rad",
                (2.0, 200.0),
                (10.0, 17.0),
                13.0,
                f"{_TABLE}: cornering stiffness / normal load 10-17 per rad",
            ),
            EffectParameter("sigma_t", "m", (0.005, 1.0), (0.1, 0.3), 0.2, f"{_TABLE}: relaxation length 0.1-0.3 m"),
            EffectParameter("t_p", "m", (0.0, 0.1), (0.012, 0.026), 0.019, f"{_TABLE}: pneumatic trail 12-26 mm"),
        ),
        fixed={"c_gamma": 0.8},
    ),
    "speed_sensor": Effect(
        "speed_sensor",
        "the bicycle ran at another speed than recorded (a wheel encoder's rolling radius, a treadmill's "
        "calibration): its speed is the recorded one times speed_scale, while the controller keeps the recorded speed",
        (
            EffectParameter(
                "speed_scale",
                "-",
                (0.7, 1.4),
                (0.95, 1.05),
                1.0,
                "a wheel encoder reads the speed within a few per cent (tyre deflection changes the rolling "
                "radius); the SBW bicycle's encoder against its treadmill: 0.97-1.02 (Pasma 2024 calibration, "
                "recorded = 1.0662 true - 0.128 m/s, over 1.5-5 m/s)",
            ),
        ),
    ),
    "steer_friction": Effect(
        "steer_friction",
        "Coulomb and viscous friction about the steer axis (bearings, a steer motor's gearbox), "
        "T = -T_coulomb tanh(deltad / eps) - c_viscous deltad, fitted in the time domain to the records",
        (
            EffectParameter(
                "T_coulomb",
                "N m",
                (0.0, 2.0),
                COULOMB_RANGE,
                0.05,
                f"{_TABLE}: steer Coulomb friction 0.02-0.15 N m (Davis bicycle 0.15, Moore 2012)",
            ),
            EffectParameter(
                "c_viscous",
                "N m s/rad",
                (0.0, 5.0),
                (0.05, 0.5),
                0.2,
                f"{_TABLE}: steer viscous damping 0.05-0.5 N m s/rad (Davis bicycle 0.34, Moore 2012)",
            ),
        ),
        needs_records=True,
    ),
}
"""The candidates.  ``tyre_slip`` holds the camber stiffness at 0.8 per rad (mid of the 0.6-0.95
literature range; the weave eigenvalues hardly depend on it, so fitting it adds a parameter the data
cannot determine)."""

LITERATURE_EXTRA = {
    "I_arm_steer": ((0.05, 0.3), "kg m^2", f"{_TABLE}: passive arms, inertia about the steer axis 0.05-0.3 kg m^2"),
}
"""Derived quantities checked against the literature (the arms' inertia about the steer axis)."""


def effect(name: str) -> Effect:
    """The effect called ``name``.

    Raises
    ------
    InputError
        For an unknown name (the message lists the candidates).
    """
    from bikerider.errors import InputError

    try:
        return EFFECTS[name]
    except KeyError:
        raise InputError("effect", name, "one of " + ", ".join(EFFECT_NAMES)) from None
