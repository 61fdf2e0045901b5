"""A record fit that lands on an alias above the samples' Nyquist frequency is no weave.

The record (``tests/data/gap_alias_record.csv``) is the calibration study's seed 1108 (tyre_slip), its run at
4.49 m/s: 270 samples at 100 Hz of a simulated roll rate with its noise. The plain damped-oscillation fit,
whose bounds reach twice the Nyquist frequency, found 626 rad/s there, and the record was used: every
candidate's refit of its own response then had to reach that alias, and where one did not (a model whose
response the refit follows to its weave) its prediction lay 620 rad/s from the record, a chi-square of
2.6e8 (the tyre fit of the trial went to its bounds: cornering stiffness 200 /rad for a hidden 15.6).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bikerider.errors import FitError
from bikerider.fitting.damped_oscillation import fit_damped_oscillation
from bikerider.gap.measured.extraction import nyquist_frequency, weave_eigenvalue

RECORD = Path(__file__).parents[2] / "data" / "gap_alias_record.csv"


def _record() -> tuple[np.ndarray, np.ndarray]:
    data = np.loadtxt(RECORD, delimiter=",", skiprows=1)
    return data[:, 0], data[:, 1]


def test_the_plain_fit_reaches_an_alias_above_the_nyquist_frequency():
    t, y = _record()
    nyquist = nyquist_frequency(t[-1] - t[0], t.size)
    assert nyquist == pytest.approx(np.pi / 0.01)
    assert fit_damped_oscillation(t, y, drift=True).omega_d > nyquist  # 626 rad/s


def test_the_record_fit_refuses_it():
    t, y = _record()
    with pytest.raises(FitError, match="no oscillation found|cycles"):
        weave_eigenvalue(t, y)
