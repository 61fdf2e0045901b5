"""bikerider: physical properties of a bicycle and its seated rider, the linear Whipple model they
give, and where real bicycles depart from it.

The method is that of Moore, Hubbard, Kooijman and Schwab (2009), "A method for estimating physical
properties of a combined bicycle and rider"; the model is the benchmark of Meijaard et al. (2007).

Public API
----------
Estimate (:mod:`bikerider.estimate`)
    :func:`estimate_default`, :func:`estimate_from_files`, :func:`estimate`,
    :func:`estimate_uncertainty`, :class:`EstimateResult`.
Model (:mod:`bikerider.benchmark`)
    :class:`BenchmarkParameters`, :data:`BENCHMARK_NAMES`, :class:`WhippleModel`,
    :class:`CriticalSpeeds`, :class:`ModalEigenvalues`; :func:`named` (the shipped parameter sets,
    :mod:`bikerider.shipped`).
Dynamics toolbox (:mod:`bikerider.benchmark`, ``docs/dynamics.md``); one bicycle or a batch
    :func:`state_space` (:class:`StateSpace`, :class:`LateralForce`), :func:`mode_shapes`
    (:class:`ModeShapes`), :func:`simulate` (:class:`Simulation`), :func:`frequency_response`
    (:class:`FrequencyResponse`), :func:`stability_batch` (the stable intervals of many bicycles;
    one bicycle's: ``WhippleModel.stability()``), :func:`sweep` and :func:`stability_map`
    (:class:`Sweep`); :func:`closed_loop` (:class:`ClosedLoopModel`: a :class:`ControlLaw` of
    :class:`GainSchedule` gains on the steer torque applied to a model), :func:`lqr_gains`,
    :func:`lqr_law`.  Figures: :mod:`bikerider.plotting`.
Design spaces at scale (:mod:`bikerider.design`, ``docs/design_space.md``)
    :func:`design_grid`, :func:`random_designs`, :func:`design_monte_carlo` (a
    :class:`DesignSpace`), :func:`explore` (run one, chunked and resumable, into a store),
    :func:`open_store`.
Bicycle and rider (:mod:`bikerider.bicycle`, :mod:`bikerider.rider`)
    :class:`BicycleBodies`, :class:`RiderMeasurements`, :class:`LumpedRider`,
    :func:`bicycle_benchmark_parameters`, :func:`merge_rider`, :func:`reduce_measured`.
Files (here, from the modules of :mod:`bikerider.io`)
    :func:`load_bicycle_file` (any bicycle file, :mod:`bikerider.io.bicycleparameters`),
    :func:`load_benchmark_parameters` (:mod:`bikerider.io.benchmark_file`),
    :func:`read_measured_file`, :func:`read_lumped_rider`, :func:`load_bicycle_toml`,
    :func:`load_rider_toml`, :func:`paper_inputs`; written: :mod:`bikerider.io.export`
    (``parameters_to_toml``, ``parameters_to_benchmark_txt``, ``parameters_to_json``, eigenvalues
    as CSV).
Uncertainty (:mod:`bikerider.uncertainty`, :mod:`bikerider.engine`)
    :func:`propagate` (first-order sigmas of the estimate chain), :func:`monte_carlo`,
    :class:`UncertaintyResult`.
Sim-to-real gap (:mod:`bikerider.gap`, its face; ``docs/gap.md``)
    :func:`diagnose_files` (the pipeline of :mod:`bikerider.diagnose`: files to a diagnosis),
    :func:`write_gap_report`; readers :func:`load_gap_model`, :func:`read_gap_eigenvalues`,
    :func:`read_gap_perturbation`; figures :func:`gap_effect_figure`, :func:`gap_plan_figure`.  The
    diagnosis itself (``diagnose``, ``Diagnosis``, ``plan_next``, ``EFFECTS``, ``fit_records``, ...)
    is imported from :mod:`bikerider.gap`.
Values and errors
    :class:`Quantity`, :class:`BikeriderError`, :class:`InputError`, :class:`FileFormatError`,
    :class:`FitError`.

The generated NumPy functions are ``bikerider.generated.<module>``; ``bikerider.generated.manifest``
says what each takes and returns.

Layout
------
``bikerider.engine``      the one uncertainty engine: stages from the manifest, chains, sigmas
``bikerider.bicycle``     bicycle measurements and their reductions (pendulums, Measured files)
``bikerider.rider``       the rider model (grid points, closures, segments)
``bikerider.benchmark``   the 25 benchmark parameters, the Whipple model and its dynamics toolbox
``bikerider.design``      design spaces: grids and random designs over millions of bicycles
``bikerider.uncertainty`` the estimate chain's sensitivities, propagation and Monte Carlo
``bikerider.io``          input files (TOML, JSON, BicycleParameters text files) and export
``bikerider.estimate``    the whole pipeline, measurements to model
``bikerider.cli``         the ``bikerider`` command line
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

_EXPORTS = {  # public name: "module" (the same name there) or "module:name"
    "estimate": "bikerider.estimate",
    "estimate_default": "bikerider.estimate",
    "estimate_from_files": "bikerider.estimate",
    "estimate_uncertainty": "bikerider.estimate",
    "EstimateResult": "bikerider.estimate",
    "BENCHMARK_NAMES": "bikerider.benchmark",
    "BenchmarkParameters": "bikerider.benchmark",
    "CriticalSpeeds": "bikerider.benchmark",
    "ModalEigenvalues": "bikerider.benchmark",
    "WhippleModel": "bikerider.benchmark",
    "named": "bikerider.shipped",
    "state_space": "bikerider.benchmark.state_space",
    "StateSpace": "bikerider.benchmark.state_space",
    "LateralForce": "bikerider.benchmark.state_space",
    "mode_shapes": "bikerider.benchmark.mode_shapes",
    "ModeShapes": "bikerider.benchmark.mode_shapes",
    "simulate": "bikerider.benchmark.simulation",
    "Simulation": "bikerider.benchmark.simulation",
    "frequency_response": "bikerider.benchmark.frequency_response",
    "FrequencyResponse": "bikerider.benchmark.frequency_response",
    "stability_batch": "bikerider.benchmark.stability",
    "StabilityBatch": "bikerider.benchmark.stability",
    "closed_loop": "bikerider.benchmark.closed_loop",
    "ClosedLoopModel": "bikerider.benchmark.closed_loop",
    "lqr_gains": "bikerider.benchmark.closed_loop",
    "lqr_law": "bikerider.benchmark.closed_loop",
    "ControlLaw": "bikerider.benchmark.control",
    "GainSchedule": "bikerider.benchmark.control",
    "sweep": "bikerider.benchmark.sweep",
    "stability_map": "bikerider.benchmark.sweep",
    "Sweep": "bikerider.benchmark.sweep",
    "design_grid": "bikerider.design:grid",
    "random_designs": "bikerider.design",
    "design_monte_carlo": "bikerider.design:monte_carlo",
    "DesignSpace": "bikerider.design",
    "explore": "bikerider.design",
    "open_store": "bikerider.design",
    "BicycleBodies": "bikerider.bicycle.bodies",
    "RiderMeasurements": "bikerider.rider.measurements",
    "LumpedRider": "bikerider.bicycle.to_benchmark",
    "bicycle_benchmark_parameters": "bikerider.bicycle.to_benchmark",
    "merge_rider": "bikerider.bicycle.to_benchmark",
    "reduce_measured": "bikerider.bicycle.raw_measurements",
    "load_bicycle_file": "bikerider.io.bicycleparameters",
    "read_measured_file": "bikerider.io.bicycleparameters",
    "read_lumped_rider": "bikerider.io.bicycleparameters",
    "load_benchmark_parameters": "bikerider.io.benchmark_file",
    "load_bicycle_toml": "bikerider.io.toml_input",
    "load_rider_toml": "bikerider.io.toml_input",
    "paper_inputs": "bikerider.io.chain_inputs",
    "propagate": "bikerider.uncertainty",
    "monte_carlo": "bikerider.uncertainty",
    "UncertaintyResult": "bikerider.uncertainty",
    "diagnose_files": "bikerider.diagnose",
    "write_gap_report": "bikerider.diagnose:write_report",
    "load_gap_model": "bikerider.io.gap_model:load_model",
    "read_gap_eigenvalues": "bikerider.io.gap_data:read_eigenvalues",
    "read_gap_perturbation": "bikerider.io.gap_data:read_perturbation",
    "gap_effect_figure": "bikerider.plotting.gap:plot_effect",
    "gap_plan_figure": "bikerider.plotting.gap_plan:plot_next",
    "Quantity": "bikerider.quantity",
    "BikeriderError": "bikerider.errors",
    "InputError": "bikerider.errors",
    "FileFormatError": "bikerider.errors",
    "FitError": "bikerider.errors",
}
__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str):
    # The public names load their modules on first use: `import bikerider` (which `bikerider --help`
    # does) stays at 0.06 s instead of the 0.4 s NumPy and the generated code take (python -X importtime).
    if name in _EXPORTS:
        module, _, attribute = _EXPORTS[name].partition(":")
        value = getattr(importlib.import_module(module), attribute or name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'bikerider' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
