"""Steer-torque multisines in the next-experiment plan (``bikerider.gap.plan.sweeps``): the frequency
response each rival predicts, the runs' noise, and a plan where a multisine sees what a decay does not."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gap_support import BP, DATA, SIL, nominal, riderless_model
from test_gap_next import _table

from bikerider.cli import main
from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.diagnosis.result import diagnose
from bikerider.gap.inference.frequency_response import describing_function_loop
from bikerider.gap.measured.tables import CanonicalData
from bikerider.gap.plan.ranking import plan_next
from bikerider.gap.plan.sweeps import (
    MAX_ROLL,
    Sweep,
    line_amplitude,
    lines_for,
    noise_covariance,
    peak_roll,
    response,
    settle_time,
    simulated_response,
    weave_shift,
)
from validation.multisine_check import STEP, check, multisine, periodic_start, simulate


@pytest.fixture(scope="module")
def riderless():
    return riderless_model()


def _second_order(model, effects, speed, omegas, gains):
    """Roll rate and steer angle per unit steer torque from ``M s^2 + C s + K`` (the dynamic stiffness, not the
    state space), with the law's torque ``k_phi phi + k_phid phi' + k_delta delta + k_deltad delta'``
    moved to the left."""
    Z = EffectModel(nominal(model), model.geometry, effects).dynamic_stiffness([speed], omegas)[0]
    s = 1j * np.asarray(omegas)
    k_phi, k_phid, k_delta, k_deltad = gains
    Z = Z.copy()
    Z[:, 1, 0] -= k_phi + k_phid * s
    Z[:, 1, 1] -= k_delta + k_deltad * s
    q = np.linalg.solve(Z, np.broadcast_to(np.array([0.0, 1.0], complex), (s.size, 2))[..., None])[..., 0]
    return s * q[:, 0], q[:, 1]


def test_the_frequency_response_is_the_transfer_function_of_the_closed_loop(riderless):
    effects = {"steer_damping": {"c_steer": 0.3}}
    omegas = 2 * math.pi * np.array([0.2, 0.7, 1.1, 3.0])
    for speed in (3.0, 6.0):
        gains = SIL(speed)
        ss = EffectModel(nominal(riderless), riderless.geometry, effects).state_space([speed])
        A, b = ss.closed_loop(gains)[0], ss.B[0, :, 1]
        roll, steer = _second_order(riderless, effects, speed, omegas, gains)
        assert response(A, b, ss.output_states[2], omegas) == pytest.approx(roll, rel=1e-9)
        assert response(A, b, ss.output_states[1], omegas) == pytest.approx(steer, rel=1e-9)


def test_a_multisine_has_its_peak_and_its_lines_on_the_grid():
    lines = lines_for(0.8, 10.0)
    assert len(lines) == 9 and lines[0] == pytest.approx(0.2) and lines[-1] == pytest.approx(3.2)
    assert np.allclose(np.array(lines) * 10.0, np.round(np.array(lines) * 10.0)) and np.all(np.diff(lines) > 0)
    a = line_amplitude(lines, 0.5, 10.0)
    # Schroeder phases keep the crest factor low: each line gets far more than 0.5 / 9
    assert 0.5 / 9 < a < 0.5 / math.sqrt(9 / 2)


def test_a_friction_rivals_describing_function_is_the_damping_of_the_same_dissipation():
    # a steer alone: inertia I, torque T = a cos(w t) on one line; friction F sign(delta') becomes c_eq with
    # c_eq * sd(delta') = sqrt(2 / pi) F, sd(delta') = a / (sqrt(2) |i w I + c_eq|) (the comparison the
    # diagnosis keeps, frequency_response.predict_frf_describing)
    I, F, a, w = 0.1, 0.05, 0.5, 2 * math.pi
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    b = np.array([0.0, 1.0 / I])
    Aeq = describing_function_loop(A, b, F, 1, np.array([w]), a)
    c = -Aeq[1, 1] * I
    sd = a / (math.sqrt(2) * abs(1j * w * I + c))
    assert c * sd == pytest.approx(math.sqrt(2 / math.pi) * F, rel=1e-6)
    # more friction than the torque can move: the steer sticks
    stuck = describing_function_loop(A, b, 10.0, 1, np.array([w]), a)
    assert -stuck[1, 1] * I > 1e3


TORQUE = 0.2
"""Peak torque of the riderless bicycle's planned multisines [N m]."""


@pytest.fixture(scope="module")
def damping_or_inertia(riderless):
    # a lab that ran at 6 m/s without control; steer damping is the truth, steer inertia the rival; multisines
    # of 0.2 N m (the light riderless bicycle's weave, lightly damped there, leans 0.4 rad under 0.5 N m: the
    # plan leaves such runs out as likely lost)
    data = _table(riderless, {"steer_damping": {"c_steer": 0.3}}, [6.0] * 9, ["a"] * 3 + ["b"] * 3 + ["c"] * 3)
    rivals = ["steer_damping", "steer_inertia"]
    diagnosis = diagnose(riderless, data, CanonicalData.empty(), effects=tuple(rivals))
    return riderless, plan_next(diagnosis, rivals=rivals, speeds=[5.5, 6.0], repeats=5, torque=TORQUE)


def test_each_rival_predicts_its_own_frequency_response(damping_or_inertia):
    model, plan = damping_or_inertia
    assert plan.sweeps
    for k, rival in enumerate(plan.rivals):
        effects = {rival.name: plan.diagnosis.fit_of(rival.effects).config[rival.name]}
        for m, sweep in enumerate(plan.sweeps):
            roll, steer = _second_order(model, effects, sweep.speed, sweep.omegas, plan.laws[sweep.law](sweep.speed))
            assert plan.sweep_mean[k, m] == pytest.approx(roll if sweep.output == "roll_rate" else steer, rel=1e-8)


def test_a_run_settles_until_every_rivals_transient_has_died(damping_or_inertia):
    # the truth may be any rival: a run read after the nominal model's settling time still carries the
    # transient of a rival with a slower mode (a loop check's seed 7206, a heavily damped steer: chi^2 96 on 18
    # degrees of freedom read after 11 s, 1.5 after 37 s).  Here steer inertia's weave is the slowest at 5.5 m/s.
    _, plan = damping_or_inertia
    nominal = [settle_time(ev) for ev in np.linalg.eigvals(plan._sweep_systems((), np.zeros((1, 0)))[0][0])]
    rivals = [
        [settle_time(ev) for ev in np.linalg.eigvals(plan._sweep_systems(r.effects, r.fit.values[None, :])[0][0])]
        for r in plan.rivals
    ]
    expected = np.max([nominal] + rivals, axis=0)
    assert plan.sweep_settle == pytest.approx(expected)
    assert np.any(plan.sweep_settle > np.array(nominal) + 1.0)
    assert plan.as_dict()["points"][len(plan.points)]["settle"] == pytest.approx(expected[0])


def test_a_multisine_sees_what_the_decays_do_not(damping_or_inertia):
    # steer damping and steer inertia move the weave alike but shape the steer's response to torque
    # differently: on an ideal, linear rig the multisines separate them far better than decays at the same
    # speed.  A real run's response departs from any linear model line by line (default without records:
    # 10 % of it), which bounds what a multisine can tell: the best of them still beats the best decay.
    _, plan = damping_or_inertia
    ideal = plan_next(
        plan.diagnosis, rivals=["steer_damping", "steer_inertia"], speeds=[5.5, 6.0], distortion=0, torque=TORQUE
    )
    d = ideal.separation(ideal.repeats)[0].min(axis=0)  # (experiments,)
    n = len(ideal.points)
    for m, sweep in enumerate(ideal.sweeps):
        decay = [j for j, e in enumerate(ideal.points) if e.speed == sweep.speed and e.law == sweep.law]
        assert d[n + m] > 3 * max(d[j] for j in decay)
    d = plan.separation(plan.repeats)[0].min(axis=0)
    n = len(plan.points)
    assert max(d[n:]) > max(d[:n]) and plan.plan[0]["experiment"].kind == "sweep"
    assert ideal.plan[0]["experiment"].kind == "sweep"
    assert plan.as_dict()["sweeps"]["distortion"] == {"value": 0.1, "source": "assumed (the data hold no records)"}
    out = plan.as_dict()
    assert out["plan"][0]["kind"] == "sweep" and "N m" in out["plan"][0]["text"]
    assert {"frf_roll_rate", "frf_steer_angle"} <= set(out["best_per_signal"])
    sweep_points = [p for p in out["points"] if p["kind"] == "sweep"]
    assert len(sweep_points) == len(plan.sweeps) and len(sweep_points[0]["lines"]) == 9
    # the sensor noise falls with the torque squared; the bicycle's own run-to-run variation does not
    # (the line-by-line distortion, a share of the response, does not either: left out here)
    rivals = ["steer_damping", "steer_inertia"]
    quiet = plan_next(plan.diagnosis, rivals=rivals, speeds=[5.5, 6.0], torque=TORQUE / 4, distortion=0)
    louder = plan_next(plan.diagnosis, rivals=rivals, speeds=[5.5, 6.0], torque=TORQUE, distortion=0)
    sensor, louder_sensor = quiet.sweep_data - quiet.sweep_run, louder.sweep_data - louder.sweep_run
    assert np.all(louder_sensor <= sensor / 15)
    assert louder.sweep_run == pytest.approx(quiet.sweep_run, rel=1e-9, abs=1e-30)
    assert np.all(np.trace(quiet.sweep_run, axis1=1, axis2=2) > 0)
    assert np.all(plan.sweep_data >= louder.sweep_data)  # the same torque, with the distortion
    # without multisines the plan is the decays' alone
    decays_only = plan_next(plan.diagnosis, rivals=["steer_damping", "steer_inertia"], speeds=[5.5], sweeps=False)
    assert not decays_only.sweeps and all(item["experiment"].kind == "decay" for item in decays_only.plan)


def test_bad_sweep_values_are_a_clear_error(damping_or_inertia):
    from bikerider.errors import InputError

    _, plan = damping_or_inertia
    with pytest.raises(InputError, match="torque = -1"):
        plan_next(plan.diagnosis, rivals=["steer_damping", "steer_inertia"], torque=-1.0)
    with pytest.raises(InputError, match="run_time = 1"):
        plan_next(plan.diagnosis, rivals=["steer_damping", "steer_inertia"], run_time=1.0)
    with pytest.raises(InputError, match="distortion = 1.5"):
        plan_next(plan.diagnosis, rivals=["steer_damping", "steer_inertia"], distortion=1.5)


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--next", "--next-torque", "0"], "--next-torque = 0"),
        (["--next", "--next-torque", "nan"], "--next-torque = nan"),
        (["--next", "--next-run-time", "1"], "--next-run-time = 1"),
        (["--next-torque", "1"], "--next as well"),
        (["--next-no-sweeps"], "--next as well"),
    ],
)
def test_bad_sweep_options_exit_2(capsys, extra, message):
    args = ["gap", "--model", str(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt"), "--data"]
    args += [str(DATA / "gap_examples" / "eigenvalues.csv"), "--effects", "steer_damping,steer_inertia"]
    assert main(args + extra) == 2
    assert message in capsys.readouterr().err


def test_the_weave_moving_from_run_to_run_moves_the_response_by_its_slopes():
    # A = V diag(lambda) V^-1 with a weave pair and two real modes: moving the weave pair by delta (its
    # modal vectors held) moves the response by the slopes weave_shift gives, to first order
    rng = np.random.default_rng(3)
    lam = np.array([-1.0 + 5.0j, -1.0 - 5.0j, -8.0, -0.5])
    V = np.empty((4, 4), complex)
    V[:, 0] = rng.standard_normal(4) + 1j * rng.standard_normal(4)
    V[:, 1] = np.conj(V[:, 0])
    V[:, 2:] = rng.standard_normal((4, 2))
    b = rng.standard_normal(4)
    omegas = np.linspace(1.0, 10.0, 7)

    def real_system(weave):
        values = lam.copy()
        values[0], values[1] = weave, np.conj(weave)
        return (V @ np.diag(values) @ np.linalg.inv(V)).real

    J = weave_shift(real_system(lam[0]), b, 2, omegas)
    h = 1e-6
    for k, step in enumerate((h, 1j * h)):
        moved = response(real_system(lam[0] + step), b, 2, omegas) - response(real_system(lam[0] - step), b, 2, omegas)
        expected = np.concatenate([moved.real, moved.imag]) / (2 * h)
        assert J[:, k] == pytest.approx(expected, rel=1e-6, abs=1e-9)
    assert weave_shift(np.diag([-1.0, -2.0]), np.ones(2), 0, omegas) is None


def _sweep_loop(riderless, speed=5.0):
    ss = EffectModel(nominal(riderless), riderless.geometry, {}).state_space([speed])
    A, b = ss.closed_loop(SIL(speed))[0], ss.B[0, :, 1]
    ev = np.linalg.eigvals(A)
    lines = lines_for(float(ev.imag.max()) / (2 * math.pi), 4.0)
    return A, b, ss.output_states, Sweep(speed, "sil", "roll_rate", 0.5, 4.0, lines)


def test_a_run_simulated_in_time_reads_the_transfer_function_without_friction(riderless):
    A, b, outputs, sweep = _sweep_loop(riderless)
    H = simulated_response(A[None, None], b[None, None], 0.0, outputs[3], (outputs[2], outputs[1]), [sweep])
    assert H[0, 0, 0] == pytest.approx(response(A, b, outputs[2], sweep.omegas), rel=2e-3)
    assert H[0, 0, 1] == pytest.approx(response(A, b, outputs[1], sweep.omegas), rel=2e-3)


def test_a_friction_the_multisine_alone_cannot_move_is_judged_by_its_run_not_by_a_locked_steer(riderless):
    # 0.1 N m of Coulomb friction under a multisine of 0.2 N m peak: the random-input describing function
    # locks the steer (its equivalent damping at the cap) and the locked-steer bicycle falls as an inverted
    # pendulum, so judged by it the run leans past any limit; simulated in time, the control law's own torque
    # moves the steer and the run leans about as much as the friction-free one (the plan judges so)
    A, b, outputs, sweep = _sweep_loop(riderless)
    sweep = Sweep(sweep.speed, sweep.law, sweep.output, 0.2, sweep.run_time, sweep.lines)
    friction = 0.1
    amplitude = line_amplitude(sweep.lines, sweep.torque, sweep.run_time)
    locked = describing_function_loop(A, b, friction, outputs[3], sweep.omegas, amplitude)
    assert np.linalg.eigvals(locked).real.max() > 1.0  # falls e-fold in under a second
    assert peak_roll(locked[None], b[None], outputs[0], [sweep], [5.0])[0] > 1e3
    H, lean = simulated_response(
        A[None, None], b[None, None], friction, outputs[3], (outputs[2], outputs[1]), [sweep], roll_index=outputs[0]
    )
    free = peak_roll(A[None], b[None], outputs[0], [sweep], [5.0])[0]
    assert lean.shape == (1, 1) and np.all(np.isfinite(H))
    assert free < lean[0, 0] < 2 * free < MAX_ROLL
    # without friction the simulated run is the linear loop's periodic response (it starts there), whose peak
    # lean is read here on a fine grid of its lines (Schroeder phases), and a run from rest leans more
    H0, lean0 = simulated_response(
        A[None, None], b[None, None], 0.0, outputs[3], (outputs[2], outputs[1]), [sweep], roll_index=outputs[0]
    )
    K = len(sweep.lines)
    phases = -math.pi * np.arange(1, K + 1) * np.arange(K) / K
    t = np.linspace(0.0, sweep.run_time, 20001)
    lines = response(A, b, outputs[0], sweep.omegas) * amplitude * np.exp(1j * phases)
    periodic = np.abs((lines[None, :] * np.exp(1j * sweep.omegas[None, :] * t[:, None])).sum(axis=1).real).max()
    assert lean0[0, 0] == pytest.approx(periodic, rel=0.01) and lean0[0, 0] < free
    assert H0[0, 0, 0] == pytest.approx(response(A, b, outputs[2], sweep.omegas), rel=2e-3)


def test_the_plans_stick_slip_runs_match_an_independent_simulation(riderless):
    # the multisine check's own Karnopp integrator (validation.multisine_check, 1 ms steps, state held) and
    # the plan's (batched) read the same response of a sticking steer; the smoothed friction the diagnosis
    # fits does not stick, and the plan counts the difference as its friction rival's own uncertainty
    A, b, outputs, sweep = _sweep_loop(riderless)
    friction = 0.15
    args = (A[None, None], b[None, None], friction, outputs[3], (outputs[2], outputs[1]), [sweep])
    stick = simulated_response(*args, stick=True)[0, 0, 0]
    smooth = simulated_response(*args)[0, 0, 0]
    t = np.arange(round(2 * sweep.run_time / STEP)) * STEP
    torque, a, phases = multisine(sweep.lines, sweep.torque, sweep.run_time, t)
    start = periodic_start(A, b, sweep.omegas, a, phases)
    y = simulate(A, b, outputs[3], friction, torque, start)[t.size // 2 :, outputs[2]]
    basis = np.exp(-1j * sweep.omegas[None, :] * (t[t.size // 2 :] - t[t.size // 2])[:, None])
    independent = (y @ basis) / (torque[t.size // 2 :] @ basis)
    linear = response(A, b, outputs[2], sweep.omegas)
    assert np.abs(stick - independent).max() < 0.05 * np.abs(independent).max()
    # friction changes the response by far more than the two integrators differ
    assert np.abs(linear - independent).max() > 5 * np.abs(stick - independent).max()
    assert np.abs(smooth - stick).max() > np.abs(stick - independent).max()


def test_the_dft_noise_of_a_run_is_what_the_plan_says():
    # a run's white sample noise read by the DFT at the multisine's lines: the plan's variance 2 sigma^2 / (N a^2)
    # per real and imaginary part, lines independent (Monte Carlo over 2000 runs)
    sweep = Sweep(4.0, "sil", "roll_rate", 0.5, 4.0, lines_for(1.1, 4.0))
    fs, sigma = 100.0, 0.03
    t = np.arange(round(fs * sweep.run_time)) / fs
    _, a, phases = multisine(sweep.lines, sweep.torque, sweep.run_time, t)
    noise = np.random.default_rng(7).standard_normal((2000, t.size)) * sigma
    H = (2 / t.size) * (noise @ np.exp(-1j * sweep.omegas[None, :] * t[:, None])) / (a * np.exp(1j * phases))
    parts = np.concatenate([H.real, H.imag], axis=1)
    planned = noise_covariance(sweep, sigma, fs)
    assert np.diag(np.cov(parts.T)) == pytest.approx(np.diag(planned), rel=0.1)
    off = np.cov(parts.T) - np.diag(np.diag(np.cov(parts.T)))
    assert np.abs(off).max() < 0.15 * planned[0, 0]


def test_a_linear_truth_achieves_the_planned_separation(damping_or_inertia):
    # the multisine check (validation.multisine_check) runs the plan's first multisines in time with each rival
    # as the truth: a linear rival's runs read its predicted response, and the separation achieved is the planned
    _, plan = damping_or_inertia
    for run in check(plan, items=2):
        assert run.bias < 1e-2 * len(plan.sweeps[0].lines), (run.sweep, run.truth, run.bias)
        for other, d in run.d_planned.items():
            assert run.d_achieved[other] == pytest.approx(d, rel=0.02, abs=0.05)
