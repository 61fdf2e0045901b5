"""The registry of candidate effects (``bikerider.gap.candidates.effects``) is the one place their names
are typed, and everything else about an effect is derived from its entry (issue 22).

A name typed again as a string literal elsewhere in ``src/bikerider`` is one more place to change when an
effect is added or renamed: take it from the registry (``STEER_FRICTION``, ``EFFECTS[name]``, a field of
the :class:`~bikerider.gap.candidates.effects.Effect`).  One exception, by rule: ``"parameters"``, the
candidate of benchmark-parameter errors, is also an ordinary word.  In the gap wing it is allowed where
it is a plain key of a dictionary (a ``dict`` key, a subscript, ``.get``'s key: the JSON output's field
of fitted values), outside the gap wing everywhere (there it names the benchmark parameters, not the
candidate).
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
from gap_support import BP, nominal

from bikerider.gap.candidates.effect_model import BENCH_ARGS, EffectModel
from bikerider.gap.candidates.effects import (
    EFFECT_NAMES,
    EFFECTS,
    OBSERVATION_EFFECTS,
    PARAMETERS,
    STRUCTURAL_KEYS,
    TIME_DOMAIN_EFFECTS,
)
from bikerider.io.gap_model import load_model

SRC = Path(__file__).resolve().parents[3] / "src" / "bikerider"
REGISTRY = "gap/candidates/effects.py"
GAP_WING = ("gap/", "plotting/gap", "io/gap_", "io/experiment.py", "commands/gap.py", "diagnose.py")
"""Files where ``"parameters"`` names the candidate (elsewhere it names the benchmark parameters)."""


def _docstrings(tree: ast.AST) -> set[int]:
    return {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }


def _plain_keys(tree: ast.AST) -> set[int]:
    """String constants used as a key: of a dict display, in a subscript, or the first argument of ``.get``."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            out |= {id(k) for k in node.keys if k is not None}
        elif isinstance(node, ast.Subscript):
            out.add(id(node.slice))
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get":
            if node.args:
                out.add(id(node.args[0]))
    return out


def typed_names(path: Path, names: set[str], gap_wing: bool = True) -> list[tuple[int, str]]:
    """``(line, name)`` of the string literals in ``path`` that are exactly an effect name (docstrings
    aside; ``"parameters"`` as a plain key in the gap wing, and anywhere outside it, aside)."""
    tree = ast.parse(path.read_text())
    skip = _docstrings(tree)
    keys = _plain_keys(tree)
    out = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Constant) or node.value not in names or id(node) in skip:
            continue
        if node.value == PARAMETERS and (not gap_wing or id(node) in keys):
            continue
        out.append((node.lineno, node.value))
    return sorted(out)


def test_effect_names_are_typed_only_in_the_registry():
    typed = {}
    for path in sorted(SRC.rglob("*.py")):
        rel = str(path.relative_to(SRC))
        if rel == REGISTRY:
            continue
        found = typed_names(path, set(EFFECT_NAMES), rel.startswith(GAP_WING))
        if found:
            typed[rel] = found
    assert not typed, (
        "effect names typed outside the registry (take them from bikerider.gap.candidates.effects: its name "
        f"constants, EFFECTS[name] or a field of the Effect): {typed}"
    )


def test_the_check_sees_a_typed_name(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text(
        '"""steer_damping in a docstring is prose."""\n\n'
        'CHOICE = "steer_damping"\n'
        'ROW = {"parameters": 1}\n'
        'VALUE = ROW["parameters"]\n'
        'VERDICT = "parameters"\n'
    )
    names = set(EFFECT_NAMES)
    assert typed_names(probe, names) == [(3, "steer_damping"), (6, "parameters")]
    assert typed_names(probe, names, gap_wing=False) == [(3, "steer_damping")]


def test_every_entry_is_consistent():
    assert EFFECT_NAMES == tuple(EFFECTS)  # the order reports list them in
    for name, e in EFFECTS.items():
        assert e.name == name and e.description
        assert len({p.name for p in e.parameters}) == len(e.parameters)
        assert all(p.bounds[0] <= p.start <= p.bounds[1] for p in e.parameters), name
        for partner in e.partners:
            assert e.needs_records and partner in EFFECTS and not EFFECTS[partner].needs_records, (name, partner)
        fitted = {p.name for p in e.parameters}
        if e.structural_keys:  # a part of the linear model: it sets every parameter it fits
            assert fitted <= set(e.structural_keys) and set(e.fixed) <= set(e.structural_keys), name
            assert not (e.observation or e.needs_records), name


def test_the_derived_lists_follow_the_entries():
    assert TIME_DOMAIN_EFFECTS == tuple(n for n in EFFECT_NAMES if EFFECTS[n].needs_records)
    assert OBSERVATION_EFFECTS == tuple(n for n in EFFECT_NAMES if EFFECTS[n].observation)
    assert STRUCTURAL_KEYS == {n: EFFECTS[n].structural_keys for n in EFFECT_NAMES if EFFECTS[n].structural_keys}
    assert PARAMETERS in EFFECTS and not EFFECTS[PARAMETERS].parameters  # its values are the benchmark shifts


def test_every_structural_entry_builds_a_model_at_its_start_values():
    # the Davis bicycle with its rider, the shipped example's model (the arms and the lean need a rider)
    davis = load_model(
        BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt", BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
    )
    values = nominal(davis)
    assert set(BENCH_ARGS) <= set(values)
    for name, keys in STRUCTURAL_KEYS.items():
        e = EFFECTS[name]
        config = {name: {**e.fixed, **{p.name: p.start for p in e.parameters}}}
        assert set(config[name]) == set(keys), name
        eigenvalues = EffectModel(values, davis.geometry, config).eigenvalues([5.0])
        assert np.all(np.isfinite(eigenvalues)), name
