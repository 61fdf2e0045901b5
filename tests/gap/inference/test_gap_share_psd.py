"""The benchmark parameters' bounded share of a time-domain fit is a covariance (positive semidefinite).

:func:`bikerider.gap.inference.timedomain.parameter_share` returns ``G G^T`` plus the draws' mean of
``(d - d0)(d - d0)^T - (G z)(G z)^T``: a difference of mean squares.  Where a fitted value stays on its
bound in every draw its row of the first mean square is zero, and its variance is ``|g|^2`` less the draws'
mean of ``(g . z)^2``, negative whenever the draws happen to spread wider than their expectation along
``g``: a negative variance, a NaN standard error.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from bikerider.gap.inference import timedomain as TD


def _draws(p: int) -> np.ndarray:
    return np.random.default_rng(TD.PARAMETER_SEED).standard_normal((TD.PARAMETER_DRAWS, p))


def _held_on_its_bound(monkeypatch):
    """A two-value fit whose second value the residuals push far below its bound (zero), the parameters'
    error along the draws' widest direction in that value: it stays on the bound in every draw."""
    p = 3
    z = _draws(p)
    w, V = np.linalg.eigh(z.T @ z / z.shape[0])
    assert w[-1] > 1.0  # the draws spread wider than N(0, I) along V[:, -1]
    J = np.eye(2)
    r = np.array([0.0, 5.0])  # the slope pushes the second value 5 below its bound
    Jq = 0.01 * np.vstack([[1.0, 0.5, -0.3], V[:, -1]])
    monkeypatch.setattr(TD, "_parameter_slopes", lambda *args: (r, J, Jq))
    layout = SimpleNamespace(lower=(0.0, 0.0), upper=(np.inf, np.inf))
    theta = np.array([0.1, 0.0])
    return layout, theta, z, J, Jq


def test_the_share_is_positive_semidefinite_where_its_excess_would_make_it_indefinite(monkeypatch):
    layout, theta, z, J, Jq = _held_on_its_bound(monkeypatch)
    share = TD.parameter_share([], {}, None, layout, theta, {"a": 1.0, "b": 1.0, "c": 1.0})
    G = share.sensitivity
    np.testing.assert_allclose(G, -Jq, rtol=1e-12)  # H = I
    # the sum before: G G^T plus the excess, the second value never moving off its bound
    free = z @ G.T
    moved = free.copy()
    moved[:, 1] = 0.0
    before = G @ G.T + (moved.T @ moved - free.T @ free) / z.shape[0]
    assert before[1, 1] < 0  # a negative variance: what the share was
    assert np.linalg.eigvalsh(before).min() < 0
    # the share now: symmetric, no negative eigenvalue, the second value's variance not negative
    cov = share.covariance
    np.testing.assert_array_equal(cov, cov.T)
    assert np.linalg.eigvalsh(cov).min() >= -1e-15 * np.abs(cov).max()
    assert cov[1, 1] >= 0 and np.isfinite(np.sqrt(cov[1, 1]))
    # the free value's share as before, to the clipped eigenvalue (tiny: the draws' sampling error)
    assert cov[0, 0] == pytest.approx(before[0, 0], rel=1e-3)
    assert share.bounded == pytest.approx(1.0)


def test_a_positive_semidefinite_matrix_is_left_as_it_is():
    rng = np.random.default_rng(5)
    a = rng.standard_normal((3, 3))
    m = a @ a.T
    m = 0.5 * (m + m.T)
    np.testing.assert_array_equal(TD.positive_semidefinite(m), m)
    # an indefinite one: its positive part (the nearest positive semidefinite matrix in the Frobenius norm)
    d = np.diag([2.0, 0.5, -0.1])
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    out = TD.positive_semidefinite(q @ d @ q.T)
    np.testing.assert_allclose(out, q @ np.diag([2.0, 0.5, 0.0]) @ q.T, atol=1e-14)
