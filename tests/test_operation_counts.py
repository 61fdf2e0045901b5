"""The generated functions must not grow: operation counts against bench/operation_counts_baseline.json.

A count (before or after common-subexpression elimination) more than 5 % above its baseline fails.
A generated function missing from the baseline fails too (it would escape the check: take a new
baseline when adding one); a removed function is reported as a warning.  When a growth is wanted,
take a new baseline with ``python bench/operation_counts.py --update`` and say why in the commit.
"""

from __future__ import annotations

import importlib.util
import json
import sys
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _tool():
    spec = importlib.util.spec_from_file_location("bench_operation_counts", ROOT / "bench" / "operation_counts.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


oc = _tool()


def test_no_generated_function_grew_more_than_5_percent():
    result = oc.compare(oc.load_counts(oc.BASELINE), oc.load_counts(oc.CURRENT))
    if result.removed:
        warnings.warn(
            "generated functions removed since the operation-count baseline: " + ", ".join(result.removed), stacklevel=1
        )
    assert not result.added, (
        "generated functions without an operation-count baseline (run "
        "`python bench/operation_counts.py --update`): " + ", ".join(result.added)
    )
    assert not result.grown, "operation counts grew by more than 5 %:\n" + "\n".join(
        f"  {name} {kind}: {old} -> {new} ({(new - old) / old:+.1%})" for name, kind, old, new in result.grown
    )


def test_baseline_covers_the_generated_modules():
    baseline = json.loads(oc.BASELINE.read_text())["operation_counts"]
    assert {"benchmark_model", "combination", "pendulum", "rider_model"} <= set(baseline)
    assert all(
        v["after_cse"] > 0 and v["before_cse"] >= v["after_cse"]
        for functions in baseline.values()
        for v in functions.values()
    )


def _counts(**functions: tuple[int, int]) -> dict[str, dict[str, int]]:
    return {name: {"after_cse": a, "before_cse": b} for name, (a, b) in functions.items()}


def test_comparison_flags_growth_not_shrinkage_or_new_functions():
    base = _counts(**{"m.f": (100, 200), "m.g": (50, 60), "m.gone": (10, 10)})
    current = _counts(**{"m.f": (106, 200), "m.g": (40, 63), "m.new": (999, 999)})
    result = oc.compare(base, current)
    assert result.grown == [("m.f", "after_cse", 100, 106)]  # +6 %; m.g's +5 % before CSE is allowed
    assert result.removed == ["m.gone"]
    assert result.added == ["m.new"]


@pytest.mark.parametrize("after, grows", [(105, False), (106, True)])
def test_five_percent_is_the_boundary(after, grows):
    result = oc.compare(_counts(**{"m.f": (100, 100)}), _counts(**{"m.f": (after, 100)}))
    assert bool(result.grown) is grows
