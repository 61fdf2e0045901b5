"""Mode shapes of the Whipple model: eigenvectors, tracked across speed by continuity.

For an eigenvalue ``s`` at speed ``v`` the mode shape is the roll and steer part ``q = [phi,
delta]`` of the eigenvector ``x = [q, s q]`` of the state matrix: the null vector of
``M s^2 + v C1 s + g K0 + v^2 K2``.

Normalisation (documented once, used everywhere): ``q`` has unit Euclidean norm and is turned
in the complex plane so that its roll component is real and positive (its steer component when
roll vanishes).  So ``|phi|`` and ``|delta|`` are the relative amplitudes of roll and steer
(``|delta| / |phi|`` their ratio) and ``arg(delta)`` is the phase of steer relative to roll:
0 or pi for a real eigenvalue (steer in or against the roll), anything for an oscillating mode
(positive: steer leads roll).  For a complex pair the shape of the eigenvalue with positive
imaginary part is the one reported; its conjugate's is the conjugate.

Tracking.  Eigenvalues are computed at each speed independently (:func:`numpy.linalg.eig`) and
come in no particular order.  :func:`track_modes` orders them so that each column is one mode,
continuous in speed: from one speed to the next it picks, of the 24 possible assignments, the one
closest to the linear extrapolation of the two previous speeds (so two real eigenvalues that
cross keep their identity).  A tracked column is named by the label most of its points carry
(the names of :meth:`WhippleModel.eigenvalues`, carried by continuation in speed from where they
are unambiguous, :mod:`bikerider.benchmark.mode_names`): ``weave`` (two columns), ``capsize``,
``castor``.
Track on a speed grid fine enough to follow the eigenvalues (steps of 0.1 m/s or less for a
bicycle).
"""

from __future__ import annotations

import itertools
from collections import Counter
from dataclasses import dataclass

import numpy as np

from bikerider.benchmark.mode_labels import check_speeds, label_modes
from bikerider.benchmark.model import WhippleModel

_PERMUTATIONS = np.array(list(itertools.permutations(range(4))))
"""The 24 orderings of four eigenvalues."""


@dataclass(frozen=True)
class ModeShapes:
    """Eigenvalues and mode shapes at each speed, one column per tracked mode.

    Attributes
    ----------
    speeds : numpy.ndarray, shape (n,)
        Speeds [m/s].
    eigenvalues : numpy.ndarray, shape S + (n, 4)
        Tracked eigenvalues [1/s] (``S`` is the model's batch shape).
    shapes : numpy.ndarray, shape S + (n, 4, 2)
        Normalised ``[phi, delta]`` of each mode (see the module docstring).
    names : tuple of str, or numpy.ndarray of str, shape S + (4,)
        Name of each column: ``("weave", "weave", "capsize", "castor")`` for a usual bicycle
        (``"other"`` where the labels do not decide); for a batch, each bicycle's.
    """

    speeds: np.ndarray
    eigenvalues: np.ndarray
    shapes: np.ndarray
    names: tuple[str, ...]

    @property
    def roll(self) -> np.ndarray:
        """Complex roll component of each shape, ``S + (n, 4)``."""
        return self.shapes[..., 0]

    @property
    def steer(self) -> np.ndarray:
        """Complex steer component of each shape, ``S + (n, 4)``."""
        return self.shapes[..., 1]

    @property
    def amplitude(self) -> np.ndarray:
        """``|phi|, |delta|`` of each shape, ``S + (n, 4, 2)`` (they square-sum to one)."""
        return np.abs(self.shapes)

    @property
    def steer_phase(self) -> np.ndarray:
        """Phase of steer relative to roll [rad], ``S + (n, 4)``, in ``(-pi, pi]``."""
        return np.angle(self.steer) - np.angle(self.roll)

    def state_vectors(self) -> np.ndarray:
        """The eigenvectors of the state matrix, ``[q, s q]``, ``S + (n, 4, 4)`` (last axis: the state)."""
        return np.concatenate([self.shapes, self.eigenvalues[..., None] * self.shapes], axis=-1)

    def column(self, name: str) -> int:
        """Column index of the mode ``name`` of one bicycle (``weave`` gives the first weave column)."""
        names = tuple(self.names)
        if name not in names:
            raise KeyError(f"no mode {name!r}; the modes are {', '.join(map(str, names))}")
        return names.index(name)


def null_vectors(model: WhippleModel, speeds: np.ndarray, eigenvalues: np.ndarray) -> np.ndarray:
    """Normalised ``[phi, delta]`` null vectors of ``M s^2 + v C1 s + g K0 + v^2 K2``.

    ``speeds`` has shape ``(n,)``, ``eigenvalues`` ``S + (n, k)`` for a model of batch shape ``S``;
    the result is ``S + (n, k, 2)``.  Of the two rows of the singular 2x2 matrix the larger gives
    the null vector.
    """

    def at(matrix):  # S + (2, 2) -> S + (1, 1, 2, 2)
        return matrix[..., None, None, :, :]

    v = np.asarray(speeds, dtype=float)[:, None, None, None]
    s = eigenvalues[..., None, None]
    gK0 = np.asarray(model.g)[..., None, None] * model.K0
    Q = at(model.M) * s * s + v * at(model.C1) * s + at(gK0) + v * v * at(model.K2)
    first = np.abs(Q[..., 0, 0]) + np.abs(Q[..., 0, 1]) >= np.abs(Q[..., 1, 0]) + np.abs(Q[..., 1, 1])
    q = np.where(
        first[..., None],
        np.stack([-Q[..., 0, 1], Q[..., 0, 0]], axis=-1),
        np.stack([Q[..., 1, 1], -Q[..., 1, 0]], axis=-1),
    )
    return normalise(q)


def normalise(q: np.ndarray) -> np.ndarray:
    """Unit norm, roll component real and positive (steer when roll is zero); ``(..., 2)``."""
    q = np.asarray(q, dtype=complex)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    q = q / np.where(norm > 0, norm, 1.0)
    reference = np.where(np.abs(q[..., :1]) > 1e-12, q[..., :1], q[..., 1:])
    size = np.abs(reference)
    return q * np.where(size > 0, np.conj(reference) / np.where(size > 0, size, 1.0), 1.0)


def track_modes(values: np.ndarray) -> np.ndarray:
    """Indices ``(..., n, 4)`` that order ``values`` ``(..., n, 4)`` so each column is continuous in speed."""
    values = np.asarray(values)
    n = values.shape[-2]
    order = np.empty(values.shape, dtype=int)
    order[..., 0, :] = np.argsort(-values[..., 0, :].real, axis=-1)  # start: by falling real part
    ordered = np.take_along_axis(values[..., 0, :], order[..., 0, :], axis=-1)
    previous = ordered
    for k in range(1, n):
        predicted = 2 * ordered - previous if k > 1 else ordered
        candidates = values[..., k, :][..., _PERMUTATIONS]  # (..., 24, 4)
        cost = np.abs(candidates - predicted[..., None, :]).sum(axis=-1)
        best = np.argmin(cost, axis=-1)
        order[..., k, :] = _PERMUTATIONS[best]
        previous, ordered = ordered, np.take_along_axis(values[..., k, :], order[..., k, :], axis=-1)
    return order


def mode_shapes(model: WhippleModel, speeds) -> ModeShapes:
    """Eigenvalues and mode shapes of ``model`` at ``speeds``, tracked by continuity.

    Parameters
    ----------
    model : WhippleModel or ClosedLoopModel
        One bicycle or a batch (a closed loop: shapes from the eigenvectors of its state matrix,
        normalised the same way).
    speeds : array_like, shape (n,)
        Increasing speeds [m/s], fine enough to follow the eigenvalues.

    Returns
    -------
    ModeShapes
        Columns ordered weave (positive imaginary part at the highest speed first), weave,
        capsize, castor where the labels allow (see the module docstring).
    """
    speeds = check_speeds(speeds)
    if isinstance(model, WhippleModel):
        raw = np.linalg.eigvals(model.state_matrix(speeds))
        vectors = None
    else:  # a closed loop (anything with state_matrix and name_modes): shapes from its eigenvectors
        raw, vectors = np.linalg.eig(model.state_matrix(speeds))
    order = track_modes(raw)
    values = np.take_along_axis(raw, order, axis=-1)
    if vectors is not None:
        vectors = normalise(np.swapaxes(np.take_along_axis(vectors, order[..., None, :], axis=-1), -1, -2)[..., :2])
    flat = values.reshape((-1,) + values.shape[-2:])
    flat_vectors = None if vectors is None else vectors.reshape((-1,) + vectors.shape[-3:])
    named = model.name_modes(speeds, flat)  # the names of WhippleModel.eigenvalues, by continuation
    all_names = []
    for k, one in enumerate(flat):  # each bicycle's columns in the order weave, weave, capsize, castor
        names = column_names(one, (named[0][k], named[1][k]))
        rank = sorted(range(4), key=lambda j: (_RANK.get(names[j], 3), -one[-1, j].imag, -one[-1, j].real))
        flat[k] = one[:, rank]
        if flat_vectors is not None:
            flat_vectors[k] = flat_vectors[k][:, rank]
        all_names.append(tuple(names[j] for j in rank))
    values = flat.reshape(values.shape)
    names_out = (
        all_names[0] if not model.batch_shape else np.array(all_names, dtype=object).reshape(model.batch_shape + (4,))
    )
    shapes = null_vectors(model, speeds, values) if flat_vectors is None else flat_vectors.reshape(values.shape + (2,))
    return ModeShapes(speeds, values, shapes, names_out)


_RANK = {"weave": 0, "capsize": 1, "castor": 2}


def column_names(values: np.ndarray, named: tuple[np.ndarray, np.ndarray] | None = None) -> list[str]:
    """Names of the tracked columns of ``values`` ``(n, 4)``: the label most of a column's points
    carry (weave for two columns, capsize and castor for one each; ``"other"`` for a column no label
    fits).  The labels are ``named`` (values and labels as :meth:`WhippleModel.name_modes` gives
    them, by continuation in speed) or, without it, the per-speed rules of
    :func:`~bikerider.benchmark.mode_labels.label_modes`."""
    labelled, labels = named if named is not None else label_modes(values)
    nearest = np.abs(values[:, :, None] - labelled[:, None, :]).argmin(axis=-1)  # (n, 4)
    point_labels = np.take_along_axis(labels, nearest, axis=-1)
    counts = [Counter(point_labels[:, k]) for k in range(4)]
    names = ["other"] * 4
    for name, wanted in (("weave", 2), ("capsize", 1), ("castor", 1)):
        for k in sorted(range(4), key=lambda k: -counts[k][name]):
            if wanted and names[k] == "other" and counts[k][name] > 0:
                names[k] = name
                wanted -= 1
    return names


__all__ = ["ModeShapes", "column_names", "mode_shapes", "normalise", "null_vectors", "track_modes"]
