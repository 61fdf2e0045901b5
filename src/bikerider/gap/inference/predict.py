"""Predict every measured scalar from a model: eigenvalues by mode, identified canonical entries.

Eigenvalues.  A measured eigenvalue of mode ``weave``, ``capsize`` or ``castor`` is compared with
the model eigenvalue nearest to the reference eigenvalue of that mode, the reference being the
nominal Whipple model under the same control, labelled as in :mod:`bikerider.benchmark.model`.
An added degree of freedom brings extra eigenvalues (lean, tyre modes); matching against the
reference keeps the comparison on the mode that continues the Whipple one.  A weave observation
gives two scalars (real and imaginary part), a real mode one.

Identified canonical entries.  An identification of the canonical form ``M q'' + v C1 q' + (g K0
+ v^2 K2) q = f`` from data sees, for any model, the 2x2 dynamic stiffness between the roll and
steer coordinates and torques with every other degree of freedom free, ``D(i omega, v)``.  The
prediction of what it identifies is the least-squares fit of the identified (free) entries to
``D`` over the subset's speed range (:data:`N_SPEEDS` speeds) and :data:`OMEGAS`, every other
entry fixed at its nominal Whipple value and ``M`` and ``K0`` symmetric, as in Moore (2012).  The
roll and steer equations are each weighted by the inverse RMS size of the nominal model's row, so
both count.  For a two-degree-of-freedom model the fit is exact at every frequency; for a model
with more freedom it is an approximation of an identification with inputs spread evenly over the
band (the real experiments' input spectra are not known here).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bikerider.benchmark.model import label_modes
from bikerider.gap.candidates.effect_model import BENCH_ARGS, EffectModel, RiderGeometry
from bikerider.gap.inference.frequency_response import predict_frf  # multisine records
from bikerider.gap.measured.multisine import FrequencyResponseData
from bikerider.gap.measured.tables import CANONICAL_ENTRIES, CanonicalData, EigenvalueData
from bikerider.generated import benchmark_model as bm

N_SPEEDS = 5
"""Speeds spanning each identified subset's range."""
OMEGAS = np.linspace(2 * np.pi * 0.2, 2 * np.pi * 2.0, 12)
"""Angular frequencies of the identification band [rad/s] (0.2-2 Hz: the weave and rider-control band)."""
_MODE_INDEX = {"weave": 0, "capsize": 2, "castor": 3}
_PENALTY = 1e6
MAX_EIGEN_CONDITION = 1e6
"""Largest condition ``|w| |v|`` (left and right eigenvectors, ``w^T v = 1``) of a matched eigenvalue
whose derivative :meth:`Predictor.eigen_derivatives` takes to first order (beyond it, near a double
root, the eigenvalues are differenced instead)."""


@dataclass
class Observations:
    """The measured scalars, flattened: eigenvalue parts first, then canonical entries.

    Attributes
    ----------
    kind : list of str
        ``eigenvalue`` or ``canonical``.
    mode : list of str
        ``weave``, ``capsize``, ``castor`` or ``canonical``.
    quantity : list of str
        ``real`` or ``imag`` for eigenvalues, the entry name for canonical entries.
    speed : ndarray
        Speed [m/s] (the middle of the subset's range for canonical entries).
    group : list of str
    value, sigma : ndarray
        Measured value and its standard uncertainty (NaN where unknown).
    source : list of str
    """

    kind: list[str]
    mode: list[str]
    quantity: list[str]
    speed: np.ndarray
    group: list[str]
    value: np.ndarray
    sigma: np.ndarray
    source: list[str]

    def __len__(self) -> int:
        return int(self.value.size)


class Predictor:
    """Predictions of :class:`Observations` for any :class:`EffectModel` built on the same bicycle.

    Parameters
    ----------
    eigen : EigenvalueData
    canonical : CanonicalData
    nominal : dict
        Nominal benchmark values (23 canonical arguments and ``g``).
    geometry : RiderGeometry
    """

    def __init__(
        self,
        eigen: EigenvalueData,
        canonical: CanonicalData,
        nominal: dict[str, float],
        geometry: RiderGeometry,
        frf: FrequencyResponseData | None = None,
    ):
        self.eigen, self.canonical, self.nominal, self.geometry = eigen, canonical, dict(nominal), geometry
        self.frf = frf if frf is not None else FrequencyResponseData.empty()  # multisine records, after the rest
        self._reference = None
        if len(eigen):
            ref = EffectModel(self.nominal, geometry).eigenvalues(eigen.speed, eigen.gains)
            self._reference, _ = label_modes(ref)
            eigen.mode = [self._resolve(m, k) for k, m in enumerate(eigen.mode)]
        self._groups = sorted(set(canonical.group))
        self._canonical_maps = {g: self._canonical_map(g) for g in self._groups}
        self.observations = self._flatten()

    # -- setup ----------------------------------------------------------------------------------
    def _resolve(self, mode: str, k: int) -> str:
        if mode != "auto":
            return mode
        value = self.eigen.value[k]
        ref = self._reference[k]
        return "capsize" if abs(value - ref[2]) <= abs(value - ref[3]) else "castor"

    def _flatten(self) -> Observations:
        kind, mode, quantity, speed, group, value, sigma, source = [], [], [], [], [], [], [], []
        e = self.eigen
        for k in range(len(e)):
            parts = [("real", e.value[k].real, e.real_sigma[k])]
            if e.mode[k] == "weave":
                parts.append(("imag", e.value[k].imag, e.imag_sigma[k]))
            for q, val, sig in parts:
                kind.append("eigenvalue"), mode.append(e.mode[k]), quantity.append(q)
                speed.append(e.speed[k]), group.append(e.group[k]), value.append(val), sigma.append(sig)
                source.append(e.source[k])
        c = self.canonical
        for k in range(len(c)):
            lo, hi = c.speed_range[c.group[k]]
            kind.append("canonical"), mode.append("canonical"), quantity.append(c.entry[k])
            speed.append(0.5 * (lo + hi)), group.append(c.group[k]), value.append(c.value[k])
            sigma.append(c.sigma[k]), source.append(c.source[k])
        f = self.frf  # multisine records: real and imaginary part of each line's response
        for k in range(len(f)):
            for q, val in (("real", f.value[k].real), ("imag", f.value[k].imag)):
                kind.append("frf"), mode.append(f"frf_{f.signal[k]}"), quantity.append(q)
                speed.append(f.speed[k]), group.append(f.group[k]), value.append(val)
                sigma.append(f.sigma[k]), source.append(f.source[k])
        return Observations(
            kind, mode, quantity, np.array(speed, float), group, np.array(value, float), np.array(sigma, float), source
        )

    def _canonical_map(self, group: str) -> dict:
        """Linear map from the dynamic stiffness over the group's band to its identified entries."""
        lo, hi = self.canonical.speed_range[group]
        speeds = np.linspace(lo, hi, N_SPEEDS)
        entries = [
            e
            for e in CANONICAL_ENTRIES
            if any(en == e and g == group for en, g in zip(self.canonical.entry, self.canonical.group))
        ]
        g = self.nominal["g"]
        s = 1j * OMEGAS
        V, S = np.meshgrid(speeds, s, indexing="ij")  # (N, F)
        # positions (row, col) in D and the basis of each free entry there
        basis = {
            "M_phidelta": {(0, 1): S**2, (1, 0): S**2},
            "C1_phidelta": {(0, 1): V * S},
            "K0_phidelta": {(0, 1): g + 0 * S, (1, 0): g + 0 * S},
            "M_deltadelta": {(1, 1): S**2},
            "C1_deltaphi": {(1, 0): V * S},
            "C1_deltadelta": {(1, 1): V * S},
            "K0_deltadelta": {(1, 1): g + 0 * S},
            "K2_deltadelta": {(1, 1): V**2 + 0 * S},
        }
        positions = [(0, 1), (1, 0), (1, 1)]
        nominal_D = EffectModel(self.nominal, self.geometry).dynamic_stiffness(speeds, OMEGAS)  # (N, F, 2, 2)
        weights = {
            0: 1 / np.sqrt(np.mean(np.abs(nominal_D[..., 0, :]) ** 2)),
            1: 1 / np.sqrt(np.mean(np.abs(nominal_D[..., 1, :]) ** 2)),
        }
        columns = []
        for entry in entries:
            col = []
            for pos in positions:
                col.append(weights[pos[0]] * basis[entry].get(pos, 0 * S).ravel())
            columns.append(np.concatenate(col))
        design = np.array(columns).T  # (3 N F, m) complex
        design_real = np.concatenate([design.real, design.imag])
        pinv = np.linalg.pinv(design_real)  # (m, 6 N F)
        row_weights = np.array([weights[p[0]] for p in positions])
        nominal_entries = _nominal_entries(self.nominal, entries)
        return {
            "speeds": speeds,
            "entries": entries,
            "pinv": pinv,
            "positions": positions,
            "row_weights": row_weights,
            "nominal_D": nominal_D,
            "nominal_entries": nominal_entries,
        }

    # -- prediction ------------------------------------------------------------------------------
    def predict(self, model: EffectModel, speed_scale=None) -> np.ndarray:
        """Predicted value of every observation, shape ``(..., n_obs)`` (batch of the model's values).

        ``speed_scale`` (a number or one per eigenvalue row) multiplies the speed the bicycle ran
        at; the control gains stay those of the rows (the controller's own speed).
        """
        parts = []
        if len(self.eigen):
            parts.append(self._predict_eigen(model, speed_scale))
        if len(self.canonical):
            parts.append(self._predict_canonical(model))
        if len(self.frf):  # multisine records; the speed scale of eigenvalue rows is not theirs
            parts.append(predict_frf(model, self.frf))
        if len(parts) > 1:
            lead = np.broadcast_shapes(*(p.shape[:-1] for p in parts))
            parts = [np.broadcast_to(p, lead + p.shape[-1:]) for p in parts]
        return np.concatenate(parts, axis=-1)

    def predict_scaled(self, flat_model: EffectModel, scales: np.ndarray) -> np.ndarray:
        """Eigenvalue predictions ``(P, n_obs_eigen)`` for ``P`` speed scales in one model call.

        A scale multiplies the speed of the rows a sensor read (``eigen.speed_sensor``) only.

        ``flat_model`` holds, for every (scale, row) pair in that order, one value of each
        parameter (shape ``(P * n_rows,)``).
        """
        P, S = scales.size, len(self.eigen)
        per_row = np.where(self.eigen.speed_sensor[None, :], scales[:, None], 1.0)  # only the sensor's readings
        speeds = (per_row * self.eigen.speed[None, :]).ravel()
        ev = flat_model.eigenvalues(speeds, np.tile(self.eigen.gains, (P, 1))).reshape(P, S, -1)
        return self._stack_eigen(self._match(ev))

    def eigenvalues(self, model: EffectModel, speed_scale=None) -> np.ndarray:
        """Matched model eigenvalue for each eigenvalue row, ``(..., n_rows)`` complex."""
        speeds = self.eigen.speed if speed_scale is None else self.eigen.speed * np.asarray(speed_scale, dtype=float)
        return self._match(model.eigenvalues(speeds, self.eigen.gains))  # (..., S, n)

    def eigen_derivatives(self, model: EffectModel, steps: np.ndarray) -> np.ndarray | None:
        """Derivatives ``(p, n_obs_eigen)`` of the eigenvalue observations in ``p`` parameters, by
        first-order perturbation of each row's matched eigenvalue, or ``None`` where that does not hold.

        ``model`` holds ``1 + p`` models: the point, then the point with one parameter moved by its
        step (``steps``, ``(p,)``, signed).  The state matrices are differenced (forward, as the fits'
        Jacobians are), the eigenvalue's derivative taken from its left and right eigenvectors at the
        point, ``d lambda = w^T dA v`` with ``w^T v = 1``: one eigendecomposition per row instead of
        one per row and parameter.  ``None`` (the caller then differences the eigenvalues themselves)
        when a matrix is not finite, a row's matched eigenvalue is not an allowed one (no weave where
        one is measured), or it is ill-conditioned (``|w| |v|`` above :data:`MAX_EIGEN_CONDITION`:
        near a double root, where a first-order derivative says little).
        """
        A = model.state_space(self.eigen.speed).closed_loop(self.eigen.gains)  # (1 + p, S, n, n)
        if A.ndim != 4 or A.shape[0] != steps.size + 1 or not np.all(np.isfinite(A)):
            return None
        try:
            lam, V = np.linalg.eig(A[0])
            W = np.linalg.inv(V)  # its rows: the left eigenvectors, scaled to w^T v = 1
        except np.linalg.LinAlgError:
            return None
        pick, allowed = self._match_index(lam)
        rows = np.arange(lam.shape[0])
        v, w = V[rows, :, pick], W[rows, pick, :]  # (S, n)
        condition = np.linalg.norm(v, axis=-1) * np.linalg.norm(w, axis=-1)
        if not np.all(allowed) or not np.all(condition <= MAX_EIGEN_CONDITION):
            return None
        dA = (A[1:] - A[0]) / steps[:, None, None, None]
        dlam = np.einsum("si,psij,sj->ps", w, dA, v)  # (p, S)
        # the observation is the matched eigenvalue with its imaginary part made positive (:meth:`_match`)
        sign = np.where(lam[rows, pick].imag < 0, -1.0, 1.0)
        out = self._stack_eigen(dlam.real + 1j * sign * dlam.imag)
        return out if np.all(np.isfinite(out)) else None

    def _match(self, ev: np.ndarray) -> np.ndarray:
        """The eigenvalue of each row's mode among a model's eigenvalues ``(..., S, n)``."""
        pick, _ = self._match_index(ev)
        matched = np.take_along_axis(ev, pick[..., None], axis=-1)[..., 0]
        return matched.real + 1j * np.abs(matched.imag)

    def _match_index(self, ev: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position of each row's mode among a model's eigenvalues ``(..., S, n)``, and whether it is an
        allowed one (in the upper half plane, oscillating where the row is a weave)."""
        ref, want_complex = self._match_reference()
        scale = 1e-9 * np.maximum(1.0, np.abs(ev).max(axis=-1, keepdims=True))
        upper = ev.imag > -scale
        oscillating = ev.imag > scale
        allowed = np.where(want_complex, oscillating, upper)
        distance = np.abs(ev - ref[:, None]) + _PENALTY * ~allowed + _PENALTY * ~upper
        pick = np.argmin(distance, axis=-1)
        ok = np.take_along_axis(allowed & upper, pick[..., None], axis=-1)[..., 0]
        return pick, ok

    def _match_reference(self) -> tuple[np.ndarray, np.ndarray]:
        """Each row's reference eigenvalue ``(S,)`` and whether an oscillating one is wanted ``(S, 1)``
        (worked out once: the rows' modes are settled when the predictor is made)."""
        if getattr(self, "_match_cache", None) is None:
            ref = np.array([self._reference[k, _MODE_INDEX[m]] for k, m in enumerate(self.eigen.mode)])  # (S,)
            ref_complex = np.abs(ref.imag) > 1e-9 * np.maximum(1.0, np.abs(ref))
            is_weave = np.array([m == "weave" for m in self.eigen.mode])
            self._match_cache = (ref, (is_weave & ref_complex)[:, None])
        return self._match_cache

    def _predict_eigen(self, model: EffectModel, speed_scale=None) -> np.ndarray:
        return self._stack_eigen(self.eigenvalues(model, speed_scale))

    def _stack_eigen(self, matched: np.ndarray) -> np.ndarray:
        """Observations ``(..., n_obs_eigen)`` of matched eigenvalues ``(..., S)``: each row's real part,
        then a weave's imaginary part."""
        if getattr(self, "_stack_cache", None) is None:
            real, imag, weave, k = [], [], [], 0
            for row, mode in enumerate(self.eigen.mode):
                real.append(k)
                k += 1
                if mode == "weave":
                    imag.append(k)
                    weave.append(row)
                    k += 1
            self._stack_cache = (np.array(real, int), np.array(imag, int), np.array(weave, int), k)
        real, imag, weave, n = self._stack_cache
        out = np.empty(matched.shape[:-1] + (n,))
        out[..., real] = matched.real
        out[..., imag] = matched[..., weave].imag
        return out

    def _predict_canonical(self, model: EffectModel) -> np.ndarray:
        identified = {}
        for group in self._groups:
            cmap = self._canonical_maps[group]
            D = model.dynamic_stiffness(cmap["speeds"], OMEGAS)  # (..., N, F, 2, 2)
            delta = D - cmap["nominal_D"]
            parts = [
                cmap["row_weights"][k] * delta[..., r, c].reshape(delta.shape[:-4] + (-1,))
                for k, (r, c) in enumerate(cmap["positions"])
            ]
            stacked = np.concatenate(parts, axis=-1)
            stacked = np.concatenate([stacked.real, stacked.imag], axis=-1)
            theta = stacked @ cmap["pinv"].T + cmap["nominal_entries"]
            for j, entry in enumerate(cmap["entries"]):
                identified[(group, entry)] = theta[..., j]
        cols = [identified[(g, e)] for e, g in zip(self.canonical.entry, self.canonical.group)]
        return np.stack(cols, axis=-1)


def _nominal_entries(nominal: dict[str, float], entries: list[str]) -> np.ndarray:

    M, C1, K0, K2 = bm.canonical_matrices(**{k: nominal[k] for k in BENCH_ARGS})
    mats = {"M": M, "C1": C1, "K0": K0, "K2": K2}
    index = {"phi": 0, "delta": 1}
    out = []
    for entry in entries:
        name, coords = entry.split("_")
        row = "phi" if coords.startswith("phi") else "delta"
        col = coords[len(row) :]
        out.append(mats[name][index[row], index[col]])
    return np.array(out)
