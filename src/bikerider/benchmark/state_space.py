"""State space ``x' = A(v) x + B u``, ``y = C x + D u`` of the Whipple model, for any speeds and batch.

States ``x = [phi, delta, phi_dot, delta_dot]`` (roll, steer and their rates; rad, rad/s).

Inputs (choose any, in any order):

``T_phi``
    roll torque on the rear frame [N m];
``T_delta``
    steer torque between rear and front frame [N m];
``F``
    lateral force [N], horizontal and perpendicular to the heading, positive to the right (+y of
    the benchmark frame), at a point of the rear frame (or of the front frame) given by a
    :class:`LateralForce`.  It enters the canonical equations as ``H F`` with
    ``H = [H_phiF, H_deltaF]`` (``derive/state_space.py``); for the rear frame
    ``H = [-z_F, c x_F cos(lam) / w]``.

Outputs (any of): the states by name, and the accelerations ``phi_ddot``, ``delta_ddot`` (rows of
``A`` and ``B``, so ``D`` is not zero for them).

Shapes.  For speeds of shape ``V`` and a model of batch shape ``S`` (``()`` for one bicycle),
``A`` is ``S + V + (4, 4)``, ``B`` is ``S + V + (4, m)`` (``B`` does not depend on the speed; it is
broadcast, read-only), ``C`` is ``(p, 4)`` (``S + V + (p, 4)`` when an acceleration is an output)
and ``D`` is ``S + V + (p, m)``.

Models with more states.  :class:`StateSpace` holds any number ``n`` of named states: the gap's
models (:meth:`bikerider.gap.candidates.effect_model.EffectModel.state_space`, the Whipple bicycle
with a leaning upper body or tyre slip) build theirs with :meth:`StateSpace.of_states`, whose
outputs are states picked by name.  :meth:`StateSpace.closed_loop` closes the steer-torque loop of
any of them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bikerider.benchmark.closed_loop import closed_loop_matrix
from bikerider.benchmark.model import WhippleModel
from bikerider.engine import arguments
from bikerider.errors import InputError
from bikerider.generated import state_space as gen
from bikerider.generated.manifest import LATERAL_FORCE_GEOMETRY, STATE_SPACE_INPUTS

STATES = ("phi", "delta", "phi_dot", "delta_dot")
"""State names, in order."""
INPUTS = STATE_SPACE_INPUTS
"""Input names (columns of the full input matrix), in order."""
OUTPUTS = STATES + ("phi_ddot", "delta_ddot")
"""Output names that :func:`state_space` accepts."""
UNITS = {
    "phi": "rad",
    "delta": "rad",
    "phi_dot": "rad/s",
    "delta_dot": "rad/s",
    "phi_ddot": "rad/s^2",
    "delta_ddot": "rad/s^2",
    "T_phi": "N m",
    "T_delta": "N m",
    "F": "N",
}
LABELS = {
    "phi": "roll angle",
    "delta": "steer angle",
    "phi_dot": "roll rate",
    "delta_dot": "steer rate",
    "phi_ddot": "roll acceleration",
    "delta_ddot": "steer acceleration",
    "T_phi": "roll torque",
    "T_delta": "steer torque",
    "F": "lateral force",
}


@dataclass(frozen=True)
class LateralForce:
    """Where a lateral force acts.

    Attributes
    ----------
    x, z : float or array_like
        The point in the benchmark frame in the reference configuration [m] (origin at the rear
        contact, x forward, z down: a point 0.9 m above the ground has ``z = -0.9``).  Arrays
        broadcast against the model's batch shape.
    body : {"rear", "front"}
        The rigid body the point belongs to: the rear frame with the rider, or the handlebar and
        fork.
    """

    x: float
    z: float
    body: str = "rear"

    def vector(self, w, c, lam) -> np.ndarray:
        """``H = [H_phiF, H_deltaF]`` (shape ``(..., 2)``) for a bicycle of wheelbase ``w``, trail
        ``c`` and steer axis tilt ``lam``."""
        if self.body not in ("rear", "front"):
            raise InputError("body", self.body, 'either "rear" or "front"')
        x, z = np.asarray(self.x, dtype=float), np.asarray(self.z, dtype=float)
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(z))):
            raise InputError("lateral force point", [x.tolist(), z.tolist()], "finite coordinates x, z [m]")
        rear, front = gen.lateral_force_input(w=w, c=c, lam=lam, x_F=x, z_F=z)
        return rear if self.body == "rear" else front


def lateral_force_vector(model: WhippleModel, force: LateralForce) -> np.ndarray:
    """``H`` of ``force`` on ``model`` (which needs its geometry, set by ``from_parameters``)."""
    if model.geometry is None:
        raise InputError(
            "lateral force",
            f"({force.x}, {force.z})",
            "a model built with WhippleModel.from_parameters (a lateral force needs the wheelbase, "
            "trail and steer axis tilt), or model.geometry = {'w': ..., 'c': ..., 'lam': ...}",
            model.source,
        )
    return force.vector(*(model.geometry[k] for k in LATERAL_FORCE_GEOMETRY))


def input_matrix(model: WhippleModel, force: LateralForce | None = None) -> np.ndarray:
    """The full input matrix ``batch_shape + (4, 3)`` for ``u = [T_phi, T_delta, F]``.

    Without ``force`` the ``F`` column is NaN (there is no point for the force to act at).
    """
    entries = model.entries()
    if force is None:
        h = np.full(model.batch_shape + (2,), np.nan)
    else:
        h = np.broadcast_to(lateral_force_vector(model, force), model.batch_shape + (2,))
    return gen.input_matrix(
        **{k: entries[k] for k in arguments("state_space.input_matrix") if k in entries},
        H_phiF=h[..., 0],
        H_deltaF=h[..., 1],
    )


def _names(kind: str, names, allowed: tuple[str, ...]) -> tuple[str, ...]:
    names = (names,) if isinstance(names, str) else tuple(names)
    for name in names:
        if name not in allowed:
            raise InputError(kind, name, f"one of {', '.join(allowed)}")
    if not names or len(set(names)) != len(names):
        raise InputError(kind, list(names), f"one or more distinct names from {', '.join(allowed)}")
    return names


@dataclass(frozen=True)
class StateSpace:
    """``x' = A x + B u``, ``y = C x + D u`` at each speed (and bicycle of a batch).

    Attributes
    ----------
    speeds : numpy.ndarray
        Speeds [m/s], shape ``V``.
    A, B, C, D : numpy.ndarray
        Shapes ``S + V + (n, n)``, ``S + V + (n, m)``, ``(p, n)`` (or ``S + V + (p, n)`` with an
        acceleration output) and ``S + V + (p, m)``; ``n = 4`` for the Whipple model.
    states, inputs, outputs : tuple of str
        Names (see the module docstring).
    """

    speeds: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]

    @classmethod
    def of_states(
        cls,
        speeds,
        A: np.ndarray,
        B: np.ndarray,
        states: tuple[str, ...],
        inputs: tuple[str, ...] = ("T_phi", "T_delta"),
        outputs: tuple[str, ...] = ("phi", "delta", "phi_dot", "delta_dot"),
    ) -> StateSpace:
        """A state space whose outputs are some of its states, picked by name (``D = 0``).

        Parameters
        ----------
        speeds : array_like
            Speeds [m/s], shape ``V``.
        A, B : numpy.ndarray
            Shapes ``S + V + (n, n)`` and ``S + V + (n, m)``.
        states, inputs, outputs : tuple of str
            ``n`` state names, ``m`` input names and the states that are outputs.
        """
        states = tuple(states)
        C = np.zeros((len(outputs), len(states)))
        for k, index in enumerate(_state_index(states, outputs, "outputs")):
            C[k, index] = 1.0
        D = np.broadcast_to(np.zeros((len(outputs), len(inputs))), A.shape[:-2] + (len(outputs), len(inputs)))
        return cls(np.asarray(speeds, dtype=float), A, B, C, D, states, tuple(inputs), tuple(outputs))

    @property
    def output_states(self) -> tuple[int, ...]:
        """The state index of each output (every output must be a state)."""
        return _state_index(self.states, self.outputs, "outputs")

    def closed_loop(self, gains) -> np.ndarray:
        """The state matrix under the steer torque ``T_delta = k_phi phi + k_phid phi_dot + k_delta
        delta + k_deltad delta_dot``.

        Parameters
        ----------
        gains : array_like or None
            ``[k_phi, k_phid, k_delta, k_deltad]``, shape ``(4,)`` or broadcast against the leading
            ``S + V`` dimensions; ``None`` (or all zero) for the open loop.

        Returns
        -------
        numpy.ndarray
            ``A + b k^T`` (``b`` the ``T_delta`` column of ``B``), shape ``S + V + (n, n)``; ``A``
            itself for the open loop.
        """
        if gains is None:
            return self.A
        gains = np.asarray(gains, dtype=float)
        if not np.any(gains):
            return self.A
        if "T_delta" not in self.inputs:
            raise InputError("inputs", list(self.inputs), "T_delta among the inputs to close the steer loop")
        index = _state_index(self.states, GAIN_STATES, "gains")
        return closed_loop_matrix(self.A, self.B[..., :, self.inputs.index("T_delta")], gains, index)

    def to_control(self, index=()):
        """One system as a python-control ``StateSpace`` with named signals (``pip install
        bikerider[control]``), named by :func:`control_name` of its speed.

        Parameters
        ----------
        index : int or tuple of int
            Which system: an index into the leading ``S + V`` dimensions (a speed, or a bicycle and a
            speed of a batch); ``()`` when there is only one.
        """
        try:
            import control
        except ImportError:
            raise InputError(
                "python-control",
                "not installed",
                "pip install 'bikerider[control]' (or pip install control) for to_control()",
            ) from None
        index = (index,) if isinstance(index, (int, np.integer)) else tuple(index)
        A = self.A[index]
        if A.ndim != 2:
            raise InputError("index", index, f"an index to one system of the leading shape {self.A.shape[:-2]}")
        v = float(np.broadcast_to(self.speeds, self.A.shape[:-2])[index])
        C = self.C if self.C.ndim == 2 else self.C[index]
        return control.ss(
            A,
            self.B[index],
            C,
            self.D[index],
            states=list(self.states),
            inputs=list(self.inputs),
            outputs=list(self.outputs),
            name=control_name(v),
        )


GAIN_STATES = ("phi", "phi_dot", "delta", "delta_dot")
"""The state each gain of :data:`bikerider.benchmark.control.GAIN_NAMES` multiplies."""


def _state_index(states: tuple[str, ...], names, kind: str) -> tuple[int, ...]:
    """The index of each of ``names`` among ``states`` (``InputError`` naming ``kind`` if one is not a state)."""
    for name in names:
        if name not in states:
            raise InputError(kind, name, f"a state ({', '.join(states)})")
    return tuple(states.index(name) for name in names)


def control_name(speed: float) -> str:
    """The python-control system name at ``speed``: ``whipple_v5_5`` for 5.5 m/s (python-control
    allows no ``.`` in a name), ``whipple_vm1_5`` for -1.5 m/s."""
    return "whipple_v" + f"{speed:g}".replace(".", "_").replace("-", "m").replace("+", "")


def state_space(
    model: WhippleModel,
    speeds,
    inputs=("T_phi", "T_delta"),
    outputs=("phi", "delta"),
    lateral_force: LateralForce | None = None,
) -> StateSpace:
    """The state space of ``model`` at ``speeds``.

    Parameters
    ----------
    model : WhippleModel
        One bicycle or a batch.
    speeds : array_like
        Speeds [m/s], any shape ``V``.
    inputs, outputs : sequence of str
        Names from :data:`INPUTS` and :data:`OUTPUTS`.
    lateral_force : LateralForce, optional
        Where the force ``F`` acts; needed when ``"F"`` is an input.

    Returns
    -------
    StateSpace

    Raises
    ------
    InputError
        An unknown input or output name, ``"F"`` without a point or without the model's geometry,
        or speeds that are not finite.
    """
    inputs = _names("inputs", inputs, INPUTS)
    outputs = _names("outputs", outputs, OUTPUTS)
    v = np.asarray(speeds, dtype=float)
    if not np.all(np.isfinite(v)):
        raise InputError("speeds", v.tolist(), "finite speeds [m/s]")
    if "F" in inputs and lateral_force is None:
        raise InputError("lateral_force", None, "a LateralForce(x, z, body) giving where the input F acts")
    A = model.state_matrix(v)
    full = input_matrix(model, lateral_force if "F" in inputs else None)
    columns = [INPUTS.index(name) for name in inputs]
    pad = (...,) + (None,) * v.ndim + (slice(None), slice(None))
    B = np.broadcast_to(full[..., columns][pad], A.shape[:-2] + (4, len(columns)))
    rows = [OUTPUTS.index(name) for name in outputs]
    C = np.zeros((len(rows), 4))
    D = np.zeros(A.shape[:-2] + (len(rows), len(columns)))
    for k, row in enumerate(rows):
        if row < 4:
            C[k, row] = 1.0
        else:  # an acceleration: the row of A and B
            D[..., k, :] = B[..., row - 2, :]
    if any(row >= 4 for row in rows):
        C = np.broadcast_to(C, A.shape[:-2] + C.shape).copy()
        for k, row in enumerate(rows):
            if row >= 4:
                C[..., k, :] = A[..., row - 2, :]
    return StateSpace(v, A, B, C, D, STATES, inputs, outputs)


__all__ = [
    "INPUTS",
    "OUTPUTS",
    "STATES",
    "LateralForce",
    "StateSpace",
    "input_matrix",
    "lateral_force_vector",
    "state_space",
]
