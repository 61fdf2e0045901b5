"""Issue 21, part 4: the friction law's corner, which decays do not decide, in the fit's interval and equivalent.

The time-domain fit models the sign of the steer rate as ``tanh(deltad / eps)`` at its own corner (0.05
rad/s).  On the calibration's roll-rate decays with the rider the steer moves at 0.05-0.1 rad/s, where
the corner changes what a torque does: against a truth with a corner of 0.02 rad/s the fit put
``T_coulomb`` a median 27 % high with intervals that missed it (coverage 67 %), and its equivalent
damping, taken as ``4 T / (pi A)`` whatever the corner, 28 % high.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from gap_support import SIL, nominal, riderless_model
from scipy.integrate import quad

from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.diagnosis.priors import equivalent_damping
from bikerider.gap.inference.problem import EffectFit
from bikerider.gap.inference.timedomain import (
    CORNER_FACTOR,
    CORNER_NODES,
    SMOOTHING,
    CornerShare,
    Layout,
    corner_nodes,
    corner_share,
    describing_gain,
    fit_time_domain,
    simulate_friction,
)
from bikerider.gap.measured.records import Record
from validation import cases as V

FRICTION = Layout.of(("steer_friction",))
T_TRUE = 0.06
"""Coulomb friction of the simulated decays [N m]; no viscous part."""
SHARP = 0.02
"""The simulated decays' corner [rad/s]: the lower end of the corners the fit allows for."""


def test_the_describing_gain_is_the_first_harmonic_and_tends_to_both_limits():
    for A, eps in ((0.05, 0.05), (0.2, 0.02), (0.03, 0.1), (1.0, 0.01)):
        first = quad(lambda th: math.tanh(A * math.sin(th) / eps) * math.sin(th), 0.0, math.pi, limit=200)[0]
        assert describing_gain(A, eps) == pytest.approx(2.0 * first / (math.pi * A), rel=1e-6)
    assert describing_gain(10.0, 1e-3) == pytest.approx(4 / (math.pi * 10.0), rel=2e-4)  # a sharp corner
    assert describing_gain(1e-4, 0.05) == pytest.approx(1 / 0.05, rel=1e-6)  # a slow steer: viscous 1/eps
    assert describing_gain(np.full((2, 3), 0.1)).shape == (2, 3)
    assert describing_gain(0.1) == describing_gain(0.1, SMOOTHING)
    with pytest.raises(ValueError, match="smoothing"):
        describing_gain(0.1, 0.0)
    with pytest.raises(ValueError, match="amplitude"):
        describing_gain(np.array([0.1, -0.2]))


def test_the_corners_span_the_range_around_the_fits_own():
    eps, weights = corner_nodes()
    assert eps[0] == SMOOTHING and sum(weights) == pytest.approx(1.0)
    assert SMOOTHING / CORNER_FACTOR < min(eps) < SMOOTHING < max(eps) < SMOOTHING * CORNER_FACTOR
    assert math.log(eps[1] / SMOOTHING) == pytest.approx(-math.log(eps[2] / SMOOTHING))


@pytest.fixture(scope="module")
def slow_decays():
    """Six roll-rate-and-steer decays under SIL with Coulomb friction of a sharp corner and steer rates of
    0.07-0.18 rad/s (the noise-free states' peaks), the fit at its own corner and its corner share."""
    model = riderless_model()
    values = nominal(model)
    records, peaks = [], []
    for speed in (2.5, 3.5, 4.5):
        ss = EffectModel(values, model.geometry, {}).state_space([speed])
        A = ss.closed_loop(np.array([SIL(speed)]))[0]
        out = ss.output_states
        for k in range(2):
            rng = np.random.default_rng(k + int(10 * speed))
            x0 = np.zeros(A.shape[-1])
            x0[out[2]], x0[out[3]] = 0.05 * (-1) ** k, 0.04
            t = np.arange(0.0, 2.0, 0.01)
            states = simulate_friction(A, ss.B[0, :, 1], x0, T_TRUE, 0.01, t.size, out[3], SHARP)
            peaks.append(float(np.max(np.abs(states[:, out[3]]))))
            signals = {
                "roll_rate": states[:, out[2]] + 0.001 * rng.standard_normal(t.size),
                "steer_angle": states[:, out[1]] + 1e-4 * rng.standard_normal(t.size),
            }
            records.append(
                Record(f"{speed}[{k}]", "test", t, signals, speed, 0.01, f"{speed} m/s", SIL, speed, None, None)
            )
    fit = fit_time_domain(records, values, model.geometry, FRICTION)
    share = corner_share(records, values, model.geometry, FRICTION, fit.values)
    return fit, share, peaks


def test_at_steer_rates_of_a_few_corners_the_corner_moves_the_split_and_hardly_the_equivalent(slow_decays):
    fit, share, peaks = slow_decays
    assert 0.05 < min(peaks) and max(peaks) < 0.25
    eps, weights = corner_nodes()
    assert [(e, w) for e, w, _ in share.corners] == list(zip(eps, weights))
    assert np.array_equal(share.corners[0][2], fit.values)
    # the share is the corner prior's mean square of the move from the fit's own corner
    moves = np.array([v - fit.values for _, _, v in share.corners])
    assert share.covariance == pytest.approx((np.array(weights)[:, None] * moves).T @ moves)
    # the corner matters at these rates: the Coulomb level moves by more than a sixth between the corners
    levels = [v[0] for _, _, v in share.corners]
    assert max(levels) - min(levels) > fit.values[0] / 6
    assert math.sqrt(share.covariance[0, 0]) > 0.05 * fit.values[0]
    # what the decays determine, the damping at their amplitude, each corner through its own law, moves far less
    A = float(np.median(peaks))
    equivalents = [v[1] + v[0] * float(describing_gain(A, e)) for e, _, v in share.corners]
    spread = (max(equivalents) - min(equivalents)) / equivalents[0]
    assert spread < 0.5 * (max(levels) - min(levels)) / levels[0]


def _friction_fit(values, corners, covariance, corner_covariance) -> EffectFit:
    values = np.asarray(values, float)
    return EffectFit(
        effects=("steer_friction",),
        names=["T_coulomb", "c_viscous"],
        units=["N m", "N m s/rad"],
        values=values,
        stderr=np.sqrt(np.diag(covariance)),
        ci_low=values,
        ci_high=values,
        config={},
        shift={},
        chi2=1.0,
        prior_chi2=0.0,
        n=100,
        success=True,
        covariance=np.asarray(covariance, float),
        corners=corners,
        corner_covariance=None if corner_covariance is None else np.asarray(corner_covariance, float),
    )


def test_the_equivalent_is_taken_at_each_corner_through_its_own_law():
    A = 0.08
    target = 1.2  # N m s/rad: the damping the decays determine, whatever the corner
    eps, weights = corner_nodes()
    corners = [(e, w, np.array([target / float(describing_gain(A, e)), 0.0])) for e, w in zip(eps, weights)]
    moves = np.array([v - corners[0][2] for _, _, v in corners])
    corner_cov = (np.array(weights)[:, None] * moves).T @ moves
    data_cov = np.diag([1e-6, 1e-4])
    fit = _friction_fit(corners[0][2], corners, data_cov + corner_cov, corner_cov)
    value, stderr, (low, high) = equivalent_damping(fit, A, folds=0)
    assert value == pytest.approx(target)
    g = np.array([float(describing_gain(A)), 1.0])
    # the corners' Coulomb levels differ by tens of per cent, their equivalents not at all: only the data's share
    assert math.sqrt(corner_cov[0, 0]) > 0.2 * corners[0][2][0]
    assert stderr == pytest.approx(math.sqrt(g @ data_cov @ g))
    assert (low, high) == pytest.approx((target - 1.96 * stderr, target + 1.96 * stderr))
    # a sharp law's 4 T / (pi A) would put the same fit well above what the decays determine
    assert 4 * corners[0][2][0] / (math.pi * A) > 1.1 * target


def test_the_calibration_truths_corner_is_drawn_over_the_fits_range_and_sizes_its_equivalent():
    drawn = [V.draw_corner(seed) for seed in range(1000, 1200)]
    assert V.draw_corner(1000) == drawn[0]
    assert SMOOTHING / CORNER_FACTOR <= min(drawn) and max(drawn) <= SMOOTHING * CORNER_FACTOR
    # log-uniform: about half below the fits' own corner
    assert 0.35 < np.mean(np.array(drawn) < SMOOTHING) < 0.65
    truth = V.Truth("t", ("steer_friction",), {"T_coulomb": 0.1, "eps_coulomb": 1e-4}, "")
    assert V.truth_equivalent(truth, 0.5) == pytest.approx(4 * 0.1 / (math.pi * 0.5), rel=1e-3)
    soft = V.Truth("t", ("steer_friction",), {"T_coulomb": 0.1, "eps_coulomb": 0.1}, "")
    assert V.truth_equivalent(soft, 0.05) < 0.6 * V.truth_equivalent(truth, 0.05)
    assert math.isnan(V.truth_equivalent(truth, None))


def test_the_plan_leaves_the_corners_share_to_its_own_corners():
    # the plan predicts a friction rival at each corner itself; the fit's covariance without the corner's share
    from bikerider.gap.plan.discrimination import bounded_covariance

    data_cov = np.diag([1e-6, 1e-4])
    corner_cov = np.array([[4e-4, -1e-3], [-1e-3, 3e-3]])
    fit = _friction_fit([0.1, 0.2], [], data_cov + corner_cov, corner_cov)
    fit.lower, fit.upper = np.zeros(2), np.array([1.0, 5.0])
    assert bounded_covariance(fit, np.array([10.0, 10.0])) == pytest.approx(data_cov)


def _share(at_nodes) -> CornerShare:
    """A corner share whose one value is ``at_nodes`` at the nodes of :func:`corner_nodes` (own corner first)."""
    eps, weights = corner_nodes()
    return CornerShare(np.zeros((1, 1)), [(e, w, np.array([v])) for e, w, v in zip(eps, weights, at_nodes)])


def test_without_a_corner_effect_the_interval_is_the_fits_own():
    low, high = _share([0.05, 0.05, 0.05]).interval(0, 0.02, 0.0, 1.0)
    assert (low, high) == pytest.approx((0.03, 0.07), rel=1e-6)
    assert _share([0.05, 0.05, 0.05]).interval(0, 0.02, 0.04, 0.065) == pytest.approx((0.04, 0.065))


def test_the_interval_spans_the_values_over_the_corners_whole_range():
    # a value linear in log eps, known exactly at each corner: the central 95 % of its uniform spread over
    # the range u in [-1, 1] (the nodes at 0 and -/+ sqrt(0.6) of the half range), u = -/+ 0.95
    nodes = np.array(CORNER_NODES)
    low, high = _share(0.05 + 0.02 * nodes).interval(0, 0.0, 0.0, 1.0)
    assert (low, high) == pytest.approx((0.05 - 0.95 * 0.02, 0.05 + 0.95 * 0.02), rel=1e-6)
    # about T_coulomb of steer_coulomb seed 1000 at the three corners (refitted at 0.02, 0.05, 0.10 rad/s:
    # 0.018, 0.028, 0.052 N m; the truth 0.066 at a corner of 0.10): rising ever faster with the corner, the interval
    # reaches further up than down, and further up than the symmetric one of the same corner share
    at_nodes = [0.028, 0.019, 0.053]
    share = _share(at_nodes)
    low, high = share.interval(0, 0.01, 0.0, 1.0)
    assert high - 0.028 > 2 * (0.028 - low) > 0
    eps, weights = corner_nodes()
    corner_variance = sum(w * (v - 0.028) ** 2 for w, v in zip(weights, at_nodes))
    symmetric = 1.96 * math.sqrt((0.01 / 1.96) ** 2 + corner_variance)
    assert high > 0.028 + symmetric + 0.005
    # wider where each corner's fit is less certain
    assert share.interval(0, 0.02, 0.0, 1.0)[1] > high


def test_a_corner_whose_refit_has_no_value_leaves_the_fits_own_interval():
    assert _share([0.05, np.nan, 0.06]).interval(0, 0.01, 0.0, 1.0) == pytest.approx((0.04, 0.06))
