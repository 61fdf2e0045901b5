"""Generated stage Jacobians (derive/sensitivities.py) against central finite differences.

Every stage of the chain is checked at random physical points - the paper's bicycle and rider
with every input scaled by a random factor within a few percent - for several batch shapes.
"""

from __future__ import annotations

import numpy as np
import pytest

from bikerider.io.chain_inputs import paper_inputs
from bikerider.uncertainty.chain import Chain, prepare_values
from bikerider.uncertainty.stages import all_stages

SHAPES = [(), (3,), (2, 4)]


def random_inputs(shape, seed, spread=0.02) -> dict[str, np.ndarray]:
    """The paper's inputs, each scaled by 1 + spread * N(0, 1), arms lengthened 3 cm so every
    closure has room at every sample."""
    rng = np.random.default_rng(seed)
    values = prepare_values(paper_inputs().quantities)
    out = {}
    for name, v in values.items():
        v = float(v) + (0.03 if name in ("l_la", "l_ua") else 0.0)
        out[name] = v * (1 + spread * rng.standard_normal(shape)) if np.isfinite(v) else np.asarray(v)
    return out


def _fd_columns(stage, nodes, step=1e-6):
    kw = stage.kwargs(nodes)
    columns = []
    for arg in stage.args:
        x = np.asarray(kw[arg], dtype=float)
        h = step * np.maximum(np.abs(x), 1e-2)
        plus = stage.value({**kw, arg: x + h})
        minus = stage.value({**kw, arg: x - h})
        columns.append(np.stack([(p - m) / (2 * h) for p, m in zip(plus, minus)], axis=-1))
    return np.stack(columns, axis=-1)


@pytest.mark.parametrize("shape", SHAPES)
def test_every_stage_jacobian_matches_finite_differences(shape):
    values = random_inputs(shape, seed=len(shape) + 1)
    chain = Chain(values)
    nodes = chain.evaluate(values)
    checked = []
    for stage in chain.stages:
        if stage.name == "rear_body":
            # IBfyy is NaN (not measured); check the rear body at a measured value instead
            nodes = {**nodes, "IBfyy": np.full(shape, 1.2)}
        J = np.asarray(stage.jacobian(stage.kwargs(nodes)))
        fd = _fd_columns(stage, nodes)
        J = np.broadcast_to(J, fd.shape)
        assert J.shape[-2:] == (len(stage.outputs), len(stage.inputs)), stage.name
        assert np.all(np.isfinite(J)), stage.name
        scale = np.max(np.abs(fd), axis=-1, keepdims=True) + 1e-12
        np.testing.assert_allclose(J / scale, fd / scale, atol=2e-6, err_msg=stage.name)
        checked.append(stage.name)
    # every stage of the raw-measurement chain ran
    assert set(checked) == {s.name for s in all_stages()} - {"handlebar_pendulum", "R_wheel_compound", "characteristic"}


def test_characteristic_and_handlebar_stages_with_their_inputs():
    """The stages the paper's inputs do not reach: handlebar periods, rear compound pendulum, a0..a4."""
    values = random_inputs((5,), seed=7)
    for name in ("IHxx", "IHxz", "IHzz", "IRyy"):
        del values[name]
    rng = np.random.default_rng(3)
    # Table 4 handlebar rows 1-2 (1.50 s at 37 deg, 0.70 s at 105 deg); the third orientation is a
    # made-up one (lost in the seed text) chosen far from the other two.
    values.update(
        T_H1=1.50 + 0.01 * rng.standard_normal(5),
        T_H2=0.70 + 0.01 * rng.standard_normal(5),
        T_H3=1.10 + 0.01 * rng.standard_normal(5),
        alpha_H1=np.radians(37.0),
        alpha_H2=np.radians(105.0),
        alpha_H3=np.radians(160.0),
        T_Ryy=1.40,
        l_pR=0.30,
        v=np.array([1.0, 3.0, 5.0, 7.0, 9.0]),
    )
    chain = Chain(values)
    names = [s.name for s in chain.stages]
    assert {"handlebar_pendulum", "R_wheel_compound", "characteristic"} <= set(names)
    nodes = chain.evaluate(values)
    for stage in chain.stages:
        if stage.name not in ("handlebar_pendulum", "R_wheel_compound", "characteristic"):
            continue
        fd = _fd_columns(stage, nodes)
        J = np.broadcast_to(stage.jacobian(stage.kwargs(nodes)), fd.shape)
        scale = np.max(np.abs(fd), axis=-1, keepdims=True) + 1e-12
        np.testing.assert_allclose(J / scale, fd / scale, atol=2e-6, err_msg=stage.name)


def test_staged_rider_equals_the_generated_rider_model():
    """The grid split (explicit points, closures, com, inertia about the com) is the rider model."""
    from bikerider.generated import rider_model

    values = random_inputs((6,), seed=11, spread=0.03)
    nodes = Chain(values).evaluate(values)
    geometry = {k: values[k] for k in "h_bb l_cs l_f rF l_hb lam_ht rR l_sp lam_st l_st l_s c w".split()}
    placement = {k: values[k] for k in "l_hh l_la l_ll l_ss l_to l_ua l_ul lam_fl c_h".split()}
    segments = {k: values[k] for k in "mBr c_ch c_la c_ll c_ua c_ul f_h f_la f_ll f_to f_ua f_ul".split()}
    points = rider_model.grid_points(**geometry, w_rh=0.13, w_fh=0.1, **placement)
    for k in (5, 13, 14, 15, 19, 23, 25):
        np.testing.assert_allclose(nodes[f"rX{k}"], points[..., k - 1, 0], rtol=1e-12)
        np.testing.assert_allclose(nodes[f"rZ{k}"], points[..., k - 1, 2], rtol=1e-12)
    mass, com, inertia = rider_model.rider_mass_properties(**geometry, **placement, **segments)
    np.testing.assert_allclose(nodes["mBr_sum"], mass, rtol=1e-12)
    np.testing.assert_allclose(nodes["xBr"], com[..., 0], rtol=1e-12)
    np.testing.assert_allclose(nodes["zBr"], com[..., 2], rtol=1e-12)
    for name, (i, j) in {"IBrxx": (0, 0), "IBryy": (1, 1), "IBrzz": (2, 2), "IBrxz": (0, 2)}.items():
        np.testing.assert_allclose(nodes[name], inertia[..., i, j], rtol=1e-11)


def test_state_matrix_jacobian_matches_finite_differences():
    from bikerider.generated import benchmark_model as gm
    from bikerider.generated import sensitivities as gen

    from bikerider.uncertainty.stages import ENTRIES

    values = random_inputs((), seed=5)
    nodes = Chain(values).evaluate(values)
    args = {k: float(nodes[k]) for k in ENTRIES}
    args.update(g=9.81, v=np.array([0.5, 4.0, 9.0]))
    J = gen.state_matrix_jacobian(**args)
    for j, name in enumerate(list(ENTRIES) + ["g", "v"]):
        h = 1e-6 * max(abs(float(np.max(args[name]))), 1e-2)
        plus = gm.state_matrix(**{**args, name: args[name] + h}).reshape(3, 16)
        minus = gm.state_matrix(**{**args, name: args[name] - h}).reshape(3, 16)
        np.testing.assert_allclose(J[..., j], (plus - minus) / (2 * h), rtol=1e-5, atol=1e-6, err_msg=name)
