"""The fits of ``bikerider period``: each trial's rate record with its damped oscillation, and the
residuals beneath, in the bikerider style."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bikerider.plotting.common import WIDTH, new_figure


def period_figure(records, fits, unit: str | None = None):
    """One pair of panels per trial: data and fit (key outside, to the right, off the peaks), and the
    residual (data minus fit) on the same time axis.

    Parameters
    ----------
    records : sequence of (path, time, rate)
        ``time`` [s] and ``rate`` (the file's unit) arrays.
    fits : sequence of DampedOscillationFit
        :func:`bikerider.fitting.damped_oscillation.fit_damped_oscillation` of each record.
    unit : str, optional
        The rate's unit as the file names it (``signal_unit``); ``None``: "as recorded".

    Returns
    -------
    matplotlib.figure.Figure
    """
    n = len(records)
    fig, axes = new_figure(
        width=WIDTH,
        height=2.9 * n + 0.3,
        nrows=2 * n,
        ncols=1,
        squeeze=False,
        gridspec_kw={"height_ratios": [3, 1] * n},
        constrained_layout=True,
    )
    label = f"angular rate [{unit}]" if unit else "angular rate [as recorded]"
    for k, ((path, time, rate), fit) in enumerate(zip(records, fits)):
        ax, res = axes[2 * k, 0], axes[2 * k + 1, 0]
        res.sharex(ax)
        ax.plot(time, rate, ".", ms=2, color="0.55", label="data")
        fine = np.linspace(time[0], time[-1], max(2000, 10 * time.size))
        ax.plot(fine, fit.evaluate(fine), "-", color="#1f77b4", lw=1.1, label="damped oscillation fit")
        ax.set_title(
            f"{Path(path).name}: T = {fit.period:.5f} +/- {fit.period_se:.2g} s, zeta = {fit.zeta:.3g}",
            loc="left",
        )
        ax.set_ylabel(label)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
        ax.tick_params(labelbottom=False)
        residual = rate - fit.evaluate(time)
        res.plot(time, residual, ".", ms=1.5, color="0.35")
        res.axhline(0.0, color="#1f77b4", lw=0.8)
        res.set_ylabel(f"residual [{unit}]" if unit else "residual")
        res.text(
            1.01,
            0.5,
            f"rms {fit.residual_rms:.3g}",
            transform=res.transAxes,
            va="center",
            ha="left",
            fontsize=8,
        )
    axes[-1, 0].set_xlabel("time [s]")
    return fig


__all__ = ["period_figure"]
