"""python-control's layouts beside bikerider's own (issue 24): ``Simulation.x``/``y``/``t`` and
``FrequencyResponse.magnitude``/``phase``/``omega``, as ``TimeResponseData`` and
``FrequencyResponseData`` have them."""

from __future__ import annotations

import numpy as np
import pytest

import bikerider
from bikerider.shipped import named


@pytest.fixture(scope="module")
def model():
    return bikerider.WhippleModel.from_parameters(named("Benchmark"))


def test_simulation_states_state_first_as_python_control(model):
    times = np.linspace(0, 2, 41)
    run = bikerider.simulate(model, [3.0, 5.0], times, initial_state=[0.05, 0, 0, 0])
    assert run.states.shape == (2, 41, 4)  # bikerider: time before state (documented)
    assert run.x.shape == (2, 4, 41) and run.y.shape == (2, run.outputs.shape[-1], 41)
    np.testing.assert_array_equal(run.x[1][0], run.states[1, :, 0])  # roll angle over time at 5 m/s
    np.testing.assert_array_equal(run.y[0][:, 7], run.outputs[0, 7])
    assert run.t is run.times


def test_frequency_response_magnitude_is_absolute_and_phase_radians(model):
    w = np.logspace(-1, 2, 50)
    bode = bikerider.frequency_response(model, [3.0, 5.0], w, inputs=("T_delta",))
    g = bode.select("phi", "T_delta")  # (speeds, frequencies)
    assert bode.magnitude.shape == (2, 2, 1, 50)  # speeds, outputs, inputs, frequencies (last)
    np.testing.assert_allclose(bode.magnitude[:, 0, 0, :], np.abs(g), rtol=0, atol=0)
    np.testing.assert_allclose(20 * np.log10(bode.magnitude[:, 0, 0, :]), bode.magnitude_db("phi", "T_delta"))
    np.testing.assert_allclose(np.exp(1j * bode.phase[:, 0, 0, :]), g / np.abs(g), atol=1e-12)
    # unwrapped: the same turning as phase_deg, up to whole turns
    turns = (np.degrees(bode.phase[:, 0, 0, :]) - bode.phase_deg("phi", "T_delta")) / 360.0
    np.testing.assert_allclose(turns, np.round(turns), atol=1e-9)
    assert np.all(np.abs(np.diff(bode.phase, axis=-1)) < np.pi)
    assert bode.omega is bode.frequencies
