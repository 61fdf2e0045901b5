"""The plan's figure (``bikerider.plotting.gap_plan``): each law's resolution probability against speed follows one
signal and push (solid), so that its curve moves with the speed alone; the best of any signal and push at each
speed is drawn apart (dotted), never below it.  Taking the best at each speed for the solid curve made it jump
wherever the best signal or push changed, which a reader took for numerical noise."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.colors import to_hex
from test_gap_next_kick import RIVALS, friction_diagnosis

from bikerider.gap.plan.ranking import plan_next
from bikerider.plotting.common import pyplot
from bikerider.plotting.gap_plan import plot_next


@pytest.fixture(scope="module")
def friction_plan():
    """Decays of a bicycle with steer friction (roll rate and steer angle logged) planned against tyre slip: four
    laws, two signals and three pushes (a friction rival), five speeds, no multisines."""
    d = friction_diagnosis(steer=True)
    return plan_next(
        d, rivals=RIVALS, speeds=np.linspace(3.0, 5.0, 5), signals=["roll_rate", "steer_angle"], sweeps=False
    )


@pytest.mark.slow
def test_each_laws_probability_follows_one_signal_and_push_and_the_best_of_any_is_dotted(friction_plan):
    plan = friction_plan
    decays = [item for item in plan.plan if item["experiment"].kind == "decay"]
    prob = {}  # law -> {(signal, push): {speed: probability}}
    for item in decays:
        e = item["experiment"]
        prob.setdefault(e.law, {}).setdefault((e.signal, e.push), {})[e.speed] = item["resolution_probability"]
    # the case in point: somewhere the best signal or push changes from one speed to the next
    switches = False
    for by_pair in prob.values():
        speeds = sorted({v for curve in by_pair.values() for v in curve})
        best = {max((c.get(v, -1.0), pair) for pair, c in by_pair.items())[1] for v in speeds}
        switches |= len(best) > 1
    assert switches, "the fixture must have a law whose best signal or push changes with speed"

    pyplot()
    fig = plot_next(plan)
    try:
        panel = fig.axes[2]
        colours = pyplot().rcParams["axes.prop_cycle"].by_key()["color"]
        drawn = 0
        for k, law in enumerate(plan.laws):
            if law not in prob:
                continue
            colour = to_hex(colours[k % len(colours)])
            lines = [ln for ln in panel.get_lines() if to_hex(ln.get_color()) == colour and len(ln.get_xdata())]
            (solid,) = [ln for ln in lines if ln.get_linestyle() == "-"]
            v, p = np.asarray(solid.get_xdata(), float), np.asarray(solid.get_ydata(), float)
            # the solid curve is one (signal, push)'s probability at every speed it is planned at
            fixed = [
                pair
                for pair, curve in prob[law].items()
                if sorted(curve) == v.tolist() and np.allclose([curve[s] for s in v], p, rtol=0, atol=1e-12)
            ]
            assert fixed, f"{law}: the solid curve is no single signal and push"
            # ... the one whose best over speed is highest, named in the legend
            assert p.max() == pytest.approx(max(max(c.values()) for c in prob[law].values()), abs=1e-12)
            signal, push = fixed[0]
            assert solid.get_label() == f"{law}, {signal.replace('_', ' ')}, push x{push:g}"
            # the dotted curve is the best of any signal and push at each speed, never below the solid one
            (dotted,) = [ln for ln in lines if ln.get_linestyle() == ":"]
            speeds = sorted({s for curve in prob[law].values() for s in curve})
            best = [max(c.get(s, -1.0) for c in prob[law].values()) for s in speeds]
            assert np.asarray(dotted.get_xdata(), float).tolist() == speeds
            q = np.asarray(dotted.get_ydata(), float)
            assert np.allclose(q, best, rtol=0, atol=1e-12)
            at = np.searchsorted(speeds, v)
            assert np.all(q[at] >= p)
            drawn += 1
        assert drawn == len(prob) >= 2
        assert "best of any signal/push" in [t.get_text() for t in panel.get_legend().get_texts()]
    finally:
        pyplot().close(fig)
