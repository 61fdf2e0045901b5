"""A friction rival's decays as a new record's fit finds them (issue 25, smooth predictions): from the kick that
starts the template, and over the record fit's valleys.

On the steer-by-wire plan the friction rival's predicted weave jumped over speed (5.3 to 8.2 rad/s between 2.9
and 3.4 m/s): its initial state was fitted under friction to the nominal model's template (a fit with more than
one valley) and its response refitted from the template's own fit alone (the nominal model's, another valley
where the friction's response is far from it).  Now the rival is simulated from the template's kick and the
refit also starts from the record fit's own scan, the deepest ends mixed by the chance that noise picks each."""

from __future__ import annotations

import numpy as np
import pytest
from gap_support import nominal, riderless_model
from test_gap_next_kick import RIVALS, friction_diagnosis

from bikerider.gap.candidates.effect_model import EffectModel
from bikerider.gap.inference.indirect import FitItem, RecordBatch, extract, extract_runs
from bikerider.gap.inference.timedomain import Layout
from bikerider.gap.plan import ranking

DT, N = 0.01, 400


def _batch(start_omega: float) -> RecordBatch:
    """One record of one signal, fitted with the two-mode function from a start at ``start_omega``."""
    start = np.array([start_omega, 0.5, 0.0, 0.0, 0.0, 0.0, -1.0])
    return RecordBatch(
        np.array([0]),
        DT,
        np.array([N]),
        ("roll_rate",),
        np.zeros((1, N, 1)),
        np.zeros((1, 1)),
        [FitItem(0, 0, "two-mode", start, 1 + 1j)],
    )


def _blend(alpha: np.ndarray) -> np.ndarray:
    """Signals ``(P, 1, N, 1)`` sliding from a decay at 4 rad/s to one at 7 rad/s: the two-mode fit holds one
    oscillation, so it has a valley at each, the deeper one changing where the two are about as strong."""
    t = np.arange(N) * DT
    slow, fast = np.exp(-0.5 * t) * np.sin(4.0 * t), np.exp(-0.5 * t) * np.sin(7.0 * t)
    return ((1 - alpha)[:, None] * slow + alpha[:, None] * fast)[:, None, :, None]


def test_a_new_records_fit_moves_continuously_between_valleys_where_one_start_jumps():
    alpha = np.linspace(0.0, 1.0, 101)
    sim = _blend(alpha)
    one = extract(_batch(4.0), sim)[0][:, 0]
    mean, cov = extract_runs(_batch(4.0), sim, np.array([0.3]))
    mean, sd = mean[:, 0], np.sqrt(cov[:, 0, 1, 1])
    # at either end the signal is one decay: every start finds it, no spread from run to run
    assert mean[0] == pytest.approx(-0.5 + 4.0j, abs=1e-6) and mean[-1] == pytest.approx(-0.5 + 7.0j, abs=1e-6)
    assert sd[0] == pytest.approx(0.0, abs=1e-6) and sd[-1] == pytest.approx(0.0, abs=1e-6)
    # the fit from the 4 rad/s start alone jumps most of the distance between the valleys in one step
    assert np.max(np.abs(np.diff(one.imag))) > 2.0
    # over noisy records' fits the mean moves from one valley to the other in steps of less than half of it, and
    # where the valleys are about as deep the run-to-run spread is of the size of their distance
    assert np.max(np.abs(np.diff(mean.imag))) < 1.5
    middle = int(np.argmax(sd))
    assert 0.3 < alpha[middle] < 0.7 and sd[middle] > 1.5
    # noise decides between close valleys: without it the deeper wins outright, a step of most of the distance
    sharp, _ = extract_runs(_batch(4.0), sim, np.array([1e-9]))
    assert np.max(np.abs(np.diff(sharp[:, 0].imag))) > 2.5


@pytest.fixture(scope="module")
def steered():
    return friction_diagnosis(steer=True)


@pytest.mark.slow
def test_a_friction_rival_without_friction_runs_from_the_templates_kick_as_the_nominal_model(steered):
    plan = ranking.plan_next(steered, rivals=RIVALS, speeds=[3.5, 4.0, 4.5], signals=["roll_rate"], sweeps=False)
    simulator = plan.simulator
    assert simulator.kicks is not None and simulator.kicks.shape == (len(simulator), 4)
    layout = Layout.of(("steer_friction",))
    # no friction: the rival is the nominal model, started from the kick the template was simulated from, so its
    # response is the template's own (noise-free) signals
    for batch, response in simulator._friction_responses(layout, np.zeros((1, 2)), None, kicked=True):
        seen = batch.mask[..., None] & np.ones(len(batch.signals), bool)
        assert np.max(np.abs(response[0] - batch.y)[seen]) < 1e-9 * np.max(np.abs(batch.y))
    # and the record fit finds in it what it finds in the template, to the refit's precision from other starts
    quiet = {name: 1e-12 for name in plan.sample_noise}  # no noise: the deepest valley alone
    mean, cov = simulator.time_domain_runs(layout, np.zeros((1, 2)), quiet)
    nominal = simulator.apparent()
    assert np.all(np.isfinite(mean))
    assert np.max(np.abs(mean - nominal) / np.abs(nominal)) < 1e-3
    assert np.all(np.abs(cov) < 1e-9)


@pytest.mark.slow
def test_a_friction_rivals_decays_at_the_datas_push_move_with_speed_as_the_weave_does(steered):
    # a fine grid: the rival's prediction at the data's push moves by steps of the bicycle's own weave; before it
    # was simulated from the template's kick and refitted from the record fit's scan it jumped (on this case by
    # 0.24 rad/s, 18 times the weave's largest step, several times one run's spread)
    grid = np.round(np.arange(3.5, 4.5001, 0.02), 2)
    plan = ranking.plan_next(steered, rivals=RIVALS, speeds=grid, signals=["roll_rate"], sweeps=False)
    friction = next(k for k, r in enumerate(plan.rivals) if r.nonlinear)
    m = [k for k, e in enumerate(plan.points) if e.law == "sil" and e.push == 1.0]
    v = np.array([plan.points[k].speed for k in m])
    assert v.size > 40
    # the bicycle's own weave over the same grid: how far physics moves between neighbouring speeds
    model = riderless_model()
    eigenvalues = EffectModel(nominal(model), model.geometry).eigenvalues(v, np.array([plan.laws["sil"](x) for x in v]))
    weave = np.abs(np.diff([e[np.argmax(e.imag)] for e in eigenvalues]))
    steps = np.abs(np.diff(plan.mean[friction, m]))
    # where a valley of the record fit comes within reach of its scan's starts or leaves it, the mean moves by a
    # part of the run-to-run spread it brings (a few hundredths of a rad/s here): within half of one run's spread
    run = np.sqrt((plan.data_cov[m] + plan.kick_cov[friction, m])[:, [0, 1], [0, 1]])  # (n, 2): real, imaginary
    allowed = 3 * weave.max() + 0.5 * np.hypot(*np.minimum(run[1:], run[:-1]).T)
    assert np.all(steps < allowed), (steps.max(), weave.max(), float(np.median(allowed)))
