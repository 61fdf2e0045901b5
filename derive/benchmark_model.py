"""The linear Whipple bicycle: canonical matrices, characteristic polynomial, critical speeds.

Meijaard, Papadopoulos, Ruina, Schwab (2007), Proc. R. Soc. A 463:1955, Appendix A gives the
canonical matrices of ``M q'' + v C1 q' + (g K0 + v^2 K2) q = f`` with ``q = [phi, delta]``
(roll, steer) from the benchmark parameters.  From the matrices this module derives the
characteristic polynomial ``det(M s^2 + v C1 s + g K0 + v^2 K2)`` and, as polynomials in
``u = v^2``, the two conditions that define the critical speeds:

* capsize: a real eigenvalue crosses zero, ``a0(u) = det(g K0 + u K2) = 0``;
* weave (Hopf): a complex pair crosses the imaginary axis, the third Hurwitz determinant
  ``a3 a2 a1 - a4 a1^2 - a0 a3^2 = 0``, which is ``v^2`` times a quadratic in ``u``, with the
  crossing frequency ``omega^2 = a1 / a3 > 0``.

The matrix-level functions take all sixteen entries, so they serve any two-degree-of-freedom
canonical model (identified matrices, models with added effects), not just the benchmark.
"""

from __future__ import annotations

import sympy as sp

from derive.codegen import GeneratedFunction, GeneratedModule, Output
from derive.symbols import BENCHMARK_NAMES, sym, syms

MATRIX_NAMES = ("M", "C1", "K0", "K2")
COORDS = ("phi", "delta")


def matrix_symbols(name: str) -> sp.Matrix:
    """The 2x2 matrix of entry symbols ``<name>_<row><col>`` (roll, steer)."""
    return sp.Matrix(2, 2, lambda i, j: sym(f"{name}_{COORDS[i]}{COORDS[j]}"))


def matrix_entry_args() -> list[sp.Symbol]:
    """All sixteen entry symbols, M then C1, K0, K2, each row by row."""
    out: list[sp.Symbol] = []
    for name in MATRIX_NAMES:
        out.extend(list(matrix_symbols(name)))
    return out


def canonical_matrices() -> dict[str, sp.Matrix]:
    """M, C1, K0 (per unit g) and K2 from the benchmark parameters (Meijaard 2007, Appendix A)."""
    p = {name: sym(name) for name in BENCHMARK_NAMES}
    w, c, lam = p["w"], p["c"], p["lam"]
    rR, mR, IRxx, IRyy = p["rR"], p["mR"], p["IRxx"], p["IRyy"]
    xB, zB, mB, IBxx, IBzz, IBxz = p["xB"], p["zB"], p["mB"], p["IBxx"], p["IBzz"], p["IBxz"]
    xH, zH, mH, IHxx, IHzz, IHxz = p["xH"], p["zH"], p["mH"], p["IHxx"], p["IHzz"], p["IHxz"]
    rF, mF, IFxx, IFyy = p["rF"], p["mF"], p["IFxx"], p["IFyy"]
    # Whole bicycle (A1-A6); the wheels are symmetric, so IRzz = IRxx and IFzz = IFxx.
    mT = mR + mB + mH + mF
    xT = (xB * mB + xH * mH + w * mF) / mT
    zT = (-rR * mR + zB * mB + zH * mH - rF * mF) / mT
    ITxx = IRxx + IBxx + IHxx + IFxx + mR * rR**2 + mB * zB**2 + mH * zH**2 + mF * rF**2
    ITxz = IBxz + IHxz - mB * xB * zB - mH * xH * zH + mF * w * rF
    ITzz = IRxx + IBzz + IHzz + IFxx + mB * xB**2 + mH * xH**2 + mF * w**2
    # Front assembly (A7-A14).
    mA = mH + mF
    xA = (xH * mH + w * mF) / mA
    zA = (zH * mH - rF * mF) / mA
    IAxx = IHxx + IFxx + mH * (zH - zA) ** 2 + mF * (rF + zA) ** 2
    IAxz = IHxz - mH * (xH - xA) * (zH - zA) + mF * (w - xA) * (rF + zA)
    IAzz = IHzz + IFxx + mH * (xH - xA) ** 2 + mF * (w - xA) ** 2
    uA = (xA - w - c) * sp.cos(lam) - zA * sp.sin(lam)
    IAll = mA * uA**2 + IAxx * sp.sin(lam) ** 2 + 2 * IAxz * sp.sin(lam) * sp.cos(lam) + IAzz * sp.cos(lam) ** 2
    IAlx = -mA * uA * zA + IAxx * sp.sin(lam) + IAxz * sp.cos(lam)
    IAlz = mA * uA * xA + IAxz * sp.sin(lam) + IAzz * sp.cos(lam)
    # Gyroscopic and static coefficients (A15-A19).
    mu = c / w * sp.cos(lam)
    SR = IRyy / rR
    SF = IFyy / rF
    ST = SR + SF
    SA = mA * uA + mu * mT * xT
    M = sp.Matrix([[ITxx, IAlx + mu * ITxz], [IAlx + mu * ITxz, IAll + 2 * mu * IAlz + mu**2 * ITzz]])
    K0 = sp.Matrix([[mT * zT, -SA], [-SA, -SA * sp.sin(lam)]])
    K2 = sp.Matrix([[0, (ST - mT * zT) / w * sp.cos(lam)], [0, (SA + SF * sp.sin(lam)) / w * sp.cos(lam)]])
    C1 = sp.Matrix(
        [
            [0, mu * ST + SF * sp.cos(lam) + ITxz / w * sp.cos(lam) - mu * mT * zT],
            [-(mu * ST + SF * sp.cos(lam)), IAlz / w * sp.cos(lam) + mu * (SA + ITzz / w * sp.cos(lam))],
        ]
    )
    return {"M": M, "C1": C1, "K0": K0, "K2": K2}


def _canonical_args() -> str:
    used = set().union(*(m.free_symbols for m in canonical_matrices().values()))
    return " ".join(name for name in BENCHMARK_NAMES if sym(name) in used)


CANONICAL_ARGS = _canonical_args()
"""Benchmark parameters the matrices depend on, in Table 1 order (g multiplies K0 outside; IByy,
IHyy do not enter): the arguments of ``canonical_matrices`` and of every model built on them."""
MATRIX_ENTRIES = tuple(s.name for s in matrix_entry_args())
"""The sixteen matrix entry names, M then C1, K0, K2, each row by row."""


def characteristic_polynomial(s: sp.Symbol | None = None) -> tuple[sp.Poly, sp.Symbol]:
    """``det(M s^2 + v C1 s + g K0 + v^2 K2)`` in the Laplace variable ``s``, from matrix entries."""
    s = s or sp.Symbol("s")
    g, v = sym("g"), sym("v")
    M, C1, K0, K2 = (matrix_symbols(n) for n in MATRIX_NAMES)
    det = (M * s**2 + v * C1 * s + g * K0 + v**2 * K2).det(method="berkowitz")
    return sp.Poly(sp.expand(det), s), s


def characteristic_coefficients() -> list[sp.Expr]:
    """Coefficients ``[a4, a3, a2, a1, a0]`` of the characteristic polynomial, highest power first."""
    poly, _ = characteristic_polynomial()
    coeffs = poly.all_coeffs()
    return [sp.expand(a) for a in coeffs]


def critical_speed_polynomials() -> dict[str, list[sp.Expr]]:
    """Polynomials in ``u = v^2`` whose positive roots are the capsize and weave speeds.

    Returns ``capsize`` (coefficients of ``a0(u)``), ``weave`` (coefficients of the third Hurwitz
    determinant divided by ``v^2``) and ``a1_over_v``/``a3_over_v`` (``a1/v`` and ``a3/v`` as
    polynomials in ``u``, whose ratio is the squared crossing frequency), highest power first.
    """
    a4, a3, a2, a1, a0 = characteristic_coefficients()
    v, u = sym("v"), sym("u")
    hurwitz3 = sp.expand(a3 * a2 * a1 - a4 * a1**2 - a0 * a3**2)
    weave = sp.expand(sp.cancel(hurwitz3 / v**2))

    def in_u(expr: sp.Expr) -> list[sp.Expr]:
        expr = sp.expand(expr)
        if expr.has(v) and sp.Poly(expr, v).as_expr().subs(v, -v).expand() != expr:
            raise ValueError("expression is not even in v")
        poly = sp.Poly(expr.subs(v**2, u).subs(v, sp.sqrt(u)), u)
        return [sp.expand(cf) for cf in poly.all_coeffs()]

    out = {
        "capsize": in_u(a0),
        "weave": in_u(weave),
        "a1_over_v": in_u(sp.expand(a1 / v)),
        "a3_over_v": in_u(sp.expand(a3 / v)),
    }
    return out


def discriminant_polynomial() -> list[sp.Expr]:
    """The discriminant of the characteristic quartic in ``s``, as a polynomial in ``u = v^2``.

    The discriminant vanishes where two eigenvalues coincide; the smallest positive root where the
    two largest real eigenvalues merge into a complex pair is the speed ``v_d`` at which the weave
    mode is born (Meijaard et al. 2007, section 6).  It is even in ``v``: the characteristic
    polynomial at ``-v`` is that at ``v`` with ``s -> -s``, which negates every root and leaves
    their squared differences unchanged.  The coefficients ``a_i`` have degree ``4 - i`` in ``v``
    and the discriminant is isobaric of weight 12, so the result has degree at most 6 in ``u``.

    To keep the expressions small the discriminant of a generic quartic is expanded in the
    coefficients of the ``a_i`` as polynomials in ``v`` (nine placeholders), and those are put back
    unexpanded; common-subexpression elimination then computes each once.

    Returns
    -------
    list of sympy.Expr
        Coefficients in ``u``, highest power first.
    """
    v, u, s = sym("v"), sym("u"), sp.Symbol("s")
    generic = sp.symbols("A4 A3 A2 A1 A0")
    discriminant = sp.discriminant(sum(a * s ** (4 - i) for i, a in enumerate(generic)), s)
    placeholders: dict[sp.Symbol, sp.Expr] = {}
    in_v: dict[sp.Symbol, sp.Expr] = {}
    for i, (name, coefficient) in enumerate(zip(generic, characteristic_coefficients())):
        poly = sp.Poly(coefficient, v)
        terms = sp.Integer(0)
        for (k,), part in zip(poly.monoms(), poly.coeffs()):
            c = sp.Symbol(f"c_{4 - i}_{k}")
            placeholders[c] = part
            terms += c * v**k
        in_v[name] = terms
    expanded = sp.Poly(sp.expand(discriminant.subs(in_v)), v)
    if any(k % 2 for (k,) in expanded.monoms()):
        raise ValueError("the discriminant is not even in v")
    coefficients = sp.Poly(expanded.as_expr().subs(v, sp.sqrt(u)), u).all_coeffs()
    return [cf.subs(placeholders) for cf in coefficients]


def state_matrix() -> sp.Matrix:
    """First-order state matrix for ``x = [phi, delta, phi', delta']``."""
    g, v = sym("g"), sym("v")
    M, C1, K0, K2 = (matrix_symbols(n) for n in MATRIX_NAMES)
    Minv = M.inv(method="ADJ")
    K = g * K0 + v**2 * K2
    top = sp.Matrix.hstack(sp.zeros(2, 2), sp.eye(2))
    bottom = sp.Matrix.hstack(-Minv * K, -Minv * v * C1)
    return sp.Matrix.vstack(top, bottom).applyfunc(sp.simplify)


def _padded(coeffs: list[sp.Expr], n: int) -> sp.Matrix:
    coeffs = [sp.Integer(0)] * (n - len(coeffs)) + list(coeffs)
    return sp.Matrix(coeffs)


def build() -> GeneratedModule:
    """The generated module ``benchmark_model``."""
    mats = canonical_matrices()
    bench_args = syms(CANONICAL_ARGS)
    entry_args = matrix_entry_args()
    g, v = sym("g"), sym("v")
    coeffs = characteristic_coefficients()
    polys = critical_speed_polynomials()
    functions = [
        GeneratedFunction(
            name="canonical_matrices",
            args=bench_args,
            outputs=[
                Output("M", mats["M"], "mass matrix M [kg m^2]"),
                Output("C1", mats["C1"], "velocity matrix C1, multiplied by v [kg m]"),
                Output("K0", mats["K0"], "gravity stiffness matrix K0, multiplied by g [kg m]"),
                Output("K2", mats["K2"], "speed stiffness matrix K2, multiplied by v^2 [kg]"),
            ],
            summary="Canonical matrices M, C1, K0, K2 of the linear Whipple model from the benchmark parameters.",
            notes="Meijaard et al. (2007), Appendix A. Rows and columns are [roll, steer].",
        ),
        GeneratedFunction(
            name="characteristic_coefficients",
            args=entry_args + [g, v],
            outputs=[
                Output(
                    "coefficients",
                    sp.Matrix(coeffs),
                    "[a4, a3, a2, a1, a0] of det(M s^2 + v C1 s + g K0 + v^2 K2), highest power first",
                    vector=True,
                )
            ],
            summary="Coefficients of the characteristic polynomial in s at speed v.",
        ),
        GeneratedFunction(
            name="state_matrix",
            args=entry_args + [g, v],
            outputs=[Output("A", state_matrix(), "state matrix for x = [phi, delta, phi', delta'] [1/s, 1/s^2]")],
            summary="First-order state matrix A(v) of the canonical model.",
        ),
        GeneratedFunction(
            name="critical_speed_polynomials",
            args=entry_args + [g],
            outputs=[
                Output(
                    "capsize",
                    _padded(polys["capsize"], 3),
                    "coefficients in u = v^2 of det(g K0 + u K2), highest first [kg^2 m^2/s^4 ...]",
                    vector=True,
                ),
                Output(
                    "weave",
                    _padded(polys["weave"], 3),
                    "coefficients in u = v^2 of the third Hurwitz determinant over v^2, highest first",
                    vector=True,
                ),
                Output(
                    "a1_over_v", _padded(polys["a1_over_v"], 2), "coefficients in u of a1/v, highest first", vector=True
                ),
                Output(
                    "a3_over_v", _padded(polys["a3_over_v"], 2), "coefficients in u of a3/v, highest first", vector=True
                ),
            ],
            summary="Polynomials in u = v^2 whose positive roots are the capsize and weave speeds.",
            scalar=True,
            notes=(
                "Capsize: det(g K0 + u K2) = 0. Weave (Hopf): the third Hurwitz determinant "
                "a3 a2 a1 - a4 a1^2 - a0 a3^2 vanishes, with crossing frequency "
                "omega^2 = a1/a3 = (a1/v)/(a3/v) > 0."
            ),
        ),
    ]
    functions.append(
        GeneratedFunction(
            name="discriminant_polynomial",
            args=entry_args + [g],
            outputs=[
                Output(
                    "discriminant",
                    _padded(discriminant_polynomial(), 7),
                    "coefficients in u = v^2 of the discriminant of the characteristic quartic in s, highest first",
                    vector=True,
                ),
            ],
            summary="The discriminant of the characteristic polynomial in s, as a polynomial in u = v^2.",
            notes=(
                "Its positive roots are the speeds at which two eigenvalues coincide; the smallest at "
                "which the two largest real eigenvalues merge into the weave pair is v_d "
                "(WhippleModel.weave_birth_speed)."
            ),
        )
    )
    return GeneratedModule(
        name="benchmark_model",
        names={"MATRIX_NAMES": MATRIX_NAMES, "COORDINATES": COORDS, "MATRIX_ENTRIES": MATRIX_ENTRIES},
        summary="Linear Whipple bicycle model: canonical matrices, characteristic polynomial, critical speeds.",
        description=(
            "Derived in derive/benchmark_model.py from Meijaard, Papadopoulos, Ruina, Schwab (2007),\n"
            "Proc. R. Soc. A 463:1955, Appendix A."
        ),
        functions=functions,
    )
