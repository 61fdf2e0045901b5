"""First-order propagation against Monte Carlo, on the paper's bicycle and rider and on the
BicycleParameters Browser (benchmark parameters with their sigmas)."""

from __future__ import annotations

import json
import math
from importlib import resources

import numpy as np
import pytest

from bikerider.errors import InputError
from bikerider.io.chain_inputs import paper_inputs
from bikerider.quantity import Quantity
from bikerider.uncertainty.montecarlo import compare, monte_carlo
from bikerider.uncertainty.propagation import propagate
from bikerider.uncertainty.stages import ENTRIES

N = 40_000
TOLERANCE = 0.03
"""Relative FO-MC tolerance: the Monte Carlo sigma's own standard error at N = 40 000 is 0.35 %."""


@pytest.fixture(scope="module")
def browser():
    from bikerider.io.name_value_file import read_name_value_file

    path = resources.files("bikerider") / "data/bicycleparameters/bicycles/Browser/Parameters/BrowserBenchmark.txt"
    return read_name_value_file(str(path)).as_dict()


@pytest.fixture(scope="module")
def paper():
    s = paper_inputs()
    return s, propagate(s.quantities, sources=s.sources)


def test_browser_first_order_matches_monte_carlo(browser):
    result = propagate(browser)
    outputs = [n for n in ENTRIES if result.sigmas[n]] + ["v_weave", "v_capsize"]
    mc = monte_carlo(browser, N, outputs=outputs, seed=1)
    for c in compare(result, mc, browser):
        assert c.relative_difference < TOLERANCE, (c.name, c.first_order, c.monte_carlo)
        assert not c.flagged
    assert result.speeds["weave"] > 0 and result.speeds["capsize"] > 0


def test_paper_benchmark_values_match_monte_carlo(paper):
    inputs, result = paper
    outputs = ["mB", "xB", "zB", "IBxx", "IBzz", "IBxz", "IRxx", "IFxx", "IFyy", "M_phiphi", "C1_phidelta", "K0_phiphi"]
    mc = monte_carlo(inputs.quantities, N, outputs=outputs, seed=2)
    for c in compare(result, mc, inputs.quantities):
        assert c.relative_difference < TOLERANCE, (c.name, c.first_order, c.monte_carlo)


def test_rear_body_mass_sigma_is_the_sum_in_quadrature(paper):
    # m_B = m_Bf + m_Br (Eq. 15; the Table 8 fractions sum to one): 0.02 kg (Table 2) and 0.1 kg (assumed)
    _, result = paper
    assert result.benchmark["mB"] == pytest.approx(math.hypot(0.02, 0.1), rel=1e-12)
    assert result.benchmark["IByy"] is None  # the rear frame's I_yy was not measured


def test_paper_speeds_disagree_and_the_comparison_says_why(paper):
    inputs, result = paper
    mc = monte_carlo(inputs.quantities, N, outputs=["v_weave", "v_capsize"], seed=3)
    by_name = {c.name: c for c in compare(result, mc, inputs.quantities)}
    capsize = by_name["v_capsize"]
    assert capsize.flagged and capsize.monte_carlo > capsize.first_order
    assert "elbow closure" in capsize.reason  # the arm spans 95 % of its length (0.583 of 0.61 m)
    assert "nonlinear" in capsize.reason and "T_Fyy" in capsize.reason
    assert mc.failures["elbow closure"] > 0.02 * N


def test_ranking_names_the_front_wheel_compound_period_for_both_speeds(paper):
    _, result = paper
    for speed in ("v_weave", "v_capsize"):
        contributions = result.contributions(speed)
        assert contributions[0].name == "T_Fyy"
        assert sum(c.share for c in contributions) == pytest.approx(1.0)
        first = contributions[0]
        assert first.elasticity == pytest.approx(first.value / result.values[speed] * first.derivative)
        assert first.variance == pytest.approx((first.derivative * first.sigma) ** 2)
    direct = math.sqrt(sum(c.variance for c in result.contributions("v_weave")))
    assert result.speeds["weave"] == pytest.approx(direct)


def test_the_estimate_chain_inputs_propagate(paper_result):
    """The lead's EstimateResult.chain_inputs (reduced inertias, NaN I_yy) go straight in."""
    result = propagate(paper_result.chain_inputs, speeds=[5.0])
    for name, value in paper_result.parameters.values.items():
        if value is None:
            assert result.benchmark[name] is None
        else:
            assert result.values[name] == pytest.approx(value, rel=1e-12)
    cs = paper_result.model.critical_speeds()
    assert result.values["v_weave"] == pytest.approx(cs.weave, rel=1e-10)
    assert result.values["v_capsize"] == pytest.approx(cs.capsize, rel=1e-10)
    assert 0 < result.speeds["weave"] < 1 and 0 < result.speeds["capsize"] < 2
    text = json.dumps(result.as_dict(), allow_nan=False)
    assert '"speeds"' in text and '"eigenvalues"' in text


def test_raw_pendulum_inputs_keep_the_correlation_the_shared_stiffness_creates(paper):
    """Only k_t uncertain: every torsional inertia moves together, so M_phiphi's sigma is the
    coherent sum; the reduced inertias given as independent values give the smaller quadrature sum."""
    inputs, _ = paper
    from bikerider.uncertainty.chain import Chain, prepare_values

    raw = {k: Quantity(q.value, 0.5 if k == "k_t" else 0.0) for k, q in inputs.quantities.items()}
    correlated = propagate(raw)
    values = prepare_values(raw)
    nodes = Chain(values).evaluate(values)
    reduced = {k: v for k, v in raw.items() if not k.startswith(("T_", "alpha_", "l_p")) and k != "k_t"}
    for name in ("IBfxx", "IBfxz", "IBfzz", "IRxx", "IFxx", "IFyy"):
        reduced[name] = Quantity(float(nodes[name]), correlated.sigmas[name])
    independent = propagate(reduced)
    for name in ("IBxx", "xB", "v_weave", "v_capsize", "M_phiphi"):
        assert independent.values[name] == pytest.approx(correlated.values[name], rel=1e-12)
    coherent = abs(correlated.derivative("M_phiphi", "k_t")) * 0.5
    assert correlated.sigmas["M_phiphi"] == pytest.approx(coherent, rel=1e-12)
    # M_phiphi = I_Txx sums IRxx + IBxx + IFxx (Meijaard et al. 2007, A4): all proportional to k_t
    parts = [correlated.sigmas[n] for n in ("IRxx", "IBfxx", "IFxx")]
    assert coherent == pytest.approx(sum(parts), rel=1e-9)
    assert independent.sigmas["M_phiphi"] == pytest.approx(math.sqrt(sum(p**2 for p in parts)), rel=1e-9)


def test_bad_inputs_are_named():
    with pytest.raises(InputError, match="w uncertainty = -0.1"):
        propagate({"w": Quantity(1.0, -0.1)})
    with pytest.raises(InputError, match="mB = 'heavy'"):
        propagate({"mB": "heavy"})
    with pytest.raises(InputError, match="g = missing: expected the acceleration due to gravity"):
        propagate({"w": 1.0})
    with pytest.raises(InputError, match="--monte-carlo"):
        monte_carlo({"w": Quantity(1.0, 0.1)}, 1)


def test_monte_carlo_is_reproducible_and_chunked(browser):
    a = monte_carlo(browser, 5001, seed=9, keep_samples=True)
    b = monte_carlo(browser, 5001, seed=9, keep_samples=True)
    assert a.samples is not None and a.samples["v_weave"].shape == (5001,)
    np.testing.assert_array_equal(a.samples["v_weave"], b.samples["v_weave"])


def test_a_bicycle_without_critical_speeds_has_no_speed_sigmas(benchmark_values):
    """Negative trail (c = -0.08 m on the Meijaard et al. 2007 benchmark): never self-stable."""
    values = {k: Quantity(v, 0.01 * abs(v)) for k, v in benchmark_values.items()}
    values["c"] = Quantity(-0.08, 0.001)
    result = propagate(values)
    assert result.speeds == {"weave": None, "capsize": None}
    assert any("no weave speed" in n for n in result.notes)
    assert result.sigmas["M_phiphi"] is not None and result.sigmas["M_phiphi"] > 0


def test_benchmark_parameters_object_propagates(browser):
    """A BenchmarkParameters (what estimate gives for Benchmark.txt bicycles or lumped riders)."""
    from bikerider.benchmark import BenchmarkParameters
    from bikerider.uncertainty import benchmark_inputs

    # without IByy/IHyy, which the linear model does not use (left out as undetermined)
    params = BenchmarkParameters.from_mapping({k: v for k, v in browser.items() if k not in ("IByy", "IHyy")})
    inputs = benchmark_inputs(params)
    assert inputs["IBxx"] == browser["IBxx"] and "IByy" not in inputs
    direct = propagate(browser)
    via = propagate(inputs)
    assert via.speeds == pytest.approx(direct.speeds, rel=1e-12)
