"""The sigmas ``estimate`` and ``benchmark`` lead with: Monte Carlo, first order beside it (issue 12)."""

from __future__ import annotations

import json
import re
from importlib import resources
from pathlib import Path

import pytest
from strategies import run_cli

from bikerider.estimate import estimate_headline_uncertainty, estimate_uncertainty
from bikerider.uncertainty.headline import DEFAULT_SAMPLES, Sigma

BROWSER_BENCHMARK = (
    resources.files("bikerider") / "data/bicycleparameters/bicycles/Browser/Parameters/BrowserBenchmark.txt"
)


def test_on_the_paper_monte_carlo_and_first_order(paper_result):
    """The audit's finding, measured.  On the paper's own inputs (its stated accuracies, the rider
    exact) the samples' standard deviations exceed first order by 13 % (weave) and 24 % (capsize)
    from 10,000 draws (the issue: 12 % and 21 %, measured against the Monte Carlo value); but they
    come from long upper tails, and the central 68 % of the samples is only 3 % and 4 % wider than
    first order's sigma, skewed upwards."""
    first_order = estimate_uncertainty(paper_result)
    headline = estimate_headline_uncertainty(paper_result, first_order, samples=10_000, seed=0)
    weave, capsize = headline.speeds["weave"], headline.speeds["capsize"]
    assert weave.first_order == pytest.approx(0.5335, abs=1e-4)
    assert capsize.first_order == pytest.approx(1.1763, abs=1e-4)
    assert 1.10 < weave.standard_deviation / weave.first_order < 1.16
    assert 1.18 < capsize.standard_deviation / capsize.first_order < 1.30
    assert 1.00 < weave.monte_carlo / weave.first_order < 1.07
    assert 1.00 < capsize.monte_carlo / capsize.first_order < 1.08
    for speed, value in ((weave, 5.6615), (capsize, 8.3581)):  # skewed upwards: the upper side is longer
        low, high = speed.interval
        assert high - value > 1.3 * (value - low)
    assert weave.first_order_holds and capsize.first_order_holds
    assert any("long upper tails" in note for note in headline.notes)


def test_the_reported_sigma_holds_from_seed_to_seed_and_the_standard_deviation_does_not(paper_result):
    """Why the reported sigma is half the central 68 %: from 100,000 draws the capsize speed's
    standard deviation moves 7 % with the seed (1.44 to 1.55 m/s for seeds 0-3: a few samples near
    the edge where the root runs off to infinity; from a million draws 1.47 to 1.71 m/s), the
    central half-width under 1 % (1.216 to 1.226 m/s)."""
    first_order = estimate_uncertainty(paper_result)
    runs = [
        estimate_headline_uncertainty(paper_result, first_order, samples=100_000, seed=seed).speeds["capsize"]
        for seed in range(4)
    ]
    deviations = [r.standard_deviation for r in runs]
    half_widths = [r.monte_carlo for r in runs]
    assert max(deviations) > 1.05 * min(deviations)
    assert max(half_widths) < 1.02 * min(half_widths)


def test_estimate_leads_with_monte_carlo_and_prints_first_order_beside(capsys):
    code, out, _ = run_cli(["estimate", "--json"])
    data = json.loads(out)
    mc = data["uncertainty"]["monte_carlo"]
    assert code == 0 and mc["samples"] == DEFAULT_SAMPLES and mc["seed"] == 0
    assert data["uncertainty"]["speeds"]["weave"] == mc["sigmas"]["v_weave"]["monte_carlo"]
    low, high = mc["sigmas"]["v_weave"]["interval_68"]
    assert data["uncertainty"]["speeds"]["weave"] == pytest.approx((high - low) / 2)
    assert data["uncertainty"]["first_order"]["speeds"]["weave"] == pytest.approx(0.5335, abs=1e-4)
    assert data["uncertainty"]["benchmark"]["w"] == pytest.approx(0.002)  # first order where it holds: exact
    code, text, _ = run_cli(["estimate"])
    line = next(row for row in text.splitlines() if row.startswith("Weave speed"))
    assert "(Monte Carlo, 10000 samples: 68 % within 5.21-6.30; first order +/- 0.53)" in line
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


def test_the_command_line_limit_is_the_module_s():
    from bikerider.commands.argument_types import MAX_REPORT_SAMPLES
    from bikerider.uncertainty.headline import MAX_SAMPLES

    assert MAX_REPORT_SAMPLES == MAX_SAMPLES


def test_a_sigma_beyond_floating_point_is_refused_by_name(tmp_path):
    """The fuzzing run's `w = 1.02+/-1e308` (Meijaard et al. 2007's benchmark otherwise): the reader
    refuses a stated uncertainty beyond the value's magnitude limit (docs/errors.md), naming it, before
    first order or the draws could overflow; no RuntimeWarning escapes (pytest makes them errors)."""
    text = (Path(__file__).parent / "data" / "BenchmarkBenchmark.txt").read_text()
    path = tmp_path / "huge.txt"
    path.write_text(re.sub(r"^w = ([0-9.]+)\+/-\S+", r"w = \1+/-1e308", text, flags=re.M))
    code, out, err = run_cli(["benchmark", str(path)])
    assert code == 2 and out == "", err
    assert "w uncertainty = 1e+308: expected at most" in err and str(path) in err
