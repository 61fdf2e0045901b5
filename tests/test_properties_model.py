"""Properties of the linear Whipple model over random physical bicycles.

Similarity law (derived here).  With every length scaled by ``s``, every mass by ``mu`` (so every
moment of inertia by ``mu s^2``) and gravity unchanged, the canonical matrices scale as
``M -> mu s^2 M``, ``C1 -> mu s C1``, ``K0 -> mu s K0``, ``K2 -> mu K2`` (their units are kg m^2,
kg m, kg m, kg).  Substituting ``lambda' = lambda / sqrt(s)`` and ``v' = sqrt(s) v`` in
``det(M' lambda'^2 + v' C1' lambda' + g K0' + v'^2 K2')`` gives ``mu^2 s^2`` times the original
determinant, so: the eigenvalues at speed ``sqrt(s) v`` are those at ``v`` divided by ``sqrt(s)``,
and the weave and capsize speeds scale by ``sqrt(s)``; ``mu`` drops out.  (``s^3`` masses, a
geometrically similar bicycle of the same materials, is the case ``mu = s^3``.)
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from bikerider.generated import combination
from hypothesis import HealthCheck, given, settings
from strategies import benchmark_mappings, factor, seated_pairs

from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters, WhippleModel
from bikerider.estimate import chain_inputs

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])

LENGTHS = {"w", "c", "rR", "rF", "xB", "zB", "xH", "zH"}
MASSES = {"mR", "mB", "mH", "mF"}
INERTIAS = {n for n in BENCHMARK_NAMES if n.startswith("I")}
SPEEDS = np.array([0.0, 0.5, 1.0, 2.5, 4.0, 6.0, 9.0])


def _model(mapping: dict[str, float]) -> WhippleModel:
    return WhippleModel.from_parameters(BenchmarkParameters.from_mapping(mapping, "<hypothesis>"))


def _sorted(ev: np.ndarray) -> np.ndarray:
    return ev[np.lexsort((ev.imag, ev.real))]


@SETTINGS
@given(benchmark_mappings())
def test_mass_and_stiffness_matrices_are_symmetric_and_M_positive_definite(mapping):
    model = _model(mapping)
    for name in ("M", "K0"):
        m = getattr(model, name)
        assert m[0, 1] == pytest.approx(m[1, 0], rel=1e-13, abs=1e-15), name
    assert np.all(np.linalg.eigvalsh(model.M) > 0)


@SETTINGS
@given(seated_pairs())
def test_matrices_of_estimated_bicycles_are_symmetric(pair):
    from bikerider.estimate import estimate

    bicycle, rider, _ = pair
    model = estimate(bicycle, rider).model
    for name in ("M", "K0"):
        m = getattr(model, name)
        assert m[0, 1] == pytest.approx(m[1, 0], rel=1e-13, abs=1e-15), name
    assert np.all(np.linalg.eigvalsh(model.M) > 0)


@SETTINGS
@given(benchmark_mappings())
def test_zero_speed_eigenvalues_are_those_of_M_and_g_K0_alone(mapping):
    model = _model(mapping)
    # At v = 0: (M s^2 + g K0) q = 0, a generalised symmetric eigenproblem in s^2.
    s_squared = scipy.linalg.eigh(-model.g * model.K0, model.M, eigvals_only=True)
    expected = _sorted(np.concatenate([np.sqrt(s_squared.astype(complex)), -np.sqrt(s_squared.astype(complex))]))
    got = _sorted(model.eigenvalues([0.0]).values[0])
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)


def _scaled(mapping: dict[str, float], s: float, mu: float) -> dict[str, float]:
    out = {}
    for name, value in mapping.items():
        if name in LENGTHS:
            out[name] = value * s
        elif name in MASSES:
            out[name] = value * mu
        elif name in INERTIAS:
            out[name] = value * mu * s**2
        else:  # lam (an angle) and g
            out[name] = value
    return out


@SETTINGS
@given(benchmark_mappings(), factor(0.5, 2.0), factor(0.3, 3.0))
def test_similar_bicycles_follow_the_similarity_law(mapping, s, mu):
    base, scaled = _model(mapping), _model(_scaled(mapping, s, mu))
    np.testing.assert_allclose(scaled.M, mu * s**2 * base.M, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(scaled.C1, mu * s * base.C1, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(scaled.K0, mu * s * base.K0, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(scaled.K2, mu * base.K2, rtol=1e-12, atol=1e-14)
    ev_base = base.eigenvalues(SPEEDS).values
    ev_scaled = scaled.eigenvalues(math.sqrt(s) * SPEEDS).values
    for row_base, row_scaled in zip(ev_base, ev_scaled):
        np.testing.assert_allclose(_sorted(row_scaled), _sorted(row_base) / math.sqrt(s), rtol=1e-7, atol=1e-7)
    speeds_base, speeds_scaled = base.critical_speeds(), scaled.critical_speeds()
    for name in ("weave", "capsize"):
        a, b = getattr(speeds_base, name), getattr(speeds_scaled, name)
        assert (a is None) == (b is None), name
        if a is not None:
            assert b == pytest.approx(math.sqrt(s) * a, rel=1e-8), name


@SETTINGS
@given(benchmark_mappings(), factor(0.7, 1.4))
def test_geometrically_similar_bicycle_of_the_same_material(mapping, s):
    """Masses as s^3, inertias as s^5: critical speeds scale by sqrt(s)."""
    base, scaled = _model(mapping), _model(_scaled(mapping, s, s**3))
    for name in ("weave", "capsize"):
        a, b = getattr(base.critical_speeds(), name), getattr(scaled.critical_speeds(), name)
        assert (a is None) == (b is None)
        if a is not None:
            assert b == pytest.approx(math.sqrt(s) * a, rel=1e-8)


_CHAIN_ANGLES = {"lam_ht", "lam_st", "lam_fl"}
_CHAIN_MASSES = {"mR", "mF", "mH", "mBf", "mBr"}
_CHAIN_FRACTIONS = {"f_h", "f_la", "f_ll", "f_to", "f_ua", "f_ul"}


@SETTINGS
@given(seated_pairs(), factor(0.7, 1.4), factor(0.5, 2.0))
def test_the_estimate_chain_is_dimensionally_consistent(pair, s, mu):
    """Scaling the measurements (lengths s, masses mu, inertias mu s^2) scales the 26 outputs alike."""
    bicycle, rider, _ = pair
    inputs = {k: q.value for k, q in chain_inputs(bicycle, rider).items()}
    scaled = {}
    for name, value in inputs.items():
        if name in _CHAIN_ANGLES or name in _CHAIN_FRACTIONS or name == "g":
            scaled[name] = value
        elif name in _CHAIN_MASSES:
            scaled[name] = value * mu
        elif name.startswith("I"):
            scaled[name] = value * mu * s**2
        else:  # every other chain input is a length or a circumference
            scaled[name] = value * s
    base = dict(zip(BENCHMARK_NAMES, np.asarray(combination.estimate_chain(**inputs), dtype=float)))
    out = dict(zip(BENCHMARK_NAMES, np.asarray(combination.estimate_chain(**scaled), dtype=float)))
    for name in BENCHMARK_NAMES:
        if not math.isfinite(base[name]):
            assert not math.isfinite(out[name]), name  # an undetermined I_yy stays undetermined
            continue
        factor_ = s if name in LENGTHS else mu if name in MASSES else mu * s**2 if name in INERTIAS else 1.0
        assert out[name] == pytest.approx(factor_ * base[name], rel=1e-11, abs=1e-14), name
