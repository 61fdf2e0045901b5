"""The gap pipeline: input files -> records -> diagnosis -> plan of the next experiment -> report folder.

``bikerider gap`` (:mod:`bikerider.commands.gap`, argparse and printing), the local page's gap jobs
(:mod:`bikerider.app.gap_jobs`) and the documents' scripts run the diagnosis through these functions,
as ``bikerider estimate`` runs :func:`bikerider.estimate.estimate`.  The readers are in ``io``
(:mod:`bikerider.io.gap_model`, :mod:`~bikerider.io.gap_data`, :mod:`~bikerider.io.experiment`), the
diagnosis and the plan in :mod:`bikerider.gap`, the figures in :mod:`bikerider.plotting.gap` and
:mod:`~bikerider.plotting.gap_plan`.
"""

from __future__ import annotations

import functools
import logging
import os
from collections.abc import Iterable
from pathlib import Path

from bikerider import progress
from bikerider.gap.candidates.effects import EFFECT_NAMES, effect
from bikerider.gap.diagnosis.result import Diagnosis, diagnose
from bikerider.gap.measured.multisine import fit_multisines
from bikerider.gap.measured.records import Record, detect_windows, fit_records
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
from bikerider.gap.plan.ranking import NextExperiment, NoExperiment, plan_next
from bikerider.gap.text import markdown
from bikerider.io import gap_data
from bikerider.io.atomic import atomic_write_bytes, atomic_write_text, figure_bytes
from bikerider.io.experiment import (
    ExperimentSettings,
    Window,
    check_record_count,
    cut_record,
    detection_signal,
    read_experiment,
    window_logs,
)
from bikerider.io.gap_model import load_model
from bikerider.io.gap_report import REPORT_NAME, check_report_folder, is_input, linked_figures, refuse_inputs
from bikerider.io.multisine import read_multisines

LOG = logging.getLogger(__name__)

LONG_WORK_ROWS = 1000
"""Eigenvalue rows and records from which the command says, before it starts, that the work takes minutes."""


def load_records(settings: ExperimentSettings, windows: list[Window]) -> list[Record]:
    """The records of an experiment's windows: each log read once, the decays of a ``detect = true``
    file found by :func:`bikerider.gap.measured.records.detect_windows`, every record cut.

    Raises
    ------
    FileFormatError
        A log that cannot be read, a column it does not have, or a window outside it (naming the
        manifest's line).
    """
    records = []
    for window, log in window_logs(settings, windows):
        spans = [(window.start, window.end)]
        if window.detect:
            roll_rate, rate = detection_signal(log, settings)
            spans = detect_windows(roll_rate, rate, settings.detector)
        records += [cut_record(log, start, end, window, settings) for start, end in spans]
    return records


def diagnose_files(
    model: str,
    data: tuple[str, ...] = (),
    experiment: tuple[str, ...] = (),
    *,
    rider: str | None = None,
    rider_rel_sigma: float = 0.0,
    control: str | None = None,
    speed: float | None = None,
    groups: str | None = None,
    effects: str | None = None,
    columns: str | None = None,
    sample_rate: float | None = None,
) -> Diagnosis:
    """Read every input of a diagnosis from its files and run it (the command's work, without output).

    Arguments as the command's options (``groups`` and ``effects`` comma-separated).  The result is
    cached within a process for the same arguments and unchanged input files (the documents and the
    tests of the shipped steer-by-wire experiment share one run; the command itself does not cache).
    """
    files = [model, rider, control, *data, *experiment]
    stamp = tuple(
        (str(f), os.stat(f).st_mtime_ns, os.stat(f).st_size) if f and os.path.isfile(f) else (str(f), None)
        for f in files
    )
    return _cached(
        stamp,
        model,
        tuple(data),
        tuple(experiment),
        rider,
        rider_rel_sigma,
        control,
        speed,
        groups,
        effects,
        columns,
        sample_rate,
    )


@functools.lru_cache(maxsize=2)
def _cached(stamp, *args):
    return run_diagnosis(*args)


def run_diagnosis(
    model, data, experiment, rider, rider_rel_sigma, control, speed, groups, effects, columns, sample_rate
) -> Diagnosis:
    """:func:`diagnose_files` without the cache, its arguments in order (``bikerider gap`` runs this)."""
    progress.begin("reading the inputs")
    loaded = load_model(model, rider, rider_rel_sigma=rider_rel_sigma)
    laws = gap_data.read_control(control) if control is not None else {}
    default_law = next(iter(laws.values())) if len(laws) == 1 else None
    keep = [g.strip() for g in groups.split(",")] if groups else None
    eigen, canonical, records = [], [], []
    for path in data:
        kind = gap_data.detect_kind(path)
        if kind == "eigenvalues":
            eigen.append(gap_data.read_eigenvalues(path, default_law, laws))
        elif kind == "perturbation":
            records.append(gap_data.read_perturbation(path, speed, default_law))
        else:
            canonical.append(gap_data.read_canonical(path, keep))
    windows_of = []
    for path in experiment:
        windows_of.append(read_experiment(path, columns, sample_rate, laws))
    where = ", ".join(map(str, experiment))
    check_record_count(len(records) + sum(len(w) for _, w in windows_of), where)  # before any log is read
    multisines = []
    for path, (settings, windows) in zip(experiment, windows_of):
        records += load_records(settings, windows)
        multisines += read_multisines(path, settings)  # steer-torque multisine runs
    check_record_count(len(records) + len(multisines), where)  # detected decays, multisine runs
    candidates = EFFECT_NAMES
    if effects:
        candidates = tuple(e.strip() for e in effects.split(","))
        for name in candidates:
            effect(name)
    table = EigenvalueData.concatenate(eigen)
    if len(table) + len(records) >= LONG_WORK_ROWS:  # a progress line: the user sees why it takes long
        logging.getLogger("bikerider.gap").warning(
            "%d eigenvalue rows and %d records, candidates %s: each is fitted on every fold, which may take "
            "minutes (fewer --effects are faster)",
            len(table),
            len(records),
            ", ".join(candidates),
        )
    return diagnose(
        loaded,
        table,
        CanonicalData.concatenate(canonical),
        candidates,
        fit_records(records),
        fit_multisines(multisines),
    )


def plan_or_reason(diagnosis: Diagnosis, options: dict) -> tuple[NextExperiment | None, str | None]:
    """``(plan, None)``, or ``(None, why)`` when no experiment can be planned: the diagnosis stands either way.

    ``options`` are the arguments of :func:`bikerider.gap.plan.ranking.plan_next`.
    """
    progress.begin("planning the next experiment")
    try:
        return plan_next(diagnosis, **options), None
    except NoExperiment as exc:  # the plan's own limits (no rivals, nothing predicted); a bad option stays an error
        logging.getLogger("bikerider.gap").info("no next experiment: %s", exc.why)
        return None, exc.why


def write_report(
    diagnosis: Diagnosis,
    folder: str | Path,
    title: str = "Sim-to-real gap diagnosis",
    inputs: Iterable[str | os.PathLike] = (),
    plan: NextExperiment | None = None,
) -> Path:
    """Write ``report.md`` and the figures into ``folder`` (created if needed); return the report path.

    Figures of a previous report in the folder that this one does not link are removed.  With
    ``plan`` (:class:`bikerider.gap.plan.ranking.NextExperiment`), also the next experiment's
    plan and its figure of the rivals' predictions diverging over speed.

    Raises
    ------
    InputError
        A file the report would write or remove is one of ``inputs``
        (:func:`bikerider.io.gap_report.check_report_folder`).
    """
    # matplotlib (about 0.3 s to import) only where figures are drawn: the command without --report draws none
    from bikerider.plotting.gap import figures, pyplot
    from bikerider.plotting.gap_plan import plot_next

    folder = Path(folder)
    check_report_folder(folder, inputs)
    folder.mkdir(parents=True, exist_ok=True)
    result = diagnosis.as_dict()
    previous = linked_figures(folder / REPORT_NAME)
    written = []
    plt = pyplot()
    pictures = list(figures(diagnosis, result))
    if plan is not None:
        result["next"] = plan.as_dict()
        pictures.append(("next.png", "Next experiment: where the rivals disagree", plot_next(plan, result["next"])))
    for name, caption, fig in pictures:
        refuse_inputs([folder / name], inputs)
        try:
            atomic_write_bytes(folder / name, figure_bytes(fig, dpi=110, format="png"))
        finally:
            plt.close(fig)
        written.append((name, caption))
    path = folder / REPORT_NAME
    atomic_write_text(path, markdown(result, title, written))
    stale = [folder / name for name in sorted(previous - {name for name, _ in written})]
    for old in stale:
        if old.is_file() and not is_input(old, inputs):
            old.unlink()
            LOG.info("%s: removed, a figure of the previous report that this one does not have", old)
    return path
