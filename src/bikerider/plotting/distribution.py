"""Histograms of the weave and capsize speeds over a sample of designs (``sweep --monte-carlo``)."""

from __future__ import annotations

import numpy as np

from bikerider.plotting.common import MODE_COLOURS, new_figure


def speed_distribution_figure(distributions, title: str = ""):
    """One panel per speed: its histogram over the sample, the median and the central 68 % and 95 %
    intervals marked.

    Parameters
    ----------
    distributions : dict
        Name to :class:`bikerider.design.distribution.SpeedDistribution`
        (:func:`bikerider.design.distribution.speed_distributions`).
    title : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    items = list(distributions.values())
    fig, axes = new_figure(height=2.4 * len(items) + 0.6, nrows=len(items))
    axes = np.atleast_1d(axes)
    fig.subplots_adjust(left=0.1, right=0.7, bottom=0.12, top=0.9, hspace=0.55)
    for ax, dist in zip(axes, items):
        mode = dist.name.split("_")[0]
        colour = MODE_COLOURS.get(mode, "0.3")
        label = dist.name.replace("_", " ")
        if not dist.values.size:
            ax.text(0.5, 0.5, f"no valid design has a {label}", transform=ax.transAxes, ha="center", va="center")
            ax.set_yticks([])
            continue
        (a, b), (c, d) = dist.central68, dist.central95
        low, high = np.quantile(dist.values, [0.001, 0.999])  # the far tails would squeeze the rest
        shown = dist.values[(dist.values >= low) & (dist.values <= high)]
        ax.hist(shown, bins=60, color=colour, alpha=0.55, label=f"{dist.count:,} designs")
        ax.axvspan(c, d, color=colour, alpha=0.08, label=f"95 %: {c:.2f}-{d:.2f} m/s")
        ax.axvspan(a, b, color=colour, alpha=0.16, label=f"68 %: {a:.2f}-{b:.2f} m/s")
        ax.axvline(dist.median, color=colour, lw=1.4, label=f"median {dist.median:.2f} m/s")
        ax.set_xlabel(f"{label} [m/s]")
        ax.set_ylabel("designs")
        cut = low > dist.values[0] or high < dist.values[-1]
        note = [f"not drawn: the 0.1 % at each end\n(below {low:.2f}, above {high:.2f} m/s)"] if cut else []
        ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7, frameon=False, title=None)
        if note:
            ax.text(1.02, 0.0, note[0], transform=ax.transAxes, fontsize=7, style="italic", color="0.25")
    if title:
        axes[0].set_title(title, loc="left")
    return fig


__all__ = ["speed_distribution_figure"]
