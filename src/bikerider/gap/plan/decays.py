"""Free decays as experiments of the plan: what one is (:class:`Experiment`), and its template.

With records, a new decay is predicted from a *template*: a decay the nominal model makes from the data's
push, with each signal's noise, fitted as a record is fitted (:func:`fit_templates`); the rivals then
predict what that fit finds in their own response over it (indirect inference, in
:mod:`bikerider.gap.plan.ranking`).

Records that log no steer do not say how the steer moved at the start of a kick, and a friction rival's
decay depends on it (Coulomb friction acts on the steer rate's sign and size).  The plan then spans it
(:func:`kick_steer_rates`): each experiment has templates started from steer rates spread over
:data:`KICK_STEER_RATE` times the roll rate either way, each rival's prediction is the mean over them and
their spread a per-run variance of its prediction.  A roll-rate record does not pin the initial steer
rate itself: an initial state fitted to the roll rate alone under the nominal model (as indirect inference
does) gives steer rates from -4300 to +180 rad/s on a withheld case of the closed loop (seed 9311; a fast
castor mode takes it up), so the range is stated, not fitted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.inference.indirect import LAMBDA_BOUNDS, levenberg_marquardt
from bikerider.gap.inference.timedomain import CORNER_FACTOR, CORNER_NODES, CORNER_WEIGHTS, corner_nodes
from bikerider.gap.measured.control import ControlLaw
from bikerider.gap.measured.extraction import MIN_CYCLES, MIN_R2, _accept_two_mode, _two_mode, _two_mode_jacobian
from bikerider.gap.measured.records import Record, RecordFit
from bikerider.gap.plan.noise import over_speed

NOISE_SEED = 2024
"""Seed of the noise added to templates (their fits' standard errors scale with it; the value does not)."""
TEMPLATE_STATES = {"roll_rate": "phid", "roll_angle": "phi", "steer_angle": "delta", "steer_rate": "deltad"}
"""A template's signals and the states they are."""
KICK_STEER_RATE = 2.5
"""Records that log no steer: a kick's initial steer rate is taken as uniform between minus and plus this
many times its initial roll rate (a hand push on the frame or the rider moves the steer as fast as the roll
or faster; the closed loop's truths kick the steer rate up to 0.8 rad/s either way with roll rates of
0.2-0.4 rad/s, ratios of 2-4, docs/gap_validation.md part 5)."""
KICK_NODES, KICK_WEIGHTS = CORNER_NODES, CORNER_WEIGHTS
"""The friction corner's three-point Gauss-Legendre rule, here over the uniform range of :data:`KICK_STEER_RATE`
(exact for a response quadratic in the steer rate; mean and variance of the uniform range exactly): the nodes
as fractions of the range, their weights; the first node is the template of the data's own state."""
SMOOTHING_FACTOR = CORNER_FACTOR
"""The friction law's corner the data do not decide (:data:`~bikerider.gap.inference.timedomain.CORNER_FACTOR`):
a friction rival's decays are predicted with its friction smoothed as ``tanh(deltad / eps)`` for ``eps``
log-uniform between :data:`~bikerider.gap.inference.timedomain.SMOOTHING` divided and multiplied by this factor
(0.02-0.125 rad/s).  The lower end is the closed loop's independent truth (``tanh(deltad / 0.02)``,
docs/gap_validation.md part 5); the steer-by-wire logs lean to a smooth corner without ruling out the sharp one
(docs/gap.md, *The friction law's corner*)."""
smoothing_nodes = corner_nodes
"""The friction smoothings ``eps`` [rad/s] a friction rival's decays are predicted at, and their weights
(:func:`~bikerider.gap.inference.timedomain.corner_nodes`: the fits' own corner first)."""


@dataclass(frozen=True)
class Experiment:
    """One kind of new decay.

    Attributes
    ----------
    speed : float
        [m/s]
    law : str
        Name of the control law acting (a key of :attr:`NextExperiment.laws`).
    signal : str
        The signal the eigenvalue is fitted to (``eigenvalue`` for tables: the data say none).
    push : float
        The push relative to the data's (records only).
    """

    speed: float
    law: str
    signal: str = "eigenvalue"
    push: float = 1.0

    kind = "decay"

    def describe(self, repeats: int | None = None) -> str:
        what = "decays" if repeats is None else (f"{repeats} decay" + ("s" if repeats != 1 else ""))
        out = f"{what} at {self.speed:.2f} m/s under {self.law}"
        if self.signal != "eigenvalue":
            out += f", eigenvalue from the {self.signal.replace('_', ' ')}"
        if self.push != 1.0:
            out += f", pushes x{self.push:g} the data's"
        return out


def steer_logged(records: list[Record]) -> bool:
    """Whether any of the records logs the steer (its angle or rate): then :func:`push_of` reads the initial
    steer state from them."""
    return any("steer_angle" in r.signals or "steer_rate" in r.signals for r in records)


def kick_steer_rates(records: list[Record]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The initial steer rates a template spans, as multiples of its initial roll rate, and their weights.

    ``(0,), (1,)`` (the data's own state, :func:`push_curve`) when the records log the steer; else the
    :data:`KICK_NODES` over :data:`KICK_STEER_RATE` with :data:`KICK_WEIGHTS` (module docstring).
    """
    if not records or steer_logged(records):
        return (0.0,), (1.0,)
    return tuple(KICK_STEER_RATE * x for x in KICK_NODES), KICK_WEIGHTS


def template_records(
    nominal: EffectModel,
    used: list[Record],
    experiments: list[Experiment],
    laws: dict[str, ControlLaw],
    noise: dict[str, float],
    steer_rates: list[float] | None = None,
) -> tuple[list[Record], list[dict[str, np.ndarray]], list[tuple[float, float, float, float]]]:
    """Each experiment's template decay as a record (the nominal model's response with the signals' noise),
    its noise-free signals and its initial state ``(phi, delta, phid, deltad)`` (the kick it starts from).

    One window for every template (the records' median length and sampling step) and one noise pattern
    (:data:`NOISE_SEED`: the same samples scaled by each signal's noise), the push the data's as a
    continuous function of speed (:func:`push_curve`): a template, its fit and every prediction from it
    move continuously with the speed, the law and the push.  ``steer_rates``: per experiment, an initial
    steer rate added to the data's, as a multiple of the template's initial roll rate
    (:func:`kick_steer_rates`; default none).
    """
    dt = float(np.median([r.time[1] - r.time[0] for r in used]))
    t = np.arange(int(np.median([r.time.size for r in used]))) * dt
    pattern = np.random.default_rng(NOISE_SEED).standard_normal((len(TEMPLATE_STATES), t.size))
    push = push_curve(used)
    speed_sigma = float(np.median([r.speed_sigma for r in used]))
    measured = any(r.speed_measured for r in used)
    records: list[Record] = []
    clean: list[dict[str, np.ndarray]] = []
    kicks: list[tuple[float, float, float, float]] = []
    for j, e in enumerate(experiments):
        law = laws[e.law]
        initial = {k: e.push * v for k, v in push(e.speed).items()}
        if steer_rates is not None and steer_rates[j]:
            initial["deltad"] = initial.get("deltad", 0.0) + steer_rates[j] * initial.get("phid", 0.0)
        out = nominal.simulate(e.speed, t, initial=initial, gains=law(e.speed))
        kicks.append(tuple(float(initial.get(name, 0.0)) for name in ("phi", "delta", "phid", "deltad")))
        clean.append({name: out[state] for name, state in TEMPLATE_STATES.items()})
        signals = {name: clean[-1][name] + noise[name] * pattern[i] for i, name in enumerate(TEMPLATE_STATES)}
        records.append(
            Record(
                f"next {e.describe()}",
                "plan",
                t,
                signals,
                e.speed,
                speed_sigma,
                "next",
                law,
                e.speed,
                None,
                None,
                (e.signal,),
                measured,
            )
        )
    return records, clean, kicks


def fit_templates(nominal: EffectModel, records: list[Record]) -> list[RecordFit]:
    """Fit every template as a record is fitted, batched: the record fit's two-mode function, started
    from the nominal model's weave and slow eigenvalues, judged by the record fit's acceptance rules
    (:func:`bikerider.gap.measured.extraction._accept_two_mode`: a significant oscillation, half a cycle and
    more with a clear decay, the slow mode in range)."""
    groups: dict[int, list[int]] = {}
    for k, r in enumerate(records):
        groups.setdefault(r.time.size, []).append(k)
    fitted: dict[int, RecordFit] = {}
    for size, index in groups.items():
        tau = records[index[0]].time - records[index[0]].time[0]
        starts, ys = [], []
        for k in index:
            r = records[k]
            ev = nominal.eigenvalues([r.speed], r.gains[None, :])[0]
            weave = ev[np.argmax(ev.imag)]
            real = ev[np.abs(ev.imag) < 1e-9 * np.maximum(1.0, np.abs(ev))].real
            slow = float(real.max()) if real.size else -1.0
            lam = float(np.clip(slow, LAMBDA_BOUNDS[0], LAMBDA_BOUNDS[1]))
            starts.append([abs(weave.imag), -weave.real, 0.0, 0.0, 0.0, 0.0, lam])
            ys.append(r.signals[r.fit_signals[0]])
        Y = np.array(ys)
        with np.errstate(all="ignore"):
            beta, cost = levenberg_marquardt("two-mode", np.array(starts), Y, np.ones(Y.shape, bool), tau)
        for j, k in enumerate(index):
            r, name = records[k], records[k].fit_signals[0]
            if not np.all(np.isfinite(beta[j])):
                fitted[k] = RecordFit(r, None, reason=f"{name}: no weave the record fit finds (less than half a cycle)")
                continue
            fun = _two_mode(beta[j], tau) - Y[j]
            res = SimpleNamespace(x=beta[j], cost=0.5 * float(cost[j]), jac=_two_mode_jacobian(beta[j], tau), fun=fun)
            total = float(np.sum((Y[j] - Y[j].mean()) ** 2))
            with np.errstate(all="ignore"):
                two, why = _accept_two_mode(res, size, tau, total, MIN_CYCLES)
            if two is None:
                fitted[k] = RecordFit(r, None, reason=f"{name}: {why}")
            elif not two[0].r2 >= MIN_R2:
                fitted[k] = RecordFit(r, None, reason=f"{name}: poor fit (r^2 = {two[0].r2:.2f})")
            else:
                estimate = two[0]
                fitted[k] = RecordFit(r, estimate, {name: estimate})
    return [fitted[k] for k in range(len(records))]


def push_curve(records: list[Record]):
    """The data's push as a function of speed: every record's initial state (:func:`push_of`), turned so its
    roll rate is positive, its median per speed group, linearly between the groups (:func:`over_speed`),
    so the template's push moves continuously with the speed."""
    pushes = []
    for r in records:
        x = push_of(r, 1.0)
        sign = -1.0 if x.get("phid", 0.0) < 0 else 1.0
        pushes.append({k: sign * v for k, v in x.items()})
    speeds = np.array([r.speed for r in records])
    names = [n for n in ("phi", "delta", "phid", "deltad") if any(n in x for x in pushes)]
    curves = {}
    for n in names:
        have = [k for k, x in enumerate(pushes) if n in x]
        curves[n] = over_speed(speeds[have], [pushes[k][n] for k in have])

    def at(speed: float) -> dict[str, float]:
        return {n: curve(speed) for n, curve in curves.items()}

    return at


def push_of(record: Record, factor: float) -> dict[str, float]:
    """The initial state of a record (its first samples; steer rate from the steer angle where not
    logged), times ``factor``."""
    s = record.signals
    dt = float(record.time[1] - record.time[0])
    out = {"phid": float(np.mean(s["roll_rate"][:2])) if "roll_rate" in s else 0.5}
    if "roll_angle" in s:
        out["phi"] = float(s["roll_angle"][0])
    if "steer_angle" in s:
        out["delta"] = float(s["steer_angle"][0])
    if "steer_rate" in s:
        out["deltad"] = float(s["steer_rate"][0])
    elif "steer_angle" in s and s["steer_angle"].size > 3:
        out["deltad"] = float((s["steer_angle"][3] - s["steer_angle"][0]) / (3 * dt))
    return {k: factor * v for k, v in out.items() if math.isfinite(v)}
