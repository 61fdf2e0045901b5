"""Rear frame plus rider into the benchmark's rear body B (Moore et al. 2009, Eqs. 15-16), and the
whole chain from the paper's measurements to the 26 benchmark values (Table 12).

Both bodies are symmetric about the XZ plane, so their centres of mass have y = 0 and the parallel
axis terms (Eq. 13) move only the xx, yy, zz and xz entries.
"""

from __future__ import annotations

import sympy as sp

from derive import rider_model
from derive.codegen import GeneratedFunction, GeneratedModule, Output
from derive.rider_model import parallel_axis
from derive.symbols import BENCHMARK_NAMES, sym, syms

FRAME_ARGS = "mBf xBf zBf IBfxx IBfyy IBfzz IBfxz"
RIDER_BODY_ARGS = "mBr xBr zBr IBrxx IBryy IBrzz IBrxz"
BODY_ARGS = "mR IRxx IRyy mF IFxx IFyy mH xH zH IHxx IHyy IHzz IHxz"
"""Wheels and handlebar/fork, which pass through to the benchmark unchanged."""


def _tensor(xx, yy, zz, xz) -> sp.Matrix:
    return sp.Matrix([[xx, 0, xz], [0, yy, 0], [xz, 0, zz]])


def combine(m1, x1, z1, I1: sp.Matrix, m2, x2, z2, I2: sp.Matrix):
    """Mass, centre of mass and inertia tensor of two bodies in the XZ plane of symmetry."""
    m = m1 + m2  # Eq. 15
    x = (m1 * x1 + m2 * x2) / m  # Eq. 16
    z = (m1 * z1 + m2 * z2) / m
    I = I1 + parallel_axis(m1, sp.Matrix([x1 - x, 0, z1 - z])) + I2 + parallel_axis(m2, sp.Matrix([x2 - x, 0, z2 - z]))
    return m, x, z, I


def rear_body() -> tuple[sp.Expr, sp.Expr, sp.Expr, sp.Matrix]:
    """Rear body B from the rear frame Bf and the rider Br (symbols for both)."""
    mBf, xBf, zBf, IBfxx, IBfyy, IBfzz, IBfxz = syms(FRAME_ARGS)
    mBr, xBr, zBr, IBrxx, IBryy, IBrzz, IBrxz = syms(RIDER_BODY_ARGS)
    return combine(
        mBf,
        xBf,
        zBf,
        _tensor(IBfxx, IBfyy, IBfzz, IBfxz),
        mBr,
        xBr,
        zBr,
        _tensor(IBrxx, IBryy, IBrzz, IBrxz),
    )


def benchmark_chain() -> tuple[list[sp.Symbol], sp.Matrix]:
    """The 26 benchmark values from bicycle geometry, measured bodies and rider measurements."""
    points, _ = rider_model.grid_points()
    m_r, com_r, I_r = rider_model.rider_mass_properties(points)
    mBf, xBf, zBf, IBfxx, IBfyy, IBfzz, IBfxz = syms(FRAME_ARGS)
    mB, xB, zB, IB = combine(mBf, xBf, zBf, _tensor(IBfxx, IBfyy, IBfzz, IBfxz), m_r, com_r[0], com_r[2], I_r)
    values = {name: sym(name) for name in BENCHMARK_NAMES}
    values.update(
        lam=sp.pi / 2 - sym("lam_ht"),
        mB=mB,
        xB=xB,
        zB=zB,
        IBxx=IB[0, 0],
        IByy=IB[1, 1],
        IBzz=IB[2, 2],
        IBxz=IB[0, 2],
    )
    geometry = [s for s in syms(rider_model.GEOMETRY_ARGS) if s.name not in ("w_rh", "w_fh")]
    args = (
        geometry
        + [sym("g")]
        + syms(BODY_ARGS)
        + syms(FRAME_ARGS)
        + syms(rider_model.RIDER_ARGS)
        + syms(rider_model.SEGMENT_ARGS)
    )
    return args, sp.Matrix([values[n] for n in BENCHMARK_NAMES])


def build() -> GeneratedModule:
    mB, xB, zB, IB = rear_body()
    chain_args, chain = benchmark_chain()
    return GeneratedModule(
        name="combination",
        summary="Rear frame and rider combined into the benchmark rear body; the whole estimate chain.",
        description=__doc__.strip(),
        names={"BENCHMARK_NAMES": tuple(BENCHMARK_NAMES)},
        functions=[
            GeneratedFunction(
                "rear_body",
                syms(FRAME_ARGS) + syms(RIDER_BODY_ARGS),
                [
                    Output("mB", mB, "rear body mass (Eq. 15) [kg]"),
                    Output("xB", xB, "rear body centre of mass x (Eq. 16) [m]"),
                    Output("zB", zB, "rear body centre of mass z (Eq. 16) [m]"),
                    Output("IB", IB, "rear body inertia tensor about its centre of mass [kg m^2]"),
                ],
                "Combine the rear frame and the rider into the benchmark rear body B.",
                scalar=True,  # merging one lumped rider (bikerider.bicycle.to_benchmark)
            ),
            GeneratedFunction(
                "estimate_chain",
                chain_args,
                [
                    Output(
                        "parameters",
                        chain,
                        "the 26 benchmark values in the order " + ", ".join(BENCHMARK_NAMES) + " [SI]",
                        vector=True,
                    )
                ],
                "The whole estimate in one expression: bicycle and rider measurements to the benchmark "
                "parameters (Table 12).",
                notes=(
                    "lam = pi/2 - lam_ht.  IByy is NaN-free only when IBfyy is given.  The runtime computes "
                    "the same chain stage by stage (bikerider.uncertainty.stages); this one-piece form is "
                    "the tests' independent check of the stages."
                ),
            ),
        ],
    )
