"""Evaluate the stage graph and its Jacobian (forward-mode chain rule) for any batch shape."""
from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from bikerider.benchmark.parameters import BENCHMARK_NAMES
from bikerider.errors import InputError
from bikerider.uncertainty.stages import FRAME, OPTIONAL_NAN, Stage, all_stages

LOG = logging.getLogger(__name__)


def known_names() -> set[str]:
    """Every node name the chain knows: its stages' inputs and outputs, the benchmark names, the
    speed ``v`` and the hub widths (Table 1 measurements the chain does not use)."""
    names = {"v", "w_fh", "w_rh", *BENCHMARK_NAMES}
    for stage in all_stages():
        names.update(stage.inputs)
        names.update(stage.outputs)
    return names


class Chain:
    """The stages that run when the nodes ``provided`` are given, in order.

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
        self.provided = tuple(provided)
        available = set(self.provided)
        self.stages: list[Stage] = []
        for stage in all_stages():
            if not all(name in available for name in stage.inputs):
                continue
            given = [name for name in stage.outputs if name in self.provided]
            if given:
                raw = [n for n in stage.inputs if n not in ("g", "k_t") and n in self.provided][:3]
                raise InputError(
                    given[0], "given",
                    f"either {given[0]} or the measurements it is computed from ({', '.join(raw)}, ...), not both",
                )
            self.stages.append(stage)
            available.update(stage.outputs)
        self.available = available

    def require(self, names: Sequence[str]) -> None:
        """Raise :class:`InputError` naming the first of ``names`` the inputs cannot give."""
        for name in names:
            if name not in self.available:
                raise InputError(name, "not computable from the inputs given",
                                 "the measurements it depends on (see bikerider sensitivity --help)")

    def evaluate(self, values: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Value of every available node; arrays broadcast against each other."""
        nodes = {k: np.asarray(v, dtype=float) for k, v in values.items()}
        for stage in self.stages:
            with np.errstate(invalid="ignore"):
                outs = stage.value(stage.kwargs(nodes))
            nodes.update(zip(stage.outputs, (np.asarray(o, dtype=float) for o in outs)))
        return nodes

    def gradients(self, values: Mapping[str, np.ndarray], wrt: Sequence[str]) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        """Node values and ``d node / d wrt`` as arrays ``(..., len(wrt))`` for every available node.

        Forward mode: each stage's Jacobian multiplies the stacked gradients of its inputs.
        """
        nodes = {k: np.asarray(v, dtype=float) for k, v in values.items()}
        n = len(wrt)
        eye = np.eye(n)
        grads: dict[str, np.ndarray] = {}
        index = {name: i for i, name in enumerate(wrt)}
        for name in nodes:
            grads[name] = eye[index[name]] if name in index else np.zeros(n)
        for stage in self.stages:
            kw = stage.kwargs(nodes)
            with np.errstate(invalid="ignore", divide="ignore"):
                outs = stage.value(kw)
                nodes.update(zip(stage.outputs, (np.asarray(o, dtype=float) for o in outs)))
                J = np.asarray(stage.jacobian(kw), dtype=float)
                inputs = np.stack(np.broadcast_arrays(*(grads[name] for name in stage.inputs)), axis=-2)
                J, inputs = _broadcast_matmul(J, inputs)
                out = J @ inputs
            for k, name in enumerate(stage.outputs):
                grads[name] = out[..., k, :]
        return nodes, grads


def _broadcast_matmul(J: np.ndarray, G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    batch = np.broadcast_shapes(J.shape[:-2], G.shape[:-2])
    return np.broadcast_to(J, batch + J.shape[-2:]), np.broadcast_to(G, batch + G.shape[-2:])


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
