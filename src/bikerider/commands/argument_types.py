"""Types of command-line arguments: numbers with the range a run can use, checked by argparse.

Each function here is an argparse ``type=``: it turns the text into a value or raises
:class:`argparse.ArgumentTypeError`, which argparse prints as one line naming the option, e.g.
``bikerider sensitivity: error: argument --seed: '-1': expected a random seed: a whole number from 0 to 2**64 - 1``,
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


def whole_number(low: int, high: int, what: str = "a whole number", shown: str | None = None) -> Callable[[str], int]:
    """A type: an integer ``low <= n <= high`` (``shown``: how the range reads in messages)."""
    expected = f"{what} from {shown or f'{low:,} to {high:,}'}"

    def parse(text: str) -> int:
        try:
            value = int(text.strip())
        except ValueError:
            raise _fail(text, expected) from None
        if not low <= value <= high:
            raise _fail(text, expected)
        return value

    parse.__name__ = "whole_number"
    return parse


seed = whole_number(0, MAX_SEED, "a random seed: a whole number", shown="0 to 2**64 - 1")
"""A type: a random seed, a whole number from 0 to 2**64 - 1."""


def report_samples(text: str) -> int:
    """Monte Carlo samples behind the sigmas ``estimate`` and ``benchmark`` report: 0 (first order
    only) or 2 to :data:`MAX_REPORT_SAMPLES` (one sample has no spread)."""
    value = whole_number(0, MAX_REPORT_SAMPLES, "0 (first order only) or a number of samples", "2 to 1,000,000")(text)
    if value == 1:
        raise _fail(text, "0 (first order only) or a number of samples from 2 to 1,000,000")
    return value


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
    "report_samples",
    "seed",
    "speed",
    "whole_number",
]
