"""The one root solver gives one bicycle (plain floats) the batch's results bit for bit."""
from __future__ import annotations

import math

import numpy as np

from bikerider.benchmark import roots


def _same(x: float, y: float) -> bool:
    return x == y or (math.isnan(x) and math.isnan(y))


def test_floats_and_arrays_agree_bit_for_bit() -> None:
    rng = np.random.default_rng(1)
    n = 3000
    capsize = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-3, 6, size=(n, 3))
    weave = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-3, 6, size=(n, 3))
    a1, a3 = rng.normal(size=(n, 2)), rng.normal(size=(n, 2))
    capsize[::7, 0] = 0.0  # linear
    capsize[::19, 1] = 0.0
    weave[::11, 0] = 0.0
    weave[::17] = 0.0  # no polynomial
    weave[::23] = [1.0, -4.0, 4.0]  # a double root
    a3[::13] = 0.0  # the crossing frequency divides by zero
    batch = roots.critical_speeds(capsize, weave, a1, a3)
    pairs = roots.quadratic_roots(weave[:, 0], weave[:, 1], weave[:, 2])
    for i in range(n):
        one = roots.critical_speeds(*(tuple(p[i].tolist()) for p in (capsize, weave, a1, a3)))
        assert all(type(x) is float for x in one)
        assert all(_same(x, float(b[i])) for x, b in zip(one, batch)), i
        low, high = roots.quadratic_roots(*(float(c) for c in weave[i]))
        assert _same(low, float(pairs[0][i])) and _same(high, float(pairs[1][i])), i
