"""The records beside the tables: each record used becomes an eigenvalue row that every model predicts by
indirect inference, or is left out with its reason; and which candidates the data can try at all."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from bikerider import progress
from bikerider.gap.candidates.effect_model import BENCH_ARGS, EffectModel
from bikerider.gap.candidates.effects import EFFECTS, OBSERVATION_EFFECTS, PARAMETERS
from bikerider.gap.candidates.nominal import GapModelInput
from bikerider.gap.inference.frequency_response import multisine_rows
from bikerider.gap.inference.indirect import RecordRows, RecordSimulator
from bikerider.gap.inference.predict import Predictor
from bikerider.gap.inference.problem import GapProblem
from bikerider.gap.measured.multisine import FrequencyResponseData, MultisineFit
from bikerider.gap.measured.records import RecordFit, eigenvalues_of
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData


@dataclass(frozen=True, eq=False)
class Compared:
    """The data as the diagnosis compares them with the model.

    Attributes
    ----------
    records : list of RecordFit
        Copies of the records given; those left out here carry their reason.
    eigen : EigenvalueData
        The table rows, then one row per record used.
    record_rows : dict
        Index in ``records`` -> its eigenvalue row.
    bias : ndarray
        Each record row's extraction bias under the nominal model (complex).
    record_set : RecordRows or None
        The records' simulator and rows, for the fit problem (``None`` without records used).
    multisines : list of MultisineFit
        Copies of the multisine records given; those left out here carry their reason.
    frf : FrequencyResponseData
        The frequency-response rows of the multisine records used.
    """

    records: list[RecordFit]
    eigen: EigenvalueData
    record_rows: dict[int, int]
    bias: np.ndarray
    record_set: RecordRows | None
    multisines: list[MultisineFit] = field(default_factory=list)
    frf: FrequencyResponseData = field(default_factory=FrequencyResponseData.empty)


def compare_records(model: GapModelInput, eigen: EigenvalueData, records: list[RecordFit] | None) -> Compared:
    """Table rows plus one row per comparable record (others get their reason).

    A record's row holds the eigenvalue its fit found; every model predicts it by indirect
    inference (:mod:`bikerider.gap.inference.indirect`), like with like however far its result lies from the
    model's weave eigenvalue; a record is left out only where the model within its parameters'
    uncertainty shows no weave the fit finds (its prediction is then undefined).
    """
    copies = [replace(f) for f in records or []]  # copies: records left out here get their reason
    used = [k for k, f in enumerate(copies) if f.used]
    if not used:
        return Compared(copies, eigen, {}, np.zeros(0, complex), None)
    progress.begin("comparing the records with the model")
    rows = eigenvalues_of(copies)
    nominal = {k: float(model.parameters.values[k]) for k in BENCH_ARGS + ("g",)}  # type: ignore[arg-type]
    fits = [copies[k] for k in used]
    simulator = RecordSimulator(fits, nominal, model.geometry)
    apparent = simulator.settle()
    matched = Predictor(rows, CanonicalData.empty(), nominal, model.geometry).eigenvalues(
        EffectModel(nominal, model.geometry)
    )
    lost = np.flatnonzero(~np.isfinite(apparent))
    if lost.size:
        # the same fit, started from the model's own weave eigenvalue instead of the record's: far
        # from the model, a start near the record can lead the refit of the model's response astray
        starts = [dict(s) for s in simulator.starts]
        for j in lost:
            for name, p in starts[j].items():
                p = np.array(p, dtype=float)
                p[0], p[1] = matched[j].imag, -matched[j].real
                starts[j][name] = p
        simulator = RecordSimulator(fits, nominal, model.geometry, starts)
        apparent = simulator.settle()
    # Every model predicts a record by the same fit applied to its own response (indirect
    # inference), so how far that lies from the model's weave eigenvalue is no reason to leave a
    # record out.  A record is left out only where the model, within its parameters' uncertainty,
    # predicts nothing the fit finds: its prediction and its uncertainty are then undefined.
    bias = apparent - matched
    reasons: list[str | None] = [
        None
        if np.isfinite(a)
        else (
            "the record fit finds no weave in the model's own response over this window (less than half a "
            "cycle, started from the record's fit and from the model's weave eigenvalue): the model predicts "
            "nothing to compare the record with"
        )
        for a in apparent
    ]
    sigmas = model.parameters.sigmas
    free = [k for k in BENCH_ARGS if sigmas.get(k, 0.0) > 0]
    if free:  # the parameters' uncertainty enters through secants over +-1 sigma: those must exist too
        # the nominal model first, then up and down per parameter: the points (and their arithmetic) of
        # the problem's parameter uncertainty, whose simulation is then this one (RecordSimulator.known)
        values = {k: np.full(2 * len(free) + 1, v) for k, v in nominal.items()}
        for j, k in enumerate(free):
            values[k][2 * j + 1] += sigmas[k]
            values[k][2 * j + 2] -= sigmas[k]
        shifted = simulator.apparent_on_workers(values)[1:]  # the same rows, on every core
        for j in range(len(used)):
            gone = sorted({free[m // 2] for m in np.flatnonzero(~np.isfinite(shifted[:, j]))})
            if reasons[j] is None and gone:
                reasons[j] = (
                    "the record fit finds no weave in the model's response over this window when "
                    f"{', '.join(gone[:3])}{' ...' if len(gone) > 3 else ''} moves by one standard uncertainty: "
                    "the model's prediction of this record is undefined within its parameters' uncertainty"
                )
    keep = []
    for j, k in enumerate(used):
        if reasons[j] is not None:
            copies[k].reason = reasons[j]
            copies[k].estimate = None
        else:
            keep.append(j)
    rows = rows.subset(np.array(keep, dtype=int))
    still = [k for k in used if copies[k].used]
    record_rows = {k: len(eigen) + j for j, k in enumerate(still)}
    record_set = RecordRows(simulator.subset(keep), np.array(list(record_rows.values()), int))
    return Compared(copies, EigenvalueData.concatenate([eigen, rows]), record_rows, bias[keep], record_set)


def compare_multisines(
    model: GapModelInput, multisines: list[MultisineFit] | None
) -> tuple[list[MultisineFit], FrequencyResponseData]:
    """Copies of the multisine records and the frequency-response rows of those used (each record
    compared with a candidate's exact closed-loop frequency response at its lines; those left out here
    get their reason, :func:`bikerider.gap.inference.frequency_response.multisine_rows`)."""
    copies = [replace(f) for f in multisines or []]
    if not any(f.used for f in copies):
        return copies, FrequencyResponseData.empty()
    nominal = {k: float(model.parameters.values[k]) for k in BENCH_ARGS + ("g",)}  # type: ignore[arg-type]
    frf, reasons = multisine_rows(copies, EffectModel(nominal, model.geometry))
    for k, why in reasons.items():
        copies[k].reason = why
    return copies, frf


def time_domain_ready(compared: Compared, problem: GapProblem) -> bool:
    """Whether the records carry a time-domain fit: every eigenvalue from a record (uniformly sampled),
    no canonical entries, and records in two groups or more."""
    used = [f for f in compared.records if f.used]
    if not used or len(compared.record_rows) != len(problem.eigen) or len(problem.predictor.canonical):
        return False
    if len({f.record.group for f in used}) < 2:
        return False
    for f in used:
        steps = np.diff(f.record.time)
        if steps.size == 0 or not np.allclose(steps, steps[0], rtol=1e-6):
            return False
    return True


def not_applicable(effects, model: GapModelInput, compared: Compared, problem: GapProblem) -> dict[str, str]:
    """The candidates among ``effects`` the data cannot try, each with the reason."""
    out = {}
    for e in effects:
        if EFFECTS[e].needs_rider and model.geometry.upper_body is None:
            out[e] = "needs a rider on the bicycle (the model has none)"
        elif e in OBSERVATION_EFFECTS and not (
            np.any(compared.eigen.speed_sensor) or np.any(compared.frf.speed_sensor)
        ):
            out[e] = (
                "needs records whose speed a sensor read during the test (a speed column); "
                "the speeds given are taken as the speeds the bicycle ran at"
            )
        elif EFFECTS[e].needs_records and not time_domain_ready(compared, problem):
            out[e] = (
                "fitted in the time domain: needs every eigenvalue to come from a record "
                "(uniformly sampled) and records in at least two groups"
            )
    if not problem.free and PARAMETERS in effects:
        out[PARAMETERS] = "the model file gives no parameter uncertainties"
    return out
