"""Model-discrimination criteria (bikerider.gap.plan.criteria) against the textbook two-rival cases."""

import math

import numpy as np
import pytest

from bikerider.gap.plan import criteria as C


def one(mu, s2, noise):
    """Two rivals, one response, one experiment: means (2, 1, 1), own (2, 1, 1, 1), noise (1, 1, 1)."""
    means = np.array(mu, float).reshape(2, 1, 1)
    own = np.array(s2, float).reshape(2, 1, 1, 1)
    return means, own, np.full((1, 1, 1), float(noise))


def test_hunter_reiner_is_the_squared_difference_over_the_noise():
    means, own, noise = one([1.0, 3.0], [0.5, 0.2], 0.25)
    assert C.hunter_reiner(means, own, noise) == pytest.approx([(3.0 - 1.0) ** 2 / 0.25])


def test_box_hill_single_response_formula():
    # Box and Hill (1967), one response: 1/2 sum pi_i pi_j [(s_i^2 - s_j^2)^2 / ((s^2 + s_i^2)(s^2 + s_j^2))
    #   + (y_i - y_j)^2 (1 / (s^2 + s_i^2) + 1 / (s^2 + s_j^2))]
    y, s2, sigma2, pi = [0.4, 1.9], [0.3, 1.1], 0.5, [0.7, 0.3]
    a, b = sigma2 + s2[0], sigma2 + s2[1]
    expected = 0.5 * pi[0] * pi[1] * ((s2[0] - s2[1]) ** 2 / (a * b) + (y[0] - y[1]) ** 2 * (1 / a + 1 / b))
    means, own, noise = one(y, s2, sigma2)
    assert C.box_hill(means, own, noise, pi) == pytest.approx([expected])


def test_buzzi_ferraris_single_response():
    means, own, noise = one([2.0, -1.0], [0.4, 0.6], 0.5)
    assert C.buzzi_ferraris(means, own, noise) == pytest.approx([9.0 / (2 * 0.5 + 0.4 + 0.6)])
    assert C.buzzi_ferraris_ratio(means, own, noise) == pytest.approx([9.0 / 2.0])


def test_jensen_renyi_against_quadrature():
    y, s2, sigma2, pi = [0.0, 1.3], [0.2, 0.9], 0.3, [0.6, 0.4]
    means, own, noise = one(y, s2, sigma2)
    x = np.linspace(-15, 15, 200001)
    dens = [np.exp(-((x - y[k]) ** 2) / (2 * (s2[k] + sigma2))) / np.sqrt(2 * np.pi * (s2[k] + sigma2)) for k in (0, 1)]
    mix = pi[0] * dens[0] + pi[1] * dens[1]
    dx = x[1] - x[0]
    h2 = [-math.log(np.sum(d**2) * dx) for d in dens]
    expected = -math.log(np.sum(mix**2) * dx) - (pi[0] * h2[0] + pi[1] * h2[1])
    assert C.jensen_renyi(means, own, noise, pi) == pytest.approx([expected], rel=1e-6)


@pytest.mark.parametrize("name", C.CRITERIA)
def test_identical_rivals_score_zero_and_order_does_not_matter(name):
    rng = np.random.default_rng(3)
    n, m = 4, 3
    A = rng.standard_normal((n, m, m))
    noise = A @ np.swapaxes(A, -1, -2) + np.eye(m)
    mu = rng.standard_normal((n, m))
    W = 0.3 * noise
    same = C.score(name, np.stack([mu, mu]), np.stack([W, W]), noise)
    assert np.allclose(same, 0.0, atol=1e-9)
    other = mu + rng.standard_normal((n, m))
    ab = C.score(name, np.stack([mu, other]), np.stack([W, 2 * W]), noise, [0.5, 0.5])
    ba = C.score(name, np.stack([other, mu]), np.stack([2 * W, W]), noise, [0.5, 0.5])
    assert np.all(ab > 0) and np.allclose(ab, ba)


@pytest.mark.parametrize("name", C.CRITERIA)
def test_invariant_under_a_change_of_units(name):
    """Observing ``L y`` instead of ``y`` (other units, real and imaginary parts mixed) changes nothing."""
    rng = np.random.default_rng(5)
    n, m, R = 3, 2, 3
    A = rng.standard_normal((n, m, m))
    noise = A @ np.swapaxes(A, -1, -2) + np.eye(m)
    mu = rng.standard_normal((R, n, m))
    W = np.stack([k * 0.2 * noise for k in range(1, R + 1)])
    L = np.array([[3.0, 0.5], [-1.0, 0.2]])
    before = C.score(name, mu, W, noise, [0.5, 0.3, 0.2])
    after = C.score(name, mu @ L.T, L @ W @ L.T, L @ noise @ L.T, [0.5, 0.3, 0.2])
    assert np.allclose(before, after)


def test_a_larger_difference_scores_higher_and_the_rivals_own_doubt_lowers_box_hill():
    means, own, noise = one([0.0, 1.0], [0.1, 0.1], 0.2)
    far, _, _ = one([0.0, 2.0], [0.1, 0.1], 0.2)
    for name in C.CRITERIA:
        assert C.score(name, far, own, noise) > C.score(name, means, own, noise)
    doubt = own * 20
    assert C.box_hill(means, doubt, noise) < C.box_hill(means, own, noise)
    assert C.buzzi_ferraris(means, doubt, noise) < C.buzzi_ferraris(means, own, noise)


def test_bad_input_says_what_was_expected():
    means, own, noise = one([0.0, 1.0], [0.1, 0.1], 0.2)
    with pytest.raises(ValueError, match="criterion 'fisher'"):
        C.score("fisher", means, own, noise)
    with pytest.raises(ValueError, match="noise: expected shape"):
        C.box_hill(means, own, np.ones((2, 1, 1)))
    with pytest.raises(ValueError, match="finite"):
        C.box_hill(means * np.nan, own, noise)
    with pytest.raises(ValueError, match="weights"):
        C.box_hill(means, own, noise, [1.0, -1.0])
