"""State space, lateral-force input, mode shapes, simulation and frequency response of the Whipple model."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from random_bicycles import batched_model, benchmark_values, random_parameters
from scipy.integrate import solve_ivp

from bikerider.benchmark import BenchmarkParameters, WhippleModel
from bikerider.benchmark.frequency_response import frequency_response
from bikerider.benchmark.mode_shapes import mode_shapes
from bikerider.benchmark.simulation import discretise, expm, simulate
from bikerider.benchmark.state_space import LateralForce, StateSpace, input_matrix, state_space
from bikerider.errors import InputError
from bikerider.io.benchmark_file import load_benchmark_parameters
from bikerider.io.name_value_file import read_name_value_file

DATA = __import__("pathlib").Path(__file__).resolve().parents[1] / "src" / "bikerider" / "data" / "bicycleparameters"
SEAT_POINT = LateralForce(0.3, -0.9)


@pytest.fixture(scope="module")
def model() -> WhippleModel:
    return WhippleModel.from_parameters(BenchmarkParameters.from_mapping(benchmark_values()))


# -- lateral force -------------------------------------------------------------------------------
def test_lateral_force_input_reproduces_moore_2012_for_the_rigid_bicycle():
    # Moore (2012), Human Control of a Bicycle (PhD dissertation, UC Davis), chapter System
    # Identification, table "H": for the rider Jason on the Davis "Rigid" bicycle the Whipple model
    # gives H = [H_phiF, H_deltaF] = [0.942975, 0.01062231] m (shared/data/gap/
    # moore2012_davis_canonical_id/lateral_force_point.csv rounds it to [0.943, 0.011]).  The force
    # acted just below the seat; its point (xcl, zcl) and the bicycle's geometry come from
    # BicycleParameters' RigidMeasured.txt and RigidBenchmark.txt, shipped with bikerider.
    measured = read_name_value_file(DATA / "bicycles" / "Rigid" / "RawData" / "RigidMeasured.txt").as_dict()
    rigid = WhippleModel.from_parameters(
        load_benchmark_parameters(DATA / "bicycles" / "Rigid" / "Parameters" / "RigidBenchmark.txt")
    )
    force = LateralForce(measured["xcl"].value, measured["zcl"].value)
    H = force.vector(**rigid.geometry)
    assert H[0] == pytest.approx(0.942975, abs=5e-7)
    assert H[1] == pytest.approx(0.01062231, abs=5e-9)
    assert H == pytest.approx([0.943, 0.011], abs=5e-4)


def test_a_force_at_a_ground_contact_does_no_work_and_above_the_rear_contact_it_is_a_roll_torque(model):
    w, c, lam = (model.geometry[k] for k in ("w", "c", "lam"))
    assert LateralForce(0.0, 0.0, "rear").vector(w, c, lam) == pytest.approx([0, 0], abs=1e-15)
    assert LateralForce(w, 0.0, "front").vector(w, c, lam) == pytest.approx([0, 0], abs=1e-15)
    assert LateralForce(0.0, -1.0, "rear").vector(w, c, lam) == pytest.approx([1.0, 0.0], abs=1e-15)
    # a point on the steer axis moves with the rear frame whichever body it belongs to
    on_axis = (w + c - 0.7 * np.sin(lam), -0.7 * np.cos(lam))
    assert LateralForce(*on_axis, "front").vector(w, c, lam) == pytest.approx(LateralForce(*on_axis).vector(w, c, lam))


def test_input_matrix_is_the_inverse_mass_matrix_times_the_generalized_forces(model):
    B = input_matrix(model, SEAT_POINT)
    H = SEAT_POINT.vector(**model.geometry)
    expected = np.linalg.solve(model.M, np.column_stack([np.eye(2), H]))
    np.testing.assert_allclose(B[2:], expected, rtol=1e-13)
    np.testing.assert_array_equal(B[:2], 0.0)


def test_state_space_outputs_and_errors(model):
    ss = state_space(
        model, [2.0, 5.0], inputs=("T_delta", "F"), outputs=("delta", "phi_dot", "delta_ddot"), lateral_force=SEAT_POINT
    )
    assert ss.A.shape == (2, 4, 4) and ss.B.shape == (2, 4, 2) and ss.C.shape == (2, 3, 4) and ss.D.shape == (2, 3, 2)
    x, u = np.array([0.1, -0.2, 0.3, 0.05]), np.array([1.5, 20.0])
    for k in range(2):
        xdot = ss.A[k] @ x + ss.B[k] @ u
        np.testing.assert_allclose(ss.C[k] @ x + ss.D[k] @ u, [x[1], x[2], xdot[3]], rtol=1e-13)
    with pytest.raises(InputError, match="lateral_force"):
        state_space(model, 5.0, inputs=("F",))
    with pytest.raises(InputError, match="one of T_phi, T_delta, F"):
        state_space(model, 5.0, inputs=("T_yaw",))
    with pytest.raises(InputError, match="from_parameters"):
        state_space(WhippleModel(model.M, model.C1, model.K0, model.K2), 5.0, inputs=("F",), lateral_force=SEAT_POINT)


def test_batched_state_space_equals_one_at_a_time():
    models = [WhippleModel.from_parameters(p) for p in random_parameters(5, seed=3)]
    batch = batched_model(models)
    batch.geometry = {k: np.array([m.geometry[k] for m in models]) for k in ("w", "c", "lam")}
    speeds = np.array([0.0, 3.0, 7.5])
    together = state_space(batch, speeds, inputs=("T_phi", "F"), lateral_force=SEAT_POINT)
    assert together.A.shape == (5, 3, 4, 4)
    for i, m in enumerate(models):
        alone = state_space(m, speeds, inputs=("T_phi", "F"), lateral_force=SEAT_POINT)
        np.testing.assert_allclose(together.A[i], alone.A, rtol=1e-14)
        np.testing.assert_allclose(together.B[i], alone.B, rtol=1e-14)
        np.testing.assert_allclose(batch.eigenvalues(speeds).values[i], m.eigenvalues(speeds).values, rtol=1e-12)


def test_to_control_gives_a_named_state_space(model):
    control = pytest.importorskip("control")
    ss = state_space(model, [4.0, 6.0], inputs=("T_delta", "F"), lateral_force=SEAT_POINT)
    sys = ss.to_control(1)
    assert isinstance(sys, control.StateSpace)
    assert sys.input_labels == ["T_delta", "F"] and sys.output_labels == ["phi", "delta"]
    assert sys.state_labels == ["phi", "delta", "phi_dot", "delta_dot"]
    np.testing.assert_allclose(np.sort_complex(sys.poles()), np.sort_complex(np.linalg.eigvals(ss.A[1])), rtol=1e-12)


@pytest.mark.parametrize("speed, name", [(5.5, "whipple_v5_5"), (0.25, "whipple_v0_25"), (-1.5, "whipple_vm1_5")])
def test_to_control_works_at_any_speed(model, speed, name):
    control = pytest.importorskip("control")
    sys = state_space(model, [speed]).to_control(0)
    assert sys.name == name
    closed = control.feedback(sys, np.zeros((2, 2)))  # python-control accepts the name in an interconnection
    np.testing.assert_allclose(
        np.sort_complex(closed.poles()), np.sort_complex(np.linalg.eigvals(model.state_matrix(speed)))
    )


# -- modes ---------------------------------------------------------------------------------------
def test_mode_shapes_are_the_normalised_eigenvectors_of_numpy_eig(model):
    speeds = np.linspace(0.0, 10.0, 201)
    shapes = mode_shapes(model, speeds)
    assert shapes.names == ("weave", "weave", "capsize", "castor")
    values, vectors = np.linalg.eig(model.state_matrix(speeds))
    for k in range(0, 201, 10):
        for j in range(4):
            i = np.argmin(np.abs(values[k] - shapes.eigenvalues[k, j]))
            assert values[k, i] == pytest.approx(shapes.eigenvalues[k, j], rel=1e-9, abs=1e-9)
            q = vectors[k, :2, i]
            q = q / np.linalg.norm(q)
            q = q * np.conj(q[0]) / abs(q[0])  # the documented normalisation: roll real, positive
            np.testing.assert_allclose(shapes.shapes[k, j], q, atol=1e-7)
    np.testing.assert_allclose(np.linalg.norm(shapes.shapes, axis=-1), 1.0, rtol=1e-12)


def test_tracked_modes_are_continuous_and_named(model):
    speeds = np.linspace(0.0, 10.0, 401)
    shapes = mode_shapes(model, speeds)
    jumps = np.abs(np.diff(shapes.eigenvalues, axis=0)).max(axis=0)
    assert jumps.max() < 0.6  # steps of 0.025 m/s; the weave pair is born with a square-root slope
    capsize = shapes.eigenvalues[:, shapes.column("capsize")]
    crossing = speeds[np.flatnonzero(np.diff(np.sign(capsize.real)))[0]]
    assert abs(crossing - 6.024262) < 0.03  # Meijaard et al. (2007), Table 2: capsize speed
    weave = shapes.eigenvalues[-1, 0]
    assert weave.imag > 0 and shapes.names[0] == "weave"


def test_batched_mode_shapes_equal_one_at_a_time():
    models = [WhippleModel.from_parameters(p) for p in random_parameters(4, seed=8)]
    speeds = np.linspace(0.5, 8.0, 76)
    together = mode_shapes(batched_model(models), speeds)
    for i, m in enumerate(models):
        alone = mode_shapes(m, speeds)
        assert tuple(together.names[i]) == alone.names
        np.testing.assert_allclose(together.eigenvalues[i], alone.eigenvalues, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(together.shapes[i], alone.shapes, atol=1e-8)


# -- simulation ----------------------------------------------------------------------------------
def test_free_response_is_the_matrix_exponential(model):
    t = np.linspace(0.0, 4.0, 161)
    x0 = np.array([0.05, -0.02, 0.1, 0.0])
    sim = simulate(model, [2.0, 4.5, 8.0], t, initial_state=x0)
    for k, v in enumerate(sim.speeds):
        A = model.state_matrix(v)
        for j in (1, 40, 160):
            np.testing.assert_allclose(sim.states[k, j], scipy.linalg.expm(A * t[j]) @ x0, rtol=1e-11, atol=1e-14)


def test_expm_equals_scipy_on_a_batch_of_any_size_and_norm():
    # the one matrix exponential (vectorised scaling and squaring) against scipy's Pade, matrix by matrix
    rng = np.random.default_rng(3)
    for n in (1, 4, 6, 11):
        M = rng.standard_normal((3, 5, n, n)) * np.array([1e-3, 0.3, 2.0, 8.0, 30.0])[:, None, None]
        got = expm(M)
        for index in np.ndindex(M.shape[:-2]):
            want = scipy.linalg.expm(M[index])
            np.testing.assert_allclose(got[index], want, rtol=1e-11, atol=1e-13 * np.abs(want).max())
    np.testing.assert_array_equal(expm(np.zeros((2, 3, 3))), np.broadcast_to(np.eye(3), (2, 3, 3)))


def test_the_zero_order_hold_is_the_first_order_holds_leading_blocks(model):
    # discretise(hold="zoh") exponentiates the smaller matrix [[A, B], [0, 0]] h: the same Phi and Gamma_0
    ss = state_space(model, [1.0, 5.0, 9.0], inputs=("T_phi", "T_delta"))
    for h in (0.01, np.array([0.002, 0.05, 0.3])):
        Phi, G0, G1 = discretise(ss.A, ss.B, h)
        Phi_z, G0_z, none = discretise(ss.A, ss.B, h, hold="zoh")
        assert none is None and G1.shape == G0.shape
        np.testing.assert_allclose(Phi_z, Phi, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(G0_z, G0, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(Phi, expm(ss.A * np.asarray(h)[..., None, None]), rtol=1e-13, atol=1e-15)


def test_a_state_space_of_named_states_picks_its_outputs_and_closes_the_steer_loop(model):
    speeds = np.array([2.0, 6.0])
    full = state_space(model, speeds)
    # the same system with its states in another order: outputs and the closed loop follow the names
    order = [3, 1, 0, 2]
    states = tuple(full.states[k] for k in order)
    ss = StateSpace.of_states(speeds, full.A[..., order, :][..., :, order], full.B[..., order, :], states)
    assert ss.outputs == ("phi", "delta", "phi_dot", "delta_dot")
    assert ss.output_states == (2, 1, 3, 0)
    np.testing.assert_array_equal(ss.C @ np.arange(4.0), [2.0, 1.0, 3.0, 0.0])
    assert ss.D.shape == (2, 4, 2) and not np.any(ss.D)
    gains = np.array([1.5, -0.4, 2.0, 0.3])  # k_phi, k_phid, k_delta, k_deltad
    k_state_order = np.array([gains[0], gains[2], gains[1], gains[3]])  # phi, delta, phi_dot, delta_dot
    want = full.A + full.B[..., :, 1:2] * k_state_order
    np.testing.assert_allclose(ss.closed_loop(gains), want[..., order, :][..., :, order], rtol=1e-14, atol=1e-14)
    assert ss.closed_loop(None) is ss.A and ss.closed_loop(np.zeros(4)) is ss.A
    with pytest.raises(InputError, match="T_delta among the inputs"):
        state_space(model, speeds, inputs=("T_phi",)).closed_loop(gains)
    with pytest.raises(InputError, match=r"outputs = 'phi_ddot': expected a state \(phi, delta, phi_dot, delta_dot\)"):
        _ = state_space(model, speeds, outputs=("phi_ddot",)).output_states
    three = ("phi", "delta", "phi_dot")
    with pytest.raises(InputError, match="outputs = 'delta_dot': expected a state"):
        StateSpace.of_states(speeds, full.A[..., :3, :3], full.B[..., :3, :], three)
    with pytest.raises(InputError, match="gains = 'delta_dot': expected a state"):
        StateSpace.of_states(speeds, full.A[..., :3, :3], full.B[..., :3, :], three, outputs=three).closed_loop(gains)


def _ode(A, B, u, t, x0):
    out = solve_ivp(
        lambda s, x: A @ x + B @ u(s),
        (t[0], t[-1]),
        x0,
        t_eval=t,
        rtol=1e-12,
        atol=1e-14,
        method="DOP853",
        max_step=0.01,
    )
    return out.y.T


def test_piecewise_linear_input_matches_an_ode_solver(model):
    # A triangle pulse of steer torque and a ramp of lateral force, linear between the samples:
    # first-order hold is exact for it.
    t = np.linspace(0.0, 3.0, 61)

    def u(s):
        return np.array([np.interp(s, [0, 0.25, 0.5, 3], [0, 2.0, 0, 0]), np.interp(s, [0, 1.0, 3], [0, 30.0, 30.0])])

    sim = simulate(model, [5.0], t, inputs=u, input_names=("T_delta", "F"), lateral_force=SEAT_POINT)
    expected = _ode(sim.system.A[0], sim.system.B[0], u, t, np.zeros(4))
    np.testing.assert_allclose(sim.states[0], expected, rtol=0, atol=1e-9 * np.abs(expected).max())


def test_sampled_input_is_held_and_nonuniform_times_work(model):
    rng = np.random.default_rng(1)
    t = np.cumsum(np.r_[0.0, rng.uniform(0.01, 0.05, 60)])
    samples = rng.normal(0.0, 1.0, (t.size, 1))

    def held(s):
        return samples[min(np.searchsorted(t, s, side="right") - 1, t.size - 1)]

    sim = simulate(model, [3.0], t, inputs=samples, input_names=("T_phi",), initial_state=[0, 0.01, 0, 0])
    A, B = sim.system.A[0], sim.system.B[0]
    x = np.array([0, 0.01, 0, 0.0])
    for k in range(t.size - 1):  # integrate each hold interval on its own (no discontinuity inside)
        x = solve_ivp(
            lambda s, y, u=samples[k]: A @ y + B @ u, (t[k], t[k + 1]), x, rtol=1e-12, atol=1e-14, method="DOP853"
        ).y[:, -1]
        np.testing.assert_allclose(sim.states[0, k + 1], x, rtol=1e-8, atol=1e-12)
    assert held(t[5] + 1e-9) == samples[5]


def test_batched_simulation_equals_one_at_a_time():
    models = [WhippleModel.from_parameters(p) for p in random_parameters(3, seed=4)]
    t = np.linspace(0, 2, 41)
    together = simulate(
        batched_model(models),
        [3.0, 6.0],
        t,
        initial_state=[0.1, 0, 0, 0],
        inputs=lambda s: [np.sin(3 * s)],
        input_names=("T_delta",),
    )
    for i, m in enumerate(models):
        alone = simulate(
            m, [3.0, 6.0], t, initial_state=[0.1, 0, 0, 0], inputs=lambda s: [np.sin(3 * s)], input_names=("T_delta",)
        )
        np.testing.assert_allclose(together.states[i], alone.states, rtol=1e-12, atol=1e-15)


def test_simulation_rejects_bad_times_and_inputs(model):
    with pytest.raises(InputError, match="increasing"):
        simulate(model, [5.0], [0.0, 0.2, 0.1])
    with pytest.raises(InputError, match=r"shape \(3, 2\)"):
        simulate(model, [5.0], [0.0, 0.1, 0.2], inputs=np.zeros((3, 1)), input_names=("T_phi", "T_delta"))
    with pytest.raises(InputError, match="hold"):
        simulate(model, [5.0], [0.0, 0.1], hold="cubic")


# -- frequency response --------------------------------------------------------------------------
def test_bode_equals_direct_evaluation_and_the_second_order_form(model):
    w = np.logspace(-1, 2, 40)
    fr = frequency_response(model, [2.0, 5.0, 9.0], w, lateral_force=SEAT_POINT)
    assert fr.system.inputs == ("T_delta", "F") and fr.system.outputs == ("phi", "delta")
    H = SEAT_POINT.vector(**model.geometry)
    for k, v in enumerate(fr.speeds):
        ss = state_space(model, v, fr.system.inputs, fr.system.outputs, SEAT_POINT)
        for j, omega in enumerate(w):
            s = 1j * omega
            direct = ss.C @ np.linalg.inv(s * np.eye(4) - ss.A) @ ss.B + ss.D
            np.testing.assert_allclose(fr.response[k, j], direct, rtol=1e-10)
            # and from the canonical form: (M s^2 + v C1 s + g K0 + v^2 K2)^-1 [e_delta, H]
            dyn = model.M * s * s + v * model.C1 * s + model.g * model.K0 + v * v * model.K2
            np.testing.assert_allclose(fr.response[k, j], np.linalg.solve(dyn, np.column_stack([[0, 1], H])), rtol=1e-9)
    assert fr.magnitude_db("phi", "T_delta").shape == (3, 40)
    assert np.all(np.abs(np.diff(fr.phase_deg("delta", "F"), axis=-1)) < 90)  # unwrapped


def test_bode_of_a_batch_equals_one_at_a_time():
    models = [WhippleModel.from_parameters(p) for p in random_parameters(3, seed=6)]
    batch = batched_model(models)
    together = frequency_response(batch, [4.0], [0.5, 5.0, 50.0], inputs=("T_delta",))
    for i, m in enumerate(models):
        alone = frequency_response(m, [4.0], [0.5, 5.0, 50.0], inputs=("T_delta",))
        np.testing.assert_allclose(together.response[i], alone.response, rtol=1e-12)
