"""Types of command-line arguments: numbers with the range a run can use, checked by argparse.

Each function here is an argparse ``type=``: it turns the text into a value or raises
:class:`argparse.ArgumentTypeError`, which argparse prints as one line naming the option, e.g.
``bikerider sensitivity: error: argument --seed: '-1': expected a whole number from 0 to 2**64 - 1``,
and exits with status 2.  The limits describe what cannot work, not what is unusual:

* a speed is finite, at least 0 and below the speed of light (:data:`SPEED_OF_LIGHT`): the
  Newtonian Whipple model means nothing beyond it, and every speed below it keeps ``v^2`` and the
  state matrices far inside floating point;
* a count of samples or designs is a whole number within a range the run can finish in memory
  and time (:data:`MAX_MONTE_CARLO` for ``sensitivity --monte-carlo``);
* a random seed is what NumPy's generators take, a whole number from 0 to 2**64 - 1.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

from bikerider.quantity import SPEED_OF_LIGHT

MAX_SEED = 2**64 - 1
"""The largest seed accepted (NumPy's SeedSequence takes any non-negative integer; 64 bits is plenty)."""

MAX_MONTE_CARLO = 10_000_000
"""Samples of ``sensitivity --monte-carlo``: about 35 s and 80 MB per output on one core.  The
sampling error of a standard deviation from N samples is about 1/sqrt(2N) of it: 0.02 % here."""

MAX_REPORT_SAMPLES = 1_000_000
"""Samples behind the sigmas ``estimate`` and ``benchmark`` report (every sampled output is kept for
its percentiles; ``bikerider.uncertainty.headline.MAX_SAMPLES``, which a test holds equal)."""


def _fail(text: str, expected: str) -> argparse.ArgumentTypeError:
    return argparse.ArgumentTypeError(f"{text!r}: expected {expected}")


def whole_number(low: int, high: int, what: str = "a whole number") -> Callable[[str], int]:
    """A type: an integer ``low <= n <= high``."""

    def parse(text: str) -> int:
        expected = f"{what} from {low:,} to {high:,}"
        try:
            value = int(text.strip())
        except ValueError:
            raise _fail(text, expected) from None
        if not low <= value <= high:
            raise _fail(text, expected)
        return value

    parse.__name__ = "whole_number"
    return parse


def seed(text: str) -> int:
    """A random seed: a whole number from 0 to 2**64 - 1."""
    try:
        value = int(text.strip())
    except ValueError:
        raise _fail(text, "a whole number from 0 to 2**64 - 1 (a random seed)") from None
    if not 0 <= value <= MAX_SEED:
        raise _fail(text, "a whole number from 0 to 2**64 - 1 (a random seed)")
    return value


def number(low: float, high: float, what: str = "a number", unit: str = "") -> Callable[[str], float]:
    """A type: a finite float ``low <= x <= high``."""

    def parse(text: str) -> float:
        shown = f" {unit}" if unit else ""
        expected = f"{what} from {low:g} to {high:g}{shown}"
        try:
            value = float(text)
        except ValueError:
            raise _fail(text, expected) from None
        if not (math.isfinite(value) and low <= value <= high):
            raise _fail(text, expected)
        return value

    parse.__name__ = "number"
    return parse


def speed(text: str) -> float:
    """A forward speed in m/s: finite, at least 0, below the speed of light."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0 <= value < SPEED_OF_LIGHT):
        raise _fail(text, "a speed in m/s, at least 0 and below the speed of light (2.998e8 m/s)")
    return value


__all__ = [
    "MAX_MONTE_CARLO",
    "MAX_REPORT_SAMPLES",
    "MAX_SEED",
    "SPEED_OF_LIGHT",
    "number",
    "seed",
    "speed",
    "whole_number",
]
