"""Text and figure of a plan for the next experiment (:mod:`bikerider.gap.next_experiment`)."""

from __future__ import annotations

import numpy as np


def next_text(result: dict, rows: int = 8) -> str:
    """The plan in words: rivals, measure, noise, the ranked experiments, the best per signal and law."""
    rivals = [" + ".join(r["effects"]) for r in result["rivals"]]
    lines = [
        "Next experiment: to tell " + ", ".join(rivals[:-1]) + " and " + rivals[-1] + " apart "
        f"({result['rivals_rule']})",
        f"Measure: {result['measure']}.",
    ]
    missing = [r for r in result["rivals"] if r.get("heldout_error")]
    if missing:
        lines.append(
            "Misfit: "
            + ", ".join(f"{' + '.join(r['effects'])} misses held-out data by {r['heldout_error']:.2f}" for r in missing)
            + " (RMS over the uncertainties, 1 the noise floor); the plan counts the misfit as a systematic error of "
            "each rival's prediction, so two rivals that both miss the data by more than they differ are not told apart."
        )
    lines += [
        "Noise: "
        + result["noise"]["note"]
        + (
            "; sample noise "
            + ", ".join(
                f"{s.replace('_', ' ')} {v['value']:.2g} ({_short_source(v['source'])})"
                for s, v in result["noise"]["signals"].items()
            )
            if result["noise"]["signals"]
            else ""
        )
        + ".",
        f"  {'rank':<5}{'experiment':<78}{'P':>6}{'n 95%':>7}{'limit':>7}  d per pair (first true/second true)",
    ]
    for k, item in enumerate(result["plan"][:rows], start=1):
        need = "-" if item["decays_for_95"] is None else str(item["decays_for_95"])
        pairs = ", ".join(
            f"{'/'.join(p['rivals'])} {p['separation'][0]:.1f}/{p['separation'][1]:.1f}" for p in item["pairs"]
        )
        lines.append(
            f"  {k:<5}{item['text']:<78}{item['resolution_probability']:>6.2f}{need:>7}{item['limit']:>7.2f}  {pairs}"
        )
    if result.get("best_per_signal"):
        lines.append(
            "  best per signal: "
            + "; ".join(
                f"{s.replace('_', ' ')} {v['resolution_probability']:.2f} at {v['speed']:.2f} m/s"
                for s, v in result["best_per_signal"].items()
            )
        )
    lines.append(
        "  best per law: "
        + "; ".join(
            f"{law} {v['resolution_probability']:.2f} at {v['speed']:.2f} m/s"
            for law, v in result["best_per_law"].items()
        )
    )
    best = result["plan"][0] if result["plan"] else None
    if best is not None:
        if best["decays_for_95"] is not None:
            lines.append(
                f"Recommendation: {best['decays_for_95']} decays at {best['speed']:.2f} m/s under {best['law']}"
                + (
                    f", eigenvalue from the {best['signal'].replace('_', ' ')}"
                    if best["signal"] != "eigenvalue"
                    else ""
                )
                + (f", pushes x{best['push']:g}" if best["push"] != 1 else "")
                + " tell the rivals apart with 95 % probability."
            )
        else:
            lines.append(
                f"Recommendation: no experiment considered reaches 95 % within {result['max_repeats']} decays; the best, "
                f"{best['text']}, reaches {best['resolution_probability']:.2f} (at most {best['limit']:.2f} with any "
                "number of decays: the rivals' own uncertainty and their misfit on held-out data keep it there)."
            )
    if result["left_out"]:
        lines.append(
            f"  {len(result['left_out'])} experiments left out (e.g. {result['left_out'][0]['experiment']}: "
            f"{result['left_out'][0]['reason']})"
        )
    return "\n".join(lines)


def _short_source(source: str) -> str:
    return "data" if source.startswith("the data") else source.split(" ")[0]


def plot_next(plan, result: dict | None = None):
    """Predictions of the rivals diverging over speed (the best plan item's law, signal and push), with
    one standard deviation of each for the planned decays, the data, and the resolution probability
    against speed for every law."""
    from bikerider.gap.report import pyplot

    plt = pyplot()
    result = result or plan.as_dict()
    best = plan.plan[0]["experiment"]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
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
        shown = plan.diagnosis.shown_values()
        taken = ", as the data were taken" if plan.records else ""
        axes[0].plot(e.speed[law_rows], shown.real[law_rows], "k.", ms=4, label=f"measured ({best.law}{taken})")
        axes[1].plot(e.speed[law_rows], shown.imag[law_rows], "k.", ms=4)
    for ax in axes[:2]:
        ax.axvline(best.speed, color="0.3", ls=":", lw=1)
        ax.set_xlabel("speed [m/s]")
        ax.grid(alpha=0.3)
    what = best.describe().replace("decays at", "").split(",", 1)
    axes[0].set_ylabel("weave real part [1/s]")
    axes[1].set_ylabel("weave imaginary part [rad/s]")
    axes[0].set_title(f"predicted under {best.law}" + (f",{what[1]}" if len(what) > 1 else ""), fontsize=9)
    axes[1].set_title(f"bands: 1 sd of the mean of {n} decays", fontsize=9)
    axes[0].legend(fontsize=8)
    # resolution probability against speed, per law (the best signal and push at each speed)
    prob = {}
    for item in plan.plan:
        x = item["experiment"]
        key = (x.law, x.speed)
        prob[key] = max(prob.get(key, 0.0), item["resolution_probability"])
    for k, law in enumerate(plan.laws):
        pts = sorted((s, p) for (name, s), p in prob.items() if name == law)
        if pts:
            s, p = zip(*pts)
            axes[2].plot(s, p, "-o", ms=3, color=colours[k % len(colours)], label=law)
    axes[2].axhline(0.95, color="0.4", ls="--", lw=1)
    axes[2].set_ylim(0, 1.02)
    axes[2].set_xlabel("speed [m/s]")
    axes[2].set_ylabel(f"resolution probability, {n} decays")
    axes[2].set_title("smallest over the pairs of rivals", fontsize=9)
    axes[2].grid(alpha=0.3)
    axes[2].legend(fontsize=7)
    fig.suptitle(
        "Where the rivals disagree: " + ", ".join(r.name for r in plan.rivals) + f" (best: {plan.plan[0]['text']})",
        fontsize=10,
    )
    fig.tight_layout()
    return fig
