"""Frequency responses (Bode) of the Whipple model: ``G(i w) = C (i w I - A)^-1 B + D``.

For every speed (and bicycle of a batch) and frequency the complex response is found by solving
``(i w I - A) X = B`` (no explicit inverse).  The default inputs and outputs are those of lateral
perturbation experiments (Moore 2012): steer torque and a lateral force to roll and steer angle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bikerider.benchmark.model import WhippleModel, check_speeds
from bikerider.benchmark.state_space import LateralForce, StateSpace, state_space
from bikerider.errors import InputError


@dataclass(frozen=True)
class FrequencyResponse:
    """Complex frequency responses.

    Attributes
    ----------
    frequencies : numpy.ndarray, shape (nf,)
        Angular frequencies [rad/s].
    speeds : numpy.ndarray, shape (n,)
        Speeds [m/s].
    response : numpy.ndarray, shape S + (n, nf, p, m)
        ``G(i w)`` from each input (last axis) to each output, frequency first.  python-control's
        ``FrequencyResponseData`` puts frequency last, ``(p, m, nf)``, with ``magnitude`` the
        absolute value ``|G|`` (not dB) and ``phase`` in radians: :attr:`magnitude`,
        :attr:`phase` and :attr:`omega` here are the same; :meth:`magnitude_db` and
        :meth:`phase_deg` are for Bode diagrams.
    system : StateSpace
        The state space evaluated (names of inputs and outputs).
    """

    frequencies: np.ndarray
    speeds: np.ndarray
    response: np.ndarray
    system: StateSpace

    def select(self, output: str, input: str) -> np.ndarray:
        """``G`` from ``input`` to ``output``, ``S + (n, nf)``."""
        return self.response[..., self.system.outputs.index(output), self.system.inputs.index(input)]

    @property
    def omega(self) -> np.ndarray:
        """Angular frequencies [rad/s] (python-control's name)."""
        return self.frequencies

    @property
    def magnitude(self) -> np.ndarray:
        """``|G|``, absolute (not dB; the response's unit: rad per N m, ...), in python-control's
        layout, frequency last: ``S + (n, p, m, nf)``."""
        return np.moveaxis(np.abs(self.response), -3, -1)

    @property
    def phase(self) -> np.ndarray:
        """``arg G`` [rad], unwrapped along frequency, python-control's layout ``S + (n, p, m, nf)``
        (``phase_deg`` also brings the lowest frequency into (-180, 180] degrees)."""
        return np.unwrap(np.moveaxis(np.angle(self.response), -3, -1), axis=-1)

    def magnitude_db(self, output: str, input: str) -> np.ndarray:
        """``20 log10 |G|`` [dB] (of the response's unit: rad per N m, rad per N, ...)."""
        with np.errstate(divide="ignore"):
            return 20 * np.log10(np.abs(self.select(output, input)))

    def phase_deg(self, output: str, input: str) -> np.ndarray:
        """Phase [deg], unwrapped along frequency and starting in (-180, 180] at the lowest one."""
        phase = np.degrees(np.unwrap(np.angle(self.select(output, input)), axis=-1))
        return phase - 360.0 * np.round((phase[..., :1] - 1e-9) / 360.0)


def frequency_response(
    model: WhippleModel,
    speeds,
    frequencies,
    inputs=("T_delta", "F"),
    outputs=("phi", "delta"),
    lateral_force: LateralForce | None = None,
) -> FrequencyResponse:
    """``C (i w I - A)^-1 B + D`` of ``model`` at every speed and angular frequency.

    Parameters
    ----------
    model : WhippleModel
        One bicycle or a batch.
    speeds : array_like, shape (n,)
        Speeds [m/s].
    frequencies : array_like, shape (nf,)
        Angular frequencies [rad/s], positive (e.g. ``numpy.logspace(-1, 2, 200)``).
    inputs, outputs : sequence of str
        Names (:mod:`bikerider.benchmark.state_space`).
    lateral_force : LateralForce, optional
        Where ``F`` acts (needed when ``F`` is an input).

    Returns
    -------
    FrequencyResponse
    """
    v = check_speeds(speeds)
    w = np.atleast_1d(np.asarray(frequencies, dtype=float))
    if w.ndim != 1 or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise InputError(
            "frequencies",
            w.tolist() if w.size < 10 else f"array of shape {w.shape}",
            "a one-dimensional array of finite, non-negative angular frequencies [rad/s]",
        )
    system = state_space(model, v, inputs, outputs, lateral_force)
    A = system.A[..., None, :, :]  # S + (n, 1, 4, 4)
    resolvent = 1j * w[:, None, None] * np.eye(4) - A  # S + (n, nf, 4, 4)
    B = np.broadcast_to(system.B[..., None, :, :], resolvent.shape[:-1] + (system.B.shape[-1],))
    X = np.linalg.solve(resolvent, B)
    C = system.C if system.C.ndim == 2 else system.C[..., None, :, :]
    G = C @ X + system.D[..., None, :, :]
    return FrequencyResponse(w, v, G, system)


__all__ = ["FrequencyResponse", "frequency_response"]
