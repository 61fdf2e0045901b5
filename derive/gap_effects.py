"""Candidate unmodelled effects for the sim-to-real gap: extended linear bicycle models.

The Whipple model of :mod:`derive.benchmark_model` is the baseline.  This module derives, from
first principles, the linear models the gap diagnosis offers as explanations of measurements the
Whipple model does not reproduce:

``steer_inertia``
    A body carried by the front frame with moment of inertia ``I_steer`` about the steer axis.
``steer_damping`` / ``steer_stiffness``
    A viscous damper ``c_steer`` and a spring ``k_steer`` between front and rear frame about the
    steer axis.
``passive_arms``
    The rider's arms as two point masses ``m_arm / 2`` at the grips ``(x_grip, +-b_grip, z_grip)``
    that move with the handlebar rather than with the rider's body (the mass is taken out of the
    rear body and carried by the front frame), and a spring ``k_arm`` and damper ``c_arm`` about
    the steer axis between the handlebar and the upper body.
``rider_lean``
    The rider's upper body ``U`` (mass ``m_u``, centre ``(x_u, z_u)``, inertia ``IUxx, IUxz,
    IUzz``) leaning by ``theta`` relative to the rear frame about a longitudinal hip axis at height
    ``z_lean``, with passive stiffness ``k_lean`` and damping ``c_lean``: three degrees of freedom
    ``[phi, delta, theta]``.  ``U`` is part of the rear body ``B``: the rest of ``B`` is ``B - U``.
``tyre_slip``
    Lateral tyre forces instead of the no-slip constraints.  Per wheel (normal load ``N``, lateral
    slip velocity ``v_lat`` of the contact point, camber ``gamma``) a cornering (slip) force that
    follows ``-N c_alpha v_lat / v`` through a first-order lag of relaxation length ``sigma_t`` and
    acts a pneumatic trail ``t_p`` behind the contact point (the aligning moment of the slip force,
    as in Pacejka's tyre models), plus a camber thrust ``N c_gamma gamma`` at the contact point.

Method.  The bicycle (with the extra bodies above) is described by exact rigid-body kinematics in
the coordinates ``q = [Y, psi, phi, delta, theta]`` (lateral position of the rear contact, yaw,
roll, steer, upper-body lean; pitch follows from the front wheel touching the ground) while it rolls
forward at constant speed ``v`` with wheels spinning at ``-v/r``.  Positions and rotations are
expanded to second order in the small coordinates (truncated jets), which gives the Lagrangian to
second order, and the linear equations of motion ``M q'' + D q' + K q = Q`` follow from Lagrange's
equations.  The lateral slip velocities of the two wheel contacts are linear in ``q'`` and ``q``.

* Without tyre slip they are the nonholonomic constraints; eliminating ``Y'`` and ``psi'`` and
  projecting the equations on the constraint's null space gives the Whipple form
  ``M q'' + C(v) q' + K(g, v) q = f``.  For the Whipple bodies alone this reproduces the canonical
  matrices of Meijaard et al. (2007) Appendix A exactly (``tests/gap/candidates/test_gap_effects.py`` checks it).
* With tyre slip the lateral tyre forces are generalized forces through the partial velocities of
  the contact points, and the heading ``psi`` enters only through ``u = Y' - v psi`` (the lateral
  velocity of the rear contact relative to the heading), so the state is
  ``[phi, delta, theta, u, r, phi', delta', theta', F_R, F_F]`` with ``r = psi'``.  As the
  cornering stiffness grows without bound the slip vanishes and the slip forces become the
  reactions of rolling without slip, still applied ``t_p`` behind the contacts (through the
  partial velocities ``Papp``, not ``P``): the limit is the no-slip kinematics with those reactions
  as multipliers, an aligning moment ``t_p F`` on each wheel (``F`` the reaction less the camber
  thrust), independent of ``sigma_t``.  It is the Whipple model only for ``t_p = 0``
  (``tests/gap/candidates/test_gap_tyre_limit.py``).

Rows and columns of every matrix follow the coordinates; the rigid-rider models are the leading
blocks with ``theta`` removed (``theta = 0`` is a holonomic constraint whose reaction acts only in
the ``theta`` equation).
"""

from __future__ import annotations

from functools import cache

import sympy as sp

from derive.benchmark_model import CANONICAL_ARGS
from derive.codegen import GeneratedFunction, GeneratedModule, Output
from derive.symbols import sym, syms

BENCHMARK_ARGS = CANONICAL_ARGS
"""The benchmark parameters the linear models depend on (those of the canonical matrices)."""
STEER_ARGS = "I_steer c_steer k_steer"
ARM_ARGS = "m_arm x_grip z_grip b_grip k_arm c_arm"
UPPER_BODY_ARGS = "m_u x_u z_u IUxx IUxz IUzz z_lean"
LEAN_ARGS = "k_lean c_lean"
TYRE_ARGS = "c_alpha c_gamma sigma_t t_p"

# Internal symbols (never arguments of generated functions).
_t = sp.Symbol("t", real=True)
_Q = sp.symbols("Y psi phi delta theta", real=True)
_QD = sp.symbols("Yd psid phid deltad thetad", real=True)
_QDD = sp.symbols("Ydd psidd phidd deltadd thetadd", real=True)
_P2, _P2D = sp.symbols("pitch2 pitch2d", real=True)
STATE_NAMES = ("phi", "delta", "theta", "u", "r", "phid", "deltad", "thetad", "F_R", "F_F")
"""State of the tyre model: roll, steer, lean, lateral velocity of the rear contact relative to the
heading, yaw rate, the three rates, and the slip (cornering) force of each tyre."""


# ---------------------------------------------------------------------------------------------
# Truncated jets: a quantity as its parts of order 0, 1 and 2 in the small coordinates.
# ---------------------------------------------------------------------------------------------
class _Jet:
    """A matrix-valued quantity to second order: ``(order 0, order 1, order 2)`` parts."""

    def __init__(self, a0, a1, a2):
        self.o = [sp.Matrix(a0), sp.Matrix(a1), sp.Matrix(a2)]

    def __mul__(self, other: _Jet) -> _Jet:
        a, b = self.o, other.o
        return _Jet(a[0] * b[0], a[0] * b[1] + a[1] * b[0], a[0] * b[2] + a[1] * b[1] + a[2] * b[0])

    def __add__(self, other: _Jet) -> _Jet:
        return _Jet(*[x + y for x, y in zip(self.o, other.o)])

    def __sub__(self, other: _Jet) -> _Jet:
        return _Jet(*[x - y for x, y in zip(self.o, other.o)])

    def scaled(self, factor: sp.Expr) -> _Jet:
        return _Jet(*[factor * x for x in self.o])

    def T(self) -> _Jet:  # noqa: N802 - transpose, as in SymPy
        return _Jet(*[x.T for x in self.o])


def _const(m) -> _Jet:
    m = sp.Matrix(m)
    return _Jet(m, sp.zeros(*m.shape), sp.zeros(*m.shape))


def _d(expr: sp.Expr) -> sp.Expr:
    """Time derivative along the motion (coordinates, the second-order pitch, explicit time)."""
    out = sp.diff(expr, _t) + sp.diff(expr, _P2) * _P2D
    for q, qd in zip(_Q, _QD):
        out += sp.diff(expr, q) * qd
    return out


def _dj(j: _Jet) -> _Jet:
    return _Jet(*[x.applyfunc(_d) for x in j.o])


def _skew(a) -> sp.Matrix:
    return sp.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def _rotation(axis, angle, order: int) -> _Jet:
    """Rotation by a small ``angle`` (of the given order) about a unit ``axis`` (Rodrigues)."""
    K = _skew(axis)
    eye, zero = sp.eye(3), sp.zeros(3, 3)
    if order == 1:
        return _Jet(eye, angle * K, angle**2 / 2 * K * K)
    return _Jet(eye, zero, angle * K)


def _body_rate(R: _Jet) -> _Jet:
    """Angular velocity in body coordinates, ``vee(R^T R')``, of a frame that starts at identity."""
    W = R.T() * _dj(R)
    return _Jet(*[sp.Matrix([x[2, 1], x[0, 2], x[1, 0]]) for x in W.o])


_EX, _EY, _EZ = sp.Matrix([1, 0, 0]), sp.Matrix([0, 1, 0]), sp.Matrix([0, 0, 1])


def _translational(m: sp.Expr, r: _Jet) -> sp.Expr:
    """Second-order part of ``m |r'|^2 / 2``."""
    vel = _dj(r)
    return m * ((vel.o[0].T * vel.o[2])[0] + sp.Rational(1, 2) * (vel.o[1].T * vel.o[1])[0])


def _rotational(inertia: sp.Matrix, rate: _Jet) -> sp.Expr:
    """Second-order part of ``w . I w / 2`` for a frame with no rotation at order zero."""
    return sp.Rational(1, 2) * (rate.o[1].T * inertia * rate.o[1])[0]


def _potential(m: sp.Expr, r: _Jet) -> sp.Expr:
    """Second-order part of the potential ``-g m z`` (z points down)."""
    return -sym("g") * m * r.o[2][2]


def _planar_inertia(xx, xz, zz) -> sp.Matrix:
    return sp.Matrix([[xx, 0, xz], [0, 0, 0], [xz, 0, zz]])


# ---------------------------------------------------------------------------------------------
# The unconstrained linear equations.
# ---------------------------------------------------------------------------------------------
@cache
def unconstrained_equations() -> dict[str, sp.Matrix]:
    """Linear equations of the bicycle with every extra body, before any contact constraint.

    Returns
    -------
    dict
        ``M, D, K`` (5x5, coordinates ``[Y, psi, phi, delta, theta]``; passive springs and dampers
        included), ``P, S`` (2x5: lateral slip velocity of the rear and front contact is
        ``P q' + S q``), ``Papp`` (2x5: partial velocities of the tyre forces, with the pneumatic
        trail), ``camber`` (2x5: wheel camber angles ``camber q``), ``loads`` (2x1: static normal
        loads ``N_R, N_F``).
    """
    (w, c, lam, rR, mR, IRxx, IRyy, xB, zB, mB, IBxx, IBzz, IBxz, xH, zH, mH, IHxx, IHzz, IHxz, rF, mF, IFxx, IFyy) = (
        syms(BENCHMARK_ARGS)
    )
    I_steer, c_steer, k_steer = syms(STEER_ARGS)
    m_arm, x_grip, z_grip, b_grip, k_arm, c_arm = syms(ARM_ARGS)
    m_u, x_u, z_u, IUxx, IUxz, IUzz, z_lean = syms(UPPER_BODY_ARGS)
    k_lean, c_lean = syms(LEAN_ARGS)
    t_p = sym("t_p")
    g, v = sym("g"), sym("v")
    Y, psi, phi, delta, theta = _Q

    # Rear frame: yaw, roll about the heading, pitch (second order) about the rear axle.
    R_roll = _rotation(_EZ, psi, 1) * _rotation(_EX, phi, 1)
    R_rear = R_roll * _rotation(_EY, _P2, 2)
    axis = sp.Matrix([sp.sin(lam), 0, sp.cos(lam)])  # steer axis, pointing down and forward
    R_front = R_rear * _rotation(axis, delta, 1)
    R_upper = R_rear * _rotation(_EX, theta, 1)

    contact_R = _Jet([v * _t, 0, 0], [0, Y, 0], [0, 0, 0])
    axle_R = sp.Matrix([0, 0, -rR])
    centre_R = contact_R + R_roll * _const(axle_R)

    def rear_point(p) -> _Jet:
        return centre_R + R_rear * _const(sp.Matrix(p) - axle_R)

    axis_point = sp.Matrix([w + c, 0, 0])  # where the steer axis meets the ground
    axis_at = rear_point(axis_point)

    def front_point(p) -> _Jet:
        return axis_at + R_front * _const(sp.Matrix(p) - axis_point)

    hinge = sp.Matrix([x_u, 0, z_lean])
    hinge_at = rear_point(hinge)

    def upper_point(p) -> _Jet:
        return hinge_at + R_upper * _const(sp.Matrix(p) - hinge)

    centre_F = front_point([w, 0, -rF])
    # Front contact: the lowest point of the front wheel, centre + rF d with d the unit vector in
    # the wheel plane closest to straight down.
    wheel_axis_F = R_front * _const(_EY)
    s = [x[2] for x in wheel_axis_F.o]
    if s[0] != 0:
        raise AssertionError("front wheel axis is not horizontal in the reference configuration")
    s_times_axis = _Jet(sp.zeros(3, 1), s[1] * wheel_axis_F.o[0], s[1] * wheel_axis_F.o[1] + s[2] * wheel_axis_F.o[0])
    down = _const(_EZ) - s_times_axis
    down = _Jet(down.o[0], down.o[1], down.o[2] + s[1] ** 2 / 2 * down.o[0])
    contact_F = centre_F + down.scaled(rF)
    height = [sp.expand(x[2]) for x in contact_F.o]
    if sp.simplify(height[0]) != 0 or sp.simplify(height[1]) != 0:
        raise AssertionError("front contact is not on the ground to first order")
    pitch = sp.solve(height[2], _P2)[0]
    pitch_rate = _d(pitch)

    def on_path(expr: sp.Expr) -> sp.Expr:
        return sp.expand(expr.subs(_P2D, pitch_rate).subs(_P2, pitch))

    rate_rear, rate_front, rate_upper = _body_rate(R_rear), _body_rate(R_front), _body_rate(R_upper)
    spin_R, spin_F = -v / rR, -v / rF
    half = sp.Rational(1, 2)

    T = sp.Integer(0)
    V = sp.Integer(0)
    # Wheels: the carrier frame's rate plus the spin about the axle; axisymmetric inertia.
    T += _translational(mR, rear_point(axle_R)) + half * IRxx * (rate_rear.o[1][0] ** 2 + rate_rear.o[1][2] ** 2)
    T += half * IRyy * (rate_rear.o[1][1] ** 2 + 2 * spin_R * rate_rear.o[2][1])
    T += _translational(mF, centre_F) + half * IFxx * (rate_front.o[1][0] ** 2 + rate_front.o[1][2] ** 2)
    T += half * IFyy * (rate_front.o[1][1] ** 2 + 2 * spin_F * rate_front.o[2][1])
    V += _potential(mR, rear_point(axle_R)) + _potential(mF, centre_F)
    # Rear body (frame and rider) and front frame (handlebar and fork).
    r_B, r_H = rear_point([xB, 0, zB]), front_point([xH, 0, zH])
    T += _translational(mB, r_B) + _rotational(_planar_inertia(IBxx, IBxz, IBzz), rate_rear)
    T += _translational(mH, r_H) + _rotational(_planar_inertia(IHxx, IHxz, IHzz), rate_front)
    V += _potential(mB, r_B) + _potential(mH, r_H)
    # Added steer inertia: inertia I_steer about the steer axis, carried by the front frame.
    T += half * I_steer * ((rate_front.o[1].T * axis)[0]) ** 2
    # Passive arms: m_arm/2 at each grip moves with the front frame instead of the rear body.
    for side in (1, -1):
        grip = [x_grip, side * b_grip, z_grip]
        T += _translational(m_arm / 2, front_point(grip)) - _translational(m_arm / 2, rear_point(grip))
        V += _potential(m_arm / 2, front_point(grip)) - _potential(m_arm / 2, rear_point(grip))
    # Upper body: leaning by theta instead of moving with the rear frame.
    upper_inertia = _planar_inertia(IUxx, IUxz, IUzz)
    r_U = upper_point([x_u, 0, z_u])
    lean_T = _translational(m_u, r_U) + _rotational(upper_inertia, rate_upper)
    lean_V = _potential(m_u, r_U)
    rigid = {theta: 0, _QD[4]: 0}
    T += lean_T - lean_T.subs(rigid)
    V += lean_V - lean_V.subs(rigid)

    lagrangian = on_path(T - V)
    if lagrangian.has(_t):
        raise AssertionError("the second-order Lagrangian depends explicitly on time")

    def total_rate(expr: sp.Expr) -> sp.Expr:
        out = sp.Integer(0)
        for q, qd, qdd in zip(_Q, _QD, _QDD):
            out += sp.diff(expr, q) * qd + sp.diff(expr, qd) * qdd
        return out

    eom = [sp.expand(total_rate(sp.diff(lagrangian, qd)) - sp.diff(lagrangian, q)) for q, qd in zip(_Q, _QD)]
    n = len(_Q)
    M = sp.Matrix(n, n, lambda i, j: eom[i].coeff(_QDD[j]))
    D = sp.Matrix(n, n, lambda i, j: eom[i].coeff(_QD[j]))
    K = sp.Matrix(n, n, lambda i, j: eom[i].coeff(_Q[j]))
    rest = sp.expand(sp.Matrix(eom) - M * sp.Matrix(_QDD) - D * sp.Matrix(_QD) - K * sp.Matrix(_Q))
    if rest != sp.zeros(n, 1):
        raise AssertionError("the equations of motion are not linear in the coordinates")
    # Passive springs and dampers: steer (front to rear frame), arms (handlebar to upper body,
    # relative rotation about the steer axis delta - sin(lam) theta), lean (upper body to frame).
    arm_form = sp.Matrix([[0, 0, 0, 1, -sp.sin(lam)]])
    steer_form = sp.Matrix([[0, 0, 0, 1, 0]])
    lean_form = sp.Matrix([[0, 0, 0, 0, 1]])
    D += c_steer * steer_form.T * steer_form + c_arm * arm_form.T * arm_form + c_lean * lean_form.T * lean_form
    K += k_steer * steer_form.T * steer_form + k_arm * arm_form.T * arm_form + k_lean * lean_form.T * lean_form

    # Lateral slip velocity of each contact point (material point of the tyre), first order.
    def wheel_rate_world(R: _Jet, body_rate: _Jet, spin: sp.Expr) -> sp.Matrix:
        return body_rate.o[1] + R.o[1] * _EY * spin

    def slip(centre: _Jet, contact: _Jet, R: _Jet, body_rate: _Jet, spin: sp.Expr) -> tuple[sp.Expr, sp.Expr]:
        arm = contact - centre
        omega0, omega1 = spin * _EY, wheel_rate_world(R, body_rate, spin)
        vel0 = _dj(centre).o[0] + _skew(omega0) * arm.o[0]
        if sp.simplify(vel0) != sp.zeros(3, 1):
            raise AssertionError("the wheel does not roll without slip in the reference motion")
        vel1 = _dj(centre).o[1] + _skew(omega0) * arm.o[1] + _skew(omega1) * arm.o[0]
        return on_path(vel1[1]), on_path(omega1[2])

    v_lat_R, yaw_R = slip(centre_R, contact_R, R_rear, rate_rear, spin_R)
    v_lat_F, yaw_F = slip(centre_F, contact_F, R_front, rate_front, spin_F)
    v_lat = [v_lat_R, v_lat_F]
    P = sp.Matrix(2, n, lambda i, j: v_lat[i].coeff(_QD[j]))
    S = sp.Matrix(2, n, lambda i, j: v_lat[i].coeff(_Q[j]))
    if sp.expand(sp.Matrix(v_lat) - P * sp.Matrix(_QD) - S * sp.Matrix(_Q)) != sp.zeros(2, 1):
        raise AssertionError("slip velocities are not linear")
    # Force application point t_p behind the contact: partial velocity v_lat - t_p * (yaw rate).
    applied = [sp.expand(v_lat_R - t_p * yaw_R), sp.expand(v_lat_F - t_p * yaw_F)]
    Papp = sp.Matrix(2, n, lambda i, j: applied[i].coeff(_QD[j]))
    camber_R = on_path((R_rear * _const(_EY)).o[1][2])
    camber_F = on_path(wheel_axis_F.o[1][2])
    camber = sp.Matrix(2, n, lambda i, j: [camber_R, camber_F][i].coeff(_Q[j]))
    # Static normal loads from the moment balance about the rear contact (rear body includes U).
    load_F = g * (mB * xB + mH * xH + mF * w) / w
    load_R = g * (mR + mB + mH + mF) - load_F
    return {
        "M": M,
        "D": D,
        "K": K,
        "P": P,
        "S": S,
        "Papp": Papp,
        "camber": camber,
        "loads": sp.Matrix([load_R, load_F]),
    }


# ---------------------------------------------------------------------------------------------
# Rolling without slip: project on the constraints.
# ---------------------------------------------------------------------------------------------
@cache
def nonholonomic_equations(lean: bool) -> dict[str, sp.Matrix]:
    """``M p'' + C p' + K p = B f`` for ``p = [phi, delta(, theta)]`` with rolling wheels.

    ``C`` holds the speed-proportional and the passive damping, ``K`` gravity, speed-squared and
    passive stiffness terms; ``B`` maps ``f = [T_phi, T_delta]`` (roll torque on the rear frame,
    steer torque between the frames) to the equations.
    """
    eq = unconstrained_equations()
    keep = [0, 1, 2, 3, 4] if lean else [0, 1, 2, 3]
    M, D, K = (eq[k].extract(keep, keep) for k in ("M", "D", "K"))
    P, S = eq["P"].extract([0, 1], keep), eq["S"].extract([0, 1], keep)
    n_ind = len(keep) - 2
    Pd, Pi = P[:, :2], P[:, 2:]
    if S[:, 0] != sp.zeros(2, 1):
        raise AssertionError("slip depends on the lateral position")
    Pd_inv = Pd.inv()
    dep_rate = -Pd_inv * Pi  # [Y', psi'] per independent rate
    dep_pos = -Pd_inv * S[:, 2:]  # [Y', psi'] per independent coordinate
    dep_psi = -Pd_inv * S[:, 1]  # [Y', psi'] per psi
    if sp.simplify(dep_psi[1]) != 0:
        raise AssertionError("the yaw rate depends on the heading")
    p = sp.Matrix(_Q[2 : 2 + n_ind])
    pd = sp.Matrix(_QD[2 : 2 + n_ind])
    pdd = sp.Matrix(_QDD[2 : 2 + n_ind])
    psi = _Q[1]
    yaw_rate = (dep_rate[1, :] * pd + dep_pos[1, :] * p)[0]
    q_rate = sp.Matrix.vstack(
        sp.Matrix([(dep_rate[0, :] * pd + dep_pos[0, :] * p)[0] + dep_psi[0] * psi, yaw_rate]), pd
    )
    q_acc = sp.Matrix.vstack(dep_rate * pdd + dep_pos * pd + dep_psi * yaw_rate, pdd)
    q_pos = sp.Matrix.vstack(sp.Matrix([_Q[0], psi]), p)
    T = sp.Matrix.vstack(dep_rate, sp.eye(n_ind))
    reduced = (T.T * (M * q_acc + D * q_rate + K * q_pos)).applyfunc(sp.expand)
    if any(e.has(_Q[0]) or e.has(psi) for e in reduced):
        raise AssertionError("the reduced equations depend on lateral position or heading")
    Mr = sp.Matrix(n_ind, n_ind, lambda i, j: reduced[i].coeff(pdd[j]))
    Cr = sp.Matrix(n_ind, n_ind, lambda i, j: reduced[i].coeff(pd[j]))
    Kr = sp.Matrix(n_ind, n_ind, lambda i, j: reduced[i].coeff(p[j]))
    # Roll torque acts on the roll coordinate, steer torque on steer; T^T maps them unchanged.
    B = sp.zeros(n_ind, 2)
    B[0, 0] = 1
    B[1, 1] = 1
    return {
        "M": Mr.applyfunc(sp.factor_terms),
        "C": Cr.applyfunc(sp.factor_terms),
        "K": Kr.applyfunc(sp.factor_terms),
        "B": B,
    }


# ---------------------------------------------------------------------------------------------
# Tyre slip: lateral tyre forces with relaxation.
# ---------------------------------------------------------------------------------------------
@cache
def tyre_descriptor() -> dict[str, sp.Matrix]:
    """Descriptor form ``E x' = A x + B f`` of the tyre model, state :data:`STATE_NAMES`."""
    eq = unconstrained_equations()
    M, D, K, P, S = eq["M"], eq["D"], eq["K"], eq["P"], eq["S"]
    Papp, camber, loads = eq["Papp"], eq["camber"], eq["loads"]
    c_alpha, c_gamma, sigma_t = syms("c_alpha c_gamma sigma_t")
    v = sym("v")
    if D[:, 0] != sp.zeros(5, 1) or K[:, 0] != sp.zeros(5, 1) or K[:, 1] != sp.zeros(5, 1):
        raise AssertionError("the equations depend on lateral position or heading")
    if sp.simplify(v * P[:, 0] + S[:, 1]) != sp.zeros(2, 1):
        raise AssertionError("the slip does not depend on heading through u = Y' - v psi only")
    n = 10
    E = sp.zeros(n, n)
    A = sp.zeros(n, n)
    B = sp.zeros(n, 2)
    # Kinematics: [phi, delta, theta]' = [phid, deltad, thetad].
    for k in range(3):
        E[k, k] = 1
        A[k, 5 + k] = 1
    # Dynamics, rows Y, psi, phi, delta, theta; rates w = [u, r, phid, deltad, thetad] and
    # Y'' = u' + v r.
    E[3:8, 3:8] = M
    A[3:8, 4] = -v * M[:, 0]
    A[3:8, 4:8] += -D[:, 1:]
    A[3:8, 0:3] = -K[:, 2:]
    A[3:8, 8:10] = Papp.T
    B[5, 0] = 1  # roll torque: roll equation
    B[6, 1] = 1  # steer torque: steer equation
    # Camber thrust N c_gamma gamma acts at the contact point at once.
    A[3:8, 0:3] += P.T * sp.diag(loads[0] * c_gamma, loads[1] * c_gamma) * camber[:, 2:]
    # Slip force: (sigma_t / v) F' = -F - N c_alpha v_lat / v, acting t_p behind the contact.
    rate_part = sp.Matrix.hstack(P[:, 0], P[:, 1:])  # coefficients of [u, r, phid, deltad, thetad]
    for i in range(2):
        E[8 + i, 8 + i] = sigma_t / v
        A[8 + i, 8 + i] = -1
        A[8 + i, 3:8] = -loads[i] * c_alpha / v * rate_part[i, :]
        A[8 + i, 0:3] = -loads[i] * c_alpha / v * S[i, 2:]
    slip = sp.zeros(2, n)
    slip[:, 0:3] = S[:, 2:]
    slip[:, 3:8] = rate_part
    return {
        "E": E.applyfunc(sp.factor_terms),
        "A": A.applyfunc(sp.factor_terms),
        "B": B,
        "slip": slip.applyfunc(sp.factor_terms),
        "loads": loads,
    }


# ---------------------------------------------------------------------------------------------
# First-order form of the two-degree-of-freedom models.
# ---------------------------------------------------------------------------------------------
def second_order_state_matrices(M: sp.Matrix, C: sp.Matrix, K: sp.Matrix, B: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix]:
    """``x' = A x + Bx f`` for ``x = [q, q']`` from ``M q'' + C q' + K q = B f`` (adjugate inverse)."""
    n = M.shape[0]
    Minv = M.adjugate() / M.det(method="berkowitz")
    A = sp.Matrix.vstack(sp.Matrix.hstack(sp.zeros(n, n), sp.eye(n)), sp.Matrix.hstack(-Minv * K, -Minv * C))
    Bx = sp.Matrix.vstack(sp.zeros(n, B.shape[1]), Minv * B)
    return A, Bx


def build() -> GeneratedModule:
    """The generated module ``gap_effects``."""
    g, v = sym("g"), sym("v")
    bench, steer, arms = syms(BENCHMARK_ARGS), syms(STEER_ARGS), syms(ARM_ARGS)
    upper, lean, tyre = syms(UPPER_BODY_ARGS), syms(LEAN_ARGS), syms(TYRE_ARGS)
    rigid = nonholonomic_equations(lean=False)
    leaning = nonholonomic_equations(lean=True)
    tyre_eq = tyre_descriptor()
    rigid_args = bench + steer + arms + [g, v]
    lean_args = bench + upper + lean + steer + arms + [g, v]
    tyre_args = bench + upper + lean + steer + arms + tyre + [g, v]
    state_A, state_B = second_order_state_matrices(rigid["M"], rigid["C"], rigid["K"], rigid["B"])
    functions = [
        GeneratedFunction(
            name="whipple_extended_matrices",
            args=rigid_args,
            outputs=[
                Output("M", rigid["M"], "mass matrix [kg m^2]"),
                Output("C", rigid["C"], "damping matrix at speed v, speed-proportional and passive [kg m^2/s]"),
                Output("K", rigid["K"], "stiffness matrix at speed v: gravity, speed squared, passive [N m/rad]"),
            ],
            summary="Whipple model with steer inertia, steer damping and stiffness, and passive arms: M, C, K.",
            notes=(
                "q = [phi, delta]; M q'' + C q' + K q = [T_phi, T_delta]. With every added parameter zero "
                "the matrices are M, v C1 and g K0 + v^2 K2 of Meijaard et al. (2007)."
            ),
        ),
        GeneratedFunction(
            name="whipple_extended_state_matrices",
            args=rigid_args,
            outputs=[
                Output("A", state_A, "state matrix for x = [phi, delta, phid, deltad] [1/s, 1/s^2]"),
                Output("B", state_B, "input matrix for f = [T_phi, T_delta] [1/(kg m^2)]"),
            ],
            summary="First-order form x' = A x + B f of the Whipple model with steer and arm effects.",
        ),
        GeneratedFunction(
            name="rider_lean_matrices",
            args=lean_args,
            outputs=[
                Output("M", leaning["M"], "mass matrix [kg m^2]"),
                Output("C", leaning["C"], "damping matrix at speed v [kg m^2/s]"),
                Output("K", leaning["K"], "stiffness matrix at speed v [N m/rad]"),
            ],
            summary="Three-degree-of-freedom model with a leaning upper body: M, C, K for [phi, delta, theta].",
            notes=(
                "theta is the upper-body lean relative to the rear frame about a longitudinal axis at "
                "height z_lean; the leading 2x2 blocks equal whipple_extended_matrices."
            ),
        ),
        GeneratedFunction(
            name="tyre_slip_descriptor",
            args=tyre_args,
            outputs=[
                Output("E", tyre_eq["E"], "descriptor matrix of E x' = A x + B f [mixed]"),
                Output("A", tyre_eq["A"], "system matrix [mixed]"),
                Output("B", tyre_eq["B"], "input matrix for f = [T_phi, T_delta] [mixed]"),
            ],
            summary="Bicycle with lateral tyre slip (and a leaning upper body): descriptor matrices E, A, B.",
            notes=(
                "x = [phi, delta, theta, u, r, phid, deltad, thetad, F_R, F_F]; drop theta, thetad and the "
                "theta equation (rows and columns 2 and 7) for a rigid rider. Needs v > 0."
            ),
        ),
        GeneratedFunction(
            name="tyre_slip_contacts",
            args=bench + upper + [g, v],
            outputs=[
                Output(
                    "slip", tyre_eq["slip"], "lateral slip velocity of the rear and front contact per state [mixed]"
                ),
                Output("loads", tyre_eq["loads"], "static normal loads of the rear and front tyre [N]", vector=True),
            ],
            summary="Contact slip velocities (slip @ x) and static tyre loads of the tyre model.",
            notes="For tyre laws other than the linear one of tyre_slip_descriptor (e.g. in validation).",
        ),
    ]
    return GeneratedModule(
        name="gap_effects",
        summary="Candidate unmodelled effects for the sim-to-real gap: extended linear bicycle models.",
        description=(
            "Derived in derive/gap_effects.py from a second-order Lagrangian of the bicycle with extra\n"
            "bodies, contact slip and passive elements; the Whipple limit is Meijaard et al. (2007)."
        ),
        functions=functions,
    )
