"""The estimate chain: the manifest's stage kinds bound to the chain's nodes.

A *node* is a named quantity (a measurement, a benchmark parameter, a matrix entry, a speed).  Which
stages run depends on which nodes the caller provides: a caller who gives pendulum periods gets the
pendulum stages; one who gives the benchmark parameters enters the graph at the canonical matrices.
Every stage is a kind of ``generated/manifest.py`` (its inputs, outputs, value and Jacobian come
from there); this module only says which node each of them reads and writes.

Raw measurement names beyond the chain's own arguments (the pendulum measurements whose
reductions would otherwise hide their correlations; described in ``derive/symbols.py``):

=============================  =============================================================
``k_t``                        torsional pendulum stiffness, shared by every torsional period
``T_Bf1..3``, ``alpha_Bf1..3``  rear frame torsional periods and axis angles (Table 4)
``T_H1..3``, ``alpha_H1..3``    handlebar/fork torsional periods and axis angles (Table 4)
``T_Rxx``, ``T_Fxx``            wheel torsional periods about a diameter (Table 6, Eq. 1)
``T_Ryy``, ``T_Fyy``            wheel compound pendulum periods (Table 6, Eq. 7)
``l_pR``, ``l_pF``              compound pendulum lengths (the pendulum mass is the wheel's)
=============================  =============================================================
"""

from __future__ import annotations

from functools import cache

from bikerider.engine import GeneratedStage, Stage
from bikerider.generated.manifest import MATRIX_ENTRIES, STAGES
from bikerider.uncertainty.speeds import SPEEDS, CriticalSpeedsStage

ENTRIES = MATRIX_ENTRIES
CANONICAL = STAGES["canonical"]["inputs"]
COEFFICIENTS = STAGES["characteristic"]["outputs"]
FRAME = tuple(name for name in STAGES["rear_body"]["inputs"] if "Bf" in name)
REAR_BODY = STAGES["rear_body"]["outputs"]
OPTIONAL_NAN = ("IBfyy", "IHyy")
"""Inputs the linear model does not need: NaN when absent, which reaches only IByy and IHyy."""
__all__ = ["CANONICAL", "COEFFICIENTS", "ENTRIES", "FRAME", "OPTIONAL_NAN", "REAR_BODY", "SPEEDS", "all_stages"]


def _pendulum_stage(body: str, prefix: str) -> GeneratedStage:
    """Eq. 6 of a body hung in three orientations (Table 4)."""
    inputs = {f"{kind}_{i}": f"{kind}_{prefix}{i}" for kind in ("T", "alpha") for i in (1, 2, 3)}
    return GeneratedStage(
        "three_orientations",
        f"{body}_pendulum",
        inputs,
        {f"I{axes}": f"I{prefix}{axes}" for axes in ("xx", "xz", "zz")},
    )


def _wheel_stages(wheel: str) -> tuple[GeneratedStage, GeneratedStage]:
    """Eq. 1 about a diameter and Eq. 7 about the axle (Table 6)."""
    return (
        GeneratedStage("torsional", f"{wheel}_wheel_torsional", {"T": f"T_{wheel}xx"}, {"J": f"I{wheel}xx"}),
        GeneratedStage(
            "compound",
            f"{wheel}_wheel_compound",
            {"T": f"T_{wheel}yy", "m_p": f"m{wheel}", "l_p": f"l_p{wheel}"},
            {"Iyy": f"I{wheel}yy"},
        ),
    )


@cache
def all_stages() -> tuple[Stage, ...]:
    """Every stage, in an order where each stage's inputs come from earlier ones or the caller.

    The characteristic coefficients run only when the caller gives a speed ``v``.
    """
    rear_torsional, rear_compound = _wheel_stages("R")
    front_torsional, front_compound = _wheel_stages("F")
    return (
        _pendulum_stage("frame", "Bf"),
        _pendulum_stage("handlebar", "H"),
        rear_torsional,
        front_torsional,
        rear_compound,
        front_compound,
        GeneratedStage("grid"),
        GeneratedStage("knee"),
        GeneratedStage("elbow"),
        GeneratedStage("rider_com"),
        GeneratedStage("rider_inertia"),
        GeneratedStage("rear_body", inputs={"mBr": "mBr_sum"}),  # the rider's mass as its segments sum it
        GeneratedStage("steer_axis"),
        GeneratedStage("canonical"),
        GeneratedStage("characteristic"),
        CriticalSpeedsStage(),
    )
