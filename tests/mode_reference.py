"""An independent reference for mode names: eigenvalues tracked by continuity on a fine speed grid.

From the highest speed of the grid down, :func:`bikerider.benchmark.mode_shapes.track_modes`
orders the eigenvalues so each column is one continuous branch; the columns are named at the top
(the complex pair weave, the larger real root capsize, the smaller castor).  Where a weave column
and another column form one complex pair, which branch is which below that speed is ambiguous, so
the reference holds only above the highest such speed (``unambiguous``; ``capsize_certain`` for
the capsize branch, which may pair with the castor branch at low speed), and only above any two
speeds of coinciding eigenvalues closer than two grid steps (which the grid cannot resolve).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bikerider.benchmark import WhippleModel
from bikerider.benchmark.mode_shapes import track_modes


@dataclass(frozen=True)
class Reference:
    speeds: np.ndarray
    tracked: np.ndarray
    """(n, 4) eigenvalues, one branch per column."""
    weave: tuple[int, int]
    capsize: int
    castor: int
    unambiguous: np.ndarray
    """(n,) where the weave branches are certain (above any pair of a weave and another branch)."""
    capsize_certain: np.ndarray
    """(n,) where the capsize branch is certain (above any pair it forms with another branch)."""


def reference(model: WhippleModel, top: float = 12.0, n: int = 4801) -> Reference | None:
    """The tracked branches of ``model`` on ``linspace(0, top, n)``; ``None`` when the eigenvalues
    at ``top`` are not one complex pair and two real roots (the names are not given there)."""
    speeds = np.linspace(0.0, top, n)
    raw = np.linalg.eigvals(model.state_matrix(speeds[::-1]))
    tracked = np.take_along_axis(raw, track_modes(raw), axis=-1)[::-1]
    at_top = tracked[-1]
    is_complex = np.abs(at_top.imag) > 1e-9 * max(1.0, np.abs(at_top).max())
    if is_complex.sum() != 2:
        return None
    weave = tuple(int(j) for j in np.nonzero(is_complex)[0])
    real = sorted((j for j in range(4) if not is_complex[j]), key=lambda j: -at_top[j].real)

    def certain(column: int, others) -> np.ndarray:
        """Above the highest speed where ``column`` forms a pair with one of ``others``."""
        mixed = np.zeros(n, dtype=bool)
        for j in others:
            mixed |= (np.abs(tracked[:, column].imag) > 1e-9) & (
                np.abs(tracked[:, column] - np.conj(tracked[:, j])) < 1e-7
            )
        out = np.ones(n, dtype=bool)
        if mixed.any():
            out[: np.nonzero(mixed)[0].max() + 1] = False
        return out

    unambiguous = certain(weave[0], real) & certain(weave[1], real)
    capsize_certain = certain(real[0], [weave[0], weave[1], real[1]])
    # two collisions (discriminant roots) closer than two grid steps: the grid cannot follow the
    # branches through them, so the reference says nothing below them
    collisions = model.collision_speeds()
    close = collisions[1:][np.diff(collisions) < 2 * (speeds[1] - speeds[0])]
    if close.size:
        unresolved = speeds <= close.max()
        unambiguous &= ~unresolved
        capsize_certain &= ~unresolved
    return Reference(speeds, tracked, weave, real[0], real[1], unambiguous, capsize_certain)


def misnamed(ref: Reference, values: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Where (over ``ref.speeds``, in the unambiguous range) the two values labelled weave are not
    the weave branches, or a value labelled capsize is not the capsize branch."""
    weave = labels[:, :2] == "weave"
    got = np.sort_complex(np.where(weave, values[:, :2], np.nan))
    want = np.sort_complex(ref.tracked[:, list(ref.weave)])
    bad = ~(np.all(weave, axis=1) & np.all(np.abs(got - want) < 1e-6, axis=1)) & ref.unambiguous
    capsize = labels[:, 2] == "capsize"
    wrong_capsize = capsize & (np.abs(values[:, 2] - ref.tracked[:, ref.capsize]) > 1e-6)
    unnamed = ~capsize & (np.abs(ref.tracked[:, ref.capsize].imag) < 1e-9)  # a real capsize branch unnamed
    return bad | ((wrong_capsize | unnamed) & ref.capsize_certain)
