"""Monte Carlo check of the first-order propagation, vectorised over samples.

Every input with a sigma is drawn from a normal distribution (independent draws); the whole
chain - pendulum reductions, grid points, closures, rider, rear body, matrices, critical speeds -
runs on the batch at once through the generated functions, in chunks that bound the memory.
Samples where a value does not exist (a limb closure out of reach, no weave or capsize speed)
are counted and left out of that output's statistics.

:func:`compare` flags outputs whose first-order sigma and Monte Carlo sigma differ by more than a
threshold and says why, from three diagnostics:

* missing samples (a closure at its limit, a speed that disappears);
* curvature: the second-order term of each input at +/- 1 sigma,
  ``c_j = (y(p + s_j) + y(p - s_j) - 2 y(p)) / 2``, whose variance ``2 c_j^2`` first-order
  propagation ignores;
* the skewness of the Monte Carlo samples.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from bikerider.errors import InputError
from bikerider.generated.manifest import STAGES
from bikerider.quantity import Quantity
from bikerider.uncertainty.chain import Chain, prepare_values
from bikerider.uncertainty.propagation import UncertaintyResult

DEFAULT_OUTPUTS = ("v_weave", "v_capsize")
_FAILURES = (
    ("knee closure", STAGES["knee"]["outputs"][0]),
    ("elbow closure", STAGES["elbow"]["outputs"][0]),
    ("no weave speed", "v_weave"),
    ("no capsize speed", "v_capsize"),
)
"""Why a sample has no value: the node that is NaN then."""
MISSING_LIMIT = 0.005
"""A fraction of samples without a value above which it is named as a cause of disagreement."""
CHUNK = 20_000
"""Samples evaluated together; bounds the generated functions' temporaries (about 60 MB)."""


@dataclass(frozen=True)
class MonteCarloResult:
    """Sample statistics of each output.

    Attributes
    ----------
    n : int
        Samples drawn.
    mean, std, skewness : dict of str to float
        Over the samples where the output exists (NaN when fewer than two do).
    valid : dict of str to int
        How many samples gave the output a value.
    failures : dict of str to int
        Reasons samples failed, counted (``knee closure``, ``elbow closure``, ``no weave speed``,
        ``no capsize speed``).
    samples : dict of str to ndarray or None
        The output samples, when kept.
    """

    n: int
    mean: dict[str, float]
    std: dict[str, float]
    skewness: dict[str, float]
    valid: dict[str, int]
    failures: dict[str, int]
    samples: dict[str, np.ndarray] | None = None


def _sigma_inputs(quantities: Mapping[str, Quantity]) -> tuple[dict[str, np.ndarray], list[str]]:
    values = prepare_values(quantities)
    varied = [n for n, q in quantities.items() if isinstance(q, Quantity) and q.sigma > 0]
    return values, varied


def sample_outputs(
    quantities: Mapping[str, Quantity],
    n: int,
    outputs: Sequence[str] = DEFAULT_OUTPUTS,
    seed: int | None = 0,
    chunk: int = CHUNK,
) -> tuple[dict[str, np.ndarray], dict[str, int]]:
    """Draw ``n`` input sets and evaluate ``outputs`` for each; also count failures.

    Raises
    ------
    InputError
        ``n`` below 2, or inputs that cannot give the outputs.
    """
    if not (isinstance(n, (int, np.integer)) and n >= 2):
        raise InputError("--monte-carlo", n, "a whole number of samples, at least 2")
    values, varied = _sigma_inputs(quantities)
    chain = Chain(values)
    chain.require(outputs)
    rng = np.random.default_rng(seed)
    out = {name: np.empty(n) for name in outputs}
    failures = {"knee closure": 0, "elbow closure": 0, "no weave speed": 0, "no capsize speed": 0}
    for start in range(0, n, chunk):
        size = min(chunk, n - start)
        batch = dict(values)
        with np.errstate(over="ignore", invalid="ignore"):  # draws beyond floating point: no value
            for name in varied:
                batch[name] = values[name] + quantities[name].sigma * rng.standard_normal(size)
            nodes = chain.evaluate(batch)
        for name in outputs:
            out[name][start : start + size] = np.broadcast_to(nodes[name], (size,))
        for label, node in _FAILURES:
            if node in nodes:
                failures[label] += int(np.sum(~np.isfinite(np.broadcast_to(nodes[node], (size,)))))
    return out, {k: v for k, v in failures.items() if v}


def monte_carlo(
    quantities: Mapping[str, Quantity],
    n: int,
    outputs: Sequence[str] = DEFAULT_OUTPUTS,
    seed: int | None = 0,
    keep_samples: bool = False,
) -> MonteCarloResult:
    """Monte Carlo statistics of ``outputs`` from ``n`` independent normal draws of the inputs.

    Parameters
    ----------
    quantities : mapping of str to Quantity
        The estimate chain's inputs (e.g. ``paper_inputs().quantities``).
    n : int
        Samples, evaluated by the chain's stages in batches.
    outputs : sequence of str
    seed : int, optional
    keep_samples : bool

    Returns
    -------
    MonteCarloResult
    """
    samples, failures = sample_outputs(quantities, n, outputs, seed)
    mean, std, skew, valid = {}, {}, {}, {}
    for name, s in samples.items():
        good = s[np.isfinite(s)]
        valid[name] = int(good.size)
        if good.size >= 2:
            m, sd = float(good.mean()), float(good.std(ddof=1))
            mean[name], std[name] = m, sd
            skew[name] = float(np.mean(((good - m) / sd) ** 3)) if sd > 0 else 0.0
        else:
            mean[name] = std[name] = skew[name] = math.nan
    return MonteCarloResult(n, mean, std, skew, valid, failures, samples if keep_samples else None)


@dataclass(frozen=True)
class Comparison:
    """First-order against Monte Carlo for one output."""

    name: str
    value: float | None
    first_order: float | None
    monte_carlo: float
    mc_mean: float
    relative_difference: float
    flagged: bool
    reason: str


def curvature(quantities: Mapping[str, Quantity], output: str) -> dict[str, tuple[float, float]]:
    """``{input: (linear term, second-order term)}`` of ``output`` at +/- 1 sigma of each input.

    One vectorised chain evaluation of ``2 n`` input sets.  A term is NaN when the output does
    not exist at one of the two points (e.g. a closure out of reach within 1 sigma).
    """
    values, varied = _sigma_inputs(quantities)
    chain = Chain(values)
    chain.require([output])
    m = len(varied)
    batch = {name: np.broadcast_to(v, (2 * m + 1,)).copy() for name, v in values.items()}
    for j, name in enumerate(varied):
        s = quantities[name].sigma
        batch[name][2 * j] += s
        batch[name][2 * j + 1] -= s
    y = np.broadcast_to(chain.evaluate(batch)[output], (2 * m + 1,))
    y0 = y[-1]
    return {
        name: (float((y[2 * j] - y[2 * j + 1]) / 2), float((y[2 * j] + y[2 * j + 1] - 2 * y0) / 2))
        for j, name in enumerate(varied)
    }


def compare(
    result: UncertaintyResult, mc: MonteCarloResult, quantities: Mapping[str, Quantity], threshold: float = 0.10
) -> list[Comparison]:
    """First-order against Monte Carlo sigma for each Monte Carlo output, with reasons."""
    out = []
    for name in mc.std:
        fo, sd = result.sigmas.get(name), mc.std[name]
        if fo is not None and fo == 0 and sd == 0:
            rel = 0.0  # a structural zero (an entry no input reaches)
        else:
            rel = abs(fo - sd) / sd if fo is not None and sd > 0 else math.inf
        flagged = not rel <= threshold
        reason = _diagnose(name, fo, mc, quantities) if flagged else "agree"
        out.append(Comparison(name, result.values.get(name), fo, sd, mc.mean[name], rel, flagged, reason))
    return out


def _diagnose(name: str, fo: float | None, mc: MonteCarloResult, quantities: Mapping[str, Quantity]) -> str:
    parts = []
    missing = mc.n - mc.valid[name]
    causes = ", ".join(f"{k} {v}" for k, v in mc.failures.items())
    if missing >= MISSING_LIMIT * mc.n:
        parts.append(
            f"{missing / mc.n:.2%} of samples have no value ({causes}): the chain is near a limit "
            "(a limb closure at full stretch or a root that vanishes), where no linearisation holds"
        )
    terms = curvature(quantities, name)
    finite = {k: v for k, v in terms.items() if math.isfinite(v[0]) and math.isfinite(v[1])}
    broken = sorted(set(terms) - set(finite))
    if broken:
        parts.append(f"the output does not exist at +/- 1 sigma of {', '.join(broken[:3])}")
    if finite and fo:
        second = math.sqrt(sum(2 * c**2 for _, c in finite.values()))
        worst = max(finite, key=lambda k: abs(finite[k][1]))
        lin, cur = finite[worst]
        if second > 0.05 * fo:
            parts.append(
                f"nonlinear: second-order terms add a sigma of {second:.3g} against {fo:.3g} first-order; "
                f"largest from {worst} (at 1 sigma: linear {lin:+.3g}, second-order {cur:+.3g})"
            )
    skew = mc.skewness.get(name, 0.0)
    if math.isfinite(skew) and abs(skew) > 0.3:
        parts.append(f"the samples are skewed (skewness {skew:+.2f})")
    if 0 < missing < MISSING_LIMIT * mc.n:
        parts.append(f"({missing / mc.n:.2%} of samples have no value: {causes})")
    return "; ".join(parts) if parts else "sampling noise or higher-order terms (no single cause found)"
