"""Fixtures shared by the gap tests."""

from __future__ import annotations

from pathlib import Path

import pytest

import bikerider
from bikerider.io.gap_model import load_model

BP = Path(bikerider.__file__).parent / "data" / "bicycleparameters"


@pytest.fixture(scope="module")
def davis():
    """The Davis instrumented bicycle with rider Jason (BicycleParameters), the default rider geometry."""
    return load_model(
        BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt", BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
    )
