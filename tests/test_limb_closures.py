"""The knee and elbow closures bend naturally for every direction of the limb (issue 12's audit).

The branch rule of ``derive/rider_model.py`` turns the limb's direction a quarter turn, the same way
for every direction, so the joint is always on the flexion side.  These tests check that with a
criterion of their own - the sign of the turn from the proximal segment to the distal one, which a
human knee or elbow moving in the sagittal plane keeps whatever the limb's direction - on riders
the project used to refuse (hands behind the shoulders) and on random riders and bicycles.  They
also pin what happens at full stretch: no NaN and no LinAlgError, first-order sigmas withheld with
a note, and Monte Carlo sigmas given.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import replace

import numpy as np
import pytest
from strategies import paper_inputs, run_cli

from bikerider.errors import InputError, ReachError
from bikerider.estimate import default_files, estimate
from bikerider.quantity import Quantity
from bikerider.rider.model import seat_rider

HIP, FOOT, KNEE, HAND, SHOULDER, ELBOW = 12, 4, 13, 18, 20, 22  # grid points 13, 5, 14, 19, 21, 23 (0-based)
TABLE_1 = ("h_bb", "l_cs", "l_f", "rF", "l_hb", "lam_ht", "rR", "l_sp", "lam_st", "l_st", "l_s", "c", "w")


def _turn(proximal: np.ndarray, joint: np.ndarray, distal: np.ndarray) -> float:
    """The z-x cross product of (joint - proximal) and (distal - joint): the sense in which the
    limb turns at the joint, seen from the rider's right (y) side."""
    a, b = joint - proximal, distal - joint
    return float(a[2] * b[0] - a[0] * b[2])


@pytest.fixture(scope="module")
def paper_senses():
    """The senses of flexion of the paper's rider (knees ahead of the legs, elbows below the arms)."""
    bicycle, rider = paper_inputs()
    p = seat_rider(bicycle, rider).grid_points
    return np.sign(_turn(p[HIP], p[KNEE], p[FOOT])), np.sign(_turn(p[SHOULDER], p[ELBOW], p[HAND]))


def _with_bicycle(bicycle, **changes):
    return replace(bicycle, values={**bicycle.values, **{k: Quantity(v) for k, v in changes.items()}})


def test_hands_behind_the_shoulders_are_seated_with_the_elbow_bent_naturally(paper_senses):
    """Swept-back bars put the grips 6 cm behind the shoulders; this rider was refused before
    ("a forward lean that keeps the shoulders behind the hands")."""
    bicycle, rider = paper_inputs()
    swept = _with_bicycle(bicycle, l_hb=0.60)  # grips at x = 0.173 m, shoulders at x = 0.235 m
    p = seat_rider(swept, rider).grid_points
    assert p[HAND][0] < p[SHOULDER][0]  # the case in question
    assert np.sign(_turn(p[SHOULDER], p[ELBOW], p[HAND])) == paper_senses[1]
    # The elbow points back: behind both the shoulder and the hand, the upper arm and forearm at
    # their lengths (Table 7: l_ua = 0.28 m, l_la = 0.33 m).
    assert p[ELBOW][0] < min(p[HAND][0], p[SHOULDER][0])
    assert np.linalg.norm(p[ELBOW] - p[SHOULDER]) == pytest.approx(0.28, rel=1e-12)
    assert np.linalg.norm(p[ELBOW] - p[HAND]) == pytest.approx(0.33, rel=1e-12)
    result = estimate(swept, rider)
    assert all(v is None or math.isfinite(v) for v in result.parameters.values.values())


def test_random_riders_and_bicycles_bend_naturally_or_are_refused_for_reach(paper_senses):
    """Every Table 1 and Table 7 measurement within +/-20 % of the paper's (the audit's draw): a
    rider is either seated with both joints on the flexion side, or refused because a limb cannot
    reach or close - never for the direction of a limb."""
    bicycle, rider = paper_inputs()
    rng = np.random.default_rng(12)
    seated = behind = seated_behind = 0
    for _ in range(400):
        try:
            b = _with_bicycle(bicycle, **{k: bicycle[k] * rng.uniform(0.8, 1.2) for k in TABLE_1})
            r = replace(rider, values={k: Quantity(q.value * rng.uniform(0.8, 1.2)) for k, q in rider.values.items()})
        except InputError:  # measurements no body or frame can have (e.g. a chest narrower than the torso)
            continue
        try:
            p = seat_rider(b, r).grid_points
        except ReachError:
            continue
        seated += 1
        hands_behind = p[HAND][0] < p[SHOULDER][0]
        behind += hands_behind
        assert np.sign(_turn(p[HIP], p[KNEE], p[FOOT])) == paper_senses[0]
        assert np.sign(_turn(p[SHOULDER], p[ELBOW], p[HAND])) == paper_senses[1]
        seated_behind += hands_behind
    assert seated > 100 and seated_behind > 5, (seated, seated_behind)  # such riders exist and are seated


@pytest.mark.parametrize("direction", np.linspace(0, 2 * math.pi, 13)[:-1])
def test_the_generated_elbow_turns_the_same_way_for_every_direction_of_the_arm(direction, paper_senses):
    """The generated elbow stage alone, with the hand placed all round the shoulder."""
    from bikerider.generated import rider_model as gen

    bicycle, rider = paper_inputs()
    p = seat_rider(bicycle, rider).grid_points
    span = 0.5
    hand = p[SHOULDER] + span * np.array([math.cos(direction), 0.0, math.sin(direction)])
    points = _grid_with_hand(gen, bicycle, rider, hand)
    assert np.sign(_turn(points[SHOULDER], points[ELBOW], points[HAND])) == paper_senses[1]


def _grid_with_hand(gen, bicycle, rider, hand):
    """The grid points with the right hand moved to ``hand`` (through the stem length and the
    handlebar length, which place it: x = r16x - l_hb, z = r12z - l_s sin(lam_ht))."""
    from bikerider.rider.model import _GRID, model_arguments

    args = {k: v for k, v in model_arguments(bicycle, rider).items() if k in _GRID}
    base = np.asarray(gen.grid_points(**args))
    # Move the hand by changing l_s (along the head tube) and l_hb (along x).
    lam = args["lam_ht"]
    dz = hand[2] - base[HAND][2]
    l_s = args["l_s"] - dz / math.sin(lam)
    x16 = base[15][0] + (args["l_s"] - l_s) * math.cos(lam)
    l_hb = x16 - hand[0]
    moved = np.asarray(gen.grid_points(**{**args, "l_s": l_s, "l_hb": l_hb}))
    assert np.allclose(moved[HAND][[0, 2]], hand[[0, 2]], atol=1e-12)
    return moved


# ------------------------------------------------------------------------------------------
# Full stretch: exactly straight, or 1e-13 m short (inside the 1e-12 tolerance)
# ------------------------------------------------------------------------------------------
def _straight_rider(tmp_path, limb: str, short: float):
    """The paper's rider with the lower leg or lower arm set so the limb spans exactly its distance
    (minus ``short`` metres), written as a rider file."""
    from bikerider.generated import rider_model as gen

    from bikerider.engine import arguments
    from bikerider.rider.model import model_arguments

    bicycle, rider = paper_inputs()
    args = model_arguments(bicycle, rider)
    leg_span, _, arm_span, _ = (
        float(x) for x in gen.limb_reach(**{k: args[k] for k in arguments("rider_model.limb_reach")})
    )
    key, other, span = ("l_la", 0.28, arm_span) if limb == "arm" else ("l_ll", 0.46, leg_span)
    text = default_files()[1].read_text()
    text = re.sub(rf"^{key} = [0-9.]+", f"{key} = {span - other - short!r}", text, flags=re.M)
    path = tmp_path / f"{limb}_{short}.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("short", [0.0, 1e-13])
@pytest.mark.parametrize("limb", ["arm", "leg"])
def test_a_limb_at_full_stretch_gets_monte_carlo_sigmas_and_a_warning(tmp_path, limb, short):
    """Before: LinAlgError from the eigenvalue sigmas, or every rider-dependent sigma dropped without
    a word.  Now: first-order sigmas withheld with a note, Monte Carlo sigmas given, the lost
    samples (about half: half the draws cannot reach) counted."""
    path = _straight_rider(tmp_path, limb, short)
    code, out, err = run_cli(["estimate", "--rider", str(path), "--json"])
    assert code == 0, err
    data = json.loads(out)
    speeds = data["uncertainty"]["speeds"]
    assert 0.1 < speeds["weave"] < 2.0 and 0.1 < speeds["capsize"] < 5.0  # Monte Carlo
    assert data["uncertainty"]["first_order"]["speeds"] == {"weave": None, "capsize": None}
    assert data["uncertainty"]["benchmark"]["xB"] is not None  # the Monte Carlo sigma, not dropped
    notes = " ".join(data["notes"])
    assert f"the {limb}s are straight" in notes
    assert "first order gives no sigma" in notes
    closure = "elbow closure" if limb == "arm" else "knee closure"
    lost = data["uncertainty"]["monte_carlo"]["failures"][closure]
    assert 0.4 < lost / data["uncertainty"]["monte_carlo"]["samples"] < 0.6
    code, out, _ = run_cli(["estimate", "--rider", str(path)])
    assert code == 0 and "Weave speed" in out and "first order: not defined here" in out


def test_just_off_full_stretch_first_order_is_flagged_not_trusted(tmp_path):
    """A slack of 1e-12 m (outside the tolerance): first order gives sigmas hundreds of times too
    large (the closure's derivative grows without bound); the headline is Monte Carlo's and the
    text says first order does not hold."""
    path = _straight_rider(tmp_path, "arm", -1e-12)
    code, out, _ = run_cli(["estimate", "--rider", str(path), "--json"])
    data = json.loads(out)
    weave = data["uncertainty"]["monte_carlo"]["sigmas"]["v_weave"]
    assert weave["first_order"] > 50 * weave["monte_carlo"] and not weave["first_order_holds"]
    assert data["uncertainty"]["speeds"]["weave"] == weave["monte_carlo"]
    assert any(note.startswith("first order does not hold for") for note in data["notes"])
