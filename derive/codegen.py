"""Turn SymPy expressions into plain, vectorised NumPy modules through jinja2 templates.

One :class:`GeneratedFunction` is one Python function: an explicit, ordered argument list
(never ``free_symbols``, whose order changes between runs), one or more matrix outputs, and one
common-subexpression pass over all of its outputs together.  Every emitted file carries a header
naming its generator and a hash of the generator's inputs, and the operation counts before and
after common-subexpression elimination.
"""

from __future__ import annotations

import hashlib
import logging
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import jinja2
import sympy as sp
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.pycode import PythonCodePrinter

from derive.symbols import describe

LOG = logging.getLogger(__name__)

DERIVE_DIR = Path(__file__).resolve().parent
TEMPLATE_DIR = DERIVE_DIR / "templates"


def _reciprocal_power(printer, expr) -> str | None:
    """``1/x`` or ``1/x**n`` for a negative integer power, else None (the printer's own form)."""
    base, exp = expr.as_base_exp()
    if exp.is_Integer and exp.is_negative:
        if exp == -1:
            return f"1/{printer.parenthesize(base, 1000)}"
        return f"1/{printer.parenthesize(base, 1000)}**{int(-exp)}"
    return None


class _Printer(NumPyPrinter):
    """NumPy printer that writes ``1/x**2`` rather than ``x**(-2.0)``."""

    def _print_Pow(self, expr, rational=False):
        return _reciprocal_power(self, expr) or super()._print_Pow(expr, rational=rational)


class _ScalarPrinter(PythonCodePrinter):
    """Plain-Python printer (``math.name``) with the same ``1/x**2`` form."""

    def _print_Pow(self, expr, rational=False):
        return _reciprocal_power(self, expr) or super()._print_Pow(expr, rational=rational)


def print_numpy(expr: sp.Expr) -> str:
    """Print one expression as NumPy source (functions as ``numpy.name``)."""
    return _Printer({"fully_qualified_modules": True, "allow_unknown_functions": False}).doprint(expr)


def print_scalar(expr: sp.Expr) -> str:
    """Print one expression as plain Python on floats (functions as ``math.name``)."""
    return _ScalarPrinter({"fully_qualified_modules": True, "allow_unknown_functions": False}).doprint(expr)


@dataclass
class Output:
    """One output of a generated function.

    Parameters
    ----------
    name : str
        Python name of the returned array.
    expr : sympy.Expr or sympy.Matrix
        A scalar gives an array of the broadcast input shape; an ``n x m`` matrix gives
        ``(..., n, m)``; a matrix declared with ``vector=True`` (``n x 1``) gives ``(..., n)``.
    doc : str
        One-line description, with unit in brackets.
    vector : bool
        Emit an ``n x 1`` matrix as a vector of shape ``(..., n)``.
    sparse : bool
        The plain-float twin returns only the entries that are not identically zero, as one flat
        tuple in row-major order; :attr:`nonzero` gives their flat indices (the manifest says them).
    """

    name: str
    expr: sp.Expr | sp.MatrixBase
    doc: str
    vector: bool = False
    sparse: bool = False

    @property
    def nonzero(self) -> tuple[int, ...]:
        """Flat (row-major) indices of the entries that are not identically zero."""
        return tuple(k for k, (_, e) in enumerate(self.entries()) if e != 0)

    def entries(self) -> list[tuple[tuple[int, ...], sp.Expr]]:
        if not isinstance(self.expr, sp.MatrixBase):
            return [((), sp.sympify(self.expr))]
        rows, cols = self.expr.shape
        if self.vector:
            if cols != 1:
                raise ValueError(f"output {self.name}: vector output needs one column")
            return [((i,), self.expr[i, 0]) for i in range(rows)]
        return [((i, j), self.expr[i, j]) for i in range(rows) for j in range(cols)]

    @property
    def shape_suffix(self) -> tuple[int, ...]:
        if not isinstance(self.expr, sp.MatrixBase):
            return ()
        rows, cols = self.expr.shape
        return (rows,) if self.vector else (rows, cols)


@dataclass
class GeneratedFunction:
    """A function to emit: ordered arguments, outputs, and a numpydoc summary."""

    name: str
    args: list[sp.Symbol]
    outputs: list[Output]
    summary: str
    notes: str = ""
    scalar: bool = False
    """Also emit ``<name>_scalar``: the same expressions on Python floats with ``math`` (no arrays),
    for single-bicycle calls where NumPy's per-operation overhead dominates."""

    def check(self) -> None:
        """Refuse expressions that use a symbol not in the argument list."""
        names = [a.name for a in self.args]
        if len(set(names)) != len(names):
            raise ValueError(f"{self.name}: repeated argument")
        allowed = set(self.args)
        for out in self.outputs:
            for _, e in out.entries():
                extra = e.free_symbols - allowed
                if extra:
                    raise ValueError(
                        f"{self.name}: output {out.name} uses {sorted(map(str, extra))}, which are not arguments"
                    )


@dataclass
class Stage:
    """One step of a chain: named inputs to named outputs, with a value and a Jacobian function.

    The runtime's one uncertainty engine (``bikerider.engine``) composes stages by the chain rule;
    it learns every stage from the manifest (``generated/manifest.py``) that :mod:`derive.extras`
    writes from these entries, so the graph is never typed again by hand.

    Parameters
    ----------
    name : str
        The stage kind (a key of the manifest's ``STAGES``).
    inputs : list of sympy.Symbol
        In the order of the Jacobian's columns; the keyword arguments of both functions.
    outputs : list of str
        Local output names, in the order of the Jacobian's rows.
    value : str
        ``"module.function"`` computing the outputs.
    picks : list of (str, tuple of int)
        For each output, the value function's output holding it and the index into it.
    jacobian : str
        ``"module.function"`` returning the ``(..., len(outputs), len(inputs))`` Jacobian.
    checks : list of (str, str, tuple of int)
        Quantities the runtime checks (not differentiated): name, value function output, index.
    """

    name: str
    inputs: list[sp.Symbol]
    outputs: list[str]
    value: str
    picks: list[tuple[str, tuple[int, ...]]]
    jacobian: str
    checks: list[tuple[str, str, tuple[int, ...]]] = field(default_factory=list)
    exprs: list[sp.Expr] | None = None
    """The outputs' expressions, when the value function was derived elsewhere: ``derive.extras``
    checks each pick against them (not written to the manifest)."""

    def entry(self) -> dict:
        """The manifest entry (plain data: names only)."""
        return {
            "inputs": tuple(s.name for s in self.inputs),
            "outputs": tuple(self.outputs),
            "value": self.value,
            "picks": tuple((name, tuple(index)) for name, index in self.picks),
            "jacobian": self.jacobian,
            "checks": tuple((name, output, tuple(index)) for name, output, index in self.checks),
        }


@dataclass
class GeneratedModule:
    """A module of generated functions, written to ``generated/<name>.py``."""

    name: str
    summary: str
    functions: list[GeneratedFunction]
    description: str = ""
    extra_source: str = field(default="")
    stages: list[Stage] = field(default_factory=list)
    """Stage kinds whose functions this module emits (collected into the manifest)."""
    names: dict[str, tuple[str, ...]] = field(default_factory=dict)
    """Named lists of symbols the runtime needs (e.g. ``BENCHMARK_NAMES``), collected into the manifest."""


@dataclass
class _Rendered:
    name: str
    args: list[dict]
    outputs: list[dict]
    summary: str
    notes: str
    assignments: list[tuple[str, str]]
    ops_before: int
    ops_after: int
    scalar: dict | None


def _render_function(fn: GeneratedFunction) -> _Rendered:
    fn.check()
    flat: list[sp.Expr] = []
    for out in fn.outputs:
        flat.extend(e for _, e in out.entries())
    ops_before = int(sum(sp.count_ops(e) for e in flat))
    replacements, reduced = sp.cse(flat, symbols=sp.numbered_symbols("_x"), order="canonical")
    ops_after = int(sum(sp.count_ops(r) for _, r in replacements) + sum(sp.count_ops(e) for e in reduced))
    assignments = [(str(lhs), print_numpy(rhs)) for lhs, rhs in replacements]
    scalar = None
    if fn.scalar:
        sparse = [o.name for o in fn.outputs if o.sparse]
        scalar = {
            "assignments": [(str(lhs), print_scalar(rhs)) for lhs, rhs in replacements],
            "returns": _scalar_returns(fn.outputs, [print_scalar(e) for e in reduced]),
            "sparse": (
                f"; {', '.join(sparse)} as a flat tuple of the entries that are not identically zero "
                "(bikerider.generated.manifest gives their indices)"
            )
            if sparse
            else "",
        }
    outputs = []
    k = 0
    for out in fn.outputs:
        entries = []
        for index, _ in out.entries():
            entries.append({"index": index, "source": print_numpy(reduced[k])})
            k += 1
        outputs.append(
            {
                "name": out.name,
                "doc": out.doc,
                "suffix": out.shape_suffix,
                "entries": entries,
            }
        )
    args = []
    for a in fn.args:
        info = describe(a.name)
        args.append({"name": a.name, "description": info.description, "unit": info.unit})
    return _Rendered(fn.name, args, outputs, fn.summary, fn.notes, assignments, ops_before, ops_after, scalar)


def _scalar_returns(outputs: list[Output], sources: list[str]) -> list[str]:
    """Each output as a Python literal: a float, a tuple, or a tuple of row tuples."""
    returns, k = [], 0
    for out in outputs:
        suffix = out.shape_suffix
        n = 1
        for size in suffix:
            n *= size
        flat = sources[k : k + n]
        k += n
        if out.sparse:
            returns.append("(" + "".join(f"{flat[i]}, " for i in out.nonzero).rstrip(" ") + ")")
            continue
        if not suffix:
            returns.append(flat[0])
        elif len(suffix) == 1:
            returns.append("(" + ", ".join(flat) + ",)")
        else:
            rows = [flat[i * suffix[1] : (i + 1) * suffix[1]] for i in range(suffix[0])]
            returns.append("(" + ", ".join("(" + ", ".join(r) + ",)" for r in rows) + ",)")
    return returns


PYPROJECT = DERIVE_DIR.parent / "pyproject.toml"


def _ruff(*args: str, source: str | None = None) -> str:
    """Run the project's pinned ruff (``pip install -e .[test]`` installs it) and return its output."""
    try:
        done = subprocess.run(
            [sys.executable, "-m", "ruff", *args], input=source, capture_output=True, text=True, check=True
        )
    except subprocess.CalledProcessError as exc:
        raise RuntimeError(f"ruff {' '.join(args)} failed: {exc.stderr.strip()}") from None
    return done.stdout


def _ruff_settings() -> str:
    """ruff's version and the project's ``[tool.ruff]`` tables: what formats generated/."""
    text = PYPROJECT.read_text(encoding="utf-8")
    start = text.find("[tool.ruff")
    return _ruff("--version") + (text[start:] if start >= 0 else "")


def format_source(text: str, filename: str) -> str:
    """``text`` as the project's formatter (ruff, the settings of pyproject.toml) writes it, so that
    generated code reads like the rest and ``make test``'s format check passes on it."""
    return _ruff("format", "--config", str(PYPROJECT), "--stdin-filename", filename, "-", source=text)


def inputs_hash() -> str:
    """SHA-256 of every file the generator reads: derive/ sources and templates, SymPy's version,
    and the formatter's version and settings."""
    h = hashlib.sha256()
    h.update(f"sympy {sp.__version__}\n".encode())
    h.update(_ruff_settings().encode())
    for path in sorted(DERIVE_DIR.rglob("*")):
        if path.is_file() and path.suffix in {".py", ".jinja"} and "__pycache__" not in path.parts:
            h.update(str(path.relative_to(DERIVE_DIR)).encode())
            h.update(b"\0")
            h.update(path.read_bytes())
            h.update(b"\0")
    return h.hexdigest()


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATE_DIR)),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["index"] = lambda idx: ", ".join(str(i) for i in idx)
    env.filters["shape"] = lambda suffix: "".join(f", {n}" for n in suffix)
    return env


def render_module(module: GeneratedModule, generator: str, digest: str) -> tuple[str, dict[str, tuple[int, int]]]:
    """Render one module to source text; also return ``{function: (ops_before, ops_after)}``."""
    rendered = [_render_function(f) for f in module.functions]
    text = (
        _environment()
        .get_template("module.py.jinja")
        .render(
            module=module,
            functions=rendered,
            uses_math=any(
                "math." in source
                for r in rendered
                if r.scalar
                for source in [*(rhs for _, rhs in r.scalar["assignments"]), *r.scalar["returns"]]
            ),
            exports=[name for r in rendered for name in ((r.name, f"{r.name}_scalar") if r.scalar else (r.name,))],
            generator=generator,
            digest=digest,
            sympy_version=sp.__version__,
        )
    )
    counts = {r.name: (r.ops_before, r.ops_after) for r in rendered}
    return format_source(text, f"generated/{module.name}.py"), counts


def write_if_changed(path: Path, text: str) -> bool:
    """Write ``text`` to ``path`` only when it differs; return whether it was written."""
    if path.exists() and path.read_text(encoding="utf-8") == text:
        return False
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)
    return True


def jacobian(outputs: list[sp.Expr], args: list[sp.Symbol]) -> sp.Matrix:
    """``(len(outputs), len(args))`` matrix of partial derivatives."""
    return sp.Matrix(len(outputs), len(args), lambda i, j: outputs[i].diff(args[j]))


def stage_functions(
    module: str,
    name: str,
    inputs: list[sp.Symbol],
    outputs: dict[str, sp.Expr],
    summary: str,
    checks: dict[str, sp.Expr] | None = None,
    derivatives: sp.Matrix | None = None,
    notes: str = "",
    scalar: bool = True,
) -> tuple[list[GeneratedFunction], Stage]:
    """A stage kind emitted as two functions: ``<name>`` (its outputs as one vector ``values``, and
    ``checks`` when there are any) and ``<name>_jacobian``, the same and the Jacobian (what a chain
    rule needs, in one call).

    Parameters
    ----------
    module : str
        The generated module the functions go into.
    inputs : list of sympy.Symbol
        Arguments of both functions, in the order of the Jacobian's columns.
    outputs : dict of str to sympy.Expr
        Output name to expression, in the order of the Jacobian's rows.
    checks : dict of str to sympy.Expr, optional
        Quantities the runtime checks (not differentiated).
    derivatives : sympy.Matrix, optional
        The Jacobian, when built more compactly than by differentiating ``outputs`` (e.g. by the
        chain rule through named intermediates); by default ``jacobian(outputs, inputs)``.
    scalar : bool
        Also emit plain-float twins (one bicycle at a time).
    """
    checks = checks or {}
    names = ", ".join(outputs)
    args = ", ".join(s.name for s in inputs)
    value_outputs = [Output("values", sp.Matrix(list(outputs.values())), f"[{names}] [SI]", vector=True)]
    if checks:
        value_outputs.append(
            Output(
                "checks",
                sp.Matrix(list(checks.values())),
                f"[{', '.join(checks)}], for the runtime's checks [SI]",
                vector=True,
            )
        )
    matrix = derivatives if derivatives is not None else jacobian(list(outputs.values()), inputs)
    functions = [
        GeneratedFunction(name, list(inputs), value_outputs, summary, notes=notes, scalar=scalar),
        GeneratedFunction(
            f"{name}_jacobian",
            list(inputs),
            [*value_outputs, Output("jacobian", matrix, f"d[{names}]/d[{args}] [SI]", sparse=True)],
            f"{name} and its Jacobian (rows in output order, columns in argument order), with one "
            "common-subexpression pass over both.",
            scalar=scalar,
        ),
    ]
    stage = Stage(
        name,
        list(inputs),
        list(outputs),
        f"{module}.{name}",
        [("values", (i,)) for i in range(len(outputs))],
        f"{module}.{name}_jacobian",
        [(check, "checks", (i,)) for i, check in enumerate(checks)],
        list(outputs.values()),
    )
    return functions, stage
