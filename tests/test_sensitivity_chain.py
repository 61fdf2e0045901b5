"""The composed chain Jacobian against finite differences of the project's own generated chain
(``combination.estimate_chain``, ``canonical_matrices``), and the vectorised critical speeds
against ``WhippleModel.critical_speeds``."""

from __future__ import annotations

import numpy as np
import pytest
from bikerider.generated import benchmark_model, combination
from test_sensitivities_stages import random_inputs

from bikerider.benchmark import BENCHMARK_NAMES, WhippleModel
from bikerider.benchmark.roots import quadratic_roots
from bikerider.engine import arguments
from bikerider.uncertainty.chain import Chain, prepare_values
from bikerider.uncertainty.speeds import critical_speeds_from_entries
from bikerider.uncertainty.stages import CANONICAL, ENTRIES

CHAIN_ARGS = arguments("combination.estimate_chain")


def chain_level_inputs(shape, seed):
    """Chain arguments (reduced inertias) at a random physical point."""
    raw = random_inputs(shape, seed)
    nodes = Chain(raw).evaluate(raw)
    out = {k: nodes[k] for k in CHAIN_ARGS if k in nodes}
    out["IBfyy"] = np.full(shape, 1.3)
    out["IHyy"] = np.full(shape, 0.25)
    return out


@pytest.mark.parametrize("shape", [(), (4,), (2, 3)])
def test_benchmark_jacobian_matches_finite_differences_of_the_generated_chain(shape):
    values = chain_level_inputs(shape, seed=20 + len(shape))
    assert set(values) == set(CHAIN_ARGS)
    names = list(values)
    nodes, grads = Chain(values).gradients(values, names)
    got = np.stack([np.broadcast_to(grads[n], shape + (len(names),)) for n in BENCHMARK_NAMES], axis=-2)
    base = combination.estimate_chain(**values)
    np.testing.assert_allclose(
        np.stack([np.broadcast_to(nodes[n], shape) for n in BENCHMARK_NAMES], -1), base, rtol=1e-12
    )
    for j, name in enumerate(names):
        x = values[name]
        h = 1e-6 * np.maximum(np.abs(x), 1e-2)
        fd = (
            combination.estimate_chain(**{**values, name: x + h})
            - combination.estimate_chain(**{**values, name: x - h})
        ) / (2 * h)[..., None]
        scale = np.abs(base) + 1.0
        np.testing.assert_allclose(got[..., j] / scale, fd / scale, atol=1e-7, err_msg=name)


def test_matrix_and_speed_jacobian_matches_finite_differences_at_benchmark_level(benchmark_values):
    """Entering at the benchmark parameters (Meijaard et al. 2007 Table 1 values)."""
    values = {k: float(v) for k, v in benchmark_values.items()}
    names = list(values)
    chain = Chain(values)
    nodes, grads = chain.gradients(values, names)
    for j, name in enumerate(names):
        h = 1e-6 * max(abs(values[name]), 1e-2)
        plus = chain.evaluate({**values, name: values[name] + h})
        minus = chain.evaluate({**values, name: values[name] - h})
        for out in ENTRIES + ("v_weave", "v_capsize"):
            fd = (plus[out] - minus[out]) / (2 * h)
            assert grads[out][j] == pytest.approx(fd, rel=1e-5, abs=1e-7 * (abs(float(nodes[out])) + 1)), (out, name)
    # speeds of the benchmark bicycle, Meijaard et al. (2007) Table 2: v_w = 4.292383 m/s, v_c = 6.024262 m/s
    assert float(nodes["v_weave"]) == pytest.approx(4.292383, abs=1e-6)
    assert float(nodes["v_capsize"]) == pytest.approx(6.024262, abs=1e-6)


def test_vectorised_speeds_equal_the_model_for_random_bicycles():
    values = chain_level_inputs((12,), seed=40)
    values.update(
        {
            k: v * (1 + 0.2 * np.random.default_rng(1).standard_normal(12))
            for k, v in values.items()
            if k in ("c", "mH", "IFyy", "IRyy", "xH")
        }
    )
    nodes = Chain(values).evaluate(values)
    speeds = critical_speeds_from_entries({k: nodes[k] for k in ENTRIES}, 9.81)
    for i in range(12):
        params = {k: float(nodes[k][i]) if np.ndim(nodes[k]) else float(nodes[k]) for k in CANONICAL}
        model = WhippleModel(*benchmark_model.canonical_matrices(**params), g=9.81)
        cs = model.critical_speeds()
        for got, want in (
            (speeds["v_weave"][i], cs.weave),
            (speeds["v_capsize"][i], cs.capsize),
            (speeds["weave_frequency"][i], cs.weave_frequency),
        ):
            if want is None:
                assert np.isnan(got)
            else:
                assert got == pytest.approx(want, rel=1e-10)


def test_quadratic_roots_edge_cases():
    c2 = np.array([1.0, 0.0, 1.0, 1.0, 1e-20, 0.0])
    c1 = np.array([-3.0, 2.0, 0.0, -2.0, 1.0, 0.0])
    c0 = np.array([2.0, -4.0, 1.0, 1.0, -3.0, 0.0])
    low, high = quadratic_roots(c2, c1, c0)
    np.testing.assert_allclose(low[:2], [1.0, 2.0])  # two real roots; linear
    assert high[0] == pytest.approx(2.0) and np.isnan(high[1])
    assert np.isnan(low[2]) and np.isnan(high[2])  # u^2 + 1: complex
    assert low[3] == pytest.approx(1.0) and high[3] == pytest.approx(1.0)  # double root
    assert low[4] == pytest.approx(3.0) and np.isnan(high[4])  # negligible leading term: linear
    assert np.isnan(low[5]) and np.isnan(high[5])  # all zero: no root


def test_both_a_reduced_value_and_its_measurements_is_an_error():
    from bikerider.errors import InputError

    values = random_inputs((), seed=2)
    values["IBfxx"] = 1.1
    with pytest.raises(InputError, match="IBfxx .*either IBfxx or the measurements"):
        Chain(values)


def test_unknown_and_non_finite_inputs_are_named():
    from bikerider.errors import InputError

    with pytest.raises(InputError, match="l_stt"):
        prepare_values({"l_stt": 0.5})
    with pytest.raises(InputError, match="w = nan: expected a finite number"):
        prepare_values({"w": float("nan")})
