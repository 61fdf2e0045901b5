"""The sigmas ``estimate`` and ``benchmark`` lead with: Monte Carlo, first order beside it (issue 12)."""

from __future__ import annotations

import json
from importlib import resources

import pytest
from strategies import run_cli

from bikerider.estimate import estimate_headline_uncertainty, estimate_uncertainty
from bikerider.uncertainty.headline import DEFAULT_SAMPLES, Sigma

BROWSER_BENCHMARK = (
    resources.files("bikerider") / "data/bicycleparameters/bicycles/Browser/Parameters/BrowserBenchmark.txt"
)


def test_on_the_paper_monte_carlo_sigmas_exceed_first_order(paper_result):
    """The audit's finding, measured: on the paper's own inputs (its stated accuracies, the rider
    exact) the Monte Carlo sigmas of the weave and capsize speeds are larger than first order's.
    The issue quoted 12 % and 21 %; 100,000 samples give 13 % and 24 % (seed 0; 13 % and 22 % with
    seed 1): the capsize speed's samples are skewed by the front wheel's I_yy."""
    first_order = estimate_uncertainty(paper_result)
    headline = estimate_headline_uncertainty(paper_result, first_order, samples=100_000, seed=0)
    weave, capsize = headline.speeds["weave"], headline.speeds["capsize"]
    assert weave.first_order == pytest.approx(0.5335, abs=1e-4)
    assert capsize.first_order == pytest.approx(1.1763, abs=1e-4)
    assert 1.10 < weave.monte_carlo / weave.first_order < 1.16
    assert 1.18 < capsize.monte_carlo / capsize.first_order < 1.30
    assert weave.first_order_holds and capsize.first_order_holds  # within a factor 1.5: no warning
    assert headline.failures.get("elbow closure", 0) < 50  # the arms reach in almost every draw


def test_estimate_leads_with_monte_carlo_and_prints_first_order_beside(capsys):
    code, out, _ = run_cli(["estimate", "--json"])
    data = json.loads(out)
    mc = data["uncertainty"]["monte_carlo"]
    assert code == 0 and mc["samples"] == DEFAULT_SAMPLES and mc["seed"] == 0
    assert data["uncertainty"]["speeds"]["weave"] == mc["sigmas"]["v_weave"]["monte_carlo"]
    assert data["uncertainty"]["first_order"]["speeds"]["weave"] == pytest.approx(0.5335, abs=1e-4)
    assert data["uncertainty"]["benchmark"]["w"] == pytest.approx(0.002)  # first order where it holds: exact
    code, text, _ = run_cli(["estimate"])
    line = next(row for row in text.splitlines() if row.startswith("Weave speed"))
    assert "(Monte Carlo, 10000 samples; first order +/- 0.53)" in line
    code, text, _ = run_cli(["estimate", "--monte-carlo", "0"])
    assert "Weave speed   5.6615 +/- 0.53 m/s (first order)" in text


def test_benchmark_prints_the_sigmas_estimate_prints_for_the_same_file():
    """Before: `benchmark` printed no sigmas although `estimate --bicycle` on the file did."""
    _, bench, _ = run_cli(["benchmark", str(BROWSER_BENCHMARK)])
    _, est, _ = run_cli(["estimate", "--bicycle", str(BROWSER_BENCHMARK), "--no-rider"])
    for label in ("Weave speed", "Capsize speed"):
        line = next(row for row in bench.splitlines() if row.startswith(label))
        assert "+/-" in line and "Monte Carlo" in line
        assert line == next(row for row in est.splitlines() if row.startswith(label))
    code, out, _ = run_cli(["benchmark", str(BROWSER_BENCHMARK), "--json"])
    data = json.loads(out)
    assert code == 0 and data["uncertainty"]["first_order"]["speeds"]["weave"] == pytest.approx(0.063, abs=5e-4)


def test_a_file_without_sigmas_gets_no_sigmas():
    path = resources.files("bikerider") / "data/bicycleparameters/bicycles/Benchmark/Parameters/BenchmarkBenchmark.txt"
    code, out, _ = run_cli(["benchmark", str(path), "--json"])
    data = json.loads(out)
    if any(data["uncertainty"]["first_order"]["benchmark"].values()):
        pytest.skip("the shipped Benchmark file states sigmas")
    assert data["uncertainty"]["monte_carlo"] is None


@pytest.mark.parametrize(
    "sigma, holds",
    [
        (Sigma(0.60, 0.53, 10), True),
        (Sigma(0.60, 0.95, 10), False),  # first order 58 % high
        (Sigma(0.60, None, 10), False),
        (Sigma(None, 0.5, 0), True),
        (Sigma(0.0, 0.0, 10), True),
    ],
)
def test_when_first_order_is_said_to_hold(sigma, holds):
    assert sigma.first_order_holds is holds
