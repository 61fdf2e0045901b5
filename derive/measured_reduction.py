"""A BicycleParameters Measured file reduced to the bicycle's bodies, stage by stage.

Each step of the reduction is written once here and emitted in a stage kind: a value function and
its Jacobian, composed at run time by the one uncertainty engine (``bikerider.engine``) through the
chain rule, so every output gets exact first-order uncertainties and no formula is written twice.
The runtime (``bikerider.bicycle.raw_measurements``) picks the stages a file's layout needs:

* ``frame_from_wheelbase``: the wheel radii ``r = d / (2 pi n)`` from the distance each rolled in
  ``n`` turns, the steer axis tilt ``lam = pi/2 - lam_ht``, the trail ``c = (rF sin(lam) - f) /
  cos(lam)`` (Meijaard et al. 2007 geometry) and the wheel centres ``(0, -rR)`` and ``(w, -rF)``,
  the reference points of the hung bodies;
* ``frame_from_heights``: the same from the frame measured with its steer axis level on a table
  (heights ``h1..h5``, diameters ``d1..d4``, distance ``d``), see below;
* ``wheels``: the torsional pendulum's stiffness from a calibration rod,
  ``k_t = 4 pi^2 I_rod / TtP1^2`` with ``I_rod = mP (3 (dP/2)^2 + lP^2) / 12``, and each wheel's
  ``I_xx`` from its torsional period (Eq. 1) and ``I_yy`` from its compound one (Eq. 7);
* ``handlebar_reference``: the handlebar reference point of a handlebar measured apart from its
  fork (``h6, h7, d5, d6, l``): ``l2`` up the steer axis and ``l1`` forward of it from the front
  wheel centre;
* ``hung_body_3``: a body hung in three orientations.  The axis of orientation ``i`` is at
  ``beta_i = lam - hang_i`` and gives the line ``sin(beta_i) x + cos(beta_i) z = sin(beta_i) x_ref
  + cos(beta_i) z_ref - off_i`` (reference point ``(x_ref, z_ref)``); the centre of mass is the
  least-squares point of the three lines (normal equations by Cramer's rule) and ``[Ixx, Ixz,
  Izz]`` is Eq. 6 solved in closed form.  The checks are each line's signed distance from the
  point, the determinant of the lines' normal equations (0 for parallel lines) and Eq. 6's;
* ``hanging_line`` and ``hung_orientation_equation``: one orientation's line and its row of Eq. 6,
  the rows of the numeric least-squares stage (``bikerider.engine.LeastSquaresStage``) that takes
  a body hung in more than three orientations, or any body when BicycleParameters' pairwise-mean
  centre of mass is asked for;
* ``compound_about_point``: Eq. 7 for a body swung about its reference point;
* ``seating``: the grip where the circles ``sqrt(LhbF^2 - (whb/2)^2)`` about the front wheel
  centre and ``sqrt(LhbR^2 - (whb/2)^2)`` about the rear one meet above the wheel centres, then the
  paper's equivalent stem and handlebar lengths (``bikerider.bicycle.raw_measurements`` explains why).

Steps are grouped into stages by what a layout needs together (one call per stage is what one
bicycle at a time costs).

Heights and diameters.  BicycleParameters forms the perpendicular distances of the wheel centres
from the steer axis: the rear offset ``a = h1 + h2 - h3 + d1/2 - d2/2``, the fork offset
``b = h4 - d3/2 - h5 + d4/2`` and the distance along the steer axis between the feet of the two
perpendiculars ``e = sqrt(D^2 - (a - b)^2)`` with ``D = d + (d2 + d3)/2``.  With the wheel centres
``a`` behind and ``b`` ahead of the axis, projecting the centre-to-centre vector ``(w, rR - rF)``
on the axis's forward normal and on the axis gives ``a + b = w cos(lam) + (rF - rR) sin(lam)`` and
``e = w sin(lam) + (rR - rF) cos(lam)``, hence ``(a + b) sin(lam) - e cos(lam) = rF - rR``, solved in
closed form (BicycleParameters iterates): ``lam = atan2(e, a + b) + asin((rF - rR) / hypot(a + b,
e))``, the root near ``atan2(e, a + b)``, which is the tilt for equal wheels; then
``w = (a + b) cos(lam) + e sin(lam)`` and the fork offset is ``b``.

Every Jacobian is exact.  Where a stage has named intermediate quantities (the hung bodies, the
seating), its derivatives are accumulated by the chain rule through them (:class:`ForwardChain`)
rather than taken of one large substituted expression; common-subexpression elimination then
shares the intermediates between the values and the derivatives.
"""

from __future__ import annotations

import sympy as sp

from derive import pendulum
from derive.codegen import GeneratedFunction, GeneratedModule, Stage, stage_functions
from derive.symbols import sym, syms

MODULE = "measured_reduction"


class ForwardChain:
    """Named intermediate quantities and their derivatives with respect to the inputs.

    Each :meth:`define` introduces a symbol for an expression of inputs and earlier intermediates;
    its derivative with respect to input ``x`` is ``sum_s d expr / d s * d s / d x`` over the
    symbols ``s`` the expression uses (taken in name order, never in ``free_symbols`` order).
    :meth:`expand` substitutes every intermediate back, so the results depend on the inputs only.
    """

    def __init__(self, inputs: list[sp.Symbol]):
        self.inputs = list(inputs)
        self.gradient: dict[sp.Symbol, dict[sp.Symbol, sp.Expr]] = {x: {x: sp.Integer(1)} for x in inputs}
        self.definitions: list[tuple[sp.Symbol, sp.Expr]] = []
        self._expanded: dict[sp.Symbol, sp.Expr] = {}

    def define(self, name: str, expr: sp.Expr) -> sp.Symbol:
        symbol = sp.Symbol(f"_{name}", real=True)
        gradient: dict[sp.Symbol, sp.Expr] = {}
        for used in sorted(expr.free_symbols, key=lambda s: s.name):
            partial = sp.diff(expr, used)
            if partial == 0:
                continue
            for x, d in self.gradient[used].items():
                gradient[x] = gradient.get(x, sp.Integer(0)) + partial * d
        self.gradient[symbol] = gradient
        self.definitions.append((symbol, expr))
        return symbol

    def expand(self, expr: sp.Expr) -> sp.Expr:
        """``expr`` with every intermediate replaced by its definition (inputs only)."""
        if len(self._expanded) < len(self.definitions):  # each definition once, in order
            for symbol, definition in self.definitions[len(self._expanded) :]:
                self._expanded[symbol] = definition.xreplace(self._expanded)
        return sp.sympify(expr).xreplace(self._expanded)

    def jacobian(self, outputs: list[sp.Symbol]) -> sp.Matrix:
        """``d outputs / d inputs``, every entry in the inputs only."""
        return sp.Matrix(
            len(outputs),
            len(self.inputs),
            lambda i, j: self.expand(self.gradient[outputs[i]].get(self.inputs[j], sp.Integer(0))),
        )

    def stage(
        self, name: str, outputs: dict[str, sp.Symbol], summary: str, checks: dict[str, sp.Symbol] | None = None
    ) -> tuple[list[GeneratedFunction], Stage]:
        """The stage functions of ``outputs`` (intermediate symbols) with the chain's Jacobian."""
        values = {key: self.expand(symbol) for key, symbol in outputs.items()}
        check_values = {key: self.expand(symbol) for key, symbol in (checks or {}).items()}
        return stage_functions(
            MODULE, name, self.inputs, values, summary, check_values, derivatives=self.jacobian(list(outputs.values()))
        )


def _rolled_radius(d: sp.Expr, n: sp.Expr) -> sp.Expr:
    """A wheel's radius from the distance it rolled in ``n`` turns."""
    return d / (2 * sp.pi * n)


def _frame(chain: ForwardChain, rR, rF, lam, w, f) -> dict[str, sp.Symbol]:
    """The trail (Meijaard et al. 2007 geometry) and the wheel centres, the reference points of
    the hung bodies."""
    return {
        "c": chain.define("c", (rF * sp.sin(lam) - f) / sp.cos(lam)),
        "x_rear": chain.define("x_rear", sp.Integer(0)),
        "z_rear": chain.define("z_rear", -rR),
        "x_front": chain.define("x_front", w),
        "z_front": chain.define("z_front", -rF),
    }


def define_frame_from_wheelbase(chain: ForwardChain, dR, nR, dF, nF, w, lam_ht, f) -> dict[str, sp.Symbol]:
    rR, rF = chain.define("rR", _rolled_radius(dR, nR)), chain.define("rF", _rolled_radius(dF, nF))
    lam = chain.define("lam", sp.pi / 2 - lam_ht)
    return {"rR": rR, "rF": rF, "lam": lam, **_frame(chain, rR, rF, lam, w, f)}


def frame_from_wheelbase() -> tuple[list[GeneratedFunction], Stage]:
    inputs = syms("dR nR dF nF w lam_ht f")
    chain = ForwardChain(inputs)
    return chain.stage(
        "frame_from_wheelbase",
        define_frame_from_wheelbase(chain, *inputs),
        "Wheel radii, steer axis tilt, trail and wheel centres from wheelbase, head tube angle and fork offset.",
    )


def frame_from_heights() -> tuple[list[GeneratedFunction], Stage]:
    dR, nR, dF, nF, h1, h2, h3, h4, h5, d1, d2, d3, d4, d = syms("dR nR dF nF h1 h2 h3 h4 h5 d1 d2 d3 d4 d")
    chain = ForwardChain([dR, nR, dF, nF, h1, h2, h3, h4, h5, d1, d2, d3, d4, d])
    rR, rF = chain.define("rR", _rolled_radius(dR, nR)), chain.define("rF", _rolled_radius(dF, nF))
    a = chain.define("a", h1 + h2 - h3 + d1 / 2 - d2 / 2)
    b = chain.define("b", h4 - d3 / 2 - h5 + d4 / 2)
    along = chain.define("e", sp.sqrt((d + (d2 + d3) / 2) ** 2 - (a - b) ** 2))
    span = chain.define("span", sp.sqrt((a + b) ** 2 + along**2))
    lam = chain.define("lam", sp.atan2(along, a + b) + sp.asin((rF - rR) / span))
    w = chain.define("w", (a + b) * sp.cos(lam) + along * sp.sin(lam))
    lam_ht = chain.define("lam_ht", sp.pi / 2 - lam)
    outputs = {"rR": rR, "rF": rF, "lam": lam, "lam_ht": lam_ht, "w": w, "f": b, **_frame(chain, rR, rF, lam, w, b)}
    return chain.stage(
        "frame_from_heights",
        outputs,
        "Wheel radii, steer axis tilt, head tube angle, wheelbase, fork offset, trail and wheel centres "
        "from heights and diameters.",
        checks={"a": a, "b": b},
    )


def define_wheels(
    chain: ForwardChain, mP, dP, lP, TtP1, TtR1, TtF1, TcR1, TcF1, mR, mF, lR, lF, g
) -> dict[str, sp.Symbol]:
    rod = mP * (3 * (dP / 2) ** 2 + lP**2) / 12  # a solid rod about a transverse axis through its middle
    k_t = chain.define("k_t", 4 * sp.pi**2 * rod / TtP1**2)  # Eq. 1 inverted
    torsional, compound = pendulum.torsional_inertia(), pendulum.compound_inertia()
    T, m_p, g_p, l_p, k = syms("T m_p g l_p k_t")
    outputs = {"k_t": k_t}
    for wheel, (Tt, Tc, m, length) in {"R": (TtR1, TcR1, mR, lR), "F": (TtF1, TcF1, mF, lF)}.items():
        outputs[f"I{wheel}xx"] = chain.define(f"I{wheel}xx", torsional.xreplace({k: k_t, T: Tt}))
        outputs[f"I{wheel}yy"] = chain.define(f"I{wheel}yy", compound.xreplace({T: Tc, m_p: m, g_p: g, l_p: length}))
    return outputs


def wheels() -> tuple[list[GeneratedFunction], Stage]:
    inputs = syms("mP dP lP TtP1 TtR1 TtF1 TcR1 TcF1 mR mF lR lF g")
    chain = ForwardChain(inputs)
    return chain.stage(
        "wheels",
        define_wheels(chain, *inputs),
        "The torsional pendulum's stiffness from its calibration rod, and the wheels' inertias (Eqs. 1 and 7).",
    )


def handlebar_reference() -> tuple[list[GeneratedFunction], Stage]:
    h6, h7, d5, d6, length, w, rF, lam = syms("h6 h7 d5 d6 l w rF lam")
    inputs = [h6, h7, d5, d6, length, w, rF, lam]
    chain = ForwardChain(inputs)
    l1 = chain.define("l1", (h7 - d6 / 2) - (h6 - d5 / 2))  # perpendicular to the steer axis, forward
    l2 = chain.define("l2", sp.sqrt((length - (d5 + d6) / 2) ** 2 - l1**2))  # along the steer axis, up
    x = chain.define("x", w - l2 * sp.sin(lam) + l1 * sp.cos(lam))
    z = chain.define("z", -rF - l2 * sp.cos(lam) - l1 * sp.sin(lam))
    return chain.stage(
        "handlebar_reference",
        {"x_ref": x, "z_ref": z},
        "The handlebar reference point of a handlebar measured apart from its fork.",
        checks={"l1": l1, "l2": l2},
    )


def define_hung_body_3(
    chain: ForwardChain, lam, x_ref, z_ref, k_t, hangs, offsets, periods, prefix: str = ""
) -> tuple[dict[str, sp.Symbol], dict[str, sp.Symbol]]:
    """Outputs ``x, z, Ixx, Ixz, Izz`` and checks ``miss_1..3, lines_det, eq6_det``."""

    def define(name, expr):
        return chain.define(prefix + name, expr)

    betas = [define(f"beta{i}", lam - h) for i, h in enumerate(hangs, start=1)]
    sines = [define(f"sin{i}", sp.sin(b)) for i, b in enumerate(betas, start=1)]
    cosines = [define(f"cos{i}", sp.cos(b)) for i, b in enumerate(betas, start=1)]
    distances = [
        define(f"d{i}", s * x_ref + c * z_ref - a) for i, (s, c, a) in enumerate(zip(sines, cosines, offsets), start=1)
    ]
    ss = define("ss", sp.Add(*(s * s for s in sines)))
    cc = define("cc", sp.Add(*(c * c for c in cosines)))
    sc = define("sc", sp.Add(*(s * c for s, c in zip(sines, cosines))))
    sd = define("sd", sp.Add(*(s * d for s, d in zip(sines, distances))))
    cd = define("cd", sp.Add(*(c * d for c, d in zip(cosines, distances))))
    lines_det = define("linesdet", ss * cc - sc**2)
    x = define("x", (cc * sd - sc * cd) / lines_det)
    z = define("z", (ss * cd - sc * sd) / lines_det)
    misses = {
        f"miss_{i}": define(f"miss{i}", s * x + c * z - d)
        for i, (s, c, d) in enumerate(zip(sines, cosines, distances), start=1)
    }
    solution, eq6_det = pendulum.three_orientation_solution()
    substitution = dict(zip(syms("T_1 T_2 T_3 alpha_1 alpha_2 alpha_3"), [*periods, *betas]))
    substitution[sym("k_t")] = k_t
    inertia = {
        f"I{axes}": define(f"I{axes}", entry.xreplace(substitution))
        for axes, entry in zip(("xx", "xz", "zz"), solution)
    }
    det = define("eq6det", eq6_det.xreplace(substitution))
    return {"x": x, "z": z, **inertia}, {**misses, "lines_det": lines_det, "eq6_det": det}


def hung_body_3() -> tuple[list[GeneratedFunction], Stage]:
    lam, x_ref, z_ref, k_t = syms("lam x_ref z_ref k_t")
    hangs, offsets, periods = syms("hang_1 hang_2 hang_3"), syms("off_1 off_2 off_3"), syms("T_1 T_2 T_3")
    chain = ForwardChain([lam, x_ref, z_ref, k_t, *hangs, *offsets, *periods])
    outputs, checks = define_hung_body_3(chain, lam, x_ref, z_ref, k_t, hangs, offsets, periods)
    return chain.stage(
        "hung_body_3",
        outputs,
        "Centre of mass (hanging lines) and in-plane inertia (Eq. 6) of a body hung in three orientations.",
        checks=checks,
    )


def hanging_line() -> tuple[list[GeneratedFunction], Stage]:
    lam, hang, off, x_ref, z_ref = syms("lam hang off x_ref z_ref")
    beta = lam - hang
    s, c = sp.sin(beta), sp.cos(beta)
    return stage_functions(
        MODULE,
        "hanging_line",
        [lam, hang, off, x_ref, z_ref],
        {"s": s, "c": c, "d": s * x_ref + c * z_ref - off},
        "One hanging orientation's line s x + c z = d (a row of the least-squares centre of mass).",
    )


def hung_orientation_equation() -> tuple[list[GeneratedFunction], Stage]:
    lam, hang, k_t, T = syms("lam hang k_t T")
    alpha = sym("alpha")
    row = [entry.xreplace({alpha: lam - hang}) for entry in pendulum.orientation_row(alpha)]
    J = pendulum.torsional_inertia().xreplace({sym("T"): T})
    return stage_functions(
        MODULE,
        "hung_orientation_equation",
        [lam, hang, k_t, T],
        {"r_xx": row[0], "r_xz": row[1], "r_zz": row[2], "J": J},
        "One hanging orientation's row of Eq. 6, J = r . [Ixx, Ixz, Izz], with J from Eq. 1.",
    )


def define_compound_about_point(
    chain: ForwardChain, T, m_p, g, x_c, z_c, x_ref, z_ref, prefix: str = ""
) -> tuple[sp.Symbol, sp.Symbol]:
    """``(Iyy, l_p)``: Eq. 7 about the reference point, and the pendulum length."""
    length = chain.define(f"{prefix}l", sp.sqrt((x_c - x_ref) ** 2 + (z_c - z_ref) ** 2))
    Iyy = chain.define(
        f"{prefix}Iyy",
        pendulum.compound_inertia().xreplace({sym("T"): T, sym("m_p"): m_p, sym("g"): g, sym("l_p"): length}),
    )
    return Iyy, length


def compound_about_point() -> tuple[list[GeneratedFunction], Stage]:
    inputs = syms("T m_p g x_c z_c x_ref z_ref")
    chain = ForwardChain(inputs)
    Iyy, length = define_compound_about_point(chain, *inputs)
    return chain.stage(
        "compound_about_point",
        {"Iyy": Iyy},
        "Eq. 7 for a body swung about its reference point (the pendulum length from its centre of mass).",
        checks={"l_p": length},
    )


def define_seating(chain: ForwardChain, w, rF, rR, c, lam, whb, LhbF, LhbR, h_bb, l_st, lam_st) -> dict[str, sp.Symbol]:
    half = whb / 2  # the grip is whb/2 to the side of the mid-plane: its in-plane distances
    front = chain.define("front", sp.sqrt(LhbF**2 - half**2))
    rear = chain.define("rear", sp.sqrt(LhbR**2 - half**2))
    span = chain.define("span", sp.sqrt(w**2 + (rR - rF) ** 2))  # rear centre (0, -rR) to front (w, -rF)
    ex = chain.define("ex", w / span)
    ez = chain.define("ez", (rR - rF) / span)
    along = chain.define("along", (rear**2 - front**2 + span**2) / (2 * span))
    height = chain.define("height", sp.sqrt(rear**2 - along**2))
    x_hand = chain.define("x_hand", along * ex + height * ez)  # the upper intersection: normal (ez, -ex)
    z_hand = chain.define("z_hand", -rR + along * ez - height * ex)
    z10 = chain.define("z10", -h_bb - l_st * sp.sin(lam_st))  # top of the seat tube
    x12 = chain.define("x12", w + c + z10 * sp.tan(lam))  # the steer axis at that height
    l_s = chain.define("l_s", (z10 - z_hand) / sp.cos(lam))  # sin(lam_ht) = cos(lam)
    l_hb = chain.define("l_hb", x12 - l_s * sp.sin(lam) - x_hand)
    l_f = chain.define("l_f", sp.sqrt((x12 - w) ** 2 + (z10 + rF) ** 2))
    return {"l_s": l_s, "l_hb": l_hb, "l_f": l_f, "x_hand": x_hand, "z_hand": z_hand}


def seating() -> tuple[list[GeneratedFunction], Stage]:
    inputs = syms("w rF rR c lam whb LhbF LhbR h_bb l_st lam_st")
    chain = ForwardChain(inputs)
    return chain.stage(
        "seating",
        define_seating(chain, *inputs),
        "The paper's stem, handlebar and fork lengths that put the rider model's hands on the grips.",
    )


STANDARD_BODIES = {"B": ("Bf", "mBf", "rear"), "H": ("H", "mH", "front")}
"""The bodies of BicycleParameters' template: node name, mass and reference wheel centre."""


def standard_layout() -> tuple[list[GeneratedFunction], Stage]:
    """BicycleParameters' template (wheelbase geometry, the rear frame and the handlebar/fork each
    hung in three orientations, every compound period, the seating measurements): every step above
    composed into one stage, so one bicycle in this layout takes one call."""
    frame_in = syms("dR nR dF nF w lam_ht f")
    wheels_in = syms("mP dP lP TtP1 TtR1 TtF1 TcR1 TcF1 mR mF lR lF g")
    body_in = {
        body: (
            syms(" ".join(f"alpha{body}{i}" for i in (1, 2, 3))),
            syms(" ".join(f"a{body}{i}" for i in (1, 2, 3))),
            syms(" ".join(f"Tt{body}{i}" for i in (1, 2, 3))),
            sym(f"Tc{body}1"),
            sym(mass),
        )
        for body, (_, mass, _) in STANDARD_BODIES.items()
    }
    seating_in = syms("whb LhbF LhbR h_bb l_st lam_st")
    inputs = [
        *frame_in,
        *wheels_in,
        *(s for b in body_in.values() for group in b for s in (group if isinstance(group, list) else [group])),
        *seating_in,
    ]
    chain = ForwardChain(inputs)
    frame = define_frame_from_wheelbase(chain, *frame_in)
    wheels = define_wheels(chain, *wheels_in)
    outputs, checks = {**frame, **wheels}, {}
    for body, (name, _, wheel) in STANDARD_BODIES.items():
        hangs, offsets, periods, Tc, mass = body_in[body]
        x_ref, z_ref = frame[f"x_{wheel}"], frame[f"z_{wheel}"]
        hung, hung_checks = define_hung_body_3(
            chain, frame["lam"], x_ref, z_ref, wheels["k_t"], hangs, offsets, periods, prefix=body
        )
        Iyy, length = define_compound_about_point(
            chain, Tc, mass, sym("g"), hung["x"], hung["z"], x_ref, z_ref, prefix=body
        )
        outputs.update(
            {
                f"x{name}": hung["x"],
                f"z{name}": hung["z"],
                **{f"I{name}{a}": hung[f"I{a}"] for a in ("xx", "xz", "zz")},
                f"I{name}yy": Iyy,
            }
        )
        checks.update({f"{body}_{check}": value for check, value in hung_checks.items()})
        checks[f"{body}_l_p"] = length
    outputs.update(define_seating(chain, sym("w"), frame["rF"], frame["rR"], frame["c"], frame["lam"], *seating_in))
    return chain.stage(
        "standard_layout",
        outputs,
        "A Measured file in BicycleParameters' template: every step of the reduction in one stage.",
        checks=checks,
    )


def build() -> GeneratedModule:
    functions: list[GeneratedFunction] = []
    stages: list[Stage] = []
    for make in (
        frame_from_wheelbase,
        frame_from_heights,
        wheels,
        handlebar_reference,
        hung_body_3,
        hanging_line,
        hung_orientation_equation,
        compound_about_point,
        seating,
        standard_layout,
    ):
        fns, stage = make()
        functions += fns
        stages.append(stage)
    return GeneratedModule(
        name=MODULE,
        summary="A BicycleParameters Measured file reduced to the bicycle's bodies, stage by stage.",
        description=__doc__.split("\n\n", 1)[1].strip(),
        functions=functions,
        stages=stages,
    )
