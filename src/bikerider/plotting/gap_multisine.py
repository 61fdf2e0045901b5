"""The multisine records of a diagnosis: measured frequency responses against the models' at the lines."""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import NullFormatter, ScalarFormatter

from bikerider.plotting.common import pyplot

MAX_RECORDS = 8
"""Most multisine records drawn (the first ones used); the figure says how many it leaves out."""
SIGNAL_LABELS = {
    "roll_rate": "roll rate [rad/s per N m]",
    "steer_angle": "steer angle [rad per N m]",
    "steer_rate": "steer rate [rad/s per N m]",
    "roll_angle": "roll angle [rad per N m]",
}


def _frf_predictions(diagnosis) -> tuple[np.ndarray, np.ndarray | None]:
    """The nominal model's and the selection's predicted ``H`` of every frequency-response row (complex)."""
    p = diagnosis.problem
    n = len(p.predictor.frf)
    at = slice(len(p.obs) - 2 * n, len(p.obs))
    nominal = p.baseline[at]
    selected = None
    fit = diagnosis.selected_fit
    if fit is not None:
        pred = diagnosis.fits.predictions(tuple(fit.effects))  # time-domain effects simulated per record
        selected = pred[at][0::2] + 1j * pred[at][1::2]
    return nominal[0::2] + 1j * nominal[1::2], selected


def _phase(H: np.ndarray, reference: np.ndarray | None = None) -> np.ndarray:
    """Unwrapped phase [deg], shifted by whole turns to start within half a turn of ``reference``'s start."""
    phase = np.degrees(np.unwrap(np.angle(H)))
    if reference is not None and phase.size:
        phase -= 360.0 * np.round((phase[0] - reference[0]) / 360.0)
    return phase


def plot_multisines(diagnosis):
    """Magnitude and phase of each multisine record's measured frequency response (error bars: two
    standard errors) at its lines, with the nominal model's and the selection's predictions there;
    ``None`` without multisine records used."""
    frf = diagnosis.problem.predictor.frf
    if not len(frf):
        return None
    plt = pyplot()
    records = list(dict.fromkeys(int(r) for r in frf.record))
    shown = records[:MAX_RECORDS]
    signals = list(dict.fromkeys(frf.signal))
    nominal, selected = _frf_predictions(diagnosis)
    rows = 2 * len(signals)
    fig, axes = plt.subplots(
        rows, len(shown), figsize=(2.6 * len(shown) + 1.0, 1.9 * rows + 0.8), squeeze=False, sharex="col"
    )
    label = "+".join(diagnosis.selected) if diagnosis.selected else None
    for col, k in enumerate(shown):
        fit = diagnosis.multisines[k]
        for s, name in enumerate(signals):
            idx = np.flatnonzero((frf.record == k) & np.array([x == name for x in frf.signal]))
            f = frf.omega[idx] / (2 * np.pi)
            H = frf.value[idx]
            err = 2 * frf.sigma[idx]
            mag, pha = axes[2 * s, col], axes[2 * s + 1, col]
            low = np.minimum(err, 0.8 * np.abs(H))  # a log axis: the bar stops above zero
            mag.errorbar(f, np.abs(H), yerr=[low, err], fmt="o", ms=3, color="k", label="measured (2 s.e.)")
            mag.plot(f, np.abs(nominal[idx]), "--", color="0.5", label="nominal")
            measured_phase = _phase(H)
            phase_err = np.degrees(err / np.maximum(np.abs(H), 1e-12))
            pha.errorbar(f, measured_phase, yerr=phase_err, fmt="o", ms=3, color="k")
            pha.plot(f, _phase(nominal[idx], measured_phase), "--", color="0.5")
            if selected is not None:
                mag.plot(f, np.abs(selected[idx]), "-", color="C0", label=label)
                pha.plot(f, _phase(selected[idx], measured_phase), "-", color="C0")
            for ax in (mag, pha):
                ax.set_xscale("log")
                ax.xaxis.set_major_formatter(ScalarFormatter())
                ax.xaxis.set_minor_formatter(NullFormatter())
            mag.set_yscale("log")
            if col == 0:
                mag.set_ylabel(
                    "|"
                    + SIGNAL_LABELS.get(name, name).split(" [")[0]
                    + "|\n["
                    + SIGNAL_LABELS.get(name, "").split("[")[-1],
                    fontsize=7,
                )
                pha.set_ylabel("phase [deg]", fontsize=7)
            for ax in (mag, pha):
                ax.tick_params(labelsize=6)
                ax.grid(alpha=0.3, which="both")
        axes[0, col].set_title(f"{fit.record.name}\n{fit.record.speed:.2f} m/s, {fit.record.law.name}", fontsize=7)
        axes[-1, col].set_xlabel("frequency [Hz]", fontsize=7)
    axes[0, 0].legend(fontsize=6)
    more = f" (the first {len(shown)} of {len(records)})" if len(records) > len(shown) else ""
    fig.suptitle(
        f"Multisine records{more}: measured frequency response from steer torque, and the models' at the lines",
        fontsize=9,
    )
    fig.tight_layout()
    return fig
