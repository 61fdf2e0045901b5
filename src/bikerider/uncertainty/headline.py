"""The uncertainty a command reports first: Monte Carlo, with first order beside it.

First-order propagation (:func:`~bikerider.uncertainty.propagate`) is exact for a linear chain and
fast, but the critical speeds are not linear in the measurements: on the paper's own inputs the
Monte Carlo sigmas of the weave and capsize speeds are about 13 % and 23 % larger than first order
(the capsize speed's samples are skewed), and near a fully stretched limb the first-order sigmas
grow without bound while the sampled ones stay finite.  So ``estimate`` and ``benchmark`` lead with
the Monte Carlo sigma of :data:`DEFAULT_SAMPLES` independent normal draws of every input that has an
uncertainty (seeded, so a run is reproducible; the whole chain runs vectorised, about 0.05 s for
the paper's bicycle and rider), and print the first-order sigma beside it.

Where the two disagree by more than :data:`DISAGREEMENT` (relative), or first order gives no finite
value, the result says that first order does not hold there.  Samples where a value does not exist
(a limb that cannot reach, a speed that vanishes) are counted and named; the sigma is over the
others.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from bikerider.quantity import Quantity
from bikerider.uncertainty.montecarlo import monte_carlo
from bikerider.uncertainty.propagation import SPEED_NODES, UncertaintyResult

DEFAULT_SAMPLES = 10_000
"""Monte Carlo samples of a default run: the sampling error of a sigma is about 1/sqrt(2 N) = 0.7 %."""
DEFAULT_SEED = 0
DISAGREEMENT = 0.5
"""First order is said not to hold for an output whose first-order sigma differs from the Monte
Carlo one by more than this fraction of it (a factor of 1.5 either way)."""


@dataclass(frozen=True)
class Sigma:
    """One output's standard uncertainty, sampled and first-order.

    Attributes
    ----------
    monte_carlo : float or None
        Sample standard deviation over the samples where the output exists (None: fewer than two).
    first_order : float or None
        None where first order gives no finite value.
    valid : int
        Samples in which the output exists.
    """

    monte_carlo: float | None
    first_order: float | None
    valid: int

    @property
    def first_order_holds(self) -> bool:
        """Whether the first-order sigma agrees with the Monte Carlo one within :data:`DISAGREEMENT`."""
        mc, fo = self.monte_carlo, self.first_order
        if mc is None:
            return fo is not None
        if fo is None:
            return False
        if mc == 0:
            return fo == 0
        return abs(fo - mc) <= DISAGREEMENT * mc

    @property
    def headline(self) -> float | None:
        """The sigma to report first: Monte Carlo where there is one."""
        return self.monte_carlo if self.monte_carlo is not None else self.first_order


@dataclass(frozen=True)
class HeadlineUncertainty:
    """Monte Carlo and first-order sigmas of a run's outputs, with notes on where they part.

    Attributes
    ----------
    samples, seed : int
        The Monte Carlo draw (``samples`` is 0 when no input has an uncertainty).
    sigmas : dict of str to Sigma
        By node name (benchmark parameter names, ``v_weave``, ``v_capsize``).
    failures : dict of str to int
        Samples without a value, by reason (``elbow closure``, ``no weave speed``, ...).
    notes : list of str
        What a reader must know: samples lost, outputs where first order does not hold.
    """

    samples: int
    seed: int
    sigmas: dict[str, Sigma]
    failures: dict[str, int] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    @property
    def speeds(self) -> dict[str, Sigma]:
        """``{"weave": Sigma, "capsize": Sigma}``."""
        return {key: self.sigmas[node] for key, node in SPEED_NODES.items() if node in self.sigmas}

    def as_dict(self) -> dict:
        """JSON-ready: samples, seed, each output's two sigmas, failures, notes."""
        return {
            "method": f"Monte Carlo: {self.samples} independent normal draws of every input with an "
            f"uncertainty (seed {self.seed}); first order beside it",
            "samples": self.samples,
            "seed": self.seed,
            "sigmas": {
                name: {
                    "monte_carlo": s.monte_carlo,
                    "first_order": s.first_order,
                    "first_order_holds": s.first_order_holds,
                    "valid_samples": s.valid,
                }
                for name, s in self.sigmas.items()
            },
            "failures": dict(self.failures),
        }


def headline_uncertainty(
    quantities: Mapping[str, Quantity],
    first_order: UncertaintyResult,
    outputs: Sequence[str] | None = None,
    samples: int = DEFAULT_SAMPLES,
    seed: int = DEFAULT_SEED,
) -> HeadlineUncertainty:
    """Monte Carlo sigmas of ``outputs`` beside the first-order ones of ``first_order``.

    Parameters
    ----------
    quantities : mapping of str to Quantity
        The chain inputs ``first_order`` was propagated from.
    first_order : UncertaintyResult
    outputs : sequence of str, optional
        Nodes to sample (default: the two critical speeds and every computed benchmark parameter).
    samples : int
        Monte Carlo draws; 0 gives first order alone.
    seed : int

    Returns
    -------
    HeadlineUncertainty
    """
    if outputs is None:
        computed = [n for n in first_order.output_names if n not in first_order.input_names]
        outputs = [n for n in computed if n in first_order.benchmark or n in SPEED_NODES.values()]
    # Only values that exist at the inputs (not IByy without the frame's I_yy, not a missing speed).
    outputs = [n for n in outputs if first_order.values.get(n) is not None]
    varied = any(q.sigma > 0 for q in quantities.values())
    if samples < 2 or not varied:
        sigmas = {n: Sigma(None, first_order.sigmas.get(n), 0) for n in outputs}
        return HeadlineUncertainty(0, seed, sigmas)
    mc = monte_carlo(quantities, samples, outputs=list(outputs), seed=seed)
    sigmas = {}
    for name in outputs:
        sd = mc.std[name]
        sigmas[name] = Sigma(sd if math.isfinite(sd) else None, first_order.sigmas.get(name), mc.valid[name])
    result = HeadlineUncertainty(samples, seed, sigmas, dict(mc.failures))
    result.notes.extend(_notes(result, first_order))
    return result


def _notes(result: HeadlineUncertainty, first_order: UncertaintyResult) -> list[str]:
    notes = []
    missing = {name: result.samples - s.valid for name, s in result.sigmas.items() if s.valid < result.samples}
    if missing:
        causes = ", ".join(f"{reason} {count}" for reason, count in result.failures.items())
        worst = max(missing.values())
        notes.append(
            f"{worst} of {result.samples} Monte Carlo samples ({worst / result.samples:.1%}) give no value "
            f"({causes or 'the value does not exist there'}): within the inputs' uncertainty the bicycle and "
            "rider can leave the region where the model exists; the sigmas are over the other samples"
        )
    # Outputs without a first-order sigma are explained where it was dropped (e.g. a straight limb).
    broken = [
        n
        for n, s in result.sigmas.items()
        if not s.first_order_holds and s.monte_carlo is not None and s.first_order is not None
    ]
    if broken:
        shown = ", ".join(_shown(n, result.sigmas[n]) for n in broken[:6]) + (", ..." if len(broken) > 6 else "")
        notes.append(
            f"first order does not hold for {shown} (first-order against Monte Carlo sigma): the chain is "
            "not linear over the inputs' uncertainty here; the Monte Carlo sigma is the one given"
        )
    return notes


def _shown(name: str, s: Sigma) -> str:
    label = {node: f"the {key} speed" for key, node in SPEED_NODES.items()}.get(name, name)
    return f"{label} ({s.first_order:.3g} against {s.monte_carlo:.3g})"


__all__ = ["DEFAULT_SAMPLES", "DEFAULT_SEED", "DISAGREEMENT", "HeadlineUncertainty", "Sigma", "headline_uncertainty"]
