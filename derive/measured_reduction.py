"""A BicycleParameters Measured file reduced in closed form, with its first-order uncertainties.

The file's standard layout (BicycleParameters' ``MeasuredTemplate.txt``): wheel radii from rolled
distances, the frame from wheelbase ``w``, head tube angle and fork offset ``f``, the torsional
pendulum calibrated by a rod, the rear frame B and the handlebar/fork H each hung in three
orientations, and compound-pendulum periods of both wheels and both bodies; optionally the seating
measurements.  The steps are those of ``bikerider.bicycle.raw_measurements`` (which documents each
one and also reduces every other layout):

* ``rR = dR / (2 pi nR)``, ``rF = dF / (2 pi nF)``, ``lam = pi/2 - lam_ht``,
  trail ``c = (rF sin(lam) - f) / cos(lam)``;
* stiffness ``k_t = 4 pi^2 I_rod / TtP1^2`` with ``I_rod = mP (3 (dP/2)^2 + lP^2) / 12``;
* wheels: ``I_xx`` from Eq. 1, ``I_yy`` from Eq. 7;
* each body: the axis of orientation ``i`` at ``beta_i = lam - alpha_i`` gives the line
  ``sin(beta_i) x + cos(beta_i) z = sin(beta_i) x_ref + cos(beta_i) z_ref - a_i`` (reference point
  the rear wheel centre ``(0, -rR)`` for B, the front one ``(w, -rF)`` for H); the centre of mass is
  the least-squares point of the three lines (normal equations by Cramer's rule), ``[Ixx, Ixz,
  Izz]`` is Eq. 6 solved in closed form, and ``I_yy`` is Eq. 7 about the reference point;
* seating: the grip where the circles ``sqrt(LhbF^2 - (whb/2)^2)`` about the front wheel centre and
  ``sqrt(LhbR^2 - (whb/2)^2)`` about the rear one meet above the wheel centres, then the paper's
  equivalent stem and handlebar lengths (``bikerider.bicycle.seating``).

Uncertainty.  Every output's standard uncertainty is ``sqrt(sum_j (d out / d x_j)^2 sigma_j^2)``
over the independent inputs ``x_j``, the derivatives exact: each intermediate quantity (``lam``,
``k_t``, the line sums, ...) is a symbol with its own expression and its derivatives with respect to
the inputs are accumulated by the chain rule through them (forward mode), so no derivative is taken
of a large substituted expression.  The common-subexpression pass of the code generator then shares
the intermediates between the values, the derivatives and the uncertainties.

Checks.  The function also returns what the runtime checks before trusting the result: the signed
distance of each body's centre of mass from each of its lines, the determinant of each body's line
normal equations (``0`` for parallel lines) and of its Eq. 6 (``0`` when two axes coincide).
"""
from __future__ import annotations

import sympy as sp

from derive import pendulum
from derive.codegen import GeneratedFunction, GeneratedModule, Output
from derive.symbols import sym

BODIES = ("B", "H")
ORIENTATIONS = (1, 2, 3)

SEATING_ARGS = ("l_cs", "h_bb", "l_sp", "l_st", "lam_st", "whb", "LhbF", "LhbR")
"""Seating inputs (the file's ``lcs, hbb, lsp, lst, lamst`` under the paper's names)."""

ARGS: tuple[str, ...] = (
    "dF", "nF", "dR", "nR", "mR", "mF", "g", "lF", "lR", "TcF1", "TcR1", "TtF1", "TtR1",
    "mP", "dP", "lP", "TtP1", "w", "lam_ht", "f", "mBf", "mH",
    *(f"{kind}{body}{i}" for body in BODIES for kind in ("alpha", "a", "Tt") for i in ORIENTATIONS),
    "TcB1", "TcH1", *SEATING_ARGS,
)
"""The inputs, in argument order (angles in radians: the runtime converts the file's degrees)."""

VALUE_NAMES: tuple[str, ...] = (
    "rR", "rF", "lam", "c", "k_t", "IRxx", "IRyy", "IFxx", "IFyy",
    "xBf", "zBf", "IBfxx", "IBfxz", "IBfzz", "IBfyy",
    "xH", "zH", "IHxx", "IHxz", "IHzz", "IHyy",
    "l_s", "l_hb", "l_f", "x_hand", "z_hand",
)
"""The computed outputs (inputs that pass through unchanged, such as ``w`` or ``mR``, are not
repeated).  The seating ones (from ``l_s``) are NaN when the seating inputs are NaN."""

CHECK_NAMES: tuple[str, ...] = (
    *(f"miss{body}{i}" for body in BODIES for i in ORIENTATIONS),
    "lines_det_B", "lines_det_H", "eq6_det_B", "eq6_det_H",
)


class ForwardChain:
    """Named intermediate quantities and their derivatives with respect to the inputs.

    Each :meth:`define` introduces a symbol for an expression of inputs and earlier intermediates;
    its derivative with respect to input ``x`` is ``sum_s d expr / d s * d s / d x`` over the
    symbols ``s`` the expression uses (taken in name order, never in ``free_symbols`` order).
    :meth:`expand` substitutes every intermediate back, so the results depend on the inputs only.
    """

    def __init__(self, inputs: list[sp.Symbol]):
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
            for symbol, definition in self.definitions[len(self._expanded):]:
                self._expanded[symbol] = definition.xreplace(self._expanded)
        return expr.xreplace(self._expanded)

    def sigma(self, symbol: sp.Symbol, sigmas: dict[sp.Symbol, sp.Symbol]) -> sp.Expr:
        """First-order standard uncertainty of ``symbol`` from independent input uncertainties."""
        terms = [(d * sigmas[x]) ** 2 for x, d in sorted(self.gradient[symbol].items(), key=lambda i: i[0].name)]
        return sp.sqrt(sp.Add(*terms))


def _least_squares_point(chain: ForwardChain, body: str, sines, cosines, distances):
    """Least-squares meeting point of the lines ``s x + c z = d`` (normal equations, Cramer's rule)."""
    ss = chain.define(f"ss{body}", sp.Add(*(s * s for s in sines)))
    cc = chain.define(f"cc{body}", sp.Add(*(c * c for c in cosines)))
    sc = chain.define(f"sc{body}", sp.Add(*(s * c for s, c in zip(sines, cosines))))
    sd = chain.define(f"sd{body}", sp.Add(*(s * d for s, d in zip(sines, distances))))
    cd = chain.define(f"cd{body}", sp.Add(*(c * d for c, d in zip(cosines, distances))))
    det = chain.define(f"linesdet{body}", ss * cc - sc**2)
    x = chain.define(f"x{body}", (cc * sd - sc * cd) / det)
    z = chain.define(f"z{body}", (ss * cd - sc * sd) / det)
    return x, z, det


def reduction() -> tuple[list[sp.Symbol], list[sp.Symbol], ForwardChain, dict[str, sp.Symbol], dict[str, sp.Symbol]]:
    """The chain: inputs, their sigma symbols, the forward chain, the value symbols and the checks."""
    x = {name: sym(name) for name in ARGS}
    inputs = [x[name] for name in ARGS]
    sigmas = [sym(f"sigma_{name}") for name in ARGS]
    chain = ForwardChain(inputs)
    two_pi = 2 * sp.pi
    out: dict[str, sp.Symbol] = {}
    checks: dict[str, sp.Symbol] = {}

    rR = out["rR"] = chain.define("rR", x["dR"] / (two_pi * x["nR"]))
    rF = out["rF"] = chain.define("rF", x["dF"] / (two_pi * x["nF"]))
    lam = out["lam"] = chain.define("lam", sp.pi / 2 - x["lam_ht"])
    out["c"] = chain.define("c", (rF * sp.sin(lam) - x["f"]) / sp.cos(lam))
    rod = chain.define("Irod", x["mP"] * (3 * (x["dP"] / 2) ** 2 + x["lP"] ** 2) / 12)
    k_t = out["k_t"] = chain.define("k_t", 4 * sp.pi**2 * rod / x["TtP1"] ** 2)

    torsional = pendulum.torsional_inertia()
    compound = pendulum.compound_inertia()
    T, m_p, g_p, l_p, k_p = (sym(n) for n in ("T", "m_p", "g", "l_p", "k_t"))
    for wheel in ("R", "F"):
        out[f"I{wheel}xx"] = chain.define(f"I{wheel}xx", torsional.xreplace({k_p: k_t, T: x[f"Tt{wheel}1"]}))
        out[f"I{wheel}yy"] = chain.define(f"I{wheel}yy", compound.xreplace(
            {T: x[f"Tc{wheel}1"], m_p: x[f"m{wheel}"], g_p: x["g"], l_p: x[f"l{wheel}"]}))

    solution, eq6_det = pendulum.three_orientation_solution()
    eq6_args = [sym(n) for n in ("T_1", "T_2", "T_3", "alpha_1", "alpha_2", "alpha_3")]
    references = {"B": (sp.Integer(0), -rR), "H": (x["w"], -rF)}
    masses = {"B": x["mBf"], "H": x["mH"]}
    for body in BODIES:
        name = "Bf" if body == "B" else body
        ref_x, ref_z = references[body]
        betas = [chain.define(f"beta{body}{i}", lam - x[f"alpha{body}{i}"]) for i in ORIENTATIONS]
        sines = [chain.define(f"sin{body}{i}", sp.sin(b)) for i, b in zip(ORIENTATIONS, betas)]
        cosines = [chain.define(f"cos{body}{i}", sp.cos(b)) for i, b in zip(ORIENTATIONS, betas)]
        distances = [chain.define(f"d{body}{i}", s * ref_x + c * ref_z - x[f"a{body}{i}"])
                     for i, s, c in zip(ORIENTATIONS, sines, cosines)]
        px, pz, lines_det = _least_squares_point(chain, body, sines, cosines, distances)
        out[f"x{name}"], out[f"z{name}"] = px, pz
        checks[f"lines_det_{body}"] = lines_det
        for i, s, c, d in zip(ORIENTATIONS, sines, cosines, distances):
            checks[f"miss{body}{i}"] = chain.define(f"miss{body}{i}", s * px + c * pz - d)
        substitution = dict(zip(eq6_args, [x[f"Tt{body}{i}"] for i in ORIENTATIONS] + betas))
        substitution[k_p] = k_t
        for axes, entry in zip(("xx", "xz", "zz"), solution):
            out[f"I{name}{axes}"] = chain.define(f"I{name}{axes}", entry.xreplace(substitution))
        checks[f"eq6_det_{body}"] = chain.define(f"eq6det{body}", eq6_det.xreplace(substitution))
        length = chain.define(f"l{body}", sp.sqrt((px - ref_x) ** 2 + (pz - ref_z) ** 2))
        out[f"I{name}yy"] = chain.define(f"I{name}yy", compound.xreplace(
            {T: x[f"Tc{body}1"], m_p: masses[body], g_p: x["g"], l_p: length}))

    # Seating (bikerider.bicycle.seating): the grip from its distances to the wheel centres.
    half = x["whb"] / 2
    front = chain.define("front", sp.sqrt(x["LhbF"] ** 2 - half**2))
    rear = chain.define("rear", sp.sqrt(x["LhbR"] ** 2 - half**2))
    span = chain.define("span", sp.sqrt(x["w"] ** 2 + (rR - rF) ** 2))
    ex = chain.define("ex", x["w"] / span)
    ez = chain.define("ez", (rR - rF) / span)
    along = chain.define("along", (rear**2 - front**2 + span**2) / (2 * span))
    height = chain.define("height", sp.sqrt(rear**2 - along**2))
    x_hand = out["x_hand"] = chain.define("x_hand", along * ex + height * ez)
    z_hand = out["z_hand"] = chain.define("z_hand", -rR + along * ez - height * ex)
    z10 = chain.define("z10", -x["h_bb"] - x["l_st"] * sp.sin(x["lam_st"]))
    x12 = chain.define("x12", x["w"] + out["c"] + z10 * sp.tan(lam))
    l_s = out["l_s"] = chain.define("l_s", (z10 - z_hand) / sp.sin(x["lam_ht"]))
    out["l_hb"] = chain.define("l_hb", x12 - l_s * sp.cos(x["lam_ht"]) - x_hand)
    out["l_f"] = chain.define("l_f", sp.sqrt((x12 - x["w"]) ** 2 + (z10 + rF) ** 2))
    return inputs, sigmas, chain, out, checks


def build() -> GeneratedModule:
    inputs, sigmas, chain, out, checks = reduction()
    sigma_of = dict(zip(inputs, sigmas))
    values = sp.Matrix([chain.expand(out[name]) for name in VALUE_NAMES])
    uncertainties = sp.Matrix([chain.expand(chain.sigma(out[name], sigma_of)) for name in VALUE_NAMES])
    check_values = sp.Matrix([chain.expand(checks[name]) for name in CHECK_NAMES])
    extra = (
        f"ARGS = {ARGS!r}\n\"\"\"The value arguments in order; the function takes them, then their standard\n"
        "uncertainties ``sigma_<name>`` in the same order.\"\"\"\n"
        f"VALUE_NAMES = {VALUE_NAMES!r}\n\"\"\"Order of ``values`` and ``sigmas``.\"\"\"\n"
        f"CHECK_NAMES = {CHECK_NAMES!r}\n\"\"\"Order of ``checks``.\"\"\""
    )
    return GeneratedModule(
        name="measured_reduction",
        summary="A BicycleParameters Measured file (standard layout) reduced in closed form, with first-order "
                "uncertainties.",
        description=__doc__.split("\n\n", 1)[1].strip(),
        extra_source=extra,
        functions=[
            GeneratedFunction(
                "standard_layout", [*inputs, *sigmas],
                [
                    Output("values", values, "the computed outputs, in VALUE_NAMES order [SI]", vector=True),
                    Output("sigmas", uncertainties, "their first-order standard uncertainties [SI]", vector=True),
                    Output("checks", check_values, "line misses [m], line and Eq. 6 determinants [1], in "
                           "CHECK_NAMES order", vector=True),
                ],
                "The reduction of a standard-layout Measured file and its first-order uncertainties.",
                notes="Inputs are independent; derivatives are exact (forward-mode chain rule in derive/).",
                scalar=True,
            ),
        ],
    )
