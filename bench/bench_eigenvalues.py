"""Item 1: eigenvalues of one bicycle at 1000 speeds.

The bicycle is BicycleParameters' Browser with rider Jason (its nominal benchmark parameters, so
both tools solve the same model); without the baseline, bikerider's own reduction of the same
files.  Measured:

* bikerider: ``bikerider.benchmark.quartic.eigenvalues_from_polynomial`` - generated
  characteristic coefficients, closed-form quartic, mode labels;
* bikerider ``WhippleModel.eigenvalues`` as it is today (state matrices, ``eigvals``, labels);
* BicycleParameters ``Bicycle.eig(speeds)`` (in its own environment; it also returns eigenvectors,
  which is what it offers);
* NumPy: ``numpy.linalg.eigvals`` on the stacked ``(1000, 4, 4)`` state matrices (built by the
  generated ``state_matrix``, included);
* SymPy: the state-matrix entries of ``derive.benchmark_model.state_matrix()`` lambdified without
  common-subexpression elimination, stacked, then ``eigvals``.
"""

from __future__ import annotations

import numpy as np
from common import Context, Row, fmt_time, measure_together, ratio_text

SPEEDS = 1000
GOAL_BP, GOAL_NUMPY, GOAL_ACCURACY = 30.0, 3.0, 1e-10


def bicycle_parameters(ctx: Context):
    """Browser + Jason as BenchmarkParameters: BicycleParameters' values, else bikerider's reduction."""
    from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters

    result = ctx.bp("raw", repeats=15)
    if "error" not in result:
        values = {k: v[0] for k, v in result["parameters"].items() if k in BENCHMARK_NAMES}
        return BenchmarkParameters.from_mapping(
            values, source="BicycleParameters Browser + Jason"
        ), "BicycleParameters' values"
    from common import DATA

    from bikerider.io.bicycleparameters import load_measured_bicycle, merge_rider, read_lumped_rider

    bicycle = load_measured_bicycle(DATA / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt")
    rider = read_lumped_rider(DATA / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt")
    return merge_rider(bicycle, rider), "bikerider's reduction"


def lambdified_state_matrix():
    """State-matrix entries lambdified from the derivation, no CSE: ``f(entries, g, v) -> (n, 4, 4)``."""
    import sympy as sp

    from derive import benchmark_model
    from derive.symbols import sym

    args = benchmark_model.matrix_entry_args() + [sym("g"), sym("v")]
    A = benchmark_model.state_matrix()
    entries = [sp.lambdify(args, A[i, j], modules="numpy", cse=False) for i in range(4) for j in range(4)]

    def evaluate(values: list, v: np.ndarray) -> np.ndarray:
        out = np.empty(v.shape + (16,))
        for k, f in enumerate(entries):
            out[..., k] = f(*values, v)
        return out.reshape(v.shape + (4, 4))

    return evaluate


def run(ctx: Context) -> list[Row]:
    from bikerider.benchmark import WhippleModel
    from bikerider.benchmark.model import matrix_entries
    from bikerider.benchmark.quartic import eigenvalues_from_polynomial

    params, origin = bicycle_parameters(ctx)
    model = WhippleModel.from_parameters(params)
    speeds = np.linspace(0.0, 10.0, SPEEDS)
    lam = lambdified_state_matrix()
    entries = list(matrix_entries(model.M, model.C1, model.K0, model.K2).values()) + [model.g]
    t = measure_together(
        {
            "ours": lambda: eigenvalues_from_polynomial(model, speeds),
            "current": lambda: model.eigenvalues(speeds),
            "numpy": lambda: np.linalg.eigvals(model.state_matrix(speeds)),
            "sympy": lambda: np.linalg.eigvals(lam(entries, speeds)),
        },
        ctx.repeats,
    )
    ours, current, numpy_t, sympy_t = t["ours"], t["current"], t["numpy"], t["sympy"]

    result = eigenvalues_from_polynomial(model, speeds)
    reference = model.eigenvalues(speeds)
    accuracy = float((np.abs(result.values - reference.values) / np.maximum(1, np.abs(reference.values))).max())
    labels_agree = bool(np.all(result.labels == reference.labels))

    baselines = [
        ("bikerider WhippleModel.eigenvalues (eigvals + labels)", current.text()),
        ("numpy.linalg.eigvals, stacked", numpy_t.text()),
        ("sympy.lambdify (no CSE) state matrix + eigvals", sympy_t.text()),
    ]
    notes = [
        f"model: Browser + Jason, {origin}; {SPEEDS} speeds 0-10 m/s",
        f"max |quartic - eigvals| / max(1, |lambda|) = {accuracy:.1e}; mode labels agree: {labels_agree}",
    ]
    bp = ctx.bp("eig", n=SPEEDS, repeats=ctx.repeats)
    met = numpy_t.median / ours.median >= GOAL_NUMPY and accuracy <= GOAL_ACCURACY
    ratios = [f"{ratio_text(numpy_t.median, ours.median)} vs numpy"]
    if "error" in bp:
        notes.append(bp["error"])
        met = None if met else False
    else:
        baselines.insert(0, ("BicycleParameters Bicycle.eig", f"{fmt_time(bp['seconds'])} (median of {bp['repeats']})"))
        ratios.insert(0, f"{ratio_text(bp['seconds'], ours.median)} vs BicycleParameters")
        met = met and bp["seconds"] / ours.median >= GOAL_BP
        ours_at = eigenvalues_from_polynomial(model, bp["speeds"]).values
        theirs = [np.array([complex(*z) for z in row]) for row in bp["eigenvalues"]]
        gap = max(
            float(np.abs(np.sort_complex(a) - np.sort_complex(b)).max() / max(1, np.abs(b).max()))
            for a, b in zip(ours_at, theirs)
        )
        notes.append(f"agreement with BicycleParameters' eigenvalues at {bp['speeds']} m/s: {gap:.1e} relative")
    ratios.append(f"{ratio_text(current.median, ours.median)} vs eigenvalues()")
    ratios.append(f"{ratio_text(sympy_t.median, ours.median)} vs lambdify")
    return [
        Row(
            "eigenvalues, one bicycle, 1000 speeds",
            f"{ours.text()} (quartic + labels)",
            baselines,
            "; ".join(ratios),
            f">= {GOAL_BP:.0f}x BicycleParameters, >= {GOAL_NUMPY:.0f}x numpy eigvals, "
            f"<= {GOAL_ACCURACY:.0e} vs eigvals",
            met,
            notes,
        )
    ]
