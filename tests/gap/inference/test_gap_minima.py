"""Issue 21 item 4: a size's 95 % interval holds every local minimum of the fit's chi-square that the data
cannot tell from the fit, and uses Student's t when the data's scale is estimated from the residuals."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.special import stdtrit

from bikerider.gap.diagnosis.fits import with_parameter_uncertainty
from bikerider.gap.diagnosis.statistics import _minima
from bikerider.gap.inference.problem import EffectFit, GapProblem, _Layout, scale_and_quantile
from bikerider.gap.text import _minima_text


class _TwoMinima(GapProblem):
    """A problem of one size ``x`` and two observations fitted from records, whose chi-square has two local
    minima: ``r1 = depth (x - 3)(x - 7)`` vanishes at both, ``r2 = tilt (x - 4)`` tips them (``tilt = 0.1``,
    ``depth = 0.5``: 0.01 at 3 and 0.09 at 7, a ridge of chi-square 4 at 5 between them).  Built without a model: only
    what :meth:`GapProblem.fit_apparent` and :func:`with_parameter_uncertainty` use."""

    def __init__(self, tilt: float = 0.1, depth: float = 0.5):
        self.tilt, self.depth = tilt, depth
        self.records = SimpleNamespace()
        self.record_obs = np.array([[0, 1]])
        self.obs = [0, 1]
        self.y = np.zeros(2)
        self.var_data = np.ones(2)
        self.var_total = np.ones(2)
        self.nominal_bias = np.zeros(2)
        self.free = ["w"]
        self.jacobian = np.zeros((2, 1))
        self._lay = _Layout(
            ("steer_damping",),
            structural=[("steer_damping", "c_steer")],
            lower=[0.0],
            upper=[20.0],
            starts=[(1.0,), (3.0,), (5.0,), (8.0,)],
            units=["N m s/rad"],
        )

    def layout(self, effects):
        return self._lay

    def configure(self, lay, x):
        return {}, {}, None

    def predict_batch(self, lay, X, indirect=True, strict=False):
        x = np.asarray(X, float)[:, 0]
        return np.stack([self.depth * (x - 3) * (x - 7), self.tilt * (x - 4)], axis=1)


def _start(problem: _TwoMinima, x: float) -> EffectFit:
    """The bias-corrected fit :meth:`GapProblem.fit` would hand on: values ``x``, near one minimum."""
    lay = problem.layout(())
    r = problem._residuals(lay, np.ones(2, bool), np.array([x]), None)
    return problem._result(lay, np.array([x]), np.array([0.1]), r, 2, True, "bias corrected")


def test_a_second_minimum_within_the_threshold_is_found_and_held_by_the_interval():
    problem = _TwoMinima()
    fit = problem.fit_apparent(_start(problem, 3.2))
    assert fit.values[0] == pytest.approx(3.0, abs=0.05)  # the deeper minimum
    assert len(fit.minima) == 1
    ((other, chi2),) = fit.minima
    assert other[0] == pytest.approx(7.0, abs=0.05) and chi2 - fit.chi2 == pytest.approx(0.08, abs=0.02)
    out = with_parameter_uncertainty(problem, fit)
    assert out.minima_within == 1
    assert out.ci_low[0] < 3.0 and out.ci_high[0] > 7.0  # one interval holds both minima
    # linearised about the fit alone it would not: the same fit without the search
    alone = with_parameter_uncertainty(problem, problem.fit_apparent(_start(problem, 3.2), starts=0))
    assert not alone.minima and alone.ci_high[0] < 5.0


def test_a_minimum_the_data_reject_is_reported_but_not_held():
    # tipped further: chi-square about 1 at 3 and 9 at 7, a ridge of 17 between them
    problem = _TwoMinima(tilt=1.0, depth=2.0)
    fit = problem.fit_apparent(_start(problem, 3.2))
    assert len(fit.minima) == 1 and fit.minima[0][0][0] > 6.0
    assert fit.minima[0][1] - fit.chi2 > 3.84
    out = with_parameter_uncertainty(problem, fit)
    assert out.minima_within == 0 and out.ci_high[0] < 6.0


def test_the_fit_moves_to_the_deeper_minimum_when_started_near_the_other():
    problem = _TwoMinima()
    fit = problem.fit_apparent(_start(problem, 6.8))
    assert fit.values[0] == pytest.approx(3.0, abs=0.05)
    assert fit.minima and fit.minima[0][0][0] == pytest.approx(7.0, abs=0.05)


def _one_size(chi2: float, n: int) -> tuple[SimpleNamespace, EffectFit]:
    """A linear problem of one size over ``n`` observations of standard error 0.2 and slope 0.4, and a fit of
    chi-square ``chi2`` to it."""

    def predict_batch(lay, X, indirect=True):
        return 0.4 * np.asarray(X, float)[:, :1] * np.ones((1, n))

    problem = SimpleNamespace(
        free=["w"],
        obs=list(range(n)),
        layout=lambda effects: None,
        predict_batch=predict_batch,
        var_total=np.full(n, 0.04),
        var_data=np.full(n, 0.04),
        jacobian=np.zeros((n, 1)),
        records=None,
        record_obs=np.zeros((0, 2), int),
    )
    fit = EffectFit(
        effects=("steer_damping",),
        names=["c_steer"],
        units=["N m s/rad"],
        values=np.array([5.0]),
        stderr=np.array([0.1]),
        ci_low=np.array([4.8]),
        ci_high=np.array([5.2]),
        config={},
        shift={},
        chi2=chi2,
        prior_chi2=0.0,
        n=n,
        success=True,
        lower=np.zeros(1),
        upper=np.full(1, 20.0),
    )
    return problem, fit


def test_a_scale_estimated_from_the_residuals_takes_students_t():
    known = 0.2 / (0.4 * np.sqrt(4))  # four rows of standard error 0.2, slope 0.4
    problem, fit = _one_size(chi2=12.0, n=4)  # reduced chi-square 4 over 3 degrees of freedom
    out = with_parameter_uncertainty(problem, fit)
    assert out.stderr[0] == pytest.approx(2 * known)
    half = (out.ci_high[0] - out.ci_low[0]) / 2
    assert half == pytest.approx(float(stdtrit(3, 0.975)) * 2 * known)  # 3.18, not 1.96
    # the stated scale stands where the residuals are within it: the normal quantile
    calm = with_parameter_uncertainty(problem, replace(fit, chi2=1.0))
    assert (calm.ci_high[0] - calm.ci_low[0]) / 2 == pytest.approx(1.96 * known)


def test_scale_and_quantile():
    assert scale_and_quantile(3.0, 10, 2) == (1.0, 1.96)
    factor, quantile = scale_and_quantile(16.0, 10, 2)
    assert factor == pytest.approx(2.0) and quantile == pytest.approx(2.306, abs=1e-3)  # t_8(0.975)
    assert scale_and_quantile(1e4, 1000, 1)[1] == pytest.approx(1.962, abs=1e-3)


def test_each_minimum_is_reported_once():
    problem = _TwoMinima()
    out = with_parameter_uncertainty(problem, problem.fit_apparent(_start(problem, 3.2)))
    assert len(out.minima) == 1 and out.minima_within == 1
    (entry,) = _minima(out)
    assert entry["within"] and entry["values"]["c_steer"] == pytest.approx(7.0, abs=0.05)
    assert entry["chi2_fit"] == pytest.approx(out.chi2)


def test_the_text_names_a_second_minimum_the_intervals_hold():
    problem = _TwoMinima()
    out = with_parameter_uncertainty(problem, problem.fit_apparent(_start(problem, 3.2)))
    (line,) = _minima_text(_minima(out), "  ")
    assert line.startswith("  another minimum of nearly equal depth: c_steer = 6.99 (chi-square 0.0898")
    assert f"against the fit's {out.chi2:.3g}" in line
    rejected = _TwoMinima(tilt=1.0, depth=2.0)
    far = with_parameter_uncertainty(rejected, rejected.fit_apparent(_start(rejected, 3.2)))
    assert _minima(far) and not _minima_text(_minima(far), "  ")  # in the JSON, not called equal depth


def test_a_bias_step_over_a_record_without_a_first_bias_stays_finite():
    # a record whose weave the nominal model's response did not show has no first bias (NaN); its
    # change of bias is unknown, not NaN: the step (SBW logs, roll rate and steer angle fitted together,
    # with the speed sensor in a pair) once became NaN there and stopped the diagnosis
    n = 4
    J = np.array([[1.0], [0.5], [0.2], [1.0]])
    run = {
        "rec": np.arange(n),
        "offset": np.array([0.1, np.nan, 0.2, 0.0]),
        "x": np.array([1.0]),
        "sigma": np.full(n, 0.1),
        "mask": np.ones(n, bool),
        "fit": SimpleNamespace(_jacobian=J, _weight=np.ones(n)),
    }
    own = np.array([0.3, 0.4, 0.2, 0.0])
    GapProblem._bias_step(run, own, 1, np.array([0.0]), np.array([10.0]))
    assert np.all(np.isfinite(run["x"]))
    assert run["x"][0] != 1.0  # the records with a known change still move it
