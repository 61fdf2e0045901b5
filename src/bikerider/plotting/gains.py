"""Control gains against speed: a law's four gains on the steer torque, one panel each (as
BicycleParameters' ``plot_gains`` draws a feedback model's gains)."""

from __future__ import annotations

import numpy as np

from bikerider.benchmark.control import GAIN_NAMES, GAIN_UNITS, ControlLaw
from bikerider.plotting.common import new_figure

GAIN_LABELS = {
    "k_phi": r"$k_\phi$ (roll angle)",
    "k_phid": r"$k_{\dot\phi}$ (roll rate)",
    "k_delta": r"$k_\delta$ (steer angle)",
    "k_deltad": r"$k_{\dot\delta}$ (steer rate)",
}


def gains_figure(laws, speeds=None, title: str = "", stable=None, stable_label: str = "closed loop stable"):
    """The gains of one or more control laws against speed.

    Parameters
    ----------
    laws : ControlLaw or sequence of ControlLaw
        Laws of :mod:`bikerider.benchmark.control` (an LQR schedule: :func:`bikerider.lqr_law`).
    speeds : array_like, optional
        Speeds [m/s] to draw over (0-10 m/s by default).
    title : str
    stable : sequence of (float, float), optional
        Speed intervals to shade (where the closed loop is stable: ``closed_loop(...).stability()``).
    stable_label : str
        The legend entry of the shading.

    Returns
    -------
    matplotlib.figure.Figure
        Four panels, ``T_delta = k_phi phi + k_phid phi_dot + k_delta delta + k_deltad delta_dot``.
    """
    laws = [laws] if isinstance(laws, ControlLaw) else list(laws)
    v = np.linspace(0.0, 10.0, 401) if speeds is None else np.asarray(speeds, dtype=float)
    fig, axes = new_figure(height=5.6, nrows=4, sharex=True)
    fig.subplots_adjust(left=0.12, right=0.78, bottom=0.09, top=0.93, hspace=0.15)
    for j, (ax, name) in enumerate(zip(axes, GAIN_NAMES)):
        for law in laws:
            ax.plot(v, law(v)[:, j], lw=1.4, label=law.name)
        ax.axhline(0.0, color="0.3", lw=0.6, zorder=0)
        for lo, hi in stable or ():
            lo, hi = max(lo, v[0]), min(hi, v[-1])
            if hi > lo:
                ax.axvspan(lo, hi, color="#e6f2e6", zorder=-1, label=stable_label if j == 0 else None)
        ax.set_ylabel(f"{GAIN_LABELS[name]}\n[{GAIN_UNITS[name]}]", fontsize=8)
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)
    axes[-1].set_xlabel("speed $v$ [m/s]")
    axes[-1].set_xlim(v[0], v[-1])
    if title:
        axes[0].set_title(title, loc="left")
    return fig


__all__ = ["gains_figure"]
