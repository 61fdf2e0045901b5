"""The distribution of the weave and capsize speeds over a sample of designs (``--monte-carlo``,
``--random``): median, central 68 % and 95 % intervals, and the values for a histogram.

Over a Monte Carlo sample of a bicycle's uncertain parameters (:func:`bikerider.design.monte_carlo`)
this is the uncertainty of its critical speeds as the sample gives it, with no assumption of a
normal distribution (the speeds have long upper tails).  A design counts where it is valid and has
the speed (:mod:`bikerider.benchmark.stability`: the weave speed begins, the capsize speed ends its
first self-stable interval; a design never self-stable has its modes' own changes of stability);
how many have none is reported beside.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bikerider.design.store import DesignStore

SPEEDS = ("weave_speed", "capsize_speed")
"""Outputs whose distribution is summarised."""
CHUNK = 1_000_000
"""Designs read at a time."""


@dataclass(frozen=True)
class SpeedDistribution:
    """One speed's distribution over the valid designs of a sample.

    Attributes
    ----------
    name : str
        ``weave_speed`` or ``capsize_speed``.
    values : numpy.ndarray
        The speed [m/s] of every valid design that has one, sorted.
    valid : int
        Valid designs (those without the speed: ``valid - values.size``).
    """

    name: str
    values: np.ndarray
    valid: int

    @property
    def count(self) -> int:
        return int(self.values.size)

    def quantiles(self, probabilities) -> np.ndarray:
        """Quantiles [m/s] (NaN when no design has the speed)."""
        if not self.values.size:
            return np.full(np.shape(probabilities), np.nan)
        return np.quantile(self.values, probabilities)

    @property
    def median(self) -> float:
        return float(self.quantiles(0.5))

    @property
    def central68(self) -> tuple[float, float]:
        """The central 68 % interval (16th to 84th percentile)."""
        lo, hi = self.quantiles([0.16, 0.84])
        return float(lo), float(hi)

    @property
    def central95(self) -> tuple[float, float]:
        """The central 95 % interval (2.5th to 97.5th percentile)."""
        lo, hi = self.quantiles([0.025, 0.975])
        return float(lo), float(hi)

    def as_dict(self) -> dict:
        """JSON-ready (``null`` where no design has the speed)."""

        def num(x: float) -> float | None:
            return float(x) if np.isfinite(x) else None

        return {
            "n": self.count,
            "valid": self.valid,
            "median": num(self.median),
            "central_68": [num(x) for x in self.central68],
            "central_95": [num(x) for x in self.central95],
        }

    def text(self) -> str:
        """One line: ``weave speed: median 5.66 m/s, 68 % within 5.21-6.30, 95 % within ...``."""
        label = self.name.replace("_", " ")
        if not self.values.size:
            return f"{label}: no valid design has one"
        (a, b), (c, d) = self.central68, self.central95
        missing = self.valid - self.count
        tail = f"; {missing:,} of {self.valid:,} valid designs have none" if missing else ""
        return (
            f"{label}: median {self.median:.3f} m/s, 68 % within {a:.3f}-{b:.3f}, 95 % within {c:.3f}-{d:.3f} "
            f"({self.count:,} designs{tail})"
        )


def speed_distributions(store: DesignStore) -> dict[str, SpeedDistribution]:
    """The distribution of each of :data:`SPEEDS` over the store's valid designs, read chunk by chunk."""
    n = store.spec.space.size
    parts: dict[str, list[np.ndarray]] = {name: [] for name in SPEEDS}
    valid = 0
    for start in range(0, n, CHUNK):
        stop = min(n, start + CHUNK)
        ok = np.asarray(store.read("valid", start, stop), dtype=bool)
        valid += int(ok.sum())
        for name in SPEEDS:
            x = np.asarray(store.read(name, start, stop), dtype=float)[ok]
            parts[name].append(x[np.isfinite(x)])
    return {name: SpeedDistribution(name, np.sort(np.concatenate(parts[name])), valid) for name in SPEEDS}


__all__ = ["SPEEDS", "SpeedDistribution", "speed_distributions"]
