"""A least-squares stage: the solution of more equations than unknowns, with its exact Jacobian.

The rows ``a_i . x = b_i`` come from a generated stage kind evaluated once per row (e.g. the line of
one hanging orientation, or its row of Eq. 6); the stage solves for ``x`` numerically and
differentiates the solution exactly:

* least squares, ``x = A^+ b``: ``dx = A^+ (db - dA x) + (A^T A)^-1 dA^T r`` with the residual
  ``r = b - A x`` (the derivative of the normal equations ``A^T A x = A^T b``);
* the mean of the solutions of every pair of rows (two unknowns only; BicycleParameters' way of
  placing a centre of mass): each pair ``p = M^-1 [b_i, b_j]`` has ``dp = M^-1 (d[b_i, b_j] - dM p)``.

The row Jacobians are generated, so the stage's Jacobian is exact; it is composed with the rest of
a chain by :class:`bikerider.engine.Chain` like any other stage.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence

import numpy as np

from bikerider.engine.stage import GeneratedStage, Stage
from bikerider.generated.manifest import STAGES

METHODS = ("least_squares", "pairwise_mean")


def conditioning_2x2(det, trace):
    """Smallest over largest singular value of a matrix ``A`` with two columns, from the
    determinant and trace of ``A^T A`` (whose eigenvalues are the squared singular values);
    0 when the rows are parallel.  Floats or arrays."""
    if isinstance(det, float) and isinstance(trace, float):  # one point: plain floats
        root = math.sqrt(max(trace * trace - 4 * det, 0.0))
        return math.sqrt(max(trace - root, 0.0) / (trace + root)) if trace + root > 0 else math.nan
    with np.errstate(divide="ignore", invalid="ignore"):
        root = np.sqrt(np.maximum(trace * trace - 4 * det, 0.0))
        return np.sqrt(np.maximum(trace - root, 0.0) / (trace + root))


class LeastSquaresStage(Stage):
    """``x`` from the rows ``a_i . x = b_i`` of a generated stage kind, one row per binding.

    Parameters
    ----------
    name : str
    row_kind : str
        A stage kind of the manifest; its outputs hold each row's coefficients and right side.
    rows : sequence of mapping of str to str
        For each row, the node bound to each input of the row kind (an input not named is its own
        node: e.g. one steer axis tilt shared by every row).
    columns : sequence of str
        The row kind's outputs that are the coefficients ``a_i``, in the order of ``x``.
    rhs : str
        The row kind's output that is ``b_i``.
    outputs : sequence of str
        Node names of the unknowns.
    method : {"least_squares", "pairwise_mean"}

    Checks (nodes ``<name>.<check>``): ``miss_<i>`` the residual ``a_i . x - b_i`` of each row,
    ``rms`` their root mean square, ``conditioning`` the smallest over the largest singular value
    of ``A`` and ``smallest_singular`` its smallest singular value.
    """

    def __init__(
        self,
        name: str,
        row_kind: str,
        rows: Sequence[Mapping[str, str]],
        columns: Sequence[str],
        rhs: str,
        outputs: Sequence[str],
        method: str = "least_squares",
    ):
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, not {method!r}")
        if method == "pairwise_mean" and len(columns) != 2:
            raise ValueError("the pairwise mean solves for two unknowns")
        self.name, self.method = name, method
        self._row = GeneratedStage(row_kind)
        local = STAGES[row_kind]["inputs"]
        bound = [tuple(row.get(a, a) for a in local) for row in rows]
        self.inputs = self.args = tuple(dict.fromkeys(node for row in bound for node in row))
        self.outputs = tuple(outputs)
        m = len(bound)
        self.checks = (
            *(f"{name}.miss_{i}" for i in range(1, m + 1)),
            f"{name}.rms",
            f"{name}.conditioning",
            f"{name}.smallest_singular",
        )
        self._local, self._bound = local, bound
        kind_outputs = STAGES[row_kind]["outputs"]
        self._columns = [kind_outputs.index(c) for c in columns]
        self._rhs = kind_outputs.index(rhs)
        position = {node: j for j, node in enumerate(self.inputs)}
        self._scatter = np.zeros((m, len(local), len(self.inputs)))  # (row, local input) -> stage input
        for i, row in enumerate(bound):
            for a, node in enumerate(row):
                self._scatter[i, a, position[node]] = 1.0

    def _rows_kwargs(self, kw: Mapping[str, object]) -> dict[str, np.ndarray]:
        """Each local input of the row kind as an array over the rows (the last axis)."""
        return {
            a: np.stack(np.broadcast_arrays(*(np.asarray(kw[row[k]], dtype=float) for row in self._bound)), axis=-1)
            for k, a in enumerate(self._local)
        }

    def _system(self, kw: Mapping[str, object]):
        rows_kw = self._rows_kwargs(kw)
        values, _ = self._row.evaluate(rows_kw)
        A = np.stack([values[c] for c in self._columns], axis=-1)  # (..., m, k)
        return rows_kw, A, values[self._rhs]

    def _solve(self, A: np.ndarray, b: np.ndarray) -> np.ndarray:
        if self.method == "least_squares":
            return (_pinv(A) @ b[..., None])[..., 0]
        points = [_pair_solution(A, b, i, j)[0] for i, j in itertools.combinations(range(A.shape[-2]), 2)]
        return np.mean(points, axis=0)

    def evaluate(self, kw: Mapping[str, object]) -> tuple[list, list]:
        _, A, b = self._system(kw)
        with np.errstate(divide="ignore", invalid="ignore"):
            x = self._solve(A, b)
            miss = (A @ x[..., None])[..., 0] - b
            singular = _singular_values(A)
        if A.shape[-1] == 2:
            N = np.swapaxes(A, -1, -2) @ A
            conditioning = conditioning_2x2(
                N[..., 0, 0] * N[..., 1, 1] - N[..., 0, 1] ** 2, N[..., 0, 0] + N[..., 1, 1]
            )
        else:
            conditioning = singular[..., -1] / singular[..., 0]
        rms = np.sqrt(np.mean(miss**2, axis=-1))
        outputs = [_plain(x[..., j]) for j in range(x.shape[-1])]
        checks = [
            *(_plain(miss[..., i]) for i in range(miss.shape[-1])),
            _plain(rms),
            _plain(conditioning),
            _plain(singular[..., -1]),
        ]
        return outputs, checks

    def jacobian(self, kw: Mapping[str, object]) -> np.ndarray:
        rows_kw, A, b = self._system(kw)
        row_jacobian = np.asarray(self._row.jacobian(rows_kw), dtype=float)  # (..., m, outputs, local)
        dA = row_jacobian[..., self._columns, :]  # (..., m, k, local)
        db = row_jacobian[..., self._rhs, :]  # (..., m, local)
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.method == "least_squares":
                local = _least_squares_derivative(A, b, dA, db)
            else:
                local = _pairwise_derivative(A, b, dA, db)
        return np.einsum("...oia,iaj->...oj", local, self._scatter)  # (..., k, inputs)


def _plain(x: np.ndarray):
    """A 0-d result as a float (one point: the next stages may take plain floats)."""
    return float(x) if np.ndim(x) == 0 else x


def _finite(A: np.ndarray) -> np.ndarray:
    """Whether each matrix of the stack ``A`` (``(..., m, k)``) has only finite entries."""
    return np.isfinite(A).all(axis=(-2, -1))


def _pinv(A: np.ndarray) -> np.ndarray:
    """The pseudo-inverse of each matrix of ``A``; NaN for a matrix with an entry that is not finite (a
    measurement the rows cannot use, e.g. a zero length they divide by), which LAPACK's SVD refuses with
    "SVD did not converge" and which the stage's checks then report by its name."""
    ok = _finite(A)
    if ok.all():
        return np.linalg.pinv(A)
    P = np.linalg.pinv(np.where(ok[..., None, None], A, 0.0))
    return np.where(ok[..., None, None], P, np.nan)


def _singular_values(A: np.ndarray) -> np.ndarray:
    """The singular values of each matrix of ``A``, largest first; NaN as in :func:`_pinv`."""
    ok = _finite(A)
    if ok.all():
        return np.linalg.svd(A, compute_uv=False)
    s = np.linalg.svd(np.where(ok[..., None, None], A, 0.0), compute_uv=False)
    return np.where(ok[..., None], s, np.nan)


def _least_squares_derivative(A, b, dA, db) -> np.ndarray:
    """``d x / d(row i, local a)``, shape ``(..., k, m, local)``, for ``x = A^+ b``."""
    P = _pinv(A)  # (..., k, m)
    x = (P @ b[..., None])[..., 0]  # (..., k)
    r = b - (A @ x[..., None])[..., 0]  # (..., m)
    inverse = P @ np.swapaxes(P, -1, -2)  # (A^T A)^-1, (..., k, k)
    # dx/dA_ic = inverse[:, c] r_i - P[:, i] x_c ; dx/db_i = P[:, i]
    by_A = inverse[..., :, None, :] * r[..., None, :, None] - P[..., :, :, None] * x[..., None, None, :]
    return np.einsum("...oic,...ica->...oia", by_A, dA) + P[..., :, :, None] * db[..., None, :, :]


def _pair_solution(A, b, i, j):
    """The solution of rows ``i`` and ``j`` (two unknowns, Cramer's rule) and the inverse matrix."""
    a00, a01, a10, a11 = A[..., i, 0], A[..., i, 1], A[..., j, 0], A[..., j, 1]
    det = a00 * a11 - a10 * a01
    inverse = np.stack([np.stack([a11, -a01], -1), np.stack([-a10, a00], -1)], -2) / det[..., None, None]
    point = np.stack([(b[..., i] * a11 - b[..., j] * a01) / det, (a00 * b[..., j] - a10 * b[..., i]) / det], -1)
    return point, inverse


def _pairwise_derivative(A, b, dA, db) -> np.ndarray:
    """``d x / d(row i, local a)`` for the mean of every pair's solution."""
    m = A.shape[-2]
    pairs = list(itertools.combinations(range(m), 2))
    out = np.zeros(A.shape[:-2] + (2, m, dA.shape[-1]))
    for i, j in pairs:
        point, inverse = _pair_solution(A, b, i, j)
        for column, row in ((0, i), (1, j)):
            # d(rhs_row) - d(row's coefficients) . point, carried through M^-1
            change = db[..., row, :] - np.einsum("...c,...ca->...a", point, dA[..., row, :, :])
            out[..., :, row, :] += inverse[..., :, column, None] * change[..., None, :]
    return out / len(pairs)


def line_rms(misses: Sequence[float]) -> float:
    """Root mean square of signed distances (floats)."""
    return math.sqrt(math.fsum(d * d for d in misses) / len(misses))
