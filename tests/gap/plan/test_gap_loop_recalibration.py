"""The maps part 5 of docs/gap_validation.md fits to the closed loop's outcomes to ask whether the plan's
resolution probabilities could be recalibrated (issue 25, item 3): each recovers a known miscalibration."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def loop_report():
    sys.path.insert(0, str(ROOT / "docs" / "scripts"))
    try:
        import gap_next_loop
    finally:
        sys.path.pop(0)
    return gap_next_loop


def _outcomes(a: float, b: float, n: int = 4000) -> tuple[np.ndarray, np.ndarray]:
    """Predicted probabilities and outcomes drawn from ``logit q = a + b logit p``."""
    rng = np.random.default_rng(3)
    p = rng.uniform(0.01, 0.99, n)
    q = 1 / (1 + np.exp(-(a + b * np.log(p / (1 - p)))))
    return p, (rng.uniform(size=n) < q).astype(float)


def test_the_logistic_map_recovers_a_pessimistic_plans_miscalibration(loop_report):
    p, y = _outcomes(1.1, 0.45)  # as the decays' map on all ties
    a, b = loop_report._platt(p, y)
    assert a == pytest.approx(1.1, abs=0.15) and b == pytest.approx(0.45, abs=0.08)


def test_the_logistic_map_of_calibrated_probabilities_is_the_identity(loop_report):
    p, y = _outcomes(0.0, 1.0)
    a, b = loop_report._platt(p, y)
    assert a == pytest.approx(0.0, abs=0.15) and b == pytest.approx(1.0, abs=0.12)


def test_the_non_decreasing_map_never_falls_and_follows_the_outcomes(loop_report):
    p, y = _outcomes(1.1, 0.45)
    grid = np.linspace(0.0, 1.0, 101)
    q = loop_report._isotonic(p, y)(grid)
    assert np.all(np.diff(q) >= 0)
    # near p = 0.3 the outcomes resolve with q = 1 / (1 + exp(-(1.1 + 0.45 logit 0.3))) = 0.68
    assert q[30] == pytest.approx(0.68, abs=0.08)
