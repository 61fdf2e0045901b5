"""Inertia from pendulum measurements (Moore et al. 2009, Eqs. 1-7).

Sign convention.  The pendulum axis lies in the bicycle's plane of symmetry at angle ``alpha``
from the ground, rotating up from the +x axis; with z pointing down its unit vector is
``e = [cos(alpha), 0, -sin(alpha)]``.  The moment of inertia about it is ``J = e^T I e`` with
``I`` the inertia tensor whose off-diagonal entry is the benchmark's ``Ixz``:

    J = cos^2 Ixx - 2 sin cos Ixz + sin^2 Izz.

This is the paper's Eq. 5 with its Eq. 3 product ``I_xz`` equal to minus the tensor entry; the
tensors the paper prints in Table 5 are tensor entries (benchmark convention).
"""

from __future__ import annotations

from functools import cache

import sympy as sp

from derive.codegen import GeneratedFunction, GeneratedModule, Output, stage_functions
from derive.symbols import sym, syms


def torsional_inertia() -> sp.Expr:
    """Eq. 1: moment of inertia about the torsional pendulum axis."""
    k_t, T = syms("k_t T")
    return k_t * T**2 / (4 * sp.pi**2)


def compound_inertia() -> sp.Expr:
    """Eq. 7: moment of inertia about the axle of a wheel swung as a compound pendulum."""
    T, m_p, g, l_p = syms("T m_p g l_p")
    return (T / (2 * sp.pi)) ** 2 * m_p * g * l_p - m_p * l_p**2


def orientation_row(alpha: sp.Expr) -> sp.Matrix:
    """Row of Eq. 6 in the benchmark convention: ``J = row . [Ixx, Ixz, Izz]``."""
    e = sp.Matrix([sp.cos(alpha), 0, -sp.sin(alpha)])
    Ixx, Ixz, Izz = syms("Ixx Ixz Izz")
    tensor = sp.Matrix([[Ixx, 0, Ixz], [0, 0, 0], [Ixz, 0, Izz]])
    J = sp.expand((e.T * tensor * e)[0, 0])
    return sp.Matrix([[J.coeff(Ixx), J.coeff(Ixz), J.coeff(Izz)]])


@cache
def three_orientation_solution() -> tuple[sp.Matrix, sp.Expr]:
    """Eq. 6 solved in closed form for exactly three orientations; also its determinant (cached:
    the trigonometric simplification takes seconds and two derivations use it)."""
    k_t = sym("k_t")
    periods = syms("T_1 T_2 T_3")
    angles = syms("alpha_1 alpha_2 alpha_3")
    A = sp.Matrix.vstack(*(orientation_row(a) for a in angles))
    J = sp.Matrix([k_t * T**2 / (4 * sp.pi**2) for T in periods])
    det = sp.factor(sp.trigsimp(A.det()))
    solution = (A.adjugate() * J / det).applyfunc(sp.trigsimp)
    return sp.ImmutableMatrix(solution), det  # cached: callers must not change it


def orientation_equation():
    """Stage: one orientation's row of Eq. 6 and its J (Eq. 1), a row of the least squares that
    takes more than three orientations."""
    alpha, k_t, T = syms("alpha k_t T")
    row = list(orientation_row(alpha))
    return stage_functions(
        "pendulum",
        "orientation_equation",
        [alpha, k_t, T],
        {"r_xx": row[0], "r_xz": row[1], "r_zz": row[2], "J": torsional_inertia()},
        "One orientation's row of Eq. 6, J = r . [Ixx, Ixz, Izz], with J from Eq. 1.",
    )


def line_through_point():
    """Stage: a pendulum-axis line through a point at an angle, as ``s x + c z = d`` with the unit
    normal ``(s, c) = (sin(alpha), cos(alpha))``."""
    alpha, x_p, z_p = syms("alpha x_p z_p")
    s, c = sp.sin(alpha), sp.cos(alpha)
    return stage_functions(
        "pendulum",
        "line_through_point",
        [alpha, x_p, z_p],
        {"s": s, "c": c, "d": s * x_p + c * z_p},
        "A pendulum-axis line through a point, in normal form s x + c z = d.",
    )


def build() -> GeneratedModule:
    k_t, T, m_p, g, l_p, alpha = syms("k_t T m_p g l_p alpha")
    solution, det = three_orientation_solution()
    stage_parts = [orientation_equation(), line_through_point()]
    return GeneratedModule(
        name="pendulum",
        summary="Moments and products of inertia from torsional and compound pendulum periods.",
        description=__doc__.split("\n\n", 1)[1].strip(),
        functions=[
            GeneratedFunction(
                "torsional_inertia",
                [k_t, T],
                [Output("J", torsional_inertia(), "moment of inertia about the pendulum axis [kg m^2]")],
                "Moment of inertia about a torsional pendulum's axis from its period (Eq. 1).",
                scalar=True,
            ),
            GeneratedFunction(
                "compound_inertia",
                [T, m_p, g, l_p],
                [Output("Iyy", compound_inertia(), "moment of inertia about the wheel axle [kg m^2]")],
                "Wheel moment of inertia about its axle from a compound pendulum period (Eq. 7).",
                scalar=True,
            ),
            GeneratedFunction(
                "inertia_from_three_orientations",
                [k_t, *syms("T_1 T_2 T_3 alpha_1 alpha_2 alpha_3")],
                [
                    Output("inertia", solution, "[Ixx, Ixz, Izz] in the benchmark convention [kg m^2]", vector=True),
                    Output("determinant", det, "determinant of Eq. 6; zero when two axes coincide [1]"),
                ],
                "Eq. 6 solved in closed form for three pendulum orientations.",
                notes="The determinant vanishes when two angles are equal modulo pi (the same axis).",
            ),
            *(f for functions, _ in stage_parts for f in functions),
        ],
        stages=[stage for _, stage in stage_parts],
    )
