"""The linear Whipple model ``M q'' + v C1 q' + (g K0 + v^2 K2) q = f`` and its eigen-analysis.

Mode labels, per speed (Meijaard et al. 2007, section 6):

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
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bikerider.benchmark.parameters import BenchmarkParameters
from bikerider.errors import InputError
from bikerider.generated import benchmark_model as gen

MATRIX_NAMES = ("M", "C1", "K0", "K2")
_COORDS = ("phi", "delta")
_CANONICAL_ARGS = (
    "w c lam rR mR IRxx IRyy xB zB mB IBxx IBzz IBxz xH zH mH IHxx IHzz IHxz rF mF IFxx IFyy".split()
)
MODES = ("weave", "weave", "capsize", "castor")
"""Label order of the four eigenvalues returned by :meth:`WhippleModel.eigenvalues`."""


def matrix_entries(M, C1, K0, K2) -> dict[str, np.ndarray]:
    """Keyword arguments ``M_phiphi, ..., K2_deltadelta`` for the generated matrix-level functions."""
    out = {}
    for name, mat in zip(MATRIX_NAMES, (M, C1, K0, K2)):
        mat = np.asarray(mat, dtype=float)
        for i, a in enumerate(_COORDS):
            for j, b in enumerate(_COORDS):
                out[f"{name}_{a}{b}"] = mat[..., i, j]
    return out


@dataclass(frozen=True)
class CriticalSpeeds:
    """Weave (Hopf) and capsize speeds in m/s; ``None`` where none exists at positive speed."""

    weave: float | None
    capsize: float | None
    weave_frequency: float | None
    """Angular frequency of the weave pair at the weave speed [rad/s]."""

    @property
    def stable_range(self) -> tuple[float, float] | None:
        """``(weave, capsize)`` when the model is self-stable between them."""
        if self.weave is not None and self.capsize is not None and self.weave < self.capsize:
            return (self.weave, self.capsize)
        return None


@dataclass(frozen=True)
class ModalEigenvalues:
    """Eigenvalues at each speed, ordered ``weave (+imag), weave (-imag), capsize, castor``."""

    speeds: np.ndarray
    values: np.ndarray
    labels: np.ndarray

    def mode(self, name: str) -> np.ndarray:
        """Eigenvalues labelled ``name`` at each speed (``weave`` gives the positive-imaginary one)."""
        index = MODES.index(name)
        return self.values[:, index]


class WhippleModel:
    """Canonical matrices and their dynamics.

    Parameters
    ----------
    M, C1, K0, K2 : array_like, shape (2, 2)
        The canonical matrices (K0 per unit g).
    g : float
        Acceleration due to gravity [m/s^2].
    """

    def __init__(self, M, C1, K0, K2, g: float = 9.81):
        mats = [np.array(m, dtype=float) for m in (M, C1, K0, K2)]
        for name, m in zip(MATRIX_NAMES, mats):
            if m.shape != (2, 2):
                raise InputError(name, m.shape, "a 2x2 matrix")
            if not np.all(np.isfinite(m)):
                raise InputError(name, m.tolist(), "finite entries")
        det_m = np.linalg.det(mats[0])
        if not (mats[0][0, 0] > 0 and det_m > 1e-12 * np.abs(mats[0]).max() ** 2):
            raise InputError("M", mats[0].tolist(), "a positive definite mass matrix (the model is singular otherwise)")
        self.M, self.C1, self.K0, self.K2 = mats
        self.g = float(g)
        self.source: str | None = None
        """Where the parameters came from, for messages (set by :meth:`from_parameters`)."""

    @classmethod
    def from_parameters(cls, parameters: BenchmarkParameters) -> "WhippleModel":
        """Build from benchmark parameters (Meijaard et al. 2007, Appendix A)."""
        v = parameters.values
        M, C1, K0, K2 = gen.canonical_matrices(**{k: v[k] for k in _CANONICAL_ARGS})
        try:
            model = cls(M, C1, K0, K2, v["g"])  # type: ignore[arg-type]
        except InputError as exc:  # name the file the parameters came from
            raise InputError(exc.name, exc.value, exc.expected, parameters.source) from None
        model.source = parameters.source
        return model

    # -- matrices ---------------------------------------------------------------------------
    def _entries(self) -> dict[str, np.ndarray]:
        return matrix_entries(self.M, self.C1, self.K0, self.K2)

    def state_matrix(self, speeds) -> np.ndarray:
        """State matrices ``(..., 4, 4)`` for ``x = [phi, delta, phi', delta']``."""
        return gen.state_matrix(**self._entries(), g=self.g, v=np.asarray(speeds, dtype=float))

    def characteristic_coefficients(self, speeds) -> np.ndarray:
        """``(..., 5)`` coefficients ``[a4, a3, a2, a1, a0]`` of the characteristic polynomial."""
        return gen.characteristic_coefficients(**self._entries(), g=self.g, v=np.asarray(speeds, dtype=float))

    # -- eigenvalues -----------------------------------------------------------------------
    def eigenvalues(self, speeds, method: str = "eigvals") -> ModalEigenvalues:
        """Eigenvalues at each speed with mode labels (see the module docstring).

        Parameters
        ----------
        speeds : array_like, shape (n,)
            Speeds [m/s].
        method : {"eigvals", "quartic"}
            ``"eigvals"``: ``numpy.linalg.eigvals`` of the state matrices (the reference).
            ``"quartic"``: the generated characteristic polynomial solved in closed form for all
            speeds at once (:mod:`bikerider.benchmark.quartic`), many times faster; equal to
            ``"eigvals"`` within about 1e-13 except at a double root (near ``v_d``), where each
            root of the pair is good to about 1e-8.
        """
        if method == "quartic":
            from bikerider.benchmark.quartic import eigenvalues_from_polynomial

            return eigenvalues_from_polynomial(self, speeds)
        if method != "eigvals":
            raise InputError("method", method, 'either "eigvals" or "quartic"')
        speeds = check_speeds(speeds)
        with np.errstate(over="ignore", invalid="ignore"):
            state = self.state_matrix(speeds)
        finite = np.all(np.isfinite(state), axis=(-2, -1))
        if not np.all(finite):
            raise InputError("speeds", float(speeds[~finite][0]),
                             "a speed at which the state matrix is finite (the model's matrices, or the speed, "
                             "are too large for floating point there)", self.source)
        raw = np.linalg.eigvals(state)
        values, labels = label_modes(raw)
        return ModalEigenvalues(speeds, values, labels)

    # -- critical speeds ---------------------------------------------------------------------
    def critical_speeds(self) -> CriticalSpeeds:
        """Weave and capsize speeds from the closed-form conditions (no scan over speed).

        Capsize: the smallest positive root of ``det(g K0 + v^2 K2) = 0``.  Weave: the smallest
        positive root of the third Hurwitz determinant (a quadratic in ``v^2``) at which the
        crossing frequency ``omega^2 = a1/a3`` is positive.
        """
        entries = {k: float(v) for k, v in self._entries().items()}
        try:
            capsize_c, weave_c, (b1, b0), (_, alpha) = gen.critical_speed_polynomials_scalar(**entries, g=self.g)
        except OverflowError:
            capsize_c = weave_c = (math.inf,)
        if not all(math.isfinite(c) for c in (*capsize_c, *weave_c)):
            raise InputError("M, C1, K0, K2", "entries too large for floating point",
                             "matrices whose critical-speed polynomials are finite", self.source)
        capsize_u = positive_real_roots(*capsize_c)
        capsize = math.sqrt(capsize_u[0]) if capsize_u else None
        weave = frequency = None
        for u in positive_real_roots(*weave_c):
            a1_over_v = b1 * u + b0  # a1/v and a3/v = alpha at u: omega^2 = a1/a3
            if alpha != 0 and a1_over_v / alpha > 0:
                weave, frequency = math.sqrt(u), math.sqrt(a1_over_v / alpha)
                break
        return CriticalSpeeds(weave, capsize, frequency)

    def weave_birth_speed(self) -> float | None:
        """The speed ``v_d`` at which the weave pair is born from two real eigenvalues [m/s].

        The discriminant of the characteristic quartic vanishes wherever two eigenvalues coincide;
        as a polynomial in ``u = v^2`` it is the generated ``discriminant_polynomial`` (derived in
        ``derive/benchmark_model.py``).  ``v_d`` is the smallest of its positive roots at which the
        two eigenvalues with the largest real parts are real just below and a complex pair just
        above (Meijaard et al. 2007, section 6; the other two
        may be real or a complex pair of their own).  ``None`` when there is no such speed.
        """
        with np.errstate(over="ignore", invalid="ignore"):
            coefficients = np.asarray(gen.discriminant_polynomial(**self._entries(), g=self.g), dtype=float)
        if not np.all(np.isfinite(coefficients)):
            raise InputError("M, C1, K0, K2", "entries too large for floating point",
                             "matrices whose characteristic discriminant is finite", self.source)
        slope = np.polyder(coefficients)
        for u in polynomial_positive_real_roots(coefficients):
            for _ in range(3):  # Newton steps: the root of a simple zero to full precision
                step = np.polyval(coefficients, u) / np.polyval(slope, u) if np.polyval(slope, u) else 0.0
                if not np.isfinite(step) or abs(step) > 1e-6 * u:
                    break
                u -= step
            if self._pair_born_at(float(np.sqrt(u))):
                return float(np.sqrt(u))
        return None

    def _pair_born_at(self, speed: float, relative: float = 1e-6) -> bool:
        """Whether the two eigenvalues with the largest real parts are real just below ``speed`` and
        a complex pair just above (the other two may be real or complex on either side)."""
        below, above = np.linalg.eigvals(self.state_matrix(np.array([speed * (1 - relative), speed * (1 + relative)])))
        tol = 1e-9 * max(1.0, float(np.abs(above).max()))
        top_below = below[np.argsort(-below.real)][:2]
        top_above = above[np.argsort(-above.real)][:2]
        return bool(np.all(np.abs(top_below.imag) <= tol) and np.all(np.abs(top_above.imag) > tol))


_ZERO = 1e-14
"""Polynomial coefficients below this fraction of the largest are zero."""
_IMAG = 1e-9
"""A complex root pair with imaginary part below ``_IMAG * max(1, |real part|)`` is a double real root."""


def positive_real_roots(c2: float, c1: float, c0: float) -> list[float]:
    """Sorted positive real roots of ``c2 u^2 + c1 u + c0`` on floats, scale-aware.

    Coefficients below ``1e-14`` of the largest count as zero; a complex pair whose imaginary part
    is below ``1e-9 max(1, |real part|)`` counts as a double real root (round-off can split a
    double root into such a pair).
    """
    scale = max(abs(c2), abs(c1), abs(c0))
    if scale == 0:
        return []
    a, b, c = c2 / scale, c1 / scale, c0 / scale
    if abs(a) <= _ZERO:
        if abs(b) <= _ZERO:
            return []
        roots = [-c / b]
    else:
        disc = b * b - 4 * a * c
        if disc >= 0:
            q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
            roots = [q / a, c / q] if q != 0 else [0.0, 0.0]
        else:
            re = -b / (2 * a)
            if math.sqrt(-disc) / (2 * abs(a)) > _IMAG * max(1.0, abs(re)):
                return []
            roots = [re, re]
    return sorted(u for u in roots if u > 0)


def polynomial_positive_real_roots(coefficients: np.ndarray) -> np.ndarray:
    """Sorted positive real roots of a polynomial of any degree (highest power first), with the
    tolerances of :func:`positive_real_roots`."""
    c = np.asarray(coefficients, dtype=float)
    scale = np.abs(c).max()
    if scale == 0:
        return np.empty(0)
    c = c / scale
    nonzero = np.flatnonzero(np.abs(c) > _ZERO)
    if nonzero.size == 0:
        return np.empty(0)
    roots = np.roots(c[nonzero[0]:])
    real = roots[np.abs(roots.imag) <= _IMAG * np.maximum(1.0, np.abs(roots.real))].real
    return np.sort(real[real > 0])


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
    """Order ``(n, 4)`` eigenvalues as weave(+), weave(-), capsize, castor; return labels too (the
    rules of the module docstring; ``"other"`` replaces capsize and castor where those two form a
    complex pair)."""
    n = raw.shape[0]
    values = np.empty((n, 4), dtype=complex)
    labels = np.empty((n, 4), dtype=object)
    for k in range(n):
        ev = raw[k]
        tol = 1e-9 * max(1.0, float(np.abs(ev).max()))
        is_complex = np.abs(ev.imag) > tol
        complex_ev = ev[is_complex & (ev.imag > 0)]
        real_ev = np.sort(ev[~is_complex].real)
        if complex_ev.size == 0:
            # all real: the two largest are the weave pair before it is born (v < v_d)
            values[k] = [real_ev[3], real_ev[2], real_ev[1], real_ev[0]]
            labels[k] = ["weave", "weave", "capsize", "castor"]
        elif complex_ev.size == 1 and complex_ev[0].real < real_ev[0]:
            # the two most negative roots have met; the two real ones are the weave pair, unborn
            w = complex_ev[0]
            values[k] = [real_ev[1], real_ev[0], w, np.conj(w)]
            labels[k] = ["weave", "weave", "other", "other"]
        elif complex_ev.size == 1:
            w = complex_ev[0]
            values[k] = [w, np.conj(w), real_ev[1], real_ev[0]]
            labels[k] = ["weave", "weave", "capsize", "castor"]
        else:
            pair = complex_ev[np.argsort(-complex_ev.imag)]
            values[k] = [pair[0], np.conj(pair[0]), pair[1], np.conj(pair[1])]
            labels[k] = ["weave", "weave", "other", "other"]
    return values, labels
