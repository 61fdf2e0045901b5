"""Records as labs write them: each kind of damage repaired on purpose, said, and the fit unchanged.

A synthetic free decay (a damped weave, a slow mode, white noise) is fitted clean and after each
damage a logger does: jittered stamps, dropped samples, repeated rows, a clock reset, missing
values, a saturated gyro, a constant bias.  The repaired record's eigenvalue must agree with the
clean one within its standard errors, and the repair must say what it did.  The shipped
steer-by-wire logs, damaged the same ways (``tests/sbw_damage.py``, seeded), must give the same
record fits, and the same verdict and selection.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sbw_damage import ROLL_RATE_BIAS, damaged_copy

import bikerider
from bikerider.gap.measured.control import NO_CONTROL
from bikerider.gap.measured.records import Record, fit_record, fit_records
from bikerider.gap.measured.repair import repair_record, repair_tags
from bikerider.io.experiment import load_records, read_experiment

SBW = Path(bikerider.__file__).parent / "data" / "gap" / "pasma2024_sbw"
WEAVE = complex(-2.5, 7.5)  # [1/s]
NOISE = 0.01  # [rad/s]


def _decay(time: np.ndarray, rng) -> np.ndarray:
    tau = time - time[0]
    clean = 0.6 * np.exp(WEAVE.real * tau) * np.sin(WEAVE.imag * tau + 0.3) + 0.05 * np.exp(-0.4 * tau)
    return clean + NOISE * rng.standard_normal(time.size)


def _record(time, rate, name="run") -> Record:
    tau = np.nan_to_num(np.asarray(time, float) - (time[0] if len(time) else 0.0))
    steer = 0.1 * np.exp(WEAVE.real * tau) * np.cos(WEAVE.imag * tau)
    return Record(
        name, name, np.asarray(time, float), {"roll_rate": rate, "steer_angle": steer}, 4.0, 0.0, "g", NO_CONTROL, 4.0
    )


@pytest.fixture
def clean():
    rng = np.random.default_rng(3)
    t = np.arange(250) * 0.01
    return t, _decay(t, rng)


def _agree(a, b, k=1.0):
    """Two record fits agree within ``k`` of the clean fit's standard errors."""
    ea, eb = a.estimate, b.estimate
    assert eb is not None, b.reason
    assert abs(ea.eigenvalue.real - eb.eigenvalue.real) < k * ea.real_sigma
    assert abs(ea.eigenvalue.imag - eb.eigenvalue.imag) < k * ea.imag_sigma


def test_a_clean_record_is_left_as_it_is(clean):
    record = _record(*clean)
    out, repair = repair_record(record)
    assert out is record and not repair.repaired and repair.problem is None


def test_jittered_stamps_are_resampled_with_an_error_bound(clean):
    t, y = clean
    rng = np.random.default_rng(4)
    stamps = t + rng.uniform(-0.05, 0.05, t.size) * 0.01  # the true instants of the samples, jittered by 5 %
    truth = _record(stamps, _decay(stamps, np.random.default_rng(3)))
    fit = fit_record(truth)
    assert fit.used and fit.record.repairs
    text = "; ".join(fit.record.repairs)
    assert "resampled to 10 ms by linear interpolation" in text and "error at most" in text
    assert np.allclose(np.diff(fit.record.time), 0.01)
    assert fit.record.raw is not None and fit.record.raw[0].size == t.size  # the samples as recorded, kept
    _agree(fit_record(_record(*clean)), fit)
    _, repair = repair_record(truth)
    assert repair.resampled and repair.bound["roll_rate"] < NOISE  # the bound is below the noise


def test_dropped_repeated_and_out_of_order_samples(clean):
    t, y = clean
    rng = np.random.default_rng(5)
    keep = np.sort(np.concatenate([[0], rng.choice(np.arange(1, t.size), int(0.95 * (t.size - 1)), replace=False)]))
    tt, yy = t[keep], y[keep]
    dup = [10, 40, 90]
    tt, yy = np.insert(tt, dup, tt[dup]), np.insert(yy, dup, yy[dup])  # repeated rows
    tt[120], tt[121] = tt[121], tt[120]  # two samples logged out of order
    fit = fit_record(_record(tt, yy))
    text = "; ".join(fit.record.repairs)
    assert "duplicate or non-increasing stamp dropped (3 repeated stamps)" in text
    assert "resampled" in text
    _agree(fit_record(_record(*clean)), fit)


def test_a_clock_reset_is_undone(clean):
    t, y = clean
    stamps = t.copy()
    stamps[100:] -= 250.0  # the logger's clock restarts (a new session counter)
    fit = fit_record(_record(stamps, y))
    assert any("clock reset after sample 100" in a for a in fit.record.repairs)
    assert np.allclose(fit.record.time, t)  # continues at the median step
    assert np.allclose(fit.record.raw[0], t)  # the samples as recorded, drawn on the same time axis
    _agree(fit_record(_record(*clean)), fit, k=1e-6)  # the very same samples


def test_missing_values_short_gap_bridged_long_gap_cut(clean):
    t, y = clean
    short = y.copy()
    short[60:62] = np.nan
    fit = fit_record(_record(t, short))
    text = "; ".join(fit.record.repairs)
    assert "2 missing roll_rate samples dropped (first at 0.600 s)" in text and "cut at" not in text
    _agree(fit_record(_record(*clean)), fit)
    long = y.copy()
    long[60:90] = np.nan  # 0.3 s: linear interpolation over it would err far more than the noise
    fit = fit_record(_record(t, long))
    text = "; ".join(fit.record.repairs)
    assert "cut at 1 gap too long to interpolate" in text and "kept 0.900-2.490 s" in text
    assert fit.record.time[-1] == pytest.approx(1.59, abs=1e-9)


def test_a_saturated_gyro_is_dropped_not_fitted(clean):
    t, y = clean
    rail = 0.9 * float(np.max(y))
    clipped = np.minimum(y, rail)
    fit = fit_record(_record(t, clipped))
    assert fit.used
    assert "clipped" in repair_tags(fit.record.repairs)
    assert any(f"clipped roll_rate samples dropped (at {rail:.4g}" in a for a in fit.record.repairs)
    _agree(fit_record(_record(*clean)), fit, k=1.5)


def test_a_constant_bias_changes_nothing_but_the_offset(clean):
    t, y = clean
    a, b = fit_record(_record(t, y)), fit_record(_record(t, y + 0.05))
    assert not b.record.repairs
    _agree(a, b, k=1e-3)


def test_a_record_the_repairs_leave_too_little_of_is_left_out_with_the_reason(clean):
    t, y = clean
    bad = np.full_like(y, np.nan)
    bad[:2] = y[:2]
    fit = fit_record(_record(t, bad))
    assert not fit.used and "usable samples left" in fit.reason


def test_one_bad_record_never_stops_the_others(clean):
    t, y = clean
    fits = fit_records([_record(t, np.full_like(y, np.nan), "dead"), _record(t, y, "fine")])
    assert [f.used for f in fits] == [False, True]


# -- the shipped steer-by-wire logs, damaged ----------------------------------------------------------
@pytest.fixture(scope="module")
def damaged(tmp_path_factory):
    out = tmp_path_factory.mktemp("sbw_damaged")
    manifest = damaged_copy(SBW, out, seed=1)
    shutil.copy(SBW / "sbw_bicycle.toml", out / "sbw_bicycle.toml")
    return out, manifest


def _fits(manifest):
    settings, windows = read_experiment(manifest, None, None, {})
    return fit_records(load_records(settings, windows))


@pytest.mark.slow
def test_damaged_sbw_logs_give_the_same_record_fits(damaged):
    _, manifest = damaged
    clean, hurt = _fits(SBW / "experiment.toml"), _fits(manifest)
    assert len(clean) == len(hurt) == 59
    assert [f.used for f in clean] == [f.used for f in hurt]
    tags = set()
    for a, b in zip(clean, hurt):
        tags |= set(repair_tags(b.record.repairs))
        if a.used:
            _agree(a, b, k=2.0)
    assert {"duplicate stamps", "missing values", "resampled", "clock reset"} <= tags
    assert not any(f.record.repairs for f in clean)  # the clean logs need nothing
    assert ROLL_RATE_BIAS > 0


@pytest.mark.slow
def test_damaged_sbw_logs_give_the_same_diagnosis(damaged):
    from bikerider.diagnose import diagnose_files

    out, manifest = damaged
    clean = diagnose_files(str(SBW / "sbw_bicycle.toml"), experiment=(str(SBW / "experiment.toml"),)).as_dict()
    hurt = diagnose_files(str(out / "sbw_bicycle.toml"), experiment=(str(manifest),)).as_dict()
    assert hurt["verdict"] == clean["verdict"] and hurt["selected"] == clean["selected"]
    assert hurt["records"]["used"] == clean["records"]["used"]
    assert len(hurt["records"]["repaired"]) >= 50
    first = {r["effect"]: r for r in clean["ranking"]}
    for r in hurt["ranking"]:
        if r["effect"] != "steer_friction":
            continue
        for name, p in r["parameters"].items():
            lo, hi = first["steer_friction"]["parameters"][name]["ci95"]
            assert lo <= p["value"] <= hi, (name, p["value"], lo, hi)
    assert math.isfinite(hurt["how_far"]["data_shrink"])


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    n=st.integers(0, 400),
    jitter=st.floats(0.0, 0.6),
    drop=st.floats(0.0, 0.5),
    holes=st.integers(0, 5),
    resets=st.integers(0, 2),
)
def test_any_damage_ends_in_a_used_record_or_a_reason(seed, n, jitter, drop, holes, resets):
    # a logger's worst: never an exception, never a silent NaN; a used record is uniformly sampled
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.01 + rng.uniform(-jitter, jitter, n) * 0.01
    y = _decay(t, rng) if n else np.zeros(0)
    keep = rng.random(n) >= drop
    t, y = t[keep], y[keep]
    for _ in range(holes):
        if t.size:
            k = int(rng.integers(0, t.size))
            (y if rng.random() < 0.7 else t)[k : k + int(rng.integers(1, 30))] = np.nan
    for _ in range(resets):
        if t.size:
            t[int(rng.integers(0, t.size)) :] -= rng.uniform(0.0, 100.0)
    fit = fit_record(_record(t, y))
    if fit.used:
        steps = np.diff(fit.record.time)
        assert np.allclose(steps, steps[0], rtol=1e-6) and np.all(np.isfinite(fit.record.signals["roll_rate"]))
        assert math.isfinite(fit.estimate.eigenvalue.real) and math.isfinite(fit.estimate.real_sigma)
    else:
        assert fit.reason


@pytest.mark.parametrize("count", ["1", "2"])
def test_records_fitted_on_worker_processes_keep_their_repairs(clean, monkeypatch, count):
    """fit_records with worker processes keeps the caller's record objects; a repaired record must stay
    the repaired one (the damaged SBW copy was refused as "not uniformly sampled" when the fits came back
    holding the caller's unrepaired record)."""
    from bikerider.gap import parallel

    monkeypatch.setenv(parallel.WORKERS_ENV, count)
    t, y = clean
    rng = np.random.default_rng(7)
    jittered = t + rng.uniform(-0.0005, 0.0005, t.size)
    records = [_record(jittered, y, f"jittered {k}") for k in range(parallel.MIN_RECORDS)]
    records.append(_record(t, y, "clean"))
    fits = fit_records(records)
    for record, fit in zip(records[:-1], fits[:-1]):
        assert fit.used, fit.reason
        assert fit.record.repairs and fit.record is not record
        steps = np.diff(fit.record.time)
        assert np.allclose(steps, steps[0])  # uniformly sampled, as the comparison with models needs
    assert fits[-1].record is records[-1]  # unrepaired: the caller's own object
