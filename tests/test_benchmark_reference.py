"""The Whipple benchmark of Meijaard et al. (2007): matrices, eigenvalues, critical speeds."""

from __future__ import annotations

import numpy as np
import pytest

from bikerider.benchmark import BenchmarkParameters, WhippleModel


@pytest.fixture(scope="module")
def model(benchmark_values) -> WhippleModel:
    return WhippleModel.from_parameters(BenchmarkParameters.from_mapping(benchmark_values))


@pytest.mark.parametrize("name", ["M", "C1", "K0", "K2"])
def test_matrices_match_published_to_1e13(model, meijaard2007, name):
    # Meijaard et al. 2007, section 5 (14 decimals), via tests/data/meijaard2007.json["matrices"].
    published = np.array(meijaard2007["matrices"][name])
    assert np.abs(getattr(model, name) - published).max() < 1e-13


def test_table2_eigenvalues_within_1e12(model, meijaard2007):
    # Meijaard et al. 2007, Table 2(b): weave (Re, |Im|), capsize, castor at v = 0..10 m/s.
    rows = meijaard2007["eigenvalues_table2b"]["rows"]
    speeds = np.array([r[0] for r in rows], dtype=float)
    eig = model.eigenvalues(speeds)
    for row, values in zip(rows, eig.values):
        v, weave_re, weave_im, capsize, castor = row
        if weave_re is None:
            # v = 0: Table 2's capsize and castor, and the two positive roots listed separately.
            assert np.abs(values[2].real - capsize) < 1e-12
            assert np.abs(values[3].real - castor) < 1e-12
            positive = sorted(meijaard2007["eigenvalues_table2b"]["v0_positive_roots"], reverse=True)
            assert np.abs(values[:2].real - positive).max() < 1e-12
            continue
        assert abs(values[0].real - weave_re) < 1e-12
        assert abs(values[0].imag - weave_im) < 1e-12
        assert abs(values[2].real - capsize) < 1e-12
        assert abs(values[3].real - castor) < 1e-12


def test_critical_speeds_within_1e10(model, meijaard2007):
    # Meijaard et al. 2007, Table 2(a): v_w = 4.29238253634111, v_c = 6.02426201538837 m/s,
    # weave frequency at v_w 3.43503384866144 rad/s.
    published = meijaard2007["speeds_table2a"]
    speeds = model.critical_speeds()
    assert abs(speeds.weave - published["v_w"]["value"]) < 1e-10
    assert abs(speeds.capsize - published["v_c"]["value"]) < 1e-10
    assert abs(speeds.weave_frequency - 3.43503384866144) < 1e-10
    assert speeds.stable_range == (speeds.weave, speeds.capsize)


def test_critical_speeds_are_where_eigenvalues_cross_zero(model):
    speeds = model.critical_speeds()
    eps = 1e-6
    weave = model.eigenvalues([speeds.weave - eps, speeds.weave + eps]).mode("weave")
    assert weave[0].real > 0 > weave[1].real
    capsize = model.eigenvalues([speeds.capsize - eps, speeds.capsize + eps]).mode("capsize")
    assert capsize[0].real < 0 < capsize[1].real


def test_characteristic_polynomial_roots_are_the_eigenvalues(model):
    v = np.linspace(0.5, 10, 7)
    coeffs = model.characteristic_coefficients(v)
    eig = model.eigenvalues(v)
    for c, ev in zip(coeffs, eig.values):
        roots = np.sort_complex(np.roots(c))
        assert np.abs(roots - np.sort_complex(ev)).max() < 1e-9


def test_no_weave_speed_when_there_is_no_hopf_crossing(benchmark_values):
    # Negative trail: the benchmark bicycle loses its self-stability; the conditions must say so
    # rather than return a spurious root.
    params = BenchmarkParameters.from_mapping({**benchmark_values, "c": -0.08})
    model = WhippleModel.from_parameters(params)
    speeds = model.critical_speeds()
    eig = model.eigenvalues(np.linspace(0, 20, 401))
    stable = np.all(eig.values.real < 0, axis=1)
    assert not stable.any()
    assert speeds.stable_range is None
