"""The Whipple model under a control law: closed-loop matrix, stable intervals, LQR gains."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from random_bicycles import random_parameters

import bikerider
from bikerider import plotting
from bikerider.benchmark.closed_loop import _quartic_discriminant, closed_loop, closed_loop_matrix, lqr_gains, lqr_law
from bikerider.benchmark.control import ControlLaw, GainSchedule
from bikerider.errors import InputError


@pytest.fixture(scope="module")
def benchmark():
    return bikerider.WhippleModel.from_parameters(bikerider.named("Benchmark"))


def _scan(system, speeds):
    """Whether every eigenvalue has a negative real part, on a grid (the reference)."""
    return np.linalg.eigvals(system.state_matrix(speeds)).real.max(axis=-1) < 0


def test_the_closed_loop_matrix_is_a_plus_b_k_transpose(benchmark):
    gains = [1.5, -0.7, 2.0, 0.3]
    system = closed_loop(benchmark, gains)
    ss = bikerider.state_space(benchmark, [2.0, 5.5], inputs=("T_delta",))
    k_state = np.array([gains[0], gains[2], gains[1], gains[3]])  # x = [phi, delta, phi_dot, delta_dot]
    expected = ss.A + ss.B[..., :, :1] * k_state
    np.testing.assert_allclose(system.state_matrix([2.0, 5.5]), expected, rtol=1e-13, atol=1e-13)
    # the simulation of the open loop with T_delta = k x fed back agrees: same derivative
    x = np.array([0.1, -0.05, 0.2, 0.3])
    u = k_state @ x
    np.testing.assert_allclose(system.state_matrix(2.0) @ x, ss.A[0] @ x + ss.B[0, :, 0] * u, rtol=1e-13)


def test_no_control_gives_the_open_loop_intervals(benchmark):
    open_loop = benchmark.stability()
    closed = closed_loop(benchmark, [0, 0, 0, 0]).stability()
    assert len(closed.intervals) == len(open_loop.intervals) == 1
    assert closed.intervals[0].lower == pytest.approx(open_loop.intervals[0].lower, rel=1e-10)
    assert closed.intervals[0].upper == pytest.approx(open_loop.intervals[0].upper, rel=1e-10)
    assert closed.weave == pytest.approx(open_loop.weave, rel=1e-10)
    assert closed.capsize == pytest.approx(open_loop.capsize, rel=1e-10)
    assert closed.weave_frequency == pytest.approx(open_loop.weave_frequency, rel=1e-8)


LAWS = [
    ControlLaw("roll rate below 6.5", {"k_phid": GainSchedule.make_ramp(2.0, 6.5, "below")}),
    ControlLaw("steer into lean", {"k_phi": GainSchedule.constant(8.0), "k_deltad": GainSchedule.constant(-0.5)}),
    ControlLaw(
        "scheduled",
        {
            "k_phi": GainSchedule.piecewise([1.0, 4.0, 8.0], [30.0, 10.0, 0.0]),
            "k_phid": GainSchedule.piecewise([0.0, 5.0], [6.0, 0.0]),
        },
    ),
]


@pytest.mark.parametrize("law", LAWS, ids=lambda law: law.name)
def test_the_intervals_agree_with_an_eigenvalue_scan(benchmark, law):
    system = closed_loop(benchmark, law)
    result = system.stability()
    v = np.linspace(0.0, 15.0, 3001)
    scan = _scan(system, v)
    ends = [x for i in result.intervals for x in (i.lower, i.upper) if np.isfinite(x)]
    away = np.all(np.abs(v[:, None] - np.array(ends + [-1.0])[None, :]) > 0.01, axis=1)  # off the ends
    assert np.array_equal(result.is_stable(v)[away], scan[away])
    for end in ends:  # each end is where the verdict changes
        if end > 0:
            assert _scan(system, [end - 1e-4]) != _scan(system, [end + 1e-4])


def test_random_bicycles_under_random_laws_agree_with_a_scan():
    parameters = random_parameters(40, seed=7)
    rng = np.random.default_rng(3)
    v = np.linspace(0.0, 12.0, 1201)
    disagreements = 0
    for params in parameters:
        model = bikerider.WhippleModel.from_parameters(params)
        law = ControlLaw.constant(rng.normal(0, [5, 2, 5, 0.5]))
        system = closed_loop(model, law)
        result = system.stability()
        ends = np.array([x for i in result.intervals for x in (i.lower, i.upper) if np.isfinite(x)] + [-1.0])
        away = np.all(np.abs(v[:, None] - ends[None, :]) > 0.02, axis=1)
        disagreements += int(np.sum(result.is_stable(v)[away] != _scan(system, v)[away]))
    assert disagreements == 0


def test_lqr_gains_solve_the_riccati_equation_and_stabilise(benchmark):
    speeds = np.linspace(0.5, 10, 20)
    gains = lqr_gains(benchmark, speeds)
    assert gains.shape == (20, 4)
    system = closed_loop(benchmark, lqr_law(benchmark, speeds))
    assert np.all(_scan(system, speeds))  # at the design speeds the LQR closed loop is stable
    # the gains are -R^-1 b^T P of the Riccati equation's solution P
    A = benchmark.state_matrix(5.0)
    b = closed_loop(benchmark, [0, 0, 0, 0]).steer_input()[:, None]
    P = scipy.linalg.solve_continuous_are(A, b, np.eye(4), np.eye(1))
    k = -(b.T @ P)[0]
    np.testing.assert_allclose(lqr_gains(benchmark, [5.0])[0], k[[0, 2, 1, 3]], rtol=1e-12)


def test_bad_weights_and_gains_are_refused(benchmark):
    with pytest.raises(InputError, match="R"):
        lqr_gains(benchmark, [5.0], R=0.0)
    with pytest.raises(InputError, match="Q"):
        lqr_gains(benchmark, [5.0], Q=-np.eye(4))
    with pytest.raises(InputError, match="four gains"):
        closed_loop(benchmark, [1.0, 2.0])
    with pytest.raises(InputError, match="k_roll"):
        closed_loop(benchmark, {"k_roll": 1.0})


def test_closed_loop_matrix_broadcasts_over_a_batch():
    A = np.zeros((3, 2, 4, 4))
    b = np.ones((3, 2, 4))
    out = closed_loop_matrix(A, b, np.array([1.0, 2.0, 3.0, 4.0]))
    assert out.shape == (3, 2, 4, 4)
    np.testing.assert_array_equal(out[1, 1, 0], [1.0, 3.0, 2.0, 4.0])


def test_closed_loop_collisions_and_names(benchmark):
    coefficients = [2.0, -3.0, 0.5, 1.0, -0.25]
    roots = np.roots(coefficients)
    product = np.prod([(roots[i] - roots[j]) ** 2 for i in range(4) for j in range(i + 1, 4)])
    assert _quartic_discriminant(*coefficients) == pytest.approx(coefficients[0] ** 6 * product.real, rel=1e-10)
    # no control: the collisions and names of the open loop
    open_loop = closed_loop(benchmark, [0, 0, 0, 0])
    np.testing.assert_allclose(open_loop.collision_speeds(), benchmark.collision_speeds(), rtol=1e-8)
    speeds = np.linspace(0, 10, 21)
    a, b = open_loop.eigenvalues(speeds), benchmark.eigenvalues(speeds)
    np.testing.assert_allclose(a.values, b.values, atol=1e-10)
    assert (a.labels == b.labels).all()
    # under a law: a closed-loop collision is where two eigenvalues meet
    system = closed_loop(benchmark, LAWS[2])
    for c in system.collision_speeds():
        ev = np.sort_complex(np.linalg.eigvals(system.state_matrix(c)))
        assert np.min(np.abs(np.diff(ev))) < 1e-3 * max(1.0, np.abs(ev).max())


def test_a_sweep_under_a_law_is_each_design_under_it():
    base = bikerider.named("Benchmark")
    trails = np.linspace(0.02, 0.12, 4)
    law = LAWS[0]
    swept = bikerider.sweep(base, {"c": trails}, speeds=[4.0, 6.0], law=law)
    for k, c in enumerate(trails):
        one = closed_loop(bikerider.WhippleModel.from_parameters(base.with_values(c=float(c))), law).stability()
        assert swept.stability.weave[k] == pytest.approx(one.weave, rel=1e-10)
        assert swept.stability.capsize[k] == pytest.approx(one.capsize, rel=1e-10)
    assert swept.law is law and swept.eigenvalues.shape == (4, 2, 4)
    free = bikerider.sweep(base, {"c": trails})
    assert np.all(swept.stability.weave < free.stability.weave)  # roll-rate feedback lowers the weave speed
    no_control = bikerider.sweep(base, {"c": trails}, law=[0, 0, 0, 0])
    np.testing.assert_allclose(no_control.stability.weave, free.stability.weave, rtol=1e-10)


def test_the_gains_figure_draws_each_gain(tmp_path):
    model = bikerider.WhippleModel.from_parameters(bikerider.named("Benchmark"))
    law = lqr_law(model, np.linspace(0.5, 10, 20))
    fig = plotting.gains_figure([law, LAWS[2]], np.linspace(0, 10, 101), title="gains", stable=[(1.0, np.inf)])
    assert len(fig.axes) == 4
    lines = fig.axes[1].get_lines()
    np.testing.assert_allclose(lines[0].get_ydata(), law(np.linspace(0, 10, 101))[:, 1])
    assert plotting.save_figure(fig, tmp_path / "gains.png").stat().st_size > 0
