"""The speed work's helpers: worker processes give the same results, the tail probabilities are
scipy.stats's, the BLAS thread limit is undone after its block."""

from __future__ import annotations

import os
import sys
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from bikerider.errors import InputError
from bikerider.gap import blas_threads, distributions, parallel
from bikerider.gap.diagnosis.result import diagnose
from bikerider.gap.measured.records import fit_records
from bikerider.io.gap_data import read_eigenvalues, read_perturbation
from bikerider.io.gap_model import load_model


def test_map_forked_gives_the_results_of_a_plain_map_in_order(monkeypatch):
    monkeypatch.setenv(parallel.WORKERS_ENV, "2")
    scale = np.array([1.0, 2.0, 3.0])  # a closure over an array: the workers are forked, nothing to pickle
    items = list(range(7))
    assert [a.tolist() for a in parallel.map_forked(lambda k: scale * k, items)] == [
        (scale * k).tolist() for k in items
    ]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="worker processes are forked on Linux only")
def test_workers_are_other_processes_unless_one_is_asked_for(monkeypatch):
    monkeypatch.setenv(parallel.WORKERS_ENV, "2")
    assert set(parallel.map_forked(lambda _: os.getpid(), range(4))) != {os.getpid()}
    monkeypatch.setenv(parallel.WORKERS_ENV, "1")
    assert set(parallel.map_forked(lambda _: os.getpid(), range(4))) == {os.getpid()}


@pytest.mark.parametrize("value", ["0", "two", "-3"])
def test_a_bad_worker_count_is_named(monkeypatch, value):
    monkeypatch.setenv(parallel.WORKERS_ENV, value)
    with pytest.raises(InputError, match=parallel.WORKERS_ENV):
        parallel.workers()


def test_tail_probabilities_are_scipy_stats_values():
    x = np.array([0.0, 0.3, 2.0, 11.0, 130.0])
    for k in (1, 4, 25, 118):
        assert np.array_equal(distributions.chi2.sf(x, k), stats.chi2.sf(x, k))
        assert distributions.chi2.ppf(0.95, k) == stats.chi2.ppf(0.95, k)
    assert np.array_equal(distributions.f.sf(x, 1, 300), stats.f.sf(x, 1, 300))
    assert distributions.chi2.sf(-1.0, 3) == 1.0  # below the support, as scipy.stats


def test_the_blas_thread_limit_holds_inside_its_block_and_is_undone_after():
    controls = blas_threads._controls()
    if not controls:
        pytest.skip("no OpenBLAS library found in this process")
    before = [get() for get, _ in controls]
    with blas_threads.one_blas_thread():
        assert [get() for get, _ in controls] == [1] * len(controls)
    assert [get() for get, _ in controls] == before


def test_the_diagnosis_on_worker_processes_equals_the_one_in_one_process(monkeypatch):
    data = Path(str(resources.files("bikerider") / "data"))
    bp, examples = data / "bicycleparameters", data / "gap_examples"
    model = load_model(
        bp / "bicycles/Rigid/Parameters/RigidBenchmark.txt", bp / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
    )
    out = {}
    for count in ("1", "2"):
        monkeypatch.setenv(parallel.WORKERS_ENV, count)
        run = fit_records([read_perturbation(examples / "perturbation_run.csv")])
        result = diagnose(
            model,
            read_eigenvalues(examples / "eigenvalues.csv"),
            effects=("steer_damping", "steer_inertia"),
            records=run,
        ).as_dict()
        result.pop("elapsed_s")
        out[count] = result
    assert out["1"] == out["2"]
    assert out["1"]["selected"] == ["steer_damping"]


class _FakeFits:
    """What :func:`parallel.cross_validate_all` uses of a diagnosis's fits: a set's result names the process
    that made it and the single fits it found in its caches."""

    def __init__(self):
        self.cv, self.full, self.bias_corrected, self.time_domain_full, self.corner_shares = {}, {}, {}, {}, {}
        self.record_rows = {0: 0}
        self.problem = type("P", (), {"obs": []})()

    def cross_validate(self, effects):
        from types import SimpleNamespace

        if len(effects) == 1:
            self.full[effects] = f"fit of {effects[0]}"
        seen = sorted(k[0] for k in self.full if len(k) == 1 and k[0] in effects)
        self.cv[effects] = SimpleNamespace(folds=[1, 2], pid=os.getpid(), singles_seen=seen)
        return self.cv[effects]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="worker processes are forked on Linux only")
def test_sets_found_while_the_candidates_run_are_done_on_the_same_workers_with_their_singles(monkeypatch):
    """The pairs of two candidates done start on a free worker before the candidates' stage ends, each
    handed its singles' fits (the worker need not fit them again)."""
    monkeypatch.setenv(parallel.WORKERS_ENV, "2")
    fits = _FakeFits()
    singles = [("a",), ("b",), ("c",)]

    def ready():
        done = [e for (e,) in singles if (e,) in fits.cv]
        return [(x, y) for i, x in enumerate(done) for y in done[i + 1 :]]

    parallel.cross_validate_all(fits, singles, then=ready)
    assert set(fits.cv) == {("a",), ("b",), ("c",), ("a", "b"), ("a", "c"), ("b", "c")}
    assert {fits.cv[s].pid for s in fits.cv} != {os.getpid()}
    for pair in [("a", "b"), ("a", "c"), ("b", "c")]:
        assert fits.cv[pair].singles_seen == list(pair)  # given by the parent, not fitted on the worker
    assert fits.full[("a",)] == "fit of a"
