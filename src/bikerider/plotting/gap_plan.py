"""Figure of a plan for the next experiment (:mod:`bikerider.gap.plan.ranking`; its text is :func:`bikerider.gap.text.next_text`)."""

from __future__ import annotations

import math
import textwrap

import numpy as np
from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter
from scipy.optimize import brentq
from scipy.special import ndtri

from bikerider.gap.plan.ranking import ODDS
from bikerider.plotting.common import pyplot

PLANNED_SHOWN = 5
"""The first decays of the plan whose speeds the figure marks (those of the best one's law, signal and push)."""


def plot_next(plan, result: dict | None = None):
    """Predictions of the rivals diverging over speed (the best plan item's law, signal and push), with
    one standard deviation of each for the planned decays, the data, and the resolution probability
    against speed for every law (:func:`_probability_panel`: one signal and push per law, solid, and the
    best of any at each speed, dotted)."""
    plt = pyplot()
    result = result or plan.as_dict()
    decays = [item for item in plan.plan if item["experiment"].kind == "decay"]
    sweeps = [item for item in plan.plan if item["experiment"].kind == "sweep"]
    best = decays[0]["experiment"]
    fig, grid = plt.subplots(2 if sweeps else 1, 3, figsize=(15, 9.2 if sweeps else 4.6), squeeze=False)
    axes = grid[0]
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    chosen = [m for m, e in enumerate(plan.points) if (e.law, e.signal, e.push) == (best.law, best.signal, best.push)]
    chosen.sort(key=lambda m: plan.points[m].speed)
    v = np.array([plan.points[m].speed for m in chosen])
    n = plan.repeats
    noise = (plan.data_cov[chosen] + plan.model_cov[chosen]) / n
    for k, rival in enumerate(plan.rivals):
        mean = plan.mean[k, chosen]
        colour = colours[k % len(colours)]
        for part, ax in enumerate(axes[:2]):
            sd = np.sqrt(plan.own_cov[k, chosen, part, part] + noise[:, part, part])
            y = mean.real if part == 0 else mean.imag
            ax.plot(v, y, "-o", ms=3, color=colour, label=rival.name if part == 0 else None)
            ax.fill_between(v, y - sd, y + sd, color=colour, alpha=0.18, lw=0)
    e = plan.problem.eigen
    law_rows = [i for i in range(len(e)) if e.law[i] == best.law and e.mode[i] == "weave"]
    if law_rows:
        # the data as taken: each record's (or row's) weave eigenvalue with its standard error
        shown = plan.diagnosis.shown_values()
        taken = ", each record's fit" if plan.records else ""
        for part, (ax, sigma) in enumerate(zip(axes[:2], (e.real_sigma, e.imag_sigma))):
            y = shown.real[law_rows] if part == 0 else shown.imag[law_rows]
            ax.errorbar(
                e.speed[law_rows],
                y,
                yerr=sigma[law_rows],
                fmt="k.",
                ms=4,
                elinewidth=0.8,
                capsize=1.5,
                label=f"measured ({best.law}{taken}, 1 sd)" if part == 0 else None,
            )
    # the planned decays: the best experiments of this law, signal and push
    planned = sorted(
        {
            item["experiment"].speed
            for item in decays[:PLANNED_SHOWN]
            if (item["experiment"].law, item["experiment"].signal, item["experiment"].push)
            == (best.law, best.signal, best.push)
        }
    )
    for ax in axes[:2]:
        for k, speed in enumerate(planned):
            ax.axvline(speed, color="0.3", ls=":", lw=1.2 if speed == best.speed else 0.8)
        ax.plot([], [], color="0.3", ls=":", lw=1, label="planned speed" + "s" * (len(planned) > 1))
        ax.set_xlabel("speed [m/s]")
        ax.grid(alpha=0.3)
    what = best.describe().replace("decays at", "").split(",", 1)
    axes[0].set_ylabel("weave real part [1/s]")
    axes[1].set_ylabel("weave imaginary part [rad/s]")
    title = f"predicted under {best.law}" + (f",{what[1]}" if len(what) > 1 else "")
    axes[0].set_title(textwrap.fill(title, 60), fontsize=9)  # a long law's name and push: two lines, not past the edge
    axes[1].set_title(f"bands: 1 sd of the mean of {n} decays", fontsize=9)
    axes[0].legend(fontsize=7)
    # resolution probability against speed, per law (its best signal and push, and the best of any at each speed)
    _probability_panel(axes[2], decays, plan, colours, "decays")
    if sweeps:
        _sweep_row(grid[1], plan, sweeps, colours)
    nxt = plan.next_run
    if nxt is not None and nxt["kind"] == "decay":
        _mark_next(axes[2], plan, decays, lambda item: item["resolution_probability"])
        axes[2].legend(fontsize=7)
    title = "Where the rivals disagree: " + ", ".join(r.name for r in plan.rivals) + f" (best: {plan.plan[0]['text']})"
    if nxt is not None:
        title += f"\nnext run, one at a time (Jensen-Renyi, star): {nxt['text']}"
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def _probability_panel(ax, items, plan, colours, what):
    """Resolution probability against speed, per law.

    The solid curve of a law follows one signal and push over speed: those of the law's best experiment (the
    highest probability over speed; of equals, the first in the plan's ranking), so that it moves with the
    speed alone.  A thin dotted curve of the same colour is the best experiment of any signal and push at each
    speed: never below the solid one, and jagged where the best signal or push changes from one speed to the
    next (which is no numerical noise).  With a single signal and push (eigenvalue tables, or linear rivals
    with one signal) the two are one curve, drawn solid.
    """
    n = plan.repeats
    prob = {}
    for item in items:
        x = item["experiment"]
        key = (x.law, x.speed)
        prob[key] = max(prob.get(key, 0.0), item["resolution_probability"])
    several = len({(item["experiment"].signal, item["experiment"].push) for item in items}) > 1
    for k, law in enumerate(plan.laws):
        of_law = [item for item in items if item["experiment"].law == law]
        if not of_law:
            continue
        colour = colours[k % len(colours)]
        top = max(of_law, key=lambda item: item["resolution_probability"])["experiment"]  # the first of equals
        pts = sorted(
            (item["experiment"].speed, item["resolution_probability"])
            for item in of_law
            if (item["experiment"].signal, item["experiment"].push) == (top.signal, top.push)
        )
        s, p = zip(*pts)
        ax.plot(s, p, "-o", ms=3, color=colour, label=_follows(top) if several else law)
        if several:
            s, p = zip(*sorted((v, q) for (name, v), q in prob.items() if name == law))
            ax.plot(s, p, ":", lw=1, color=colour)
    if several:
        ax.plot([], [], color="0.3", ls=":", lw=1, label="best of any signal/push")
    ax.axhline(0.95, color="0.4", ls="--", lw=1)
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("speed [m/s]")
    ax.set_ylabel(f"resolution probability, {n} {what}")
    ax.set_title(f"{what}: smallest over the pairs of rivals", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def _follows(e) -> str:
    """The legend of a law's curve that follows the signal and push of experiment ``e``, e.g. ``"sil, roll rate,
    push x0.5"`` (the push relative to the data's)."""
    out = e.law
    if e.signal != "eigenvalue":
        out += f", {e.signal.replace('_', ' ')}"
    return out + f", push x{e.push:g}"


def _sweep_row(axes, plan, sweeps, colours):
    """The best multisine's frequency response per rival (magnitude and phase, bands one standard deviation
    of the mean of the planned runs, the magnitude's as a factor ``exp(sd / |H|)``), and the multisines'
    resolution probability against speed."""
    best = sweeps[0]["experiment"]
    m = plan.sweeps.index(best)
    f = np.array(best.lines)
    K = f.size
    cov = plan.sweep_data[m] + plan.sweep_model[m]
    for k, rival in enumerate(plan.rivals):
        H = plan.sweep_mean[k, m]
        S = plan.sweep_own[k, m] + cov / plan.repeats
        # first-order spread of |H| and of the phase from the real and imaginary parts' covariance
        re, im = H.real, H.imag
        mag = np.abs(H)
        var_re, var_im, cross = np.diag(S)[:K], np.diag(S)[K:], np.diag(S[:K, K:])
        sd_mag = np.sqrt(np.maximum(re**2 * var_re + im**2 * var_im + 2 * re * im * cross, 0)) / mag
        sd_phase = np.sqrt(np.maximum(im**2 * var_re + re**2 * var_im - 2 * re * im * cross, 0)) / mag**2
        phase = np.degrees(np.unwrap(np.angle(H)))
        if k == 0:
            reference = phase[0]
        phase = phase + 360.0 * np.round((reference - phase[0]) / 360.0)  # every rival on the first one's branch
        colour = colours[k % len(colours)]
        axes[0].plot(f, mag, "-o", ms=3, color=colour, label=rival.name)
        # on the log axis, the band as a factor (a band below zero has no place there)
        spread = np.exp(np.minimum(sd_mag / mag, 3.0))
        axes[0].fill_between(f, mag / spread, mag * spread, color=colour, alpha=0.18, lw=0)
        axes[1].plot(f, phase, "-o", ms=3, color=colour)
        band = np.degrees(sd_phase)
        axes[1].fill_between(f, phase - band, phase + band, color=colour, alpha=0.18, lw=0)
    unit = "rad/s" if best.output == "roll_rate" else "rad"
    axes[0].set_ylabel(f"|{best.output.replace('_', ' ')} / steer torque| [{unit} / N m]")
    axes[1].set_ylabel("phase [deg]")

    for ax in axes[:2]:
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("frequency [Hz]")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_yscale("log")
    axes[0].set_title(f"best multisine: {best.torque:g} N m at {best.speed:.2f} m/s under {best.law}", fontsize=9)
    axes[1].set_title(f"bands: 1 sd of the mean of {plan.repeats} runs", fontsize=9)
    axes[0].legend(fontsize=8)
    _separation_panel(axes[2], sweeps, plan, colours)


def _separation_panel(ax, items, plan, colours):
    """The multisines' separation ``d`` of a single run against speed, per law (the best multisine at each
    speed, smallest over the pairs of rivals), on a log scale, with the ``d`` one run needs for a 95 %
    resolution: where a probability would sit at 1.00 everywhere, how far beyond it each speed and law is."""
    d_one = plan.separation(1.0)  # (pairs, 2, points)
    worst = d_one.min(axis=(0, 1))
    index = {id(x): m for m, x in enumerate(plan.experiments)}
    best = {}
    for item in items:
        x = item["experiment"]
        key = (x.law, x.speed)
        best[key] = max(best.get(key, 0.0), float(worst[index[id(x)]]))
    for k, law in enumerate(plan.laws):
        pts = sorted((s, d) for (name, s), d in best.items() if name == law)
        if pts:
            s, d = zip(*pts)
            ax.plot(s, d, "-o", ms=3, color=colours[k % len(colours)], label=law)
    if plan.next_run is not None and plan.next_run["kind"] == "sweep":
        _mark_next(ax, plan, items, lambda item: float(worst[index[id(item["experiment"])]]))
    ax.axhline(D_95, color="0.4", ls="--", lw=1, label=f"d for 95 % from one run ({D_95:.1f})")
    ax.set_yscale("log")
    # labels at 1, 1.5, 2, 3, 5 and 7 of every decade the separations span (a log axis labels only its decades)
    ax.yaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 1.5, 2.0, 3.0, 5.0, 7.0)))
    ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("speed [m/s]")
    ax.set_ylabel("separation d of one multisine run")
    ax.set_title("multisines: one run's separation, smallest over the pairs", fontsize=9)
    ax.grid(alpha=0.3, which="both")
    # beside the panel: the separations fill it from the 95 % line up, and the next run's star may sit
    # anywhere in it (at its speed, often below every law's best)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)


def _mark_next(ax, plan, items, value) -> None:
    """A star at the next single run (:attr:`NextExperiment.next_run`) on a panel against speed, at ``value`` of
    its plan item."""
    e = plan.experiments[plan.next_run["index"]]
    item = next((x for x in items if x["experiment"] == e), None)
    if item is None:
        return
    ax.plot(
        [e.speed],
        [value(item)],
        "*",
        ms=14,
        mfc="gold",
        mec="k",
        zorder=5,
        label=f"next run ({e.law}, {e.signal.replace('_', ' ')})",
    )


def _d_for(probability: float) -> float:
    """The separation whose resolution probability ``Phi(d / 2 - ln(ODDS) / d)`` is ``probability``."""
    z = float(ndtri(probability))
    return brentq(lambda d: d / 2 - math.log(ODDS) / d - z, 1e-3, 1e3)


D_95 = _d_for(0.95)
