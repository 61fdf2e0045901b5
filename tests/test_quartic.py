"""The vectorised quartic solver and the polynomial paths to eigenvalues and critical speeds.

Reference roots come from ``numpy.linalg.eigvals`` (of companion matrices, or of the model's state
matrices through ``WhippleModel.eigenvalues``) and from exactly known roots.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from bikerider.generated import benchmark_model as gen

from bikerider.benchmark import BenchmarkParameters, WhippleModel
from bikerider.benchmark.model import label_modes
from bikerider.benchmark.quartic import eigenvalues_from_polynomial, quartic_roots
from bikerider.benchmark.roots import positive_real_roots
from bikerider.errors import InputError
from bikerider.io.bicycleparameters import read_benchmark_file

PERMUTATIONS = np.array(list(itertools.permutations(range(4))))


def matched_error(found: np.ndarray, expected: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Per row, the largest ``|found - expected| / scale`` under the best pairing of the roots."""
    diff = np.abs(found[:, PERMUTATIONS] - expected[:, None, :]) / scale[:, None, :]
    return diff.max(axis=-1).min(axis=-1)


def companion_eigvals(coefficients: np.ndarray) -> np.ndarray:
    monic = coefficients[:, 1:] / coefficients[:, :1]
    companion = np.zeros((len(coefficients), 4, 4))
    companion[:, 0, :] = -monic
    companion[:, 1:, :3] = np.eye(3)
    return np.linalg.eigvals(companion)


def separated_roots(rng: np.random.Generator, n: int) -> np.ndarray:
    """Rows of four roots (two real and one pair, four real, or two pairs), pairwise at least 5 %
    of the row's largest modulus apart, moduli from 1e-3 to 1e3 between rows."""
    rows = []
    while len(rows) < n:
        kind = rng.integers(3)
        a = rng.uniform(-1, 1, 4)
        b = rng.uniform(0.05, 1, 2)
        if kind == 0:
            r = [a[0], a[1], a[2] + 1j * b[0], a[2] - 1j * b[0]]
        elif kind == 1:
            r = list(a)
        else:
            r = [a[0] + 1j * b[0], a[0] - 1j * b[0], a[1] + 1j * b[1], a[1] - 1j * b[1]]
        r = np.array(r, dtype=complex)
        top = np.abs(r).max()
        gaps = np.abs(r[:, None] - r[None, :])[~np.eye(4, dtype=bool)]
        if gaps.min() < 0.05 * top:
            continue
        rows.append(r * 10 ** rng.uniform(-3, 3))
    return np.array(rows)


@pytest.fixture(scope="module")
def benchmark_model(benchmark_values) -> WhippleModel:
    return WhippleModel.from_parameters(BenchmarkParameters.from_mapping(benchmark_values))


def test_random_quartics_match_eigvals_to_1e10():
    rng = np.random.default_rng(20260521)
    roots = separated_roots(rng, 3000)
    coefficients = np.array([np.poly(r).real for r in roots]) * rng.uniform(0.1, 10, (len(roots), 1))
    found = quartic_roots(coefficients)
    scale = np.repeat(np.abs(roots).max(axis=1, keepdims=True), 4, axis=1)
    assert matched_error(found, companion_eigvals(coefficients), scale).max() < 1e-10
    assert matched_error(found, roots, scale).max() < 1e-10


def test_roots_are_sorted_and_conjugate_pairs_exact():
    roots = np.array([[-2.0, 0.5, 1 + 3j, 1 - 3j], [-1 + 1j, -1 - 1j, 2 + 0.5j, 2 - 0.5j]])
    found = quartic_roots(np.array([np.poly(r).real for r in roots]))
    np.testing.assert_array_equal(found, np.sort(found, axis=-1))
    for row in found:
        complex_part = row[np.abs(row.imag) > 0]
        np.testing.assert_array_equal(np.sort(complex_part), np.sort(np.conj(complex_part)))


def test_batch_shapes_broadcast():
    rng = np.random.default_rng(3)
    roots = separated_roots(rng, 6)
    coefficients = np.array([np.poly(r).real for r in roots]).reshape(2, 3, 5)
    found = quartic_roots(coefficients)
    assert found.shape == (2, 3, 4)
    np.testing.assert_allclose(found.reshape(6, 4), quartic_roots(coefficients.reshape(6, 5)), rtol=0, atol=0)
    single = quartic_roots(coefficients[1, 2])
    assert single.shape == (4,)
    np.testing.assert_array_equal(single, found[1, 2])


def test_exact_double_root_to_sqrt_eps():
    # (x - 3)^2 (x + 1)(x - 7/2): the double root is resolved to about sqrt(machine eps) relative,
    # the mean of the pair much better (see the module docstring of bikerider.benchmark.quartic).
    coefficients = np.poly([3.0, 3.0, -1.0, 3.5]).real
    found = quartic_roots(coefficients)
    distance = np.abs(found - 3.0)
    pair = found[np.argsort(distance)[:2]]
    assert np.all(np.abs(pair - 3.0) < 1e-7 * 3.0)
    assert abs(pair.mean() - 3.0) < 1e-12 * 3.0
    others = np.sort(found[np.argsort(distance)[2:]].real)
    np.testing.assert_allclose(others, [-1.0, 3.5], rtol=1e-13)


def test_bicycle_eigenvalues_at_1000_speeds_match_eigvals_to_1e10(benchmark_model, paper_result):
    speeds = np.linspace(0.0, 10.0, 1000)
    for model in (benchmark_model, paper_result.model):
        ours = eigenvalues_from_polynomial(model, speeds)
        reference = model.eigenvalues(speeds)
        scale = np.maximum(1.0, np.abs(reference.values))
        assert (np.abs(ours.values - reference.values) / scale).max() < 1e-10
        np.testing.assert_array_equal(ours.labels, reference.labels)
        np.testing.assert_array_equal(ours.speeds, speeds)


def test_double_root_at_benchmark_vd(benchmark_model, meijaard2007):
    # Meijaard et al. 2007, Table 2(a): v_d = 0.68428307889246 m/s, where the two real weave
    # eigenvalues meet at lambda = 3.7829040512932 1/s (tests/data/meijaard2007.json).
    v_d = meijaard2007["speeds_table2a"]["v_d"]["value"]
    published = meijaard2007["speeds_table2a"]["v_d"]["lambda"]
    ours = eigenvalues_from_polynomial(benchmark_model, [v_d]).mode("weave")
    pair = quartic_roots(benchmark_model.characteristic_coefficients([v_d]))[0]
    pair = pair[np.argsort(np.abs(pair - published))[:2]]
    assert np.all(np.abs(pair - published) < 1e-7 * published)
    assert abs(pair.mean().real - published) < 1e-10 * published
    reference = np.linalg.eigvals(benchmark_model.state_matrix([v_d]))[0]
    reference = reference[np.argsort(np.abs(reference - published))[:2]]
    assert abs(pair.mean() - reference.mean()) < 1e-10 * published
    assert abs(ours[0].real - published) < 1e-7 * published


def test_labels_follow_label_modes_rules():
    raw = np.array(
        [
            [-5.0, 1.0, 2.0, -0.5],  # all real: two largest are weave
            [-5.0, 1 + 2j, 1 - 2j, -0.5],  # one pair
            [1 + 2j, 1 - 2j, -3 + 5j, -3 - 5j],  # two pairs: larger imaginary part is weave
            [-3 + 0.1j, 1.0, -3 - 0.1j, 2.0],  # one pair below both reals: the reals are the unborn weave
            [-1 + 2j, -1 - 2j, 0.5, -6.0],  # one pair between the reals (above the weave speed)
        ],
        dtype=complex,
    )
    values, labels = label_modes(raw)
    np.testing.assert_array_equal(values[0], [2.0, 1.0, -0.5, -5.0])
    np.testing.assert_array_equal(values[1], [1 + 2j, 1 - 2j, -0.5, -5.0])
    np.testing.assert_array_equal(values[2], [-3 + 5j, -3 - 5j, 1 + 2j, 1 - 2j])
    np.testing.assert_array_equal(values[3], [2.0, 1.0, -3 + 0.1j, -3 - 0.1j])
    np.testing.assert_array_equal(values[4], [-1 + 2j, -1 - 2j, 0.5, -6.0])
    assert labels[0].tolist() == labels[1].tolist() == labels[4].tolist() == ["weave", "weave", "capsize", "castor"]
    assert labels[2].tolist() == labels[3].tolist() == ["weave", "weave", "other", "other"]
    reference_values, reference_labels = _label_modes_loop(raw)  # the rules one speed at a time
    np.testing.assert_array_equal(values, reference_values)
    np.testing.assert_array_equal(labels, reference_labels)


UNBORN_WEAVE = Path(__file__).parent / "data" / "UnbornWeaveBenchmark.txt"
"""Not a real bicycle: capsize and castor roots that meet before the weave pair is born (see the file)."""


def test_capsize_and_castor_meeting_before_the_weave_is_born_are_not_called_weave():
    model = WhippleModel.from_parameters(read_benchmark_file(UNBORN_WEAVE).parameters)
    assert model.weave_birth_speed() == pytest.approx(1.2858, abs=1e-4)
    speeds = np.array([0.5, 2.0])
    reference, fast = model.eigenvalues(speeds), model.eigenvalues(speeds, method="quartic")
    assert np.abs(fast.values - reference.values).max() < 1e-10
    assert (fast.labels == reference.labels).all()
    below, above = reference.values
    # at 0.5 m/s: the weave pair still two positive real roots, the other two a complex pair
    assert reference.labels[0].tolist() == ["weave", "weave", "other", "other"]
    assert below[0].imag == below[1].imag == 0 and below[0].real > below[1].real > 0
    assert below[2].imag > 0 and below[2].real < 0
    # at 2 m/s, past v_d: the usual labels, the weave pair complex
    assert reference.labels[1].tolist() == ["weave", "weave", "capsize", "castor"] and above[0].imag > 0


def _random_models(benchmark_model: WhippleModel, n: int, spread: float, seed: int) -> list[WhippleModel]:
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        mats = [
            m * (1 + spread * rng.standard_normal(m.shape))
            for m in (benchmark_model.M, benchmark_model.C1, benchmark_model.K0, benchmark_model.K2)
        ]
        mats[0] = (mats[0] + mats[0].T) / 2
        if np.linalg.eigvalsh(mats[0]).min() <= 0:
            continue  # a model needs a positive definite mass matrix
        out.append(WhippleModel(*mats, g=benchmark_model.g))
    return out


def test_scalar_speed_polynomials_equal_the_generated_numpy_ones(benchmark_model):
    # The plain-float variant the code generator emits must be the same expressions.
    for model in [benchmark_model] + _random_models(benchmark_model, 50, 0.3, 1):
        entries = {
            f"{n}_{a}{b}": float(m[i, j])
            for n, m in zip(("M", "C1", "K0", "K2"), (model.M, model.C1, model.K0, model.K2))
            for i, a in enumerate(("phi", "delta"))
            for j, b in enumerate(("phi", "delta"))
        }
        scalar = gen.critical_speed_polynomials_scalar(**entries, g=model.g)
        vectorised = gen.critical_speed_polynomials(**entries, g=model.g)
        for ours, reference in zip(scalar, vectorised):
            np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-13 * np.abs(reference).max())


def test_critical_speeds_are_eigenvalue_crossings(benchmark_model):
    # Independent of the Hurwitz polynomials and of mode labels: just above and below each critical
    # speed, the number of eigenvalues with a positive real part changes by one at capsize (a real
    # root crosses zero) and by two at weave (a complex pair crosses the imaginary axis).
    def unstable(model, v):
        return int(np.sum(model.eigenvalues([v]).values.real > 0))

    checked = found_none = 0
    for model in _random_models(benchmark_model, 120, 0.4, 2):
        speeds = model.critical_speeds()
        if speeds.weave is None or speeds.capsize is None:
            found_none += 1
            continue
        eps = 1e-5 * max(speeds.weave, speeds.capsize)
        if abs(speeds.weave - speeds.capsize) < 100 * eps:
            continue
        # and in the direction that defines them: the weave pair turns stable, capsize unstable
        assert unstable(model, speeds.capsize + eps) - unstable(model, speeds.capsize - eps) == 1
        assert unstable(model, speeds.weave + eps) - unstable(model, speeds.weave - eps) == -2
        checked += 1
    assert checked > 5 and found_none > 0  # 8 of the 120 draws have both, well apart


def test_positive_real_roots_edge_cases():
    assert positive_real_roots(0.0, 0.0, 0.0) == []
    assert positive_real_roots(0.0, 2.0, -4.0) == [2.0]  # linear
    assert positive_real_roots(1e-20, 2.0, -4.0) == [2.0]  # leading coefficient below 1e-14
    assert positive_real_roots(1.0, 0.0, 1.0) == []  # u^2 + 1
    assert positive_real_roots(1.0, -3.0, 2.0) == pytest.approx([1.0, 2.0], rel=1e-15)
    assert positive_real_roots(1.0, 3.0, 2.0) == []  # both negative
    double = positive_real_roots(1.0, -4.0, 4.0 + 1e-18)  # rounding makes the pair complex
    assert double == pytest.approx([2.0, 2.0])


@pytest.mark.parametrize(
    "bad, field",
    [
        (np.ones(4), "coefficients"),
        (np.ones((3, 6)), "coefficients"),
        (np.array([[1.0, 2.0, np.nan, 1.0, 1.0]]), "coefficients[0, 2]"),
        (np.array([[1.0, 2.0, 3.0, 1.0, 1.0], [0.0, 2.0, 3.0, 1.0, 1.0]]), "coefficients[1, 0]"),
    ],
)
def test_bad_coefficients_are_named(bad, field):
    with pytest.raises(InputError) as info:
        quartic_roots(bad)
    assert info.value.name == field


def test_bad_speeds_are_named(benchmark_model):
    with pytest.raises(InputError) as info:
        eigenvalues_from_polynomial(benchmark_model, [1.0, np.inf])
    assert info.value.name == "speeds"


def test_overflowing_matrices_are_an_error_not_nan(benchmark_model):
    huge = WhippleModel(
        benchmark_model.M * 1e120,
        benchmark_model.C1 * 1e120,
        benchmark_model.K0 * 1e120,
        benchmark_model.K2 * 1e120,
        g=benchmark_model.g,
    )
    with pytest.raises(InputError) as info:
        huge.critical_speeds()
    assert "too large" in str(info.value)


def test_the_labels_of_polynomial_roots_follow_the_rules():
    # eigenvalues_from_polynomial labels its roots by label_modes; on quartics of every kind (four real
    # roots, one pair, two pairs) that must equal the rules applied one speed at a time.
    from bikerider.benchmark.quartic import _factored_roots

    rng = np.random.default_rng(11)
    roots = separated_roots(rng, 600)
    coefficients = np.array([np.poly(r).real for r in roots])
    with np.errstate(all="ignore"):  # as eigenvalues_from_polynomial calls it
        factored = _factored_roots(coefficients)
    values, labels = label_modes(factored.T)
    expected_values, expected_labels = _label_modes_loop(factored.T)
    scale = np.abs(expected_values).max(axis=1, keepdims=True)
    assert (np.abs(values - expected_values) / scale).max() < 1e-14
    np.testing.assert_array_equal(labels, expected_labels)
    assert {"other", "castor"} <= set(labels.ravel())  # every case was exercised


def _label_modes_loop(raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mode-labelling rules of ``bikerider.benchmark.mode_labels``, one speed at a time (an independent
    implementation, the oracle of the vectorised one)."""
    n = raw.shape[0]
    values = np.empty((n, 4), dtype=complex)
    labels = np.empty((n, 4), dtype=object)
    for k in range(n):
        ev = raw[k]
        tol = 1e-9 * max(1.0, float(np.abs(ev).max()))
        is_complex = np.abs(ev.imag) > tol
        complex_ev = ev[is_complex & (ev.imag > 0)]
        real_ev = np.sort(ev[~is_complex].real)
        if complex_ev.size == 0:  # all real: the two largest are the weave pair before it is born
            values[k] = [real_ev[3], real_ev[2], real_ev[1], real_ev[0]]
            labels[k] = ["weave", "weave", "capsize", "castor"]
        elif complex_ev.size == 1 and complex_ev[0].real < real_ev[0]:  # the two most negative have met
            w = complex_ev[0]
            values[k] = [real_ev[1], real_ev[0], w, np.conj(w)]
            labels[k] = ["weave", "weave", "other", "other"]
        elif complex_ev.size == 1:
            w = complex_ev[0]
            values[k] = [w, np.conj(w), real_ev[1], real_ev[0]]
            labels[k] = ["weave", "weave", "capsize", "castor"]
        else:
            pair = complex_ev[np.argsort(-complex_ev.imag)]
            values[k] = [pair[0], np.conj(pair[0]), pair[1], np.conj(pair[1])]
            labels[k] = ["weave", "weave", "other", "other"]
    return values, labels


def test_model_eigenvalues_quartic_method_equals_eigvals(benchmark_model):
    speeds = np.linspace(1.0, 10.0, 50)  # away from v_d = 0.684 m/s, where roots are double
    fast, reference = benchmark_model.eigenvalues(speeds, method="quartic"), benchmark_model.eigenvalues(speeds)
    assert (fast.labels == reference.labels).all()
    assert np.abs(fast.values - reference.values).max() < 1e-10
    with pytest.raises(InputError, match="method"):
        benchmark_model.eigenvalues(speeds, method="fast")
