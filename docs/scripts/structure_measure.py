#!/usr/bin/env python3
"""Measure the structure of bikerider's source tree, before and after the gap-wing restructure (issue 22).

Standalone, standard library only; nothing of the project is imported or run.  Usage::

    python3 docs/scripts/structure_measure.py REPO_ROOT [--details]

prints markdown: files and lines per package and sub-package, imports inside functions (and how
many carry a comment giving the reason), file-level import cycles, imports that run back up the
layers (the package rules of tests/test_layers.py and the target layer order of issue 22), the
crossings between io/ and gap/ on the static call path of ``bikerider gap --model M --experiment X``
to the selected effect, candidate effect names typed as string literals outside the registry, the
size of the big classes, and duplicated runs of lines.  ``--details`` lists what each count counted.

Every rule below is written so that the same script measures the old layout (flat gap/) and the
new one (gap/measured, candidates, inference, diagnosis, plan, text, plotting/gap*.py, diagnose.py):
old and new paths are both in LAYERS, the call-path entry and the effect registry are found by name.
"""

from __future__ import annotations

import argparse
import ast
import hashlib
import io
import re
import subprocess
import sys
import tokenize
from collections import defaultdict
from pathlib import Path

# ---------------------------------------------------------------------------------------------------
# Layer order (low to high).  A path (relative to src/bikerider) takes the rank of its longest matching
# prefix.  The gap wing's old files are mapped to the layer the restructure gives them, so an import
# that will run back up after the moves is counted already today.
# ---------------------------------------------------------------------------------------------------
LAYERS = [
    # ground
    ("generated/", 0, "ground"),
    ("errors.py", 0, "ground"),
    ("notes.py", 0, "ground"),
    ("quantity.py", 0, "ground"),
    ("inertia.py", 0, "ground"),
    ("fitting/", 0, "ground"),
    ("engine/", 1, "engine"),
    ("benchmark/", 2, "benchmark"),
    ("bicycle/", 3, "bicycle/rider"),
    ("rider/", 3, "bicycle/rider"),
    ("uncertainty/", 4, "uncertainty"),
    ("report.py", 4, "uncertainty"),
    # gap: measured -> candidates -> inference -> diagnosis -> plan -> text -> validation -> face
    ("gap/measured/", 5.1, "gap.measured"),
    ("gap/control.py", 5.1, "gap.measured"),
    ("gap/data.py", 5.1, "gap.measured"),
    ("gap/extraction.py", 5.1, "gap.measured"),
    ("gap/records.py", 5.1, "gap.measured"),
    ("gap/candidates/", 5.2, "gap.candidates"),
    ("gap/effects.py", 5.2, "gap.candidates"),
    ("gap/model_input.py", 5.2, "gap.candidates"),
    ("gap/models.py", 5.2, "gap.candidates"),
    ("gap/inference/", 5.3, "gap.inference"),
    ("gap/fit.py", 5.3, "gap.inference"),
    ("gap/indirect.py", 5.3, "gap.inference"),
    ("gap/low_rank.py", 5.3, "gap.inference"),
    ("gap/predict.py", 5.3, "gap.inference"),
    ("gap/timedomain.py", 5.3, "gap.inference"),
    ("gap/diagnosis/", 5.4, "gap.diagnosis"),
    ("gap/diagnosis.py", 5.4, "gap.diagnosis"),
    ("gap/plan/", 5.5, "gap.plan"),
    ("gap/next_experiment.py", 5.5, "gap.plan"),
    ("gap/next_sweep.py", 5.5, "gap.plan"),
    ("gap/text.py", 5.6, "gap.text"),
    ("gap/validation/", 5.7, "gap.validation"),
    ("gap/validation.py", 5.7, "gap.validation"),
    ("gap/next_validation.py", 5.7, "gap.validation"),
    ("gap/__init__.py", 5.9, "gap face"),
    # gap figures belong with plotting
    ("gap/report.py", 8, "plotting"),
    ("gap/next_report.py", 8, "plotting"),
    ("io/", 6, "io"),
    ("design/", 7, "design"),
    ("plotting/", 8, "plotting"),
    ("estimate.py", 8, "pipelines"),
    ("diagnose.py", 8, "pipelines"),
    ("shipped.py", 8, "pipelines"),
    ("reproduction.py", 8, "pipelines"),
    ("commands/", 9, "commands"),
    ("cli.py", 9, "commands"),
    ("__main__.py", 9, "commands"),
    ("__init__.py", 10, "bikerider face"),
]

# test_layers.py: packages (and top-level modules) that never import io
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

# the gap wing: gap/ plus the files of other packages that serve it (old and new names)
GAP_WING = re.compile(r"^(gap/|io/(gap_\w+|experiment)\.py$|commands/gap\.py$|plotting/gap\w*\.py$|diagnose\.py$)")

# call path of `bikerider gap --model M --experiment X` (no --data, no --control, as the shipped SBW example)
ENTRY_NAMES = ("_diagnose_files", "diagnose_files")
NOT_ON_EXPERIMENT_PATH = {"detect_kind", "read_eigenvalues", "read_perturbation", "read_canonical", "read_control"}
BIG_CLASSES = ("Diagnosis", "NextExperiment", "GapProblem", "Plan", "DiagnosisResult")


# ---------------------------------------------------------------------------------------------------
# reading the tree
# ---------------------------------------------------------------------------------------------------
class Module:
    def __init__(self, src: Path, path: Path):
        self.path = path
        self.rel = path.relative_to(src / "bikerider").as_posix()
        parts = path.relative_to(src).with_suffix("").parts
        self.is_package = parts[-1] == "__init__"
        self.name = ".".join(parts[:-1] if self.is_package else parts)
        self.text = path.read_text(encoding="utf-8")
        self.lines = self.text.count("\n") + (0 if self.text.endswith("\n") or not self.text else 1)
        self.tree = ast.parse(self.text)
        self.comment_lines, self.trailing_comment = _comments(self.text)
        parents: dict[ast.AST, ast.AST] = {}
        for node in ast.walk(self.tree):
            for child in ast.iter_child_nodes(node):
                parents[child] = node
        self.parents = parents

    def enclosing_function(self, node):
        p = self.parents.get(node)
        while p is not None and not isinstance(p, (ast.FunctionDef, ast.AsyncFunctionDef)):
            p = self.parents.get(p)
        return p


def _comments(text: str):
    """Lines that are only a comment, and lines that end in one."""
    only, trailing = set(), set()
    code_lines = set()
    try:
        for tok in tokenize.generate_tokens(io.StringIO(text).readline):
            if tok.type == tokenize.COMMENT:
                (only if tok.start[0] not in code_lines else trailing).add(tok.start[0])
            elif tok.type not in (tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT, tokenize.ENCODING):
                code_lines.add(tok.start[0])
                if tok.start[0] in only:  # cannot happen (comments end a line); kept for safety
                    only.discard(tok.start[0])
    except tokenize.TokenError:
        pass
    return only, trailing


def read_tree(root: Path) -> dict[str, Module]:
    src = root / "src"
    mods = {}
    for path in sorted((src / "bikerider").rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        m = Module(src, path)
        mods[m.name] = m
    return mods


def rank_of(rel: str):
    best = None
    for prefix, rank, name in LAYERS:
        if (rel == prefix or (prefix.endswith("/") and rel.startswith(prefix))) and (
            best is None or len(prefix) > len(best[0])
        ):
            best = (prefix, rank, name)
    return (best[1], best[2]) if best else (None, "?")


# ---------------------------------------------------------------------------------------------------
# imports
# ---------------------------------------------------------------------------------------------------
def _absolute(mod: Module, node: ast.ImportFrom) -> str | None:
    if node.level == 0:
        return node.module
    base = mod.name.split(".") if mod.is_package else mod.name.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def import_targets(mods: dict[str, Module], mod: Module, node) -> list[tuple[str, str | None]]:
    """(module of this tree, name taken from it or None) for one import statement."""
    out = []
    # only modules of src/bikerider count (bikerider.generated lives in generated/ and is not read)
    if isinstance(node, ast.Import):
        out += [(a.name, None) for a in node.names if a.name in mods]
    else:
        base = _absolute(mod, node)
        if not base or base not in mods:
            return out
        for a in node.names:
            out.append((f"{base}.{a.name}", None) if f"{base}.{a.name}" in mods else (base, a.name))
    return out


def is_own(mod: Module, node) -> bool:
    if isinstance(node, ast.Import):
        return any(a.name.split(".")[0] == "bikerider" for a in node.names)
    return node.level > 0 or (node.module or "").split(".")[0] == "bikerider"


def all_imports(mods):
    """[(module, node, inside_function, [(target, name)])] for every import statement."""
    rows = []
    for mod in mods.values():
        for node in ast.walk(mod.tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                rows.append((mod, node, mod.enclosing_function(node) is not None, import_targets(mods, mod, node)))
    return rows


def has_reason(mod: Module, node) -> bool:
    """A comment on the import's own lines, or a comment line right above the run of imports it opens or belongs to."""
    return reason_line(mod, node) is not None


def reason_line(mod: Module, node) -> int | None:
    """The line of the comment that gives an import's reason (None without one)."""
    for line in range(node.lineno, node.end_lineno + 1):
        if line in mod.trailing_comment:
            return line
    body = None
    parent = mod.parents.get(node)
    for field in ("body", "orelse", "finalbody", "handlers"):
        seq = getattr(parent, field, None)
        if isinstance(seq, list) and node in seq:
            body = seq
            break
    first = node
    if body is not None:
        k = body.index(node)
        while k > 0 and isinstance(body[k - 1], (ast.Import, ast.ImportFrom)):
            k -= 1
        first = body[k]
    return first.lineno - 1 if (first.lineno - 1) in mod.comment_lines else None


# ---------------------------------------------------------------------------------------------------
# graphs
# ---------------------------------------------------------------------------------------------------
def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def unit_of(mod: Module) -> str:
    """The package (or top-level module) of tests/test_layers.py."""
    first = mod.rel.split("/")[0].removesuffix(".py")
    return "bikerider" if first == "__init__" else first


# ---------------------------------------------------------------------------------------------------
# static call graph (for the io <-> gap crossings)
# ---------------------------------------------------------------------------------------------------
class Defs:
    """Top-level functions, classes and methods of every module; names each module binds."""

    def __init__(self, mods):
        self.mods = mods
        self.nodes = {}  # "module:qual" -> (module, ast node, class name or None)
        self.classes = {}  # "module:Class" -> ClassDef
        self.bind = {}  # module -> {name: ("module", m) | ("def", key)}
        for m in mods.values():
            for node in m.tree.body:
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    self.nodes[f"{m.name}:{node.name}"] = (m, node, None)
                elif isinstance(node, ast.ClassDef):
                    self.nodes[f"{m.name}:{node.name}"] = (m, node, node.name)
                    self.classes[f"{m.name}:{node.name}"] = node
                    for item in node.body:
                        if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
                            self.nodes[f"{m.name}:{node.name}.{item.name}"] = (m, item, node.name)
        for m in mods.values():
            self.bind[m.name] = self._names(m, [n for n in m.tree.body if isinstance(n, (ast.Import, ast.ImportFrom))])
            for key in self.nodes:
                mod, _, qual = key.partition(":")
                if mod == m.name and "." not in qual:
                    self.bind[m.name].setdefault(qual, ("def", key))

    def _names(self, m, imports):
        out = {}
        for node in imports:
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.asname and a.name in self.mods:
                        out[a.asname] = ("module", a.name)
                continue
            for (target, name), a in zip(import_targets(self.mods, m, node), node.names):
                local = a.asname or a.name
                out[local] = ("module", target) if name is None else ("def", self.resolve_def(target, name))
        return out

    def resolve_def(self, module, name, depth=0):
        key = f"{module}:{name}"
        if key in self.nodes or depth > 5:
            return key
        m = self.mods.get(module)
        if m is None:
            return key
        for node in m.tree.body:  # re-exported through a package's __init__
            if isinstance(node, ast.ImportFrom):
                for (target, taken), a in zip(import_targets(self.mods, m, node), node.names):
                    if (a.asname or a.name) == name and taken is not None:
                        return self.resolve_def(target, taken, depth + 1)
        return key

    def local_names(self, m, fn):
        names = dict(self.bind[m.name])
        inner = [n for n in ast.walk(fn) if isinstance(n, (ast.Import, ast.ImportFrom))]
        names.update(self._names(m, inner))
        return names


def _annotation_class(node, names, defs):
    if node is None:
        return None
    if isinstance(node, ast.BinOp):  # X | None
        return _annotation_class(node.left, names, defs) or _annotation_class(node.right, names, defs)
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        try:
            return _annotation_class(ast.parse(node.value, mode="eval").body, names, defs)
        except SyntaxError:
            return None
    if isinstance(node, ast.Name) and names.get(node.id, ("",))[0] == "def":
        key = names[node.id][1]
        return key if key in defs.classes else None
    return None


def call_graph(defs: Defs):
    """{function key: [callee keys in source order]} resolved statically (names, modules, self, typed locals)."""
    attr_types = {}  # "module:Class" -> {attr: class key}
    for key, cls in defs.classes.items():
        m = defs.mods[key.partition(":")[0]]
        names = defs.bind[m.name]
        types = {}
        for item in cls.body:
            if isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
                c = _annotation_class(item.annotation, names, defs)
                if c:
                    types[item.target.id] = c
        for node in ast.walk(cls):
            if isinstance(node, ast.Assign) and isinstance(node.value, ast.Call):
                for t in node.targets:
                    if isinstance(t, ast.Attribute) and isinstance(t.value, ast.Name) and t.value.id == "self":
                        fn = node.value.func
                        bound = names.get(fn.id, ("", None)) if isinstance(fn, ast.Name) else ("", None)
                        if bound[0] == "def" and bound[1] in defs.classes:
                            types[t.attr] = bound[1]
        attr_types[key] = types

    def method(cls_key, attr):
        seen = 0
        while cls_key and seen < 5:
            cand = f"{cls_key}.{attr}"
            if cand in defs.nodes:
                return cand
            cls = defs.classes.get(cls_key)
            m = defs.mods[cls_key.partition(":")[0]]
            base = None
            for b in cls.bases if cls else []:
                if isinstance(b, ast.Name) and defs.bind[m.name].get(b.id, ("",))[0] == "def":
                    base = defs.bind[m.name][b.id][1]
            cls_key, seen = base, seen + 1
        return None

    graph = {}
    for key, (m, fn, cls) in defs.nodes.items():
        if isinstance(fn, ast.ClassDef):  # calling a class runs its __init__ / __post_init__
            graph[key] = [k for k in (f"{key}.__init__", f"{key}.__post_init__") if k in defs.nodes]
            continue
        names = defs.local_names(m, fn)
        cls_key = f"{m.name}:{cls}" if cls else None
        local = {}
        for a in fn.args.args + fn.args.kwonlyargs:
            c = _annotation_class(a.annotation, names, defs)
            if c:
                local[a.arg] = c
        calls = sorted((n for n in ast.walk(fn) if isinstance(n, ast.Call)), key=lambda n: (n.lineno, n.col_offset))
        for node in ast.walk(fn):
            if (
                isinstance(node, ast.Assign)
                and isinstance(node.value, ast.Call)
                and isinstance(node.value.func, ast.Name)
            ):
                b = names.get(node.value.func.id)
                if b and b[0] == "def" and b[1] in defs.classes:
                    for t in node.targets:
                        if isinstance(t, ast.Name):
                            local[t.id] = b[1]
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                c = _annotation_class(node.annotation, names, defs)
                if c:
                    local[node.target.id] = c

        def type_of(expr, names=names, local=local, cls_key=cls_key):
            if isinstance(expr, ast.Name):
                if expr.id == "self":
                    return cls_key
                b = names.get(expr.id)
                if b and b[0] == "def" and b[1] in defs.classes:
                    return b[1]
                return local.get(expr.id)
            if (
                isinstance(expr, ast.Attribute)
                and isinstance(expr.value, ast.Name)
                and expr.value.id == "self"
                and cls_key
            ):
                return attr_types.get(cls_key, {}).get(expr.attr)
            if isinstance(expr, ast.Call) and isinstance(expr.func, ast.Name):
                b = names.get(expr.func.id)
                if b and b[0] == "def" and b[1] in defs.classes:
                    return b[1]
            return None

        out = []
        for c in calls:
            f = c.func
            target = None
            if isinstance(f, ast.Name):
                b = names.get(f.id)
                if b and b[0] == "def":
                    target = b[1]
            elif isinstance(f, ast.Attribute):
                if isinstance(f.value, ast.Name) and names.get(f.value.id, ("",))[0] == "module":
                    target = defs.resolve_def(names[f.value.id][1], f.attr)
                else:
                    t = type_of(f.value)
                    if t:
                        target = method(t, f.attr)
            if target in defs.nodes:
                out.append(target)
        graph[key] = out
    return graph


def is_builder(defs, key) -> bool:
    """A class, or a static/class method of one (an alternative constructor)."""
    _, node, cls = defs.nodes[key]
    if isinstance(node, ast.ClassDef):
        return True
    return cls is not None and any(
        isinstance(d, ast.Name) and d.id in ("staticmethod", "classmethod") for d in node.decorator_list
    )


def area(defs, key):
    rel = defs.nodes[key][0].rel
    first = rel.split("/")[0]
    return first if first in ("io", "gap") else "other"


def crossings(defs, graph, entry, skip=frozenset()):
    """DFS over the call graph from ``entry`` (each function expanded once, callees in source order).

    Returns the io->gap and gap->io call sites met; each call also returns, so the path crosses the
    border 2 x (calls) times in all.
    """
    seen, io_gap, gap_io = set(), [], []
    order = []

    def visit(k):
        seen.add(k)
        order.append(k)
        for callee in graph.get(k, ()):
            if callee.split(":")[1].split(".")[-1] in skip:
                continue
            a, b = area(defs, k), area(defs, callee)
            if (a, b) == ("io", "gap"):
                io_gap.append((k, callee))
            elif (a, b) == ("gap", "io"):
                gap_io.append((k, callee))
            if callee not in seen:
                visit(callee)

    visit(entry)
    return io_gap, gap_io, order


# ---------------------------------------------------------------------------------------------------
# duplicated runs of lines (identical after folding white space; blank, comment, import and
# punctuation-only lines passed over, as the `duplicates` command does)
# ---------------------------------------------------------------------------------------------------
PUNCT = re.compile(r"^[\s()\[\]{},:;.]*$")


def duplicate_pairs(mods, min_lines=6):
    seqs = {}
    for m in mods.values():
        seq = []
        for n, line in enumerate(m.text.splitlines(), 1):
            s = " ".join(line.split())
            if not s or PUNCT.match(s) or s.startswith(("#", "import ", "from ")):
                continue
            seq.append((n, s))
        seqs[m.rel] = seq
    where = defaultdict(list)
    for rel, seq in seqs.items():
        for k in range(len(seq) - min_lines + 1):
            h = hashlib.sha1("\n".join(s for _, s in seq[k : k + min_lines]).encode()).hexdigest()
            where[h].append((rel, k))
    pairs = {}
    for places in where.values():
        if len(places) < 2 or len(places) > 8:
            continue
        for i in range(len(places)):
            for j in range(i + 1, len(places)):
                (a, ka), (b, kb) = places[i], places[j]
                if a == b and abs(ka - kb) < min_lines:
                    continue
                key = (a, b) if (a, ka) <= (b, kb) else (b, a)
                first = (seqs[a][ka][0], seqs[b][kb][0]) if key == (a, b) else (seqs[b][kb][0], seqs[a][ka][0])
                pairs.setdefault(key, first)
    return pairs


# ---------------------------------------------------------------------------------------------------
# the report
# ---------------------------------------------------------------------------------------------------
def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("root", type=Path, help="repository root (holds src/bikerider)")
    ap.add_argument("--details", action="store_true", help="list what each count counted")
    args = ap.parse_args(argv)
    root = args.root.resolve()
    mods = read_tree(root)
    out = []
    p = out.append
    head = ""
    try:
        head = subprocess.run(
            ["git", "-C", str(root), "log", "-1", "--format=%h %ad", "--date=short"],
            capture_output=True,
            text=True,
            check=False,
        ).stdout.strip()
    except OSError:
        pass
    p(f"# Structure of {root.name} ({head or 'no git'})\n")

    # -- sizes ------------------------------------------------------------------------------------
    p("## Files and lines per package / sub-package\n")
    p("| folder | files | lines | largest file |")
    p("|---|---:|---:|---|")
    folders = defaultdict(list)
    for m in mods.values():
        folders[str(Path(m.rel).parent)].append(m)
    total_files = total_lines = 0
    for folder in sorted(folders):
        ms = folders[folder]
        big = max(ms, key=lambda m: m.lines)
        name = "(top-level modules)" if folder == "." else folder + "/"
        p(f"| {name} | {len(ms)} | {sum(m.lines for m in ms)} | {Path(big.rel).name} {big.lines} |")
        total_files += len(ms)
        total_lines += sum(m.lines for m in ms)
    p(f"| **src/bikerider** | {total_files} | {total_lines} | |")
    gap_mods = [m for m in mods.values() if m.rel.startswith("gap/")]
    wing = [m for m in mods.values() if GAP_WING.match(m.rel)]
    p(f"| gap/ (all sub-packages) | {len(gap_mods)} | {sum(m.lines for m in gap_mods)} | |")
    p(
        f"| gap wing (gap/, io/gap_*, io/experiment, commands/gap, plotting/gap*, diagnose) | {len(wing)} | "
        f"{sum(m.lines for m in wing)} | |"
    )
    p("")
    p("The gap wing by the layer it has (or will have) in the target order, whatever its folder:\n")
    p("| target layer | files | lines | files (lines) |")
    p("|---|---:|---:|---|")
    layers = defaultdict(list)
    for m in wing:
        layers[(rank_of(m.rel)[0], rank_of(m.rel)[1])].append(m)
    for (rank, name), ms in sorted(layers.items(), key=lambda kv: (kv[0][0] is None, kv[0][0] or 0, kv[0][1])):
        p(
            f"| {name} | {len(ms)} | {sum(m.lines for m in ms)} | "
            + ", ".join(f"{m.rel} {m.lines}" for m in sorted(ms, key=lambda m: -m.lines))
            + " |"
        )
    p("")
    p("| tests | files | lines | |")
    p("|---|---:|---:|---|")
    tests = root / "tests"
    if tests.is_dir():
        tfolders = defaultdict(lambda: [0, 0])
        for t in tests.rglob("*.py"):
            f = str(t.parent.relative_to(root))
            tfolders[f][0] += 1
            tfolders[f][1] += t.read_text(encoding="utf-8", errors="replace").count("\n")
        for f in sorted(tfolders):
            p(f"| {f}/ | {tfolders[f][0]} | {tfolders[f][1]} | |")
    p("")

    # -- imports inside functions ------------------------------------------------------------------
    imports = all_imports(mods)
    inside = [(m, n, t) for m, n, f, t in imports if f]
    gapi = [(m, n, t) for m, n, t in inside if m.rel.startswith("gap/")]
    wingi = [(m, n, t) for m, n, t in inside if GAP_WING.match(m.rel)]
    p("## Imports inside functions (statements)\n")
    p("| where | all | bikerider's own | with a reason comment | distinct reason comments |")
    p("|---|---:|---:|---:|---:|")
    for label, rows in (("src/bikerider", inside), ("gap/", gapi), ("gap wing", wingi)):
        reasons = {(m.rel, reason_line(m, n)) for m, n, _ in rows if has_reason(m, n)}
        p(
            f"| {label} | {len(rows)} | {sum(is_own(m, n) for m, n, _ in rows)} | "
            f"{sum(has_reason(m, n) for m, n, _ in rows)} | {len(reasons)} |"
        )
    per_name = defaultdict(int)
    for m, n, _ in inside:
        mod = n.module if isinstance(n, ast.ImportFrom) else n.names[0].name
        for a in n.names:
            per_name[f"{mod}.{a.name}" if isinstance(n, ast.ImportFrom) else a.name] += 1
    top = sorted(per_name.items(), key=lambda kv: (-kv[1], kv[0]))[:6]
    p("\nNames most often imported inside functions: " + ", ".join(f"`{k}` x{v}" for k, v in top) + "\n")
    if args.details:
        p("<details><summary>imports inside functions without a reason comment, per file</summary>\n")
        cnt = defaultdict(int)
        for m, n, _ in inside:
            if not has_reason(m, n):
                cnt[m.rel] += 1
        for rel, c in sorted(cnt.items(), key=lambda kv: -kv[1]):
            p(f"- {rel}: {c}")
        p("\n</details>\n")

    # -- file graph, cycles ------------------------------------------------------------------------
    graph_all, graph_top = defaultdict(set), defaultdict(set)
    edges = []  # (importer, imported, line, inside)
    for m, n, f, targets in imports:
        for target, _name in targets:
            if target == m.name:
                continue
            graph_all[m.name].add(target)
            if not f:
                graph_top[m.name].add(target)
            edges.append((m, mods[target], n.lineno, f))
    cyc_all = strongly_connected(graph_all)
    cyc_top = strongly_connected(graph_top)
    p("## Import cycles between modules (file level)\n")
    p("| imports counted | cycles | modules in cycles |")
    p("|---|---:|---|")
    p(
        f"| all (top and inside functions) | {len(cyc_all)} | "
        + "; ".join(" <-> ".join(mods[x].rel for x in c) for c in cyc_all)
        + " |"
    )
    p(
        f"| top of file only | {len(cyc_top)} | "
        + "; ".join(" <-> ".join(mods[x].rel for x in c) for c in cyc_top)
        + " |"
    )
    p("")

    # -- layers ------------------------------------------------------------------------------------
    units = defaultdict(set)
    for m, t, line, f in edges:
        a, b = unit_of(m), unit_of(t)
        if a != b and b != "bikerider":
            units[a].add(b)
    unit_cycles = strongly_connected(units)
    below_io = sorted({f"{m.rel}:{line}" for m, t, line, f in edges if unit_of(m) in BELOW_IO and unit_of(t) == "io"})
    back, seen_stmt = [], set()
    for m, t, line, f in edges:
        if t.name == "bikerider" or (m.rel, t.rel, line) in seen_stmt:  # the lazy face (__version__, ...) is no layer
            continue
        seen_stmt.add((m.rel, t.rel, line))
        ra, rb = rank_of(m.rel)[0], rank_of(t.rel)[0]
        if ra is not None and rb is not None and rb > ra:
            back.append((m, t, line, f))
    gap_sub = [e for e in back if e[0].rel.startswith("gap/") and e[1].rel.startswith("gap/")]
    p("## Imports that run back up the layers\n")
    p("| rule | violations |")
    p("|---|---:|")
    p(f"| tests/test_layers.py: package cycles | {len(unit_cycles)} |")
    p(f"| tests/test_layers.py: a package below io imports io | {len(below_io)} |")
    p(
        f"| target order (LAYERS): import statements from a lower layer to a higher | {len(back)} "
        f"({sum(1 for e in back if e[3])} inside functions) |"
    )
    p(
        f"| ... of them inside gap/ (sub-layer order measured < candidates < inference < diagnosis < plan < text < validation) | {len(gap_sub)} |"
    )
    p("")
    p("| importer | imported | line | inside a function |")
    p("|---|---|---:|---|")
    for m, t, line, f in sorted(back, key=lambda e: (e[0].rel, e[2])):
        p(f"| {m.rel} ({rank_of(m.rel)[1]}) | {t.rel} ({rank_of(t.rel)[1]}) | {line} | {'yes' if f else ''} |")
    p("")

    # -- io <-> gap crossings ------------------------------------------------------------------------
    defs = Defs(mods)
    cg = call_graph(defs)
    entry = None
    for name in ENTRY_NAMES:
        found = sorted(k for k in defs.nodes if k.endswith(":" + name))
        if found:
            entry = found[0]
            break
    p("## io <-> gap on the call path of `bikerider gap --model M --experiment X`\n")
    run_entry = next((k for k in sorted(defs.nodes) if k.endswith("commands.gap:run")), None)
    if entry:
        p(
            "Static call graph (each function expanded once, callees in source order; the --data and --control "
            "readers left out; calls on untyped objects, e.g. `diagnosis.as_dict()` in a reader, are not seen, "
            "so these are lower bounds).  A call site is *builds* when it calls a class or a static/class "
            "method of one (a reader building the data classes below it, which the architecture allows), "
            "*runs* otherwise (gap logic run from io, or io run from gap).  Each call also returns: border "
            "crossings = 2 x call sites.\n"
        )
        p(
            "| from | functions reached | selection reached | io -> gap builds | io -> gap runs | gap -> io | "
            "border crossings |"
        )
        p("|---|---:|---|---:|---:|---:|---:|")
        details = []
        for label, start in ((entry, entry), (run_entry, run_entry)):
            if start is None:
                continue
            io_gap, gap_io, order = crossings(defs, cg, start, NOT_ON_EXPERIMENT_PATH)
            reached_sel = any(k.endswith(("._select", ":select", ":select_effects")) for k in order)
            builds = [e for e in io_gap if is_builder(defs, e[1])]
            p(
                f"| `{label.split('bikerider.')[-1]}` | {len(order)} | {'yes' if reached_sel else 'NO'} | {len(builds)} | "
                f"{len(io_gap) - len(builds)} | {len(gap_io)} | {2 * (len(io_gap) + len(gap_io))} |"
            )
            details.append((label, io_gap + gap_io))
        per_io = defaultdict(int)
        for a, b in details[0][1]:
            per_io[defs.nodes[a][0].rel] += 1
        p(
            "\nCall sites per io file (from the first entry): "
            + ", ".join(f"{k} {v}" for k, v in sorted(per_io.items()))
            + "\n"
        )
        if args.details:
            for label, rows in details:
                p(f"From `{label}`:")
                for a, b in rows:
                    p(f"- `{a}` -> `{b}` ({'builds' if is_builder(defs, b) else 'runs'})")
                p("")
    else:
        p("no entry function found\n")

    # -- effect names ----------------------------------------------------------------------------------
    registry = None
    for m in mods.values():
        for node in m.tree.body:
            tgt = node.targets[0] if isinstance(node, ast.Assign) else getattr(node, "target", None)
            if (
                isinstance(tgt, ast.Name)
                and tgt.id == "EFFECT_NAMES"
                and isinstance(getattr(node, "value", None), ast.Tuple)
            ):
                # the names typed in the tuple, or module-level constants holding them (NAME = "name")
                consts = {
                    n.targets[0].id: n.value.value
                    for n in m.tree.body
                    if isinstance(n, ast.Assign)
                    and isinstance(n.targets[0], ast.Name)
                    and isinstance(n.value, ast.Constant)
                    and isinstance(n.value.value, str)
                }
                registry = (
                    m,
                    [
                        e.value if isinstance(e, ast.Constant) else consts[e.id]
                        for e in node.value.elts
                        if isinstance(e, ast.Constant) or (isinstance(e, ast.Name) and e.id in consts)
                    ],
                )
    p("## Candidate effect names typed as string literals outside the registry\n")
    if registry:
        reg, names = registry
        nameset = set(names)
        word = re.compile(r"\b(" + "|".join(map(re.escape, names)) + r")\b")
        exact, inside_str, per_file = [], [], defaultdict(int)
        for m in mods.values():
            if m is reg:
                continue
            docs = set()
            for node in ast.walk(m.tree):
                if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
                    first = node.body[0]
                    if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                        docs.add(id(first.value))
            for node in ast.walk(m.tree):
                if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs:
                    if node.value in nameset:
                        exact.append((m.rel, node.lineno, node.value))
                        per_file[m.rel] += 1
                    elif word.search(node.value):
                        inside_str.append((m.rel, node.lineno))
        no_param = [e for e in exact if e[2] != "parameters"]
        p(f"Registry: `{reg.rel}` ({len(names)} names).\n")
        p("| literals | count |")
        p("|---|---:|")
        p(f"| a string literal that is exactly an effect name | {len(exact)} |")
        p(f'| ... without `"parameters"` (also an ordinary word/key) | {len(no_param)} |')
        p(f"| ... in gap/ | {sum(1 for e in exact if e[0].startswith('gap/'))} |")
        p(f"| other strings (not docstrings) naming an effect | {len(inside_str)} |")
        p("\nPer file: " + ", ".join(f"{k} {v}" for k, v in sorted(per_file.items(), key=lambda kv: -kv[1])) + "\n")
    else:
        p("registry (EFFECT_NAMES) not found\n")

    # -- big classes ------------------------------------------------------------------------------
    p("## The big classes\n")
    p("| class | file | lines | methods | fields typed `object` | getattr/setattr/hasattr on self |")
    p("|---|---|---:|---:|---:|---:|")
    for key, cls in sorted(defs.classes.items()):
        if cls.name not in BIG_CLASSES:
            continue
        m = mods[key.partition(":")[0]]
        methods = [n for n in cls.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
        obj = sum(
            1
            for n in cls.body
            if isinstance(n, ast.AnnAssign) and isinstance(n.annotation, ast.Name) and n.annotation.id == "object"
        )
        dyn = sum(
            1
            for n in ast.walk(cls)
            if isinstance(n, ast.Call)
            and isinstance(n.func, ast.Name)
            and n.func.id in ("getattr", "setattr", "hasattr")
            and n.args
            and isinstance(n.args[0], ast.Name)
            and n.args[0].id == "self"
        )
        p(f"| {cls.name} | {m.rel} | {cls.end_lineno - cls.lineno + 1} | {len(methods)} | {obj} | {dyn} |")
    largest = sorted(
        (
            (n.end_lineno - n.lineno + 1, f"{mods[k.partition(':')[0]].rel}:{k.partition(':')[2]}")
            for k, (mm, n, c) in defs.nodes.items()
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and mm.rel.startswith("gap/")
        ),
        reverse=True,
    )[:5]
    p("\nLongest functions in gap/: " + ", ".join(f"`{name}` {n}" for n, name in largest) + "\n")

    # -- duplicates ------------------------------------------------------------------------------
    pairs = duplicate_pairs(mods)
    gap_pairs = {k: v for k, v in pairs.items() if any(GAP_WING.match(x) for x in k)}
    p(
        "## Duplicated code (pairs of places sharing a run of 6 identical lines, white space folded; blank, comment, "
        "import and punctuation lines passed over; a run found in more than 8 places is too common to count)\n"
    )
    p("| pairs | count |")
    p("|---|---:|")
    p(f"| in src/bikerider | {len(pairs)} |")
    p(f"| ... touching the gap wing | {len(gap_pairs)} |")
    p("")
    p(
        "Touching the gap wing: "
        + "; ".join(f"{a}:{la} ~ {b}:{lb}" for (a, b), (la, lb) in sorted(gap_pairs.items()))
        + "\n"
    )
    p(
        "(Runs alike but for names and values are not counted here; the `duplicates` command of the tool library finds those.)\n"
    )
    # -- who outside src/ imports the gap wing -----------------------------------------------------------
    p("## Who outside src/ imports the gap wing (tests, docs, bench)\n")
    p("| file | gap-wing modules it imports (module: names) |")
    p("|---|---|")
    pattern = re.compile(
        r"from[ \t]+(bikerider[\w.]*)[ \t]+import[ \t]+(?:\(([^)]*)\)|([\w \t,]+))|import[ \t]+(bikerider[\w.]*)"
    )
    users = {}
    for folder in ("tests", "docs", "bench", "derive"):
        base = root / folder
        if not base.is_dir():
            continue
        for path in sorted(base.rglob("*")):
            if path.suffix not in (".py", ".md") or "__pycache__" in path.parts:
                continue
            found = defaultdict(set)
            for mt in pattern.finditer(path.read_text(encoding="utf-8", errors="replace")):
                module = mt.group(1) or mt.group(4)
                names = re.sub(r"#[^\n]*", "", mt.group(2) or mt.group(3) or "")
                taken = [x.split()[0] for x in names.replace("\n", ",").split(",") if x.strip()]
                for x in taken or [None]:
                    full = f"{module}.{x}" if x else module
                    target = full if full in mods else module
                    if target in mods and GAP_WING.match(mods[target].rel):
                        if full not in mods and x:
                            found[mods[target].rel].add(x.split()[0])
                        else:
                            found[mods[target].rel]
            if found:
                users[path.relative_to(root).as_posix()] = found
    for rel, found in users.items():
        p(
            f"| {rel} | "
            + "; ".join(f"{k}: {', '.join(sorted(v)) or '(module)'}" for k, v in sorted(found.items()))
            + " |"
        )
    p(f"\n{len(users)} files outside src/ import the gap wing.\n")
    print("\n".join(out))


if __name__ == "__main__":
    main()
