"""The one root solver gives one polynomial (plain floats) the batch's results bit for bit."""

from __future__ import annotations

import math

import numpy as np

from bikerider.benchmark import roots


def _same(x: float, y: float) -> bool:
    return x == y or (math.isnan(x) and math.isnan(y))


def test_floats_and_arrays_agree_bit_for_bit() -> None:
    rng = np.random.default_rng(1)
    n = 3000
    c = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-3, 6, size=(n, 3))
    c[::7, 0] = 0.0  # linear
    c[::19, 1] = 0.0
    c[::17] = 0.0  # no polynomial
    c[::23] = [1.0, -4.0, 4.0]  # a double root
    c[::29] = [1.0, -4.0, 4.0 + 1e-22]  # a double root split by round-off into a complex pair
    low, high = roots.quadratic_roots(c[:, 0], c[:, 1], c[:, 2])
    for i in range(n):
        one = roots.quadratic_roots(*(float(x) for x in c[i]))
        assert all(type(x) is float for x in one)
        assert _same(one[0], float(low[i])) and _same(one[1], float(high[i])), i
        positive = roots.positive_real_roots(*c[i])
        assert positive == [u for u in (float(low[i]), float(high[i])) if u > 0], i
