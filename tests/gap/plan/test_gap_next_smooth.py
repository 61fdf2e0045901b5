"""The plan's predictions are continuous in speed (issue 25): on a fine speed grid no rival's predicted weave
and no resolution probability jumps by more than the bicycle's own weave moves."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from gap_support import decay_record, nominal, riderless_model

from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.diagnosis.result import diagnose
from bikerider.gap.measured.records import fit_records
from bikerider.gap.measured.tables import CanonicalData, EigenvalueData
from bikerider.gap.plan.ranking import over_speed, plan_next, speed_groups

TRUTH = {"steer_damping": {"c_steer": 0.3}}
RIVALS = ["steer_damping", "tyre_slip"]
SPEEDS = np.linspace(2.8, 4.4, 200)


@pytest.fixture(scope="module", params=["steer logged", "roll rate only"])
def fine_plan(request):
    # records of different lengths and pushes at three speeds (as a lab's windows are): the plan's template
    # must not jump where the nearest record changes, half-way between their speeds; with the roll rate only,
    # the templates span the kick's unknown steer rate (three per experiment) and must not jump either
    model = riderless_model()
    records = []
    for j, (v, duration, push) in enumerate([(3.0, 1.6, 0.5), (3.5, 2.2, 1.0), (4.0, 1.8, 0.7)]):
        for k in range(3):
            initial = {"phid": push * (1 + 0.2 * k), "deltad": 0.4 * push, "delta": 0.03 * push}
            records.append(
                decay_record(
                    model, v, f"{v} m/s", TRUTH, seed=10 * j + k, duration=duration, steer_noise=2e-4, initial=initial
                )
            )
    if request.param == "roll rate only":
        records = [replace(r, signals={"roll_rate": r.signals["roll_rate"]}) for r in records]
    d = diagnose(
        model, EigenvalueData.empty(), CanonicalData.empty(), effects=tuple(RIVALS), records=fit_records(records)
    )
    plan = plan_next(d, rivals=RIVALS, speeds=SPEEDS, signals=["roll_rate"], sweeps=False)
    assert len(plan.kick_rates) == (3 if request.param == "roll rate only" else 1)
    return model, plan


def test_the_data_noise_is_interpolated_between_the_data_speeds():
    speeds = [3.0, 3.01, 2.99, 4.0, 4.02, 5.0]
    assert [sorted(g.tolist()) for g in speed_groups(speeds)] == [[0, 1, 2], [3, 4], [5]]
    curve = over_speed(speeds, [1.0, 1.0, 1.0, 3.0, 3.0, 7.0])
    assert curve(2.0) == 1.0 and curve(3.5) == pytest.approx(1 + 2 * 0.5 / 1.01) and curve(9.0) == 7.0
    assert over_speed(speeds, np.ones(6), least=4) is None


@pytest.mark.slow
def test_predictions_and_odds_are_continuous_in_speed(fine_plan):
    model, plan = fine_plan
    weave = EffectModel(nominal(model), model.geometry)
    prob = plan.probability(plan.repeats).min(axis=0)
    checked = 0
    for law in plan.laws:
        m = [k for k, e in enumerate(plan.points) if e.law == law]
        v = np.array([plan.points[k].speed for k in m])
        if v.size < 20:
            continue
        # the bicycle's own weave over the same grid: how far physics moves between neighbouring speeds
        gains = np.array([plan.laws[law](x) for x in v])
        ev = weave.eigenvalues(v, gains)
        lam = np.array([e[np.argmax(e.imag)] for e in ev])
        neighbours = np.diff(v) < 1.5 * (SPEEDS[1] - SPEEDS[0])
        physics = np.abs(np.diff(lam))[neighbours].max()
        for k in range(len(plan.rivals)):
            steps = np.abs(np.diff(plan.mean[k, m]))[neighbours]
            assert steps.max() < 3 * physics + 1e-3, (law, plan.rivals[k].name, steps.max(), physics)
        noise = np.sqrt(plan.data_cov[m, 1, 1])
        assert np.abs(np.diff(noise))[neighbours].max() < 0.05 * noise.max(), law
        assert np.abs(np.diff(prob[m]))[neighbours].max() < 0.05, law
        checked += 1
    assert checked >= 2
