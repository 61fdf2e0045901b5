"""Records' initial states in the time domain (gap/inference/timedomain.py: ``initial_states``).

A record holding the roll rate alone hardly sees some directions of its initial state (at 6 m/s under the
steer-into-lean law, one at 4.7e-4 of the largest singular value of its design).  Solved by normal equations
with a 1e-12 ridge, the gyro's noise pushed the state along them to four times its true size (0.6 rad/s
true, 1.1 to 2.3 fitted), and such states drove the nonlinear friction simulation and the friction fit's
split in the calibration's ``steer_coulomb`` trials.  Those directions are now left out
(:data:`~bikerider.gap.inference.timedomain.STATE_RCOND`): the state stays the size of the true one, and the
fitted response still matches the record.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from gap_support import decay_record, nominal, riderless_model

from bikerider.gap.inference import timedomain as TD

NOISE = 0.01
"""Gyro noise of the records [rad/s]."""
TRUE_SIZE = 0.6
"""The largest component of the records' initial state (``phid`` 0.6 rad/s, ``deltad`` 0.3 rad/s)."""


def _batch(speed: float, roll_rate_only: bool):
    model = riderless_model()
    records = []
    for seed in range(4):
        r = decay_record(model, speed, f"{speed} m/s", seed=seed, duration=2.5, noise=NOISE)
        records.append(replace(r, signals={"roll_rate": r.signals["roll_rate"]}) if roll_rate_only else r)
    ((_, batch),) = TD.make_batches(records, min_step=TD.FIT_STEP)
    layout = TD.Layout.of(("steer_friction",))
    A, _, outputs, _ = TD.systems(nominal(model), model.geometry, batch.records, layout, np.zeros((1, 2)))
    return batch, A[0], outputs


def _roll_rate_fit(batch, A, outputs, x0):
    """Each record's fitted roll rate (the state's response plus the best offset) and its RMS residual."""
    states = TD.simulate_linear(A, x0, batch.dt, batch.N)
    sim = states[..., outputs[TD.OBSERVED["roll_rate"]]]
    y = batch.y["roll_rate"]
    mask = np.arange(batch.N)[None, :] < batch.length[:, None]
    offset = np.nanmean(np.where(mask, y - sim, np.nan), axis=1)
    rms = np.sqrt(np.nanmean(np.where(mask, (sim + offset[:, None] - y) ** 2, np.nan), axis=1))
    return sim + offset[:, None], rms


def test_a_roll_rate_only_records_state_is_not_its_noise_along_a_direction_it_hardly_sees(monkeypatch):
    batch, A, outputs = _batch(6.0, roll_rate_only=True)
    design, _ = TD._stack(batch, TD._transitions(A, batch.dt, batch.N), outputs)
    s = np.linalg.svd(design, compute_uv=False)
    assert np.all(s[:, -2] / s[:, 0] < TD.STATE_RCOND)  # a direction (beside the absent steer offset) unseen
    x0 = TD.initial_states(batch, A, outputs)
    assert np.max(np.abs(x0)) < 1.5 * TRUE_SIZE  # bounded: the state's size, not the noise's reach
    fitted, rms = _roll_rate_fit(batch, A, outputs, x0)
    assert np.all(rms < 1.1 * NOISE)  # the response still matches the record to its noise
    # every direction fitted (rcond 1e-6, about where the normal equations' 1e-12 ridge acted before): the
    # state four times its size for a residual no smaller than the noise's
    monkeypatch.setattr(TD, "STATE_RCOND", 1e-6)
    full = TD.initial_states(batch, A, outputs)
    assert np.max(np.abs(full)) > 3 * TRUE_SIZE
    _, rms_full = _roll_rate_fit(batch, A, outputs, full)
    np.testing.assert_allclose(rms, rms_full, rtol=0.02)  # the left-out direction bought nothing
    with pytest.raises(ValueError, match="1e-6"):  # below that the Gram matrix cannot tell the directions
        TD._solve(design, batch.y["roll_rate"][:, :1], rcond=1e-8)


@pytest.mark.parametrize("speed", [3.0, 6.0])
def test_a_record_with_the_steer_angle_is_fitted_as_by_full_least_squares(speed, monkeypatch):
    # every direction seen: the truncated solve is the full least squares
    batch, A, outputs = _batch(speed, roll_rate_only=False)
    x0 = TD.initial_states(batch, A, outputs)
    monkeypatch.setattr(TD, "STATE_RCOND", 1e-6)
    np.testing.assert_allclose(x0, TD.initial_states(batch, A, outputs), rtol=1e-9, atol=1e-12)
    assert np.max(np.abs(x0)) < 1.5 * TRUE_SIZE
