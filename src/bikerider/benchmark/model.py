"""The linear Whipple model ``M q'' + v C1 q' + (g K0 + v^2 K2) q = f`` and its eigen-analysis.

Eigenvalues are labelled weave, capsize and castor by the rules of :mod:`bikerider.benchmark.modes`
(``"other"`` where they do not apply); the critical speeds are the roots of generated polynomials
(:mod:`bikerider.benchmark.roots`), found without a scan over speed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bikerider.benchmark.modes import MODES, ModalEigenvalues, check_speeds, label_modes
from bikerider.benchmark.parameters import BenchmarkParameters
from bikerider.benchmark.quartic import eigenvalues_from_polynomial
from bikerider.benchmark.roots import critical_speeds, polynomial_positive_real_roots
from bikerider.engine import arguments
from bikerider.errors import InputError
from bikerider.generated import benchmark_model as gen
from bikerider.generated.manifest import COORDINATES, MATRIX_NAMES

_CANONICAL_ARGS = arguments("benchmark_model.canonical_matrices")


def matrix_entries(M, C1, K0, K2) -> dict[str, np.ndarray]:
    """Keyword arguments ``M_phiphi, ..., K2_deltadelta`` for the generated matrix-level functions."""
    out = {}
    for name, mat in zip(MATRIX_NAMES, (M, C1, K0, K2)):
        mat = np.asarray(mat, dtype=float)
        for i, a in enumerate(COORDINATES):
            for j, b in enumerate(COORDINATES):
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
            polynomials = gen.critical_speed_polynomials_scalar(**entries, g=self.g)
        except OverflowError:
            polynomials = ((math.inf,),) * 4
        if not all(math.isfinite(c) for c in (*polynomials[0], *polynomials[1])):
            raise InputError("M, C1, K0, K2", "entries too large for floating point",
                             "matrices whose critical-speed polynomials are finite", self.source)
        weave, capsize, frequency = (float(x) for x in critical_speeds(*polynomials))
        return CriticalSpeeds(*(x if math.isfinite(x) else None for x in (weave, capsize, frequency)))

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


__all__ = ["MODES", "CriticalSpeeds", "ModalEigenvalues", "WhippleModel", "check_speeds", "label_modes",
           "matrix_entries"]
