"""The gap diagnosis of uploaded files, run in a background thread with its progress.

A job takes an upload folder (:mod:`bikerider.app.uploads`) and the names in it of the model, the
manifests (``--experiment``) and data tables (``--data``), and runs the package's own entry point,
:func:`bikerider.diagnose.diagnose_files` (handed to :class:`GapJobs` by ``bikerider serve``:
the page never re-implements the diagnosis), then the next-experiment plan
(:func:`bikerider.gap.plan.ranking.plan_next`, the defaults of ``gap --next``) and the report
folder (:func:`bikerider.diagnose.write_report`, as ``gap --report``).  The diagnosis has no
hook that says how far it is, so the progress is the step it is on (reading and fitting, planning,
writing the report), the seconds since it started and the messages the package logs meanwhile.
One job runs at a time (the machine's cores are the diagnosis's); others wait their turn.
"""

from __future__ import annotations

import io
import logging
import math
import re
import threading
import time
import uuid
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bikerider.app.uploads import UploadFolders
from bikerider.errors import BikeriderError, InputError

LOG = logging.getLogger(__name__)
STEPS = (
    "queued",
    "reading the files and fitting every candidate on every fold",
    "planning the next experiment",
    "writing the report",
    "done",
)
"""The steps a job goes through (``"failed"`` ends it early)."""


def plain(value):
    """JSON-ready: NumPy scalars to Python numbers, non-finite floats to None."""
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return plain(value.tolist())
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


@dataclass
class GapJob:
    """One diagnosis: what it reads, where it is, and what it found."""

    ident: str
    folder: Path
    model: Path
    experiment: list[Path]
    data: list[Path]
    next_plan: bool = True
    step: str = "queued"
    started: float | None = None
    finished: float | None = None
    messages: list[str] = field(default_factory=list)
    error: str | None = None
    summary: str | None = None
    next_text: str | None = None
    result: dict | None = None
    report: Path | None = None
    figures: list[tuple[str, str]] = field(default_factory=list)

    def status(self) -> dict:
        """The page's view of the job."""
        now = self.finished or time.time()
        return {
            "id": self.ident,
            "step": self.step,
            "step_index": STEPS.index(self.step) if self.step in STEPS else None,
            "steps": list(STEPS),
            "elapsed": None if self.started is None else round(now - self.started, 1),
            "messages": self.messages[-20:],
            "error": self.error,
            "summary": self.summary,
            "next": self.next_text,
            "figures": [{"name": n, "caption": c} for n, c in self.figures],
            "result": self.result,
        }


class _JobLog(logging.Handler):
    """The package's log messages made in the job's thread, as the job's progress messages."""

    def __init__(self, job: GapJob) -> None:
        super().__init__(logging.INFO)
        self.job, self.thread = job, threading.get_ident()

    def emit(self, record: logging.LogRecord) -> None:
        if record.thread == self.thread:
            self.job.messages.append(record.getMessage())


class GapJobs:
    """The page's diagnoses.

    Parameters
    ----------
    uploads : UploadFolders
    diagnose : callable
        ``diagnose(model, data, experiment)`` with paths as strings, returning a
        :class:`bikerider.gap.diagnosis.result.Diagnosis` (``bikerider serve`` passes
        :func:`bikerider.diagnose.diagnose_files`).
    """

    def __init__(self, uploads: UploadFolders, diagnose: Callable) -> None:
        self.uploads, self.diagnose = uploads, diagnose
        self.jobs: dict[str, GapJob] = {}
        self._one_at_a_time = threading.Lock()

    def start(self, folder: str, model: str, experiment=(), data=(), next_plan: bool = True) -> GapJob:
        """Check the names and start a job in a new thread.

        Raises
        ------
        InputError
            A name that is not an uploaded file, no model, or neither manifests nor data.
        """
        if not model:
            raise InputError("model", "missing", "the model file among the uploaded files (gap --model)")
        if not experiment and not data:
            raise InputError(
                "--data/--experiment", "missing", "data files (--data) or a manifest of records (--experiment)"
            )
        job = GapJob(
            uuid.uuid4().hex,
            self.uploads.folder(folder),
            self.uploads.path(folder, model),
            [self.uploads.path(folder, name) for name in experiment],
            [self.uploads.path(folder, name) for name in data],
            bool(next_plan),
        )
        self.jobs[job.ident] = job
        threading.Thread(target=self._run, args=(job,), name=f"gap-{job.ident[:8]}", daemon=True).start()
        return job

    def get(self, ident: str) -> GapJob:
        try:
            return self.jobs[ident]
        except KeyError:
            raise InputError("job", ident, "the id of a diagnosis started on this page") from None

    def _run(self, job: GapJob) -> None:
        # The report's figures and text: matplotlib is loaded only when a diagnosis runs.
        from bikerider.diagnose import write_report
        from bikerider.gap.plan.ranking import plan_next
        from bikerider.gap.text import next_text, summary_text
        from bikerider.io.gap_report import linked_figures

        with self._one_at_a_time:
            handler = _JobLog(job)
            logger = logging.getLogger("bikerider")
            logger.addHandler(handler)
            previous = logger.level
            if logger.getEffectiveLevel() > logging.INFO:
                logger.setLevel(logging.INFO)
            job.started = time.time()
            try:
                job.step = STEPS[1]
                diagnosis = self.diagnose(str(job.model), tuple(map(str, job.data)), tuple(map(str, job.experiment)))
                result = diagnosis.as_dict()
                plan = None
                if job.next_plan:
                    job.step = STEPS[2]
                    plan = plan_next(diagnosis)
                    result["next"] = plan.as_dict()
                    job.next_text = next_text(result["next"])
                job.summary = summary_text(result)
                job.step = STEPS[3]
                report = job.folder.parent / f"report-{job.ident}"
                job.report = write_report(diagnosis, report, title=f"Sim-to-real gap: {job.model.name}", plan=plan)
                captions = dict(_captions(job.report))
                job.figures = [(name, captions.get(name, name)) for name in sorted(linked_figures(job.report))]
                job.result = plain({k: result[k] for k in result if k not in ("next",)})
                job.step = STEPS[4]
            except BikeriderError as exc:
                job.error = f"bikerider gap: error: {exc}"
                job.step = "failed"
            except OSError as exc:
                job.error = f"bikerider gap: error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": ")
                job.step = "failed"
            except Exception as exc:  # a bug: the page says so instead of hanging
                LOG.exception("the diagnosis failed")
                job.error = f"bikerider gap: internal error ({type(exc).__name__}: {exc}); please report it"
                job.step = "failed"
            finally:
                job.finished = time.time()
                logger.removeHandler(handler)
                logger.setLevel(previous)

    def figure(self, ident: str, name: str) -> bytes:
        """A PNG figure of a finished job's report."""
        job = self.get(ident)
        if name not in {n for n, _ in job.figures} or job.report is None:
            raise InputError("figure", name, "a figure of the report")
        return (job.report.parent / name).read_bytes()

    def report_zip(self, ident: str) -> bytes:
        """The report folder of a finished job (``report.md`` and its figures) as a zip archive."""
        job = self.get(ident)
        if job.report is None:
            raise InputError("report", ident, "a finished diagnosis")
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
            for path in sorted(job.report.parent.iterdir()):
                if path.is_file():
                    archive.write(path, f"gap_report/{path.name}")
        return buffer.getvalue()


def _captions(report: Path) -> list[tuple[str, str]]:
    """``(figure file, caption)`` of each figure a report links."""
    text = report.read_text(encoding="utf-8")
    return [(m.group(2), m.group(1)) for m in re.finditer(r"!\[([^\]]*)\]\(([^()/\\]+\.png)\)", text)]


__all__ = ["GapJob", "GapJobs", "STEPS", "plain"]
