"""Issue 21, part 4: steer friction's 95 % interval counts the benchmark parameters' uncertainty.

The friction fit's standard errors came from a jackknife over the held-out folds alone; every fold
shares the parameters' error, so the folds agreed with each other on a biased value (calibration seed
1000: T_coulomb 0.046 [0.042, 0.049] N m for a truth of 0.066, the fit with the truth's parameters
0.062) and the interval excluded the truth.
"""

from __future__ import annotations

import numpy as np
import pytest
from gap_support import friction_decay_record, nominal, riderless_model

from bikerider.gap import parallel
from bikerider.gap.diagnosis.result import FEW_FOLDS_FRICTION, as_dict, diagnose
from bikerider.gap.diagnosis.statistics import interval_quantile, jackknife_quantile
from bikerider.gap.inference.timedomain import (
    Layout,
    corner_nodes,
    corner_share,
    fit_covariance,
    fit_time_domain,
    parameter_sensitivity,
)
from bikerider.gap.measured.records import Record, fit_records
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData

T_TRUE, C_TRUE = 0.08, 0.1
"""The friction of the simulated bicycle: Coulomb [N m] and viscous [N m s/rad]."""
FRICTION = Layout.of(("steer_friction",))


def _friction_record(values, geometry, speed, group, seed, noise=0.01) -> Record:
    """A decay of the bicycle with :data:`T_TRUE` and :data:`C_TRUE` (``gap_support.friction_decay_record``)."""
    return friction_decay_record(values, geometry, speed, group, seed, T_TRUE, C_TRUE, noise)


@pytest.fixture(scope="module")
def riderless():
    return riderless_model()


def _records(model, values):
    return [_friction_record(values, model.geometry, v, f"{v} m/s", seed=k) for v in (2.5, 3.5, 4.5) for k in range(2)]


def test_the_sensitivity_is_how_far_the_fit_moves_with_a_parameter(riderless):
    # the fit refitted with one benchmark parameter moved by its standard uncertainty moves as the
    # Gauss-Newton sensitivity says
    values = nominal(riderless)
    records = _records(riderless, values)
    fit = fit_time_domain(records, values, riderless.geometry, FRICTION)
    sigmas = {k: s for k, s in riderless.parameters.sigmas.items() if s > 0 and k in values}
    G = parameter_sensitivity(records, values, riderless.geometry, FRICTION, fit.values, sigmas)
    assert G.shape == (2, len(sigmas))
    k = int(np.argmax(np.abs(G[1])))  # the parameter that moves the viscous part most
    name = list(sigmas)[k]
    moved = fit_time_domain(
        records, {**values, name: values[name] + sigmas[name]}, riderless.geometry, FRICTION, start=fit.values
    )
    assert np.all(np.abs(G[:, k]) > 0.002)  # one standard uncertainty moves the fit by a few per cent
    # the refit stops within its own tolerance (xtol 1e-3) along the valley where Coulomb and viscous
    # friction trade off, and one standard uncertainty is not infinitesimal: a third of the change
    assert moved.values - fit.values == pytest.approx(G[:, k], rel=0.35)


def test_the_interval_covers_a_truth_the_folds_all_miss_alike(riderless):
    # records of a bicycle whose parameters are off by 1.5 standard deviations of their joint effect on
    # the Coulomb level (along its sensitivity): every fold is fitted off the truth alike, so the
    # jackknife alone is narrow and misses it; with the parameters' share counted, the interval covers it
    values = nominal(riderless)
    sigmas = {k: s for k, s in riderless.parameters.sigmas.items() if s > 0 and k in values}
    probe = _records(riderless, values)
    fit = fit_time_domain(probe, values, riderless.geometry, FRICTION)
    G = parameter_sensitivity(probe, values, riderless.geometry, FRICTION, fit.values, sigmas)
    shift = 1.5 * G[0] / np.linalg.norm(G[0])  # in standard uncertainties: the fit's level moves by -1.5 sd
    truth_values = {**values, **{k: values[k] + u * sigmas[k] for k, u in zip(sigmas, shift)}}
    records = fit_records(_records(riderless, truth_values))
    d = diagnose(riderless, EigenvalueData.empty(), CanonicalData.empty(), effects=("steer_friction",), records=records)
    full = d.fits.fit_of(("steer_friction",))
    spread = full.jackknife_covariance
    assert spread is not None and full.covariance is not None
    g = len(d.folds)
    jackknife_only = np.sqrt(spread[0, 0]) * jackknife_quantile(g)
    assert abs(full.values[0] - T_TRUE) > jackknife_only  # the folds' spread alone misses the truth
    assert full.ci_low[0] <= T_TRUE <= full.ci_high[0]
    # the parameters' share is the fit's response to their uncertainty, added to the folds' spread
    parameters = full.covariance - spread
    assert parameters[0, 0] > 4 * spread[0, 0]


def test_the_quantile_of_a_sum_of_a_jackknife_and_a_known_variance():
    # Welch-Satterthwaite: the jackknife's share alone has one degree of freedom fewer than the folds,
    # a known share alone is normal, and a sum lies between
    g = np.array([1.0])
    assert interval_quantile(g, [[1.0]], [[1.0]], 3) == pytest.approx(jackknife_quantile(3))
    assert interval_quantile(g, [[1.0]], [[0.0]], 3) == pytest.approx(1.96, abs=1e-9)
    assert interval_quantile(g, [[1.0]], None, 3) == pytest.approx(1.96, abs=1e-9)
    mixed = interval_quantile(g, [[4.0]], [[1.0]], 3)  # dof 2 * 16 = 32
    assert 1.96 < mixed < jackknife_quantile(3)
    assert mixed == pytest.approx(2.037, abs=2e-3)


def _diagnosis(model, values, speeds):
    records = fit_records(
        [_friction_record(values, model.geometry, v, f"{v} m/s", seed=k) for v in speeds for k in range(2)]
    )
    return diagnose(model, EigenvalueData.empty(), CanonicalData.empty(), effects=("steer_friction",), records=records)


def test_two_sessions_get_the_fits_own_covariance(riderless):
    # issue 25's closed loop: with two sessions there is no jackknife, and the standard errors were
    # infinite, the interval the whole search range; the fit's own Gauss-Newton covariance sizes it
    values = nominal(riderless)
    d = _diagnosis(riderless, values, (2.5, 4.5))
    assert len(d.folds) == 2
    full = d.fits.fit_of(("steer_friction",))
    assert np.all(np.isfinite(full.stderr)) and full.jackknife_covariance is None
    span = np.asarray(full.upper) - np.asarray(full.lower)
    assert np.all(full.ci_high - full.ci_low < 0.05 * span)
    assert full.ci_low[0] <= T_TRUE <= full.ci_high[0]
    assert full.ci_low[1] <= C_TRUE <= full.ci_high[1]
    # the data's share is s^2 (J^T J)^-1, the parameters' share added as with a jackknife
    records = [r.record for r in d.fits.records]
    own = fit_covariance(records, values, riderless.geometry, FRICTION, full.values)
    assert own.reduced_chi2 < 1  # the weights are the signals' scatter, not their noise: scaled down
    # and the friction corner's (refits at the corners the data do not decide)
    assert [e for e, _, _ in full.corners] == list(corner_nodes()[0])
    share = corner_share(records, values, riderless.geometry, FRICTION, full.values)
    assert full.corner_covariance == pytest.approx(share.covariance)
    assert full.covariance - own.covariance - full.corner_covariance == pytest.approx(
        d.fits.parameter_covariance(FRICTION, full.values)
    )
    # each corner's fit within the data's and the parameters' shares, mixed over the corner's range
    # (CornerShare.interval); Welch-Satterthwaite with hundreds of degrees of freedom for the data's
    # share: about the normal 1.96
    base = own.covariance + d.fits.parameter_covariance(FRICTION, full.values)
    for k in range(full.values.size):
        quantile = interval_quantile(np.eye(full.values.size)[k], base, own.covariance, own.dof + 1)
        assert 1.959 < quantile < 1.97
        half = quantile * np.sqrt(base[k, k])
        expected = share.interval(k, half, full.lower[k], full.upper[k])
        assert (full.ci_low[k], full.ci_high[k]) == pytest.approx(expected, rel=1e-9)
        assert full.ci_low[k] < full.values[k] < full.ci_high[k]
    # the interval does not see the scatter from session to session: the output says so
    assert FEW_FOLDS_FRICTION in as_dict(d)["notes"]


def test_the_fits_own_covariance_is_the_scatter_of_its_values(riderless):
    # two-session sets of simulated decays with white noise (nominal parameters): the fits' error over
    # their own standard error has unit scatter (0.93 and 1.01 over 12 sets; 6 here, for time)
    values = nominal(riderless)
    z = []
    for s in range(6):
        records = [
            _friction_record(values, riderless.geometry, v, f"{v} m/s", seed=k)
            for v in (2.5, 4.5)
            for k in (2 * s, 2 * s + 1)
        ]
        fit = fit_time_domain(records, values, riderless.geometry, FRICTION)
        own = fit_covariance(records, values, riderless.geometry, FRICTION, fit.values)
        z.append((fit.values - [T_TRUE, C_TRUE]) / np.sqrt(np.diag(own.covariance)))
    rms_z = np.sqrt(np.mean(np.square(z), axis=0))
    assert np.all((rms_z > 0.5) & (rms_z < 1.6))  # not the unscaled (J^T J)^-1: that gives about 0.03


def test_three_sessions_keep_the_jackknife(riderless):
    # a calibration study runs on this path: three sessions or more keep the jackknife over the folds
    # plus the parameters' share, and the numbers of main at b2e4f82 (before the two-session fallback), as
    # moved since by the safeguarded chord steps on the records' initial states (standard errors 0.00881,
    # 0.00751 before; the fitted values' own move is within 1 %) and by the Gauss-Newton steps that replaced
    # them (timedomain.STATE_STEPS: 0.008979, 0.007492 with the chord steps, 0.3 % and 0.02 %), and by
    # the held-state slopes (timedomain._held_changes: 0.008954, 0.007493 with the refitted differences,
    # -0.7 % and +1.4 %: the parameters' share, whose slopes they are)
    values = nominal(riderless)
    d = _diagnosis(riderless, values, (2.5, 3.5, 4.5))
    assert len(d.folds) == 3
    full = d.fits.fit_of(("steer_friction",))
    folds = np.array([f.values for f in d.fits.cross_validate(("steer_friction",)).fits])
    centred = folds - folds.mean(axis=0)
    spread = 2 / 3 * centred.T @ centred
    assert full.jackknife_covariance == pytest.approx(spread, rel=1e-12)
    # plus the friction corner's share, known from the model as the parameters' is
    corners = full.corner_covariance
    assert full.covariance == pytest.approx(
        spread + d.fits.parameter_covariance(FRICTION, full.values) + corners, rel=1e-12
    )
    # decays of 0.5 rad/s steer rate, ten corners: the corner moves the fit by a few per cent of its interval
    assert np.all(np.diag(corners) > 0) and np.all(np.diag(corners) < 0.01 * np.diag(full.covariance))
    assert np.sqrt(np.diag(full.covariance - corners)) == pytest.approx(
        [0.008888608263989586, 0.0075982162229898485], rel=1e-4
    )
    # the interval without the corner's share (recomputed with the corner's share set to zero after the
    # held-state slopes: they were [0.06061, 0.08738], [0.09571, 0.11675] with the refitted differences) ...
    before_low, before_high = [0.060740901438725514, 0.08716745226817182], [0.09558569050403598, 0.11695359614149436]
    # ... now each corner's within the jackknife's and the parameters' shares, mixed over the corner's range
    # (CornerShare.interval): for these decays (0.5 rad/s steer rate, ten corners) within 1 % of it
    base = spread + d.fits.parameter_covariance(FRICTION, full.values)
    share = d.fits.corner_share(("steer_friction",), full.values)
    for k in range(full.values.size):
        half = interval_quantile(np.eye(2)[k], base, spread, 3) * np.sqrt(base[k, k])
        expected = share.interval(k, half, full.lower[k], full.upper[k])
        assert (full.ci_low[k], full.ci_high[k]) == pytest.approx(expected, rel=1e-9)
    assert full.ci_low == pytest.approx(before_low, rel=1e-2)
    assert full.ci_high == pytest.approx(before_high, rel=1e-2)
    assert FEW_FOLDS_FRICTION not in as_dict(d)["notes"]


def test_the_corners_worked_out_on_workers_are_those_of_one_process(riderless, monkeypatch):
    # the friction corner's refits run on the worker that cross-validates the candidate; the parent takes
    # them over and does not refit
    values = nominal(riderless)
    out = {}
    for count in ("1", "2"):
        monkeypatch.setenv(parallel.WORKERS_ENV, count)
        d = _diagnosis(riderless, values, (2.5, 3.5, 4.5))
        full = d.fits.fit_of(("steer_friction",))
        out[count] = (full.values, full.covariance, full.corner_covariance, len(d.fits.corner_shares))
    assert np.array_equal(out["1"][0], out["2"][0])
    assert np.array_equal(out["1"][1], out["2"][1]) and np.array_equal(out["1"][2], out["2"][2])
    assert out["1"][3] == out["2"][3] == 1
