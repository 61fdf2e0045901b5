"""The Whipple model under a control law on the steer torque: closed-loop state matrix, eigenvalues,
mode names and every stable speed interval.

A :class:`~bikerider.benchmark.control.ControlLaw` gives the steer torque

    T_delta = k_phi(v) phi + k_phid(v) phi_dot + k_delta(v) delta + k_deltad(v) delta_dot,

each gain constant, piecewise linear in speed or a ramp (:mod:`bikerider.benchmark.control`).
Applied to the model ``M q'' + v C1 q' + (g K0 + v^2 K2) q = [0, T_delta]`` it gives

    A_cl(v) = A(v) + b k(v)^T,        b = [0, 0, (M^-1)[:, 1]]   (the steer-torque column of B),

with ``k`` the gains in state order ``[k_phi, k_delta, k_phid, k_deltad]``; in second-order form
``M q'' + (v C1 - e k_rates^T) q' + (g K0 + v^2 K2 - e k_angles^T) q = 0``, ``e = [0, 1]^T``.

Stable intervals.  On each speed interval where every gain is linear in ``v`` (between the break
speeds of the law; one interval for constant gains), the coefficients ``a4 .. a0`` of the
closed-loop characteristic polynomial are polynomials in ``v`` (degrees 0 to 4) and so is the third
Hurwitz determinant ``H3 = a3 a2 a1 - a4 a1^2 - a0 a3^2`` (degree 6 at most).  Every eigenvalue has a
negative real part exactly when all ``a_k > 0`` and ``H3 > 0`` (Lienard-Chipart, ``a4 = det M > 0``),
so the real roots of these polynomials and the break speeds cut ``v >= 0`` into pieces of fixed
verdict, and one evaluation per piece decides it: no scan over speed, as for the open loop
(:mod:`bikerider.benchmark.stability`).  At an end of a stable interval either ``a0`` changes sign
(a real eigenvalue crosses zero: capsize-like) or ``H3`` does with ``omega^2 = a1 / a3 > 0`` (a
complex pair crosses at ``+/- i omega``: weave-like); the result uses the open loop's
:class:`~bikerider.benchmark.stability.Stability`, so the weave and capsize speeds follow the same
rules.  With every gain zero the intervals are those of ``WhippleModel.stability()``.

Entry points: :func:`closed_loop` (a :class:`ClosedLoopModel`), :func:`lqr_gains` and
:func:`lqr_law` (optimal full-state feedback on the steer torque at each speed, from the continuous
algebraic Riccati equation), :func:`closed_loop_matrix` (any state matrix and input column, also
used by the gap's models with extra states).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg
from numpy.polynomial import Polynomial

from bikerider.benchmark import mode_names
from bikerider.benchmark.control import GAIN_NAMES, ControlLaw, GainSchedule
from bikerider.benchmark.mode_labels import ModalEigenvalues, check_speeds
from bikerider.benchmark.model import CriticalSpeeds, WhippleModel
from bikerider.benchmark.stability import Crossing, Stability, StableInterval, _critical
from bikerider.errors import InputError

GAIN_STATE_INDEX = (0, 2, 1, 3)
"""State index (``x = [phi, delta, phi_dot, delta_dot]``) of each gain of :data:`GAIN_NAMES`."""


def closed_loop_matrix(A: np.ndarray, b: np.ndarray, gains: np.ndarray, state_index=GAIN_STATE_INDEX) -> np.ndarray:
    """``A + b k^T``: the state matrix under the steer torque ``T_delta = k^T x``.

    Parameters
    ----------
    A : numpy.ndarray, shape (..., n, n)
    b : numpy.ndarray, shape (..., n)
        The steer-torque column of the input matrix.
    gains : numpy.ndarray, shape (..., 4)
        ``[k_phi, k_phid, k_delta, k_deltad]`` (:data:`GAIN_NAMES`), broadcast against ``A``'s batch.
    state_index : sequence of 4 int
        The state index of roll, roll rate, steer, steer rate (``(0, 2, 1, 3)`` for the Whipple
        states; a model with more states gives its own).
    """
    gains = np.asarray(gains, dtype=float)
    n = A.shape[-1]
    row = np.zeros(np.broadcast_shapes(gains.shape[:-1], A.shape[:-2]) + (n,))
    for k, index in enumerate(state_index):
        row[..., index] = gains[..., k]
    return A + np.asarray(b)[..., :, None] * row[..., None, :]


def _law(law) -> ControlLaw:
    """A :class:`ControlLaw` from a law or four constant gains."""
    if isinstance(law, ControlLaw):
        return law
    if isinstance(law, dict):
        unknown = sorted(set(law) - set(GAIN_NAMES))
        if unknown:
            raise InputError("control gains", unknown[0], "one of the gains " + ", ".join(GAIN_NAMES))
        return ControlLaw.constant([float(law.get(k, 0.0)) for k in GAIN_NAMES])
    return ControlLaw.constant(law)


class ClosedLoopModel:
    """A :class:`~bikerider.benchmark.model.WhippleModel` (one bicycle or a batch) under a control law.

    Parameters
    ----------
    model : WhippleModel
    law : ControlLaw, dict or sequence of 4 float
        The law on the steer torque; a dict ``{"k_phi": ..., ...}`` or ``[k_phi, k_phid, k_delta,
        k_deltad]`` is a law of constant gains.
    """

    def __init__(self, model: WhippleModel, law):
        self.model = model
        self.law = _law(law)
        self.source = model.source

    @property
    def batch_shape(self) -> tuple[int, ...]:
        return self.model.batch_shape

    def gains(self, speeds) -> np.ndarray:
        """The law's gains ``speeds.shape + (4,)`` (order :data:`GAIN_NAMES`)."""
        return self.law(np.asarray(speeds, dtype=float))

    def steer_input(self) -> np.ndarray:
        """``b``, the steer-torque column of the input matrix, ``batch_shape + (4,)``."""
        Minv = np.linalg.inv(self.model.M)
        b = np.zeros(self.batch_shape + (4,))
        b[..., 2:] = Minv[..., :, 1]
        return b

    def state_matrix(self, speeds) -> np.ndarray:
        """Closed-loop state matrices ``batch_shape + speeds.shape + (4, 4)``."""
        v = np.asarray(speeds, dtype=float)
        A = self.model.state_matrix(v)
        b = self.steer_input()[(...,) + (None,) * v.ndim + (slice(None),)]
        return closed_loop_matrix(A, b, self.gains(v))

    def eigenvalues(self, speeds) -> ModalEigenvalues:
        """Closed-loop eigenvalues at each speed, named as the open loop's are
        (:mod:`bikerider.benchmark.mode_names`: by continuation in speed from the highest speeds
        with one complex pair, across :meth:`collision_speeds`): ``weave``, ``capsize``, ``castor``
        where the closed loop keeps that structure, ``"other"`` where it does not.  Under strong
        feedback the names say which open-loop branch an eigenvalue continues, no more."""
        speeds = check_speeds(speeds)
        raw = np.linalg.eigvals(self.state_matrix(speeds)).reshape((-1, speeds.size, 4))
        values, labels = self.name_modes(speeds, raw)
        shape = self.batch_shape + speeds.shape + (4,)
        return ModalEigenvalues(speeds, values.reshape(shape), labels.reshape(shape))

    def name_modes(self, speeds: np.ndarray, raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`WhippleModel.name_modes`, for the closed loop: ``raw`` ``(b, n, 4)`` ordered
        weave(+), weave(-), capsize, castor by continuation, with the labels."""
        speeds = np.asarray(speeds, dtype=float)
        values = np.empty(raw.shape, dtype=complex)
        labels = np.empty(raw.shape, dtype=object)
        for b, one in enumerate(self._bicycles()):
            edges = one.collision_speeds()
            top = float(max(10.0, 2.0 * edges[-1])) if len(edges) else 10.0
            named = mode_names.naming(lambda v: np.linalg.eigvals(one.state_matrix(v)), edges, top)
            values[b], labels[b] = mode_names.apply(raw[b], np.abs(speeds), named)
        return values, labels

    def _bicycles(self) -> list[ClosedLoopModel]:
        """Each bicycle of the batch under the law (the model itself for one bicycle)."""
        if not self.batch_shape:
            return [self]
        entries = {k: e.reshape(-1) for k, e in self.model.entries().items()}
        g = np.broadcast_to(self.model.g, self.batch_shape).reshape(-1)
        return [
            ClosedLoopModel(
                WhippleModel.from_entries({k: float(e[b]) for k, e in entries.items()}, float(g[b])), self.law
            )
            for b in range(g.size)
        ]

    def collision_speeds(self) -> np.ndarray:
        """Speeds [m/s] where two closed-loop eigenvalues coincide: the real roots of the discriminant
        of the characteristic quartic, a polynomial in ``v`` on each piece of the law (one bicycle)."""
        out: list[float] = []
        for lower, upper, (a, b, c, d, e) in self.characteristic_polynomials():
            out.extend(_real_roots(_quartic_discriminant(a, b, c, d, e), lower, upper))
        return np.array(sorted(out))

    # -- stability ---------------------------------------------------------------------------
    def characteristic_polynomials(self) -> list[tuple[float, float, list[Polynomial]]]:
        """``[(lower, upper, [a4, a3, a2, a1, a0]), ...]``: the coefficients of the characteristic
        polynomial as polynomials in ``v`` on each interval where the gains are linear in speed
        (one bicycle)."""
        self.model._one_bicycle("characteristic_polynomials")
        breaks = _break_speeds(self.law)
        edges = [0.0, *[b for b in breaks if b > 0], math.inf]
        M, C1, K0, K2, g = (np.asarray(x, dtype=float) for x in (*_matrices(self.model), self.model.g))
        pieces = []
        for lower, upper in zip(edges, edges[1:]):
            x0 = lower
            x1 = 0.5 * (lower + upper) if math.isfinite(upper) else lower + 1.0
            if x1 == x0:
                x1 = x0 + 1.0
            k0, k1 = self.law(np.array([x0, x1]))
            slope = (k1 - k0) / (x1 - x0)
            gain = [Polynomial([k0[j] - slope[j] * x0, slope[j]]) for j in range(4)]  # affine in v
            v = Polynomial([0.0, 1.0])
            # second-order form: damping C(v) = v C1 - e [k_phid, k_deltad], stiffness K(v) = g K0 + v^2 K2 - e [k_phi, k_delta]
            C = [[v * C1[i, j] for j in range(2)] for i in range(2)]
            K = [[Polynomial([g * K0[i, j]]) + v * v * K2[i, j] for j in range(2)] for i in range(2)]
            C[1][0] = C[1][0] - gain[1]
            C[1][1] = C[1][1] - gain[3]
            K[1][0] = K[1][0] - gain[0]
            K[1][1] = K[1][1] - gain[2]
            a4 = Polynomial([M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]])
            a3 = M[0, 0] * C[1][1] + C[0][0] * M[1, 1] - M[0, 1] * C[1][0] - C[0][1] * M[1, 0]
            a2 = (
                M[0, 0] * K[1][1]
                + C[0][0] * C[1][1]
                + K[0][0] * M[1, 1]
                - M[0, 1] * K[1][0]
                - C[0][1] * C[1][0]
                - K[0][1] * M[1, 0]
            )
            a1 = C[0][0] * K[1][1] + K[0][0] * C[1][1] - C[0][1] * K[1][0] - K[0][1] * C[1][0]
            a0 = K[0][0] * K[1][1] - K[0][1] * K[1][0]
            pieces.append((lower, upper, [a4, a3, a2, a1, a0]))
        return pieces

    def stability(self) -> Stability:
        """Every closed-loop stable speed interval (``v >= 0``), every crossing of the imaginary axis,
        and the weave and capsize speeds by the open loop's rules (module docstring; one bicycle)."""
        pieces = self.characteristic_polynomials()
        points: list[tuple[float, str, list[Polynomial]]] = []  # (speed, kind, coefficients there)
        verdicts: list[tuple[float, float, bool]] = []
        for lower, upper, (a4, a3, a2, a1, a0) in pieces:
            if a4.coef[0] <= 0:
                raise InputError("M", self.model.M.tolist(), "a mass matrix with a positive determinant", self.source)
            h3 = a3 * a2 * a1 - a4 * a1 * a1 - a0 * a3 * a3
            cuts = [lower]
            for kind, poly in (("real", a0), ("oscillatory", h3), ("", a1), ("", a2), ("", a3)):
                for root in _real_roots(poly, lower, upper):
                    cuts.append(root)
                    if kind:
                        points.append((root, kind, [a4, a3, a2, a1, a0, h3]))
            cuts = sorted(set(cuts))
            ends = cuts[1:] + [upper]
            for a, b in zip(cuts, ends):
                mid = 0.5 * (a + b) if math.isfinite(b) else a + max(1.0, a)
                stable = all(p(mid) > 0 for p in (a3, a2, a1, a0, h3))
                verdicts.append((a, b, stable))
        crossings = _crossings(points)
        intervals: list[StableInterval] = []
        for a, b, stable in verdicts:
            if not stable:
                continue
            if intervals and intervals[-1].upper == a and _at(crossings, a) is None:
                last = intervals.pop()  # a break speed or a touch, not an end: merge
                intervals.append(StableInterval(last.lower, b, last.lower_crossing, None))
            else:
                intervals.append(StableInterval(a, b, _at(crossings, a) if a > 0 else None, None))
        intervals = [
            StableInterval(
                i.lower, i.upper, i.lower_crossing, _at(crossings, i.upper) if math.isfinite(i.upper) else None
            )
            for i in intervals
        ]
        weave, capsize, frequency = _critical(intervals, tuple(crossings))
        return Stability(tuple(intervals), tuple(crossings), weave, capsize, frequency)

    def critical_speeds(self) -> CriticalSpeeds:
        """Weave and capsize speeds and stable intervals of the closed loop (one bicycle)."""
        result = self.stability()
        return CriticalSpeeds(
            result.weave, result.capsize, result.weave_frequency, tuple((i.lower, i.upper) for i in result.intervals)
        )


def closed_loop(model: WhippleModel, law) -> ClosedLoopModel:
    """``model`` under ``law`` (a :class:`ControlLaw`, ``{"k_phi": ...}`` or four constant gains)."""
    return ClosedLoopModel(model, law)


def _quartic_discriminant(a, b, c, d, e):
    """The discriminant of ``a s^4 + b s^3 + c s^2 + d s + e`` (coefficients of any ring: floats or
    polynomials in the speed); zero exactly where two roots coincide."""
    return (
        256 * a**3 * e**3
        - 192 * a**2 * b * d * e**2
        - 128 * a**2 * c**2 * e**2
        + 144 * a**2 * c * d**2 * e
        - 27 * a**2 * d**4
        + 144 * a * b**2 * c * e**2
        - 6 * a * b**2 * d**2 * e
        - 80 * a * b * c**2 * d * e
        + 18 * a * b * c * d**3
        + 16 * a * c**4 * e
        - 4 * a * c**3 * d**2
        - 27 * b**4 * e**2
        + 18 * b**3 * c * d * e
        - 4 * b**3 * d**3
        - 4 * b**2 * c**3 * e
        + b**2 * c**2 * d**2
    )


def _matrices(model: WhippleModel):
    return model.M, model.C1, model.K0, model.K2


def _break_speeds(law: ControlLaw) -> list[float]:
    speeds: set[float] = set()
    for schedule in law.gains.values():
        if schedule.ramp is not None:
            speeds.add(float(schedule.ramp[1]))
        elif len(schedule.speeds) > 1:
            speeds.update(float(s) for s in schedule.speeds)
    return sorted(speeds)


def _real_roots(poly: Polynomial, lower: float, upper: float) -> list[float]:
    """Real roots of ``poly`` in ``(lower, upper)``, polished by Newton steps."""
    coef = np.trim_zeros(poly.coef, "b")
    if coef.size < 2:
        return []
    scale = np.abs(coef).max()
    coef = coef.copy()
    coef[np.abs(coef) < 1e-15 * scale] = 0.0
    coef = np.trim_zeros(coef, "b")
    if coef.size < 2:
        return []
    p = Polynomial(coef)
    dp = p.deriv()
    out = []
    for root in p.roots():
        if abs(root.imag) > 1e-7 * max(1.0, abs(root.real)):
            continue
        x = float(root.real)
        for _ in range(3):
            d = dp(x)
            if d == 0:
                break
            step = p(x) / d
            if not math.isfinite(step) or abs(step) > 1e-6 * max(1.0, abs(x)):
                break
            x -= step
        if lower < x < upper:
            out.append(float(x))
    return out


def _crossings(points) -> list[Crossing]:
    """The roots of ``a0`` and of ``H3`` (with ``a1 / a3 > 0``) where the sign changes, as crossings."""
    out = []
    for speed, kind, (a4, a3, a2, a1, a0, h3) in sorted(points, key=lambda p: p[0]):
        poly = a0 if kind == "real" else h3
        step = 1e-7 * max(1.0, speed)
        below, above = poly(speed - step), poly(speed + step)
        if below * above >= 0:  # a touch, not a sign change
            continue
        rising = above > below
        if kind == "real":
            out.append(Crossing(speed, "real", bool(rising == (a1(speed) > 0)), 0.0))
        else:
            omega2 = float(a1(speed) / a3(speed)) if a3(speed) != 0 else -1.0
            if omega2 > 0:
                out.append(Crossing(speed, "oscillatory", bool(rising == (a3(speed) > 0)), math.sqrt(omega2)))
    return out


def _at(crossings: list[Crossing], speed: float) -> Crossing | None:
    return next((c for c in crossings if abs(c.speed - speed) <= 1e-9 * max(1.0, speed)), None)


# -- optimal full-state feedback --------------------------------------------------------------
def lqr_gains(model: WhippleModel, speeds, Q=None, R: float = 1.0) -> np.ndarray:
    """Linear-quadratic regulator gains on the steer torque at each speed.

    Minimises ``integral (x^T Q x + R T_delta^2) dt`` for ``x' = A(v) x + b T_delta`` (solving the
    continuous algebraic Riccati equation with :func:`scipy.linalg.solve_continuous_are`) and
    returns the law's gains ``T_delta = k^T x``, i.e. ``k = -R^-1 b^T P``.

    Parameters
    ----------
    model : WhippleModel
        One bicycle.
    speeds : array_like, shape (n,)
        Speeds [m/s].
    Q : array_like, shape (4, 4), optional
        State weight (states ``[phi, delta, phi_dot, delta_dot]``), symmetric positive
        semi-definite; the identity by default.
    R : float
        Weight of the steer torque, positive.

    Returns
    -------
    numpy.ndarray, shape (n, 4)
        ``[k_phi, k_phid, k_delta, k_deltad]`` (:data:`GAIN_NAMES`) at each speed.
    """
    model._one_bicycle("lqr_gains")
    speeds = check_speeds(speeds)
    Q = np.eye(4) if Q is None else np.asarray(Q, dtype=float)
    if Q.shape != (4, 4) or not np.all(np.isfinite(Q)) or not np.allclose(Q, Q.T):
        raise InputError("Q", Q.tolist(), "a finite symmetric 4x4 state weight")
    if np.linalg.eigvalsh(Q).min() < -1e-12 * max(1.0, np.abs(Q).max()):
        raise InputError("Q", Q.tolist(), "a positive semi-definite state weight")
    if not (isinstance(R, (int, float)) and math.isfinite(R) and R > 0):
        raise InputError("R", R, "a positive weight of the steer torque")
    b = ClosedLoopModel(model, NO_GAINS).steer_input()[:, None]
    out = np.empty((speeds.size, 4))
    for i, A in enumerate(model.state_matrix(speeds)):
        try:
            P = scipy.linalg.solve_continuous_are(A, b, Q, np.array([[R]]))
        except (np.linalg.LinAlgError, ValueError) as exc:
            raise InputError(
                "Q",
                Q.tolist(),
                f"weights for which the Riccati equation has a stabilising solution at {speeds[i]:g} m/s ({exc})",
                model.source,
            ) from None
        k_state = -(b.T @ P)[0] / R
        out[i] = k_state[list(GAIN_STATE_INDEX)]
    return out


def lqr_law(model: WhippleModel, speeds, Q=None, R: float = 1.0, name: str = "LQR") -> ControlLaw:
    """The LQR gains of :func:`lqr_gains` at ``speeds`` as a law, piecewise linear between them
    (held beyond the ends): a gain-scheduled controller to apply with :func:`closed_loop`."""
    speeds = check_speeds(speeds)
    gains = lqr_gains(model, speeds, Q, R)
    if speeds.size == 1:
        schedules = {k: GainSchedule.constant(float(gains[0, j]), k) for j, k in enumerate(GAIN_NAMES)}
    else:
        schedules = {
            k: GainSchedule.piecewise(speeds.tolist(), gains[:, j].tolist(), k) for j, k in enumerate(GAIN_NAMES)
        }
    return ControlLaw(name, schedules, f"LQR on the steer torque, R = {R:g}")


NO_GAINS = ControlLaw("no control")

__all__ = [
    "GAIN_STATE_INDEX",
    "ClosedLoopModel",
    "closed_loop",
    "closed_loop_matrix",
    "lqr_gains",
    "lqr_law",
]
