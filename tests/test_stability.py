"""Stable speed intervals, crossings and critical speeds against dense eigenvalue scans, and the
batched analysis against the one-bicycle analysis (the audit itself: test_stability_audit.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from random_bicycles import batched_model, benchmark_values
from test_stability_audit import GRID, STEP, _unstable_count

from bikerider.benchmark import BenchmarkParameters, WhippleModel
from bikerider.benchmark.stability import stability, stability_batch


@pytest.mark.slow
def test_every_stable_interval_agrees_with_the_dense_scan(random_models, random_scan):
    for model, stable in zip(random_models, random_scan):
        result = model.stability()
        ours = result.is_stable(GRID)
        bounds = np.array([b for i in result.intervals for b in (i.lower, i.upper)] + [np.inf])
        disagree = np.flatnonzero(ours != stable)
        # only at grid points within one step of an interval end (the end lies between them)
        near = np.abs(GRID[disagree, None] - bounds[None, :]).min(axis=1) <= STEP
        assert near.all(), (result, GRID[disagree[~near]])
        for interval in result.intervals:  # stable at speeds above the scan where it says so
            if math.isinf(interval.upper):
                assert _unstable_count(model, [max(interval.lower * 2, 30.0), 300.0]).max() == 0


def test_crossings_change_the_number_of_unstable_eigenvalues_as_they_say(random_models):
    counted = 0
    for model in random_models[:600]:
        for crossing in model.stability().crossings:
            eps = 1e-6 * crossing.speed
            below, above = _unstable_count(model, [crossing.speed - eps, crossing.speed + eps])
            step = 1 if crossing.kind == "real" else 2
            assert above - below == (-step if crossing.stabilising else step), crossing
            if crossing.kind == "oscillatory":  # the pair is at +/- i frequency there
                values = np.linalg.eigvals(model.state_matrix(crossing.speed))
                assert np.abs(np.abs(values.imag) - crossing.frequency).min() < 1e-6 * crossing.frequency
            counted += 1
    assert counted > 800


def _random_matrix_models(n: int, seed: int) -> list[WhippleModel]:
    """Canonical matrices perturbed entry by entry (30 % of them give several stable intervals or odd
    crossings that physical parameter sets rarely do)."""
    base = WhippleModel.from_parameters(BenchmarkParameters.from_mapping(benchmark_values()))
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        mats = [m * (1 + 0.6 * rng.standard_normal(m.shape)) for m in (base.M, base.C1, base.K0, base.K2)]
        mats[0] = (mats[0] + mats[0].T) / 2
        if np.linalg.eigvalsh(mats[0]).min() > 0:
            out.append(WhippleModel(*mats))
    return out


def test_several_stable_intervals_agree_with_the_scan():
    # Entry-wise random matrices give bicycles stable in two separate speed ranges (about 1 in 500).
    found = 0
    grid = np.linspace(0.0, 40.0, 2001)
    for model in _random_matrix_models(6000, seed=3):
        result = model.stability()
        if len(result.intervals) < 2:
            continue
        found += 1
        stable = (np.linalg.eigvals(model.state_matrix(grid)).real < 0).all(axis=-1)
        bounds = np.array([b for i in result.intervals for b in (i.lower, i.upper)])
        disagree = np.flatnonzero(result.is_stable(grid) != stable)
        assert (np.abs(grid[disagree, None] - bounds[None, :]).min(axis=1) <= grid[1]).all()
        first = result.intervals[0]
        speeds = model.critical_speeds()
        assert speeds.stable_range == (first.lower, first.upper)
        assert len(speeds.stable_intervals) == len(result.intervals)
    assert found >= 3


def test_batched_stability_equals_one_at_a_time(random_models):
    models = random_models[:800] + _random_matrix_models(400, seed=5)
    batch = stability_batch(batched_model(models).entries(), 9.81)
    for i, model in enumerate(models):
        one = stability({k: float(v) for k, v in model.entries().items()}, model.g)
        lower = batch.lower[i][np.isfinite(batch.lower[i])]
        assert lower.size == len(one.intervals)
        for k, interval in enumerate(one.intervals):
            assert batch.lower[i, k] == pytest.approx(interval.lower, rel=1e-12)
            assert batch.upper[i, k] == pytest.approx(interval.upper, rel=1e-12)
            for kind, crossing in (
                (batch.lower_kind[i, k], interval.lower_crossing),
                (batch.upper_kind[i, k], interval.upper_crossing),
            ):
                assert kind == {None: 0, "real": 1, "oscillatory": 2}[crossing.kind if crossing else None]
        for got, want in (
            (batch.weave[i], one.weave),
            (batch.capsize[i], one.capsize),
            (batch.weave_frequency[i], one.weave_frequency),
        ):
            assert (np.isnan(got) and want is None) or got == pytest.approx(want, rel=1e-12)


def test_benchmark_bicycle_is_stable_between_its_published_speeds():
    # Meijaard et al. (2007), Table 2: v_w = 4.292382 m/s, v_c = 6.024262 m/s
    model = WhippleModel.from_parameters(BenchmarkParameters.from_mapping(benchmark_values()))
    result = model.stability()
    (interval,) = result.intervals
    assert interval.lower == pytest.approx(4.292382, abs=1e-6) and interval.upper == pytest.approx(6.024262, abs=1e-6)
    assert interval.lower_crossing.kind == "oscillatory" and interval.lower_crossing.stabilising
    assert interval.upper_crossing.kind == "real" and not interval.upper_crossing.stabilising
    assert [c.speed for c in result.crossings] == [interval.lower, interval.upper]


def test_a_batched_model_asks_for_the_batched_stability():
    model = batched_model([WhippleModel.from_parameters(BenchmarkParameters.from_mapping(benchmark_values()))] * 2)
    with pytest.raises(Exception, match="stability_batch"):
        model.critical_speeds()
