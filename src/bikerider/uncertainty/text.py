"""Plain-text and Markdown rendering of sensitivities, rankings and Monte Carlo comparisons."""

from __future__ import annotations

import math

import sympy as sp

from bikerider.quantity import DEG
from bikerider.uncertainty import names
from bikerider.uncertainty.montecarlo import Comparison
from bikerider.uncertainty.propagation import Contribution, UncertaintyResult
from bikerider.uncertainty.symbolic import SensitivityExpression

PRINT_LIMIT = 400
"""Steps longer than this many operations are summarised unless the full text is asked for."""


def _fmt(x: float | None, digits: int = 4) -> str:
    if x is None or not math.isfinite(x):
        return "-"
    return f"{x:.{digits}g}"


def _value_text(name: str, value: float, sigma: float) -> tuple[str, str]:
    unit = names.unit(name)
    if unit == "rad":
        return f"{value / DEG:.4g} deg", f"{sigma / DEG:.3g} deg"
    suffix = f" {unit}" if unit and unit != "1" else ""
    return f"{value:.4g}{suffix}", f"{sigma:.3g}{suffix}"


def output_header(result: UncertaintyResult, output: str) -> str:
    y, s = result.values.get(output), result.sigmas.get(output)
    unit = names.unit(output)
    desc = names.describe(output)[0]
    if y is None:
        return f"{output} ({desc}): not determined by these inputs"
    rel = f" ({abs(s / y):.1%})" if s is not None and y else ""
    return f"{output} ({desc}) = {_fmt(y, 5)} {unit}, first-order sigma {_fmt(s, 3)} {unit}{rel}"


def ranking_rows(contributions: list[Contribution], output: str, top: int | None = None) -> list[list[str]]:
    out_unit = names.unit(output)
    rows = []
    for rank, c in enumerate(contributions[:top] if top else contributions, start=1):
        value, sigma = _value_text(c.name, c.value, c.sigma)
        in_unit = names.unit(c.name)
        rows.append(
            [
                str(rank),
                c.name,
                value,
                sigma if c.sigma else "0",
                f"{c.derivative:.4g} {out_unit}/{in_unit}".rstrip("/ "),
                _fmt(c.elasticity, 3),
                f"{c.share:.1%}",
                c.source,
            ]
        )
    return rows


RANKING_HEADER = ["rank", "input", "value", "sigma", "dy/dp", "elasticity", "variance share", "sigma from"]


def table(header: list[str], rows: list[list[str]], markdown: bool = False) -> str:
    """A column-aligned text table, or a Markdown table."""
    if markdown:
        lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
        return "\n".join(lines)
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(header)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths)).rstrip()]
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
    return "\n".join(lines)


def ranking_text(result: UncertaintyResult, output: str, top: int | None = None, markdown: bool = False) -> str:
    contributions = [c for c in result.contributions(output) if c.derivative != 0]
    lines = [output_header(result, output), ""]
    lines.append(table(RANKING_HEADER, ranking_rows(contributions, output, top), markdown))
    leader = next((c for c in contributions if c.share > 0), None)
    if leader is not None:
        lines += [
            "",
            f"Measurement that matters most: {leader.name} ({names.describe(leader.name)[0]}), "
            f"{leader.share:.1%} of the first-order variance.",
        ]
    return "\n".join(lines)


def comparison_rows(comparisons: list[Comparison]) -> list[list[str]]:
    return [
        [
            c.name,
            _fmt(c.value, 5),
            _fmt(c.first_order, 3),
            _fmt(c.monte_carlo, 3),
            _fmt(c.mc_mean, 5),
            f"{c.relative_difference:+.1%}" if math.isfinite(c.relative_difference) else "-",
            ("> 10 %: " if c.flagged else "") + c.reason,
        ]
        for c in comparisons
    ]


COMPARISON_HEADER = [
    "output",
    "value",
    "first-order sigma",
    "Monte Carlo sigma",
    "Monte Carlo mean",
    "|FO - MC| / MC",
    "verdict",
]


def _print(expr: sp.Expr, latex: bool, symbol_names: dict, full: bool) -> str:
    ops = int(sp.count_ops(expr))
    if ops > PRINT_LIMIT and not full:
        return f"[{ops} operations; --full prints it]"
    if latex:
        return sp.latex(expr, symbol_names=symbol_names)
    return sp.sstr(expr)


def expression_text(expr: SensitivityExpression, value: float | None, latex: bool = False, full: bool = False) -> str:
    """The derivative's steps, the conditions of speeds, and its closed form when small."""
    symbol_names = expr.latex_names()
    lines = []
    eq = " = "
    for node, F in expr.conditions:
        lhs = f"F_{{{names.latex(node)}}}" if latex else f"F[{node}]"
        lines.append(f"{lhs}{eq}{_print(F, latex, symbol_names, full)}    ({node} is a root of F = 0)")
    if expr.conditions:
        lines.append("")
    if expr.closed_form is not None:
        lhs = expr.steps[0][0]
        lhs_text = symbol_names.get(lhs, str(lhs)) if latex else str(lhs)
        lines.append(f"{lhs_text}{eq}{_print(expr.closed_form, latex, symbol_names, full)}")
    else:
        lines.append(
            f"Chain rule, {len(expr.steps)} steps (a closed form in one piece would have about {expr.size} operations):"
        )
        for lhs, rhs in expr.steps:
            lhs_text = symbol_names.get(lhs, str(lhs)) if latex else str(lhs)
            lines.append(f"  {lhs_text}{eq}{_print(rhs, latex, symbol_names, full)}")
    if value is not None:
        lines += ["", f"value at the inputs: {value:.6g} {names.unit(expr.output)}/{names.unit(expr.wrt)}"]
    return "\n".join(lines)
