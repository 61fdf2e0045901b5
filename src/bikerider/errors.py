"""Errors a user can meet.  Every message names what was wrong, its value and what was expected.

The command line prints ``BikeriderError`` messages without a traceback and exits with status 2.
``docs/errors.md`` lists them all.
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


class ReachError(InputError):
    """A rider whose legs or arms cannot reach the pedals or the handlebar grips."""


class FileFormatError(BikeriderError):
    """A file that cannot be read: names the file and, where known, the line."""

    def __init__(self, path: object, message: str, line: int | None = None):
        self.path, self.line = str(path), line
        where = f"{path}:{line}" if line is not None else f"{path}"
        super().__init__(f"{where}: {message}")


class FitError(BikeriderError):
    """A fit (pendulum period, damped oscillation, line intersection) that did not converge or
    whose result cannot be trusted."""


def _show(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if value == MISSING:
        return MISSING
    return repr(value) if isinstance(value, str) else str(value)
