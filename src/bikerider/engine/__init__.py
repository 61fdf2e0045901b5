"""The one uncertainty engine: chains of stages, their values, exact Jacobians and first-order sigmas.

Every computation of bikerider that carries an uncertainty runs here: the reduction of a Measured
file, the pendulum reductions of the project's TOML files, a lumped rider merged into the rear
frame, the estimate chain's sensitivities and its Monte Carlo samples.  Stages come from the
manifest that ``make derive`` writes (``generated/manifest.py``), so the graph the runtime walks is
the one the derivations describe.

================================  ============================================================
:class:`Stage`                    a step: named inputs to named outputs, value and Jacobian
:class:`GeneratedStage`           a stage kind of the manifest bound to node names
:class:`LeastSquaresStage`        more equations than unknowns, solved with an exact Jacobian
:class:`DifferencedStage`         any callable, its Jacobian by central differences
:class:`Chain`                    which stages run, their values (any batch shape), gradients
:func:`first_order`, `propagate`  first-order standard uncertainties of named quantities
================================  ============================================================
"""

from bikerider.engine.chain import Chain
from bikerider.engine.first_order import FirstOrder, first_order, propagate
from bikerider.engine.least_squares import LeastSquaresStage, conditioning_2x2
from bikerider.engine.stage import DifferencedStage, GeneratedStage, Stage, arguments, generated_function

__all__ = [
    "Chain",
    "DifferencedStage",
    "FirstOrder",
    "GeneratedStage",
    "LeastSquaresStage",
    "Stage",
    "arguments",
    "conditioning_2x2",
    "first_order",
    "generated_function",
    "propagate",
]
