"""Linear bicycle models with any set of candidate effects: state space, eigenvalues, time response.

One :class:`EffectModel` is the Whipple bicycle (benchmark parameters) plus the effects it is given,
built from the generated code of ``derive/gap_effects.py``:

* no ``rider_lean`` and no ``tyre_slip``: ``whipple_extended_state_matrices`` (state
  ``[phi, delta, phi_dot, delta_dot]``);
* ``rider_lean``: ``rider_lean_matrices`` (state ``[phi, delta, theta, phi_dot, delta_dot,
  theta_dot]``);
* ``tyre_slip``: ``tyre_slip_descriptor`` (state ``[phi, delta, (theta,) u, r, phi_dot, delta_dot,
  (theta_dot,) F_R, F_F]``).

Each is a :class:`bikerider.benchmark.state_space.StateSpace` (the one state-space class of the
package), its outputs the states ``phi, delta, phi_dot, delta_dot``.

Steer inertia, damping, stiffness and the passive arms enter every one of them.  A known control
law acting during the measurements, steer torque ``T_delta = k_phi phi + k_phid phid + k_delta delta
+ k_deltad deltad`` (benchmark sign convention: positive torque turns the handlebar to positive
steer), closes the loop in every model alike.

Every parameter value may carry a leading batch shape (e.g. ``(P, 1)``) that broadcasts against
the speeds, which is how the diagnosis evaluates many parameter sets in one call.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from bikerider.benchmark.quartic import quartic_roots
from bikerider.benchmark.simulation import expm
from bikerider.benchmark.state_space import StateSpace
from bikerider.errors import InputError
from bikerider.gap.candidates.effects import EFFECTS, STRUCTURAL_KEYS, TYRE_SLIP
from bikerider.gap.measured.control import GAIN_NAMES  # noqa: F401  (the order of the gain arrays)
from bikerider.generated import gap_effects as gen
from bikerider.generated.manifest import FUNCTIONS, UPPER_BODY_ARGS

BENCH_ARGS = FUNCTIONS["benchmark_model.canonical_matrices"]["args"]
"""Benchmark parameters the linear models depend on (plus ``g``)."""
UPPER_BODY_KEYS = UPPER_BODY_ARGS
GRIP_KEYS = ("x_grip", "z_grip", "b_grip")
FRAME_KEYS = tuple(key for e in EFFECTS.values() if not (e.adds_lean or e.adds_tyres) for key in e.structural_keys)
"""The parameters of the effects that every generated model takes (between the frames and the arms: the
lean and the tyres have models of their own)."""
OUTPUT_NAMES = ("phi", "delta", "phid", "deltad")


@dataclass(frozen=True)
class RiderGeometry:
    """Where the rider's moving parts are: the upper body that can lean and the grips.

    Attributes
    ----------
    upper_body : dict or None
        ``m_u, x_u, z_u, IUxx, IUxz, IUzz, z_lean`` (SI); ``None`` for a riderless bicycle.
    grips : dict
        ``x_grip, z_grip, b_grip`` [m].
    notes : str
        How the values were obtained.
    uncertainty : dict
        The geometry's independent sources of uncertainty: a name (e.g. ``"hip axis height"`` or
        ``"grips.z_grip"``) to the shift of each value it moves by one standard uncertainty,
        ``{key: shift}`` (keys of :data:`UPPER_BODY_KEYS` and :data:`GRIP_KEYS`, SI).  Empty: the
        geometry is taken as known.  :mod:`bikerider.gap.candidates.nominal` states the default
        geometry's; a model file's ``"value +/- sigma"`` gives one source per value.
    """

    upper_body: dict[str, float] | None
    grips: dict[str, float]
    notes: str = ""
    uncertainty: dict[str, dict[str, float]] = field(default_factory=dict)

    def __post_init__(self):
        for key in GRIP_KEYS:
            value = self.grips.get(key)
            if value is None or not math.isfinite(value):
                raise InputError(f"grips.{key}", value, "a finite number [m]")
        if self.grips["b_grip"] <= 0:
            raise InputError("grips.b_grip", self.grips["b_grip"], "a positive half-width [m]")
        if self.upper_body is not None:
            for key in UPPER_BODY_KEYS:
                value = self.upper_body.get(key)
                if value is None or not math.isfinite(value):
                    raise InputError(f"upper_body.{key}", value, "a finite number")
            if self.upper_body["m_u"] <= 0 or self.upper_body["IUxx"] <= 0 or self.upper_body["IUzz"] <= 0:
                raise InputError("upper_body", self.upper_body, "a positive mass and positive moments of inertia")
        for name, shift in self.uncertainty.items():
            for key, value in shift.items():
                if key not in GRIP_KEYS + tuple(UPPER_BODY_KEYS):
                    raise InputError(
                        f"uncertainty of {name}", key, "a key of " + ", ".join(GRIP_KEYS + tuple(UPPER_BODY_KEYS))
                    )
                if not math.isfinite(value):
                    raise InputError(
                        f"uncertainty of {name}", f"{key}: {value}", "a finite shift per standard uncertainty"
                    )

    def sources(self, keys) -> list[str]:
        """The sources of :attr:`uncertainty` that move any of ``keys`` (and a value this geometry has)."""
        have = set(self.grips) | set(self.upper_body or {})
        return [
            name
            for name, shift in self.uncertainty.items()
            if any(key in keys and key in have and value != 0 for key, value in shift.items())
        ]

    def shifted(self, name: str, factor: float) -> RiderGeometry:
        """This geometry with source ``name`` of :attr:`uncertainty` moved by ``factor`` standard
        uncertainties (an ``InputError`` where that leaves an impossible geometry, e.g. a negative mass)."""
        shift = self.uncertainty[name]
        grips = {k: v + factor * shift.get(k, 0.0) for k, v in self.grips.items()}
        upper = None
        if self.upper_body is not None:
            upper = {k: v + factor * shift.get(k, 0.0) for k, v in self.upper_body.items()}
        return RiderGeometry(upper, grips, f"{self.notes}; {name} moved by {factor:+g} sigma", self.uncertainty)


def geometry_keys(effects) -> tuple[str, ...]:
    """The rider geometry's values the predictions of a set of effects depend on: the grips with the
    passive arms, the upper body with the rider's lean (none for the other effects)."""
    keys: tuple[str, ...] = ()
    if any("m_arm" in STRUCTURAL_KEYS.get(e, ()) for e in effects):
        keys += GRIP_KEYS
    if any(e in EFFECTS and EFFECTS[e].adds_lean for e in effects):
        keys += tuple(UPPER_BODY_KEYS)
    return keys


def _as_float(value) -> np.ndarray:
    return np.asarray(value, dtype=float)


@dataclass
class EffectModel:
    """The Whipple bicycle with a set of candidate effects.

    Parameters
    ----------
    values : mapping
        The benchmark parameters in :data:`BENCH_ARGS` and ``g`` (SI); values may be arrays with a
        leading batch shape.
    geometry : RiderGeometry
    effects : mapping
        Effect name to ``{parameter: value}`` for the structural effects that are on (see
        :data:`STRUCTURAL_KEYS`).  Missing parameters of an active effect raise ``InputError``.
    """

    values: Mapping[str, object]
    geometry: RiderGeometry
    effects: Mapping[str, Mapping[str, float]] = field(default_factory=dict)

    def __post_init__(self):
        missing = [k for k in BENCH_ARGS + ("g",) if k not in self.values]
        if missing:
            raise InputError(missing[0], "missing", "a value for every benchmark parameter")
        for name, params in self.effects.items():
            if name not in STRUCTURAL_KEYS:
                raise InputError("effect", name, "one of " + ", ".join(STRUCTURAL_KEYS))
            for key in STRUCTURAL_KEYS[name]:
                if key not in params:
                    raise InputError(f"{name}.{key}", "missing", "a value for every parameter of the effect")
        riders = [name for name in self.effects if EFFECTS[name].needs_rider]
        if riders and self.geometry.upper_body is None:
            raise InputError("effect", riders[0], "a model with a rider (this bicycle has no upper body to move)")

    # -- arguments of the generated functions ------------------------------------------------
    @property
    def lean(self) -> bool:
        return any(EFFECTS[name].adds_lean for name in self.effects)

    @property
    def tyre(self) -> bool:
        return any(EFFECTS[name].adds_tyres for name in self.effects)

    def _extra(self, key: str, default: float = 0.0):
        for params in self.effects.values():
            if key in params:
                return _as_float(params[key])
        return default

    def _args(self) -> dict[str, object]:
        args: dict[str, object] = {k: _as_float(self.values[k]) for k in BENCH_ARGS}
        args["g"] = _as_float(self.values["g"])
        for key in FRAME_KEYS:
            args[key] = self._extra(key)
        args.update({k: float(v) for k, v in self.geometry.grips.items()})
        return args

    def _upper(self) -> dict[str, float]:
        if self.geometry.upper_body is not None:
            return dict(self.geometry.upper_body)
        # No rider: a massless placeholder; its equation is removed with theta.
        return {"m_u": 0.0, "x_u": 0.0, "z_u": -1.0, "IUxx": 0.0, "IUxz": 0.0, "IUzz": 0.0, "z_lean": -0.5}

    # -- state space ---------------------------------------------------------------------------
    def state_space(self, speeds) -> StateSpace:
        """State-space matrices at each speed (shape ``(..., S, n, n)``).

        Inputs ``T_phi, T_delta``; outputs the states ``phi, delta, phi_dot, delta_dot``
        (:meth:`~bikerider.benchmark.state_space.StateSpace.output_states` gives their state
        indices); the states are named as in the module docstring, rates with ``_dot``.

        Raises
        ------
        InputError
            A speed that is not finite and positive (the tyre model divides by it; no model here is
            meant for standing still).
        """
        speeds = _as_float(speeds)
        if speeds.ndim != 1 or speeds.size == 0 or not np.all(np.isfinite(speeds)) or np.any(speeds <= 0):
            raise InputError("speeds", speeds.tolist(), "a one-dimensional array of finite, positive speeds [m/s]")
        args = self._args()
        if not self.lean and not self.tyre:
            A, B = gen.whipple_extended_state_matrices(**args, v=speeds)
            return StateSpace.of_states(speeds, A, B, ("phi", "delta", "phi_dot", "delta_dot"))
        lean_args = dict(args, **self._upper(), k_lean=self._extra("k_lean", 1.0), c_lean=self._extra("c_lean", 0.0))
        if not self.tyre:
            M, C, K = gen.rider_lean_matrices(**lean_args, v=speeds)
            n = 3
            Minv_K = np.linalg.solve(M, K)
            Minv_C = np.linalg.solve(M, C)
            forces = np.zeros(M.shape[:-2] + (3, 2))
            forces[..., 0, 0] = 1.0
            forces[..., 1, 1] = 1.0
            Minv_B = np.linalg.solve(M, forces)
            shape = M.shape[:-2]
            A = np.zeros(shape + (2 * n, 2 * n))
            A[..., :n, n:] = np.eye(n)
            A[..., n:, :n] = -Minv_K
            A[..., n:, n:] = -Minv_C
            B = np.zeros(shape + (2 * n, 2))
            B[..., n:, :] = Minv_B
            return StateSpace.of_states(speeds, A, B, ("phi", "delta", "theta", "phi_dot", "delta_dot", "theta_dot"))
        tyre_args = dict(lean_args, **{k: self._extra(k) for k in STRUCTURAL_KEYS[TYRE_SLIP]})
        E, Ad, Bd = gen.tyre_slip_descriptor(**tyre_args, v=speeds)
        names = gen_state_names()
        if not self.lean:
            keep = [0, 1, 3, 4, 5, 6, 8, 9]
            E = E[..., keep, :][..., :, keep]
            Ad = Ad[..., keep, :][..., :, keep]
            Bd = Bd[..., keep, :]
            names = tuple(names[k] for k in keep)
        n = Ad.shape[-1]
        AB = np.linalg.solve(E, np.concatenate([Ad, np.broadcast_to(Bd, Ad.shape[:-1] + Bd.shape[-1:])], axis=-1))
        return StateSpace.of_states(speeds, AB[..., :n], AB[..., n:], names)  # one factorisation of E for both

    # -- analyses --------------------------------------------------------------------------------
    def eigenvalues(self, speeds, gains=None) -> np.ndarray:
        """Closed-loop eigenvalues ``(..., S, n)`` at each speed (gains ``(4,)`` or ``(S, 4)``)."""
        ss = self.state_space(speeds)
        return eigenvalues_of(ss.closed_loop(gains))

    def dynamic_stiffness(self, speeds, omegas) -> np.ndarray:
        """Open-loop ``D(i omega) = G(i omega)^-1``, ``G`` from ``[T_phi, T_delta]`` to ``[phi, delta]``.

        Returns ``(..., S, F, 2, 2)``: the 2x2 dynamic stiffness the roll and steer coordinates
        show with every other degree of freedom free.  For the two-degree-of-freedom models it is
        ``M s^2 + C s + K`` at ``s = i omega``; with the leaning upper body, the Schur complement of
        that 3x3 matrix on the lean; with tyres, the inverse of the transfer function.
        """
        omegas = _as_float(omegas)
        if not self.tyre:  # second-order models: assemble M s^2 + C s + K, eliminate the lean
            speeds = _as_float(speeds)
            if speeds.ndim != 1 or speeds.size == 0 or not np.all(np.isfinite(speeds)) or np.any(speeds <= 0):
                raise InputError("speeds", speeds.tolist(), "a one-dimensional array of finite, positive speeds [m/s]")
            args = self._args()
            if self.lean:
                args = dict(args, **self._upper(), k_lean=self._extra("k_lean", 1.0), c_lean=self._extra("c_lean", 0.0))
                M, C, K = gen.rider_lean_matrices(**args, v=speeds)
            else:
                M, C, K = gen.whipple_extended_matrices(**args, v=speeds)
            s = (1j * omegas)[:, None, None]
            Z = M[..., None, :, :] * s**2 + C[..., None, :, :] * s + K[..., None, :, :]  # (..., S, F, n, n)
            if not self.lean:
                return Z
            # the upper body is free: D = Z_qq - Z_q,theta Z_theta,theta^-1 Z_theta,q
            return Z[..., :2, :2] - Z[..., :2, 2:3] @ Z[..., 2:3, :2] / Z[..., 2:3, 2:3]
        ss = self.state_space(speeds)
        n = ss.A.shape[-1]
        s = 1j * omegas[:, None, None]
        A = ss.A[..., None, :, :]
        B = ss.B[..., None, :, :]
        resolvent_B = np.linalg.solve(s * np.eye(n) - A, B.astype(complex))
        G = resolvent_B[..., list(ss.output_states[:2]), :]
        return np.linalg.inv(G)

    def simulate(
        self, speed: float, time, *, initial: Mapping[str, float] | None = None, gains=None
    ) -> dict[str, np.ndarray]:
        """Free response from an initial state (e.g. a roll-rate kick), exact for the linear model.

        Parameters
        ----------
        speed : float
        time : array_like
            Increasing sample times starting at 0 [s].
        initial : mapping, optional
            Initial values of ``phi, delta, phid, deltad`` (default ``phid = 0.5`` rad/s).
        gains : array_like, optional
            Control gains ``[k_phi, k_phid, k_delta, k_deltad]``.

        Returns
        -------
        dict
            ``time`` and ``phi, delta, phid, deltad`` at the sample times.
        """
        time = _as_float(time)
        if time.ndim != 1 or time.size < 2 or not np.all(np.isfinite(time)) or np.any(np.diff(time) <= 0):
            raise InputError("time", time[:5].tolist(), "increasing finite sample times")
        ss = self.state_space([speed])
        A = ss.closed_loop(None if gains is None else np.asarray(gains, float))[0]
        x0 = np.zeros(A.shape[0])
        for name, value in (initial or {"phid": 0.5}).items():
            if name not in OUTPUT_NAMES:
                raise InputError("initial", name, "one of " + ", ".join(OUTPUT_NAMES))
            x0[ss.output_states[OUTPUT_NAMES.index(name)]] = float(value)
        states = np.empty((time.size, x0.size))
        states[0] = x0
        x = x0
        steps: dict[float, np.ndarray] = {}
        for k in range(1, time.size):
            dt = round(float(time[k] - time[k - 1]), 12)
            if dt not in steps:
                steps[dt] = expm(A * dt)
            x = steps[dt] @ x
            states[k] = x
        out = {"time": time.copy()}
        for name, index in zip(OUTPUT_NAMES, ss.output_states):
            out[name] = states[:, index].real
        return out


def eigenvalues_of(A: np.ndarray) -> np.ndarray:
    """Eigenvalues of a batch of state matrices ``(..., n, n)``.

    Four states (every model without lean or tyres): the characteristic polynomial (Faddeev-LeVerrier)
    solved in closed form by :func:`bikerider.benchmark.quartic.quartic_roots`, several times faster
    than ``eigvals`` on small batched matrices and equal to it to about 1e-12 relative for simple
    roots; otherwise, or when a matrix is not finite, ``numpy.linalg.eigvals``.
    """
    if A.shape[-1] != 4 or not np.all(np.isfinite(A)):
        return np.linalg.eigvals(A)
    eye = np.eye(4)
    c = np.empty(A.shape[:-2] + (5,))
    c[..., 0] = 1.0
    M = np.broadcast_to(eye, A.shape)
    for k in range(1, 5):
        AM = A @ M
        c[..., k] = -np.trace(AM, axis1=-2, axis2=-1) / k
        M = AM + c[..., k, None, None] * eye
    return quartic_roots(c)


def gen_state_names() -> tuple[str, ...]:
    """State names of the generated tyre model (with lean)."""
    return ("phi", "delta", "theta", "u", "r", "phi_dot", "delta_dot", "theta_dot", "F_R", "F_F")
