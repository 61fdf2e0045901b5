"""Random but physically valid bicycles: every benchmark parameter within a factor of the benchmark.

Each of the 25 parameters of Meijaard et al. (2007) Table 1 (``tests/data/meijaard2007.json``; ``g``
kept) is multiplied by its own uniform factor in ``[1 - spread, 1 + spread]``; a draw is kept when
:meth:`bikerider.benchmark.BenchmarkParameters.from_mapping` accepts it (positive masses, inertia
tensors that satisfy the triangle inequality, wheels with ``I_yy <= 2 I_xx``, ...).  At a spread of
0.5 about one draw in sixty is valid, so a vectorised pre-filter of the same inertia inequalities
(slightly looser, so it never rejects a draw the project accepts) spares most of the calls.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np

from bikerider.benchmark import BenchmarkParameters, WhippleModel
from bikerider.benchmark.model import MATRIX_NAMES
from bikerider.errors import InputError

DATA = Path(__file__).parent / "data"


def benchmark_values() -> dict[str, float]:
    """Meijaard et al. (2007) Table 1, with ``lam`` for ``lambda``."""
    values = dict(json.loads((DATA / "meijaard2007.json").read_text())["parameters"]["values"])
    values["lam"] = values.pop("lambda")
    return values


def _triangle(xx, yy, zz, xz, slack=1e-6):
    mean, radius = (xx + zz) / 2, np.hypot((xx - zz) / 2, xz)
    moments = np.stack([mean - radius, yy, mean + radius])
    total = moments.sum(axis=0)
    return np.all(moments > 0, axis=0) & np.all(moments <= (total - moments) * (1 + slack), axis=0)


def random_parameters(n: int, spread: float = 0.5, seed: int = 0) -> list[BenchmarkParameters]:
    """``n`` valid parameter sets, each parameter uniform within ``+/- spread`` of the benchmark."""
    base = benchmark_values()
    names = [k for k in base if k != "g"]
    rng = np.random.default_rng(seed)
    out: list[BenchmarkParameters] = []
    logging.getLogger("bikerider").setLevel(logging.ERROR)  # wheel inertias accepted within sigma
    while len(out) < n:
        draws = {k: base[k] * rng.uniform(1 - spread, 1 + spread, 20000) for k in names}
        keep = (
            _triangle(draws["IBxx"], draws["IByy"], draws["IBzz"], draws["IBxz"])
            & _triangle(draws["IHxx"], draws["IHyy"], draws["IHzz"], draws["IHxz"])
            & (draws["IRyy"] <= 2 * draws["IRxx"] * (1 + 1e-6))
            & (draws["IFyy"] <= 2 * draws["IFxx"] * (1 + 1e-6))
        )
        for i in np.flatnonzero(keep):
            try:
                out.append(BenchmarkParameters.from_mapping({"g": base["g"], **{k: float(draws[k][i]) for k in names}}))
            except InputError:
                continue
            if len(out) == n:
                break
    return out


def batched_model(models: list[WhippleModel]) -> WhippleModel:
    """One :class:`WhippleModel` holding a list of single models as a batch."""
    mats = [np.stack([getattr(m, name) for m in models]) for name in MATRIX_NAMES]
    return WhippleModel(*mats, g=np.array([m.g for m in models]))
