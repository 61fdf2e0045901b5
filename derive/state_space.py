"""Inputs of the linear Whipple model: roll torque, steer torque and a lateral force at a point.

The canonical form of Meijaard et al. (2007) takes a roll torque ``T_phi`` on the rear frame and a
steer torque ``T_delta`` between the frames: ``M q'' + v C1 q' + (g K0 + v^2 K2) q = [T_phi,
T_delta]``.  A lateral force ``F`` (horizontal, perpendicular to the heading, positive to the right,
the benchmark's +y) at a material point of the rear frame or of the front frame adds ``H F`` to the
right-hand side, ``H = [H_phiF, H_deltaF]`` (Moore 2012, *Human control of a bicycle*, chapters
"Extensions of the Whipple model" and "System identification").

Derivation.  To first order the lateral displacement of a point ``p = (x, 0, z)`` of the rear
frame is ``Y + x psi - z phi`` (yaw ``psi`` and roll ``phi`` act about the rear contact, pitch is of
second order), and a point of the front frame moves in addition with the steer rotation ``delta``
about the steer axis ``(sin lam, 0, cos lam)`` through ``(w + c, 0, 0)``; both come from the
cross product of the small rotation vector with the point's position below.  The generalized force
of ``F`` for the independent rates ``[phi', delta']`` is ``F`` times the partial velocity of the
point once the dependent rates ``[Y', psi']`` are eliminated with the rolling constraints.  The
constraints are those derived from exact rigid-body kinematics in :mod:`derive.gap_effects`
(``unconstrained_equations()["P"]``), so the elimination here is the one that gives the Whipple
matrices there.  The direction of the force (the yaw frame's lateral axis or the ground's) makes
no difference to first order.

With ``B_T = M^-1`` the state space of ``x = [phi, delta, phi', delta']`` is
``x' = A(v) x + B u`` with ``B = [0; M^-1 [I | H]]`` for ``u = [T_phi, T_delta, F]``; ``B`` does not
depend on the speed.
"""

from __future__ import annotations

import sympy as sp

from derive.benchmark_model import matrix_symbols
from derive.codegen import GeneratedFunction, GeneratedModule, Output
from derive.gap_effects import unconstrained_equations
from derive.symbols import syms

_RATES = sp.symbols("Yd_f psid_f phid_f deltad_f", real=True)
"""Internal rates ``[Y', psi', phi', delta']`` of the first-order point kinematics."""
GEOMETRY = ("w", "c", "lam")
"""The benchmark parameters a lateral force's generalized forces depend on."""
POINT = ("x_F", "z_F")
"""Where the lateral force acts, in the benchmark frame."""
FORCE_VECTOR = ("H_phiF", "H_deltaF")
"""``H``: the generalized forces [roll, steer] per unit lateral force."""
INPUTS = ("T_phi", "T_delta", "F")
"""The inputs ``u``, in the order of the columns of ``B``: roll torque, steer torque, lateral force."""


def _cross(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def point_lateral_velocity(body: str) -> sp.Expr:
    """First-order lateral velocity of the point ``(x_F, 0, z_F)`` fixed in ``body``.

    ``body`` is ``"rear"`` (the rear frame with the rider) or ``"front"`` (handlebar and fork).
    The result is linear in the rates :data:`_RATES`.
    """
    w, c, lam, x, z = syms(" ".join(GEOMETRY + POINT))
    Yd, psid, phid, deltad = _RATES
    point = sp.Matrix([x, 0, z])
    # The rear frame turns about the rear contact: yaw about z, roll about x.
    rear_rate = sp.Matrix([phid, 0, psid])
    velocity = sp.Matrix([0, Yd, 0]) + _cross(rear_rate, point)
    if body == "front":
        axis = sp.Matrix([sp.sin(lam), 0, sp.cos(lam)])
        velocity += _cross(deltad * axis, point - sp.Matrix([w + c, 0, 0]))
    elif body != "rear":
        raise ValueError(f"body must be 'rear' or 'front', not {body!r}")
    return sp.expand(velocity[1])


def lateral_force_vector(body: str) -> sp.Matrix:
    """``H = [H_phiF, H_deltaF]``: the generalized force per unit lateral force at a point of ``body``.

    The partial velocities of the point with respect to the independent rates ``[phi', delta']``
    after the rolling constraints (rear and front contact without lateral slip) fix ``[Y', psi']``.
    """
    P = unconstrained_equations()["P"].extract([0, 1], [0, 1, 2, 3])
    dependent = -P[:, :2].inv() * P[:, 2:]  # [Y', psi'] per unit [phi', delta']
    partial = [point_lateral_velocity(body).coeff(r) for r in _RATES]
    J = sp.Matrix([partial])  # 1 x 4 in [Y', psi', phi', delta']
    T = sp.Matrix.vstack(dependent, sp.eye(2))  # all rates per independent rate
    return (J * T).T.applyfunc(sp.simplify)


def input_matrix() -> sp.Matrix:
    """``B = [0; M^-1 [I | H]]`` (4 x 3) for ``u = [T_phi, T_delta, F]`` from the entries of M and H."""
    M = matrix_symbols("M")
    H = sp.Matrix(syms(" ".join(FORCE_VECTOR)))
    Minv = M.adjugate() / M.det(method="berkowitz")
    return sp.Matrix.vstack(sp.zeros(2, 3), (Minv * sp.Matrix.hstack(sp.eye(2), H)).applyfunc(sp.factor_terms))


def build() -> GeneratedModule:
    """The generated module ``state_space``."""
    geometry = syms(" ".join(GEOMETRY + POINT))
    M = matrix_symbols("M")
    functions = [
        GeneratedFunction(
            name="lateral_force_input",
            args=geometry,
            outputs=[
                Output(
                    "rear",
                    lateral_force_vector("rear"),
                    "[H_phiF, H_deltaF] for a force at a point of the rear frame [m]",
                    vector=True,
                ),
                Output(
                    "front",
                    lateral_force_vector("front"),
                    "[H_phiF, H_deltaF] for a force at a point of the front frame (handlebar and fork) [m]",
                    vector=True,
                ),
            ],
            summary="Generalized forces [roll, steer] of a unit lateral force at the point (x_F, z_F) of either frame.",
            notes=(
                "M q'' + v C1 q' + (g K0 + v^2 K2) q = [T_phi, T_delta] + H F. A force at a wheel's ground "
                "contact does no work (H = 0); above the rear contact (x_F = 0) it acts as a roll torque -z_F F."
            ),
        ),
        GeneratedFunction(
            name="input_matrix",
            args=list(M) + syms(" ".join(FORCE_VECTOR)),
            outputs=[
                Output(
                    "B",
                    input_matrix(),
                    "input matrix for u = [T_phi, T_delta, F], x = [phi, delta, phi', delta'] [1/(kg m^2), 1/(kg m)]",
                )
            ],
            summary="Input matrix B of x' = A(v) x + B u for roll torque, steer torque and a lateral force.",
            notes="B = [0; M^-1 [I | H]]; it does not depend on the speed.",
        ),
    ]
    return GeneratedModule(
        name="state_space",
        names={"LATERAL_FORCE_GEOMETRY": GEOMETRY, "STATE_SPACE_INPUTS": INPUTS},
        summary="Inputs of the linear Whipple model: roll torque, steer torque and a lateral force at a point.",
        description=(
            "Derived in derive/state_space.py from first-order point kinematics and the rolling\n"
            "constraints of derive/gap_effects.py; the lateral force follows Moore (2012), Human\n"
            "control of a bicycle, chapter Extensions of the Whipple model."
        ),
        functions=functions,
    )
