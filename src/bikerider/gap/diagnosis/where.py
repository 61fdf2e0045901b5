"""Where and whether: the gap map by mode, speed band and quantity, the test of the whole gap, and the
verdict with the parameter test (module docstring of :mod:`bikerider.gap.diagnosis.result`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bikerider.gap.candidates.effects import PARAMETERS
from bikerider.gap.diagnosis.folds import N_SPEED_BANDS
from bikerider.gap.diagnosis.statistics import ALPHA, rms
from bikerider.gap.distributions import chi2
from bikerider.gap.inference.low_rank import low_rank_chi2
from bikerider.gap.inference.problem import EffectFit, GapProblem


@dataclass(frozen=True)
class Whether:
    """The verdict and, where the benchmark parameters were fitted, their test.

    Attributes
    ----------
    verdict : str
        ``none``, ``parameters`` or ``structural``.
    parameter_test : dict or None
        The parameter fit's chi-square (data plus prior), its degrees of freedom and p-value, and the
        prior's share (``None`` without a parameter fit).
    """

    verdict: str
    parameter_test: dict | None


def gap_map(p: GapProblem) -> list[dict]:
    """The normalised residuals summarised per cell (mode or canonical entry, speed band, quantity),
    each with its chi-square, p-value and significance (Bonferroni over the cells)."""
    obs = p.obs
    z = -p.z(p.baseline)  # measured minus model, normalised
    eig_speeds = np.unique(obs.speed[[k == "eigenvalue" for k in obs.kind]])
    bands = np.array_split(eig_speeds, min(N_SPEED_BANDS, eig_speeds.size)) if eig_speeds.size else []
    # multisine records: bands of their speeds to 0.1 m/s (a run's mean speed scatters)
    frf_speeds = np.unique(np.round(obs.speed[[k == "frf" for k in obs.kind]], 1))
    frf_bands = np.array_split(frf_speeds, min(N_SPEED_BANDS, frf_speeds.size)) if frf_speeds.size else []
    cells = []
    keys = []
    for i in range(len(obs)):
        if obs.kind[i] in ("eigenvalue", "frf"):
            v = obs.speed[i] if obs.kind[i] == "eigenvalue" else round(float(obs.speed[i]), 1)
            band = next(b for b in (bands if obs.kind[i] == "eigenvalue" else frf_bands) if b[0] <= v <= b[-1])
            band_key = (float(band[0]), float(band[-1]))
        else:
            band_key = tuple(float(x) for x in p.predictor.canonical.speed_range[obs.group[i]])
        key = (
            (obs.mode[i], band_key, obs.quantity[i])
            if obs.kind[i] in ("eigenvalue", "frf")
            else ("canonical", band_key, f"{obs.quantity[i]} ({obs.group[i]})")
        )
        keys.append(key)
    unique = list(dict.fromkeys(keys))
    for key in unique:
        idx = [i for i, k in enumerate(keys) if k == key]
        zz = z[idx]
        stat = float(np.sum(zz**2))
        pval = float(chi2.sf(stat, len(idx)))
        cells.append(
            {
                "mode": key[0],
                "speed_band": list(key[1]),
                "quantity": key[2],
                "n": len(idx),
                "mean_residual": float(np.mean(p.y[idx] - p.baseline[idx])),
                "mean_measured": float(np.mean(p.y[idx])),
                "mean_predicted": float(np.mean(p.baseline[idx])),
                "combined_sigma": float(np.sqrt(np.mean(p.var_total[idx]))),
                "data_sigma": float(np.sqrt(np.mean(p.var_data[idx]))),
                "model_sigma": float(np.sqrt(np.mean(p.var_model[idx]))),
                "rms_z": rms(zz),
                "chi2": stat,
                "p_value": pval,
                "significant": bool(pval < ALPHA / max(len(unique), 1)),
                **_data_only_cell(p, idx, ALPHA / max(len(unique), 1)),
            }
        )
    return cells


def gap_test(p: GapProblem) -> dict:
    """The whole gap's chi-square against the combined uncertainty of data and parameters, and against
    the data's alone."""
    r = p.y - p.baseline
    stat, n = low_rank_chi2(r, p.var_data, p.jacobian)  # r^T (D + J J^T)^-1 r in linear time
    if np.all(p.var_data > 0):
        data_stat = float(np.sum(r**2 / p.var_data))
    else:  # rows taken as exact: any residual is a gap against the data alone
        data_stat = (
            math.inf
            if np.any(r[p.var_data <= 0] != 0)
            else float(np.sum(r[p.var_data > 0] ** 2 / p.var_data[p.var_data > 0]))
        )
    return {
        "chi2": stat,
        "dof": n,
        "p_value": float(chi2.sf(stat, n)),
        "rms_z": rms(-p.z(p.baseline)),
        "significant": bool(chi2.sf(stat, n) < ALPHA),
        "data_only": {
            "chi2": data_stat,
            "p_value": float(chi2.sf(data_stat, n)),
            "significant": bool(chi2.sf(data_stat, n) < ALPHA),
        },
    }


def whether(test: dict, parameter_fit: EffectFit | None, p: GapProblem) -> Whether:
    """The verdict (module docstring of :mod:`bikerider.gap.diagnosis.result`) from the gap test and the
    fit of the benchmark parameters (``None`` when they are not a candidate)."""
    parameter_test = None
    if parameter_fit is not None:
        stat = parameter_fit.chi2 + parameter_fit.prior_chi2
        parameter_test = {
            "chi2": stat,
            "dof": parameter_fit.n,
            "p_value": float(chi2.sf(stat, parameter_fit.n)),
            "prior_chi2": parameter_fit.prior_chi2,
            "prior_dof": len(p.free),
        }
    if not test["significant"]:
        # within the combined uncertainty: no gap at all, or one the parameters' uncertainty covers
        return Whether(PARAMETERS if test["data_only"]["significant"] and p.free else "none", parameter_test)
    if parameter_test is None:
        return Whether("structural", None)
    verdict = PARAMETERS if chi2.sf(parameter_test["chi2"], parameter_fit.n) >= ALPHA else "structural"
    return Whether(verdict, parameter_test)


def _data_only_cell(problem: GapProblem, idx: list[int], alpha: float) -> dict:
    """A gap-map cell's RMS residual and significance against the data's uncertainty alone."""
    var = problem.var_data[idx]
    if not np.all(var > 0):
        return {"rms_z_data": None, "significant_data": None}
    z = (problem.y[idx] - problem.baseline[idx]) / np.sqrt(var)
    return {"rms_z_data": rms(z), "significant_data": bool(chi2.sf(float(np.sum(z**2)), len(idx)) < alpha)}
