"""The rider geometry's stated uncertainty, carried into the intervals of the candidates that use it."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from gap_support import decay_record

import bikerider
from bikerider.errors import InputError
from bikerider.gap.candidates.effect_model import GRIP_KEYS, UPPER_BODY_KEYS, EffectModel, RiderGeometry, geometry_keys
from bikerider.gap.diagnosis.fits import with_parameter_uncertainty
from bikerider.gap.diagnosis.result import diagnose
from bikerider.gap.inference.problem import GapProblem
from bikerider.gap.measured.records import fit_records
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
from bikerider.io.gap_model import load_model

DATA = Path(bikerider.__file__).parent / "data"
BP = DATA / "bicycleparameters"
EMPTY = CanonicalData([], np.empty(0), np.empty(0), [], {}, [])


def _weaves(model, effects, sigma=0.03, seed=3) -> EigenvalueData:
    """Noisy weave eigenvalues of a truth with ``effects`` (two uncontrolled groups, one controlled)."""
    rng = np.random.default_rng(seed)
    nominal = {k: float(model.parameters.values[k]) for k in model.parameters.values}
    speeds = np.concatenate([np.linspace(5.0, 9.0, 5), np.linspace(4.0, 7.5, 5)])
    gains = np.array([(0, 0, 0, 0)] * 5 + [(0, 5.0, -2.0, -0.5)] * 5, float)
    n = speeds.size
    eig = EigenvalueData(
        speeds,
        np.zeros(n, complex),
        np.full(n, sigma),
        np.full(n, sigma),
        np.zeros(n),
        ["weave"] * n,
        ["a"] * 5 + ["c"] * 5,
        gains,
        [f"synthetic:{k}" for k in range(n)],
    )
    problem = GapProblem(model, eig, EMPTY)
    weave = problem.predictor.eigenvalues(EffectModel(nominal, model.geometry, effects))
    eig.value = weave + sigma * (rng.standard_normal(n) + 1j * rng.standard_normal(n))
    return eig


def _known(model):
    """The same model with its geometry taken as known."""
    return replace(model, geometry=replace(model.geometry, uncertainty={}))


def test_the_default_geometry_states_its_uncertainty(davis):
    sources = davis.geometry.uncertainty
    assert {"grip height", "grip reach", "grip half-width", "hip axis height", "upper-body mass fraction"} <= set(
        sources
    )
    assert all(v != 0 for shift in sources.values() for v in shift.values())
    riderless = load_model(DATA / "gap" / "kooijman2008_bicycle.toml").geometry
    assert riderless.sources(UPPER_BODY_KEYS) == []  # no upper body: nothing of it is uncertain
    assert set(riderless.sources(GRIP_KEYS)) == {"grip height", "grip reach", "grip half-width"}
    assert geometry_keys(("steer_damping",)) == () and geometry_keys(("tyre_slip",)) == ()
    assert set(geometry_keys(("passive_arms",))) == set(GRIP_KEYS)
    assert set(geometry_keys(("rider_lean", "steer_damping"))) == set(UPPER_BODY_KEYS)


def test_shifted_geometry_and_impossible_shifts(davis):
    g = davis.geometry
    up = g.shifted("hip axis height", 1.0)
    assert up.upper_body["z_lean"] == pytest.approx(g.upper_body["z_lean"] + 0.05)
    assert up.grips == g.grips and g.upper_body["z_lean"] != up.upper_body["z_lean"]  # the original unchanged
    heavy = replace(g, uncertainty={"mass": {"m_u": 10 * g.upper_body["m_u"]}})
    with pytest.raises(InputError, match="upper_body"):
        heavy.shifted("mass", -1.0)
    with pytest.raises(InputError, match="uncertainty of odd"):
        RiderGeometry(g.upper_body, g.grips, "", {"odd": {"x_elbow": 0.1}})
    with pytest.raises(InputError, match="uncertainty of odd"):
        RiderGeometry(g.upper_body, g.grips, "", {"odd": {"z_grip": float("nan")}})


def test_the_geometry_share_is_zero_for_effects_that_do_not_use_it(davis):
    eig = _weaves(davis, {"steer_damping": {"c_steer": 0.3}})
    p, q = GapProblem(davis, eig, EMPTY), GapProblem(_known(davis), eig, EMPTY)
    assert p.geometry_sources(p.layout(("steer_damping",))) == []
    a = with_parameter_uncertainty(p, p.fit(("steer_damping",)))
    b = with_parameter_uncertainty(q, q.fit(("steer_damping",)))
    np.testing.assert_array_equal(a.covariance, b.covariance)
    riderless = load_model(DATA / "gap" / "kooijman2008_bicycle.toml")
    r = GapProblem(riderless, _weaves(riderless, {"steer_damping": {"c_steer": 0.3}}), EMPTY)
    assert all(r.geometry_sources(r.layout((e,))) == [] for e in ("steer_damping", "steer_inertia", "tyre_slip"))


@pytest.mark.parametrize(
    "effect, truth",
    [
        ("passive_arms", {"m_arm": 1.5, "k_arm": 2.0, "c_arm": 1.5}),
        ("rider_lean", {"k_lean": 120.0, "c_lean": 30.0}),
    ],
)
def test_the_geometry_widens_the_rider_effects_intervals(davis, effect, truth):
    eig = _weaves(davis, {effect: truth})
    p, q = GapProblem(davis, eig, EMPTY), GapProblem(_known(davis), eig, EMPTY)
    lay = p.layout((effect,))
    fit = p.fit((effect,))
    before = p.predict_batch(lay, fit.values[None])
    Jg = p.geometry_jacobian(lay, fit.values)
    assert Jg.shape == (len(p.obs), len(p.geometry_sources(lay))) and Jg.shape[1] >= 3
    assert np.all(np.isfinite(Jg)) and np.all(np.abs(Jg).max(axis=0) > 0)
    # predicting with a shifted geometry changed nothing of the problem: same geometry, same predictions
    assert p.geometry is davis.geometry
    np.testing.assert_array_equal(p.predict_batch(lay, fit.values[None]), before)
    with_geometry = with_parameter_uncertainty(p, fit)
    without = with_parameter_uncertainty(q, q.fit((effect,)))
    np.testing.assert_allclose(with_geometry.values, without.values)
    share = np.diag(with_geometry.covariance) - np.diag(without.covariance)
    assert np.all(share > 0)
    assert np.all(with_geometry.ci_high - with_geometry.ci_low >= without.ci_high - without.ci_low)


def _write(tmp_path, text: str) -> Path:
    path = tmp_path / "model.toml"
    path.write_text((DATA / "gap" / "kooijman2008_bicycle.toml").read_text() + text)
    return path


RIDER = "\n[rider]\nmass = 6.0\nx = 0.3\nz = -0.9\nIxx = 0.5\nIxz = 0.1\nIzz = 0.3\n"  # inside the 12 kg rear body
UPPER = (
    '\n[upper_body]\nm_u = 35.0\nx_u = 0.3\nz_u = -1.4\nIUxx = 1.7\nIUxz = 0.0\nIUzz = 0.8\nz_lean = "-1.1 +/- 0.03"\n'
)


def test_a_model_files_geometry_takes_value_plus_minus_sigma(tmp_path):
    model = load_model(
        _write(tmp_path, RIDER + UPPER + '\n[grips]\nx_grip = 0.85\nz_grip = "-1.0 +/- 0.02"\nb_grip = 0.3\n')
    )
    g = model.geometry
    assert g.upper_body["z_lean"] == -1.1 and g.grips["z_grip"] == -1.0
    # the file's values replace the default's sources: one per value given with a sigma, the others known
    assert g.uncertainty == {"upper_body.z_lean": {"z_lean": 0.03}, "grips.z_grip": {"z_grip": 0.02}}
    only_upper = load_model(_write(tmp_path, RIDER + UPPER)).geometry
    assert "grip height" in only_upper.uncertainty and "hip axis height" not in only_upper.uncertainty


def test_a_negative_geometry_sigma_is_refused_naming_the_field(tmp_path):
    with pytest.raises(InputError, match="upper_body.z_lean"):
        load_model(_write(tmp_path, RIDER + UPPER.replace("0.03", "-0.03")))


def test_records_are_predicted_with_the_shifted_geometry_by_indirect_inference(davis):
    # a rider with stiff arms, decays at four speeds: the geometry's slopes come from the records'
    # apparent eigenvalues under the shifted geometry, and the problem's own simulator is left as it was
    arms = {"passive_arms": {"m_arm": 1.5, "k_arm": 2.0, "c_arm": 1.5}}
    records = [decay_record(davis, v, f"{v} m/s", arms, seed=k, duration=2.5) for v in (4.0, 5.0, 6.0) for k in (0, 1)]
    d = diagnose(davis, EigenvalueData.empty(), CanonicalData.empty(), effects=(), records=fit_records(records))
    p = d.problem
    assert p.records is not None and len(p.record_obs)
    lay = p.layout(("passive_arms",))
    x = np.array([1.5, 2.0, 1.5])
    simulator, known = p.records.simulator, dict(p.records.simulator.known)
    Jg = p.geometry_jacobian(lay, x)
    rows = p.record_obs.ravel()
    assert np.all(np.isfinite(Jg)) and np.all(np.abs(Jg[rows]).max(axis=0) > 0)
    assert p.records.simulator is simulator and simulator.geometry is davis.geometry
    assert simulator.known.keys() == known.keys()
    # the apparent eigenvalues' secant differs from the weave eigenvalues' (a short record's fit)
    weave = p.geometry_jacobian(lay, x, indirect=False)
    assert not np.allclose(Jg[rows], weave[rows])


def test_a_step_to_an_impossible_geometry_takes_the_one_sided_secant(davis):
    # one sigma of the upper body's mass below would leave it negative: the secant from the fit's own geometry
    m_u = davis.geometry.upper_body["m_u"]
    wide = replace(davis, geometry=replace(davis.geometry, uncertainty={"mass": {"m_u": 2 * m_u}}))
    p = GapProblem(wide, _weaves(davis, {"rider_lean": {"k_lean": 120.0, "c_lean": 30.0}}), EMPTY)
    lay = p.layout(("rider_lean",))
    x = np.array([120.0, 30.0])
    J = p.geometry_jacobian(lay, x)[:, 0]
    up = p.with_geometry(p.geometry.shifted("mass", 1.0)).predict_batch(lay, x[None])[0]
    np.testing.assert_allclose(J, up - p.predict_batch(lay, x[None])[0])
    assert np.max(np.abs(J)) > 0
