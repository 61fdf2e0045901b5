"""The packages of bikerider as layers: no import cycles between them, and no model imports io.

Every ``import bikerider.<x>...`` in ``src/bikerider`` (at the top of a module or inside a function)
is an edge from the importing package (or top-level module) to ``<x>``; the graph must have no
cycle.  Readers live in ``io``: the reductions and models below it never import it.
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "bikerider"
BELOW_IO = (
    "benchmark",
    "bicycle",
    "rider",
    "uncertainty",
    "engine",
    "fitting",
    "gap",
    "inertia",
    "quantity",
    "errors",
    "generated",
)
"""Packages and modules that never import ``bikerider.io``."""


def _unit(path: Path) -> str:
    """The package (or top-level module) a file belongs to."""
    parts = path.relative_to(SRC).with_suffix("").parts
    return parts[0] if parts[0] != "__init__" else "bikerider"


def _imports() -> dict[str, dict[str, str]]:
    """``{unit: {imported unit: "file:line" of the first such import}}``."""
    edges: dict[str, dict[str, str]] = {}
    for path in sorted(SRC.rglob("*.py")):
        unit = _unit(path)
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = (
                    [node.module] + [f"{node.module}.{a.name}" for a in node.names]
                    if node.module == "bikerider"
                    else [node.module]
                )
            for name in names:
                parts = name.split(".")
                if parts[0] == "bikerider" and len(parts) > 1 and parts[1] != unit and not parts[1].startswith("__"):
                    target = parts[1]
                    if (SRC / target).is_dir() or (SRC / f"{target}.py").is_file():
                        edges.setdefault(unit, {}).setdefault(target, f"{path.relative_to(SRC)}:{node.lineno}")
    return edges


def test_the_packages_import_each_other_without_a_cycle():
    edges = _imports()
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(unit: str) -> list[str] | None:
        state[unit] = 1
        stack.append(unit)
        for target in edges.get(unit, {}):
            if state.get(target) == 1:
                return stack[stack.index(target) :] + [target]
            if target not in state and (cycle := visit(target)):
                return cycle
        state[unit] = 2
        stack.pop()
        return None

    for unit in sorted(edges):
        if unit not in state and (cycle := visit(unit)):
            where = [edges[a][b] for a, b in zip(cycle, cycle[1:])]
            raise AssertionError(f"import cycle {' -> '.join(cycle)}: " + ", ".join(where))


def test_reductions_and_models_never_import_io():
    edges = _imports()
    offending = {unit: edges[unit]["io"] for unit in BELOW_IO if "io" in edges.get(unit, {})}
    assert not offending, f"readers live in io; these import it: {offending}"
