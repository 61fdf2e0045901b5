"""Notes: what bikerider left out of, changed in, or doubts about its inputs.

A reader or check that leaves a value out (an impossible ``IByy`` in a benchmark file), drops an
entry it does not need (``IRzz``, ``yB = 0``), ignores what it cannot use (a sigma on a mass
fraction) or accepts a value that is possible but unusual (``lam_deg = 0.3665``, which looks like
radians) calls :func:`note`.  A note is never silent:

* the command line collects the notes of a run (:func:`collecting`, in ``bikerider.cli``); every
  ``--json`` output carries them as ``"notes"`` (:func:`shown_with`), and the notes no output has
  shown yet are printed on stderr at the end of the run, at default verbosity;
* outside a collection (library use) a note is logged as a WARNING on the ``bikerider`` logger,
  which Python shows even when logging is not configured.

Readers that return notes with their result (``BenchmarkFile.notes``, ``MeasuredReduction.notes``,
``EstimateResult.notes``) keep doing so; :func:`add` appends to such a list and notes in one call.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Iterator
from contextlib import contextmanager

LOG = logging.getLogger("bikerider")


class NoteCollection:
    """The notes of one run, in the order they were made, each once."""

    def __init__(self) -> None:
        self.messages: list[str] = []
        self.shown: set[str] = set()

    def add(self, message: str) -> bool:
        """Keep ``message``; whether it is new to this run."""
        if message in self.messages:
            return False
        self.messages.append(message)
        return True

    def unshown(self) -> list[str]:
        """The notes no output has shown yet."""
        return [m for m in self.messages if m not in self.shown]


_ACTIVE: list[NoteCollection] = []


def note(message: str) -> str:
    """Record ``message`` as a note of the current run (see the module docstring); return it."""
    if _ACTIVE:
        # Printed at the end of the run (or shown in its output): logged here only at DEBUG (``-vv``,
        # when it was made), and once, however often it is made.
        if _ACTIVE[-1].add(message):
            LOG.debug("note: %s", message)
    else:
        LOG.warning("%s", message)
    return message


def add(notes: list[str], message: str) -> None:
    """Append ``message`` to a result's ``notes`` list and :func:`note` it."""
    if message not in notes:
        notes.append(message)
    note(message)


@contextmanager
def collecting() -> Iterator[NoteCollection]:
    """Collect the notes made inside the block (the innermost collection gets them)."""
    collection = NoteCollection()
    _ACTIVE.append(collection)
    try:
        yield collection
    finally:
        _ACTIVE.remove(collection)


def collected() -> list[str]:
    """The notes of the innermost collection so far (empty outside one)."""
    return list(_ACTIVE[-1].messages) if _ACTIVE else []


def shown_with(notes: Iterable[str] = ()) -> list[str]:
    """``notes`` followed by every collected note not among them, all marked as shown: what an
    output that shows notes (a ``--json`` object, a report) should list.

    A collected note that is one of ``notes`` with the file it came from in front
    (``"FILE: note"``, as readers note what they also return) is the same note: listed once."""
    out = list(dict.fromkeys(notes))
    if _ACTIVE:
        collection = _ACTIVE[-1]
        given = tuple(f": {n}" for n in out)
        out += [m for m in collection.messages if m not in out and not m.endswith(given)]
        collection.shown.update(collection.messages)
    return out


__all__ = ["NoteCollection", "add", "collected", "collecting", "note", "shown_with"]
