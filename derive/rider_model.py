"""The seated rider of Moore, Hubbard, Kooijman, Schwab (2009): 31 grid points, closures, segments.

Grid points follow Table 10 with the fork offset of Table 11.  Two corrections to the printed
table, both forced by its own value column: the elbow ``r23`` keeps the shoulder's ``y = l_ss/2``
(the printed ``r19 + [-u, l_ss/2, -v]`` would put it at ``y = l_ss``), and the labels of
``r10`` (top of seat tube) and ``r11`` (bottom of head tube) are swapped in the print.

Closures.  The knee (grid point 14) lies ``l_ll`` from the bottom bracket (5) and ``l_ul`` from
the hip (13); the right elbow (23) lies ``l_la`` from the hand (19) and ``l_ua`` from the
shoulder (21).  Each is solved analytically in the plane of the limb: with ``A`` the distal end,
``B`` the proximal end, ``D = |B - A|``, unit vector ``e = (B - A)/D`` and a unit normal ``n``,
the joint is ``A + p e + q n`` and SymPy's two solutions of ``p^2 + q^2 = l_a^2``,
``(p - D)^2 + q^2 = l_b^2`` are

    p = (D^2 + l_a^2 - l_b^2) / (2 D),   q = -/+ sqrt(-(D - l_a - l_b)(D - l_a + l_b)(D + l_a - l_b)(D + l_a + l_b)) / (2 D).

Branch rule (natural bending): take the root ``q >= 0`` along the normal ``n`` obtained by turning
the limb's direction ``e`` a quarter turn, always the same way for each limb: ``n = (-e_z, e_x)``
for the knee, ``n = (e_z, -e_x)`` for the elbow (x forward, z down).  For the usual seating (hip
above and behind the pedal axis, hand ahead of and below the shoulder) the knee then lies ahead of
the foot-to-hip line and the elbow below and behind the hand-to-shoulder line.  Because ``n`` turns
with the limb, the joint stays on the same side of the limb for every direction of it: the
sense of flexion of a knee or elbow moving in the sagittal plane does not depend on where the hand
or foot is.  Hands behind the shoulders (swept-back bars, an upright rider) bend the elbow
backwards and up, as an arm drawn back does; no direction of the limb lacks its natural bend.  The
only geometries without one are those with no closure at all: a limb too short to span the
distance, or one segment longer than the other plus the span (including hand on shoulder, D = 0,
where the plane of bending is not defined).  ``bikerider.rider.model`` refuses exactly those.  No
numerical starting guess is involved.

Segments (Table 9, Eqs. 9-10): cylinders for the upper and lower legs and arms, a cuboid torso of
width ``l_y = l_ss - c_ua/pi`` and stadium-section thickness ``l_x = (c_ch - 2 l_y)/(pi - 2)``,
and a sphere for the head.  Each segment's local z axis runs from its lower-numbered grid point
to its higher-numbered one, local y is global Y, and x follows by the right-hand rule (Eq. 11);
the local tensors are rotated (Eq. 12), moved to the rider's centre of mass (Eq. 13) and summed
(Eq. 14).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from derive.codegen import GeneratedFunction, GeneratedModule, Output
from derive.symbols import syms

GEOMETRY_ARGS = "h_bb l_cs l_f w_fh rF l_hb lam_ht w_rh rR l_sp lam_st l_st l_s c w"
"""The 15 bicycle measurements of Table 1, in the paper's order."""
RIDER_ARGS = "l_hh l_la l_ll l_ss l_to l_ua l_ul lam_fl c_h"
"""Rider measurements that place grid points (Table 7)."""
SEGMENT_ARGS = "mBr c_ch c_la c_ll c_ua c_ul f_h f_la f_ll f_to f_ua f_ul"
"""Rider mass, circumferences and mass fractions (Tables 7-8)."""


def _xz(x, z) -> sp.Matrix:
    return sp.Matrix([x, 0, z])


def _y(y) -> sp.Matrix:
    return sp.Matrix([0, y, 0])


@dataclass
class Closure:
    """One limb closure: both analytic branches and the chosen one."""

    joint: sp.Matrix
    branches: tuple[sp.Expr, sp.Expr]
    chosen_q: sp.Expr
    reach: sp.Expr
    distance: sp.Expr


def solve_closure(A: sp.Matrix, B: sp.Matrix, la: sp.Symbol, lb: sp.Symbol, normal_sign: int) -> Closure:
    """Joint at ``la`` from ``A`` and ``lb`` from ``B`` (same y), on the natural branch.

    ``normal_sign=+1`` uses ``n = (-e_z, e_x)`` (forward when B is above A: the knee);
    ``normal_sign=-1`` uses ``n = (e_z, -e_x)`` (downward when B is behind A: the elbow).
    """
    D, p, q = sp.Symbol("D", positive=True), sp.Symbol("p", real=True), sp.Symbol("q", real=True)
    solutions = sp.solve([p**2 + q**2 - la**2, (p - D) ** 2 + q**2 - lb**2], [p, q], dict=True)
    if len(solutions) != 2:
        raise RuntimeError(f"expected two closure branches, SymPy gave {len(solutions)}")
    natural = [s for s in solutions if not s[q].could_extract_minus_sign()]
    if len(natural) != 1:
        raise RuntimeError("could not tell the q >= 0 branch from the q <= 0 one")
    p_sol, q_sol = natural[0][p], natural[0][q]
    dx, dz = B[0] - A[0], B[2] - A[2]
    distance = sp.sqrt(dx**2 + dz**2)
    ex, ez = dx / distance, dz / distance
    nx, nz = (-ez, ex) if normal_sign > 0 else (ez, -ex)
    p_e, q_e = p_sol.subs(D, distance), q_sol.subs(D, distance)
    joint = A + sp.Matrix([p_e * ex + q_e * nx, 0, p_e * ez + q_e * nz])
    return Closure(joint, (solutions[0][q], solutions[1][q]), q_sol, la + lb, distance)


def grid_points() -> tuple[list[sp.Matrix], dict[str, Closure]]:
    """The 31 grid points (index 0 is grid point 1) and the two closures."""
    (h_bb, l_cs, l_f, w_fh, rF, l_hb, lam_ht, w_rh, rR, l_sp, lam_st, l_st, l_s, c, w) = syms(GEOMETRY_ARGS)
    (l_hh, l_la, l_ll, l_ss, l_to, l_ua, l_ul, lam_fl, c_h) = syms(RIDER_ARGS)
    r: dict[int, sp.Matrix] = {}
    f_o = rF * sp.cos(lam_ht) - c * sp.sin(lam_ht)  # fork offset (Table 11)
    r[1] = _xz(0, 0)
    r[2] = _xz(0, -rR)
    r[3] = r[2] + _y(w_rh / 2)
    r[4] = r[2] - _y(w_rh / 2)
    r[5] = _xz(sp.sqrt(l_cs**2 - (rR - h_bb) ** 2), -h_bb)
    r[6] = _xz(w, 0)
    r[7] = r[6] + _xz(0, -rF)
    r[8] = r[7] + _y(w_fh / 2)
    r[9] = r[7] - _y(w_fh / 2)
    r[10] = r[5] + _xz(-l_st * sp.cos(lam_st), -l_st * sp.sin(lam_st))
    fork = sp.sqrt(l_f**2 - f_o**2)
    r[11] = r[7] + _xz(-f_o * sp.sin(lam_ht) - sp.cos(lam_ht) * fork, f_o * sp.cos(lam_ht) - sp.sin(lam_ht) * fork)
    r[12] = _xz(r[11][0] - (r[11][2] - r[10][2]) / sp.tan(lam_ht), r[10][2])
    r[13] = r[10] + _xz(-l_sp * sp.cos(lam_st), -l_sp * sp.sin(lam_st))
    knee = solve_closure(r[5], r[13], l_ll, l_ul, normal_sign=+1)
    r[14] = knee.joint
    r[15] = r[13] + _xz(l_to * sp.cos(lam_fl), -l_to * sp.sin(lam_fl))
    r[16] = r[12] + _xz(-l_s * sp.cos(lam_ht), -l_s * sp.sin(lam_ht))
    r[17] = r[16] + _y(l_ss / 2)
    r[18] = r[16] - _y(l_ss / 2)
    r[19] = r[17] + _xz(-l_hb, 0)
    r[20] = r[18] + _xz(-l_hb, 0)
    r[21] = r[15] + _y(l_ss / 2)
    r[22] = r[15] - _y(l_ss / 2)
    elbow = solve_closure(r[19], r[21], l_la, l_ua, normal_sign=-1)
    r[23] = elbow.joint
    r[24] = r[23] - _y(l_ss)
    head_radius = c_h / (2 * sp.pi)
    r[25] = r[15] + _xz(head_radius * sp.cos(lam_fl), -head_radius * sp.sin(lam_fl))
    r[26] = r[5] + _y(l_hh / 2)
    r[27] = r[5] - _y(l_hh / 2)
    r[28] = r[14] + _y(l_hh / 2)
    r[29] = r[14] - _y(l_hh / 2)
    r[30] = r[13] + _y(l_hh / 2)
    r[31] = r[13] - _y(l_hh / 2)
    return [r[i] for i in range(1, 32)], {"knee": knee, "elbow": elbow}


@dataclass
class Segment:
    """One rigid segment of the rider."""

    name: str
    shape: str
    start: int
    end: int
    mass: sp.Expr
    local_inertia: sp.Matrix
    length: sp.Expr


def segments() -> list[Segment]:
    """The eleven segments of Fig. 4 with their local inertia tensors (Table 9)."""
    (l_hh, l_la, l_ll, l_ss, l_to, l_ua, l_ul, lam_fl, c_h) = syms(RIDER_ARGS)
    (mBr, c_ch, c_la, c_ll, c_ua, c_ul, f_h, f_la, f_ll, f_to, f_ua, f_ul) = syms(SEGMENT_ARGS)
    pi = sp.pi

    def cylinder(m, circumference, length):
        transverse = m / 12 * (3 * circumference**2 / (4 * pi**2) + length**2)
        return sp.diag(transverse, transverse, m * circumference**2 / (8 * pi**2))

    l_y = l_ss - c_ua / pi  # Eq. 9
    l_x = (c_ch - 2 * l_y) / (pi - 2)  # Eq. 10
    l_z = l_to
    m_to = f_to * mBr
    torso = m_to / 12 * sp.diag(l_y**2 + l_z**2, l_x**2 + l_z**2, l_x**2 + l_y**2)
    m_h = f_h * mBr
    head = sp.eye(3) * m_h * c_h**2 / (10 * pi**2)
    out = [
        Segment("torso", "cuboid", 13, 15, m_to, torso, l_to),
        Segment("head", "sphere", 25, 25, m_h, head, sp.Integer(0)),
    ]
    limbs = [
        ("lower leg", f_ll, c_ll, l_ll, ((26, 28), (27, 29))),
        ("upper leg", f_ul, c_ul, l_ul, ((28, 30), (29, 31))),
        ("upper arm", f_ua, c_ua, l_ua, ((21, 23), (22, 24))),
        ("lower arm", f_la, c_la, l_la, ((19, 23), (20, 24))),
    ]
    for name, fraction, circumference, length, ends in limbs:
        for side, (a, b) in zip(("right", "left"), ends):
            m = fraction * mBr
            out.append(Segment(f"{side} {name}", "cylinder", a, b, m, cylinder(m, circumference, length), length))
    return out


def rotation(direction: sp.Matrix, length: sp.Expr) -> sp.Matrix:
    """Eq. 11 for a segment in a plane y = const: columns are the local x, y, z axes."""
    z = direction / length
    y = sp.Matrix([0, 1, 0])
    x = y.cross(z)
    return sp.Matrix.hstack(x, y, z)


def parallel_axis(m: sp.Expr, d: sp.Matrix) -> sp.Matrix:
    """Eq. 13: the term added to move an inertia tensor from a mass centre by ``d``."""
    dx, dy, dz = d
    return m * sp.Matrix(
        [
            [dy**2 + dz**2, -dx * dy, -dx * dz],
            [-dx * dy, dz**2 + dx**2, -dy * dz],
            [-dx * dz, -dy * dz, dx**2 + dy**2],
        ]
    )


def rider_mass_properties(points: list[sp.Matrix]) -> tuple[sp.Expr, sp.Matrix, sp.Matrix]:
    """Rider mass, centre of mass (Eq. 8) and inertia tensor about it (Eqs. 11-14)."""
    segs = segments()
    mass = sp.Add(*(s.mass for s in segs))
    centres = [(points[s.start - 1] + points[s.end - 1]) / 2 for s in segs]
    com = sp.Matrix.zeros(3, 1)
    for s, r in zip(segs, centres):
        com += s.mass * r
    com = com / mass
    inertia = sp.zeros(3, 3)
    for s, r in zip(segs, centres):
        if s.shape == "sphere":
            local = s.local_inertia
        else:
            R = rotation(points[s.end - 1] - points[s.start - 1], s.length)
            local = R * s.local_inertia * R.T
        inertia += local + parallel_axis(s.mass, r - com)
    return mass, com, inertia


def build() -> GeneratedModule:
    points, closures = grid_points()
    geometry = syms(GEOMETRY_ARGS)
    placement = syms(RIDER_ARGS)
    segment_args = syms(SEGMENT_ARGS)
    grid = sp.Matrix.vstack(*(p.T for p in points))
    mass, com, inertia = rider_mass_properties(points)
    knee, elbow = closures["knee"], closures["elbow"]
    reach = sp.Matrix([knee.distance, knee.reach, elbow.distance, elbow.reach])
    branch_text = "\n".join(f"    {name}: q = {sp.sstr(b)}" for name, c in closures.items() for b in c.branches)
    description = (
        "Derived in derive/rider_model.py.  Closure branches found by SymPy (D is the distance\n"
        "between the limb's ends, l_a and l_b the lengths from the distal and proximal ends):\n\n"
        f"{branch_text}\n\n"
        "The natural branch is q >= 0 along the limb direction turned a quarter turn, the same way\n"
        "for every direction of the limb (forward for a knee over the pedals, down for an elbow below\n"
        "the shoulders)."
    )
    used_geometry = [s for s in geometry if s.name not in ("w_rh", "w_fh")]
    return GeneratedModule(
        name="rider_model",
        summary="Seated rider on the bicycle (Moore et al. 2009): grid points, limb reach, mass properties.",
        description=description,
        names={
            "GEOMETRY": tuple(GEOMETRY_ARGS.split()),
            "RIDER_PLACEMENT": tuple(RIDER_ARGS.split()),
            "RIDER_SEGMENTS": tuple(SEGMENT_ARGS.split()),
        },
        functions=[
            GeneratedFunction(
                "grid_points",
                geometry + placement,
                [Output("points", grid, "grid points 1..31 (rows) in the benchmark frame [m]")],
                "The 31 skeleton grid points of Table 10, knees and elbows on the natural branch.",
            ),
            GeneratedFunction(
                "limb_reach",
                used_geometry + placement,
                [
                    Output(
                        "reach",
                        reach,
                        "[hip to pedal-axis distance, l_ll + l_ul, shoulder to hand distance, l_ua + l_la] [m]",
                        vector=True,
                    )
                ],
                "Distances the leg and arm closures must span, and the limb lengths that span them.",
                notes="A closure has a solution when |l_a - l_b| <= distance <= l_a + l_b.",
            ),
            GeneratedFunction(
                "rider_mass_properties",
                used_geometry + placement + segment_args,
                [
                    Output("mass", mass, "rider mass, the sum of the segment masses [kg]"),
                    Output("com", com, "rider centre of mass [x, y, z] (Eq. 8) [m]", vector=True),
                    Output("inertia", inertia, "rider inertia tensor about its centre of mass (Eq. 14) [kg m^2]"),
                ],
                "Rider mass, centre of mass and inertia tensor from cylinders, a cuboid and a sphere.",
            ),
        ],
    )
