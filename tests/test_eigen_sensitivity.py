"""Eigenvalue sensitivities from left and right eigenvectors against finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from bikerider.generated import benchmark_model as gm

from bikerider.benchmark.model import label_modes
from bikerider.errors import InputError
from bikerider.uncertainty.chain import Chain
from bikerider.uncertainty.eigen import PARAMETERS, eigen_sensitivity
from bikerider.uncertainty.propagation import propagate
from bikerider.uncertainty.stages import ENTRIES

SPEEDS = np.array([1.0, 3.0, 4.5, 6.0, 9.0])


def _labelled(entries, g, speeds):
    A = gm.state_matrix(**entries, g=g, v=speeds)
    values, _ = label_modes(np.linalg.eigvals(A))
    return values


@pytest.fixture(scope="module")
def benchmark_entries(benchmark_values):
    nodes = Chain(benchmark_values).evaluate(benchmark_values)
    return {k: float(nodes[k]) for k in ENTRIES}


def test_eigenvalue_derivatives_match_finite_differences(benchmark_entries):
    sens = eigen_sensitivity(benchmark_entries, 9.81, SPEEDS)
    np.testing.assert_allclose(sens.values, _labelled(benchmark_entries, 9.81, SPEEDS), rtol=1e-12)
    for p, name in enumerate(PARAMETERS):
        base = 9.81 if name == "g" else benchmark_entries[name]
        h = 1e-5 * max(abs(base), 1.0)

        def shifted(delta):
            entries = dict(benchmark_entries)
            g = 9.81
            if name == "g":
                g += delta
            else:
                entries[name] += delta
            return _labelled(entries, g, SPEEDS)

        fd = (shifted(h) - shifted(-h)) / (2 * h)
        scale = np.abs(sens.derivatives[..., p]).max() + 1e-9
        np.testing.assert_allclose(sens.derivatives[..., p] / scale, fd / scale, atol=1e-5, err_msg=name)
    assert np.all(sens.condition >= 1 - 1e-9)


def test_condition_number_grows_at_the_double_root(benchmark_entries):
    """Near v_d (0.684 m/s, Meijaard et al. 2007 Table 2) the weave pair is a double eigenvalue."""
    far = eigen_sensitivity(benchmark_entries, 9.81, [3.0]).condition[0, 0]
    near = eigen_sensitivity(benchmark_entries, 9.81, [0.6842]).condition[0, 0]
    assert near > 50 * far


def test_propagated_eigenvalue_sigmas_match_finite_difference_propagation():
    """sigma of Re/Im of each eigenvalue from the chain rule equals one built from perturbed chains."""
    from bikerider.io.chain_inputs import paper_inputs

    q = paper_inputs().quantities
    result = propagate(q, speeds=[2.0, 7.0])
    eig = result.eigenvalues
    assert eig is not None and eig.sigma_real.shape == (2, 4)
    from bikerider.uncertainty.chain import prepare_values

    values = prepare_values(q)
    chain = Chain(values)
    var_re = np.zeros((2, 4))
    var_im = np.zeros((2, 4))
    for name, quantity in q.items():
        if quantity.sigma == 0:
            continue
        h = 1e-6 * max(abs(quantity.value), 1e-2)
        lam = []
        for d in (h, -h):
            nodes = chain.evaluate({**values, name: values[name] + d})
            lam.append(_labelled({k: float(nodes[k]) for k in ENTRIES}, 9.81, np.array([2.0, 7.0])))
        d = (lam[0] - lam[1]) / (2 * h) * quantity.sigma
        var_re += d.real**2
        var_im += d.imag**2
    np.testing.assert_allclose(eig.sigma_real, np.sqrt(var_re), rtol=1e-4)
    np.testing.assert_allclose(eig.sigma_imag, np.sqrt(var_im), rtol=1e-4, atol=1e-12)
    assert eig.as_list()[0]["mode"] == "weave"


def test_bad_speeds_are_named(benchmark_entries):
    with pytest.raises(InputError, match="speeds"):
        eigen_sensitivity(benchmark_entries, 9.81, [[1.0, 2.0]])
    with pytest.raises(InputError, match="speeds"):
        eigen_sensitivity(benchmark_entries, 9.81, [float("inf")])
