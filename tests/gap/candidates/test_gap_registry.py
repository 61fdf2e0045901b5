"""The registry of candidate effects (``bikerider.gap.candidates.effects``) is where their names are typed.

A name typed again as a string literal elsewhere in ``src/bikerider`` is one more place to change when
an effect is added or renamed (issue 22).  The places that still type names are listed with their
counts: a count may go down, never up, and a file not listed may type none.  (``"parameters"``, the
candidate of benchmark-parameter errors, is also an ordinary key, so it is not counted.)
"""

from __future__ import annotations

import ast
from pathlib import Path

from bikerider.gap.candidates.effects import EFFECT_NAMES

SRC = Path(__file__).resolve().parents[3] / "src" / "bikerider"
REGISTRY = "gap/candidates/effects.py"
STILL_TYPED = {
    "gap/candidates/effect_model.py": 14,  # STRUCTURAL_KEYS and the model's switches
    "gap/diagnosis/result.py": 8,
    "gap/inference/problem.py": 2,
    "gap/inference/timedomain.py": 4,
    "plotting/gap.py": 13,
}
"""Effect names typed as string literals outside the registry today (issue 22 measured 79 before the
validation harnesses left the package)."""


def _typed_names(path: Path, names: set[str]) -> list[int]:
    """Lines of the string literals in ``path`` that are exactly an effect name (docstrings aside)."""
    tree = ast.parse(path.read_text())
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    return [
        node.lineno
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and node.value in names and id(node) not in docstrings
    ]


def test_effect_names_are_typed_only_in_the_registry_and_the_places_listed():
    names = set(EFFECT_NAMES) - {"parameters"}
    over = {}
    for path in sorted(SRC.rglob("*.py")):
        rel = str(path.relative_to(SRC))
        if rel == REGISTRY:
            continue
        lines = _typed_names(path, names)
        if len(lines) > STILL_TYPED.get(rel, 0):
            over[rel] = lines
    assert not over, (
        "effect names typed outside the registry (take them from bikerider.gap.candidates.effects, e.g. "
        f"EFFECTS[name] or a field of the Effect): {over}"
    )


def test_the_check_sees_a_typed_name(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text('"""steer_damping in a docstring is prose."""\n\nCHOICE = "steer_damping"\n')
    assert _typed_names(probe, set(EFFECT_NAMES)) == [3]
