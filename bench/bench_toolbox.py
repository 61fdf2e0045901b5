"""Dynamics toolbox at scale: A(v) and eigenvalues for 1e6 (bicycle, speed) pairs; a stability map.

Bicycles: 10000 random valid parameter sets (each benchmark parameter within +/-50 % of Meijaard
et al. 2007, as in the tests) at 100 speeds 0-10 m/s, one batched ``WhippleModel``; both sides work
in chunks of 1000 bicycles (1e5 pairs) so that neither holds more than a few hundred MB.

* ``A(v)``: bikerider's generated ``state_matrix`` (``WhippleModel.state_matrix``) against plain
  NumPy: ``inv(M)`` of the stacked mass matrices, then ``[[0, I], [-M^-1 (g K0 + v^2 K2),
  -M^-1 v C1]]`` by broadcasting.
* eigenvalues: bikerider's ``WhippleModel.eigenvalues(method="quartic")`` (generated characteristic
  coefficients, closed-form quartic, mode labels) against ``numpy.linalg.eigvals`` of the stacked
  NumPy state matrices (built as above, included; no labels).
* stability map: ``bikerider.benchmark.sweep.stability_map`` over trail x rear-body mass, 200 x 200
  designs, then stability at 100 speeds (validity checks, generated matrices, the stable intervals
  from the Routh-Hurwitz polynomials, ``Sweep.stable()``) against plain NumPy on the same generated
  canonical matrices (given to it untimed): state matrices at every speed, ``eigvals``, all real
  parts negative.  The notes count the (design, speed) points where the two disagree.
"""

from __future__ import annotations

import numpy as np
from common import ROOT, Context, Row, measure_together, ratio_text

PAIRS_BICYCLES, PAIRS_SPEEDS, CHUNK = 10_000, 100, 1000
MAP_SIDE, MAP_SPEEDS = 200, 100
GOAL_A, GOAL_EIGENVALUES, GOAL_MAP = 2.0, 3.0, 20.0
"""Ratios to plain NumPy each item must reach."""


def _random_models(n: int):
    import sys

    sys.path.insert(0, str(ROOT / "tests"))
    from random_bicycles import random_parameters

    from bikerider.benchmark import WhippleModel
    from bikerider.benchmark.model import MATRIX_NAMES

    models = [WhippleModel.from_parameters(p) for p in random_parameters(n, 0.5, seed=11)]
    mats = [np.stack([getattr(m, name) for m in models]) for name in MATRIX_NAMES]
    return WhippleModel(*mats, g=9.81)


def numpy_state_matrices(M, C1, K0, K2, g, speeds):
    """Plain NumPy ``(n, s, 4, 4)`` state matrices of stacked ``(n, 2, 2)`` matrices at ``speeds``."""
    Minv = np.linalg.inv(M)[:, None]  # (n, 1, 2, 2)
    v = speeds[None, :, None, None]
    K = g * K0[:, None] + v * v * K2[:, None]
    C = v * C1[:, None]
    lower = np.concatenate([-Minv @ K, -Minv @ C], axis=-1)
    upper = np.broadcast_to(np.concatenate([np.zeros((2, 2)), np.eye(2)], axis=-1), lower.shape)
    return np.concatenate([upper, lower], axis=-2)


def run(ctx: Context) -> list[Row]:
    from bikerider.generated import benchmark_model as gen

    from bikerider.benchmark import WhippleModel
    from bikerider.benchmark.sweep import stability_map
    from bikerider.shipped import named

    n_bicycles = PAIRS_BICYCLES // 10 if ctx.quick else PAIRS_BICYCLES
    side = MAP_SIDE // 4 if ctx.quick else MAP_SIDE
    repeats = 2 if ctx.quick else 3
    speeds = np.linspace(0.0, 10.0, PAIRS_SPEEDS)
    batch = _random_models(n_bicycles)
    chunks = [
        WhippleModel(batch.M[k : k + CHUNK], batch.C1[k : k + CHUNK], batch.K0[k : k + CHUNK], batch.K2[k : k + CHUNK])
        for k in range(0, n_bicycles, CHUNK)
    ]

    def ours_A():
        for m in chunks:
            m.state_matrix(speeds)

    def numpy_A():
        for m in chunks:
            numpy_state_matrices(m.M, m.C1, m.K0, m.K2, m.g, speeds)

    def ours_eig():
        for m in chunks:
            m.eigenvalues(speeds, method="quartic")

    def numpy_eig():
        for m in chunks:
            np.linalg.eigvals(numpy_state_matrices(m.M, m.C1, m.K0, m.K2, m.g, speeds))

    t = measure_together(
        {"ours_A": ours_A, "numpy_A": numpy_A, "ours_eig": ours_eig, "numpy_eig": numpy_eig}, repeats, min_sample=0.0
    )
    pairs = n_bicycles * PAIRS_SPEEDS
    # accuracy of both routes on the first chunk
    m = chunks[0]
    diff_A = np.abs(m.state_matrix(speeds) - numpy_state_matrices(m.M, m.C1, m.K0, m.K2, m.g, speeds)).max()
    ours = np.sort_complex(m.eigenvalues(speeds, method="quartic").values.reshape(-1, 4))
    reference = np.sort_complex(np.linalg.eigvals(m.state_matrix(speeds)).reshape(-1, 4))
    diff_eig = np.median(np.abs(ours - reference).max(axis=-1))
    rows = [
        Row(
            f"A(v), {pairs:.0e} (bicycle, speed) pairs",
            f"{t['ours_A'].text()} (generated state_matrix)",
            [("plain NumPy: inv(M), block matrices by broadcasting", t["numpy_A"].text())],
            f"{ratio_text(t['numpy_A'].median, t['ours_A'].median)} vs NumPy",
            f">= {GOAL_A:g}x NumPy",
            t["numpy_A"].median >= GOAL_A * t["ours_A"].median,
            [
                f"{n_bicycles} random bicycles x {PAIRS_SPEEDS} speeds, chunks of {CHUNK} bicycles; "
                f"largest difference between the two {diff_A:.1e}"
            ],
        ),
        Row(
            f"eigenvalues, {pairs:.0e} (bicycle, speed) pairs",
            f"{t['ours_eig'].text()} (quartic, labelled)",
            [("numpy.linalg.eigvals of the NumPy state matrices (unlabelled)", t["numpy_eig"].text())],
            f"{ratio_text(t['numpy_eig'].median, t['ours_eig'].median)} vs NumPy",
            f">= {GOAL_EIGENVALUES:g}x NumPy",
            t["numpy_eig"].median >= GOAL_EIGENVALUES * t["ours_eig"].median,
            [f"median over pairs of the largest eigenvalue difference to eigvals: {diff_eig:.1e} 1/s"],
        ),
    ]
    base = named("Benchmark")
    trails, masses = np.linspace(-0.02, 0.2, side), np.linspace(20.0, 140.0, side)
    map_speeds = np.linspace(0.0, 10.0, MAP_SPEEDS)
    grid_c, grid_m = np.meshgrid(trails, masses, indexing="ij")
    args = {
        k: np.full(grid_c.shape, float(base.values[k]))
        for k in "w c lam rR mR IRxx IRyy xB zB mB IBxx IBzz IBxz xH zH mH IHxx IHzz IHxz rF mF IFxx IFyy".split()
    }
    args["c"], args["mB"] = grid_c, grid_m
    M, C1, K0, K2 = (x.reshape(-1, 2, 2) for x in gen.canonical_matrices(**args))

    def ours_map():
        return stability_map(base, ("c", trails), ("mB", masses), map_speeds).stable()

    def numpy_map():
        out = []
        for k in range(0, M.shape[0], CHUNK):
            A = numpy_state_matrices(
                M[k : k + CHUNK], C1[k : k + CHUNK], K0[k : k + CHUNK], K2[k : k + CHUNK], 9.81, map_speeds
            )
            out.append((np.linalg.eigvals(A).real < 0).all(axis=-1))
        return np.concatenate(out).reshape(side, side, MAP_SPEEDS)

    t = measure_together({"ours": ours_map, "numpy": numpy_map}, repeats, min_sample=0.0)
    ours_stable, numpy_stable = ours_map(), numpy_map()
    disagree = int((ours_stable != numpy_stable).sum())
    rows.append(
        Row(
            f"stability map {side}x{side} designs at {MAP_SPEEDS} speeds",
            f"{t['ours'].text()} (stability_map + Sweep.stable)",
            [("plain NumPy: state matrices + eigvals at every (design, speed), matrices given", t["numpy"].text())],
            f"{ratio_text(t['numpy'].median, t['ours'].median)} vs NumPy",
            f">= {GOAL_MAP:g}x NumPy",
            t["numpy"].median >= GOAL_MAP * t["ours"].median,
            [
                f"trail -0.02-0.2 m x rear-body mass 20-140 kg of the benchmark bicycle; {disagree} of "
                f"{ours_stable.size} (design, speed) points disagree (a point on a stability boundary, "
                "where eigvals' rounding decides)"
            ],
        )
    )
    return rows
