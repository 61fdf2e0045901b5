"""Properties of every inertia tensor and mass sum the method produces, over random physical inputs.

The strategies (tests/strategies.py) perturb the paper's bicycle and rider and the Meijaard
benchmark within physical ranges.  Checks here are independent of ``bikerider.inertia``: symmetry,
positive principal moments and the triangle inequality are tested with ``numpy.linalg.eigvalsh``,
and the rider's tensor is recomputed from the grid points by a separate NumPy implementation of
Moore et al. (2009), Table 9 and Eqs. 8-14, summed about an arbitrary reference point.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from bikerider.generated import combination, rider_model
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import benchmark_mappings, factor, inertia_tensors, seated_pairs

from bikerider.benchmark import BenchmarkParameters
from bikerider.bicycle.pendulum import inertia_from_orientations
from bikerider.engine import arguments
from bikerider.estimate import chain_inputs
from bikerider.quantity import Quantity
from bikerider.rider.model import model_arguments

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def assert_physical_tensor(tensor: np.ndarray, what: str) -> None:
    """Symmetric, positive definite, principal moments within the triangle inequality."""
    t = np.asarray(tensor, dtype=float)
    assert t.shape == (3, 3), what
    assert np.all(np.isfinite(t)), what
    scale = np.abs(t).max()
    assert np.allclose(t, t.T, rtol=0, atol=1e-13 * scale), f"{what} not symmetric: {t}"
    p = np.linalg.eigvalsh(t)
    assert p[0] > 0, f"{what} not positive definite: principal {p}"
    assert p[2] <= p[0] + p[1] + 1e-12 * p.sum(), f"{what} breaks the triangle inequality: {p}"


def parallel_axis(m: float, d: np.ndarray) -> np.ndarray:
    """Eq. 13, written independently: m (|d|^2 E - d d^T)."""
    d = np.asarray(d, dtype=float)
    return m * (d @ d * np.eye(3) - np.outer(d, d))


# ---------------------------------------------------------------------------------------------
# An independent NumPy rider model (Table 9, Eqs. 8-14) over the generated grid points
# ---------------------------------------------------------------------------------------------
_LIMBS = (  # (fraction, circumference, length, (start, end) grid points, 1-based)
    ("f_ll", "c_ll", "l_ll", ((26, 28), (27, 29))),
    ("f_ul", "c_ul", "l_ul", ((28, 30), (29, 31))),
    ("f_ua", "c_ua", "l_ua", ((21, 23), (22, 24))),
    ("f_la", "c_la", "l_la", ((19, 23), (20, 24))),
)


def rider_segments(points: np.ndarray, a: dict[str, float]) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """``(mass, centre, tensor about the centre in the benchmark frame)`` of each of the 11 segments."""
    out = []

    def rotate(start: int, end: int, local: np.ndarray) -> np.ndarray:
        axis = points[end - 1] - points[start - 1]
        z = axis / np.linalg.norm(axis)
        y = np.array([0.0, 1.0, 0.0])
        x = np.cross(y, z)
        r = np.column_stack([x, y, z])
        return r @ local @ r.T

    m = a["f_to"] * a["mBr"]
    ly = a["l_ss"] - a["c_ua"] / math.pi
    lx = (a["c_ch"] - 2 * ly) / (math.pi - 2)
    lz = a["l_to"]
    box = m / 12 * np.diag([ly**2 + lz**2, lx**2 + lz**2, lx**2 + ly**2])
    out.append((m, (points[12] + points[14]) / 2, rotate(13, 15, box)))
    m = a["f_h"] * a["mBr"]
    radius = a["c_h"] / (2 * math.pi)
    out.append((m, points[24].copy(), 0.4 * m * radius**2 * np.eye(3)))
    for fraction, circumference, length, ends in _LIMBS:
        m = a[fraction] * a["mBr"]
        r = a[circumference] / (2 * math.pi)
        L = a[length]
        local = np.diag([m * (3 * r**2 + L**2) / 12] * 2 + [m * r**2 / 2])
        for start, end in ends:
            out.append((m, (points[start - 1] + points[end - 1]) / 2, rotate(start, end, local)))
    return out


def inertia_about(segments, point: np.ndarray) -> np.ndarray:
    return sum(I + parallel_axis(m, c - point) for m, c, I in segments)


@SETTINGS
@given(seated_pairs(), st.lists(factor(-2.0, 2.0), min_size=3, max_size=3))
def test_rider_inertia_is_physical_and_independent_of_the_reference_point(pair, offset):
    bicycle, rider, model = pair
    args = model_arguments(bicycle, rider)
    points = np.asarray(rider_model.grid_points(**{k: args[k] for k in arguments("rider_model.grid_points")}))
    segments = rider_segments(points, args)
    # The closures give every limb its measured length.
    for _, _, length, ends in _LIMBS:
        for start, end in ends:
            assert np.linalg.norm(points[end - 1] - points[start - 1]) == pytest.approx(args[length], rel=1e-9)
    mass = sum(m for m, _, _ in segments)
    com = sum(m * c for m, c, _ in segments) / mass
    assert model.mass == pytest.approx(rider["mBr"], rel=1e-12)  # the fractions sum to one
    assert model.mass == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose(model.com, com, rtol=0, atol=1e-12)
    # Sum about an arbitrary point P, then move to the centre of mass: the same tensor (Eq. 13).
    reference = np.asarray(offset)
    shifted = inertia_about(segments, reference) - parallel_axis(mass, com - reference)
    scale = np.abs(model.inertia).max()
    np.testing.assert_allclose(model.inertia, shifted, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(model.inertia, inertia_about(segments, com), rtol=0, atol=1e-10 * scale)
    assert_physical_tensor(model.inertia, "rider inertia")
    for m, _, I in segments:
        assert m > 0
        assert_physical_tensor(I, "rider segment")


@SETTINGS
@given(seated_pairs(), st.lists(factor(-2.0, 2.0), min_size=2, max_size=2))
def test_rear_body_conserves_mass_and_moment_and_is_physical(pair, offset):
    bicycle, rider, model = pair
    frame = {k: bicycle[k] for k in ("mBf", "xBf", "zBf", "IBfxx", "IBfzz", "IBfxz")}
    frame["IBfyy"] = bicycle["IBfyy"] if bicycle.get("IBfyy") is not None else math.nan
    I_r = model.inertia
    rider_body = dict(
        mBr=model.mass,
        xBr=model.com[0],
        zBr=model.com[2],
        IBrxx=I_r[0, 0],
        IBryy=I_r[1, 1],
        IBrzz=I_r[2, 2],
        IBrxz=I_r[0, 2],
    )
    mB, xB, zB, IB = (np.asarray(x) for x in combination.rear_body(**frame, **rider_body))
    assert float(mB) == pytest.approx(frame["mBf"] + model.mass, rel=1e-14)
    assert float(mB * xB) == pytest.approx(frame["mBf"] * frame["xBf"] + model.mass * model.com[0], rel=1e-12)
    assert float(mB * zB) == pytest.approx(frame["mBf"] * frame["zBf"] + model.mass * model.com[2], rel=1e-12)
    # Independent combination about an arbitrary point P in the XZ plane, moved to B's centre.
    frame_tensor = np.array(
        [[frame["IBfxx"], 0, frame["IBfxz"]], [0, frame["IBfyy"], 0], [frame["IBfxz"], 0, frame["IBfzz"]]]
    )
    rider_tensor = np.array([[I_r[0, 0], 0, I_r[0, 2]], [0, I_r[1, 1], 0], [I_r[0, 2], 0, I_r[2, 2]]])
    point = np.array([offset[0], 0.0, offset[1]])
    frame_c = np.array([frame["xBf"], 0.0, frame["zBf"]])
    rider_c = np.array([model.com[0], 0.0, model.com[2]])
    centre = np.array([float(xB), 0.0, float(zB)])
    about_p = (
        frame_tensor
        + parallel_axis(frame["mBf"], frame_c - point)
        + rider_tensor
        + parallel_axis(model.mass, rider_c - point)
    )
    expected = about_p - parallel_axis(float(mB), centre - point)
    finite = np.isfinite(expected)
    np.testing.assert_allclose(IB[finite], expected[finite], rtol=0, atol=1e-10 * np.abs(IB[finite]).max())
    if np.isfinite(frame["IBfyy"]):
        assert_physical_tensor(IB, "rear body B")
    else:  # I_yy not measured: the xz block is still a physical 2x2 tensor, I_yy stays undetermined
        assert np.isnan(IB[1, 1])
        block = IB[np.ix_([0, 2], [0, 2])]
        assert np.all(np.linalg.eigvalsh(block) > 0)


@SETTINGS
@given(seated_pairs())
def test_the_estimate_chain_conserves_total_mass_and_gives_physical_bodies(pair):
    bicycle, rider, model = pair
    inputs = {k: q.value for k, q in chain_inputs(bicycle, rider).items()}
    values = dict(
        zip(
            "w c lam g rR mR IRxx IRyy xB zB mB IBxx IByy IBzz IBxz xH zH mH IHxx IHyy IHzz IHxz rF mF IFxx IFyy".split(),
            np.asarray(combination.estimate_chain(**inputs), dtype=float),
        )
    )
    total_in = bicycle["mR"] + bicycle["mF"] + bicycle["mH"] + bicycle["mBf"] + rider["mBr"]
    total_out = values["mR"] + values["mF"] + values["mH"] + values["mB"]
    assert total_out == pytest.approx(total_in, rel=1e-13)
    # The rear body's first moment is the frame's plus the rider's (Eq. 16).
    assert values["mB"] * values["xB"] == pytest.approx(
        bicycle["mBf"] * bicycle["xBf"] + model.mass * model.com[0], rel=1e-12
    )
    params = BenchmarkParameters.from_mapping(
        {k: (None if not math.isfinite(x) else x) for k, x in values.items()}, "<hypothesis>"
    )
    for body in ("B", "H"):
        yy = params[f"I{body}yy"]
        tensor = np.array(
            [
                [params[f"I{body}xx"], 0, params[f"I{body}xz"]],
                [0, yy if yy is not None else np.nan, 0],
                [params[f"I{body}xz"], 0, params[f"I{body}zz"]],
            ],
            dtype=float,
        )
        if yy is None:
            assert np.all(np.linalg.eigvalsh(tensor[np.ix_([0, 2], [0, 2])]) > 0)
        else:
            assert_physical_tensor(tensor, f"benchmark body {body}")


@SETTINGS
@given(benchmark_mappings())
def test_benchmark_bodies_of_random_bicycles_are_physical(mapping):
    params = BenchmarkParameters.from_mapping(mapping, "<hypothesis>")
    v = params.values
    for body in ("B", "H"):
        tensor = np.array(
            [[v[f"I{body}xx"], 0, v[f"I{body}xz"]], [0, v[f"I{body}yy"], 0], [v[f"I{body}xz"], 0, v[f"I{body}zz"]]],
            dtype=float,
        )
        assert_physical_tensor(tensor, f"I{body}")
    for wheel in ("R", "F"):  # an axisymmetric wheel: diag(Ixx, Iyy, Ixx)
        assert_physical_tensor(np.diag([v[f"I{wheel}xx"], v[f"I{wheel}yy"], v[f"I{wheel}xx"]]), f"wheel {wheel}")


# ---------------------------------------------------------------------------------------------
# Pendulum reductions (Eqs. 1-6)
# ---------------------------------------------------------------------------------------------
K_T = 5.01  # N m/rad, the paper's torsional pendulum (Kooijman 2006 as quoted by Moore et al. 2009)


def periods_for(tensor: np.ndarray, angles: np.ndarray) -> list[Quantity]:
    """Forward model, independent of the generated rows: J = e^T I e, e = [cos a, 0, -sin a]; T = 2 pi sqrt(J/k)."""
    out = []
    for a in angles:
        e = np.array([math.cos(a), 0.0, -math.sin(a)])
        out.append(Quantity(2 * math.pi * math.sqrt(e @ tensor @ e / K_T)))
    return out


_angle_triples = st.tuples(factor(-0.3, 0.3), factor(0.8, 1.5), factor(2.0, 2.8))


@SETTINGS
@given(inertia_tensors(), _angle_triples, st.lists(st.booleans(), min_size=3, max_size=3))
def test_pendulum_reduction_recovers_the_tensor_and_ignores_half_turns(tensor, angles, flips):
    angles = np.asarray(angles)
    periods = periods_for(tensor, angles)
    first = inertia_from_orientations(Quantity(K_T), periods, [Quantity(a) for a in angles], "body")
    recovered = np.array([q.value for q in first])
    np.testing.assert_allclose(recovered, [tensor[0, 0], tensor[0, 2], tensor[2, 2]], rtol=1e-9, atol=1e-12)
    xx, xz, zz = recovered
    assert_physical_tensor(np.array([[xx, 0, xz], [0, tensor[1, 1], 0], [xz, 0, zz]]), "pendulum reduction")
    # Turning any orientation by 180 degrees is the same pendulum axis: the same tensor.
    turned = [a + math.pi if f else a for a, f in zip(angles, flips)]
    second = inertia_from_orientations(Quantity(K_T), periods, [Quantity(a) for a in turned], "body")
    np.testing.assert_allclose([q.value for q in second], recovered, rtol=1e-9, atol=1e-12)
    every = inertia_from_orientations(Quantity(K_T), periods, [Quantity(a + math.pi) for a in angles], "body")
    np.testing.assert_allclose([q.value for q in every], recovered, rtol=1e-9, atol=1e-12)


@SETTINGS
@given(inertia_tensors(), st.lists(factor(-1.5, 1.5), min_size=4, max_size=6, unique=True))
def test_least_squares_reduction_with_more_orientations(tensor, angles):
    angles = np.sort(np.asarray(angles))
    if np.min(np.diff(angles)) < 0.2 or angles[-1] - angles[0] > math.pi - 0.2:
        angles = np.linspace(-1.4, 1.4, len(angles))
    periods = periods_for(tensor, angles)
    result = inertia_from_orientations(Quantity(K_T), periods, [Quantity(a) for a in angles], "body")
    np.testing.assert_allclose(
        [q.value for q in result], [tensor[0, 0], tensor[0, 2], tensor[2, 2]], rtol=1e-9, atol=1e-12
    )
    flipped = inertia_from_orientations(Quantity(K_T), periods, [Quantity(a - math.pi) for a in angles], "body")
    np.testing.assert_allclose([q.value for q in flipped], [q.value for q in result], rtol=1e-9, atol=1e-12)
