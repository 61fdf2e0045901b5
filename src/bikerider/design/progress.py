"""A progress bar on standard error: designs done, rate and time left; no dependency.

On a terminal the bar is redrawn in place at most :data:`INTERVAL` seconds apart; otherwise (a log
file, CI) a line is printed every :data:`LOG_INTERVAL` seconds.  ``quiet`` prints nothing.
"""

from __future__ import annotations

import sys
import time

INTERVAL = 0.5
LOG_INTERVAL = 30.0
WIDTH = 24


def _duration(seconds: float) -> str:
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
        Designs to do in this run (finished chunks of an earlier run excluded).
    done_before : int
        Designs an earlier, interrupted run already finished (shown, not counted in the rate).
    quiet : bool
        Print nothing.
    stream : file, optional
        Default ``sys.stderr``.
    """

    def __init__(self, total: int, done_before: int = 0, quiet: bool = False, stream=None, label: str = "designs"):
        self.total, self.done_before, self.quiet, self.label = total, done_before, quiet, label
        self.stream = stream or sys.stderr
        self.done = 0
        self.start = self.last = time.monotonic()
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def text(self) -> str:
        elapsed = max(time.monotonic() - self.start, 1e-9)
        rate = self.done / elapsed
        left = (self.total - self.done) / rate if rate > 0 else float("inf")
        whole = self.total + self.done_before
        now = self.done + self.done_before
        fraction = now / whole if whole else 1.0
        bar = "#" * int(WIDTH * fraction) + "-" * (WIDTH - int(WIDTH * fraction))
        return (
            f"[{bar}] {now:,}/{whole:,} {self.label} ({100 * fraction:.0f}%), {rate:,.0f}/s, "
            f"{_duration(elapsed)} elapsed, {_duration(left)} left"
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


__all__ = ["Progress"]
