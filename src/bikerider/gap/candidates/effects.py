"""The candidate unmodelled effects: their physical parameters, units, usual ranges and priors.

Each effect names the parameters the diagnosis fits, their bounds (what is physically possible, or
the edge of the search), their usual range (what the literature measured: a value outside it is
flagged, not refused) and their prior (:class:`Prior`, a distribution with its source), which the
selection weighs as evidence against the held-out data (:mod:`bikerider.gap.diagnosis.result`).  Ranges and
priors are from the table in ``data/gap/README.md`` of the reference material and the sources quoted
per parameter (``docs/gap.md``, section "Priors"); the models themselves are derived in
``derive/gap_effects.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.special import ndtri  # the normal quantile (scipy.stats.norm.ppf's own function, without its import)

from bikerider.errors import InputError
from bikerider.generated.manifest import TYRE_ARGS

# The names, typed here and nowhere else (tests/gap/candidates/test_gap_registry.py): take them from here.
PARAMETERS = "parameters"
STEER_DAMPING = "steer_damping"
STEER_INERTIA = "steer_inertia"
STEER_STIFFNESS = "steer_stiffness"
PASSIVE_ARMS = "passive_arms"
RIDER_LEAN = "rider_lean"
TYRE_SLIP = "tyre_slip"
SPEED_SENSOR = "speed_sensor"
STEER_FRICTION = "steer_friction"
EFFECT_NAMES = (
    PARAMETERS,
    STEER_DAMPING,
    STEER_INERTIA,
    STEER_STIFFNESS,
    PASSIVE_ARMS,
    RIDER_LEAN,
    TYRE_SLIP,
    SPEED_SENSOR,
    STEER_FRICTION,
)
"""Every candidate, in the order reports list them (the keys of :data:`EFFECTS`, in this order)."""
COULOMB_RANGE = (0.02, 0.15)
"""Steer Coulomb friction of the literature [N m] (data/gap/README.md table; Davis bicycle 0.15 +/-
0.05, Moore 2012)."""


@dataclass(frozen=True)
class Prior:
    """A prior distribution of one candidate parameter, with its source.

    Attributes
    ----------
    kind : str
        ``"lognormal"`` (a positive size: ``centre`` the median, ``spread`` the geometric standard
        deviation, a factor above 1), ``"halfcauchy"`` (a size whose typical value may be zero:
        ``centre`` unused, ``spread`` the scale; heavy tails, so that data can overrule it) or
        ``"normal"`` (``centre`` the mean, ``spread`` the standard deviation).
    centre, spread : float
    source : str
        Where it comes from.
    broad : bool
        Made broad for lack of measured values (said in the output and the docs).
    """

    kind: str
    centre: float
    spread: float
    source: str
    broad: bool = False

    def log_ratio(self, x: float) -> float:
        """``ln p(x) - ln p(mode)`` (0 at the most probable value, negative elsewhere): the evidence, in
        nats, a fitted value ``x`` loses to its prior.  Densities of a lognormal prior are taken per unit
        of ``ln x`` (the scale on which a size is uncertain), so the ratio does not depend on units."""
        if self.kind == "normal":
            return -0.5 * ((x - self.centre) / self.spread) ** 2
        if self.kind == "halfcauchy":
            return -math.log1p((max(x, 0.0) / self.spread) ** 2)
        # lognormal; a value at zero (the effect absent) is taken as a millionth of the median
        u = math.log(max(x, 1e-6 * self.centre) / self.centre) / math.log(self.spread)
        return -0.5 * u * u

    def interval(self, p: float = 0.95) -> tuple[float, float]:
        """The central (half-Cauchy: lower) interval holding probability ``p``."""

        if self.kind == "normal":
            z = float(ndtri(0.5 + p / 2))
            return self.centre - z * self.spread, self.centre + z * self.spread
        if self.kind == "halfcauchy":
            return 0.0, self.spread * math.tan(math.pi * p / 2)
        z = float(ndtri(0.5 + p / 2))
        return self.centre / self.spread**z, self.centre * self.spread**z

    def sample(self, rng: np.random.Generator, p: float = 0.95) -> float:
        """A draw from the prior, restricted to its :meth:`interval` of probability ``p``."""
        lo, hi = self.interval(p)
        while True:
            if self.kind == "normal":
                x = self.centre + self.spread * float(rng.standard_normal())
            elif self.kind == "halfcauchy":
                x = abs(self.spread * float(rng.standard_cauchy()))
            else:
                x = self.centre * self.spread ** float(rng.standard_normal())
            if lo <= x <= hi:
                return x

    def describe(self, unit: str) -> str:
        """The prior in words, e.g. ``lognormal, median 0.3 N m s/rad, 95 % within 0.035-2.6``."""
        lo, hi = self.interval()
        if self.kind == "normal":
            head = f"normal, mean {self.centre:.3g} {unit}, sd {self.spread:.3g}"
        elif self.kind == "halfcauchy":
            head = f"half-Cauchy, scale {self.spread:.3g} {unit}"
        else:
            head = f"lognormal, median {self.centre:.3g} {unit}, factor {self.spread:.3g}"
        return f"{head}, 95 % within {lo:.3g}-{hi:.3g}" + (" (broad: few measured values)" if self.broad else "")


def prior_from_range(lo: float, hi: float, source: str) -> Prior:
    """The prior a stated range ``[lo, hi]`` makes (a bicycle's own ``[plausible]`` table): lognormal with
    95 % inside the range when ``lo > 0``, else half-Cauchy with its 80 % point at ``hi``."""
    if lo > 0 and hi > lo:
        return Prior("lognormal", math.sqrt(lo * hi), math.exp(math.log(hi / lo) / (2 * 1.959964)), source)
    return Prior("halfcauchy", 0.0, max(hi, 1e-12) / math.tan(math.pi * 0.8 / 2), source)


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
    prior : Prior or None
        The prior weighed in the selection (``None``: derived from the literature range by
        :func:`prior_from_range`).
    check : str
        What to check when a fitted value lies above the usual range (what else could make it large).
    """

    name: str
    unit: str
    bounds: tuple[float, float]
    literature: tuple[float, float]
    start: float
    source: str
    prior: Prior | None = None
    check: str = ""

    def the_prior(self) -> Prior:
        """:attr:`prior`, or the one the literature range makes."""
        return self.prior if self.prior is not None else prior_from_range(*self.literature, self.source)


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
    needs_records : bool
        Fitted in the time domain to records.
    partners : tuple of str
        For a time-domain effect: the linear candidates searched together with it as pairs (the other
        pairs are searched between linear candidates only, to keep the time-domain fits few).
    structural_keys : tuple of str
        The parameters of :class:`~bikerider.gap.candidates.effect_model.EffectModel` it sets (fitted and
        fixed); empty for an effect that is no part of the linear model (``parameters``, an observation
        effect, a time-domain effect).
    observation : bool
        It changes how the data were taken rather than the bicycle (no model parameter).
    adds_lean, adds_tyres : bool
        It needs the model with the rider's lean degree of freedom (``rider_lean_matrices``), or with
        the tyres' lateral forces (``tyre_slip_descriptor``), of ``derive/gap_effects.py``.
    nests : dict
        The simpler candidates this effect holds as a special case: simpler effect name to the values of
        this effect's own parameters that make it that effect (``steer_friction`` with ``T_coulomb = 0``
        is ``steer_damping``).  Where the data do not exclude those values, the ranking takes the
        simpler one first (:func:`bikerider.gap.diagnosis.which.order`).
    """

    name: str
    description: str
    parameters: tuple[EffectParameter, ...]
    fixed: dict[str, float] = field(default_factory=dict)
    needs_rider: bool = False
    needs_records: bool = False
    partners: tuple[str, ...] = ()
    structural_keys: tuple[str, ...] = ()
    observation: bool = False
    adds_lean: bool = False
    adds_tyres: bool = False
    nests: dict[str, dict[str, float]] = field(default_factory=dict)


_TABLE = "data/gap/README.md literature table"
C_STEER_PRIOR = (
    f"{_TABLE}: bearings and seals 0.05-0.5 N m s/rad (Davis bicycle 0.34 +/- 0.04, Moore 2012); hands on "
    "the bar 0.5-3 N m s/rad (passive arms, same table); no measured back-EMF damping of a steer motor in "
    "the reference material, and Coulomb friction acts as a viscous damping 4 T / (pi A) at steer-rate "
    "amplitude A: broad"
)
C_STEER_CHECK = (
    "a rider's hands on the bar, a steer motor's back-EMF, a steering damper, or Coulomb friction acting "
    "as its linear equivalent 4 T / (pi A) at the steer-rate amplitude A of the runs"
)

EFFECTS: dict[str, Effect] = {
    PARAMETERS: Effect(
        PARAMETERS,
        "the benchmark parameters moved within their stated uncertainty (Gaussian prior); no new physics",
        (),
    ),
    STEER_DAMPING: Effect(
        STEER_DAMPING,
        "viscous damping between front and rear frame about the steer axis (bearing, rider's hands)",
        (
            EffectParameter(
                "c_steer",
                "N m s/rad",
                (0.0, 20.0),
                (0.05, 0.5),
                0.3,
                f"{_TABLE}: steer viscous damping 0.05-0.5 N m s/rad (Davis bicycle 0.34, Moore 2012)",
                Prior("lognormal", 0.3, 3.0, C_STEER_PRIOR, broad=True),
                C_STEER_CHECK,
            ),
        ),
        structural_keys=("c_steer",),
    ),
    STEER_INERTIA: Effect(
        STEER_INERTIA,
        "extra moment of inertia carried by the front frame about the steer axis (hands, accessories)",
        (
            EffectParameter(
                "I_steer",
                "kg m^2",
                (0.0, 2.0),
                (0.05, 0.3),
                0.15,
                f"{_TABLE}: passive arms, inertia about the steer axis 0.05-0.3 kg m^2",
                Prior(
                    "lognormal",
                    0.1,
                    2.5,
                    f"{_TABLE}: hands and arms 0.05-0.3 kg m^2 about the steer axis; no measured inertia of "
                    "accessories or of a steer motor's rotor through its gearbox in the reference material",
                    broad=True,
                ),
                "hands or arms heavier than usual, a steer motor's rotor (its inertia times the gear ratio "
                "squared), a basket or a load on the handlebar",
            ),
        ),
        structural_keys=("I_steer",),
    ),
    STEER_STIFFNESS: Effect(
        STEER_STIFFNESS,
        "a spring between front and rear frame about the steer axis (cables, the rider's arms)",
        (
            EffectParameter(
                "k_steer",
                "N m/rad",
                (0.0, 100.0),
                (0.0, 10.0),
                3.0,
                f"{_TABLE}: passive arms, steer stiffness 0-10 N m/rad",
                Prior("halfcauchy", 0.0, 3.0, f"{_TABLE}: passive arms, steer stiffness 0-10 N m/rad"),
                "cables or a spring on the steer, a steer motor's position control, a rider holding the bar",
            ),
        ),
        structural_keys=("k_steer",),
    ),
    PASSIVE_ARMS: Effect(
        PASSIVE_ARMS,
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
                Prior(
                    "lognormal",
                    1.45,
                    1.6,
                    f"{_TABLE}: inertia about the steer axis 0.05-0.3 kg m^2, i.e. about 0.6-3.5 kg at grips "
                    "0.29 m from the bicycle's plane",
                ),
                "the grips' place (the arms' inertia grows with the square of their distance from the axis)",
            ),
            EffectParameter(
                "k_arm",
                "N m/rad",
                (0.0, 100.0),
                (0.0, 10.0),
                3.0,
                f"{_TABLE}: passive arms, steer stiffness 0-10 N m/rad",
                Prior("halfcauchy", 0.0, 3.0, f"{_TABLE}: passive arms, steer stiffness 0-10 N m/rad"),
                "a rider gripping the bar firmly (arm stiffness grows with muscle co-contraction)",
            ),
            EffectParameter(
                "c_arm",
                "N m s/rad",
                (0.0, 30.0),
                (0.5, 3.0),
                1.0,
                f"{_TABLE}: passive arms, steer damping 0.5-3 N m s/rad",
                Prior("lognormal", 1.2, 1.6, f"{_TABLE}: passive arms, steer damping 0.5-3 N m s/rad"),
                "a firm grip, or steer damping of the bicycle itself (bearings, a steer motor) beside the arms",
            ),
        ),
        needs_rider=True,
        structural_keys=("m_arm", "k_arm", "c_arm"),
    ),
    RIDER_LEAN: Effect(
        RIDER_LEAN,
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
                Prior(
                    "lognormal",
                    128.0,
                    2.0,
                    f"{_TABLE}: about 128 N m/rad (Moore 2012), one estimate: spread taken as a factor 2",
                    broad=True,
                ),
                "a rider bracing the upper body (the stiffness grows with muscle tone)",
            ),
            EffectParameter(
                "c_lean",
                "N m s/rad",
                (0.1, 1000.0),
                (25.0, 100.0),
                50.0,
                f"{_TABLE}: about 50 N m s/rad (Moore 2012); range taken as half to twice that value",
                Prior(
                    "lognormal",
                    50.0,
                    2.0,
                    f"{_TABLE}: about 50 N m s/rad (Moore 2012), one estimate: spread taken as a factor 2",
                    broad=True,
                ),
                "a rider bracing the upper body",
            ),
        ),
        needs_rider=True,
        structural_keys=("k_lean", "c_lean"),
        adds_lean=True,
    ),
    TYRE_SLIP: Effect(
        TYRE_SLIP,
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
                Prior(
                    "lognormal",
                    13.0,
                    1.15,
                    f"{_TABLE}: cornering stiffness / normal load 10-17 per rad; the Magic-Formula "
                    "Schwalbe Energizer Plus 28x1.75 (Dell'Orto et al. 2023) linearised: 10-16 per rad at "
                    "300-600 N and 300-500 kPa (data/gap/tyres)",
                ),
                "tyre pressure, the load on each wheel, a tyre of another kind (knobbly, wide, tubular)",
            ),
            EffectParameter(
                "sigma_t",
                "m",
                (0.005, 1.0),
                (0.1, 0.3),
                0.2,
                f"{_TABLE}: relaxation length 0.1-0.3 m",
                Prior("lognormal", 0.17, 1.35, f"{_TABLE}: relaxation length 0.1-0.3 m"),
                "tyre pressure and width; weave eigenvalues determine it poorly (docs/gap.md, Limits)",
            ),
            EffectParameter(
                "t_p",
                "m",
                (0.0, 0.1),
                (0.012, 0.026),
                0.019,
                f"{_TABLE}: pneumatic trail 12-26 mm",
                Prior(
                    "lognormal",
                    0.018,
                    1.2,
                    f"{_TABLE}: pneumatic trail 12-26 mm (the Magic-Formula tyre of data/gap/tyres, linearised)",
                ),
                "tyre pressure and load",
            ),
        ),
        fixed={"c_gamma": 0.8},
        structural_keys=TYRE_ARGS,
        adds_tyres=True,
    ),
    SPEED_SENSOR: Effect(
        SPEED_SENSOR,
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
                Prior(
                    "normal",
                    1.0,
                    0.025,
                    "a wheel encoder within a few per cent (tyre deflection changes the rolling radius); the "
                    "SBW bicycle's encoder against its treadmill 0.97-1.02 (Pasma 2024 calibration)",
                ),
                "the encoder's rolling radius, a treadmill's belt speed calibration",
            ),
        ),
        observation=True,
    ),
    STEER_FRICTION: Effect(
        STEER_FRICTION,
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
                Prior(
                    "halfcauchy",
                    0.0,
                    0.1,
                    f"{_TABLE}: steer Coulomb friction 0.02-0.15 N m; Davis bicycle 0.15 +/- 0.05 N m "
                    "(Moore 2012); a steer motor's gearbox and seals: no measured value here (heavy tails)",
                ),
                "a steer motor's gearbox or brushes, tight headset bearings or seals, cables rubbing",
            ),
            EffectParameter(
                "c_viscous",
                "N m s/rad",
                (0.0, 5.0),
                (0.05, 0.5),
                0.2,
                f"{_TABLE}: steer viscous damping 0.05-0.5 N m s/rad (Davis bicycle 0.34, Moore 2012)",
                Prior(
                    "halfcauchy",
                    0.0,
                    0.3,
                    f"{_TABLE}: steer viscous damping 0.05-0.5 N m s/rad; Davis bicycle 0.34 +/- 0.04 N m s/rad "
                    "(Moore 2012); zero allowed (pure Coulomb friction)",
                ),
                "a steer motor's back-EMF, a steering damper, grease in the bearings",
            ),
        ),
        needs_records=True,
        # a steer motor's rotor inertia, a spring, and an error of the speed sensor
        partners=(STEER_INERTIA, STEER_STIFFNESS, SPEED_SENSOR),
        # without its Coulomb part it is the viscous steer damping (c_viscous as c_steer)
        nests={STEER_DAMPING: {"T_coulomb": 0.0}},
    ),
}
"""The candidates.  ``tyre_slip`` holds the camber stiffness at 0.8 per rad (mid of the 0.6-0.95
literature range; the weave eigenvalues hardly depend on it, so fitting it adds a parameter the data
cannot determine)."""

OBSERVATION_EFFECTS = tuple(name for name, e in EFFECTS.items() if e.observation)
"""Candidates that change how the data were taken rather than the bicycle (no model parameter)."""
TIME_DOMAIN_EFFECTS = tuple(name for name, e in EFFECTS.items() if e.needs_records)
"""Nonlinear candidates fitted in the time domain to records (:mod:`bikerider.gap.inference.timedomain`)."""
STRUCTURAL_KEYS = {name: e.structural_keys for name, e in EFFECTS.items() if e.structural_keys}
"""The model parameters of each structural effect (``parameters`` has none of its own)."""

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

    try:
        return EFFECTS[name]
    except KeyError:
        raise InputError("effect", name, "one of " + ", ".join(EFFECT_NAMES)) from None
