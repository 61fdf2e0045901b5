"""Shared fixtures."""

from __future__ import annotations

import json
import logging
import os
import sys
from pathlib import Path

import pytest
from hypothesis import settings

# CI runs the property tests on a fixed example sequence, so a red run is reproducible; a
# developer's run keeps exploring new examples.
settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

DATA = Path(__file__).parent / "data"
ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # validation/ (the gap's blind-check harnesses) lives beside src/, not installed
    sys.path.insert(0, str(ROOT))
TESTS = Path(__file__).resolve().parent
if str(TESTS) not in sys.path:  # tests/gap/... import the shared helpers here (gap_support, sbw_damage, ...)
    sys.path.insert(0, str(TESTS))


@pytest.fixture(scope="session")
def meijaard2007() -> dict:
    """Meijaard, Papadopoulos, Ruina, Schwab (2007), Proc. R. Soc. A 463:1955 - the project's copy of
    shared/reference/meijaard2007.json (parameters Table 1, matrices sec. 5, Table 2 eigenvalues)."""
    return json.loads((DATA / "meijaard2007.json").read_text())


@pytest.fixture(scope="session")
def benchmark_values(meijaard2007) -> dict[str, float]:
    values = dict(meijaard2007["parameters"]["values"])
    values["lam"] = values.pop("lambda")
    return values


@pytest.fixture(scope="session")
def paper_result():
    """The method on the paper's own bicycle and rider."""
    from bikerider.estimate import estimate_default

    logging.getLogger("bikerider").setLevel(logging.ERROR)
    return estimate_default()


@pytest.fixture(scope="session")
def random_models():
    """2704 random valid bicycles, each benchmark parameter within +/-50 % of Meijaard et al. (2007)
    (the count of the issue-14 audit; tests/random_bicycles.py)."""
    from random_bicycles import random_parameters

    from bikerider.benchmark import WhippleModel

    return [WhippleModel.from_parameters(p) for p in random_parameters(2704, 0.5, seed=0)]


@pytest.fixture(scope="session")
def random_scan(random_models):
    """Whether each of ``random_models`` is stable at each speed of a dense grid (eigvals)."""
    from test_stability_audit import scan_stability

    return scan_stability(random_models)
