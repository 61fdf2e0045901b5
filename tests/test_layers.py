"""The packages of bikerider as layers: no import cycles between them, and no model imports io.

Every ``import bikerider.<x>...`` in ``src/bikerider`` (at the top of a module or inside a function)
is an edge from the importing package (or top-level module) to ``<x>``; the graph must have no
cycle.  Readers live in ``io``: the reductions and models below it never import it.

At file level (issue 22), counting the imports inside functions: no module imports one that imports
it back; the gap's floors (measured < candidates < inference < diagnosis < plan < text) import only
downwards and never the face ``bikerider.gap``; the gap's domain and the readers draw no figures; and
an import inside a function of the gap wing says why in a comment.
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


# ---------------------------------------------------------------------------------------------
# File level (issue 22): modules, not only packages, counting the imports inside functions too
# ---------------------------------------------------------------------------------------------
GAP_FLOORS = {
    "parallel": 0,  # the worker pool, the BLAS thread limit and the two tail probabilities: below every floor
    "blas_threads": 0,
    "distributions": 0,
    "measured": 1,
    "candidates": 2,
    "inference": 3,
    "diagnosis": 4,
    "plan": 5,
    "text": 6,
}
"""The gap's floors, low to high: a module of a floor imports only from its own floor or below."""
GAP_WING = (
    "gap/",
    "plotting/gap.py",
    "plotting/gap_plan.py",
    "plotting/gap_multisine.py",
    "diagnose.py",
    "io/gap_",
    "io/experiment.py",
    "io/multisine.py",
)
"""Files of the gap wing, whose imports inside functions must each say why (a comment)."""
KNOWN_FILE_CYCLES = {frozenset({"io/benchmark_file.py", "io/bicycleparameters.py"})}
"""File-level cycles older than this test (each side imports the other inside a function)."""


def _module_files() -> dict[str, Path]:
    """``{"bikerider.gap.text": path}`` for every module (packages by their ``__init__``)."""
    out = {}
    for path in SRC.rglob("*.py"):
        parts = ("bikerider",) + path.relative_to(SRC).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def _file_imports() -> list[tuple[str, str, int, bool, bool]]:
    """``(importer, imported, line, inside a function, with a reason comment)`` for every import of a
    bikerider module, files relative to ``src/bikerider``."""
    modules = _module_files()
    rows = []
    for name, path in sorted(modules.items()):
        text = path.read_text()
        tree = ast.parse(text)
        lines = text.splitlines()
        parents = {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                targets = [f"{node.module}.{a.name}" for a in node.names] + [node.module]
            else:
                continue
            inside, up = False, parents.get(node)
            while up is not None:
                inside = inside or isinstance(up, (ast.FunctionDef, ast.AsyncFunctionDef))
                up = parents.get(up)
            reason = _has_reason(node, parents.get(node), lines)
            seen = set()
            for target in targets:
                while target and target not in modules:  # `from pkg import name`: the package
                    target = target.rpartition(".")[0]
                if target and target != name and target not in seen and target.startswith("bikerider"):
                    seen.add(target)
                    rows.append(
                        (
                            str(path.relative_to(SRC)),
                            str(modules[target].relative_to(SRC)),
                            node.lineno,
                            inside,
                            reason,
                        )
                    )
                    break  # the most specific module of the statement's first name is enough
    return rows


def _has_reason(node, parent, lines: list[str]) -> bool:
    """A comment on the import's lines, or on the line before the first import of its block."""
    if any("#" in lines[k - 1] for k in range(node.lineno, node.end_lineno + 1)):
        return True
    first = node
    for field in ("body", "orelse", "finalbody"):
        seq = getattr(parent, field, None)
        if isinstance(seq, list) and node in seq:
            k = seq.index(node)
            while k > 0 and isinstance(seq[k - 1], (ast.Import, ast.ImportFrom)):
                k -= 1
            first = seq[k]
    return first.lineno >= 2 and lines[first.lineno - 2].strip().startswith("#")


def _all_imports_inside_functions() -> list[tuple[str, int, bool]]:
    """``(file, line, with a reason)`` of every import statement inside a function (any module)."""
    out = []
    for path in sorted(SRC.rglob("*.py")):
        text = path.read_text()
        tree = ast.parse(text)
        lines = text.splitlines()
        parents = {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}
        for fn in ast.walk(tree):
            if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for node in ast.walk(fn):
                    if isinstance(node, (ast.Import, ast.ImportFrom)):
                        out.append((str(path.relative_to(SRC)), node.lineno, _has_reason(node, parents[node], lines)))
    return sorted(set(out))


def test_no_module_imports_another_that_imports_it_back():
    graph: dict[str, set[str]] = {}
    for importer, imported, *_ in _file_imports():
        graph.setdefault(importer, set()).add(imported)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles = []

    def visit(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                component.add(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(frozenset(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    assert set(cycles) <= KNOWN_FILE_CYCLES, [sorted(c) for c in cycles if c not in KNOWN_FILE_CYCLES]


def _floor(path: str) -> int | None:
    parts = path.split("/")
    if parts[0] != "gap" or len(parts) < 2:
        return None
    return GAP_FLOORS.get(parts[1].removesuffix(".py"))


def test_the_gap_floors_import_only_downwards():
    rows = _file_imports()
    up = [
        f"{a}:{line} imports {b}"
        for a, b, line, *_ in rows
        if _floor(a) is not None and _floor(b) is not None and _floor(b) > _floor(a)
    ]
    assert not up, up
    face = [f"{a}:{line}" for a, b, line, *_ in rows if a.startswith("gap/") and b == "gap/__init__.py"]
    assert not face, f"no module under gap/ imports the face bikerider.gap: {face}"
    outside = [
        f"{a}:{line} imports {b}" for a, b, line, *_ in rows if _floor(a) and _floor(b) is None and b.startswith("gap/")
    ]
    assert not outside, f"every module of gap/ is on a floor: {outside}"


def test_the_gap_domain_and_the_readers_draw_no_figures():
    rows = _file_imports()
    bad = [
        f"{a}:{line} imports {b}"
        for a, b, line, *_ in rows
        if a.startswith(("gap/", "io/")) and (b.startswith("plotting/") or b == "diagnose.py")
    ]
    assert not bad, bad


def test_imports_inside_the_gap_wings_functions_say_why():
    counts: dict[str, int] = {}
    for path, line, reason in _all_imports_inside_functions():
        if path.startswith(GAP_WING) and not reason:
            counts[path] = counts.get(path, 0) + 1
    assert not counts, f"imports inside functions without a comment giving the reason (move them to the top): {counts}"
