"""Item 2: weave and capsize speeds of one bicycle, without a speed scan.

Measured on the bicycle of item 1 (Browser + Jason):

* bikerider: ``WhippleModel.critical_speeds`` - the closed-form conditions (capsize
  ``det(g K0 + v^2 K2) = 0``, weave: third Hurwitz determinant, quadratics in ``v^2``) from the
  generated plain-float ``critical_speed_polynomials_scalar``;
* bikerider's generated NumPy ``critical_speed_polynomials`` on 0-d arrays with ``numpy.roots``
  (what a batch path costs on one bicycle);
* NumPy scan: ``eigvals`` of the state matrices on a 1000-point grid 0-10 m/s, sign changes
  interpolated linearly (what a user without the closed form does; 0.01 m/s grid);
* BicycleParameters scan: the same with ``Bicycle.eig`` (it has no critical-speed function);
* SymPy: ``derive.benchmark_model.critical_speed_polynomials()`` lambdified without CSE on the
  same scalars, then ``numpy.roots``.
"""

from __future__ import annotations

import numpy as np
from common import Context, Row, fmt_time, measure_together, ratio_text

GOAL_SECONDS = 100e-6
GRID = 1000


def scan(model, speeds: np.ndarray) -> tuple[float | None, float | None]:
    """Weave and capsize speeds from eigenvalues on a grid (linear interpolation of sign changes)."""
    values = np.linalg.eigvals(model.state_matrix(speeds))
    is_complex = np.abs(values.imag) > 1e-9 * np.maximum(1.0, np.abs(values).max(axis=1, keepdims=True))
    weave = np.where(is_complex, values.real, -np.inf).max(axis=1)
    real_max = np.where(~is_complex, values.real, -np.inf).max(axis=1)

    def crossing(v, s):
        change = np.flatnonzero((s[1:] < 0) != (s[:-1] < 0))
        if change.size == 0:
            return None
        i = change[0]
        return float(v[i] + (v[i + 1] - v[i]) * s[i] / (s[i] - s[i + 1]))

    has = np.isfinite(weave)
    v_weave = crossing(speeds[has], weave[has])
    above = speeds > (v_weave or 0.0)
    return v_weave, crossing(speeds[above], real_max[above])


def lambdified_polynomials():
    import sympy as sp

    from derive import benchmark_model
    from derive.symbols import sym

    args = benchmark_model.matrix_entry_args() + [sym("g")]
    polys = benchmark_model.critical_speed_polynomials()
    funcs = {k: sp.lambdify(args, v, modules="numpy", cse=False) for k, v in polys.items()}

    def speeds(values: list) -> tuple[float | None, float | None]:
        capsize = [r.real for r in np.roots(funcs["capsize"](*values)) if abs(r.imag) < 1e-9 and r.real > 0]
        a1, a3 = funcs["a1_over_v"](*values), funcs["a3_over_v"](*values)
        weave = None
        for r in sorted(np.roots(funcs["weave"](*values)), key=lambda z: z.real):
            if abs(r.imag) < 1e-9 and r.real > 0 and np.polyval(a1, r.real) / np.polyval(a3, r.real) > 0:
                weave = float(np.sqrt(r.real))
                break
        return weave, (float(np.sqrt(min(capsize))) if capsize else None)

    return speeds


def run(ctx: Context) -> list[Row]:
    from bench_eigenvalues import bicycle_parameters
    from bikerider.generated import benchmark_model as gen

    from bikerider.benchmark import WhippleModel
    from bikerider.benchmark.model import matrix_entries

    params, origin = bicycle_parameters(ctx)
    model = WhippleModel.from_parameters(params)
    grid = np.linspace(0.0, 10.0, GRID)
    lam = lambdified_polynomials()
    values = [float(x) for x in matrix_entries(model.M, model.C1, model.K0, model.K2).values()] + [model.g]
    entries = matrix_entries(model.M, model.C1, model.K0, model.K2)

    def numpy_polynomials():
        capsize_c, weave_c, _, _ = gen.critical_speed_polynomials(**entries, g=model.g)
        return np.roots(capsize_c[np.abs(capsize_c) > 0]), np.roots(weave_c)

    t = measure_together(
        {
            "ours": lambda: model.critical_speeds(),
            "current": numpy_polynomials,
            "numpy": lambda: scan(model, grid),
            "sympy": lambda: lam(values),
        },
        ctx.repeats,
    )
    ours, current, numpy_t, sympy_t = t["ours"], t["current"], t["numpy"], t["sympy"]

    exact = model.critical_speeds()
    scanned = scan(model, grid)
    notes = [
        f"model: Browser + Jason, {origin}",
        f"bikerider: weave {exact.weave:.10f} m/s, capsize {exact.capsize:.10f} m/s",
        f"numpy scan ({GRID} speeds): weave {scanned[0]:.6f}, capsize {scanned[1]:.6f} m/s",
        f"sympy.lambdify: weave {lam(values)[0]:.10f}, capsize {lam(values)[1]:.10f} m/s",
    ]
    baselines = [
        ("bikerider generated NumPy polynomials on 0-d arrays + np.roots", current.text()),
        (f"numpy eigvals scan, {GRID} speeds", numpy_t.text()),
        ("sympy.lambdify (no CSE) polynomials + np.roots", sympy_t.text()),
    ]
    ratios = [
        f"{ratio_text(numpy_t.median, ours.median)} vs numpy scan",
        f"{ratio_text(current.median, ours.median)} vs NumPy polynomials",
        f"{ratio_text(sympy_t.median, ours.median)} vs lambdify",
    ]
    bp = ctx.bp("scan", n=GRID, repeats=ctx.repeats)
    if "error" in bp:
        notes.append(bp["error"])
    else:
        baselines.insert(
            0,
            (
                f"BicycleParameters Bicycle.eig scan, {GRID} speeds",
                f"{fmt_time(bp['seconds'])} (median of {bp['repeats']})",
            ),
        )
        ratios.insert(0, f"{ratio_text(bp['seconds'], ours.median)} vs BicycleParameters scan")
        notes.append(f"BicycleParameters scan: weave {bp['weave']:.6f}, capsize {bp['capsize']:.6f} m/s")
    return [
        Row(
            "weave and capsize speeds, one bicycle",
            f"{ours.text()} (closed form, floats)",
            baselines,
            "; ".join(ratios),
            f"< {fmt_time(GOAL_SECONDS)}, no speed scan",
            ours.median < GOAL_SECONDS,
            notes,
        )
    ]
