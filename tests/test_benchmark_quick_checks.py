"""The benchmark checks skip rules 2-5 and 7 when every value lies well inside its range
(``parameters._QUICK``): the errors must be exactly those of the full checks, in their order, for
values at and across every boundary of those rules."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bikerider.benchmark import parameters
from bikerider.benchmark.parameters import BENCHMARK_NAMES, BenchmarkParameters
from bikerider.errors import InputErrors

EDGES = [0.0, -0.0, 5e-324, 1e-7, 1e-6, 9.99e-4, 1e-3, 0.5, 1.0, 1.5, 3.0, 5.0, 100.0, 1000.0, 1e4, 2e4]
EDGES += [math.pi / 2, math.pi, math.inf, math.nan]
NUMBERS = st.one_of(st.sampled_from(EDGES), st.sampled_from(EDGES).map(lambda x: -x), st.floats(-2e4, 2e4))


def _errors(values: dict, sigmas: dict, quick: bool) -> list[str]:
    with pytest.MonkeyPatch.context() as monkeypatch:
        if not quick:
            monkeypatch.setattr(parameters, "_well_inside", lambda *_: False)
        try:
            BenchmarkParameters(dict(values), dict(sigmas), "f.txt").validate()
        except InputErrors as exc:
            return [str(e) for e in exc.errors]
        except Exception as exc:  # one error is raised as itself
            return [f"{type(exc).__name__}: {exc}"]
    return []


@pytest.fixture(scope="module")
def benchmark():
    from importlib import resources
    from pathlib import Path

    from bikerider.io.bicycleparameters import load_measured_bicycle, merge_rider, read_lumped_rider

    data = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
    bodies = load_measured_bicycle(data / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt")
    rider = read_lumped_rider(data / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt")
    return merge_rider(bodies, rider)


def test_the_reference_set_takes_the_quick_pass(benchmark):
    assert parameters._well_inside(benchmark.values, benchmark.sigmas)


@settings(max_examples=400, deadline=None)
@given(
    changes=st.lists(
        st.tuples(st.sampled_from(BENCHMARK_NAMES), NUMBERS, NUMBERS, st.booleans()), min_size=1, max_size=3
    )
)
def test_quick_pass_gives_the_errors_of_the_full_checks(benchmark, changes):
    values, sigmas = dict(benchmark.values), dict(benchmark.sigmas)
    for name, value, sigma, drop in changes:
        values[name] = None if drop and name in parameters.OPTIONAL_NAMES else value
        sigmas[name] = sigma
    assert _errors(values, sigmas, True) == _errors(values, sigmas, False)
