"""Fused C kernels for design-space sweeps, from the SymPy expressions of ``derive/benchmark_model.py``.

The generated NumPy functions evaluate one operation at a time over whole arrays: every common
subexpression becomes an array that lives until the function returns (about 200 of them in
``critical_speed_polynomials``), so a design costs about 1.8 KB and large batches leave the cache.
The kernels emitted here evaluate the same expressions design by design, in blocks of
:data:`BLOCK` designs that stay in the first-level cache, and never materialise a temporary:

``bikerider_stability``
    benchmark parameters -> canonical matrix entries -> critical-speed polynomials (the
    expressions of ``canonical_matrices`` and ``critical_speed_polynomials``) -> every stable speed
    interval, the weave and capsize speeds and the weave frequency, by the rules of
    ``bikerider.benchmark.stability.stability_batch`` (ported line by line), and stability at given
    speeds as packed bits.
``bikerider_weave``
    benchmark parameters -> entries -> characteristic coefficients at each speed
    (``characteristic_coefficients``) -> the four roots by the closed-form quartic of
    ``bikerider.benchmark.quartic`` (ported line by line) -> the labelled weave eigenvalue.

The expressions are the same SymPy objects the NumPy modules are generated from, with one
common-subexpression pass per block (entries; polynomials; coefficients), printed as C99.  The
hand-written parts (interval logic, quartic) live in ``templates/design_kernels.c.jinja``; the C
source is emitted inside ``generated/design_kernels.py`` (as ``C_SOURCE``, with the argument and
output layout), which the runtime (``bikerider.design.compiled``) compiles with the machine's C
compiler at first use.  The NumPy functions stay the reference: the tests hold the two equal.
"""

from __future__ import annotations

import sympy as sp
from sympy.printing.c import C99CodePrinter

from derive import benchmark_model
from derive.codegen import TEMPLATE_DIR, _environment, format_source
from derive.symbols import sym, syms

BLOCK = 64
"""Designs evaluated together: their inputs, entries and coefficients (about 40 doubles each) stay
in the first-level cache, and the straight-line expression code vectorises across them."""
MODULE = "design_kernels"
NEWTON_STEPS = 2
"""Guarded Newton steps after the closed-form quartic: ``bikerider.benchmark.quartic.NEWTON_STEPS``
(a test holds the two equal)."""
OUTPUTS = {
    "bikerider_stability": (
        ("lower", "float64", "3"),
        ("upper", "float64", "3"),
        ("lower_kind", "int8", "3"),
        ("upper_kind", "int8", "3"),
        ("weave", "float64", ""),
        ("capsize", "float64", ""),
        ("weave_frequency", "float64", ""),
        ("mass_ok", "int8", ""),
        ("stable_bits", "uint8", "bits"),
    ),
    "bikerider_weave": (("real", "float64", "speeds"), ("imag", "float64", "speeds")),
}
"""The output arrays of each exported C function, in the order of its pointer arguments (the
signatures are in ``templates/design_kernels.c.jinja``; ``stable_bits`` follows the speeds), with
their element types and the width of one design's value: ``""`` one value, ``"3"`` one per stable
interval, ``"bits"`` one bit per map speed (packed, little-endian), ``"speeds"`` one per speed."""


class _CPrinter(C99CodePrinter):
    """C99 with ``x*x`` and ``x*x*x`` for small powers (vectorisable; NumPy computes ``x**2`` the same
    way) and ``1.0/(...)`` for negative integer powers."""

    def _print_Pow(self, expr):
        base, exp = expr.as_base_exp()
        if exp.is_Integer and 2 <= exp <= 3:
            b = self.parenthesize(base, 1000)
            return "*".join([b] * int(exp))
        if exp.is_Integer and exp.is_negative:
            return f"1.0/({self._print(sp.Pow(base, -exp))})"
        return super()._print_Pow(expr)


def _print(expr: sp.Expr) -> str:
    return _CPrinter().doprint(expr)


def _block(outputs: list[sp.Expr], targets: list[str], replace: dict | None = None) -> dict:
    """One common-subexpression pass over ``outputs``; C statements assigning ``targets``."""
    if replace:
        outputs = [sp.sympify(e).xreplace(replace) for e in outputs]
    outputs = [sp.sympify(e) for e in outputs]
    before = int(sum(sp.count_ops(e) for e in outputs))
    replacements, reduced = sp.cse(outputs, symbols=sp.numbered_symbols("_x"), order="canonical")
    after = int(sum(sp.count_ops(r) for _, r in replacements) + sum(sp.count_ops(e) for e in reduced))
    lines = [f"const double {lhs} = {_print(rhs)};" for lhs, rhs in replacements]
    lines += [f"{target} = {_print(e)};" for target, e in zip(targets, reduced)]
    return {"lines": lines, "ops": (before, after)}


def structure(mats: dict[str, sp.Matrix]) -> dict[sp.Symbol, sp.Expr]:
    """Entries of the benchmark's canonical matrices that are zero, or equal to another entry, by
    construction (``C1_phiphi = K2_phiphi = K2_deltaphi = 0``, ``M`` and ``K0`` symmetric): the
    matrix-level polynomials serve any two-degree-of-freedom model, but inside a kernel fed by
    ``canonical_matrices`` these substitutions are exact and cut the polynomials' operations to a
    quarter."""
    out: dict[sp.Symbol, sp.Expr] = {}
    for name in benchmark_model.MATRIX_NAMES:
        symbols, exprs = benchmark_model.matrix_symbols(name), mats[name]
        for i in (0, 1):
            for j in (0, 1):
                if exprs[i, j] == 0:
                    out[symbols[i, j]] = sp.Integer(0)
        if exprs[1, 0] != 0 and sp.expand(exprs[1, 0] - exprs[0, 1]) == 0:
            out[symbols[1, 0]] = symbols[0, 1]
    return out


def arguments() -> tuple[str, ...]:
    """The kernels' inputs: the arguments of ``canonical_matrices`` (the one list in
    ``derive/benchmark_model.py``), then ``g``."""
    return tuple(benchmark_model.CANONICAL_ARGS.split()) + ("g",)


def manifest_entries() -> dict[str, dict]:
    """The kernels' entries of ``generated/manifest.py`` (``KERNELS``): per exported C function its
    inputs (gathered from one pointer array, in this order) and its outputs with their types, so the
    runtime names them from the manifest as it does the NumPy functions'."""
    return {f"{MODULE}.{name}": {"args": arguments(), "outputs": outputs} for name, outputs in OUTPUTS.items()}


def build() -> dict:
    """The rendering context: expression blocks, layout and operation counts."""
    args = arguments()
    lam = sym("lam")
    sin_lam, cos_lam = sp.Symbol("sin_lam"), sp.Symbol("cos_lam")
    trig = {sp.sin(lam): sin_lam, sp.cos(lam): cos_lam}
    mats = benchmark_model.canonical_matrices()
    entry_symbols = benchmark_model.matrix_entry_args()
    entry_exprs = [mats[name][i, j] for name in benchmark_model.MATRIX_NAMES for i in (0, 1) for j in (0, 1)]
    entries = _block(entry_exprs, [f"e[{k}][i]" for k in range(16)], trig)
    leftover = {f for e in entry_exprs for f in sp.sympify(e).xreplace(trig).atoms(sp.Function)}
    if leftover:
        raise ValueError(f"canonical matrices use functions other than sin/cos(lam): {leftover}")
    polys = benchmark_model.critical_speed_polynomials()
    padded = (
        list(benchmark_model._padded(polys["capsize"], 3))
        + list(benchmark_model._padded(polys["weave"], 3))
        + list(benchmark_model._padded(polys["a1_over_v"], 2))
        + list(benchmark_model._padded(polys["a3_over_v"], 2))
    )
    zeros = structure(mats)
    polynomials = _block([sp.expand(sp.sympify(e).xreplace(zeros)) for e in padded], [f"p[{k}][i]" for k in range(10)])
    coefficients = _block(
        [sp.expand(sp.sympify(e).xreplace(zeros)) for e in benchmark_model.characteristic_coefficients()],
        [f"a[{k}]" for k in range(5)],
    )
    return {
        "args": [{"name": name, "index": k} for k, name in enumerate(args)],
        "lam_index": args.index("lam"),
        "g_index": args.index("g"),
        "entries": [{"name": s.name, "index": k} for k, s in enumerate(entry_symbols)],
        "entry_block": entries["lines"],
        "polynomial_block": polynomials["lines"],
        "coefficient_block": coefficients["lines"],
        "block": BLOCK,
        "counts": {
            "entries": entries["ops"],
            "critical_speed_polynomials": polynomials["ops"],
            "characteristic_coefficients": coefficients["ops"],
        },
        "argument_names": args,
        "speed": syms("v")[0].name,
        "newton_steps": NEWTON_STEPS,
    }


def render(generator: str, digest: str) -> tuple[str, dict[str, tuple[int, int]]]:
    """``generated/design_kernels.py`` (the C source inside a Python module) and its operation counts."""
    context = build()
    env = _environment()
    c_source = env.get_template("design_kernels.c.jinja").render(**context, generator=generator, digest=digest)
    if "'''" in c_source or '"""' in c_source or "\\" in c_source:
        raise ValueError("the C source must not contain triple quotes or backslashes (it is embedded in a raw string)")
    text = env.get_template("design_kernels.py.jinja").render(
        **context, c_source=c_source, generator=generator, digest=digest, sympy_version=sp.__version__
    )
    counts = {name: ops for name, ops in context["counts"].items()}
    return format_source(text, f"generated/{MODULE}.py"), counts


__all__ = ["BLOCK", "MODULE", "OUTPUTS", "TEMPLATE_DIR", "arguments", "build", "manifest_entries", "render"]
