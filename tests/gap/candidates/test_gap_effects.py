"""The candidate-effect models of derive/gap_effects.py: limits, cross-checks, time response, control."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bikerider.generated import benchmark_model as bm
from bikerider.generated import gap_effects as gen

from bikerider.benchmark.model import label_modes
from bikerider.errors import InputError
from bikerider.gap.candidates.effect_model import BENCH_ARGS, EffectModel, RiderGeometry
from bikerider.io.gap_model import load_model

ZERO_EXTRAS = dict(I_steer=0.0, c_steer=0.0, k_steer=0.0, m_arm=0.0, k_arm=0.0, c_arm=0.0)
GRIPS = dict(x_grip=0.85, z_grip=-1.05, b_grip=0.3)
UPPER = dict(m_u=40.0, x_u=0.3, z_u=-1.2, IUxx=1.5, IUxz=0.3, IUzz=1.0, z_lean=-0.95)


@pytest.fixture(scope="module")
def bench(benchmark_values):
    return {k: benchmark_values[k] for k in BENCH_ARGS}


@pytest.fixture(scope="module")
def geometry():
    return RiderGeometry(dict(UPPER), dict(GRIPS))


def _whipple(bench, v):
    M, C1, K0, K2 = bm.canonical_matrices(**bench)
    return M, v * C1, 9.81 * K0 + v**2 * K2


def test_extended_model_without_effects_is_meijaard_2007(bench, meijaard2007):
    # Meijaard et al. (2007) section 5: M, C1, K0, K2 of the benchmark bicycle to 14 decimals.
    ref = meijaard2007["matrices"]
    for v in (0.5, 4.0, 7.0):
        M, C, K = gen.whipple_extended_matrices(**bench, **ZERO_EXTRAS, **GRIPS, g=9.81, v=v)
        np.testing.assert_allclose(M, ref["M"], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(C, v * np.array(ref["C1"]), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(K, 9.81 * np.array(ref["K0"]) + v**2 * np.array(ref["K2"]), rtol=1e-11, atol=1e-10)


def test_steer_damping_and_stiffness_act_between_the_frames_only(bench):
    v = 5.0
    M0, C0, K0 = gen.whipple_extended_matrices(**bench, **ZERO_EXTRAS, **GRIPS, g=9.81, v=v)
    extras = dict(ZERO_EXTRAS, c_steer=0.4, k_steer=3.0)
    M, C, K = gen.whipple_extended_matrices(**bench, **extras, **GRIPS, g=9.81, v=v)
    np.testing.assert_allclose(M, M0, atol=1e-14)
    np.testing.assert_allclose(C - C0, [[0, 0], [0, 0.4]], atol=1e-12)
    np.testing.assert_allclose(K - K0, [[0, 0], [0, 3.0]], atol=1e-10)


def test_added_steer_inertia_equals_a_front_frame_inertia_about_the_steer_axis(bench):
    # Two derivations: the Lagrangian with a body of inertia I_steer about the steer axis, and
    # Meijaard's Appendix A formulas with I n n^T added to the handlebar's inertia tensor.
    I = 0.25
    lam = bench["lam"]
    n = np.array([math.sin(lam), math.cos(lam)])
    moved = dict(
        bench,
        IHxx=bench["IHxx"] + I * n[0] ** 2,
        IHzz=bench["IHzz"] + I * n[1] ** 2,
        IHxz=bench["IHxz"] + I * n[0] * n[1],
    )
    for v in (1.0, 6.0):
        M, C, K = gen.whipple_extended_matrices(**bench, **dict(ZERO_EXTRAS, I_steer=I), **GRIPS, g=9.81, v=v)
        Mr, Cr, Kr = _whipple(moved, v)
        np.testing.assert_allclose(M, Mr, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(C, Cr, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(K, Kr, rtol=1e-12, atol=1e-10)


def test_arm_masses_equal_moving_point_masses_from_rear_body_to_handlebar(bench):
    # Lagrangian (point masses on the front frame minus the same on the rear frame) against the
    # parallel-axis theorem on the benchmark bodies (the validation truth's implementation).
    from validation.cases import _move_arms

    moved = _move_arms(dict(bench), 3.0, GRIPS)
    for v in (2.0, 6.0):
        M, C, K = gen.whipple_extended_matrices(**bench, **dict(ZERO_EXTRAS, m_arm=3.0), **GRIPS, g=9.81, v=v)
        Mr, Cr, Kr = _whipple({k: moved[k] for k in BENCH_ARGS}, v)
        np.testing.assert_allclose(M, Mr, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(C, Cr, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(K, Kr, rtol=1e-12, atol=1e-10)


def test_rider_lean_matches_the_hand_derived_coupling(bench):
    # The validation truth assembles the lean coupling by Newton-Euler; the candidate comes from the
    # Lagrangian with the nonholonomic projection.  Their leading 2x2 blocks are Meijaard's.
    from validation.cases import TRUTHS, TruthSimulator

    sim = TruthSimulator.__new__(TruthSimulator)  # only the parts _lean_terms reads
    sim.values = dict(bench, g=9.81)
    sim.g = 9.81
    sim.geometry = {"upper": dict(UPPER)}
    sim.truth = TRUTHS["rider_lean"]
    for v in (2.0, 5.5):
        M, C, K = gen.rider_lean_matrices(**bench, **UPPER, k_lean=0.0, c_lean=0.0, **ZERO_EXTRAS, **GRIPS, g=9.81, v=v)
        Mw, Cw, Kw = _whipple(bench, v)
        Ml, Cl, Kl = sim._lean_terms(v)
        np.testing.assert_allclose(M[:2, :2], Mw, atol=1e-12)
        np.testing.assert_allclose(C[:2, :2], Cw, atol=1e-12)
        np.testing.assert_allclose(K[:2, :2], Kw, atol=1e-9)
        m, h = UPPER["m_u"], UPPER["z_lean"] - UPPER["z_u"]
        np.testing.assert_allclose(M[:, 2], Ml[:, 2], atol=1e-12)
        np.testing.assert_allclose(C[2], Cl[2], atol=1e-12)
        np.testing.assert_allclose(C[:2, 2], 0.0, atol=1e-12)
        # gravity on the upper body: -g m h in the roll-lean and lean-lean entries
        np.testing.assert_allclose(K[2], [-9.81 * m * h, Kl[2, 1], -9.81 * m * h], atol=1e-9)
        np.testing.assert_allclose(K[0, 2], Kl[0, 2], atol=1e-9)


def _weave_capsize_castor(eigs: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """The eigenvalues of ``eigs`` nearest each of ``reference``."""
    return np.array([eigs[np.argmin(np.abs(eigs - r))] for r in reference])


def test_stiff_lean_reproduces_the_whipple_eigenvalues(bench, geometry):
    speeds = np.array([2.0, 4.5, 7.0])
    values = dict(bench, g=9.81)
    whipple = EffectModel(values, geometry).eigenvalues(speeds)
    stiff = EffectModel(values, geometry, {"rider_lean": {"k_lean": 1e8, "c_lean": 1e3}}).eigenvalues(speeds)
    for w, s in zip(whipple, stiff):
        np.testing.assert_allclose(_weave_capsize_castor(s, w), w, atol=2e-3)


@pytest.mark.parametrize("relaxation", [0.2, 0.01])
def test_stiff_tyres_reproduce_the_whipple_eigenvalues(bench, geometry, relaxation):
    # As the cornering stiffness grows without bound the slip vanishes: the four Whipple eigenvalues
    # return and the tyre modes leave for infinity.
    speeds = np.array([1.0, 3.0, 4.5, 6.0, 9.0])
    values = dict(bench, g=9.81)
    whipple = EffectModel(values, geometry).eigenvalues(speeds)
    for c_alpha, tol in ((1e4, 2e-2), (1e6, 2e-4)):
        tyre = EffectModel(
            values, geometry, {"tyre_slip": {"c_alpha": c_alpha, "c_gamma": 0.8, "sigma_t": relaxation, "t_p": 0.0}}
        ).eigenvalues(speeds)
        for w, t in zip(whipple, tyre):
            near = _weave_capsize_castor(t, w)
            np.testing.assert_allclose(near, w, atol=tol * max(1.0, np.abs(w).max()))
            others = np.array([x for x in t if np.min(np.abs(near - x)) > 1e-9])
            assert others.size == 4 and np.min(np.abs(others)) > 20


def test_realistic_tyres_change_the_weave_only_a_little(bench, geometry):
    # A physical check on the tyre model: with literature values and no pneumatic trail the weave
    # moves by a few per cent at most, as rigid-contact models are known to predict weave well.
    speeds = np.array([4.0, 6.0])
    values = dict(bench, g=9.81)
    ref, _ = label_modes(EffectModel(values, geometry).eigenvalues(speeds))
    tyre = EffectModel(values, geometry, {"tyre_slip": {"c_alpha": 13.0, "c_gamma": 0.8, "sigma_t": 0.2, "t_p": 0.0}})
    eigs = tyre.eigenvalues(speeds)
    for k in range(2):
        weave = _weave_capsize_castor(eigs[k], ref[k, :1])[0]
        assert abs(weave - ref[k, 0]) < 0.1 * abs(ref[k, 0])


def test_control_gains_close_the_loop_in_benchmark_convention(bench, geometry):
    # T_delta = k_phi phi + k_phid phid + k_delta delta + k_deltad deltad added to M q'' + C q' + K q = f
    gains = np.array([3.0, 5.0, -2.0, -0.5])
    v = 4.0
    M, C, K = _whipple(bench, v)
    Kc = K - np.array([[0, 0], [gains[0], gains[2]]])
    Cc = C - np.array([[0, 0], [gains[1], gains[3]]])
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(M, Kc), -np.linalg.solve(M, Cc)]])
    expected = np.sort_complex(np.linalg.eigvals(A))
    for effects in ({}, {"tyre_slip": {"c_alpha": 1e6, "c_gamma": 0.8, "sigma_t": 0.01, "t_p": 0.0}}):
        got = EffectModel(dict(bench, g=9.81), geometry, effects).eigenvalues([v], gains)[0]
        np.testing.assert_allclose(_weave_capsize_castor(got, expected), expected, atol=1e-3)


def test_time_response_matches_an_independent_integration(bench, geometry):
    from scipy.integrate import solve_ivp

    model = EffectModel(dict(bench, g=9.81), geometry, {"steer_damping": {"c_steer": 0.5}})
    t = np.linspace(0, 3, 61)
    out = model.simulate(5.0, t, initial={"phid": 0.4})
    M, C, K = _whipple(bench, 5.0)
    C = C + np.array([[0, 0], [0, 0.5]])
    sol = solve_ivp(
        lambda _, x: np.concatenate([x[2:], np.linalg.solve(M, -C @ x[2:] - K @ x[:2])]),
        (0, 3),
        [0, 0, 0.4, 0],
        t_eval=t,
        rtol=1e-10,
        atol=1e-12,
    )
    np.testing.assert_allclose(out["phid"], sol.y[2], atol=1e-7)
    np.testing.assert_allclose(out["delta"], sol.y[1], atol=1e-7)


def test_models_refuse_bad_speeds_and_riderless_rider_effects(bench):
    riderless = RiderGeometry(None, dict(GRIPS))
    model = EffectModel(dict(bench, g=9.81), riderless)
    for bad in ([0.0, 1.0], [-2.0], [np.nan], [np.inf]):
        with pytest.raises(InputError, match="speeds"):
            model.eigenvalues(bad)
    with pytest.raises(InputError, match="rider"):
        EffectModel(dict(bench, g=9.81), riderless, {"rider_lean": {"k_lean": 100.0, "c_lean": 10.0}})
    with pytest.raises(InputError, match="c_steer"):
        EffectModel(dict(bench, g=9.81), riderless, {"steer_damping": {}})


def test_default_rider_geometry_from_the_davis_bicycle_and_jason():
    from pathlib import Path

    import bikerider

    root = Path(bikerider.__file__).parent / "data" / "bicycleparameters"
    model = load_model(
        root / "bicycles/Rigid/Parameters/RigidBenchmark.txt", root / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
    )
    upper = model.geometry.upper_body
    # JasonRigidBenchmark.txt: mB = 83.5 kg, zB = -1.10674939861 m
    assert upper["m_u"] == pytest.approx(0.5 * 83.5)
    assert upper["z_lean"] - upper["z_u"] == pytest.approx(0.3)
    assert model.parameters["mB"] == pytest.approx(22.9 + 83.5)


def test_each_effect_can_be_plotted_on_its_own(bench, geometry, tmp_path):
    from bikerider.plotting.gap import plot_effect

    values = dict(bench, g=9.81)
    for name, params in {
        "rider_lean": {"k_lean": 128.0, "c_lean": 50.0},
        "tyre_slip": {"c_alpha": 13.0, "c_gamma": 0.8, "sigma_t": 0.2, "t_p": 0.02},
    }.items():
        path = tmp_path / f"{name}.png"
        figure = plot_effect(EffectModel(values, geometry, {name: params}), np.linspace(1, 8, 15), title=name)
        figure.savefig(path)
        assert path.read_bytes()[:4] == b"\x89PNG" and path.stat().st_size > 5000
