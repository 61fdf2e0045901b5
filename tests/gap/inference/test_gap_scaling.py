"""The pieces that keep ``gap``'s cost linear in the data (the timings themselves: bench/bench_gap_scaling.py).

The gap test no longer forms the n x n covariance (:mod:`bikerider.gap.inference.low_rank`), the folds do not
grow with the number of groups, and the record fit's grid scan accumulates its normal equations in
blocks; each must give what the direct computation gives.
"""

from __future__ import annotations

import numpy as np
import pytest

from bikerider.gap.inference.low_rank import low_rank_chi2
from bikerider.gap.measured.control import ControlLaw
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData


def _table(speeds, groups, sigma=np.nan, seed=1) -> EigenvalueData:
    rng = np.random.default_rng(seed)
    n = len(speeds)
    speeds = np.asarray(speeds, float)
    value = (-0.3 * (speeds - 6) + 0.05 * rng.standard_normal(n)) + 1j * (2.5 + 0.05 * rng.standard_normal(n))
    law = ControlLaw.constant(np.zeros(4))
    return EigenvalueData(
        speeds,
        value,
        np.full(n, sigma),
        np.full(n, sigma),
        np.zeros(n),
        ["weave"] * n,
        list(groups),
        np.zeros((n, 4)),
        [f"t:{k}" for k in range(n)],
        [law.name] * n,
        {law.name: law},
    )


def test_low_rank_chi2_is_the_dense_quadratic_form():
    rng = np.random.default_rng(0)
    for _ in range(200):
        n, p = int(rng.integers(1, 30)), int(rng.integers(0, 8))
        J = rng.standard_normal((n, p))
        variance = rng.uniform(0.1, 2.0, n)
        r = rng.standard_normal(n)
        variance[: int(rng.integers(0, min(n, p) + 1))] = 0.0  # exact rows, at most the rank of J
        covariance = np.diag(variance) + J @ J.T
        chi2, dof = low_rank_chi2(r, variance, J)
        assert chi2 == pytest.approx(float(r @ np.linalg.solve(covariance, r)), rel=1e-8, abs=1e-10)
        assert dof == np.linalg.matrix_rank(covariance)


def test_low_rank_chi2_with_more_exact_rows_than_parameters():
    # The covariance is singular: residuals the parameters reproduce have a finite statistic on the
    # rank's degrees of freedom; any others an infinite one (r^T C^+ r on the support).
    rng = np.random.default_rng(1)
    J = rng.standard_normal((10, 3))
    variance = np.r_[np.zeros(6), np.ones(4)]
    shift = rng.standard_normal(3)
    inside = J @ shift + np.r_[np.zeros(6), rng.standard_normal(4)]
    chi2, dof = low_rank_chi2(inside, variance, J)
    covariance = np.diag(variance) + J @ J.T
    assert dof == 7 and chi2 == pytest.approx(float(inside @ np.linalg.pinv(covariance) @ inside), rel=1e-8)
    assert low_rank_chi2(inside + np.r_[1.0, np.zeros(9)], variance, J) == (np.inf, 7)


def test_a_table_taken_as_exact_gets_a_meaningful_gap_statistic(davis):
    # Found with 12 rows at distinct speeds and no uncertainties (no replicates): the dense solve of a
    # singular covariance gave chi2 = -1.8e17 and verdict "parameters".  24 exact observations cannot
    # all be met by shifts of 23 parameters: the gap is certain.
    from bikerider.gap.diagnosis.result import diagnose

    d = diagnose(davis, _table(np.linspace(4, 9, 12), ["g"] * 12), CanonicalData.empty(), ())
    assert d.gap_test["chi2"] == np.inf and d.gap_test["significant"] and d.verdict == "structural"
    assert d.gap_test["dof"] <= 24


def test_the_folds_do_not_grow_with_the_groups(davis):
    from bikerider.gap.diagnosis.folds import MAX_FOLDS
    from bikerider.gap.diagnosis.result import diagnose

    n = 3 * MAX_FOLDS + 1
    groups = [f"run{k:03d}" for k in range(n)]
    d = diagnose(davis, _table(np.linspace(4, 9, n), groups, sigma=0.05), CanonicalData.empty(), ())
    masks = np.array([held for _, held in d.folds])
    assert len(d.folds) == MAX_FOLDS
    assert np.all(masks.sum(axis=0) == 1)  # every observation held out exactly once
    obs_group = np.array(d.problem.obs.group)
    for held in masks:  # whole groups only
        inside = set(obs_group[held])
        assert not inside & set(obs_group[~held])
    few = diagnose(davis, _table(np.linspace(4, 9, 6), groups[:6], sigma=0.05), CanonicalData.empty(), ())
    assert [name for name, _ in few.folds] == [f"group {g}" for g in groups[:6]]


def test_the_scan_accumulated_in_blocks_is_the_scan_at_once(monkeypatch):
    from bikerider.gap.measured import extraction

    t = 0.3 + np.arange(1500) / 100.0
    y = 0.3 * np.exp(-0.8 * (t - 0.3)) * np.sin(4.5 * t) + 0.05 * np.exp(0.05 * t)
    y = y + 0.01 * np.random.default_rng(3).standard_normal(t.size)
    whole = extraction.scan_start(t, y)
    monkeypatch.setattr(extraction, "SCAN_CHUNK", 97)
    np.testing.assert_allclose(extraction.scan_start(t, y), whole, rtol=1e-9, atol=1e-12)
