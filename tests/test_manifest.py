"""The manifest (generated/manifest.py) against the generated code, and the runtime against retyping it.

``make derive`` writes the manifest from the same objects that emit the functions; these tests check
that it describes them (arguments in order, output shapes, stage functions that exist), and that no
module of the runtime types a list of generated argument names again: every tuple or list of three
or more names written in ``src/`` is compared with every function's arguments and every named list
of the manifest (in any order), and with every stage's inputs.
"""

from __future__ import annotations

import ast
import importlib
import inspect
from pathlib import Path

import numpy as np
import pytest
from bikerider.generated import manifest

SRC = Path(__file__).resolve().parents[1] / "src" / "bikerider"


def _function(name: str):
    module, function = name.split(".")
    return getattr(importlib.import_module(f"bikerider.generated.{module}"), function)


@pytest.mark.parametrize("name", sorted(manifest.FUNCTIONS))
def test_every_function_takes_and_returns_what_the_manifest_says(name):
    entry = manifest.FUNCTIONS[name]
    function = _function(name)
    assert tuple(inspect.signature(function).parameters) == entry["args"]
    rng = np.random.default_rng(0)
    with np.errstate(all="ignore"):
        result = function(**{a: rng.uniform(0.3, 0.9, (2,)) for a in entry["args"]})
    result = result if isinstance(result, tuple) else (result,)
    assert [r.shape for r in result] == [(2, *shape) for _, shape in entry["outputs"]]
    if entry["scalar"]:
        twin = _function(f"{name}_scalar")
        assert tuple(inspect.signature(twin).parameters) == entry["args"]
        point = {a: float(v[0]) for a, v in zip(entry["args"], [rng.uniform(0.3, 0.9, 1) for _ in entry["args"]])}
        try:
            scalar = twin(**point)
        except (ValueError, ZeroDivisionError):
            return  # outside the domain at this point: the NumPy function gives NaN there
        with np.errstate(all="ignore"):
            arrays = function(**point)
        scalar = scalar if len(entry["outputs"]) > 1 else (scalar,)
        arrays = arrays if isinstance(arrays, tuple) else (arrays,)
        for (output, _), got, expected in zip(entry["outputs"], scalar, arrays):
            nonzero = entry.get("nonzero", {}).get(output)
            flat = np.ravel(expected)[list(nonzero)] if nonzero is not None else np.ravel(expected)
            np.testing.assert_allclose(np.ravel(got), flat, rtol=1e-12, atol=1e-300, err_msg=output)


@pytest.mark.parametrize("kind", sorted(manifest.STAGES))
def test_every_stage_names_functions_that_take_its_inputs(kind):
    stage = manifest.STAGES[kind]
    value, jacobian = manifest.FUNCTIONS[stage["value"]], manifest.FUNCTIONS[stage["jacobian"]]
    assert sorted(value["args"]) == sorted(stage["inputs"])
    assert jacobian["args"] == stage["inputs"]
    assert jacobian["outputs"][-1][1] == (len(stage["outputs"]), len(stage["inputs"]))
    outputs = dict(value["outputs"])
    for name, index in stage["picks"] + tuple((o, i) for _, o, i in stage["checks"]):
        assert len(index) == len(outputs[name])


@pytest.mark.parametrize("name", sorted(manifest.KERNELS))
def test_every_kernel_is_declared_in_the_c_source_as_the_manifest_says(name):
    """Each fused C kernel takes the manifest's inputs (gathered from one pointer array) and writes
    one array per manifest output, in that order (the C signature has a pointer per output)."""
    module, function = name.split(".")
    source = importlib.import_module(f"bikerider.generated.{module}").C_SOURCE
    signature = source[source.index(f"int64_t {function}(") :].split("{", 1)[0]
    entry = manifest.KERNELS[name]
    assert "const double *const *args" in signature and len(entry["args"]) >= 4
    c_types = {"float64": "double", "int8": "int8_t", "uint8": "uint8_t"}
    pointers = [
        p.split("*")[0].split()[-1]
        for p in signature.split(",")
        if "*" in p and "args" not in p and "speeds" not in p.split("*")[-1] and "strides" not in p
    ]
    assert pointers == [c_types[dtype] for _, dtype, _ in entry["outputs"]]


def _known_lists() -> dict[frozenset[str], str]:
    known = {frozenset(entry["args"]): f"the arguments of {name}" for name, entry in manifest.FUNCTIONS.items()}
    known.update({frozenset(entry["args"]): f"the inputs of {name}" for name, entry in manifest.KERNELS.items()})
    known.update({frozenset(s["inputs"]): f"the inputs of stage {k}" for k, s in manifest.STAGES.items()})
    known.update(
        {
            frozenset(s["outputs"]): f"the outputs of stage {k}"
            for k, s in manifest.STAGES.items()
            if len(s["outputs"]) >= 3
        }
    )
    for name in dir(manifest):
        value = getattr(manifest, name)
        if name.isupper() and isinstance(value, tuple) and all(isinstance(v, str) for v in value):
            known[frozenset(value)] = f"manifest.{name}"
    return {names: what for names, what in known.items() if len(names) >= 3}


def _run_of_arguments(names: tuple[str, ...]) -> str | None:
    """A generated function whose arguments hold ``names`` (four or more) consecutively, in order."""
    if len(names) < 4:
        return None
    for function, entry in manifest.FUNCTIONS.items():
        args = entry["args"]
        for start in range(len(args) - len(names) + 1):
            if args[start : start + len(names)] == names:
                return f"the arguments of {function}"
    return None


def test_no_list_of_generated_names_is_typed_in_the_runtime():
    known = _known_lists()
    retyped = []
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.Tuple, ast.List)) and len(node.elts) >= 3:
                if all(isinstance(e, ast.Constant) and isinstance(e.value, str) for e in node.elts):
                    names = frozenset(e.value for e in node.elts)
                    run = _run_of_arguments(tuple(e.value for e in node.elts))
                    if names in known:
                        retyped.append(f"{path.relative_to(SRC)}:{node.lineno} retypes {known[names]}")
                    elif run:
                        retyped.append(f"{path.relative_to(SRC)}:{node.lineno} retypes a run of {run}")
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and len(node.value.split()) >= 3:
                names = frozenset(node.value.split())
                if names in known:
                    retyped.append(f"{path.relative_to(SRC)}:{node.lineno} retypes {known[names]} (as a string)")
    assert not retyped, "import these from bikerider.generated.manifest:\n" + "\n".join(retyped)


def _generated_names(tree: ast.Module) -> tuple[set[str], set[str]]:
    """Names a module binds to generated modules, and to generated functions."""
    modules, functions = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module == "bikerider.generated":
            modules.update(alias.asname or alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("bikerider.generated."):
            functions.update(alias.asname or alias.name for alias in node.names)
    return modules, functions


def test_no_generated_function_is_called_positionally():
    """A generated function takes its arguments by keyword everywhere in the runtime (an argument
    order changed by a derivation must not shift values silently)."""
    positional = []
    for path in sorted(SRC.rglob("*.py")):
        tree = ast.parse(path.read_text())
        modules, functions = _generated_names(tree)
        for node in ast.walk(tree):
            if not isinstance(node, ast.Call) or not node.args:
                continue
            func = node.func
            if (isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name) and func.value.id in modules) or (
                isinstance(func, ast.Name) and func.id in functions
            ):
                positional.append(f"{path.relative_to(SRC)}:{node.lineno}")
    assert not positional, "call generated functions with keyword arguments:\n" + "\n".join(positional)
