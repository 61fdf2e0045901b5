"""Progress of long work on standard error: a bar with rate and time left, or a line per stage.

:class:`Progress` is one counted task (designs of a sweep, records, fold fits): on a terminal the
bar is redrawn in place at most :data:`INTERVAL` seconds apart; otherwise (a log file, CI) a line is
printed every :data:`LOG_INTERVAL` seconds.  ``quiet`` prints nothing.

Work done in stages deep inside a computation (the gap diagnosis: records, candidates, pairs, the
plan) reports through the module functions :func:`begin`, :func:`advance` and :func:`end`, which do
nothing unless a command has switched reporting on with :func:`reporting`.  The computation thus
needs no progress argument, and a library caller sees nothing.  :func:`current` says which stage
runs and how far it is (for a message when the user interrupts it).  No dependency.
"""

from __future__ import annotations

import sys
import time
from contextlib import contextmanager

INTERVAL = 0.5
LOG_INTERVAL = 30.0
WIDTH = 24


def format_duration(seconds: float) -> str:
    """``seconds`` as a person reads a clock: ``m:ss``, or ``h:mm:ss`` from an hour on; ``?`` when unknown."""
    if seconds != seconds or seconds == float("inf"):
        return "?"
    seconds = int(round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


class Progress:
    """``update(n)`` after each finished chunk; ``close()`` at the end.

    Parameters
    ----------
    total : int
        Items to do in this run (finished chunks of an earlier run excluded).
    done_before : int
        Items an earlier, interrupted run already finished (shown, not counted in the rate).
    quiet : bool
        Print nothing.
    stream : file, optional
        Default ``sys.stderr``.
    label : str
        What is counted.
    prefix : str
        Text before the bar (the stage).
    """

    def __init__(
        self,
        total: int,
        done_before: int = 0,
        quiet: bool = False,
        stream=None,
        label: str = "designs",
        prefix: str = "",
    ):
        self.total, self.done_before, self.quiet, self.label = total, done_before, quiet, label
        self.prefix = prefix
        self.stream = stream or sys.stderr
        self.done = 0
        self.start = self.last = time.monotonic()
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def text(self) -> str:
        elapsed = max(time.monotonic() - self.start, 1e-9)
        rate = self.done / elapsed
        left = max(self.total - self.done, 0) / rate if rate > 0 else float("inf")
        whole = self.total + self.done_before
        now = min(self.done + self.done_before, whole)
        fraction = now / whole if whole else 1.0
        bar = "#" * int(WIDTH * fraction) + "-" * (WIDTH - int(WIDTH * fraction))
        shown = f"{rate:,.0f}/s" if rate >= 10 else f"{rate:.2g}/s"
        return (
            f"{self.prefix}[{bar}] {now:,}/{whole:,} {self.label} ({100 * fraction:.0f}%), {shown}, "
            f"{format_duration(elapsed)} elapsed, {format_duration(left)} left"
        )

    def update(self, n: int) -> None:
        self.done += n
        if self.quiet:
            return
        now = time.monotonic()
        if self.tty and (now - self.last >= INTERVAL or self.done >= self.total):
            self.stream.write("\r" + self.text())
            self.stream.flush()
            self.last = now
        elif not self.tty and now - self.last >= LOG_INTERVAL:
            self.stream.write(self.text() + "\n")
            self.stream.flush()
            self.last = now

    def note(self, text: str) -> None:
        """A line of its own on the stream (what the run is doing), unless quiet."""
        if not self.quiet:
            self.stream.write(text + "\n")
            self.stream.flush()

    def close(self) -> None:
        if self.quiet or (self.total == 0 and self.done_before):  # a resumed run with nothing left: said already
            return
        self.stream.write(("\r" if self.tty else "") + self.text() + "\n")
        self.stream.flush()


FIRST_LINE = 5.0
"""Seconds a stage runs before its first progress line when standard error is not a terminal."""
SHORT_STAGE = 1.0
"""Stages shorter than this [s] leave no line when standard error is not a terminal (a quick run, or
an error found while reading the inputs, stays a clean message)."""
CLEAR = "\r\x1b[K"
"""Back to the start of the terminal's line and clear it."""


class Reporter:
    """The stages of one command's work, one :class:`Progress` each (see the module docstring).

    On a terminal, a counted stage draws its bar in place (and leaves its final line), an uncounted
    one shows its name until the next stage.  Otherwise (a log file, CI), a stage that runs
    :data:`FIRST_LINE` seconds prints a progress line, then one every :data:`LOG_INTERVAL` seconds,
    and every stage of :data:`SHORT_STAGE` seconds or more a line when it ends.
    """

    def __init__(self, quiet: bool = False, stream=None, name: str = "bikerider"):
        self.quiet, self.name = quiet, name
        self.stream = stream or sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.stage: str | None = None
        self.bar: Progress | None = None
        self.started = time.monotonic()
        self.shown = False  # a progress line of this stage was printed (not a terminal)
        self.transient = False  # an uncounted stage's name is on the terminal's line

    def _write(self, text: str) -> None:
        if not self.quiet:
            self.stream.write(text)
            self.stream.flush()

    def begin(self, stage: str, total: int = 0, unit: str = "") -> None:
        self.end()
        self.stage, self.started, self.shown = stage, time.monotonic(), False
        if total > 0:
            self.bar = Progress(total, quiet=self.quiet or not self.tty, stream=self.stream, label=unit)
            self.bar.prefix = f"{self.name}: {stage} "
            if self.transient:
                self._write(CLEAR)
                self.transient = False
        elif self.tty:
            self._write(f"{CLEAR}{self.name}: {stage} ...")
            self.transient = True

    def advance(self, n: int = 1) -> None:
        if self.bar is None:
            return
        self.bar.update(n)
        if not self.tty and not self.quiet:
            now = time.monotonic()
            due = FIRST_LINE if not self.shown else LOG_INTERVAL
            if now - max(self.started, self.bar.last if self.shown else self.started) >= due:
                self._write(self.bar.text() + "\n")
                self.bar.last, self.shown = now, True

    def end(self) -> None:
        if self.stage is None:
            return
        took = time.monotonic() - self.started
        if self.bar is not None:
            if self.tty:
                self.bar.close()
            elif took >= SHORT_STAGE:
                done = min(self.bar.done, self.bar.total)
                self._write(f"{self.name}: {self.stage}: {done:,} {self.bar.label} done in {format_duration(took)}\n")
        elif not self.tty and took >= SHORT_STAGE:
            self._write(f"{self.name}: {self.stage}: done in {format_duration(took)}\n")
        self.stage, self.bar = None, None

    def finish(self) -> None:
        """End the last stage and clear a terminal line left by an uncounted one."""
        self.end()
        if self.transient:
            self._write(CLEAR)
            self.transient = False

    def where(self) -> str | None:
        """The stage running and how far it is, or ``None``."""
        if self.stage is None:
            return None
        if self.bar is None:
            return self.stage
        return f"{self.stage} ({min(self.bar.done, self.bar.total):,} of {self.bar.total:,} {self.bar.label})"


_ACTIVE: list[Reporter] = []


@contextmanager
def reporting(quiet: bool = False, stream=None, name: str = "bikerider"):
    """Switch stage reporting on for the work inside the ``with`` block; yields the :class:`Reporter`."""
    reporter = Reporter(quiet, stream, name)
    _ACTIVE.append(reporter)
    try:
        yield reporter
        reporter.finish()
    finally:
        _ACTIVE.remove(reporter)


def begin(stage: str, total: int = 0, unit: str = "") -> None:
    """Start a stage of ``total`` items (0: a stage without a count); ends the previous one."""
    if _ACTIVE:
        _ACTIVE[-1].begin(stage, total, unit)


def advance(n: int = 1) -> None:
    """``n`` more items of the current stage done."""
    if _ACTIVE:
        _ACTIVE[-1].advance(n)


def end() -> None:
    """The current stage is done."""
    if _ACTIVE:
        _ACTIVE[-1].end()


def current() -> str | None:
    """The stage running and how far it is (``None`` when reporting is off or between stages)."""
    return _ACTIVE[-1].where() if _ACTIVE else None


__all__ = ["Progress", "Reporter", "advance", "begin", "current", "end", "reporting"]
