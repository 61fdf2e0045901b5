"""The Measured-file reduction over batches, its least-squares stages, and the one inertia check.

The reduction's stages broadcast over batches of points; these tests check that a batch gives what
its points give one at a time, that the least-squares stage's solution and exact Jacobian agree with
general solvers and with central differences, that its pairwise-mean variant equals solving each
pair, and that the one tensor check (``bikerider.inertia``) agrees with an independent eigenvalue
check.  ``tests/measured_oracle.py`` is the independent NumPy reduction they compare with.
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import measured_oracle as oracle
import numpy as np
import pytest

from bikerider.bicycle import raw_measurements as rm
from bikerider.bicycle.pendulum import centre_of_mass_from_lines
from bikerider.engine import Chain, LeastSquaresStage
from bikerider.errors import FitError, InputError
from bikerider.inertia import inertia_problem
from bikerider.io.name_value_file import read_name_value_file
from bikerider.quantity import Quantity

DATA = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
#: Browser: wheelbase geometry, three orientations, seating; Rigid: heights-and-diameters geometry,
#: handlebar and fork hung apart, five orientations (least squares of Eq. 6).
MEASURED = {name: DATA / "bicycles" / name / "RawData" / f"{name}Measured.txt" for name in ("Browser", "Rigid")}


def _arithmetic(x):
    """Plain arithmetic (correctly rounded, so identical on floats and on arrays), a constant output
    and one that is NaN."""
    return {
        "p": x["a"] * x["b"] + x["c"] / x["a"],
        "q": np.sqrt(x["b"] * x["b"] + x["c"]),
        "const": 2.5,
        "nan": x["a"] * math.nan,
    }


INPUTS = {"a": Quantity(1.5, 0.01), "b": Quantity(-0.7, 0.002), "c": Quantity(3.0, 0.0), "d": Quantity(9.0, 0.5)}


def test_the_oracles_vectorized_and_pointwise_propagation_are_identical():
    pointwise = oracle.propagate(_arithmetic, INPUTS)
    batched = oracle.propagate(_arithmetic, INPUTS, vectorized=True)
    assert list(pointwise) == list(batched) == ["p", "q", "const", "nan"]
    for key in ("p", "q", "const"):
        assert batched[key] == pointwise[key], key
    assert math.isnan(batched["nan"].value) and batched["nan"].sigma == pointwise["nan"].sigma == 0.0


def test_the_oracles_propagation_matches_the_first_order_formula():
    a, b, c = (INPUTS[k] for k in "abc")
    # p = a b + c / a: dp/da = b - c / a^2, dp/db = a (c and d carry no uncertainty that matters)
    expected = math.hypot((b.value - c.value / a.value**2) * a.sigma, a.value * b.sigma)
    for vectorized in (False, True):
        result = oracle.propagate(_arithmetic, INPUTS, vectorized=vectorized)
        assert result["p"].sigma == pytest.approx(expected, rel=1e-8)
        assert result["const"].sigma == 0.0


@pytest.mark.parametrize("name", sorted(MEASURED))
@pytest.mark.parametrize("method", ["least_squares", "pairwise_mean"])
def test_a_batch_reduces_as_its_points_one_by_one(name, method):
    """Each point of a batch perturbs different inputs, so mixing points up anywhere would show."""
    values = read_name_value_file(MEASURED[name]).as_dict()
    layout = rm.detect_layout(values)
    inputs = rm.measured_inputs(values, layout)
    chain = Chain(rm._stages(rm._layout_key(layout, method)), inputs)
    rng = np.random.default_rng(7)
    batch = {
        k: q.value + (q.sigma or 1e-4 * abs(q.value)) * rng.uniform(-1, 1, 5) if math.isfinite(q.value) else q.value
        for k, q in inputs.items()
    }
    together = chain.evaluate(batch)
    for point in range(5):
        alone = chain.evaluate({k: float(v[point]) if np.ndim(v) else v for k, v in batch.items()})
        for key, value in alone.items():
            value = float(value)
            got = np.broadcast_to(together[key], (5,))[point]
            if math.isnan(value):
                assert math.isnan(got), key
            else:
                assert got == pytest.approx(value, rel=1e-12, abs=1e-15), (key, point)


@pytest.mark.parametrize("name", sorted(MEASURED))
def test_reduction_equals_the_oracles_pointwise_propagation(name):
    """The reduction's exact sigmas against central differences evaluated one point at a time."""
    data = read_name_value_file(MEASURED[name])
    reduction = rm.reduce_measured(data, source=data)
    values = {k: q for k, q in data.items() if k not in oracle.KNOWN_EXTRAS}
    pointwise = oracle.propagate(lambda x: oracle.evaluate_measured(x, reduction.layout), values)
    results = {**reduction.bodies.values, **reduction.extras}
    assert set(results) == {k for k, q in pointwise.items() if math.isfinite(q.value)}
    for key, q in results.items():
        assert q.value == pytest.approx(pointwise[key].value, rel=1e-12, abs=1e-15), key
        # central differences at a relative step of 1e-6 resolve a sigma to about 1e-8
        assert q.sigma == pytest.approx(pointwise[key].sigma, rel=1e-6, abs=1e-15), key


def _random_lines(rng, batch, m):
    betas = rng.uniform(0, math.pi, (batch, m))
    return betas, rng.normal(0, 0.5, (batch, m, 2))


def _lines_stage(m: int, method: str = "least_squares") -> LeastSquaresStage:
    rows = [{"alpha": f"alpha_{i}", "x_p": f"x_{i}", "z_p": f"z_{i}"} for i in range(m)]
    return LeastSquaresStage("lines", "line_through_point", rows, ("s", "c"), "d", ("x", "z"), method)


def test_the_least_squares_stage_equals_lstsq_and_svd():
    """Lines through random points: the solution and the conditioning against NumPy's solvers, for
    a batch of 200 line sets at once."""
    rng = np.random.default_rng(1)
    betas, points = _random_lines(rng, 200, 4)
    stage = _lines_stage(4)
    kw = {f"alpha_{i}": betas[:, i] for i in range(4)}
    kw.update({f"x_{i}": points[:, i, 0] for i in range(4)} | {f"z_{i}": points[:, i, 1] for i in range(4)})
    (x, z), checks = stage.evaluate(kw)
    conditioning = checks[-2]
    for i in range(200):
        normals = np.column_stack([np.sin(betas[i]), np.cos(betas[i])])
        d = np.sum(normals * points[i], axis=1)
        point, *_ = np.linalg.lstsq(normals, d, rcond=None)
        singular = np.linalg.svd(normals, compute_uv=False)
        assert conditioning[i] == pytest.approx(singular[-1] / singular[0], rel=1e-9, abs=1e-12)
        if conditioning[i] > 1e-3:
            assert (x[i], z[i]) == pytest.approx(tuple(point), rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("method", ["least_squares", "pairwise_mean"])
def test_the_least_squares_stage_jacobian_matches_central_differences(method):
    rng = np.random.default_rng(4)
    betas, points = _random_lines(rng, 1, 5)
    stage = _lines_stage(5, method)
    kw = {f"alpha_{i}": float(betas[0, i]) for i in range(5)}
    kw.update(
        {f"x_{i}": float(points[0, i, 0]) for i in range(5)} | {f"z_{i}": float(points[0, i, 1]) for i in range(5)}
    )
    J = stage.jacobian(kw)
    for j, name in enumerate(stage.inputs):
        h = 1e-6
        up = np.array(stage.value({**kw, name: kw[name] + h}))
        down = np.array(stage.value({**kw, name: kw[name] - h}))
        np.testing.assert_allclose(J[:, j], (up - down) / (2 * h), rtol=1e-6, atol=1e-8, err_msg=name)


def test_the_pairwise_mean_equals_solving_each_pair():
    rng = np.random.default_rng(2)
    betas, points = _random_lines(rng, 50, 5)
    stage = _lines_stage(5, "pairwise_mean")
    kw = {f"alpha_{i}": betas[:, i] for i in range(5)}
    kw.update({f"x_{i}": points[:, i, 0] for i in range(5)} | {f"z_{i}": points[:, i, 1] for i in range(5)})
    x, z = stage.value(kw)
    for i in range(50):
        normals = np.column_stack([np.sin(betas[i]), np.cos(betas[i])])
        d = np.sum(normals * points[i], axis=1)
        pairs = [np.linalg.solve(normals[[a, b]], d[[a, b]]) for a in range(5) for b in range(a + 1, 5)]
        assert (x[i], z[i]) == pytest.approx(tuple(np.mean(pairs, axis=0)), rel=1e-8, abs=1e-10)


def test_parallel_hanging_lines_are_refused():
    points = [(Quantity(0.0), Quantity(0.1)), (Quantity(0.0), Quantity(-0.2)), (Quantity(0.0), Quantity(0.3))]
    angles = [Quantity(0.0), Quantity(math.pi), Quantity(1e-5)]
    with pytest.raises(FitError, match="parallel"):
        centre_of_mass_from_lines(points, angles, "frame")


def test_the_inertia_check_agrees_with_eigenvalues():
    """The one tensor check against the principal moments from ``eigvalsh``, around the triangle
    limit (within a hair of it on purpose) and the positive-definite one."""
    rng = np.random.default_rng(3)
    decided = 0
    for _ in range(3000):
        xx, zz = rng.uniform(0.05, 2.0, 2)
        xz = rng.uniform(-1, 1) * math.sqrt(xx * zz) * rng.choice([1.0, 0.999999, 1.0000001])
        yy = (xx + zz) * rng.choice([rng.uniform(0.3, 1.6), 1 + rng.normal(0, 1e-7)])
        principal = np.linalg.eigvalsh(np.array([[xx, 0.0, xz], [0.0, yy, 0.0], [xz, 0.0, zz]]))
        margin = (principal[0] + principal[1] - principal[2]) / principal.sum()
        if abs(margin) < 1e-8 or abs(principal[0]) < 1e-8 * principal.sum():
            continue  # within round-off of a limit: either answer is right
        decided += 1
        assert (inertia_problem(xx, yy, zz, xz) is None) == (margin > 0 and principal[0] > 0), (xx, xz, zz, yy)
    assert decided > 2000
    assert inertia_problem(0.5, 1.0, 0.7, -0.1) is None  # an ordinary frame
    assert "triangle" in inertia_problem(0.5, 1.3, 0.7, -0.1)[1]  # I_yy beyond the in-plane moments' sum
    assert inertia_problem(0.5, None, 0.7, -0.1) is None  # I_yy not determined: the xz block alone


def test_two_parallel_lines_leave_the_pairwise_mean_undefined():
    """BicycleParameters' pairwise mean needs every pair of lines to cross; the least-squares point
    does not (here two of Rigid's five rear frame lines are made parallel, 1 mm apart)."""
    from bikerider.io.name_value_file import parse_name_value_text

    text = MEASURED["Rigid"].read_text()
    text = text.replace("alphaB5 = 51.8+/-0.1", "alphaB5 = 55.7+/-0.1").replace(
        "aB5 = 0.51625+/-0.001", "aB5 = 0.51925+/-0.001"
    )
    data = parse_name_value_text(text, "Parallel.txt")
    assert data["alphaB5"].value == data["alphaB3"].value
    assert "xBf" in rm.reduce_measured(data, source=data).bodies.values
    with pytest.raises(
        FitError, match=r"Parallel.txt: the hanging lines are parallel: two lines of the rear frame \(B\)"
    ):
        rm.reduce_measured(data, source=data, com_method="pairwise_mean")


def test_a_compound_period_too_short_is_named(tmp_path):
    values = read_name_value_file(MEASURED["Browser"]).as_dict()
    values["TcB1"] = Quantity(0.3, 0.001)
    with pytest.raises(InputError, match="TcB1.*shorter one gives a negative moment of inertia"):
        rm.reduce_measured(values)
