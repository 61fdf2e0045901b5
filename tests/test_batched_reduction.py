"""The batched raw-measurement reduction: one call over every point of the numerical Jacobian.

``propagate(..., vectorized=True)`` evaluates the nominal point and every perturbed point in one
array call; these tests check that this gives what evaluating the points one at a time gives, that
the batched building blocks (closed-form least squares of the hanging lines, pairwise mean) agree
with general solvers, and that the closed-form I_yy screen never contradicts the full tensor check.
"""
from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from bikerider.bicycle import raw_measurements as rm
from bikerider.bicycle.hanging_lines import (
    intersect_lines, least_squares_point, mean_of_pairwise_intersections, pairwise_mean_point,
)
from bikerider.bicycle.propagation import perturbed_points, propagate
from bikerider.errors import FitError, InputError
from bikerider.inertia import check_inertia_tensor
from bikerider.io.name_value_file import read_name_value_file
from bikerider.quantity import Quantity

DATA = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
#: Browser: wheelbase geometry, three orientations, seating; Rigid: heights-and-diameters geometry,
#: handlebar and fork hung apart, five orientations (least squares of Eq. 6).
MEASURED = {name: DATA / "bicycles" / name / "RawData" / f"{name}Measured.txt" for name in ("Browser", "Rigid")}


def _arithmetic(x):
    """Plain arithmetic (correctly rounded, so identical on floats and on arrays), a constant output
    and one that is NaN."""
    return {"p": x["a"] * x["b"] + x["c"] / x["a"], "q": np.sqrt(x["b"] * x["b"] + x["c"]), "const": 2.5,
            "nan": x["a"] * math.nan}


INPUTS = {"a": Quantity(1.5, 0.01), "b": Quantity(-0.7, 0.002), "c": Quantity(3.0, 0.0), "d": Quantity(9.0, 0.5)}


def test_vectorized_and_pointwise_propagation_are_identical():
    pointwise = propagate(_arithmetic, INPUTS)
    batched = propagate(_arithmetic, INPUTS, vectorized=True)
    assert list(pointwise) == list(batched) == ["p", "q", "const", "nan"]
    for key in ("p", "q", "const"):
        assert batched[key] == pointwise[key], key
    assert math.isnan(batched["nan"].value) and batched["nan"].sigma == pointwise["nan"].sigma == 0.0


def test_propagation_matches_the_first_order_formula():
    a, b, c = (INPUTS[k] for k in "abc")
    # p = a b + c / a: dp/da = b - c / a^2, dp/db = a (c and d carry no uncertainty that matters)
    expected = math.hypot((b.value - c.value / a.value**2) * a.sigma, a.value * b.sigma)
    for vectorized in (False, True):
        result = propagate(_arithmetic, INPUTS, vectorized=vectorized)
        assert result["p"].sigma == pytest.approx(expected, rel=1e-8)
        assert result["const"].sigma == 0.0


def test_perturbed_points_step_each_uncertain_input_up_then_down():
    points, varied, steps, sigmas = perturbed_points(INPUTS)
    assert points.shape == (4, 2 * 3 + 1)  # a, b, d have an uncertainty
    assert varied.tolist() == [0, 1, 3]
    assert sigmas.tolist() == [0.01, 0.002, 0.5]
    nominal = np.array([q.value for q in INPUTS.values()])
    assert np.array_equal(points[:, 0], nominal)
    for j, i in enumerate(varied):
        up, down = points[:, 2 * j + 1], points[:, 2 * j + 2]
        assert up[i] == nominal[i] + steps[j] and down[i] == nominal[i] - steps[j]
        others = np.arange(4) != i
        assert np.array_equal(up[others], nominal[others]) and np.array_equal(down[others], nominal[others])


@pytest.mark.parametrize("name", sorted(MEASURED))
@pytest.mark.parametrize("method", ["least_squares", "pairwise_mean"])
def test_a_batch_reduces_as_its_points_one_by_one(name, method):
    """Each point of a batch perturbs different inputs, so mixing points up anywhere would show."""
    values = read_name_value_file(MEASURED[name]).as_dict()
    layout = rm.detect_layout(values)
    rng = np.random.default_rng(7)
    nominal = {k: q.value for k, q in values.items()}
    batch = {k: v + (q.sigma or 1e-4 * abs(v)) * rng.uniform(-1, 1, 5) for (k, q), v in zip(values.items(), nominal.values())}
    together = rm.evaluate_measured(batch, layout, com_method=method)
    for point in range(5):
        alone = rm.evaluate_measured({k: float(v[point]) for k, v in batch.items()}, layout, com_method=method)
        assert set(alone) == set(together)
        for key, value in alone.items():
            if math.isnan(value):
                assert math.isnan(together[key][point]), key
            else:
                assert together[key][point] == pytest.approx(value, rel=1e-12, abs=1e-15), (key, point)


@pytest.mark.parametrize("name", sorted(MEASURED))
def test_reduction_equals_the_pointwise_propagation(name):
    """The batched reduction against the same Jacobian evaluated one point at a time."""
    data = read_name_value_file(MEASURED[name])
    reduction = rm.reduce_measured(data, source=data)
    values = {k: q for k, q in data.items() if k not in ("xcl", "zcl", "ds1", "ds3")}
    pointwise = propagate(lambda x: rm.evaluate_measured(x, reduction.layout), values)
    results = {**reduction.bodies.values, **reduction.extras}
    assert set(results) == {k for k, q in pointwise.items() if math.isfinite(q.value)}
    for key, q in results.items():
        assert q.value == pytest.approx(pointwise[key].value, rel=1e-12, abs=1e-15), key
        # central differences at a relative step of 1e-6 resolve a sigma to about 1e-8
        assert q.sigma == pytest.approx(pointwise[key].sigma, rel=1e-6, abs=1e-15), key


def _random_lines(rng, batch, m):
    betas = rng.uniform(0, math.pi, (batch, m))
    return np.sin(betas), np.cos(betas), rng.normal(0, 0.5, (batch, m))


def test_closed_form_least_squares_equals_lstsq_and_svd():
    rng = np.random.default_rng(1)
    sin, cos, d = _random_lines(rng, 200, 4)
    x, z, conditioning = least_squares_point(sin, cos, d)
    for i in range(200):
        normals = np.column_stack([sin[i], cos[i]])
        point, *_ = np.linalg.lstsq(normals, d[i], rcond=None)
        singular = np.linalg.svd(normals, compute_uv=False)
        assert conditioning[i] == pytest.approx(singular[-1] / singular[0], rel=1e-9, abs=1e-12)
        if conditioning[i] > 1e-3:
            assert (x[i], z[i]) == pytest.approx(tuple(point), rel=1e-9, abs=1e-12)
    # the lines axis may be any axis
    x0, z0, c0 = least_squares_point(sin.T, cos.T, d.T, axis=0)
    assert np.array_equal(x0, x) and np.array_equal(z0, z) and np.array_equal(c0, conditioning)


def test_batched_pairwise_mean_equals_solving_each_pair():
    rng = np.random.default_rng(2)
    sin, cos, d = _random_lines(rng, 50, 5)
    x, z = pairwise_mean_point(sin, cos, d)
    for i in range(50):
        normals = np.column_stack([sin[i], cos[i]])
        pairs = [np.linalg.solve(normals[[a, b]], d[i, [a, b]]) for a in range(5) for b in range(a + 1, 5)]
        assert (x[i], z[i]) == pytest.approx(tuple(np.mean(pairs, axis=0)), rel=1e-8, abs=1e-10)
        assert mean_of_pairwise_intersections(normals, d[i]) == pytest.approx(np.array([x[i], z[i]]))


def test_parallel_hanging_lines_are_refused():
    normals = np.array([[0.0, 1.0], [0.0, -1.0], [1e-5, 1.0]])
    with pytest.raises(FitError, match="parallel"):
        intersect_lines(normals / np.linalg.norm(normals, axis=1)[:, None], np.array([0.1, 0.2, 0.3]))


def test_the_closed_form_yy_screen_never_contradicts_the_tensor_check():
    rng = np.random.default_rng(3)
    decided = 0
    for _ in range(3000):
        xx, zz = rng.uniform(0.05, 2.0, 2)
        xz = rng.uniform(-1, 1) * math.sqrt(xx * zz) * rng.choice([1.0, 0.999999, 1.0000001])
        # around the triangle limit yy = xx + zz, sometimes within the screen's margin of it
        yy = (xx + zz) * rng.choice([rng.uniform(0.3, 1.6), 1 + rng.normal(0, 1e-7)])
        verdict = rm._triangle_verdict(xx, xz, zz, yy)
        if verdict is None:
            continue
        decided += 1
        tensor = np.array([[xx, 0.0, xz], [0.0, yy, 0.0], [xz, 0.0, zz]])
        try:
            check_inertia_tensor("I", tensor)
            passes = True
        except InputError:
            passes = False
        assert passes == (verdict > 0), (xx, xz, zz, yy)
    assert decided > 1000  # about half the draws are within the margin of a limit on purpose
    assert rm._triangle_verdict(0.5, -0.1, 0.7, 1.0) == 1.0  # an ordinary frame
    assert rm._triangle_verdict(0.5, -0.1, 0.7, 1.3) == -1.0  # I_yy beyond the in-plane moments' sum
    assert rm._triangle_verdict(0.5, -0.1, 0.7, 1.2) is None  # exactly at the limit: the full check decides


def test_two_parallel_lines_leave_the_pairwise_mean_undefined():
    """BicycleParameters' pairwise mean needs every pair of lines to cross; the least-squares point
    does not (here two of Rigid's five rear frame lines are made parallel, 1 mm apart)."""
    from bikerider.io.name_value_file import parse_name_value_text

    text = MEASURED["Rigid"].read_text()
    text = text.replace("alphaB5 = 51.8+/-0.1", "alphaB5 = 55.7+/-0.1").replace("aB5 = 0.51625+/-0.001", "aB5 = 0.51925+/-0.001")
    data = parse_name_value_text(text, "Parallel.txt")
    assert data["alphaB5"].value == data["alphaB3"].value
    assert "xBf" in rm.reduce_measured(data, source=data).bodies.values
    with pytest.raises(FitError, match=r"Parallel.txt: the hanging lines are parallel: two lines of the rear frame \(B\)"):
        rm.reduce_measured(data, source=data, com_method="pairwise_mean")
