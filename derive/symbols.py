"""The one table of symbols: every symbol bikerider derives with, its description and its unit.

Each entry is ``name: (description, unit, latex, positive)``.  ``name`` is the Python identifier
used in generated code and in input files.  Tests check that every argument of every generated
function is described here with a non-empty description and unit.  Angles are in radians
everywhere past the input boundary.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import sympy as sp


@dataclass(frozen=True)
class SymbolInfo:
    """Description of one symbol."""

    name: str
    description: str
    unit: str
    latex: str
    positive: bool


_TABLE: dict[str, tuple[str, str, str, bool]] = {
    # --- Benchmark parameters (Meijaard et al. 2007, Table 1) -------------------------------
    "w": ("wheelbase", "m", "w", True),
    "c": ("trail", "m", "c", False),
    "lam": ("steer axis tilt from vertical (pi/2 - head tube angle)", "rad", r"\lambda", False),
    "g": ("acceleration due to gravity", "m/s^2", "g", True),
    "rR": ("rear wheel radius", "m", "r_R", True),
    "mR": ("rear wheel mass", "kg", "m_R", True),
    "IRxx": ("rear wheel moment of inertia about a diameter", "kg m^2", "I_{Rxx}", True),
    "IRyy": ("rear wheel moment of inertia about its axle", "kg m^2", "I_{Ryy}", True),
    "xB": ("rear body (frame and rider) centre of mass, x", "m", "x_B", False),
    "zB": ("rear body (frame and rider) centre of mass, z (down positive)", "m", "z_B", False),
    "mB": ("rear body (frame and rider) mass", "kg", "m_B", True),
    "IBxx": ("rear body moment of inertia about x through its centre of mass", "kg m^2", "I_{Bxx}", True),
    "IByy": ("rear body moment of inertia about y through its centre of mass", "kg m^2", "I_{Byy}", True),
    "IBzz": ("rear body moment of inertia about z through its centre of mass", "kg m^2", "I_{Bzz}", True),
    "IBxz": ("rear body product of inertia (tensor entry xz)", "kg m^2", "I_{Bxz}", False),
    "xH": ("handlebar and fork centre of mass, x", "m", "x_H", False),
    "zH": ("handlebar and fork centre of mass, z (down positive)", "m", "z_H", False),
    "mH": ("handlebar and fork mass", "kg", "m_H", True),
    "IHxx": ("handlebar and fork moment of inertia about x", "kg m^2", "I_{Hxx}", True),
    "IHyy": ("handlebar and fork moment of inertia about y", "kg m^2", "I_{Hyy}", True),
    "IHzz": ("handlebar and fork moment of inertia about z", "kg m^2", "I_{Hzz}", True),
    "IHxz": ("handlebar and fork product of inertia (tensor entry xz)", "kg m^2", "I_{Hxz}", False),
    "rF": ("front wheel radius", "m", "r_F", True),
    "mF": ("front wheel mass", "kg", "m_F", True),
    "IFxx": ("front wheel moment of inertia about a diameter", "kg m^2", "I_{Fxx}", True),
    "IFyy": ("front wheel moment of inertia about its axle", "kg m^2", "I_{Fyy}", True),
    # --- Bicycle geometry (Moore et al. 2009, Table 1) ---------------------------------------
    "h_bb": ("bottom bracket height", "m", "h_{bb}", True),
    "l_cs": ("chain stay length", "m", "l_{cs}", True),
    "l_f": ("fork length", "m", "l_f", True),
    "w_fh": ("front hub width", "m", "w_{fh}", True),
    "l_hb": ("handlebar length", "m", "l_{hb}", True),
    "lam_ht": ("head tube angle from the ground", "rad", r"\lambda_{ht}", True),
    "w_rh": ("rear hub width", "m", "w_{rh}", True),
    "l_sp": ("seat post length", "m", "l_{sp}", True),
    "lam_st": ("seat tube angle from the ground", "rad", r"\lambda_{st}", True),
    "l_st": ("seat tube length", "m", "l_{st}", True),
    "l_s": ("stem length", "m", "l_s", True),
    # --- Bicycle bodies measured separately (Moore et al. 2009, Tables 2-6) ----------------
    "mBf": ("rear frame mass (without rider)", "kg", "m_{Bf}", True),
    "xBf": ("rear frame centre of mass, x", "m", "x_{Bf}", False),
    "zBf": ("rear frame centre of mass, z (down positive)", "m", "z_{Bf}", False),
    "IBfxx": ("rear frame moment of inertia about x", "kg m^2", "I_{Bfxx}", True),
    "IBfyy": ("rear frame moment of inertia about y", "kg m^2", "I_{Bfyy}", True),
    "IBfzz": ("rear frame moment of inertia about z", "kg m^2", "I_{Bfzz}", True),
    "IBfxz": ("rear frame product of inertia (tensor entry xz)", "kg m^2", "I_{Bfxz}", False),
    # --- Pendulums (Moore et al. 2009, Eqs. 1-7) -------------------------------------------
    "k_t": ("torsional pendulum stiffness", "N m/rad", "k", True),
    "T": ("oscillation period", "s", "T", True),
    "alpha": ("pendulum axis angle from the ground, rotating up from +x", "rad", r"\alpha", False),
    "l_p": ("compound pendulum length (pivot to wheel centre)", "m", "l", True),
    "m_p": ("mass of the body on the pendulum", "kg", "m", True),
    "Ixx": ("moment of inertia about x", "kg m^2", "I_{xx}", True),
    "Izz": ("moment of inertia about z", "kg m^2", "I_{zz}", True),
    "Ixz": ("product of inertia (tensor entry xz)", "kg m^2", "I_{xz}", False),
    "T_1": ("torsional period in orientation 1", "s", "T_1", True),
    "T_2": ("torsional period in orientation 2", "s", "T_2", True),
    "T_3": ("torsional period in orientation 3", "s", "T_3", True),
    "alpha_1": ("pendulum axis angle of orientation 1", "rad", r"\alpha_1", False),
    "alpha_2": ("pendulum axis angle of orientation 2", "rad", r"\alpha_2", False),
    "alpha_3": ("pendulum axis angle of orientation 3", "rad", r"\alpha_3", False),
    "x_c": ("centre of mass of a hung body, x", "m", "x_c", False),
    "z_c": ("centre of mass of a hung body, z (down positive)", "m", "z_c", False),
    "x_p": ("a point of a pendulum-axis line, x", "m", "x_p", False),
    "z_p": ("a point of a pendulum-axis line, z (down positive)", "m", "z_p", False),
    # --- A body hung from the torsional pendulum (BicycleParameters' photographs) -----------
    "hang": ("hanging angle: the upward steer axis from the photograph's horizontal", "rad", r"\alpha_h", False),
    "off": (
        "distance from the pendulum axis to the body's reference point, positive to its left in the photograph",
        "m",
        "a_h",
        False,
    ),
    "x_ref": (
        "reference point of a hung body (a wheel centre or the handlebar reference point), x",
        "m",
        r"x_{ref}",
        False,
    ),
    "z_ref": ("reference point of a hung body, z (down positive)", "m", r"z_{ref}", False),
    # --- Rider (Moore et al. 2009, Tables 7 and 8) -----------------------------------------
    "mBr": ("rider mass", "kg", "m_{Br}", True),
    "c_ch": ("chest circumference", "m", "c_{ch}", True),
    "lam_fl": ("forward lean angle (seat to head centre, from the ground)", "rad", r"\lambda_{fl}", True),
    "c_h": ("head circumference", "m", "c_h", True),
    "l_hh": ("hip joint to hip joint", "m", "l_{hh}", True),
    "c_la": ("lower arm circumference", "m", "c_{la}", True),
    "l_la": ("lower arm length (elbow to hand centre)", "m", "l_{la}", True),
    "c_ll": ("lower leg circumference", "m", "c_{ll}", True),
    "l_ll": ("lower leg length (floor to knee)", "m", "l_{ll}", True),
    "l_ss": ("shoulder to shoulder", "m", "l_{ss}", True),
    "l_to": ("torso length (hips to shoulders)", "m", "l_{to}", True),
    "c_ua": ("upper arm circumference", "m", "c_{ua}", True),
    "l_ua": ("upper arm length (shoulder to elbow)", "m", "l_{ua}", True),
    "c_ul": ("upper leg circumference", "m", "c_{ul}", True),
    "l_ul": ("upper leg length (knee to hip)", "m", "l_{ul}", True),
    "f_h": ("head mass fraction of rider mass", "1", "f_h", True),
    "f_la": ("lower arm mass fraction (each)", "1", "f_{la}", True),
    "f_ll": ("lower leg mass fraction (each)", "1", "f_{ll}", True),
    "f_to": ("torso mass fraction", "1", "f_{to}", True),
    "f_ua": ("upper arm mass fraction (each)", "1", "f_{ua}", True),
    "f_ul": ("upper leg mass fraction (each)", "1", "f_{ul}", True),
    # --- Rider model results -----------------------------------------------------------------
    "xBr": ("rider centre of mass, x", "m", "x_{Br}", False),
    "zBr": ("rider centre of mass, z (down positive)", "m", "z_{Br}", False),
    "IBrxx": ("rider moment of inertia about x", "kg m^2", "I_{Brxx}", True),
    "IBryy": ("rider moment of inertia about y", "kg m^2", "I_{Bryy}", True),
    "IBrzz": ("rider moment of inertia about z", "kg m^2", "I_{Brzz}", True),
    "IBrxz": ("rider product of inertia (tensor entry xz)", "kg m^2", "I_{Brxz}", False),
    # --- Benchmark model ---------------------------------------------------------------------
    "v": ("forward speed", "m/s", "v", False),
    "u": ("forward speed squared", "m^2/s^2", "u", False),
    # --- Sim-to-real gap: candidate unmodelled effects (derive/gap_effects.py) -----------
    "I_steer": ("added moment of inertia about the steer axis, carried by the front frame", "kg m^2", r"I_{s}", False),
    "c_steer": ("viscous steer damping between front and rear frame", "N m s/rad", r"c_{s}", False),
    "k_steer": ("steer stiffness between front and rear frame", "N m/rad", r"k_{s}", False),
    "m_arm": ("mass of the rider's arms that moves with the handlebar (both arms)", "kg", r"m_{a}", False),
    "x_grip": ("handlebar grip position, x", "m", r"x_{g}", False),
    "z_grip": ("handlebar grip position, z (down positive)", "m", r"z_{g}", False),
    "b_grip": ("half the distance between the two grips", "m", r"b_{g}", False),
    "k_arm": ("passive arm stiffness about the steer axis (handlebar to upper body)", "N m/rad", r"k_{a}", False),
    "c_arm": ("passive arm damping about the steer axis (handlebar to upper body)", "N m s/rad", r"c_{a}", False),
    "m_u": ("rider upper-body mass (leans about the hip axis)", "kg", r"m_{U}", False),
    "x_u": ("rider upper-body centre of mass, x", "m", r"x_{U}", False),
    "z_u": ("rider upper-body centre of mass, z (down positive)", "m", r"z_{U}", False),
    "IUxx": ("rider upper-body moment of inertia about x through its centre of mass", "kg m^2", r"I_{Uxx}", False),
    "IUxz": ("rider upper-body product of inertia (tensor entry xz)", "kg m^2", r"I_{Uxz}", False),
    "IUzz": ("rider upper-body moment of inertia about z through its centre of mass", "kg m^2", r"I_{Uzz}", False),
    "z_lean": ("height coordinate of the upper-body lean (hip) axis, z (down positive)", "m", r"z_{h}", False),
    "k_lean": ("passive upper-body lean stiffness", "N m/rad", r"k_{l}", False),
    "c_lean": ("passive upper-body lean damping", "N m s/rad", r"c_{l}", False),
    "c_alpha": ("tyre cornering stiffness per unit normal load", "1/rad", r"C_{\alpha}", False),
    "c_gamma": ("tyre camber stiffness per unit normal load", "1/rad", r"C_{\gamma}", False),
    "sigma_t": ("tyre relaxation length", "m", r"\sigma", False),
    "t_p": ("tyre pneumatic trail", "m", r"t_{p}", False),
    # --- State space inputs (derive/state_space.py) ---------------------------------------
    "x_F": (
        "lateral force application point, x (in the frame that carries it, reference configuration)",
        "m",
        r"x_F",
        False,
    ),
    "z_F": ("lateral force application point, z (down positive)", "m", r"z_F", False),
    "H_phiF": ("roll generalized force per unit lateral force (roll moment arm)", "m", r"H_{\phi F}", False),
    "H_deltaF": ("steer generalized force per unit lateral force", "m", r"H_{\delta F}", False),
    # --- Sensitivities (derive/sensitivities.py) ------------------------------------------
    "mBr_sum": (
        "rider mass as the sum of its segment masses (mBr times the sum of the fractions)",
        "kg",
        r"\sum m_i",
        True,
    ),
    "v_weave": ("weave speed: the weave pair crosses the imaginary axis", "m/s", "v_w", True),
    "v_capsize": ("capsize speed: the capsize eigenvalue crosses zero", "m/s", "v_c", True),
}
# --- BicycleParameters Measured-file fields (derive/measured_reduction.py; angles in radians) ---
_MEASURED: dict[str, tuple[str, str, str, bool]] = {
    "dF": ("distance rolled by the front wheel in nF turns", "m", "d_F", True),
    "nF": ("number of front wheel turns rolled over dF", "1", "n_F", True),
    "dR": ("distance rolled by the rear wheel in nR turns", "m", "d_R", True),
    "nR": ("number of rear wheel turns rolled over dR", "1", "n_R", True),
    "lF": ("front wheel compound pendulum length (pivot to wheel centre)", "m", "l_F", True),
    "lR": ("rear wheel compound pendulum length (pivot to wheel centre)", "m", "l_R", True),
    "TcF1": ("front wheel compound pendulum period", "s", "T_{cF}", True),
    "TcR1": ("rear wheel compound pendulum period", "s", "T_{cR}", True),
    "TtF1": ("front wheel torsional pendulum period", "s", "T_{tF}", True),
    "TtR1": ("rear wheel torsional pendulum period", "s", "T_{tR}", True),
    "mP": ("calibration rod mass", "kg", "m_P", True),
    "dP": ("calibration rod diameter", "m", "d_P", True),
    "lP": ("calibration rod length", "m", "l_P", True),
    "TtP1": ("calibration rod torsional pendulum period", "s", "T_{tP}", True),
    "f": ("fork offset (perpendicular distance of the front wheel centre from the steer axis)", "m", "f", False),
    "TcB1": ("rear frame compound pendulum period (about the rear wheel axle)", "s", "T_{cB}", True),
    "TcH1": ("handlebar and fork compound pendulum period (about the front wheel axle)", "s", "T_{cH}", True),
    "whb": ("handlebar width between the two grips", "m", "w_{hb}", True),
    "LhbF": ("distance from the front wheel centre to a handlebar grip", "m", "L_{hbF}", True),
    "LhbR": ("distance from the rear wheel centre to a handlebar grip", "m", "L_{hbR}", True),
}
for _body, _word in {"B": "rear frame", "H": "handlebar and fork"}.items():
    for _i in (1, 2, 3):
        _MEASURED[f"alpha{_body}{_i}"] = (
            f"hanging angle of the {_word} in orientation {_i}: steer axis from the photograph's horizontal",
            "rad",
            rf"\alpha_{{{_body}{_i}}}",
            False,
        )
        _MEASURED[f"a{_body}{_i}"] = (
            f"distance from the pendulum axis to the {_word}'s reference point in orientation {_i}",
            "m",
            f"a_{{{_body}{_i}}}",
            False,
        )
        _MEASURED[f"Tt{_body}{_i}"] = (
            f"torsional pendulum period of the {_word} in orientation {_i}",
            "s",
            f"T_{{t{_body}{_i}}}",
            True,
        )
for _i in (1, 2, 3):
    _MEASURED[f"hang_{_i}"] = (
        f"hanging angle in orientation {_i}: the upward steer axis from the photograph's horizontal",
        "rad",
        rf"\alpha_{{h{_i}}}",
        False,
    )
    _MEASURED[f"off_{_i}"] = (
        f"distance from the pendulum axis to the reference point in orientation {_i}",
        "m",
        f"a_{{h{_i}}}",
        False,
    )
_HEIGHTS = {  # BicycleParameters' frame measured with its steer axis level on a table (see measured_reduction.py)
    "h1": "height h1 of the heights-and-diameters frame measurement (rear wheel offset from the steer axis)",
    "h2": "height h2 of the heights-and-diameters frame measurement (rear wheel offset from the steer axis)",
    "h3": "height h3 of the heights-and-diameters frame measurement (rear wheel offset from the steer axis)",
    "h4": "height h4 of the heights-and-diameters frame measurement (fork offset)",
    "h5": "height h5 of the heights-and-diameters frame measurement (fork offset)",
    "d1": "diameter d1 of the heights-and-diameters frame measurement (rear wheel offset)",
    "d2": "diameter d2 of the heights-and-diameters frame measurement (rear offset, axis distance)",
    "d3": "diameter d3 of the heights-and-diameters frame measurement (fork offset, axis distance)",
    "d4": "diameter d4 of the heights-and-diameters frame measurement (fork offset)",
    "d": "distance d of the heights-and-diameters frame measurement (along the steer axis)",
    "h6": "height of the top of the front axle, steer axis level (fork and handlebar measured apart)",
    "h7": "height of the top of the handlebar reference circle, steer axis level",
    "d5": "front axle diameter, for the handlebar reference point",
    "d6": "handlebar reference circle diameter",
    "l": "outer distance from the front axle to the handlebar reference circle",
}
for _name, _description in _HEIGHTS.items():
    _MEASURED[_name] = (_description, "m", _name, True)
_TABLE.update(_MEASURED)
# --- Raw pendulum measurements as inputs of the estimate chain (bikerider.uncertainty.stages) ---
for _body, _word in {"Bf": "rear frame", "H": "handlebar/fork"}.items():
    for _i in (1, 2, 3):
        _TABLE[f"T_{_body}{_i}"] = (f"{_word} torsional period, orientation {_i}", "s", f"T_{{{_body},{_i}}}", True)
        _TABLE[f"alpha_{_body}{_i}"] = (
            f"{_word} pendulum axis angle, orientation {_i}",
            "rad",
            rf"\alpha_{{{_body},{_i}}}",
            False,
        )
for _w, _wheel in {"R": "rear", "F": "front"}.items():
    _TABLE[f"T_{_w}xx"] = (f"{_wheel} wheel torsional period about a diameter", "s", f"T_{{{_w}xx}}", True)
    _TABLE[f"T_{_w}yy"] = (f"{_wheel} wheel compound pendulum period", "s", f"T_{{{_w}yy}}", True)
    _TABLE[f"l_p{_w}"] = (f"{_wheel} wheel compound pendulum length", "m", f"l_{{p{_w}}}", True)
for _k in range(5):
    _TABLE[f"a{_k}"] = (
        f"coefficient of s^{_k} in the characteristic polynomial",
        f"kg^2 m^4 s^{_k - 4}",
        f"a_{_k}",
        False,
    )
for _k, _where in {
    5: "pedal axis",
    13: "hip",
    14: "knee",
    15: "shoulder line",
    19: "hand",
    23: "elbow",
    25: "head centre",
}.items():
    for _axis in "XZ":
        _TABLE[f"r{_axis}{_k}"] = (
            f"rider grid point {_k} ({_where}), {_axis} coordinate",
            "m",
            f"r_{{{_axis}{_k}}}",
            False,
        )

_MATRIX_UNITS = {
    "M": ("mass matrix", ("kg m^2", "kg m^2", "kg m^2", "kg m^2")),
    "C1": ("speed-proportional damping-like matrix", ("kg m", "kg m", "kg m", "kg m")),
    "K0": ("gravity-proportional stiffness matrix, per unit g", ("kg m", "kg m", "kg m", "kg m")),
    "K2": ("speed-squared-proportional stiffness matrix", ("kg", "kg", "kg", "kg")),
}
_COORDS = ("phi", "delta")
_COORD_WORDS = {"phi": "roll", "delta": "steer"}
for _m, (_what, _units) in _MATRIX_UNITS.items():
    for _i, _a in enumerate(_COORDS):
        for _j, _b in enumerate(_COORDS):
            _TABLE[f"{_m}_{_a}{_b}"] = (
                f"{_what}, entry ({_COORD_WORDS[_a]} equation, {_COORD_WORDS[_b]} coordinate)",
                _units[2 * _i + _j],
                rf"{_m}_{{\{_a}\{_b}}}",
                False,
            )


def describe(name: str) -> SymbolInfo:
    """Return the table entry of ``name``; raise ``KeyError`` naming it when absent."""
    try:
        description, unit, latex, positive = _TABLE[name]
    except KeyError:
        raise KeyError(f"symbol {name!r} has no entry in derive/symbols.py") from None
    return SymbolInfo(name, description, unit, latex, positive)


@cache
def sym(name: str) -> sp.Symbol:
    """The SymPy symbol of ``name`` (real; positive where the table says so)."""
    info = describe(name)
    if info.positive:
        return sp.Symbol(name, positive=True)
    return sp.Symbol(name, real=True)


def syms(names: str) -> list[sp.Symbol]:
    """Symbols for a whitespace-separated list of names, in that order."""
    return [sym(n) for n in names.split()]


def all_symbols() -> dict[str, SymbolInfo]:
    """Every table entry, by name, in table order."""
    return {name: describe(name) for name in _TABLE}


def latex_names() -> dict[sp.Symbol, str]:
    """Mapping for ``sympy.latex(..., symbol_names=...)``."""
    return {sym(n): describe(n).latex for n in _TABLE}


BENCHMARK_NAMES = (
    "w c lam g rR mR IRxx IRyy xB zB mB IBxx IByy IBzz IBxz xH zH mH IHxx IHyy IHzz IHxz rF mF IFxx IFyy"
).split()
"""The benchmark parameters in Meijaard et al. (2007) Table 1 order."""
