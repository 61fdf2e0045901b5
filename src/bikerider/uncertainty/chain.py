"""The estimate chain's stages run by the uncertainty engine, and its inputs checked by name."""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping
from functools import lru_cache

import numpy as np

from bikerider.engine import Chain as _EngineChain
from bikerider.engine import arguments
from bikerider.errors import InputError
from bikerider.generated.manifest import BENCHMARK_NAMES
from bikerider.uncertainty.stages import FRAME, OPTIONAL_NAN, all_stages

LOG = logging.getLogger(__name__)

ESTIMATE_INPUTS = arguments("combination.estimate_chain")
"""The estimate chain's inputs from a bicycle, a seated rider and the mass fractions, in order (the
generated test oracle ``combination.estimate_chain`` takes the same)."""


def known_names() -> set[str]:
    """Every node name the chain knows: its stages' inputs and outputs, the benchmark names, the
    speed ``v`` and the hub widths (Table 1 measurements the chain does not use)."""
    names = {"v", "w_fh", "w_rh", *BENCHMARK_NAMES}
    for stage in all_stages():
        names.update(stage.inputs)
        names.update(stage.outputs)
    return names


class Chain(_EngineChain):
    """The estimate chain's stages that run when the nodes ``provided`` are given, in order.

    Parameters
    ----------
    provided : iterable of str
        Names of the nodes the caller gives values for.

    Raises
    ------
    InputError
        A node given together with every measurement it is computed from (ambiguous).
    """

    def __init__(self, provided: Iterable[str]):
        super().__init__(all_stages(), provided)


@lru_cache(maxsize=32)
def _chain(provided: tuple[str, ...]) -> Chain:
    return Chain(provided)


def benchmark_values(values: Mapping[str, object]) -> dict[str, object]:
    """The benchmark parameters the estimate chain's stages give for ``values``.

    Parameters
    ----------
    values : mapping of str to float or array_like
        Nodes of the chain by name (e.g. every name of :data:`ESTIMATE_INPUTS`); arrays broadcast
        against each other, so one call evaluates a whole batch of bicycles.

    Returns
    -------
    dict of str to float or numpy.ndarray
        Every name of ``BENCHMARK_NAMES``; NaN where the inputs do not determine a value (``IByy``,
        ``IHyy`` without their I_yy) or where the geometry does not close.
    """
    nodes = _chain(tuple(values)).evaluate(values)
    return {name: nodes[name] for name in BENCHMARK_NAMES}


def prepare_values(values: Mapping[str, object]) -> dict[str, np.ndarray]:
    """Check names and fill the optional NaN inputs; return float arrays.

    Raises
    ------
    InputError
        An unknown name, or a value that is not a finite number (NaN is allowed only for
        ``IBfyy`` and ``IHyy``, which reach nothing but ``IByy``/``IHyy``).
    """
    known = known_names()
    out: dict[str, np.ndarray] = {}
    for name, raw in values.items():
        if name not in known:
            close = sorted(n for n in known if n.lower().startswith(name[:2].lower()))[:8]
            hint = f" (names starting alike: {', '.join(close)})" if close else ""
            raise InputError(name, raw, f"a name of the estimate chain{hint}")
        try:
            array = np.asarray(getattr(raw, "value", raw), dtype=float)
        except (TypeError, ValueError):
            raise InputError(name, raw, "a number") from None
        if not np.all(np.isfinite(array)) and name not in OPTIONAL_NAN:
            raise InputError(name, raw, "a finite number")
        out[name] = array
    for name in with_optional(out):
        out.setdefault(name, np.asarray(np.nan))
    return out


def with_optional(provided: Iterable[str]) -> tuple[str, ...]:
    """``provided`` plus ``IBfyy`` when rear frame values are given without it (it is NaN then)."""
    names = tuple(provided)
    if any(name in names for name in FRAME) and "IBfyy" not in names:
        names += ("IBfyy",)
    return names
