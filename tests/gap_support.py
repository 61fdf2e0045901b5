"""Pieces the gap tests share: the riderless Davis bicycle, the SBW experiment's kind of control law, and
synthetic free decays of a linear model."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import bikerider
from bikerider.gap.candidates.effect_model import BENCH_ARGS, EffectModel
from bikerider.gap.inference.predict import Predictor
from bikerider.gap.measured.control import ControlLaw, GainSchedule
from bikerider.gap.measured.records import Record
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
from bikerider.io.gap_model import load_model

DATA = Path(bikerider.__file__).parent / "data"
BP = DATA / "bicycleparameters"
MODEL = [
    "--model",
    str(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt"),
    "--rider",
    str(BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt"),
]
"""``bikerider gap`` arguments of the Davis bicycle with its rider (the shipped example's model)."""
SIL = ControlLaw("sil", {"k_phid": GainSchedule.make_ramp(2.0, 6.5, "below")})
"""Steer into lean below 6.5 m/s, as the steer-by-wire experiment's law."""


def riderless_model():
    """The Davis instrumented bicycle without its rider (BicycleParameters' RigidBenchmark.txt)."""
    return load_model(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt")


def nominal(model) -> dict[str, float]:
    """A model file's benchmark values and ``g``."""
    return {k: float(model.parameters.values[k]) for k in BENCH_ARGS + ("g",)}


def decay_record(
    model,
    speed: float,
    group: str,
    effects=None,
    *,
    seed: int = 0,
    duration: float = 2.0,
    noise: float = 0.01,
    steer_noise: float = 0.0,
    initial=None,
    speed_measured: bool = False,
) -> Record:
    """A linear model's decay under :data:`SIL` after a push (roll rate and steer angle, 100 Hz), with noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 0.01)
    out = EffectModel(nominal(model), model.geometry, effects or {}).simulate(
        speed, t, initial=initial or {"phid": 0.6, "deltad": 0.3}, gains=SIL(speed)
    )
    signals = {
        "roll_rate": out["phid"] + noise * rng.standard_normal(t.size),
        "steer_angle": out["delta"] + (steer_noise * rng.standard_normal(t.size) if steer_noise else 0.0),
    }
    return Record(
        f"{group}[{seed}]",
        "test",
        t,
        signals,
        speed,
        0.01,
        group,
        SIL,
        speed,
        None,
        None,
        ("roll_rate",),
        speed_measured,
    )


def friction_decay_record(
    values: dict, geometry, speed: float, group: str, seed: int, T_coulomb: float, c_viscous: float, noise: float = 0.01
) -> Record:
    """A decay under :data:`SIL` of a bicycle with Coulomb and viscous steer friction simulated by the time-domain
    fit's own law (``timedomain.simulate_friction``): roll rate with noise and the steer angle, 100 Hz, 2 s."""
    from bikerider.gap.inference.timedomain import simulate_friction

    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 2.0, 0.01)
    ss = EffectModel(values, geometry, {"steer_damping": {"c_steer": c_viscous}}).state_space([speed])
    A = ss.closed_loop(np.array([SIL(speed)]))[0]
    outputs = ss.output_states
    x0 = np.zeros(A.shape[-1])
    x0[outputs[2]], x0[outputs[3]], x0[outputs[1]] = 0.6 * (-1) ** seed, 0.5, 0.02
    states = simulate_friction(A, ss.B[0, :, 1], x0, T_coulomb, 0.01, t.size, outputs[3])
    signals = {
        "roll_rate": states[:, outputs[2]] + noise * rng.standard_normal(t.size),
        "steer_angle": states[:, outputs[1]],
    }
    return Record(
        f"{group}[{seed}]", "test", t, signals, speed, 0.01, group, SIL, speed, None, None, ("roll_rate",), False
    )


def weave_table(model, speeds: np.ndarray, effects: dict) -> EigenvalueData:
    """Weave eigenvalues of ``model`` with ``effects`` at ``speeds`` (no noise), standard errors 0.05."""
    values = nominal(model)

    def table(eigenvalues):
        n = speeds.size
        return EigenvalueData(
            speeds, eigenvalues, np.full(n, 0.05), np.full(n, 0.05), np.zeros(n), ["weave"] * n, ["a"] * n,
            np.zeros((n, 4)), [f"run {k}" for k in range(n)],
        )  # fmt: skip

    weave = Predictor(table(np.zeros(speeds.size, complex)), CanonicalData.empty(), values, model.geometry)
    return table(weave.eigenvalues(EffectModel(values, model.geometry, effects)))
