"""The friction law's corner (issue 25, honest odds at a push): a friction rival's decays are predicted over the
smoothings ``eps`` of its friction that the data do not decide, each as a move from the decay at the data's push,
and their spread is part of the rival's own uncertainty."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bikerider.gap.inference.timedomain import SMOOTHING, simulate_friction
from bikerider.gap.plan import decays, ranking
from bikerider.gap.plan.decays import Experiment


def test_the_corners_span_the_truths_smoothing_around_the_fits_own():
    eps, weights = decays.smoothing_nodes()
    assert eps[0] == SMOOTHING and sum(weights) == pytest.approx(1.0)
    # symmetric in log eps around the fits' own; the range reaches the closed loop's truth (0.02 rad/s)
    assert math.log(eps[1] / SMOOTHING) == pytest.approx(-math.log(eps[2] / SMOOTHING))
    assert SMOOTHING / decays.SMOOTHING_FACTOR <= 0.02 < min(eps) < SMOOTHING < max(eps)


def test_a_sharper_corner_is_simulated_when_asked_and_the_default_is_the_fits_own():
    A = np.array([[0.0, 1.0], [-20.0, -1.0]])
    b = np.array([0.0, 1.0])
    x0 = np.array([0.1, 0.0])
    default = simulate_friction(A, b, x0, 0.5, 0.01, 200, 1)
    assert np.array_equal(default, simulate_friction(A, b, x0, 0.5, 0.01, 200, 1, SMOOTHING))
    sharp = simulate_friction(A, b, x0, 0.5, 0.01, 200, 1, 0.02)
    assert not np.allclose(sharp, default)
    # a sharper corner sticks harder near a standstill: the motion dies out sooner
    assert np.abs(sharp[100:, 0] - sharp[-1, 0]).max() <= np.abs(default[100:, 0] - default[-1, 0]).max()
    with pytest.raises(ValueError, match="smoothing"):
        simulate_friction(A, b, x0, 0.5, 0.01, 10, 1, 0.0)


def test_corners_move_a_push_from_the_datas_and_leave_the_datas_push_alone():
    points = [Experiment(4.0, "sil", "roll_rate", p) for p in (0.5, 1.0, 2.0)] + [
        Experiment(5.0, "sil", "roll_rate", 2.0)  # no decay at the data's push there: not anchored
    ]
    own = np.array([-1 + 5j, -1.2 + 5.5j, -1.5 + 6j, -2 + 7j])
    sharp = own + np.array([0.3 + 1j, 0.1 + 0.2j, -0.2 - 0.5j, 0.4 + 0.4j])  # a corner's predictions
    smooth = own - np.array([0.3 + 1j, 0.1 + 0.2j, -0.2 - 0.5j, 0.4 + 0.4j])
    weights = decays.smoothing_nodes()[1]
    mean, cov = ranking._Planner._over_corners(SimpleNamespace(points=points), own, [sharp, smooth], weights)
    # at the data's push the fit meets the data at any corner: no spread, the fit's own prediction
    assert mean[1] == own[1] and np.all(cov[1] == 0)
    # elsewhere the corner's move from the data's push: (0.3 + 1j) - (0.1 + 0.2j) at half the push
    w = weights[1]
    assert cov[0, 0, 0] == pytest.approx(2 * w * 0.2**2) and cov[0, 1, 1] == pytest.approx(2 * w * 0.8**2)
    assert cov[2, 1, 1] == pytest.approx(2 * w * 0.7**2)
    assert cov[3, 1, 1] == pytest.approx(2 * w * 0.4**2)  # unanchored
    assert np.allclose(mean, own)  # symmetric corners: the mean stays
    assert np.all(np.linalg.eigvalsh(cov) >= -1e-15)
