"""Issue 21 item 6: the fits of models with more than four states (tyres, the rider's lean) take their
Jacobian from one eigendecomposition per row (first-order eigenvalue perturbation) instead of differencing
the eigenvalues of one model per parameter; the slopes and the fits are those of the differences."""

from __future__ import annotations

import numpy as np
import pytest
from gap_support import weave_table

from bikerider.gap.inference import predict
from bikerider.gap.inference.differences import forward_jacobian
from bikerider.gap.inference.problem import GapProblem
from bikerider.gap.measured.tables import CanonicalData

TYRES = {"tyre_slip": {"c_alpha": 12.0, "sigma_t": 0.2, "t_p": 0.03, "c_gamma": 0.8}}
"""A hidden tyre: cornering stiffness 12 1/rad, relaxation length 0.2 m, pneumatic trail 3 cm (camber
stiffness the candidate's fixed 0.8)."""


@pytest.fixture(scope="module")
def tyred(davis):
    return GapProblem(davis, weave_table(davis, np.linspace(4.0, 8.0, 7), TYRES), CanonicalData.empty())


def _jacobians(problem: GapProblem, effects: tuple[str, ...], x: np.ndarray):
    lay = problem.layout(effects)
    mask = np.ones(len(problem.obs), bool)
    lower, upper = problem.bounds(lay)
    steps = 1e-5 * np.minimum(np.maximum(upper - lower, 1e-6), 10.0)
    steps[len(lay.structural) :] = 1e-3

    def residuals(X):
        return problem._residuals_batch(lay, mask, X, None)

    perturbed = problem._perturbation_jacobian(lay, mask, x, steps, upper, None)
    forward = forward_jacobian(residuals, x, steps, upper)
    # the reference: central differences of the residuals, steps ten times larger (truncation error h^2)
    H = 10 * steps
    central = np.stack(
        [(residuals((x + H[j] * e)[None])[0] - residuals((x - H[j] * e)[None])[0]) / (2 * H[j]) for j, e in enumerate(np.eye(x.size))],
        axis=1,
    )  # fmt: skip
    return lay, perturbed, forward, central


@pytest.mark.parametrize(
    "effects, x",
    [
        (("tyre_slip",), np.array([10.0, 0.3, 0.02])),
        (("parameters", "tyre_slip"), None),
        (("rider_lean",), None),
    ],
)
def test_the_perturbation_slopes_are_the_differences(tyred, effects, x):
    lay = tyred.layout(effects)
    assert tyred._perturbable(lay)
    if x is None:  # the structural sizes at their first start, every parameter shifted by half a sigma
        x = np.array(list(lay.starts[0]) + [0.5] * lay.n_shift, dtype=float)
        lower, upper = tyred.bounds(lay)
        x = np.clip(x, lower + 1e-3 * (upper - lower), upper - 1e-3 * (upper - lower))
    lay, perturbed, forward, central = _jacobians(tyred, effects, x)
    assert perturbed is not None and perturbed.shape == forward.shape
    scale = np.linalg.norm(central, axis=0) + 1e-12
    # both within a ten-thousandth of the central slopes (both first order in the step)
    error_perturbed = np.linalg.norm(perturbed - central, axis=0) / scale
    error_forward = np.linalg.norm(forward - central, axis=0) / scale
    assert np.all(error_forward < 1e-4), error_forward
    assert np.all(error_perturbed < 1e-4), error_perturbed


def test_four_states_a_speed_sensor_and_other_observations_keep_the_differences(davis, tyred):
    assert not tyred._perturbable(tyred.layout(("steer_damping",)))  # four states: the quartic is cheap
    assert not tyred._perturbable(tyred.layout(("parameters",)))
    assert not tyred._perturbable(tyred.layout(("tyre_slip", "speed_sensor")))  # the scale moves the speeds


def test_an_ill_conditioned_eigenvalue_falls_back_to_the_differences(tyred, monkeypatch):
    lay = tyred.layout(("tyre_slip",))
    x = np.array([10.0, 0.3, 0.02])
    _, upper = tyred.bounds(lay)
    mask = np.ones(len(tyred.obs), bool)
    steps = np.full(3, 1e-5)
    assert tyred._perturbation_jacobian(lay, mask, x, steps, upper, None) is not None
    monkeypatch.setattr(predict, "MAX_EIGEN_CONDITION", 0.0)  # every eigenvalue now counts as ill-conditioned
    assert tyred._perturbation_jacobian(lay, mask, x, steps, upper, None) is None
    # and the fit still runs (on the differences)
    fit = tyred.fit(("tyre_slip",))
    assert fit.success and fit.chi2 < 1e-3


def test_the_fit_is_the_fit_of_the_differences(tyred, monkeypatch):
    """The hidden tyre fitted with the perturbation slopes and with the differences: the same values, well
    within a hundredth of their standard errors."""
    calls = []
    derivatives = predict.Predictor.eigen_derivatives
    monkeypatch.setattr(predict.Predictor, "eigen_derivatives", lambda *a: calls.append(1) or derivatives(*a))
    fit = tyred.fit(("tyre_slip",))
    assert calls  # the slopes were the perturbation's
    monkeypatch.setattr(GapProblem, "_perturbable", lambda self, lay: False)
    tyred._memo.clear()
    reference = tyred.fit(("tyre_slip",))
    assert fit.chi2 == pytest.approx(reference.chi2, abs=1e-6)
    assert np.all(np.abs(fit.values - reference.values) <= 0.01 * reference.stderr + 1e-9)
    np.testing.assert_allclose(fit.stderr, reference.stderr, rtol=1e-3)
    truth = [TYRES["tyre_slip"][name] for name in ("c_alpha", "sigma_t", "t_p")]
    np.testing.assert_allclose(fit.values, truth, rtol=1e-3)
