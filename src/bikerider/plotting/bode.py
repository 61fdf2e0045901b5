"""Bode diagrams: magnitude and phase from steer torque and a lateral force to roll and steer."""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from bikerider.benchmark.frequency_response import FrequencyResponse, frequency_response
from bikerider.benchmark.model import WhippleModel
from bikerider.benchmark.state_space import LABELS, UNITS, LateralForce
from bikerider.plotting.common import CYCLE, WIDTH, new_figure

OUTPUT_STYLES = {"phi": "-", "delta": "--", "phi_dot": "-.", "delta_dot": ":"}


def plot_bode(
    ax,
    response: FrequencyResponse,
    output: str,
    input: str,
    *,
    phase_ax=None,
    hertz: bool = False,
    label_speeds: bool = True,
):
    """Magnitude (``ax``, dB) and phase (``phase_ax``, degrees) from ``input`` to ``output``, one line
    per speed of ``response``.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``.
    """
    f = response.frequencies / (2 * np.pi) if hertz else response.frequencies
    magnitude = response.magnitude_db(output, input)
    phase = response.phase_deg(output, input)
    style = OUTPUT_STYLES.get(output, "-")
    for k, v in enumerate(response.speeds):
        colour = CYCLE[k % len(CYCLE)]
        ax.semilogx(f, magnitude[k], style, color=colour, label=f"{v:g} m/s" if label_speeds else None)
        if phase_ax is not None:
            phase_ax.semilogx(f, phase[k], style, color=colour)
    unit = f"{UNITS[output]} / {UNITS[input]}"
    ax.set_ylabel(f"magnitude [dB, {unit}]")
    if phase_ax is not None:
        phase_ax.set_ylabel("phase [deg]")
        phase_ax.set_xlabel("frequency [Hz]" if hertz else "frequency [rad/s]")
    else:
        ax.set_xlabel("frequency [Hz]" if hertz else "frequency [rad/s]")
    ax.grid(True, which="both", lw=0.3, color="0.85")
    if phase_ax is not None:
        phase_ax.grid(True, which="both", lw=0.3, color="0.85")
    return ax


def bode_figure(
    model: WhippleModel,
    speeds=(3.0, 5.0, 7.0),
    frequencies=None,
    *,
    lateral_force: LateralForce | None = None,
    title: str = "",
):
    """Bode diagrams from steer torque (left) and, given ``lateral_force``, a lateral force (right)
    to roll (solid) and steer (dashed) at a few speeds (:func:`plot_bode`)."""
    w = np.logspace(-1, 2, 300) if frequencies is None else np.asarray(frequencies, dtype=float)
    inputs = ("T_delta",) if lateral_force is None else ("T_delta", "F")
    response = frequency_response(model, speeds, w, inputs=inputs, lateral_force=lateral_force)
    fig, axes = new_figure(width=WIDTH, height=4.6, nrows=2, ncols=len(inputs), sharex=True, squeeze=False)
    fig.subplots_adjust(left=0.09, right=0.78, wspace=0.42, hspace=0.12, top=0.9, bottom=0.11)
    for j, name in enumerate(inputs):
        for output in ("phi", "delta"):
            plot_bode(axes[0, j], response, output, name, phase_ax=axes[1, j], label_speeds=output == "phi")
        symbol = {"T_delta": "$T_\\delta$", "T_phi": "$T_\\phi$", "F": "$F$"}[name]
        axes[0, j].set_title(f"from {LABELS[name]} {symbol}", loc="left")
    stable = model.stability()
    handles = [Line2D([], [], color=CYCLE[k % len(CYCLE)]) for k in range(len(response.speeds))]
    handles += [Line2D([], [], color="0.2", ls=OUTPUT_STYLES[o]) for o in ("phi", "delta")]
    labels = [f"{v:g} m/s" + (" (self-stable)" if stable.is_stable(v) else "") for v in response.speeds]
    labels += ["to roll angle", "to steer angle"]
    note = (
        ""
        if lateral_force is None
        else (
            f"\n\n$F$ acts at x = {lateral_force.x:.2f} m,\nheight "
            f"{-lateral_force.z:.2f} m ({lateral_force.body} frame)"
        )
    )
    axes[0, -1].legend(handles, labels, loc="upper left", bbox_to_anchor=(1.04, 1.0), borderaxespad=0.0, title=None)
    if note:
        axes[1, -1].text(1.04, 1.0, note.strip(), transform=axes[1, -1].transAxes, va="top", fontsize=7)
    if title:
        fig.suptitle(title, x=0.02, y=0.99, ha="left", va="top", fontsize=9)
        fig.subplots_adjust(top=0.86)
    fig.align_ylabels()
    return fig


__all__ = ["bode_figure", "plot_bode"]
