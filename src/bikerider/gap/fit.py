"""The fitting problem: observations, their uncertainties, and fits of effects to subsets of them.

Uncertainties.  Each measured scalar ``y_i`` has

* a data variance: its stated standard uncertainty squared plus, for eigenvalues, the speed
  uncertainty carried through the nominal model's slope ``d lambda / d v``.  Rows without a stated
  uncertainty get one estimated from the scatter of successive residuals (sorted by speed within a
  group) of the same mode and quantity, ``s^2 = sum(d^2) / (2 n_d)``, which a smooth gap does not
  inflate;
* a model variance: the benchmark parameters' standard uncertainties carried through the model at
  first order (central differences of one standard deviation), with the full covariance
  ``J J^T`` across observations.

Fits.  A set of effects is fitted by bounded nonlinear least squares
(:func:`scipy.optimize.least_squares`) on the residuals ``(prediction - y) / w``: ``w`` is the
square root of data plus model variance for structural effects (the parameter uncertainty is a
nuisance they must live with); when ``parameters`` is in the set the benchmark parameters
themselves move, ``p = p0 + u sigma_p`` with the prior residuals ``u`` appended, and ``w`` holds the
data variance alone.  Starts are the best of a grid over each fitted parameter's literature range (at most
:data:`MAX_STARTS` points);
the Jacobian is a forward difference evaluated for all parameters in one batched model call.
Standard errors come from ``(J^T J)^-1``, scaled by the reduced chi-square when that exceeds one;
95 % intervals are +-1.96 standard errors, clipped to the bounds.
"""

from __future__ import annotations

import itertools
import logging
import math
from dataclasses import dataclass, field

import numpy as np

from bikerider.errors import InputError
from bikerider.gap.data import CanonicalData, EigenvalueData
from bikerider.gap.effects import EFFECTS
from bikerider.gap.model_input import GapModelInput
from bikerider.gap.models import BENCH_ARGS, STRUCTURAL_KEYS, EffectModel
from bikerider.gap.predict import Predictor

LOG = logging.getLogger(__name__)
MAX_STARTS = 32
"""Most grid points tried as starting values of one fit (a fixed random subset beyond that)."""
_BAD = 1e3
"""Residual assigned to every observation when a model cannot be evaluated (singular matrices)."""


@dataclass
class EffectFit:
    """A set of effects fitted to a subset of the observations.

    Attributes
    ----------
    effects : tuple of str
    names, units : list of str
        Fitted parameters (structural ones by symbol, benchmark ones as ``parameters.<name>``).
    values, stderr, ci_low, ci_high : ndarray
    config : dict
        Effect name to ``{parameter: value}`` for :class:`EffectModel` (fixed values included).
    shift : dict
        Benchmark parameter changes (``parameters`` effect), SI.
    chi2 : float
        Sum of squared data residuals over the fitted points.
    prior_chi2 : float
        Sum of squared prior residuals ``u`` (``parameters`` only, else 0).
    n : int
        Number of fitted points.
    success : bool
    message : str
    """

    effects: tuple[str, ...]
    names: list[str]
    units: list[str]
    values: np.ndarray
    stderr: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    config: dict[str, dict[str, float]]
    shift: dict[str, float]
    chi2: float
    prior_chi2: float
    n: int
    success: bool
    message: str = ""


@dataclass
class _Layout:
    """How a fit's parameter vector maps onto effect parameters and benchmark shifts."""

    effects: tuple[str, ...]
    structural: list[tuple[str, str]] = field(default_factory=list)  # (effect, parameter)
    lower: list[float] = field(default_factory=list)
    upper: list[float] = field(default_factory=list)
    starts: list[tuple[float, ...]] = field(default_factory=list)
    units: list[str] = field(default_factory=list)
    n_shift: int = 0


class GapProblem:
    """Observations of one bicycle, its nominal model and their uncertainties.

    Parameters
    ----------
    model : GapModelInput
    eigen : EigenvalueData
    canonical : CanonicalData
    """

    def __init__(self, model: GapModelInput, eigen: EigenvalueData, canonical: CanonicalData):
        if len(eigen) + len(canonical) == 0:
            raise InputError("data", "empty", "at least one measured eigenvalue or identified entry")
        self.model_input = model
        self.geometry = model.geometry
        values, sigmas = model.parameters.values, model.parameters.sigmas
        self.nominal = {k: float(values[k]) for k in BENCH_ARGS + ("g",)}  # type: ignore[arg-type]
        self.free = [k for k in BENCH_ARGS if sigmas.get(k, 0.0) > 0]
        self.free_sigma = np.array([sigmas[k] for k in self.free])
        self.predictor = Predictor(eigen, canonical, self.nominal, self.geometry)
        self.obs = self.predictor.observations
        self.y = self.obs.value
        self.baseline = self.predictor.predict(EffectModel(self.nominal, self.geometry))
        self.notes: list[str] = []
        self.jacobian = self._parameter_jacobian()  # (n_obs, n_free), per sigma
        self.var_model = np.sum(self.jacobian**2, axis=1)
        self.var_speed = self._speed_variance(eigen)
        self.sigma_data = self._data_sigma()
        self.var_data = self.sigma_data**2 + self.var_speed
        self.var_total = self.var_data + self.var_model
        bad = np.flatnonzero(~(self.var_total > 0))
        if bad.size:
            k = int(bad[0])
            raise InputError(
                f"uncertainty of {self.obs.source[k]} ({self.obs.mode[k]} {self.obs.quantity[k]})",
                0.0,
                "a data or parameter uncertainty: give real_sigma/imag_sigma (or sigma) in the data, "
                "or parameter uncertainties in the model file",
            )

    # -- uncertainties -------------------------------------------------------------------------
    def _parameter_jacobian(self) -> np.ndarray:
        n = len(self.free)
        if n == 0:
            return np.zeros((len(self.obs), 0))
        steps = np.concatenate([np.diag(self.free_sigma), -np.diag(self.free_sigma)])
        values = self._values_batch(steps)
        pred = self.predictor.predict(EffectModel(values, self.geometry))
        return ((pred[:n] - pred[n:]) / 2).T

    def _values_batch(self, shifts: np.ndarray) -> dict[str, object]:
        """Benchmark values with shifts ``(P, n_free)`` (SI) applied, shaped ``(P, 1)``."""
        values: dict[str, object] = dict(self.nominal)
        for j, name in enumerate(self.free):
            values[name] = (self.nominal[name] + shifts[:, j])[:, None]
        return values

    def _speed_variance(self, eigen: EigenvalueData) -> np.ndarray:
        out = np.zeros(len(self.obs))
        if not len(eigen) or not np.any(eigen.speed_sigma > 0):
            return out
        # the step: the speed uncertainty, at least 1 mm/s, at most half the speed (never a negative speed)
        h = np.minimum(np.maximum(eigen.speed_sigma, 1e-3), 0.5 * eigen.speed)
        base = EffectModel(self.nominal, self.geometry)
        slopes = []
        for sign in (1, -1):
            shifted = EigenvalueData(
                eigen.speed + sign * h,
                eigen.value,
                eigen.real_sigma,
                eigen.imag_sigma,
                eigen.speed_sigma,
                list(eigen.mode),
                eigen.group,
                eigen.gains,
                eigen.source,
            )
            pred = Predictor(
                shifted, CanonicalData([], np.empty(0), np.empty(0), [], {}, []), self.nominal, self.geometry
            )
            pred._reference = self.predictor._reference
            slopes.append(pred.predict(base))
        slope = (slopes[0] - slopes[1]) / 2  # per h, eigenvalue parts first
        k = 0
        for row in range(len(eigen)):
            parts = 2 if eigen.mode[row] == "weave" else 1
            for _ in range(parts):
                out[k] = (slope[k] / h[row] * eigen.speed_sigma[row]) ** 2
                k += 1
        return out

    def _data_sigma(self) -> np.ndarray:
        sigma = self.obs.sigma.copy()
        missing = ~np.isfinite(sigma)
        if not np.any(missing):
            return sigma
        residual = self.y - self.baseline
        for key in sorted({(m, q) for m, q, miss in zip(self.obs.mode, self.obs.quantity, missing) if miss}):
            idx = [i for i in range(len(sigma)) if missing[i] and (self.obs.mode[i], self.obs.quantity[i]) == key]
            diffs = []
            for group in sorted({self.obs.group[i] for i in idx}):
                members = sorted((i for i in idx if self.obs.group[i] == group), key=lambda i: self.obs.speed[i])
                diffs += list(np.diff(residual[members]))
            if len(diffs) >= 2:
                estimate = float(math.sqrt(np.sum(np.square(diffs)) / (2 * len(diffs))))
                sigma[idx] = estimate
                self.notes.append(
                    f"{key[0]} {key[1]}: no stated uncertainty; {estimate:.3g} 1/s estimated from the "
                    f"scatter of {len(diffs)} successive residuals"
                )
            else:
                sigma[idx] = 0.0
                self.notes.append(
                    f"{key[0]} {key[1]}: no stated uncertainty and too few points to estimate one; "
                    "only the speed and parameter uncertainties count"
                )
        return sigma

    # -- models ------------------------------------------------------------------------------------
    def layout(self, effects: tuple[str, ...]) -> _Layout:
        lay = _Layout(tuple(effects))
        grids = []
        for name in effects:
            if name == "parameters":
                lay.n_shift = len(self.free)
                continue
            for p in EFFECTS[name].parameters:
                lay.structural.append((name, p.name))
                lay.lower.append(p.bounds[0])
                lay.upper.append(p.bounds[1])
                lay.units.append(p.unit)
                lo, hi = p.literature
                grids.append(sorted({float(np.clip(x, *p.bounds)) for x in (lo, 0.5 * (lo + hi), hi, p.start)}))
        if not grids:
            lay.starts = [()]
            return lay
        mids = tuple(g[len(g) // 2] for g in grids)
        total = math.prod(len(g) for g in grids)
        if total <= MAX_STARTS:
            lay.starts = list(itertools.product(*grids))
        else:  # a fixed random subset of the grid, and the middle of every range
            rng = np.random.default_rng(0)
            picks = {tuple(int(rng.integers(len(g))) for g in grids) for _ in range(4 * MAX_STARTS)}
            lay.starts = [mids] + [tuple(g[i] for g, i in zip(grids, pick)) for pick in sorted(picks)][: MAX_STARTS - 1]
        return lay

    def configure(self, lay: _Layout, x: np.ndarray) -> tuple[dict[str, object], dict[str, dict[str, object]]]:
        """Benchmark values and effect configuration for parameter vectors ``x`` of shape ``(P, p)``."""
        n_struct = len(lay.structural)
        config: dict[str, dict[str, object]] = {}
        for name in lay.effects:
            if name != "parameters":
                config[name] = dict(EFFECTS[name].fixed)
        for j, (name, param) in enumerate(lay.structural):
            config[name][param] = x[:, j : j + 1]
        if lay.n_shift:
            values = self._values_batch(x[:, n_struct:] * self.free_sigma)
        else:
            values = dict(self.nominal)
        return values, config

    def predict_batch(self, lay: _Layout, x: np.ndarray) -> np.ndarray:
        """Predictions ``(P, n_obs)`` for parameter vectors ``x`` ``(P, p)``; NaN rows when singular."""
        values, config = self.configure(lay, np.atleast_2d(x))
        try:
            with np.errstate(all="ignore"):
                out = self.predictor.predict(EffectModel(values, self.geometry, config))
        except np.linalg.LinAlgError:
            return np.full((np.atleast_2d(x).shape[0], len(self.obs)), np.nan)
        if out.ndim == 1:
            out = np.broadcast_to(out, (np.atleast_2d(x).shape[0], out.size))
        return out

    def z(self, prediction: np.ndarray) -> np.ndarray:
        """Residuals ``(prediction - y) / sqrt(data + model variance)``."""
        return (prediction - self.y) / np.sqrt(self.var_total)

    # -- fitting -------------------------------------------------------------------------------
    def fit(self, effects: tuple[str, ...], mask: np.ndarray | None = None) -> EffectFit:
        """Fit ``effects`` to the observations selected by ``mask`` (all by default)."""
        from scipy.optimize import least_squares

        mask = np.ones(len(self.obs), bool) if mask is None else np.asarray(mask, bool)
        lay = self.layout(tuple(effects))
        n_struct = len(lay.structural)
        weight = np.sqrt(self.var_data if lay.n_shift else self.var_total)
        weight = np.where(weight > 0, weight, np.sqrt(self.var_total))[mask]
        y = self.y[mask]
        p = n_struct + lay.n_shift

        def residuals_batch(X: np.ndarray) -> np.ndarray:
            pred = self.predict_batch(lay, X)[:, mask]
            r = (pred - y) / weight
            r = np.where(np.isfinite(r), r, _BAD)
            if lay.n_shift:
                r = np.concatenate([r, X[:, n_struct:]], axis=1)
            return r

        if p == 0:
            r = residuals_batch(np.zeros((1, 0)))[0]
            return self._result(lay, np.zeros(0), np.zeros(0), r, int(mask.sum()), True, "nothing to fit")
        lower = np.array(lay.lower + [-5.0] * lay.n_shift)
        upper = np.array(lay.upper + [5.0] * lay.n_shift)
        starts = np.array([list(s) + [0.0] * lay.n_shift for s in lay.starts])
        costs = np.sum(residuals_batch(starts) ** 2, axis=1)
        x0 = starts[int(np.argmin(costs))]
        scale = np.array([max(hi - lo, 1e-6) for lo, hi in zip(lay.lower, lay.upper)] + [1.0] * lay.n_shift)
        steps = np.concatenate([1e-5 * np.minimum(scale[:n_struct], 10.0), np.full(lay.n_shift, 1e-3)])

        def jac(x: np.ndarray) -> np.ndarray:
            h = steps * np.where(x + steps <= upper, 1.0, -1.0)
            X = np.vstack([x, x + np.diag(h)])
            R = residuals_batch(X)
            return ((R[1:] - R[0]) / h[:, None]).T

        def fun(x: np.ndarray) -> np.ndarray:
            return residuals_batch(x[None, :])[0]

        result = least_squares(
            fun,
            x0,
            jac=jac,
            bounds=(lower, upper),
            x_scale=np.where(scale > 0, scale, 1.0) * 0.1,
            method="trf",
            max_nfev=50 * p,
            ftol=1e-6,
            xtol=1e-6,
            gtol=1e-8,
        )
        J = jac(result.x)
        dof = max(result.fun.size - p, 1)
        reduced = float(np.sum(result.fun**2)) / dof
        try:
            cov = np.linalg.pinv(J.T @ J) * max(1.0, reduced)
            stderr = np.sqrt(np.clip(np.diag(cov), 0, None))
        except np.linalg.LinAlgError:
            stderr = np.full(p, np.inf)
        return self._result(lay, result.x, stderr, result.fun, int(mask.sum()), bool(result.success), result.message)

    def _result(
        self, lay: _Layout, x: np.ndarray, stderr: np.ndarray, r: np.ndarray, n: int, ok: bool, message: str
    ) -> EffectFit:
        n_struct = len(lay.structural)
        names = [f"{param}" for _, param in lay.structural] + [f"parameters.{k}" for k in self.free][: lay.n_shift]
        units = list(lay.units) + ["sigma"] * lay.n_shift
        values, config = self.configure(lay, x[None, :] if x.size else np.zeros((1, 0)))
        config_out = {
            e: {k: float(np.asarray(v).ravel()[0]) for k, v in params.items()} for e, params in config.items()
        }
        shift = {}
        if lay.n_shift:
            for j, name in enumerate(self.free):
                shift[name] = float(x[n_struct + j] * self.free_sigma[j])
        lo = np.array(lay.lower + [-5.0] * lay.n_shift)
        hi = np.array(lay.upper + [5.0] * lay.n_shift)
        ci_low = np.clip(x - 1.96 * stderr, lo, hi) if x.size else x
        ci_high = np.clip(x + 1.96 * stderr, lo, hi) if x.size else x
        data_r = r[:n]
        prior = r[n:] if lay.n_shift else np.zeros(0)
        return EffectFit(
            tuple(lay.effects),
            names,
            units,
            x,
            stderr,
            ci_low,
            ci_high,
            config_out,
            shift,
            float(np.sum(data_r**2)),
            float(np.sum(prior**2)),
            n,
            ok,
            str(message),
        )

    def predict_fit(self, fit: EffectFit) -> np.ndarray:
        """Predictions of every observation with a fitted set of effects."""
        lay = self.layout(fit.effects)
        return self.predict_batch(lay, fit.values[None, :])[0]

    def fitted_model(self, fit: EffectFit) -> EffectModel:
        """The :class:`EffectModel` of a fit (nominal parameters plus any fitted shift)."""
        values = dict(self.nominal)
        for name, delta in fit.shift.items():
            values[name] = self.nominal[name] + delta
        return EffectModel(values, self.geometry, fit.config)


def structural_parameter_names(effect: str) -> tuple[str, ...]:
    """Every model parameter an effect sets (fitted and fixed)."""
    return STRUCTURAL_KEYS.get(effect, ())
