"""How far to trust the estimate: closed-form sensitivities and uncertainty propagation.

========================  ==================================================================
``stages``, ``chain``     the estimate chain as stages with generated values and Jacobians
``speeds``                weave and capsize speeds for a whole batch, and their gradients
``propagation``           :func:`propagate`: first-order sigmas of every output, rankings
``montecarlo``            vectorised Monte Carlo check, and why it disagrees where it does
``eigen``                 eigenvalue sensitivities from left and right eigenvectors
``symbolic``              d output / d input as SymPy expressions (exact chain-rule steps)
``inputs``                the paper's measurements with their stated accuracies
``names``, ``text``       node names and units; text and Markdown rendering
========================  ==================================================================

Typical use::

    from bikerider.uncertainty import paper_inputs, propagate
    result = propagate(paper_inputs().quantities)
    result.speeds            # {"weave": sigma, "capsize": sigma} in m/s
    result.contributions("v_capsize")[0].name   # the measurement to redo first
"""
from bikerider.uncertainty.inputs import InputSet, benchmark_inputs, paper_inputs, raw_inputs_from_toml
from bikerider.uncertainty.montecarlo import MonteCarloResult, compare, monte_carlo
from bikerider.uncertainty.propagation import Contribution, UncertaintyResult, propagate


def __getattr__(name: str):
    # SymPy is imported only when symbolic expressions are asked for.
    if name in ("SensitivityExpression", "sensitivity_expression"):
        from bikerider.uncertainty import symbolic

        return getattr(symbolic, name)
    raise AttributeError(f"module 'bikerider.uncertainty' has no attribute {name!r}")


__all__ = [
    "Contribution", "InputSet", "benchmark_inputs", "MonteCarloResult", "SensitivityExpression", "UncertaintyResult",
    "compare", "monte_carlo", "paper_inputs", "propagate", "raw_inputs_from_toml", "sensitivity_expression",
]
