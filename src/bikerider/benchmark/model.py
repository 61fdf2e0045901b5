"""The linear Whipple model ``M q'' + v C1 q' + (g K0 + v^2 K2) q = f`` and its eigen-analysis.

Eigenvalues are labelled weave, capsize and castor by the rules of
:mod:`bikerider.benchmark.mode_labels` (``"other"`` where they do not apply); the stable intervals
and the weave and capsize speeds come from the characteristic polynomial
(:mod:`bikerider.benchmark.stability`, whose roots are those of :mod:`bikerider.benchmark.roots`),
found without a scan over speed.  One bicycle or a batch of them: the matrices may carry leading
batch dimensions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bikerider.benchmark import mode_names, rules
from bikerider.benchmark.mode_labels import MODES, ModalEigenvalues, check_speeds, label_modes
from bikerider.benchmark.parameters import BenchmarkParameters
from bikerider.benchmark.quartic import eigenvalues_from_polynomial, quartic_roots
from bikerider.benchmark.roots import IMAGINARY, ZERO, polynomial_positive_real_roots, positive_real_roots
from bikerider.benchmark.stability import Stability, stability
from bikerider.engine import arguments
from bikerider.errors import InputError
from bikerider.generated import benchmark_model as gen
from bikerider.generated.manifest import COORDINATES, LATERAL_FORCE_GEOMETRY, MATRIX_ENTRIES, MATRIX_NAMES

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
    """Weave and capsize speeds in m/s (``None`` where there is none) and the stable intervals.

    The definitions (crossings with their direction, the interval they bound) are those of
    :mod:`bikerider.benchmark.stability`.
    """

    weave: float | None
    capsize: float | None
    weave_frequency: float | None
    """Angular frequency of the weave pair at the weave speed [rad/s]."""
    stable_intervals: tuple[tuple[float, float], ...] = ()
    """Every speed interval in which all eigenvalues have negative real parts, lowest first; an
    upper end ``inf`` means stable at every higher speed."""

    @property
    def stable_range(self) -> tuple[float, float] | None:
        """The first (lowest-speed) self-stable interval ``(lower, upper)``, ``upper`` possibly
        ``inf``; ``None`` when the model is stable at no speed."""
        return self.stable_intervals[0] if self.stable_intervals else None


class WhippleModel:
    """Canonical matrices and their dynamics, for one bicycle or a batch.

    Parameters
    ----------
    M, C1, K0, K2 : array_like, shape (..., 2, 2)
        The canonical matrices (K0 per unit g).  Leading dimensions are a batch of bicycles; the
        four broadcast against each other (and ``g``) to the batch shape :attr:`batch_shape`.
    g : float or array_like
        Acceleration due to gravity [m/s^2].

    Notes
    -----
    For a batch, the speed-dependent methods return arrays of shape ``batch_shape +
    speeds.shape + ...`` (every bicycle at every speed); :meth:`critical_speeds`,
    :meth:`stability` and :meth:`weave_birth_speed` take one bicycle
    (:func:`bikerider.benchmark.stability.stability_batch` is their batched form).
    """

    def __init__(self, M, C1, K0, K2, g: float = 9.81):
        mats = [np.array(m, dtype=float) for m in (M, C1, K0, K2)]
        for name, m in zip(MATRIX_NAMES, mats):
            if m.ndim < 2 or m.shape[-2:] != (2, 2):
                raise InputError(name, m.shape, "a 2x2 matrix, or a batch of them of shape (..., 2, 2)")
            if not np.all(np.isfinite(m)):
                bad = tuple(int(i) for i in np.argwhere(~np.isfinite(m))[0][:-2])
                raise InputError(_at(name, bad), (m[bad] if bad else m).tolist(), "finite entries")
        g_array = np.asarray(g, dtype=float)
        try:
            shape = np.broadcast_shapes(*(m.shape[:-2] for m in mats), g_array.shape)
        except ValueError:
            raise InputError(
                "M, C1, K0, K2, g",
                [m.shape for m in mats] + [g_array.shape],
                "batch shapes that broadcast against each other",
            ) from None
        mats = [np.broadcast_to(m, shape + (2, 2)) for m in mats]
        M0 = mats[0]
        singular = rules.singular_mass_matrix(M0)
        if np.any(singular):
            bad = tuple(int(i) for i in np.argwhere(singular)[0]) if shape else ()
            raise InputError(_at("M", bad), M0[bad].tolist(), rules.SINGULAR_MASS_EXPECTED)
        self.M, self.C1, self.K0, self.K2 = mats
        self.batch_shape: tuple[int, ...] = tuple(shape)
        """Shape of the batch of bicycles; ``()`` for one."""
        self.g = float(g_array) if g_array.ndim == 0 else np.broadcast_to(g_array, shape)
        self.source: str | None = None
        """Where the parameters came from, for messages (set by :meth:`from_parameters`)."""
        self.geometry: dict[str, np.ndarray] | None = None
        """Wheelbase ``w``, trail ``c`` and steer axis tilt ``lam`` (set by :meth:`from_parameters`),
        which a lateral-force input needs (:mod:`bikerider.benchmark.state_space`)."""

    @classmethod
    def from_parameters(cls, parameters: BenchmarkParameters) -> WhippleModel:
        """Build from benchmark parameters (Meijaard et al. 2007, Appendix A)."""
        v = parameters.values
        M, C1, K0, K2 = gen.canonical_matrices(**{k: v[k] for k in _CANONICAL_ARGS})
        try:
            model = cls(M, C1, K0, K2, v["g"])  # type: ignore[arg-type]
        except InputError as exc:  # name the file the parameters came from
            raise InputError(exc.name, exc.value, exc.expected, parameters.source) from None
        model.source = parameters.source
        model.geometry = {k: np.asarray(v[k], dtype=float) for k in LATERAL_FORCE_GEOMETRY}
        return model

    @classmethod
    def from_entries(cls, entries: dict[str, float], g: float = 9.81) -> WhippleModel:
        """Build from the sixteen entries ``M_phiphi ... K2_deltadelta`` (:meth:`entries`)."""
        mats = [[[entries[f"{name}_{a}{b}"] for b in COORDINATES] for a in COORDINATES] for name in MATRIX_NAMES]
        return cls(*mats, g=g)

    # -- matrices ---------------------------------------------------------------------------
    def _entries(self) -> dict[str, np.ndarray]:
        return matrix_entries(self.M, self.C1, self.K0, self.K2)

    def entries(self) -> dict[str, np.ndarray]:
        """The sixteen entries ``M_phiphi ... K2_deltadelta`` (each of the batch shape), the keyword
        arguments of the generated matrix-level functions."""
        return self._entries()

    def _batched(self, speeds) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
        """Entries and g shaped ``batch + (1,) * speeds.ndim`` and the speeds, for outer broadcasting."""
        v = np.asarray(speeds, dtype=float)
        pad = (...,) + (None,) * v.ndim
        entries = {k: e[pad] for k, e in self._entries().items()}
        g = self.g if not self.batch_shape else np.asarray(self.g)[pad]
        return entries, g, v

    def state_matrix(self, speeds) -> np.ndarray:
        """State matrices ``batch_shape + speeds.shape + (4, 4)`` for ``x = [phi, delta, phi', delta']``."""
        entries, g, v = self._batched(speeds)
        return gen.state_matrix(**entries, g=g, v=v)

    def characteristic_coefficients(self, speeds) -> np.ndarray:
        """``batch_shape + speeds.shape + (5,)`` coefficients ``[a4, a3, a2, a1, a0]`` of the
        characteristic polynomial."""
        entries, g, v = self._batched(speeds)
        return gen.characteristic_coefficients(**entries, g=g, v=v)

    # -- eigenvalues -----------------------------------------------------------------------
    def eigenvalues(self, speeds, method: str = "eigvals") -> ModalEigenvalues:
        """Eigenvalues at each speed with mode labels (see the module docstring).

        Parameters
        ----------
        speeds : array_like, shape (n,)
            Speeds [m/s].  For a batch the values have shape ``batch_shape + (n, 4)``.
        method : {"eigvals", "quartic"}
            ``"eigvals"``: ``numpy.linalg.eigvals`` of the state matrices (the reference).
            ``"quartic"``: the generated characteristic polynomial solved in closed form for all
            speeds at once (:mod:`bikerider.benchmark.quartic`), many times faster; equal to
            ``"eigvals"`` within about 1e-13 except at a double root (near ``v_d``), where each
            root of the pair is good to about 1e-8.
        """
        if method not in ("eigvals", "quartic"):
            raise InputError("method", method, 'either "eigvals" or "quartic"')
        if method == "quartic":
            return eigenvalues_from_polynomial(self, speeds)
        speeds = check_speeds(speeds)
        with np.errstate(over="ignore", invalid="ignore"):
            state = self.state_matrix(speeds)
        finite = np.all(np.isfinite(state), axis=(-2, -1))
        if not np.all(finite):
            raise InputError(
                "speeds",
                float(speeds[np.nonzero(~finite)[-1][0]]),
                "a speed at which the state matrix is finite (the model's matrices, or the speed, "
                "are too large for floating point there)",
                self.source,
            )
        raw = np.linalg.eigvals(state).reshape((-1,) + speeds.shape + (4,))
        values, labels = self.name_modes(speeds, raw)
        shape = self.batch_shape + speeds.shape + (4,)
        return ModalEigenvalues(speeds, values.reshape(shape), labels.reshape(shape))

    def name_modes(self, speeds: np.ndarray, raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Order eigenvalues ``raw`` (``(b, n, 4)``: each bicycle of the flattened batch at each of
        ``speeds``) as weave(+), weave(-), capsize, castor by continuation from where the names are
        unambiguous (:mod:`bikerider.benchmark.mode_names`); return them with their labels.

        The whole batch is named at once; a bicycle the batched path cannot decide (two complex
        pairs in a segment, no segment with one pair) is named on its own."""
        speeds = np.abs(np.asarray(speeds, dtype=float))
        edges = self._collision_table()
        edges = edges[:, : int(np.isfinite(edges).sum(axis=1).max(initial=0))]  # NaN padding only: no column
        entries = {k: np.asarray(e, dtype=float).reshape(-1) for k, e in self._entries().items()}
        g = np.broadcast_to(np.asarray(self.g, dtype=float), self.batch_shape).reshape(-1)

        def at(v, rows=slice(None)):  # (b, k) speeds, one row per bicycle (of ``rows``)
            some = {k: e[rows, None] for k, e in entries.items()}
            return quartic_roots(gen.characteristic_coefficients(**some, g=g[rows, None], v=v))

        largest = np.where(np.isfinite(edges), edges, 0.0).max(axis=1, initial=0.0)
        top = np.maximum(10.0, 2.0 * largest)
        pairs, names, alone = mode_names.batch_naming(at, edges, top)
        values, labels = mode_names.batch_apply(np.asarray(raw, dtype=complex), speeds, edges, pairs, names)
        for b, named in _name_one_by_one(at, entries, g, edges, top, np.nonzero(alone)[0]):
            values[b], labels[b] = mode_names.apply(raw[b], speeds, named)
        return values, labels

    def _collision_table(self) -> np.ndarray:
        """:meth:`collision_speeds` of every bicycle of the flattened batch, ``(b, m)``, NaN-padded."""
        with np.errstate(over="ignore", invalid="ignore"):
            coefficients = np.asarray(gen.discriminant_polynomial(**self._entries(), g=self.g), dtype=float)
        flat = coefficients.reshape(-1, coefficients.shape[-1])
        if not np.all(np.isfinite(flat)):
            raise InputError(
                "M, C1, K0, K2",
                "entries too large for floating point",
                "matrices whose characteristic discriminant is finite",
                self.source,
            )
        return np.sqrt(_polished_roots_batch(flat))

    def collision_speeds(self):
        """The speeds [m/s] at which two eigenvalues coincide: the positive roots, in ``u = v^2``, of
        the discriminant of the characteristic quartic (the generated ``discriminant_polynomial``).

        Returns an increasing array for one bicycle; for a batch, an object array of the batch shape
        holding one such array per bicycle.
        """
        table = self._collision_table()
        out = np.empty(table.shape[0], dtype=object)
        for b, row in enumerate(table):
            out[b] = row[np.isfinite(row)]
        return out[0] if not self.batch_shape else out.reshape(self.batch_shape)

    # -- critical speeds ---------------------------------------------------------------------
    def critical_speeds(self) -> CriticalSpeeds:
        """Weave and capsize speeds and the stable intervals, from the characteristic polynomial.

        No scan over speed: the Routh-Hurwitz conditions are polynomials in ``v^2`` whose real
        roots, with the direction of each crossing, give every stable interval; the weave and
        capsize speeds are the crossings that bound the first one
        (:mod:`bikerider.benchmark.stability` gives the rules, also for several intervals or none).
        """
        result = self.stability()
        return CriticalSpeeds(
            result.weave, result.capsize, result.weave_frequency, tuple((i.lower, i.upper) for i in result.intervals)
        )

    def stability(self) -> Stability:
        """Stable intervals, every crossing of the imaginary axis (speed, kind, direction) and the
        critical speeds (:func:`bikerider.benchmark.stability.stability`)."""
        self._one_bicycle("stability")
        values = [x for m in (self.M, self.C1, self.K0, self.K2) for x in m.ravel().tolist()]  # floats, fast
        entries = dict(zip(MATRIX_ENTRIES, values))
        try:
            return stability(entries, self.g)
        except (OverflowError, ValueError):
            raise InputError(
                "M, C1, K0, K2",
                "entries too large for floating point",
                "matrices whose critical-speed polynomials are finite",
                self.source,
            ) from None

    def weave_birth_speed(self) -> float | None:
        """The speed ``v_d`` at which the weave pair is born from two real eigenvalues [m/s].

        The discriminant of the characteristic quartic vanishes wherever two eigenvalues coincide
        (:meth:`collision_speeds`).  ``v_d`` is the smallest of those speeds at which the two
        eigenvalues named weave (by continuation from high speed, :mod:`bikerider.benchmark.mode_names`:
        the two that merge there, which are not always the two largest) are real just below and a
        complex pair just above (Meijaard et al. 2007, section 6).  ``None`` when there is no such
        speed.
        """
        self._one_bicycle("weave_birth_speed")
        edges = self.collision_speeds()
        if not len(edges):
            return None
        named = mode_names.naming(lambda v: np.linalg.eigvals(self.state_matrix(v)), edges, max(10.0, 2 * edges[-1]))
        for i, speed in enumerate(edges):
            below, above = named.names[i], named.names[i + 1]
            real_below = "weave" in below[2 * named.pairs[i] :]
            pair_above = "weave" in above[: 2 * named.pairs[i + 1]]
            if real_below and pair_above:
                return float(speed)
        return None

    def _one_bicycle(self, method: str) -> None:
        if self.batch_shape:
            raise InputError(
                "model",
                f"a batch of shape {self.batch_shape}",
                f"one bicycle for {method}() (for a batch: bikerider.benchmark.stability."
                "stability_batch(model.entries(), model.g))",
                self.source,
            )


def _polished_roots_batch(coefficients: np.ndarray) -> np.ndarray:
    """:func:`_polished_roots` of every row of ``coefficients`` ``(b, d + 1)`` at once (companion
    matrices' eigenvalues, as ``numpy.roots``, with the tolerances of
    :func:`~bikerider.benchmark.roots.polynomial_positive_real_roots`), ``(b, d)`` NaN-padded."""
    b, d1 = coefficients.shape
    d = d1 - 1
    out = np.full((b, d), np.nan)
    if b == 0 or d == 0:
        return out
    scale = np.abs(coefficients).max(axis=1, keepdims=True)
    c = coefficients / np.where(scale > 0, scale, 1.0)
    full = np.abs(c[:, 0]) > ZERO
    for row in np.nonzero(~full)[0]:  # a lower degree: numpy.roots, one at a time
        roots = _polished_roots(coefficients[row])
        out[row, : roots.size] = roots
    rows = np.nonzero(full)[0]
    if rows.size:
        monic = c[rows, 1:] / c[rows, :1]
        companion = np.zeros((rows.size, d, d))
        companion[:, 0, :] = -monic
        companion[:, np.arange(1, d), np.arange(d - 1)] = 1.0
        roots = np.linalg.eigvals(companion)
        real = np.abs(roots.imag) <= IMAGINARY * np.maximum(1.0, np.abs(roots.real))
        u = np.where(real & (roots.real > 0), roots.real, np.nan)
        poly = coefficients[rows][:, None, :]
        slope = poly[..., :-1] * np.arange(d, 0, -1)
        for _ in range(3):  # Newton steps, each kept only while it is small (a simple root)
            value = _horner(poly, u)
            derivative = _horner(slope, u)
            with np.errstate(divide="ignore", invalid="ignore"):
                step = np.where(derivative != 0, value / derivative, 0.0)
            small = np.isfinite(step) & (np.abs(step) <= 1e-6 * u)
            u = np.where(small, u - step, u)
        out[rows] = np.sort(u, axis=1)  # NaN last
    return out


def _horner(poly: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Polynomials ``poly`` ``(..., 1, k)`` (highest power first) at ``x`` ``(..., n)``."""
    out = np.zeros(x.shape)
    for j in range(poly.shape[-1]):
        out = out * x + poly[..., j]
    return out


def _polished_roots(coefficients: np.ndarray) -> np.ndarray:
    """Positive real roots of a polynomial (highest power first), each polished by Newton steps."""
    slope = np.polyder(coefficients)
    out = []
    for u in polynomial_positive_real_roots(coefficients):
        for _ in range(3):  # Newton steps: the root of a simple zero to full precision
            step = np.polyval(coefficients, u) / np.polyval(slope, u) if np.polyval(slope, u) else 0.0
            if not np.isfinite(step) or abs(step) > 1e-6 * u:
                break
            u -= step
        out.append(u)
    return np.sort(np.array(out, dtype=float))


def _eigenvalues_of(entries: dict[str, float], g: float):
    """Speeds ``(k,)`` to the eigenvalues ``(k, 4)`` of one bicycle given by its matrix entries."""

    def at(speeds):  # the closed-form quartic: several times faster than eigvals, good to 1e-8 at a double root
        return quartic_roots(gen.characteristic_coefficients(**entries, g=g, v=np.asarray(speeds, dtype=float)))

    return at


def _name_one_by_one(at, entries: dict[str, np.ndarray], g: np.ndarray, edges: np.ndarray, top: np.ndarray, lone):
    """:func:`mode_names.naming` of each bicycle ``lone`` of a flattened batch (``at``: batched
    speeds to eigenvalues, ``entries``/``g`` per bicycle, ``edges`` NaN-padded collision speeds,
    ``top`` a speed above them), yielding ``(bicycle, naming)``.  Their evaluations are batched:
    first all their :func:`mode_names.naming_speeds` in one call, then all their predicted
    :func:`mode_names.path_speeds` in another, served to each naming by speed list."""
    rows = [edges[b][np.isfinite(edges[b])] for b in lone]
    first = [mode_names.naming_speeds(row, float(top[b])) for b, row in zip(lone, rows)]
    width = max((x.size for x in first), default=0)
    padded = np.array([np.pad(x, (0, width - x.size), constant_values=x[-1]) for x in first])
    evaluated = at(padded.reshape(len(lone), width), lone) if len(lone) else None
    ahead = [
        mode_names.path_speeds(row, float(top[b]), evaluated[k, : first[k].size])
        for k, (b, row) in enumerate(zip(lone, rows))
    ]
    owner = np.array([b for b, speeds in zip(lone, ahead) for _ in speeds], dtype=np.intp)
    if owner.size:
        followed = at(np.array([x for speeds in ahead for x in speeds]).reshape(owner.size, -1), owner)
    served: list[dict[bytes, np.ndarray]] = [{} for _ in lone]
    p = 0
    for k, speeds in enumerate(ahead):
        for x in speeds:
            served[k][x.tobytes()] = followed[p]
            p += 1
    for k, (b, row) in enumerate(zip(lone, rows)):
        one = {key: e[b] for key, e in entries.items()}
        at_b = _served(_eigenvalues_of(one, float(g[b])), served[k])
        yield b, mode_names.naming(at_b, row, float(top[b]), evaluated[k, : first[k].size])


def _served(at, ready: dict[bytes, np.ndarray]):
    """``at`` (speeds to eigenvalues), but speed lists already evaluated (``ready``, keyed by their
    bytes) are served from there: evaluations batched over several bicycles beforehand."""

    def served(speeds):
        hit = ready.get(np.asarray(speeds, dtype=float).tobytes())
        return hit if hit is not None else at(speeds)

    return served


def _at(name: str, index: tuple[int, ...]) -> str:
    """``name`` with a batch index, ``M[3, 1]``, for messages (just ``name`` for one bicycle)."""
    return f"{name}[{', '.join(map(str, index))}]" if index else name


__all__ = [
    "MODES",
    "CriticalSpeeds",
    "ModalEigenvalues",
    "WhippleModel",
    "check_speeds",
    "label_modes",
    "matrix_entries",
    "positive_real_roots",
]
