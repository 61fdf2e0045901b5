"""The estimate chain as a graph of stages, each with a value function and a closed-form Jacobian.

A *node* is a named quantity (a measurement, a benchmark parameter, a matrix entry, a speed).  A
:class:`Stage` turns input nodes into output nodes with a generated value function and the
generated Jacobian of ``derive/sensitivities.py``.  Which stages run depends on which nodes the
caller provides: a caller who gives pendulum periods gets the pendulum stages; one who gives the
benchmark parameters enters the graph at the canonical matrices.

Raw measurement names beyond the chain's own arguments (the pendulum measurements whose
reductions would otherwise hide their correlations):

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

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bikerider.generated import benchmark_model as gen_model
from bikerider.generated import combination as gen_combination
from bikerider.generated import pendulum as gen_pendulum
from bikerider.generated import sensitivities as gen

GEOMETRY = ("h_bb", "l_cs", "l_f", "rF", "l_hb", "lam_ht", "rR", "l_sp", "lam_st", "l_st", "l_s", "c", "w")
PLACEMENT = ("l_hh", "l_la", "l_ll", "l_ss", "l_to", "l_ua", "l_ul", "lam_fl", "c_h")
SEGMENTS = ("mBr", "c_ch", "c_la", "c_ll", "c_ua", "c_ul", "f_h", "f_la", "f_ll", "f_to", "f_ua", "f_ul")
GRID_POINTS = (5, 13, 14, 15, 19, 23, 25)
COORDINATES = tuple(f"r{axis}{k}" for k in GRID_POINTS for axis in "XZ")
FRAME = ("mBf", "xBf", "zBf", "IBfxx", "IBfyy", "IBfzz", "IBfxz")
RIDER_BODY = ("mBr_sum", "xBr", "zBr", "IBrxx", "IBryy", "IBrzz", "IBrxz")
REAR_BODY = ("mB", "xB", "zB", "IBxx", "IByy", "IBzz", "IBxz")
CANONICAL = ("w", "c", "lam", "rR", "mR", "IRxx", "IRyy", "xB", "zB", "mB", "IBxx", "IBzz", "IBxz",
             "xH", "zH", "mH", "IHxx", "IHzz", "IHxz", "rF", "mF", "IFxx", "IFyy")
MATRIX_NAMES = ("M", "C1", "K0", "K2")
ENTRIES = tuple(f"{m}_{a}{b}" for m in MATRIX_NAMES for a in ("phi", "delta") for b in ("phi", "delta"))
COEFFICIENTS = ("a4", "a3", "a2", "a1", "a0")
SPEEDS = ("v_weave", "v_capsize")
OPTIONAL_NAN = ("IBfyy", "IHyy")
"""Inputs the linear model does not need: NaN when absent, which reaches only IByy and IHyy."""

Arrays = dict[str, np.ndarray]


@dataclass(frozen=True)
class Stage:
    """One step of the chain.

    Attributes
    ----------
    name : str
    inputs, outputs : tuple of str
        Node names, in the order of the Jacobian's columns and rows.
    args : tuple of str
        Keyword names of the generated functions, aligned with ``inputs``.
    value : callable
        ``value(kwargs) -> list of arrays`` aligned with ``outputs``.
    jacobian : callable
        ``jacobian(kwargs) -> array (..., len(outputs), len(inputs))``.
    symbolic : str or None
        Key of the stage's expressions in ``generated.sensitivities.STAGES``.
    """

    name: str
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    args: tuple[str, ...]
    value: Callable[[Arrays], list[np.ndarray]]
    jacobian: Callable[[Arrays], np.ndarray]
    symbolic: str | None

    def kwargs(self, nodes: Arrays) -> Arrays:
        """Keyword arguments of the generated functions from node values."""
        return {arg: nodes[name] for arg, name in zip(self.args, self.inputs)}


def _columns(array: np.ndarray) -> list[np.ndarray]:
    return [array[..., i] for i in range(array.shape[-1])]


def _pendulum_stage(body: str, prefix: str) -> Stage:
    names = ("k_t", *(f"T_{prefix}{i}" for i in (1, 2, 3)), *(f"alpha_{prefix}{i}" for i in (1, 2, 3)))

    def value(kw: Arrays) -> list[np.ndarray]:
        inertia, _ = gen_pendulum.inertia_from_three_orientations(**kw)
        return _columns(inertia)

    return Stage(
        f"{body}_pendulum", names, (f"I{prefix}xx", f"I{prefix}xz", f"I{prefix}zz"),
        ("k_t", "T_1", "T_2", "T_3", "alpha_1", "alpha_2", "alpha_3"),
        value, lambda kw: gen.three_orientations_jacobian(**kw), "three_orientations",
    )


def _torsional_stage(wheel: str) -> Stage:
    return Stage(
        f"{wheel}_wheel_torsional", ("k_t", f"T_{wheel}xx"), (f"I{wheel}xx",), ("k_t", "T"),
        lambda kw: [gen_pendulum.torsional_inertia(**kw)], lambda kw: gen.torsional_jacobian(**kw), "torsional",
    )


def _compound_stage(wheel: str) -> Stage:
    return Stage(
        f"{wheel}_wheel_compound", (f"T_{wheel}yy", f"m{wheel}", "g", f"l_p{wheel}"), (f"I{wheel}yy",),
        ("T", "m_p", "g", "l_p"),
        lambda kw: [gen_pendulum.compound_inertia(**kw)], lambda kw: gen.compound_jacobian(**kw), "compound",
    )


def _vector_stage(name: str, inputs: tuple[str, ...], outputs: tuple[str, ...], value_fn, jac_fn,
                  args: tuple[str, ...] | None = None) -> Stage:
    return Stage(name, inputs, outputs, args or inputs,
                 lambda kw: _columns(value_fn(**kw)), lambda kw: jac_fn(**kw), name)


def _rear_body_value(kw: Arrays) -> list[np.ndarray]:
    mB, xB, zB, IB = gen_combination.rear_body(**kw)
    return [mB, xB, zB, IB[..., 0, 0], IB[..., 1, 1], IB[..., 2, 2], IB[..., 0, 2]]


def _canonical_value(kw: Arrays) -> list[np.ndarray]:
    mats = gen_model.canonical_matrices(**kw)
    return [m[..., i, j] for m in mats for i in (0, 1) for j in (0, 1)]


def _steer_axis_value(kw: Arrays) -> list[np.ndarray]:
    return [math.pi / 2 - kw["lam_ht"]]


def _steer_axis_jacobian(kw: Arrays) -> np.ndarray:
    # d(lam)/d(lam_ht) for lam = pi/2 - lam_ht (derive/combination.py)
    return np.full(np.shape(kw["lam_ht"]) + (1, 1), -1.0)


def _characteristic_value(kw: Arrays) -> list[np.ndarray]:
    return _columns(gen_model.characteristic_coefficients(**kw))


def all_stages() -> tuple[Stage, ...]:
    """Every stage, in an order where each stage's inputs come from earlier ones or the caller.

    The critical speeds are a stage of their own (:mod:`bikerider.uncertainty.speeds`); the
    characteristic coefficients run only when the caller gives a speed ``v``.
    """
    from bikerider.uncertainty import speeds

    rider_args = COORDINATES + PLACEMENT + SEGMENTS
    return (
        _pendulum_stage("frame", "Bf"),
        _pendulum_stage("handlebar", "H"),
        _torsional_stage("R"),
        _torsional_stage("F"),
        _compound_stage("R"),
        _compound_stage("F"),
        _vector_stage("grid", GEOMETRY + ("l_to", "lam_fl", "c_h"), COORDINATES[:4] + COORDINATES[6:10] + COORDINATES[12:],
                      gen.grid_coordinates, gen.grid_jacobian),
        _vector_stage("knee", ("rX5", "rZ5", "rX13", "rZ13", "l_ll", "l_ul"), ("rX14", "rZ14"),
                      gen.knee, gen.knee_jacobian),
        _vector_stage("elbow", ("rX19", "rZ19", "rX15", "rZ15", "l_la", "l_ua"), ("rX23", "rZ23"),
                      gen.elbow, gen.elbow_jacobian),
        _vector_stage("rider_com", rider_args, RIDER_BODY[:3], gen.rider_com, gen.rider_com_jacobian),
        _vector_stage("rider_inertia", rider_args + ("xBr", "zBr"), RIDER_BODY[3:],
                      gen.rider_inertia, gen.rider_inertia_jacobian),
        Stage("rear_body", FRAME + RIDER_BODY, REAR_BODY, FRAME + ("mBr",) + RIDER_BODY[1:],
              _rear_body_value, lambda kw: gen.rear_body_jacobian(**kw), "rear_body"),
        Stage("steer_axis", ("lam_ht",), ("lam",), ("lam_ht",), _steer_axis_value, _steer_axis_jacobian, "steer_axis"),
        Stage("canonical", CANONICAL, ENTRIES, CANONICAL, _canonical_value,
              lambda kw: gen.canonical_jacobian(**kw), "canonical"),
        Stage("characteristic", ENTRIES + ("g", "v"), COEFFICIENTS, ENTRIES + ("g", "v"), _characteristic_value,
              lambda kw: gen.characteristic_jacobian(**kw), "characteristic"),
        speeds.speed_stage(),
    )
