"""Issue 21 item 4: a single candidate's 95 % intervals from few records are profile-likelihood intervals.

The calibration study's rider lean damping and tyre relaxation length were missed on the far side of long,
curved chi-square valleys that the interval linearised about the fit, and the hull of the points the searches
visited, did not reach (docs/gap_validation.md part 4).  :meth:`GapProblem.profile_apparent` steps each size
out from the fit and re-minimises the others; :func:`with_parameter_uncertainty` with ``profile`` takes the
data's share of each size's interval where its profile chi-square rises ``q^2 max(1, s^2) D_kk / B_kk`` above
the fit's (the data's variance over the chi-square's own) and adds the shares the chi-square cannot see (the
benchmark parameters', the rider geometry's) in quadrature, so each share is counted once.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from bikerider.gap.diagnosis.fits import with_parameter_uncertainty
from bikerider.gap.inference.problem import PROFILE_TOLERANCE, EffectFit, GapProblem, _Layout


class _Synthetic(GapProblem):
    """A problem of two sizes ``x`` (0-5) and ``y`` (0-10) fitted from records, built without a model: only
    what :meth:`GapProblem.fit_apparent`, :meth:`GapProblem.profile_apparent` and
    :func:`with_parameter_uncertainty` use.  The observations are 0; ``predict(X)`` gives the predictions
    ``(P, n)``; ``var_data`` and ``var_total`` their variances; ``jacobian`` the benchmark parameters' slopes
    per sigma (one parameter)."""

    def __init__(self, predict, n: int, var_data: float = 1.0, var_total: float = 1.0, jacobian=None):
        self._predict = predict
        self.records = SimpleNamespace()
        self.record_obs = np.arange(n).reshape(-1, 2)
        self.obs = list(range(n))
        self.y = np.zeros(n)
        self.var_data = np.full(n, var_data)
        self.var_total = np.full(n, var_total)
        self.nominal_bias = np.zeros(n)
        self.free = ["w"]
        self.jacobian = np.zeros((n, 1)) if jacobian is None else np.asarray(jacobian, float)
        self.calls = 0
        self._lay = _Layout(
            ("tyre_slip",),
            structural=[("tyre_slip", "c_alpha"), ("tyre_slip", "sigma_t")],
            lower=[0.0, 0.0],
            upper=[5.0, 10.0],
            starts=[(1.0, 1.0)],
            units=["1/rad", "m"],
        )

    def layout(self, effects):
        return self._lay

    def configure(self, lay, x):
        return {}, {}, None

    def predict_batch(self, lay, X, indirect=True, strict=False):
        self.calls += 1
        return self._predict(np.atleast_2d(np.asarray(X, float)))

    def parameter_jacobian_at(self, lay, x, indirect=True, columns=None):
        return np.array(self.jacobian)


EPS, SIGMA = 0.05, 0.3


def _banana(X: np.ndarray) -> np.ndarray:
    """A curved valley: ``(y - x^2) / EPS`` and ``(x - 1) / SIGMA`` (chi-square 0 at (1, 1)).  In ``x`` the
    profile is nearly ``((x - 1) / SIGMA)^2``; in ``y`` it is nearly ``((sqrt(y) - 1) / SIGMA)^2``, asymmetric
    about the fit: the linearisation (``dy = 2 x dx``) ends short of its upper crossing."""
    x, y = X[:, 0], X[:, 1]
    return np.stack([(y - x**2) / EPS, (x - 1) / SIGMA], axis=1)


def _fit(problem: _Synthetic, values) -> EffectFit:
    """The fit :meth:`GapProblem.fit_apparent` polishes from ``values`` (no search for other minima)."""
    lay = problem.layout(())
    x = np.asarray(values, float)
    r = problem._residuals(lay, np.ones(len(problem.obs), bool), x, None)
    start = problem._result(lay, x, np.array([0.1, 0.1]), r, len(problem.obs), True, "bias corrected")
    return problem.fit_apparent(start, starts=0)


def _profile_chi2(k: int, value: float) -> float:
    """The banana's profile chi-square at size ``k`` = ``value``, the other size minimised (bounded)."""

    def chi2(other: float) -> float:
        X = np.array([[value, other]]) if k == 0 else np.array([[other, value]])
        return float(np.sum(_banana(X) ** 2))

    bounds = (0.0, 10.0) if k == 0 else (0.0, 5.0)
    return float(minimize_scalar(chi2, bounds=bounds, method="bounded", options={"xatol": 1e-10}).fun)


def _crossing(k: int, side: float, target: float) -> float:
    """Where the banana's profile of size ``k`` reaches ``target`` on ``side`` of 1 (bisection)."""
    inside, outside = 1.0, (5.0 if k == 0 else 10.0) if side > 0 else 0.0
    for _ in range(60):
        middle = 0.5 * (inside + outside)
        inside, outside = (middle, outside) if _profile_chi2(k, middle) < target else (inside, middle)
    return 0.5 * (inside + outside)


def test_the_profile_interval_reaches_the_far_side_of_a_curved_valley():
    problem = _Synthetic(_banana, 2)
    fit = _fit(problem, [1.0, 1.0])
    assert fit.values == pytest.approx([1.0, 1.0], abs=1e-6) and fit.chi2 < 1e-8
    old = with_parameter_uncertainty(problem, fit)
    new = with_parameter_uncertainty(problem, fit, profile=True)
    assert new.profiled == ["c_alpha", "sigma_t"]
    target = 1.96**2  # data only (D = B, no other share) and a chi-square below its degrees of freedom: 3.84
    high = _crossing(1, 1.0, target)
    assert high == pytest.approx((1 + 1.96 * SIGMA) ** 2, rel=0.02)  # about 2.52
    assert new.ci_high[1] == pytest.approx(high, abs=0.02)
    assert old.ci_high[1] < high - 0.25  # linearised: 1 + 1.96 * 2 SIGMA = 2.18
    # the lower end lies nearer the fit than the linearisation's (sqrt(y) - 1 = -0.588: y = 0.17, not -0.18)
    assert new.ci_low[1] == pytest.approx(_crossing(1, -1.0, target), abs=0.02)
    # the size whose profile is quadratic keeps its linearised interval
    assert new.ci_low[0] == pytest.approx(old.ci_low[0], abs=0.01)
    assert new.ci_high[0] == pytest.approx(old.ci_high[0], abs=0.01)


def test_the_profile_ends_lie_on_the_threshold():
    problem = _Synthetic(_banana, 2)
    fit = _fit(problem, [1.0, 1.0])
    ends = problem.profile_apparent(fit, np.full(2, 1.96**2))
    for k in range(2):
        for value, chi2 in ((ends.low[k], ends.chi2_low[k]), (ends.high[k], ends.chi2_high[k])):
            assert chi2 - fit.chi2 == pytest.approx(1.96**2, abs=PROFILE_TOLERANCE)
            # the other size truly minimised there: an independent profile agrees
            assert _profile_chi2(k, value) == pytest.approx(chi2, abs=0.02)
    assert ends.calls < 40  # batched: every size and side in one model call per round


def _linear(X: np.ndarray) -> np.ndarray:
    """Four observations linear in both sizes (chi-square 0 at (2.5, 5), the intervals inside the bounds)."""
    M = np.array([[1.0, 0.5], [0.5, 1.0], [1.0, -0.3], [0.2, 1.0]])
    return (X - np.array([2.5, 5.0])) @ M.T


def test_a_quadratic_chi_square_gives_the_sandwich_interval_each_share_once():
    # the data's variance half of the weights', the parameter's error the other half, common to every row:
    # the sandwich's variance is not the chi-square's own, and its profile must give the sandwich interval
    jacobian = np.array([[np.sqrt(0.5)], [np.sqrt(0.5)], [np.sqrt(0.5)], [-np.sqrt(0.5)]])
    problem = _Synthetic(_linear, 4, var_data=0.5, var_total=1.0, jacobian=jacobian)
    fit = _fit(problem, [2.5, 5.0])
    linear = with_parameter_uncertainty(problem, fit)
    profiled = with_parameter_uncertainty(problem, fit, profile=True)
    assert profiled.profiled == ["c_alpha", "sigma_t"]
    np.testing.assert_allclose(profiled.ci_low, linear.ci_low, rtol=0.01)
    np.testing.assert_allclose(profiled.ci_high, linear.ci_high, rtol=0.01)
    # the chi-square's own curvature alone would not: the shares differ from it by more than the tolerance
    M = np.array([[1.0, 0.5], [0.5, 1.0], [1.0, -0.3], [0.2, 1.0]])
    own = 1.96 * np.sqrt(np.diag(np.linalg.inv(M.T @ M)))
    half = (linear.ci_high - linear.ci_low) / 2
    assert np.all(np.abs(half / own - 1) > 0.1)


def test_without_profile_nothing_is_profiled():
    problem = _Synthetic(_banana, 2)
    out = with_parameter_uncertainty(problem, _fit(problem, [1.0, 1.0]))
    assert out.profiled == []
