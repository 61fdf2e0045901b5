"""Closed-form sensitivities of the estimate chain, stage by stage.

The chain from measurements to critical speeds is a composition of stages::

    pendulum periods, angles, k_t  --(Eqs. 1, 6, 7)-->  body inertias
    geometry, rider lengths        --(Table 10)------>  seven grid points (x, z)
    grid points, rider sizes       --(Eqs. 8-14)----->  rider mass, centre of mass, inertia
    rear frame, rider              --(Eqs. 15-16)---->  rear body B
    benchmark parameters           --(Meijaard A)---->  M, C1, K0, K2
    matrix entries, g, v           ----------------->  characteristic coefficients a4..a0
    matrix entries, g              --(implicit)------>  weave and capsize speeds

Differentiating the rider stage as one expression is too slow (its tree has about 126 000
operations; SymPy needs about 100 s for its 238 partial derivatives).  Each stage is instead
differentiated on its own and the runtime multiplies the stage Jacobians (the chain rule).  The
rider stage is split at the seven grid points its segments use (5, 13, 14, 15, 19, 23, 25; the
others are their mirror images in y or are not used), whose x and z coordinates are symbols
``rX<k>``, ``rZ<k>`` of the symbol table.

Critical speeds are implicit: a speed ``v`` is a root of a condition ``F(e, g, v) = 0`` with ``e``
the sixteen matrix entries, so ``dv/de = -(dF/de) / (dF/dv)`` at the root.  Capsize:
``F = det(g K0 + v^2 K2)``.  Weave: ``F = (a3 a2 a1 - a4 a1^2 - a0 a3^2) / v^2``, the third
Hurwitz determinant over ``v^2`` (``a1`` and ``a3`` are odd in ``v``).

Every Jacobian is emitted as a NumPy function returning ``(..., n_out, n_in)``, rows in output
order and columns in argument order.  The stage expressions themselves are also emitted, as
``srepr`` strings in ``EXPRESSIONS``, so the runtime can differentiate and print them with SymPy
without importing ``derive``; the stages' names, inputs, outputs and functions go into the
manifest (``generated/manifest.py``).
"""

from __future__ import annotations

import itertools
from functools import cache

import sympy as sp

from derive import benchmark_model, pendulum, rider_model
from derive.codegen import GeneratedFunction, GeneratedModule, Output, Stage, jacobian, stage_functions
from derive.combination import FRAME_ARGS, RIDER_BODY_ARGS, rear_body
from derive.symbols import sym, syms

GRID_POINTS = (5, 13, 14, 15, 19, 23, 25)
"""Grid points whose x and z the rider's segments use (Table 10 numbering)."""
MIRRORS = {20: 19, 21: 15, 22: 15, 24: 23, 26: 5, 27: 5, 28: 14, 29: 14, 30: 13, 31: 13}
"""Grid points with the same x and z as another one (they differ in y only)."""

USED_GEOMETRY = "h_bb l_cs l_f rF l_hb lam_ht rR l_sp lam_st l_st l_s c w"
"""Table 1 measurements the chain uses (the hub widths place no segment)."""
REAR_BODY_OUTPUTS = "mB xB zB IBxx IByy IBzz IBxz"
COEFFICIENT_NAMES = "a4 a3 a2 a1 a0"


BASE_POINTS = (5, 13, 15, 19, 25)
"""Grid points given explicitly by geometry and rider placement; 14 and 23 are closures."""
CLOSURES = {"knee": (14, 5, 13, "l_ll", "l_ul", +1), "elbow": (23, 19, 15, "l_la", "l_ua", -1)}
"""Closure stages: joint point, distal end, proximal end, distal length, proximal length, normal sign
(as in ``rider_model.grid_points``; the elbow's proximal end 21 has the x and z of 15)."""


@cache
def _grid_points() -> list[sp.Matrix]:
    return rider_model.grid_points()[0]


def point_symbols(k: int) -> list[sp.Symbol]:
    return [sym(f"rX{k}"), sym(f"rZ{k}")]


def grid_coordinates() -> tuple[list[sp.Symbol], list[sp.Symbol], sp.Matrix]:
    """x and z of the explicit grid points as functions of geometry and rider placement."""
    points = _grid_points()
    for mirror, base in MIRRORS.items():
        for axis in (0, 2):
            if sp.expand(points[mirror - 1][axis] - points[base - 1][axis]) != 0:
                raise RuntimeError(f"grid point {mirror} is not the mirror of {base}")
    args = syms(USED_GEOMETRY) + [s for s in syms(rider_model.RIDER_ARGS) if s.name in ("l_to", "lam_fl", "c_h")]
    outputs = [s for k in BASE_POINTS for s in point_symbols(k)]
    coords = sp.Matrix([points[k - 1][axis] for k in BASE_POINTS for axis in (0, 2)])
    extra = coords.free_symbols - set(args)
    if extra:
        raise RuntimeError(f"grid coordinates use {sorted(map(str, extra))}")
    return args, outputs, coords


def closure(name: str) -> tuple[list[sp.Symbol], list[sp.Symbol], sp.Matrix]:
    """One limb closure (knee or elbow) from the coordinates of the limb's ends and its lengths."""
    joint, distal, proximal, la, lb, sign = CLOSURES[name]
    (xa, za), (xb, zb) = point_symbols(distal), point_symbols(proximal)
    solved = rider_model.solve_closure(sp.Matrix([xa, 0, za]), sp.Matrix([xb, 0, zb]), sym(la), sym(lb), sign)
    args = [xa, za, xb, zb, sym(la), sym(lb)]
    return args, point_symbols(joint), sp.Matrix([solved.joint[0], solved.joint[2]])


def _check_split(coords: sp.Matrix) -> None:
    """The staged grid points equal rider_model.grid_points at a test point (guards the split)."""
    points = _grid_points()
    point = {
        s: sp.Float(v, 30)
        for s, v in zip(
            syms(USED_GEOMETRY),
            (
                "0.295",
                "0.46",
                "0.455",
                "0.342",
                "0.19",
                "1.1955",
                "0.342",
                "0.24",
                "1.1955",
                "0.53",
                "0.25",
                "0.055",
                "1.12",
            ),
        )
    }
    point.update(
        {
            s: sp.Float(v, 30)
            for s, v in zip(
                syms(rider_model.RIDER_ARGS), ("0.26", "0.33", "0.46", "0.44", "0.48", "0.28", "0.46", "1.4469", "0.58")
            )
        }
    )
    values = {s: e.xreplace(point) for s, e in zip([s for k in BASE_POINTS for s in point_symbols(k)], coords)}
    values.update(point)
    for name in CLOSURES:
        args, outs, exprs = closure(name)
        values.update({s: e.xreplace(values) for s, e in zip(outs, exprs)})
    for k in GRID_POINTS:
        for s, axis in zip(point_symbols(k), (0, 2)):
            staged, direct = sp.N(values[s], 30), sp.N(points[k - 1][axis].xreplace(point), 30)
            if not abs(staged - direct) < 1e-20:
                raise RuntimeError(f"staged grid point {k} differs from rider_model.grid_points")


def _symbolic_points() -> list[sp.Matrix]:
    """The 31 grid points with the x and z of :data:`GRID_POINTS` (and mirrors) as symbols."""
    points = _grid_points()
    by_point = {k: tuple(point_symbols(k)) for k in GRID_POINTS}
    by_point.update({m: by_point[b] for m, b in MIRRORS.items()})
    replaced = list(points)
    for k, (x, z) in by_point.items():
        replaced[k - 1] = sp.Matrix([x, points[k - 1][1], z])
    return replaced


def _rider_args() -> list[sp.Symbol]:
    return (
        [s for k in GRID_POINTS for s in point_symbols(k)]
        + syms(rider_model.RIDER_ARGS)
        + syms(rider_model.SEGMENT_ARGS)
    )


def rider_com() -> tuple[list[sp.Symbol], sp.Matrix]:
    """Rider mass and centre of mass (Eq. 8) with the grid points as symbols."""
    mass, com, _ = rider_model.rider_mass_properties(_symbolic_points())
    if sp.simplify(com[1]) != 0:
        raise RuntimeError("the rider's centre of mass is off the plane of symmetry")
    args = _rider_args()
    outputs = sp.Matrix([mass, com[0], com[2]])
    extra = outputs.free_symbols - set(args)
    if extra:
        raise RuntimeError(f"the rider's segments use grid points beyond {GRID_POINTS}: {sorted(map(str, extra))}")
    return args, outputs


def rider_inertia() -> tuple[list[sp.Symbol], sp.Matrix]:
    """Rider inertia about its centre of mass (Eqs. 11-14), the centre ``(xBr, 0, zBr)`` a symbol.

    The same sum as ``rider_model.rider_mass_properties`` with the centre of mass left as an
    input: the chain rule then adds its dependence through ``rider_com``.
    """
    points = _symbolic_points()
    com = sp.Matrix([sym("xBr"), 0, sym("zBr")])
    inertia = sp.zeros(3, 3)
    for s in rider_model.segments():
        centre = (points[s.start - 1] + points[s.end - 1]) / 2
        local = s.local_inertia
        if s.shape != "sphere":
            R = rider_model.rotation(points[s.end - 1] - points[s.start - 1], s.length)
            local = R * local * R.T
        inertia += local + rider_model.parallel_axis(s.mass, centre - com)
    args = _rider_args() + syms("xBr zBr")
    outputs = sp.Matrix([inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 2]])
    extra = outputs.free_symbols - set(args)
    if extra:
        raise RuntimeError(f"the rider's segments use grid points beyond {GRID_POINTS}: {sorted(map(str, extra))}")
    return args, outputs


def rear_body_outputs() -> tuple[list[sp.Symbol], sp.Matrix]:
    """Rear body B (Eqs. 15-16) from the rear frame and the rider, as a column."""
    mB, xB, zB, IB = rear_body()
    return syms(FRAME_ARGS) + syms(RIDER_BODY_ARGS), sp.Matrix([mB, xB, zB, IB[0, 0], IB[1, 1], IB[2, 2], IB[0, 2]])


def canonical_outputs() -> tuple[list[sp.Symbol], sp.Matrix]:
    """The sixteen matrix entries (M, C1, K0, K2, row by row) from the benchmark parameters."""
    mats = benchmark_model.canonical_matrices()
    column = sp.Matrix([e for name in benchmark_model.MATRIX_NAMES for e in mats[name]])
    return syms(benchmark_model.CANONICAL_ARGS), column


def capsize_condition() -> sp.Expr:
    """``det(g K0 + v^2 K2)``: zero at the capsize speed."""
    K0, K2 = benchmark_model.matrix_symbols("K0"), benchmark_model.matrix_symbols("K2")
    return (sym("g") * K0 + sym("v") ** 2 * K2).det(method="berkowitz")


def weave_condition_in_coefficients() -> sp.Expr:
    """Third Hurwitz determinant over ``v^2`` in the coefficient symbols ``a4..a0``."""
    a4, a3, a2, a1, a0 = syms(COEFFICIENT_NAMES)
    return (a3 * a2 * a1 - a4 * a1**2 - a0 * a3**2) / sym("v") ** 2


def weave_condition() -> sp.Expr:
    """The weave condition in matrix entries, ``g`` and ``v`` (``a1``, ``a3`` divided by ``v``)."""
    v = sym("v")
    a4, a3, a2, a1, a0 = benchmark_model.characteristic_coefficients()
    a3v, a1v = sp.expand(a3 / v), sp.expand(a1 / v)
    if a3v.has(sp.Pow(v, -1)) or a1v.has(sp.Pow(v, -1)):
        raise RuntimeError("a1 or a3 is not odd in v")
    return a3v * a2 * a1v - a4 * a1v**2 - a0 * a3v**2


def speed_gradient(condition: sp.Expr) -> sp.Matrix:
    """``dv/d[entries, g] = -(dF/d[entries, g]) / (dF/dv)`` for a condition ``F = 0``."""
    v = sym("v")
    args = benchmark_model.matrix_entry_args() + [sym("g")]
    dF_dv = sp.Symbol("_dF_dv")
    grad = sp.Matrix([[-condition.diff(a) / dF_dv for a in args]])
    return grad.subs(dF_dv, condition.diff(v))


def three_orientation_solution() -> sp.Matrix:
    """Eq. 6 for three orientations as adjugate over determinant (``pendulum`` simplifies further;
    this form is equal and about three times quicker to build)."""
    angles = syms("alpha_1 alpha_2 alpha_3")
    A = sp.Matrix.vstack(*(pendulum.orientation_row(a) for a in angles))
    J = sp.Matrix([pendulum.torsional_inertia().subs(sym("T"), T) for T in syms("T_1 T_2 T_3")])
    det = sp.factor(sp.trigsimp(A.det()))
    return A.adjugate() * J / det


def stage_table() -> dict[str, dict[str, list]]:
    """Every stage: its inputs, outputs and output expressions (SymPy objects), in chain order."""
    k_t, T, m_p, g, l_p, v = syms("k_t T m_p g l_p v")
    solution = three_orientation_solution()
    grid_args, grid_outputs, coords = grid_coordinates()
    _check_split(coords)
    com_args, com_outputs = rider_com()
    inertia_args, inertia_outputs = rider_inertia()
    body_args, body_outputs = rear_body_outputs()
    canon_args, canon_outputs = canonical_outputs()
    entries = benchmark_model.matrix_entry_args()
    table: dict[str, dict[str, list]] = {
        "three_orientations": {
            "inputs": [k_t, *syms("T_1 T_2 T_3 alpha_1 alpha_2 alpha_3")],
            "outputs": syms("Ixx Ixz Izz"),
            "exprs": list(solution),
        },
        "torsional": {"inputs": [k_t, T], "outputs": [sp.Symbol("J")], "exprs": [pendulum.torsional_inertia()]},
        "compound": {"inputs": [T, m_p, g, l_p], "outputs": [sp.Symbol("Iyy")], "exprs": [pendulum.compound_inertia()]},
        "grid": {"inputs": grid_args, "outputs": grid_outputs, "exprs": list(coords)},
    }
    for name in CLOSURES:
        args, outs, exprs = closure(name)
        table[name] = {"inputs": args, "outputs": outs, "exprs": list(exprs)}
    table.update(
        {
            "rider_com": {"inputs": com_args, "outputs": syms("mBr_sum xBr zBr"), "exprs": list(com_outputs)},
            "rider_inertia": {
                "inputs": inertia_args,
                "outputs": syms("IBrxx IBryy IBrzz IBrxz"),
                "exprs": list(inertia_outputs),
            },
            "rear_body": {"inputs": body_args, "outputs": syms(REAR_BODY_OUTPUTS), "exprs": list(body_outputs)},
            "steer_axis": {"inputs": [sym("lam_ht")], "outputs": [sym("lam")], "exprs": [sp.pi / 2 - sym("lam_ht")]},
            "canonical": {"inputs": canon_args, "outputs": entries, "exprs": list(canon_outputs)},
            "characteristic": {
                "inputs": entries + [g, v],
                "outputs": syms(COEFFICIENT_NAMES),
                "exprs": benchmark_model.characteristic_coefficients(),
            },
            "capsize_condition": {
                "inputs": entries + [g, v],
                "outputs": [sym("v_capsize")],
                "exprs": [capsize_condition()],
            },
            "weave_condition": {
                "inputs": syms(COEFFICIENT_NAMES) + [v],
                "outputs": [sym("v_weave")],
                "exprs": [weave_condition_in_coefficients()],
            },
        }
    )
    return table


def _stages_source(stages: dict[str, dict[str, list]]) -> str:
    """``EXPRESSIONS = {...}``: names and ``srepr`` strings, deterministic text."""
    lines = [
        "#: Stage expressions for the runtime's symbolic sensitivities (keys: the manifest's stage",
        "#: kinds): stage -> (input names, output names, srepr of each output in the inputs).",
        "#: A condition (capsize_condition, weave_condition) gives the expression F whose root in v",
        "#: is the speed named as its output.",
        "EXPRESSIONS = {",
    ]
    for name, stage in stages.items():
        lines.append(f"    {name!r}: (")
        lines.append(f"        {tuple(s.name for s in stage['inputs'])!r},")
        lines.append(f"        {tuple(s.name for s in stage['outputs'])!r},")
        lines.append("        (")
        lines.extend(f"            {sp.srepr(expr)!r}," for expr in stage["exprs"])
        lines.append("        ),")
        lines.append("    ),")
    lines.append("}")
    return "\n".join(lines)


def _names(symbols: list[sp.Symbol]) -> str:
    return ", ".join(s.name for s in symbols)


def _stage_jacobian(
    name: str, stage: dict[str, list], summary: str, notes: str = "", scalar: bool = False
) -> GeneratedFunction:
    J = jacobian(sp.Matrix(stage["exprs"]), stage["inputs"])
    doc = f"d[{_names(stage['outputs'])}]/d[{_names(stage['inputs'])}] [SI]"
    return GeneratedFunction(
        f"{name}_jacobian",
        stage["inputs"],
        [Output("jacobian", J, doc, sparse=True)],
        summary,
        notes=notes,
        scalar=scalar,
    )


def build() -> GeneratedModule:
    stages = stage_table()
    g, v = syms("g v")
    entries = benchmark_model.matrix_entry_args()
    grid = stages["grid"]
    functions = [
        _stage_jacobian(
            "three_orientations",
            stages["three_orientations"],
            "Jacobian of Eq. 6 solved for three orientations (benchmark-convention Ixz).",
        ),
        _stage_jacobian("torsional", stages["torsional"], "Jacobian of Eq. 1, J = k T^2 / (4 pi^2).", scalar=True),
        _stage_jacobian(
            "compound", stages["compound"], "Jacobian of Eq. 7, Iyy = (T / 2 pi)^2 m g l - m l^2.", scalar=True
        ),
        GeneratedFunction(
            "grid_coordinates",
            grid["inputs"],
            [Output("coordinates", sp.Matrix(grid["exprs"]), f"[{_names(grid['outputs'])}] [m]", vector=True)],
            "x and z of the grid points given explicitly by geometry and placement (Table 10).",
        ),
        _stage_jacobian("grid", grid, "Jacobian of the explicit grid point coordinates."),
    ]
    for name in CLOSURES:
        stage = stages[name]
        functions += [
            GeneratedFunction(
                name,
                stage["inputs"],
                [Output("coordinates", sp.Matrix(stage["exprs"]), f"[{_names(stage['outputs'])}] [m]", vector=True)],
                f"The {name} (natural branch) from the ends of its limb and the limb's two lengths.",
                notes="NaN where the limb cannot span the distance between its ends.",
            ),
            _stage_jacobian(name, stage, f"Jacobian of the {name} closure."),
        ]
    for name, what in (
        ("rider_com", "Rider mass and centre of mass [mBr_sum, xBr, zBr] (Eq. 8)"),
        ("rider_inertia", "Rider inertia [IBrxx, IBryy, IBrzz, IBrxz] about (xBr, 0, zBr) (Eqs. 11-14)"),
    ):
        stage = stages[name]
        functions += [
            GeneratedFunction(
                name,
                stage["inputs"],
                [Output("properties", sp.Matrix(stage["exprs"]), f"[{_names(stage['outputs'])}] [SI]", vector=True)],
                f"{what} from grid point coordinates.",
            ),
            _stage_jacobian(name, stage, f"Jacobian of {name} at fixed grid points."),
        ]
    functions += [
        _stage_jacobian(
            "rear_body",
            stages["rear_body"],
            "Jacobian of the rear body (Eqs. 15-16).",
            notes="The argument mBr is the rider's mass as its segments sum it (mBr_sum).",
            scalar=True,
        ),  # merging one lumped rider (bikerider.bicycle.to_benchmark)
        _stage_jacobian(
            "canonical",
            stages["canonical"],
            "Jacobian of the canonical matrix entries (Meijaard et al. 2007, Appendix A).",
        ),
        _stage_jacobian(
            "characteristic",
            stages["characteristic"],
            "Jacobian of the characteristic polynomial's coefficients [a4, a3, a2, a1, a0].",
        ),
        GeneratedFunction(
            "capsize_speed_gradient",
            entries + [g, v],
            [
                Output(
                    "gradient",
                    speed_gradient(capsize_condition()).T,
                    "d v_capsize / d[matrix entries, g] [SI]",
                    vector=True,
                )
            ],
            "Implicit derivative of the capsize speed: -(dF/dp)/(dF/dv), F = det(g K0 + v^2 K2).",
            notes="Evaluate at v = the capsize speed; F must have a simple root there (dF/dv != 0).",
        ),
        GeneratedFunction(
            "weave_speed_gradient",
            entries + [g, v],
            [
                Output(
                    "gradient",
                    speed_gradient(weave_condition()).T,
                    "d v_weave / d[matrix entries, g] [SI]",
                    vector=True,
                )
            ],
            "Implicit derivative of the weave speed: -(dF/dp)/(dF/dv), F the third Hurwitz determinant / v^2.",
            notes="Evaluate at v = the weave speed; F must have a simple root there (dF/dv != 0).",
        ),
        GeneratedFunction(
            "state_matrix_jacobian",
            entries + [g, v],
            [
                Output(
                    "jacobian",
                    jacobian(sp.Matrix(list(benchmark_model.state_matrix())), entries + [g, v]),
                    "d[A entries, row by row]/d[matrix entries, g, v] [SI]",
                )
            ],
            "Jacobian of the state matrix A(v) (x = [phi, delta, phi', delta']), for eigenvalue sensitivities.",
        ),
    ]
    steer_functions, steer_stage = stage_functions(
        "sensitivities",
        "steer_axis",
        stages["steer_axis"]["inputs"],
        {"lam": stages["steer_axis"]["exprs"][0]},
        "Steer axis tilt from the head tube angle, lam = pi/2 - lam_ht.",
    )
    functions += steer_functions
    return GeneratedModule(
        name="sensitivities",
        summary="Closed-form stage Jacobians of the estimate chain and the implicit critical-speed gradients.",
        description=__doc__.strip(),
        functions=functions,
        extra_source=_stages_source(stages),
        stages=[*chain_stages(stages), steer_stage],
    )


def _entries(output: str, shape: tuple[int, ...]) -> list[tuple[str, tuple[int, ...]]]:
    """Every entry of a value function's output, row by row."""
    if not shape:
        return [(output, ())]
    return [(output, index) for index in itertools.product(*(range(n) for n in shape))]


_VALUES: dict[str, tuple[str, list[tuple[str, tuple[int, ...]]]]] = {
    "three_orientations": ("pendulum.inertia_from_three_orientations", _entries("inertia", (3,))),
    "torsional": ("pendulum.torsional_inertia", _entries("J", ())),
    "compound": ("pendulum.compound_inertia", _entries("Iyy", ())),
    "grid": ("sensitivities.grid_coordinates", _entries("coordinates", (2 * len(BASE_POINTS),))),
    "knee": ("sensitivities.knee", _entries("coordinates", (2,))),
    "elbow": ("sensitivities.elbow", _entries("coordinates", (2,))),
    "rider_com": ("sensitivities.rider_com", _entries("properties", (3,))),
    "rider_inertia": ("sensitivities.rider_inertia", _entries("properties", (4,))),
    "rear_body": (
        "combination.rear_body",
        [("mB", ()), ("xB", ()), ("zB", ()), ("IB", (0, 0)), ("IB", (1, 1)), ("IB", (2, 2)), ("IB", (0, 2))],
    ),
    "canonical": (
        "benchmark_model.canonical_matrices",
        [e for name in benchmark_model.MATRIX_NAMES for e in _entries(name, (2, 2))],
    ),
    "characteristic": ("benchmark_model.characteristic_coefficients", _entries("coefficients", (5,))),
}
"""The value function of each stage of the chain and where each output sits in what it returns
(``derive.extras`` checks every pick against the stage's expression)."""
_CHECKS = {"three_orientations": [("determinant", "determinant", ())]}


def chain_stages(stages: dict[str, dict[str, list]]) -> list[Stage]:
    """The stages of the estimate chain, for the manifest (the conditions are not stages: the
    runtime solves them for the speeds and differentiates them implicitly)."""
    out = []
    for name, (value, picks) in _VALUES.items():
        stage = stages[name]
        out.append(
            Stage(
                name,
                stage["inputs"],
                [s.name for s in stage["outputs"]],
                value,
                picks,
                f"sensitivities.{name}_jacobian",
                _CHECKS.get(name, []),
                list(stage["exprs"]),
            )
        )
    return out
