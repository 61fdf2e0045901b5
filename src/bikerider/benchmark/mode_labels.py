"""Eigenvalues at speeds and their mode labels by rules at one speed (Meijaard et al. 2007, section 6).

The models name their eigenvalues by continuation in speed (:mod:`bikerider.benchmark.mode_names`),
which falls back on these rules only where it cannot decide (no speed with exactly one complex
pair) and uses them for the layout of its result.  The rules at one speed are right wherever the
weave pair is complex, but below its birth they guess: the two largest real eigenvalues are not
always the two that merge.

Mode labels, per speed:

* castor: the real eigenvalue with the most negative real part;
* weave: the complex-conjugate pair when there is one; when all four eigenvalues are real
  (below the speed ``v_d`` where the weave pair is born), the two largest, which merge at ``v_d``;
* capsize: the remaining real eigenvalue.

Two cases fall outside these rules and give the label ``"other"``.  When the two most negative
eigenvalues meet before the weave pair is born (some unusual bicycles, at low speed), their complex
pair has a real part below both remaining real eigenvalues: those two are the weave pair, not yet
born, and the pair is ``"other"`` (eigenvalues move continuously, so a pair born below the two other
roots stays below them until its real part crosses one, which the weave pair's does not do at the
low speeds where this happens).  When two complex pairs exist, the pair with the larger imaginary
part is weave and the other ``"other"``.

An eigenvalue is complex when its imaginary part exceeds :data:`IMAGINARY_TOLERANCE` times
``max(1, max |eigenvalue|)`` of its speed.  :func:`label_modes` is the one implementation of these
rules, for eigenvalues from ``eigvals`` and from the characteristic polynomial alike.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bikerider.errors import InputError

MODES = ("weave", "weave", "capsize", "castor")
"""Label order of the four eigenvalues returned by :meth:`WhippleModel.eigenvalues`."""
IMAGINARY_TOLERANCE = 1e-9
"""An eigenvalue whose imaginary part is below this fraction of ``max(1, max |eigenvalue|)`` is real."""


@dataclass(frozen=True)
class ModalEigenvalues:
    """Eigenvalues at each speed, ordered ``weave (+imag), weave (-imag), capsize, castor``."""

    speeds: np.ndarray
    values: np.ndarray
    """``(n, 4)`` for one bicycle, ``batch_shape + (n, 4)`` for a batch."""
    labels: np.ndarray
    """The label of each value, the shape of :attr:`values`."""

    def mode(self, name: str) -> np.ndarray:
        """Eigenvalues labelled ``name`` at each speed (``weave`` gives the positive-imaginary one)."""
        index = MODES.index(name)
        return self.values[..., index]


def check_speeds(speeds) -> np.ndarray:
    """Speeds as a one-dimensional float array; :class:`InputError` unless all are finite."""
    try:
        out = np.atleast_1d(np.asarray(speeds, dtype=float))
    except (TypeError, ValueError):
        raise InputError("speeds", speeds, "a one-dimensional array of finite speeds") from None
    if out.ndim != 1 or not np.all(np.isfinite(out)):
        raise InputError("speeds", out.tolist(), "a one-dimensional array of finite speeds")
    return out


def label_modes(raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Order ``(n, 4)`` eigenvalues as weave(+), weave(-), capsize, castor (the rules of the module
    docstring), for all speeds at once; return the labels too."""
    raw = np.asarray(raw, dtype=complex)
    n = raw.shape[0]
    largest = np.abs(raw).max(axis=-1, keepdims=True)
    imag = raw.imag
    is_complex = np.abs(imag) > IMAGINARY_TOLERANCE * np.maximum(1.0, largest)
    upper = is_complex & (imag > 0)
    # Order: upper-half-plane roots by falling imaginary part, then real roots by falling real
    # part, then the lower-half-plane roots (replaced by the conjugates below).  One float key:
    # a group offset times a span wider than any value.
    span = 4.0 * (float(largest.max(initial=0.0)) + 1.0)
    key = np.where(upper, -imag, np.where(is_complex, 2 * span, span - raw.real))
    order = np.argsort(key, axis=-1)
    rows = np.arange(n)[:, None]
    s = np.where(is_complex, raw, raw.real)[rows, order]
    pairs = upper.sum(axis=-1)
    values = np.empty((n, 4), dtype=complex)
    values[:, 0] = s[:, 0]
    one_or_two = pairs > 0
    values[:, 1] = np.where(one_or_two, np.conj(s[:, 0]), s[:, 1])
    values[:, 2] = np.where(one_or_two, s[:, 1], s[:, 2])
    values[:, 3] = np.where(pairs == 2, np.conj(s[:, 1]), np.where(pairs == 1, s[:, 2], s[:, 3]))
    low = (pairs == 1) & (s[:, 0].real < s[:, 2].real)  # the pair below both real roots
    values[low] = np.stack([s[low, 1], s[low, 2], s[low, 0], np.conj(s[low, 0])], axis=-1)
    labels = np.empty((n, 4), dtype=object)
    labels[:] = np.array(MODES, dtype=object)
    labels[(pairs == 2) | low, 2:] = "other"  # the second of two pairs, or a pair below both real roots
    return values, labels


__all__ = ["IMAGINARY_TOLERANCE", "MODES", "ModalEigenvalues", "check_speeds", "label_modes"]
