"""Usual ranges and priors: whether a fitted value is usual, usable and what evidence it loses to its
prior; and steer friction as the viscous damping it equals at the records' amplitude (module docstring
of :mod:`bikerider.gap.diagnosis.result`, "Usual, and priors")."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.candidates.effects import (
    COULOMB_RANGE,
    EFFECTS,
    LITERATURE_EXTRA,
    PARAMETERS,
    STEER_FRICTION,
    EffectParameter,
    Prior,
    prior_from_range,
)
from bikerider.gap.diagnosis.fits import time_domain
from bikerider.gap.diagnosis.statistics import ALPHA, variance_quantile
from bikerider.gap.distributions import chi2
from bikerider.gap.inference.problem import EffectFit, GapProblem
from bikerider.gap.inference.timedomain import (
    SMOOTHING,
    Layout,
    closed_loop,
    describing_gain,
    friction_states,
    initial_states,
    make_batches,
    simulate_linear,
    systems,
)
from bikerider.gap.measured.records import RecordFit

UNDETERMINED = 1.0
"""A fitted value whose standard error exceeds this many times the width of its plausible range is
not determined by the data (the data narrow it down less than the literature already does)."""
AMPLITUDE_SPREAD = 2.0
"""Records whose steer-rate amplitudes span less than this factor (10th to 90th percentile) are decays of
one amplitude: they do not tell Coulomb from viscous friction (:meth:`Priors.friction_equivalent`)."""


def equivalent_damping(fit: EffectFit, amplitude: float, folds: int) -> tuple[float, float, tuple[float, float]]:
    """A steer-friction fit as the viscous damping it equals at steer-rate amplitude ``amplitude`` [rad/s]:
    ``c_eq = c_viscous + N(A) T_coulomb``, its standard error and 95 % interval.

    ``N(A)`` is the describing function of the fit's own friction law, ``tanh(deltad / eps)``
    (:func:`bikerider.gap.inference.timedomain.describing_gain`; ``4 / (pi A)`` for a sharp corner), at
    each corner the fit was refitted at (``fit.corners``): the data determine the damping at their
    amplitude, whatever corner the law is given, so the corner's share of ``c_eq`` is the corner prior's
    mean square of the move of ``c_eq`` itself, each corner's values through its own ``N(A)`` (not the
    fit's covariance's corner share through the fit's own ``N(A)``, which counts the split's move that
    the equivalent does not make).  The rest of the variance comes from the fit's covariance; Student's t
    with Welch-Satterthwaite degrees of freedom over ``folds`` held-out folds where the covariance holds a
    jackknife (:func:`bikerider.gap.diagnosis.statistics.interval_quantile`), else 1.96.
    """
    i, j = fit.names.index("T_coulomb"), fit.names.index("c_viscous")

    def at(eps: float, values: np.ndarray) -> float:
        return float(values[j] + describing_gain(amplitude, eps) * values[i])

    gradient = np.zeros(len(fit.names))
    gradient[i], gradient[j] = float(describing_gain(amplitude)), 1.0
    value = at(SMOOTHING, np.asarray(fit.values, float))
    if fit.covariance is not None and np.all(np.isfinite(fit.covariance)):
        covariance = np.asarray(fit.covariance, float)
        if fit.corner_covariance is not None:
            covariance = covariance - fit.corner_covariance
        corner = sum(w * (at(eps, v) - value) ** 2 for eps, w, v in fit.corners)
        variance = max(float(gradient @ covariance @ gradient), 0.0) + corner
        stderr = math.sqrt(variance)
    else:
        stderr = float(math.hypot(gradient[i] * fit.stderr[i], fit.stderr[j]))
    timed = time_domain(fit.effects) and fit.covariance is not None and folds >= 3
    if timed and fit.jackknife_covariance is not None:
        quantile = variance_quantile(stderr**2, float(gradient @ fit.jackknife_covariance @ gradient), folds)
    else:
        quantile = 1.96
    return value, stderr, (max(value - quantile * stderr, 0.0), value + quantile * stderr)


@dataclass(frozen=True, eq=False)
class Priors:
    """What the diagnosis judges fitted values against.

    Attributes
    ----------
    plausible : dict
        The bicycle's own ``[plausible]`` table: parameter -> ``(low, high, why)``.
    amplitudes : ndarray
        Each used record's steer-rate amplitude [rad/s], where known (:func:`steer_rate_amplitudes`).
    n_folds : int
        The diagnosis's held-out folds (the jackknife's quantile of a time-domain fit).
    problem : GapProblem or None
        The fit problem (the arms' geometry, the uncertain parameters); needed to judge the arms'
        mass and the benchmark parameters' shifts.
    unsteered : tuple of Record
        The used records that hold no steer signal; ``amplitudes`` ends with theirs, inferred from the
        nominal model's response fitted to them (:func:`inferred_steer_rate_amplitudes`), and a friction
        fit's equivalent infers them from its own response (:meth:`friction_equivalent`).
    """

    plausible: dict
    amplitudes: np.ndarray
    n_folds: int = 0
    problem: GapProblem | None = None
    unsteered: tuple = ()
    _fitted: dict = field(default_factory=dict, repr=False)

    def steer_rate_amplitude(self) -> float | None:
        """Median steer-rate amplitude of the records used [rad/s] (None without steer signals)."""
        known = self.amplitudes[np.isfinite(self.amplitudes)]
        return float(np.median(known)) if known.size else None

    def plausible_range(self, name: str) -> tuple[float, float, str]:
        """The usual range of a fitted parameter and where it comes from (a value outside it is flagged)."""
        if name in self.plausible:
            return self.plausible[name]
        param = parameter(name)
        lo, hi = param.literature
        if name == "c_steer":
            amplitude = self.steer_rate_amplitude()
            if amplitude is not None and amplitude > 0:
                extra = 4 * COULOMB_RANGE[1] / (math.pi * amplitude)
                return (
                    lo,
                    hi + extra,
                    (
                        f"{param.source}; above it, the linear equivalent 4 T / (pi A) of Coulomb "
                        f"friction T up to {COULOMB_RANGE[1]:g} N m at the records' steer-rate "
                        f"amplitude A = {amplitude:.3g} rad/s adds up to {extra:.3g} N m s/rad"
                    ),
                )
        return lo, hi, param.source

    def prior_of(self, name: str) -> Prior:
        """The prior of a fitted parameter: the bicycle's own ``[plausible]`` range made a prior
        (:func:`bikerider.gap.candidates.effects.prior_from_range`), else the registry's."""
        if name in self.plausible:
            lo, hi, why = self.plausible[name]
            return prior_from_range(lo, hi, f"this bicycle's [plausible] table: {why}")
        return parameter(name).the_prior()

    def log_prior(self, fit: EffectFit) -> float:
        """``ln p(values) - ln p(modes)`` of a fit's values under their priors [nats, <= 0]: what the
        selection weighs against the held-out log-likelihood (the benchmark shifts: ``-chi2 / 2`` of
        their Gaussian prior)."""
        total = -0.5 * fit.prior_chi2 if PARAMETERS in fit.effects else 0.0
        for k, name in enumerate(fit.names):
            if not name.startswith(PARAMETERS + "."):
                total += self.prior_of(name).log_ratio(float(fit.values[k]))
        return float(total)

    def friction_equivalent(self, fit: EffectFit) -> dict | None:
        """Coulomb plus viscous steer friction as the viscous damping it equals at the records' amplitude.

        The describing function of Coulomb friction ``T`` on a sinusoidal steer rate of amplitude ``A`` is a
        viscous damping ``N(A) T`` (``4 T / (pi A)`` for a sharp corner; the fit's own law's,
        :func:`equivalent_damping`), so ``c_eq = c_viscous + N(A) T`` at the records' median amplitude, with
        its standard error from the fit's covariance and its corners.  Records whose amplitudes span less
        than a factor :data:`AMPLITUDE_SPREAD` (10th to 90th percentile) are decays of one amplitude: they
        determine ``c_eq`` but not the split between Coulomb and viscous friction (``separable`` false).
        Records without a steer signal count with the amplitude of the fit's own response fitted to them
        (:func:`fitted_steer_rate_amplitudes`; ``inferred`` in the result: how many).  ``None`` for a fit
        without steer friction or without any amplitude.
        """
        if STEER_FRICTION not in fit.effects or "T_coulomb" not in fit.names:
            return None
        amplitudes = self.amplitudes
        if self.unsteered and self.problem is not None:
            key = (tuple(fit.effects), tuple(np.asarray(fit.values, float)))
            if key not in self._fitted:  # the same fit is judged in the ranking, the pairs and the selection
                self._fitted[key] = fitted_steer_rate_amplitudes(
                    list(self.unsteered), self.problem, fit.effects, fit.values
                )
            amplitudes = np.concatenate([amplitudes[: amplitudes.size - len(self.unsteered)], self._fitted[key]])
        amplitudes = amplitudes[np.isfinite(amplitudes) & (amplitudes > 0)]
        if not amplitudes.size:
            return None
        a = float(np.median(amplitudes))
        lo, hi = np.percentile(amplitudes, [10, 90])
        spread = float(hi / lo)
        value, stderr, (low, high) = equivalent_damping(fit, a, self.n_folds)
        separable = spread >= AMPLITUDE_SPREAD
        return {
            "c_equivalent": value,
            "stderr": stderr,
            "ci95": [low, high],
            "unit": "N m s/rad",
            "amplitude": a,
            "amplitude_spread": spread,
            "separable": bool(separable),
            "inferred": len(self.unsteered),
            "note": (
                f"the records' steer-rate amplitudes span a factor {spread:.2g} (10th-90th percentile, median "
                f"A = {a:.3g} rad/s"
                + (
                    f"; {len(self.unsteered)} of {self.amplitudes.size} inferred from this fit's response "
                    "fitted to records that hold no steer signal)"
                    if self.unsteered
                    else ")"
                )
                + (
                    ": Coulomb and viscous friction are told apart by how the damping changes with amplitude"
                    if separable
                    else (
                        ": decays of one amplitude, which cannot tell Coulomb from viscous friction; what they "
                        "determine is the equivalent viscous damping c_eq = c_viscous + N(A) T_coulomb (N(A) the "
                        f"describing function of the fit's friction law, {describing_gain(a):.3g} s/rad here, "
                        f"4/(pi A) = {4 / (math.pi * a):.3g} for a sharp one) = "
                        f"{value:.3g} [{low:.3g}, {high:.3g}] "
                        "N m s/rad, not the split"
                    )
                )
            ),
        }

    def plausibility(self, fit: EffectFit) -> tuple[bool, list[dict]]:
        """Whether every fitted value is usual (module docstring), with one check per fitted value.

        A check holds the value, its 95 % interval, the usual range and its source, the prior and its
        log ratio, whether the data determine the value and whether it is pinned at a search bound, and a
        ``flag`` (text) when the value lies outside the usual range.  ``usable`` is false only where the
        data cannot carry the value (undetermined, or pinned at the edge of the search).
        """

        checks = []
        ok = True
        pinned = set(fit.at_bound()) if fit.names else set()
        if PARAMETERS in fit.effects:
            limit = float(chi2.ppf(1 - ALPHA, max(len(self.problem.free), 1)))
            good = fit.prior_chi2 <= limit
            shifted = [n for n in fit.names if n.startswith(PARAMETERS + ".")]
            at = sorted(n.split(".", 1)[1] for n in shifted if n in pinned)
            checks.append(
                {
                    "name": "sum of squared shifts / sigma^2",
                    "value": fit.prior_chi2,
                    "literature": [0.0, limit],
                    "plausible": bool(good and not at),
                    "usable": not at,
                    "at_bound": at,
                    "log_prior": -0.5 * fit.prior_chi2,
                    "source": "the parameters' stated uncertainties (chi-square at 1 %)",
                }
            )
            ok = ok and bool(good) and not at
        for k, name in enumerate(fit.names):
            if name.startswith(PARAMETERS + "."):
                continue
            lo, hi, source = self.plausible_range(name)
            param = parameter(name)
            prior = self.prior_of(name)
            unit = fit.units[k]
            # zero where the prior makes it the most probable size (a half-Cauchy: none of the effect, e.g.
            # no viscous part beside Coulomb friction) is a value, not the edge of the search
            at_zero = fit.lower[k] == 0 and fit.values[k] <= 1e-4 * max(fit.upper[k] - fit.lower[k], 1e-12)
            at_bound = name in pinned and not (at_zero and prior.kind == "halfcauchy")
            ci = (float(fit.ci_low[k]), float(fit.ci_high[k]))
            if name == "m_arm":
                # judge the arms by their inertia about the steer axis
                inertia = arm_inertia(self.problem, fit.values[k])
                (lo, hi), unit, source = LITERATURE_EXTRA["I_arm_steer"]
                scale = inertia / fit.values[k] if fit.values[k] > 0 else arm_inertia(self.problem, 1.0)
                value, shown, ci = inertia, "I_arm_steer", (ci[0] * scale, ci[1] * scale)
                determined = math.isfinite(fit.stderr[k]) and fit.stderr[k] * scale <= UNDETERMINED * (hi - lo)
            else:
                value, shown = float(fit.values[k]), name
                determined = math.isfinite(fit.stderr[k]) and fit.stderr[k] <= UNDETERMINED * max(hi - lo, 1e-12)
            # below the usual range is usual too where the prior makes zero the most probable size
            usual = bool(lo <= value <= hi or (value < lo and prior.kind == "halfcauchy"))
            flag = None
            if not usual:
                side = "above" if value > hi else "below"
                precise = " (the data determine it: 95 % interval " if determined else " (95 % interval "
                # the value is judged, not its interval; where the interval reaches the usual range, say so
                reaches = ci[0] <= hi if side == "above" else ci[1] >= lo
                within = ", which reaches the usual range" if reaches else ""
                flag = (
                    f"{shown} = {value:.3g} {unit}{precise}[{ci[0]:.3g}, {ci[1]:.3g}]{within}) is {side} the usual "
                    f"{lo:g}-{hi:.3g} {unit} from {source}"
                    + (f": check {param.check}" if side == "above" and param.check else "")
                )
            good = bool(usual and determined and not at_bound)
            checks.append(
                {
                    "name": shown,
                    "value": value,
                    "unit": unit,
                    "literature": [lo, hi],
                    "plausible": good,
                    "in_range": usual,
                    "determined": bool(determined),
                    "at_bound": bool(at_bound),
                    "usable": bool(determined and not at_bound),
                    "bounds": [float(fit.lower[k]), float(fit.upper[k])],
                    "ci95": list(ci),
                    "source": source,
                    "prior": prior.describe(fit.units[k]),
                    "prior_source": prior.source,
                    "log_prior": prior.log_ratio(float(fit.values[k])),
                    "flag": flag,
                }
            )
            ok = ok and good
        return ok, checks


def steer_rate_amplitudes(records: list[RecordFit], record_rows: dict[int, int]) -> np.ndarray:
    """Each used record's steer-rate amplitude [rad/s], where known: ``sqrt(2)`` times the RMS steer rate
    over the record, from a steer-rate signal, or from a steer-angle signal times the record's weave
    frequency."""
    out = []
    for k in record_rows:
        f = records[k]
        r = f.record
        if "steer_rate" in r.signals and np.all(np.isfinite(r.signals["steer_rate"])):
            out.append(math.sqrt(2) * float(np.std(r.signals["steer_rate"])))
        elif "steer_angle" in r.signals and np.all(np.isfinite(r.signals["steer_angle"])) and f.estimate is not None:
            x = r.signals["steer_angle"]
            out.append(math.sqrt(2) * float(np.std(x)) * abs(f.estimate.eigenvalue))
    return np.array(out, float)


def unsteered_records(records: list[RecordFit], record_rows: dict[int, int]) -> list:
    """The used records (:class:`~bikerider.gap.measured.records.Record`) that hold no usable steer signal."""
    return [
        records[k].record
        for k in record_rows
        if not any(
            name in records[k].record.signals and np.all(np.isfinite(records[k].record.signals[name]))
            for name in ("steer_rate", "steer_angle")
        )
    ]


def fitted_steer_rate_amplitudes(records: list, problem: GapProblem, effects, values) -> np.ndarray:
    """``sqrt(2)`` times the RMS steer rate [rad/s] of a steer-friction fit's response fitted to each record
    (:func:`~bikerider.gap.inference.timedomain.friction_states`: the friction simulated in time from the
    record's fitted initial state), over the window the fit reads.  On the steer-by-wire logs with their steer
    signal hidden, these are 1.17 times the amplitudes the steer signal gives (median; 10th-90th percentile
    0.92-1.64), where the nominal model's response gives 1.33 (0.97-3.0): the friction holds the steer back."""
    layout = Layout.of(tuple(effects))
    out = np.full(len(records), np.nan)
    # a record that is not uniformly sampled keeps NaN and never stops the diagnosis
    for idx, batch in make_batches(records, skip_nonuniform=True):
        A, b, outputs, T = systems(problem.nominal, problem.geometry, batch.records, layout, np.atleast_2d(values))
        states, _ = friction_states(batch, A, b, outputs, T)
        for j, n in enumerate(batch.length):
            out[idx[j]] = math.sqrt(2) * float(np.std(states[0, j, :n, outputs[3]]))
    return out


def inferred_steer_rate_amplitudes(records: list, problem: GapProblem) -> np.ndarray:
    """The steer-rate amplitude [rad/s] of each used record that holds no steer signal, inferred:
    ``sqrt(2)`` times the RMS steer rate of the nominal closed loop's response fitted to the record (its
    initial state by least squares on the signals it has, :func:`~bikerider.gap.inference.timedomain.initial_states`),
    over the window a time-domain fit reads.  A roll-rate gyro alone sees the weave, and the weave's shape
    carries the steer with it; friction's hold on the steer is left out (a friction fit's equivalent uses
    :func:`fitted_steer_rate_amplitudes`).  ``records`` as :func:`unsteered_records` gives them."""
    out = np.full(len(records), np.nan)
    if not records:
        return out
    model = EffectModel(problem.nominal, problem.geometry)
    # a record that is not uniformly sampled keeps NaN and never stops the diagnosis
    for idx, batch in make_batches(records, skip_nonuniform=True):
        A, _, outputs = closed_loop(model, batch.records)
        states = simulate_linear(A, initial_states(batch, A, outputs), batch.dt, batch.N)
        for j, n in enumerate(batch.length):
            out[idx[j]] = math.sqrt(2) * float(np.std(states[j, :n, outputs[3]]))
    return out


def parameter(name: str) -> EffectParameter:
    """The registry's entry of a fitted parameter, by name."""
    return next(p for e in EFFECTS.values() for p in e.parameters if p.name == name)


def arm_inertia(problem: GapProblem, m_arm: float) -> float:
    """Moment of inertia of the arm masses about the steer axis [kg m^2]."""
    g = problem.geometry.grips
    v = problem.nominal
    lam, w, c = v["lam"], v["w"], v["c"]
    # distance of a grip from the steer axis (axis through (w + c, 0, 0), direction (sin lam, 0, cos lam))
    rel = np.array([g["x_grip"] - (w + c), g["b_grip"], g["z_grip"]])
    axis = np.array([math.sin(lam), 0.0, math.cos(lam)])
    perp = rel - (rel @ axis) * axis
    return float(m_arm * (perp @ perp))


def implausible_reasons(checks: list[dict]) -> list[str]:
    """Why a fit is implausible, one phrase per failing value."""
    out = []
    for c in checks:
        if c.get("plausible", True):
            continue
        name = c["name"]
        if name.startswith("sum of squared shifts"):
            parts = []
            if c["value"] > c["literature"][1]:
                parts.append(
                    f"parameter shifts of chi-square {c['value']:.3g} (the prior allows {c['literature'][1]:.3g})"
                )
            if c.get("at_bound"):
                parts.append("shifts pinned at a bound: " + ", ".join(c["at_bound"]))
            out.append("; ".join(parts))
            continue
        unit = c.get("unit", "")
        if c.get("at_bound"):
            out.append(f"{name} = {c['value']:.3g} {unit} at its search bound {c['bounds']}")
        elif not c.get("determined", True):
            out.append(
                f"{name} = {c['value']:.3g} {unit} not determined by the data (95 % interval "
                f"[{c['ci95'][0]:.3g}, {c['ci95'][1]:.3g}])"
            )
        else:
            out.append(
                c.get("flag")
                or f"{name} = {c['value']:.3g} {unit} outside the usual {c['literature'][0]:g}-"
                f"{c['literature'][1]:.3g} {unit}"
            )
    return out
