"""The bodies' checks pass a value well inside its limits at once (``bodies._QUICK``): the errors
and notes must be exactly those of the full checks, for values at and across every boundary."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bikerider.bicycle import bodies
from bikerider.errors import ErrorCollector, InputErrors

EDGES = [0.0, -0.0, 5e-324, 1e-7, 1e-6, 9.99e-4, 1e-3, 0.5, 1.0, 3.0, 5.0, 100.0, 500.0, 1e4, 2e4, math.inf, math.nan]
NUMBERS = st.one_of(st.sampled_from(EDGES), st.sampled_from(EDGES).map(lambda x: -x), st.floats(-2e4, 2e4))


def _outcome(values, quick: bool, monkeypatch) -> tuple[list[str], list[str]]:
    monkeypatch.setattr(bodies, "_QUICK", bodies._QUICK if quick else {})
    errors, notes = ErrorCollector(), []
    bodies.check_bicycle_values(values, "f.txt", errors, notes)
    try:
        errors.raise_any()
    except InputErrors as exc:
        return [str(e) for e in exc.errors], notes
    except Exception as exc:  # one error is raised as itself
        return [str(exc)], notes
    return [], notes


@pytest.fixture(scope="module")
def reference_values():
    from importlib import resources
    from pathlib import Path

    from bikerider.io.bicycleparameters import load_measured_bicycle

    data = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
    return dict(load_measured_bicycle(data / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt").values)


@settings(max_examples=300, deadline=None)
@given(name=st.sampled_from(sorted(bodies._QUICK)), value=NUMBERS, sigma=NUMBERS)
def test_quick_checks_give_the_errors_and_notes_of_the_full_checks(reference_values, name, value, sigma):
    from bikerider.quantity import Quantity

    values = dict(reference_values, **{name: Quantity(value, sigma)})
    with pytest.MonkeyPatch.context() as monkeypatch:
        assert _outcome(values, True, monkeypatch) == _outcome(values, False, monkeypatch)
