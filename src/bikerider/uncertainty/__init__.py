"""How far to trust the estimate: closed-form sensitivities and uncertainty propagation.

========================  ==================================================================
``stages``, ``chain``     the estimate chain as the manifest's stages, run by ``bikerider.engine``
``speeds``                weave and capsize speeds as a stage, and their implicit gradients
``propagation``           :func:`propagate`: first-order sigmas of every output, rankings
``montecarlo``            vectorised Monte Carlo check, and why it disagrees where it does
``eigen``                 eigenvalue sensitivities from left and right eigenvectors
``symbolic``              d output / d input as SymPy expressions (exact chain-rule steps)
``inputs``                chain inputs with where their sigmas come from
``names``, ``text``       node names and units; text and Markdown rendering
========================  ==================================================================

Typical use::

    from bikerider.io.chain_inputs import paper_inputs
    from bikerider.uncertainty import propagate
    result = propagate(paper_inputs().quantities)
    result.speeds            # {"weave": sigma, "capsize": sigma} in m/s
    result.contributions("v_capsize")[0].name   # the measurement to redo first

``symbolic`` imports SymPy; import it by name when symbolic expressions are wanted.
"""

from bikerider.uncertainty.inputs import InputSet, benchmark_inputs
from bikerider.uncertainty.montecarlo import MonteCarloResult, compare, monte_carlo
from bikerider.uncertainty.propagation import Contribution, UncertaintyResult, propagate

__all__ = [
    "Contribution",
    "InputSet",
    "MonteCarloResult",
    "UncertaintyResult",
    "benchmark_inputs",
    "compare",
    "monte_carlo",
    "propagate",
]
