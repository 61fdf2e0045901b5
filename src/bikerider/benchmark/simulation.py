"""Exact time responses of the Whipple model at fixed speeds (matrix exponential, no ODE solver).

Between two sample times ``t_k`` and ``t_k+1 = t_k + h`` the linear model with an input held
constant (zero-order hold) or varying linearly (first-order hold) has the exact solution

    x_k+1 = Phi x_k + Gamma_0 u_k + Gamma_1 (u_k+1 - u_k) / h,

with ``Phi = exp(A h)`` and ``Gamma_0``, ``Gamma_1`` the blocks of the exponential of the augmented
matrix ``[[A, B, 0], [0, 0, I], [0, 0, 0]] h`` (Van Loan's method; :func:`discretise`, the one
discretisation of the package, used by the gap's time-domain fits too, with :func:`expm`).  So the result at the sample
times is exact (to rounding) for inputs that are piecewise constant (``hold="zoh"``: sampled data
from a controller or a logger) or piecewise linear between the samples (``hold="foh"``); a smooth
input given as a function is sampled at the times and held linearly, with an error of order
``h^2`` times its curvature.  Several speeds (and a batch of bicycles) are simulated at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bikerider.benchmark.model import WhippleModel, check_speeds
from bikerider.benchmark.state_space import LateralForce, StateSpace, state_space
from bikerider.errors import InputError


@dataclass(frozen=True)
class Simulation:
    """A time response.

    Attributes
    ----------
    times : numpy.ndarray, shape (nt,)
        Sample times [s].
    speeds : numpy.ndarray, shape (n,)
        Speeds [m/s].
    states : numpy.ndarray, shape S + (n, nt, 4)
        ``[phi, delta, phi_dot, delta_dot]`` at each time (``S``: the model's batch shape): time
        before state, so ``states[k, :, 0]`` is the roll angle at speed ``k`` over time.
        python-control's ``TimeResponseData.states`` is ``(4, nt)``, state first: that is :attr:`x`.
    outputs : numpy.ndarray, shape S + (n, nt, p)
        The chosen outputs (python-control's ``(p, nt)`` layout: :attr:`y`).
    inputs : numpy.ndarray, shape (nt, m)
        The input samples used.
    system : StateSpace
        The state space simulated.
    """

    times: np.ndarray
    speeds: np.ndarray
    states: np.ndarray
    outputs: np.ndarray
    inputs: np.ndarray
    system: StateSpace

    def output(self, name: str) -> np.ndarray:
        """One output by name, ``S + (n, nt)``."""
        return self.outputs[..., self.system.outputs.index(name)]

    @property
    def t(self) -> np.ndarray:
        """The sample times [s] (python-control's name)."""
        return self.times

    @property
    def x(self) -> np.ndarray:
        """The states as python-control lays them out, state before time: ``S + (n, 4, nt)``
        (``x[k]`` at speed ``k`` is python-control's ``(4, nt)``); a view of :attr:`states`."""
        return np.swapaxes(self.states, -1, -2)

    @property
    def y(self) -> np.ndarray:
        """The outputs as python-control lays them out, output before time: ``S + (n, p, nt)``."""
        return np.swapaxes(self.outputs, -1, -2)


def _times(times) -> np.ndarray:
    t = np.asarray(times, dtype=float)
    if t.ndim != 1 or t.size < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InputError(
            "times",
            t.tolist() if t.size < 10 else f"array of shape {t.shape}",
            "at least two finite, strictly increasing times [s]",
        )
    return t


def _samples(inputs, times: np.ndarray, m: int) -> np.ndarray:
    """Input samples ``(nt, m)`` from None, a callable ``u(t)`` or an array."""
    if inputs is None:
        return np.zeros((times.size, m))
    if callable(inputs):
        rows = [np.atleast_1d(np.asarray(inputs(float(t)), dtype=float)) for t in times]
        u = np.array(rows)
    else:
        u = np.asarray(inputs, dtype=float)
        if u.ndim == 1 and m == 1:
            u = u[:, None]
    if u.shape != (times.size, m):
        raise InputError(
            "inputs",
            f"shape {u.shape}",
            f"shape ({times.size}, {m}): one value per time and input (or a function of t returning {m})",
        )
    if not np.all(np.isfinite(u)):
        raise InputError("inputs", "non-finite samples", "finite input values")
    return u


def expm(M: np.ndarray) -> np.ndarray:
    """Matrix exponential of a batch of small matrices ``(..., n, n)``, vectorised over the batch.

    Scaling and squaring: each matrix is scaled by a power of two to a 1-norm of at most 1/2, the
    Taylor series is summed to degree 14 (truncation below 1e-16 relative), and the result squared
    back.  (``scipy.linalg.expm`` loops over a batch in Python, far slower for the thousands of
    4x4 to 11x11 matrices of the gap's time-domain fits.)
    """
    M = np.asarray(M, dtype=float)
    n = M.shape[-1]
    norm = np.max(np.sum(np.abs(M), axis=-2), axis=-1)
    s = np.ceil(np.log2(np.maximum(norm, 1e-300) / 0.5)).clip(0, None).astype(int)
    X = M / (2.0**s)[..., None, None]
    eye = np.eye(n)
    E = eye + X / 14.0
    for k in range(13, 0, -1):
        E = eye + (X @ E) / k
    for k in range(int(s.max()) if s.size else 0):
        E = np.where((k < s)[..., None, None], E @ E, E)
    return E


def discretise(
    A: np.ndarray, B: np.ndarray, h: float | np.ndarray, hold: str = "foh"
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """``Phi, Gamma_0, Gamma_1`` for steps ``h`` (see the module docstring); batched over ``A``, ``B``.

    Parameters
    ----------
    A, B : numpy.ndarray
        Shapes ``(..., n, n)`` and ``(..., n, m)``.
    h : float or numpy.ndarray
        The step [s], broadcast against the batch.
    hold : {"foh", "zoh"}
        ``"zoh"`` when only ``Phi`` and ``Gamma_0`` are needed (an input held constant over the
        step): the exponential of the smaller matrix ``[[A, B], [0, 0]] h``, ``Gamma_1`` ``None``.
    """
    n, m = A.shape[-1], B.shape[-1]
    size = n + (2 * m if hold == "foh" else m)
    shape = np.broadcast_shapes(A.shape[:-2], B.shape[:-2], np.shape(h))
    big = np.zeros(shape + (size, size))
    big[..., :n, :n] = A
    big[..., :n, n : n + m] = B
    if hold == "foh":
        big[..., n : n + m, n + m :] = np.eye(m)
    E = expm(big * np.asarray(h, dtype=float)[..., None, None])
    return E[..., :n, :n], E[..., :n, n : n + m], (E[..., :n, n + m :] if hold == "foh" else None)


def simulate(
    model: WhippleModel,
    speeds,
    times,
    initial_state=None,
    inputs=None,
    input_names=("T_phi", "T_delta"),
    outputs=("phi", "delta", "phi_dot", "delta_dot"),
    lateral_force: LateralForce | None = None,
    hold: str | None = None,
) -> Simulation:
    """Time response of ``model`` at each of ``speeds`` (held constant), exact at the sample times.

    Parameters
    ----------
    model : WhippleModel
        One bicycle or a batch.
    speeds : array_like, shape (n,)
        Speeds [m/s]; every one is simulated.
    times : array_like, shape (nt,)
        Increasing sample times [s], starting at the time of the initial state.
    initial_state : array_like, shape (4,) or broadcastable to S + (n, 4), optional
        ``[phi, delta, phi_dot, delta_dot]`` at ``times[0]`` (rad, rad/s); zero by default.
    inputs : None, callable or array_like, optional
        ``None`` (no input), a function ``u(t)`` returning one value per input, or samples of
        shape ``(nt, m)`` (``(nt,)`` for one input).
    input_names : sequence of str
        The inputs, from ``T_phi``, ``T_delta``, ``F`` (:mod:`bikerider.benchmark.state_space`).
    outputs : sequence of str
        Outputs to return besides the states.
    lateral_force : LateralForce, optional
        Where ``F`` acts (needed when ``F`` is an input).
    hold : {"zoh", "foh"}, optional
        How the input varies between samples: held constant (the default for samples) or linear
        (the default for a function).

    Returns
    -------
    Simulation
    """
    t = _times(times)
    v = check_speeds(speeds)
    system = state_space(model, v, input_names, outputs, lateral_force)
    hold = hold or ("foh" if callable(inputs) else "zoh")
    if hold not in ("zoh", "foh"):
        raise InputError("hold", hold, 'either "zoh" (piecewise constant input) or "foh" (piecewise linear)')
    u = _samples(inputs, t, len(system.inputs))
    lead = system.A.shape[:-2]
    x = np.broadcast_to(
        np.zeros(4) if initial_state is None else np.asarray(initial_state, dtype=float), lead + (4,)
    ).copy()
    if not np.all(np.isfinite(x)):
        raise InputError("initial_state", np.asarray(initial_state).tolist(), "finite [phi, delta, phi_dot, delta_dot]")
    steps = np.diff(t)
    uniform = np.allclose(steps, steps[0], rtol=1e-12, atol=0)
    if uniform:
        Phi, G0, G1 = discretise(system.A, system.B, steps[0])
    else:  # one exponential per step: (..., nt-1, n, n)
        Phi, G0, G1 = discretise(system.A[..., None, :, :], system.B[..., None, :, :], steps)
    states = np.empty(lead + (t.size, 4))
    states[..., 0, :] = x
    for k in range(t.size - 1):
        P, Q0, Q1 = (Phi, G0, G1) if uniform else (Phi[..., k, :, :], G0[..., k, :, :], G1[..., k, :, :])
        step = Q0 @ u[k] + (Q1 @ ((u[k + 1] - u[k]) / steps[k]) if hold == "foh" else 0.0)
        x = np.einsum("...ij,...j->...i", P, x) + step
        states[..., k + 1, :] = x
    y = np.einsum("...ij,...tj->...ti", system.C, states) + np.einsum("...ij,tj->...ti", system.D, u)
    return Simulation(t, v, states, y, u, system)


__all__ = ["Simulation", "discretise", "expm", "simulate"]
