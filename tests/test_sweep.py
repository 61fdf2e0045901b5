"""with_values, sweeps over one or two parameters, and the shipped parameter sets."""

from __future__ import annotations

import numpy as np
import pytest
from random_bicycles import benchmark_values

from bikerider.benchmark import BenchmarkParameters, WhippleModel
from bikerider.benchmark.sweep import stability_map, sweep
from bikerider.errors import InputError
from bikerider.quantity import Quantity
from bikerider.shipped import BICYCLES, named


@pytest.fixture(scope="module")
def base() -> BenchmarkParameters:
    values = benchmark_values()
    return BenchmarkParameters.from_mapping({k: Quantity(v, 0.01 * abs(v)) for k, v in values.items()}, "bench")


def test_with_values_keeps_the_uncertainties_of_what_did_not_change(base):
    changed = base.with_values(c=0.1, mB=Quantity(90.0, 2.0))
    assert changed["c"] == 0.1 and changed.sigmas["c"] == 0.0
    assert changed["mB"] == 90.0 and changed.sigmas["mB"] == 2.0
    for name in ("w", "lam", "IBxx", "rF"):
        assert changed[name] == base[name] and changed.sigmas[name] == base.sigmas[name]
    assert base["c"] == pytest.approx(0.08)  # the original is unchanged
    assert "c=0.1" in changed.source
    with pytest.raises(InputError, match="mB = -1"):
        base.with_values(mB=-1.0)
    with pytest.raises(InputError, match="one of the benchmark names"):
        base.with_values(trail=0.1)


def test_one_parameter_sweep_equals_one_bicycle_at_a_time(base):
    trails = np.linspace(-0.04, 0.2, 13)
    speeds = np.linspace(0.0, 10.0, 21)
    result = sweep(base, {"c": trails}, speeds)
    assert result.valid.all() and result.eigenvalues.shape == (13, 21, 4)
    for i, c in enumerate(trails):
        model = WhippleModel.from_parameters(base.with_values(c=float(c)))
        speeds_one = model.critical_speeds()
        for got, want in (
            (result.stability.weave[i], speeds_one.weave),
            (result.stability.capsize[i], speeds_one.capsize),
        ):
            assert (np.isnan(got) and want is None) or got == pytest.approx(want, rel=1e-12)
        stable = np.zeros(21, bool)
        for lo, hi in speeds_one.stable_intervals:
            stable |= (speeds > lo) & (speeds < hi)
        np.testing.assert_array_equal(result.stable()[i], stable)
        np.testing.assert_allclose(result.eigenvalues[i], model.eigenvalues(speeds).values, rtol=1e-7, atol=1e-7)


def test_a_stability_map_marks_impossible_designs_and_goes_on(base):
    # IBxx and IBzz share a validity check (the rear body's inertia tensor): every pair is checked.
    result = stability_map(
        base, ("IBxx", np.linspace(0.5, 12.0, 6)), ("IBzz", np.linspace(0.2, 6.0, 5)), speeds=np.linspace(0, 10, 11)
    )
    assert result.shape == (6, 5)
    assert not result.valid.all() and result.valid.any()
    i, j = np.argwhere(~result.valid)[0]
    assert "IB" in result.reasons[i, j] and np.isnan(result.stability.weave[i, j])
    assert not result.stable()[i, j].any()
    for i, j in np.argwhere(result.valid):
        one = WhippleModel.from_parameters(base.with_values(IBxx=result.values[0][i], IBzz=result.values[1][j]))
        assert result.stability.weave[i, j] == pytest.approx(one.critical_speeds().weave, rel=1e-12)


def test_separable_validity_equals_checking_every_pair(base):
    masses, trails = np.array([-5.0, 40.0, 85.0]), np.array([0.05, 0.08])
    result = stability_map(base, ("mB", masses), ("c", trails))
    assert result.valid.tolist() == [[False, False], [True, True], [True, True]]
    assert "mB = -5" in result.reasons[0, 1]


def test_sweep_rows_are_tidy(base):
    result = sweep(base, {"c": [0.06, 0.08]}, [4.0, 5.0])
    designs = result.design_rows()
    assert [d["c"] for d in designs] == [0.06, 0.08]
    assert designs[1]["stable_intervals"][0]["lower_crossing"] == "oscillatory"
    rows = result.speed_rows()
    assert len(rows) == 4 and set(rows[0]) >= {"c", "speed", "stable", "weave_real", "weave_imag", "capsize_real"}
    assert rows[3]["stable"] is True  # the benchmark bicycle at 5 m/s


def test_sweep_rejects_bad_axes(base):
    with pytest.raises(InputError, match="one of the benchmark names"):
        sweep(base, {"trail": [0.1]})
    with pytest.raises(InputError, match="non-empty"):
        sweep(base, {"c": []})
    with pytest.raises(InputError, match="one or two"):
        sweep(base, {"c": [0.1], "w": [1.0], "mB": [80.0]})


def test_every_shipped_bicycle_loads_and_jason_sits_on_two():
    for name in BICYCLES:
        parameters = named(name)
        assert name in parameters.source
        WhippleModel.from_parameters(parameters).critical_speeds()
    # Meijaard et al. (2007), Table 2: the benchmark bicycle's weave and capsize speeds
    speeds = WhippleModel.from_parameters(named("benchmark")).critical_speeds()
    assert speeds.weave == pytest.approx(4.292382, abs=1e-6) and speeds.capsize == pytest.approx(6.024262, abs=1e-6)
    with_rider = named("Browser", rider="Jason")
    assert with_rider["mB"] > named("Browser")["mB"] + 60
    with pytest.raises(InputError, match="seated on the Fisher"):
        named("Fisher", rider="Jason")
    with pytest.raises(InputError, match="one of the shipped bicycles"):
        named("Batavus")
