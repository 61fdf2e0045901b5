"""Eigenvalue sensitivities at a given speed from left and right eigenvectors.

For a simple eigenvalue ``lambda`` of the state matrix ``A(p)`` with right eigenvector ``x`` and
left eigenvector ``y`` (``y^H A = lambda y^H``)::

    d lambda / d p = y^H (dA/dp) x / (y^H x)

``dA/dp`` for the sixteen matrix entries and ``g`` is the generated ``state_matrix_jacobian``; the
chain rule carries it to the measurements.  The left eigenvectors are the rows of ``X^-1``
(conjugated), ``X`` the matrix of right eigenvectors.  The formula fails at a double eigenvalue
(the weave pair is born from two real eigenvalues at ``v_d``); :attr:`EigenSensitivity.condition`
(``|y| |x| / |y^H x|``) grows without bound there, and first-order sigmas near it are not to be
trusted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bikerider.benchmark.mode_labels import MODES, check_speeds
from bikerider.benchmark.model import WhippleModel
from bikerider.engine import arguments
from bikerider.generated import benchmark_model as gen_model
from bikerider.generated import sensitivities as gen
from bikerider.uncertainty.stages import ENTRIES

PARAMETERS = tuple(a for a in arguments("sensitivities.state_matrix_jacobian") if a != "v")
"""Columns of :attr:`EigenSensitivity.derivatives`: the matrix entries, then ``g``."""


@dataclass(frozen=True)
class EigenSensitivity:
    """Labelled eigenvalues at each speed and their derivatives.

    Attributes
    ----------
    speeds : ndarray, shape (n,)
    values : ndarray, shape (n, 4), complex
        Ordered weave (+imag), weave (-imag), capsize, castor (:data:`bikerider.benchmark.mode_labels.MODES`).
    derivatives : ndarray, shape (n, 4, 17), complex
        d lambda / d [matrix entries, g].
    condition : ndarray, shape (n, 4)
        Eigenvalue condition numbers ``|y| |x| / |y^H x|`` (1 for a normal matrix; large near a
        double eigenvalue).
    labels : ndarray, shape (n, 4), object
    """

    speeds: np.ndarray
    values: np.ndarray
    derivatives: np.ndarray
    condition: np.ndarray
    labels: np.ndarray


def eigen_sensitivity(entries: dict[str, float], g: float, speeds) -> EigenSensitivity:
    """Eigenvalues and d lambda / d[entries, g] at each speed (vectorised over speeds).

    Raises
    ------
    InputError
        Speeds that are not a one-dimensional array of finite numbers.
    """
    speeds = check_speeds(speeds)
    kw = {k: np.asarray(entries[k], dtype=float) for k in ENTRIES}
    A = gen_model.state_matrix(**kw, g=g, v=speeds)
    raw, X = np.linalg.eig(A)
    Y_h = np.linalg.inv(X)  # rows are left eigenvectors y_i^H
    dA = gen.state_matrix_jacobian(**kw, g=g, v=speeds).reshape(speeds.shape + (4, 4, len(PARAMETERS) + 1))
    dA = dA[..., :-1]  # the speed is fixed; d/dv is not a parameter
    # y_i^H dA_p x_i for every eigenvalue i and parameter p
    numerator = np.einsum("nij,njkp,nki->nip", Y_h, dA, X)
    yx = np.einsum("nij,nji->ni", Y_h, X)
    derivs_raw = numerator / yx[..., None]
    cond_raw = np.linalg.norm(Y_h, axis=-1) * np.linalg.norm(X, axis=-2) / np.abs(yx)
    named = WhippleModel.from_entries({k: float(kw[k]) for k in ENTRIES}, g)  # names by continuation in speed
    values, labels = (x[0] for x in named.name_modes(speeds, raw[None]))
    order = np.empty(values.shape, dtype=int)
    for n in range(values.shape[0]):
        free = list(range(4))
        for k in range(4):
            j = min(free, key=lambda i: abs(raw[n, i] - values[n, k]))
            order[n, k] = j
            free.remove(j)
    take = np.take_along_axis
    return EigenSensitivity(
        speeds,
        values,
        take(derivs_raw, order[..., None], axis=1),
        take(cond_raw, order, axis=1),
        labels,
    )


__all__ = ["MODES", "PARAMETERS", "EigenSensitivity", "eigen_sensitivity"]
