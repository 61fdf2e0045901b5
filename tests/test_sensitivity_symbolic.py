"""Symbolic sensitivities: hand-derived closed forms, and agreement with the numeric Jacobian."""

from __future__ import annotations

import pytest
import sympy as sp

from bikerider.errors import InputError
from bikerider.io.chain_inputs import paper_inputs
from bikerider.uncertainty.chain import Chain, prepare_values
from bikerider.uncertainty.propagation import propagate
from bikerider.uncertainty.symbolic import node_symbol, sensitivity_expression

S = node_symbol


@pytest.fixture(scope="module")
def paper():
    q = paper_inputs().quantities
    values = prepare_values(q)
    point = {k: float(v) for k, v in Chain(values).evaluate(values).items()}
    return q, point, propagate(q)


def test_hand_derived_closed_forms(paper, benchmark_values):
    q, _, _ = paper
    # Meijaard et al. (2007) eq. A4: I_Txx contains m_H z_H^2, and M_phiphi = I_Txx.
    assert sensitivity_expression("M_phiphi", "mH", benchmark_values).closed_form == S("zH", False) ** 2
    # Eq. 16: x_B = (m_Bf x_Bf + m_Br x_Br) / m_B, written back in terms of m_B (Eq. 15).
    e = sensitivity_expression("xB", "xBf", q).closed_form
    assert e == S("mBf", True) / S("mB", True)
    # Eq. 1: J = k T^2 / (4 pi^2), so dI_Fxx/dT = k T / (2 pi^2).
    e = sensitivity_expression("IFxx", "T_Fxx", q).closed_form
    assert sp.simplify(e - S("k_t", True) * S("T_Fxx", True) / (2 * sp.pi**2)) == 0
    # Meijaard et al. (2007) eq. A19: K2_phidelta contains S_F cos(lam)/w with S_F = I_Fyy/r_F.
    e = sensitivity_expression("K2_phidelta", "IFyy", benchmark_values).closed_form
    assert sp.simplify(e - sp.cos(S("lam", False)) / (S("rF", True) * S("w", True))) == 0
    # lam = pi/2 - lam_ht
    assert sensitivity_expression("lam", "lam_ht", q).closed_form == -1


@pytest.mark.parametrize(
    "output, wrt",
    [
        ("v_capsize", "T_Fyy"),
        ("v_weave", "IHxz"),
        ("IBfxz", "alpha_Bf2"),
        ("IBrxx", "l_to"),
        ("zB", "lam_fl"),
        ("v_capsize", "mBr"),
        ("xBr", "l_ul"),
        ("M_phidelta", "k_t"),
    ],
)
def test_symbolic_steps_equal_the_numeric_jacobian(paper, output, wrt):
    q, point, result = paper
    expr = sensitivity_expression(output, wrt, q)
    assert expr.evaluate(point) == pytest.approx(result.derivative(output, wrt), rel=1e-9, abs=1e-14)
    if expr.closed_form is not None and output != "v_weave":  # weave also needs a0..a4 at v_weave
        values = {s: point[s.name] for s in expr.closed_form.free_symbols if s.name in point}
        assert float(expr.closed_form.xreplace(values).evalf()) == pytest.approx(
            result.derivative(output, wrt), rel=1e-9
        )


def test_speed_conditions_are_reported(paper):
    q, _, _ = paper
    expr = sensitivity_expression("weave_speed", "T_Fyy", q)
    assert expr.output == "v_weave" and [n for n, _ in expr.conditions] == ["v_weave"]
    a = [S(f"a{k}", False) for k in range(5)]
    condition = expr.conditions[0][1]
    v = [s for s in condition.free_symbols if s.name == "v_weave"][0]
    # third Hurwitz determinant over v^2 (derive/sensitivities.py)
    assert sp.simplify(condition - (a[3] * a[2] * a[1] - a[4] * a[1] ** 2 - a[0] * a[3] ** 2) / v**2) == 0


def test_no_dependence_is_zero_and_latex_uses_table_names(paper):
    q, _, _ = paper
    assert sensitivity_expression("IFyy", "l_st", q).closed_form == 0
    expr = sensitivity_expression("M_phiphi", "mH", q)
    text = sp.latex(expr.closed_form, symbol_names=expr.latex_names())
    assert text == "z_H^{2}" or "z_{H}" in text


def test_unknown_names_are_errors(paper):
    q, _, _ = paper
    with pytest.raises(InputError, match="OUTPUT = 'weave_sped'"):
        sensitivity_expression("weave_sped", "mH", q)
    with pytest.raises(InputError, match="--wrt = 'mHH'"):
        sensitivity_expression("weave_speed", "mHH", q)
