"""The sim-to-real gap: where a bicycle model departs from measurements, and which unmodelled effect
explains it (``bikerider gap``; docs/gap.md).

The face of the gap's domain; its floors, each importing only those below it:

==========================  ===========================================================================
:mod:`.measured`            what was measured: eigenvalue and canonical tables, records and their
                            repair, the modes extracted from them, control laws
:mod:`.candidates`          the physics on trial: the registry of effects, the nominal model input,
                            the effect model
:mod:`.inference`           fitting a candidate: the fit problem, predictions, indirect and time-domain
                            fits, low-rank tests
:mod:`.diagnosis`           the diagnosis: statistics, then where, whether, which and the selection
                            (:class:`Diagnosis`)
:mod:`.plan`                the next experiment (:class:`NextExperiment`) and its sweeps
:mod:`.text`                the summary, the plan and ``report.md`` as text (no matplotlib)
==========================  ===========================================================================

Reading files is :mod:`bikerider.io` (``io.gap_model``, ``io.gap_data``, ``io.experiment``), the figures
:mod:`bikerider.plotting.gap` and :mod:`bikerider.plotting.gap_plan`, the whole pipeline from files to
a report folder :mod:`bikerider.diagnose` (also ``bikerider.diagnose_files``).  No module under
``gap/`` imports this face.
"""

from __future__ import annotations

import importlib

_EXPORTS = {  # public name: the module that defines it
    "diagnose": "bikerider.gap.diagnosis.result",
    "Diagnosis": "bikerider.gap.diagnosis.result",
    "plan_next": "bikerider.gap.plan.ranking",
    "NextExperiment": "bikerider.gap.plan.ranking",
    "NoExperiment": "bikerider.gap.plan.ranking",
    "EFFECTS": "bikerider.gap.candidates.effects",
    "EFFECT_NAMES": "bikerider.gap.candidates.effects",
    "Effect": "bikerider.gap.candidates.effects",
    "effect": "bikerider.gap.candidates.effects",
    "EffectModel": "bikerider.gap.candidates.effect_model",
    "RiderGeometry": "bikerider.gap.candidates.effect_model",
    "BENCH_ARGS": "bikerider.gap.candidates.effect_model",
    "GapModelInput": "bikerider.gap.candidates.nominal",
    "EffectFit": "bikerider.gap.inference.problem",
    "Record": "bikerider.gap.measured.records",
    "RecordFit": "bikerider.gap.measured.records",
    "fit_records": "bikerider.gap.measured.records",
    "MultisineRecord": "bikerider.gap.measured.multisine",
    "MultisineFit": "bikerider.gap.measured.multisine",
    "fit_multisine": "bikerider.gap.measured.multisine",
    "fit_multisines": "bikerider.gap.measured.multisine",
    "EigenvalueData": "bikerider.gap.measured.tables",
    "CanonicalData": "bikerider.gap.measured.tables",
    "summary_text": "bikerider.gap.text",
    "next_text": "bikerider.gap.text",
    "markdown": "bikerider.gap.text",
}
__all__ = list(_EXPORTS)


def __getattr__(name: str):
    # The public names load their modules on first use, as bikerider's own face does: a reader that
    # imports one floor (io.gap_data imports gap.measured.tables) does not load the diagnosis and SciPy.
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'bikerider.gap' has no attribute {name!r}")
