"""The engine's one-point path (sparse Jacobians written straight into the gradient matrix, sigmas
summed over the entries that can count) against plain dense forward mode: every stage's whole
Jacobian times the stacked gradients of its inputs, and every row's root sum of squares.

The two must agree bit for bit where every entry is finite, and where one is not (a NaN input
without uncertainty, as a Measured file without seating measurements gives) the point path must
spread it as the product does.
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from bikerider.bicycle import raw_measurements, to_benchmark
from bikerider.engine import Chain, first_order
from bikerider.engine.first_order import _root_sum_squares
from bikerider.io.bicycleparameters import load_measured_bicycle, read_lumped_rider
from bikerider.io.name_value_file import read_name_value_file
from bikerider.quantity import Quantity

DATA = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
BICYCLES = DATA / "bicycles"
RIDER = DATA / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt"


def dense_forward_mode(stages, values, wrt):
    """Reference: ``G[outputs] = J @ G[inputs]`` with each stage's whole Jacobian."""
    chain = Chain(stages, values)
    rows = {name: i for i, name in enumerate(values)}
    for stage in chain.stages:
        for name in stage.outputs:
            rows[name] = len(rows)
    G = np.zeros((len(rows), len(wrt)))
    for k, name in enumerate(wrt):
        G[rows[name], k] = 1.0
    nodes = dict(values)
    with np.errstate(invalid="ignore", divide="ignore"):
        for stage in chain.stages:
            outputs, checks, J = stage.evaluate_with_jacobian(stage.kwargs(nodes))
            nodes.update(zip(stage.outputs, outputs))
            nodes.update(zip(stage.checks, checks))
            G[[rows[n] for n in stage.outputs]] = J @ G[[rows[n] for n in stage.inputs]]
    return nodes, rows, G


def measured_case(bike: str, drop: tuple[str, ...] = ()):
    values = read_name_value_file(BICYCLES / bike / "RawData" / f"{bike}Measured.txt").as_dict()
    for name in drop:
        values.pop(name)
    layout = raw_measurements.detect_layout(values)
    stages = raw_measurements._stages(raw_measurements._layout_key(layout, "least_squares"))
    return stages, raw_measurements.measured_inputs(values, layout)


def rider_case():
    bodies = load_measured_bicycle(BICYCLES / "Browser" / "RawData" / "BrowserMeasured.txt").values
    rider = read_lumped_rider(RIDER).values
    inputs = {name: bodies.get(name) or Quantity(math.nan) for name in to_benchmark._FRAME}
    inputs.update({name: rider.get(name) or Quantity(math.nan) for name in to_benchmark.RIDER_BODY_NAMES})
    inputs["lam_ht"] = bodies["lam_ht"]
    return to_benchmark._STAGES, inputs


CASES = {
    "standard layout (one generated stage)": lambda: measured_case("Browser"),
    "standard layout without seating (NaN inputs)": lambda: measured_case(
        "Browser", tuple(raw_measurements.SEATING_FIELDS)
    ),
    "stages one by one, least squares (Rigid)": lambda: measured_case("Rigid"),
    "lumped rider merged (NaN IBfyy)": rider_case,
}


@pytest.mark.parametrize("case", CASES)
def test_point_gradients_and_sigmas_equal_dense_forward_mode(case):
    stages, quantities = CASES[case]()
    result = first_order(stages, quantities)
    values = {name: q.value for name, q in quantities.items()}
    nodes, rows, G = dense_forward_mode(stages, values, result.wrt)
    names = [name for name in rows if name not in quantities]
    assert names, "the case computes nothing"
    for name in names:
        np.testing.assert_array_equal(result.gradients[name], G[rows[name]], err_msg=name)
        assert result.nodes[name] == nodes[name] or (math.isnan(result.nodes[name]) and math.isnan(nodes[name]))
    expected = _root_sum_squares(G[[rows[n] for n in names]], result.sigmas)
    got = result.quantities(names)
    for name, sigma in zip(names, expected):
        value = nodes[name]
        assert got[name].sigma == (sigma if math.isfinite(value) else 0.0), name


def test_a_non_finite_entry_spreads_as_through_the_product():
    """Without seating measurements the seating stage's inputs are NaN (no uncertainty): the rows
    they reach are NaN in every column, as ``J @ G`` makes them, and their sigma is 0."""
    stages, quantities = measured_case("Browser", tuple(raw_measurements.SEATING_FIELDS))
    result = first_order(stages, quantities)
    assert np.isnan(result.gradients["l_hb"]).all()
    assert np.isfinite(result.gradients["IBfxx"]).all()
    assert result.quantity("l_hb").sigma == 0.0
