"""Errors a user can meet.  Every message names what was wrong, its value and what was expected.

The command line prints ``BikeriderError`` messages without a traceback and exits with status 2.
``docs/errors.md`` lists them all.

The readers report every error of a file at once, not one per run: they check each value and
relation inside :meth:`ErrorCollector.check` and raise :class:`InputErrors` (one message, one line
per error) when more than one went wrong.
"""

from __future__ import annotations

MISSING = "missing"
"""The value shown for a required measurement that was not given."""


class BikeriderError(Exception):
    """Base class of every error bikerider raises on purpose."""


class InputError(BikeriderError, ValueError):
    """A measurement or parameter that cannot be right.

    Parameters
    ----------
    name : str
        The measurement, as the user wrote it (e.g. ``"rear_frame.mass"``).
    value : object
        The value received.
    expected : str
        What would have been acceptable, phrased for the user.
    source : str, optional
        Where the value came from (a file, a file and line).
    """

    def __init__(self, name: str, value: object, expected: str, source: str | None = None):
        self.name, self.value, self.expected, self.source = name, value, expected, source
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{name} = {_show(value)}: expected {expected}")

    def __reduce__(self):
        # rebuilt from its fields, not from ``args`` (the message alone): an error raised in a worker
        # process must reach the parent whole (pickling it by message failed there and stopped the pool)
        return type(self), (self.name, self.value, self.expected, self.source)


class InputErrors(InputError):
    """Several input errors found together: every error of a file, reported at once.

    ``name``, ``value``, ``expected`` and ``source`` are those of the first error (the one a check
    that stops at the first problem would have raised); :attr:`errors` holds them all, in the
    order they were found.
    """

    def __init__(self, errors: list[InputError]):
        flat: list[InputError] = []
        for error in errors:
            flat.extend(error.errors if isinstance(error, InputErrors) else [error])
        if len(flat) < 2:
            raise ValueError("InputErrors needs at least two errors (raise a single one as it is)")
        self.errors = flat
        first = flat[0]
        self.name, self.value, self.expected, self.source = first.name, first.value, first.expected, first.source
        BikeriderError.__init__(self, f"{len(flat)} input errors:\n" + listing(flat))

    def __reduce__(self):
        return type(self), (self.errors,)


MAX_LISTED = 20
"""The most errors a message lists one per line; the rest are counted."""


def listing(errors: list) -> str:
    """The lines of a message listing several errors (at most :data:`MAX_LISTED`, then a count)."""
    lines = [f"  {e}" for e in errors[:MAX_LISTED]]
    if len(errors) > MAX_LISTED:
        lines.append(f"  ... and {len(errors) - MAX_LISTED} more")
    return "\n".join(lines)


class ErrorCollector:
    """Collects the :class:`InputError` of independent checks, to report them all at once.

    Examples
    --------
    >>> errors = ErrorCollector()
    >>> for name, value in (("w", -1.0), ("c", 0.08), ("rR", -0.3)):
    ...     with errors.check():
    ...         if value < 0 and name != "c":
    ...             raise InputError(name, value, "a positive value")
    >>> len(errors.errors)
    2
    >>> errors.raise_any()
    Traceback (most recent call last):
    ...
    bikerider.errors.InputErrors: 2 input errors:
      w = -1: expected a positive value
      rR = -0.3: expected a positive value
    """

    def __init__(self) -> None:
        self.errors: list[InputError] = []

    def __bool__(self) -> bool:
        return bool(self.errors)

    def check(self) -> _Keeper:
        """Run the block; an :class:`InputError` it raises is kept (and the block left), not raised."""
        return _Keeper(self)

    def add(self, error: InputError) -> None:
        """Keep ``error`` (each of them, for :class:`InputErrors`); an error already kept, word for
        word (one value that several checks depend on, such as a pendulum's stiffness), once."""
        seen = {str(e) for e in self.errors}
        for e in error.errors if isinstance(error, InputErrors) else [error]:
            if str(e) not in seen:
                seen.add(str(e))
                self.errors.append(e)

    def raise_any(self) -> None:
        """Raise what was collected: nothing, the one error, or :class:`InputErrors`."""
        if len(self.errors) == 1:
            raise self.errors[0]
        if self.errors:
            raise InputErrors(self.errors)


class _Keeper:
    """The context of :meth:`ErrorCollector.check` (a class, not a generator: readers enter one
    per value they check)."""

    __slots__ = ("collector",)

    def __init__(self, collector: ErrorCollector):
        self.collector = collector

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind: object, error: BaseException | None, traceback: object) -> bool:
        if isinstance(error, InputError):
            self.collector.add(error)
            return True  # kept, not raised
        return False


class ReachError(InputError):
    """A rider whose legs or arms cannot reach the pedals or the handlebar grips."""


class FileFormatError(BikeriderError):
    """A file that cannot be read: names the file and, where known, the line."""

    def __init__(self, path: object, message: str, line: int | None = None):
        self.path, self.line = str(path), line
        where = f"{path}:{line}" if line is not None else f"{path}"
        super().__init__(f"{where}: {message}")
        self.message = message

    def __reduce__(self):
        return type(self), (self.path, self.message, self.line)


class FitError(BikeriderError):
    """A fit (pendulum period, damped oscillation, line intersection) that did not converge or
    whose result cannot be trusted."""


def _show(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if value == MISSING:
        return MISSING
    return repr(value) if isinstance(value, str) else str(value)
