"""Layout of the gap report's contact sheet of the records (pages, sizes, fonts, notes in their panels)."""

from types import SimpleNamespace

import numpy as np
import pytest

from bikerider.plotting.common import pyplot
from bikerider.plotting.gap import RECORDS_PER_PAGE, record_sheets

REASON = (
    "the record fit finds no weave in the model's response over this window when IHzz moves by one standard "
    "uncertainty: the model's prediction of this record is undefined within its parameters' uncertainty"
)


def _fit(k: int, used: bool, reason: str = REASON):
    t = np.linspace(0.0, 2.0, 200)
    decay = np.exp(-3 * t) * np.cos(7 * t)
    record = SimpleNamespace(
        name=f"eigen_normal_sil6.5n2_5.4kph.log.gz[{100 * k}:{100 * k + 90}]",
        speed=1.5,
        time=t,
        signals={"roll_rate": decay},
        raw=None,
        repairs=(),
    )
    estimate = SimpleNamespace(evaluate=lambda s: np.exp(-3 * s) * np.cos(7 * s), eigenvalue=-3 + 7j, r2=0.97)
    return SimpleNamespace(record=record, used=used, estimate=estimate, reason=None if used else reason)


def _sheets(fits):
    return record_sheets(fits, {}, "nominal model")


@pytest.fixture(scope="module")
def plt():
    plt = pyplot()
    yield plt
    plt.close("all")


def test_59_records_make_three_pages_of_one_size_with_readable_ticks(plt):
    # the SBW experiment's 59 records (every third left out with a long reason)
    pages = _sheets([_fit(k, k % 3 != 0) for k in range(59)])
    assert len(pages) == 3 == -(-59 // RECORDS_PER_PAGE)
    assert [sum(ax.has_data() for ax in fig.axes) for fig in pages] == [20, 20, 19]
    sizes = {tuple(fig.get_size_inches()) for fig in pages}
    assert len(sizes) == 1
    width, height = sizes.pop()
    assert 9 <= width <= 13 and 0.7 <= height / width <= 1.2  # about 1280 px square at the report's 110 dpi
    for fig in pages:
        fig.canvas.draw()
        for ax in fig.axes:
            if ax.has_data():
                labels = ax.get_xticklabels() + ax.get_yticklabels()
                assert min(label.get_fontsize() for label in labels) >= 8


def test_every_note_stays_inside_its_panel(plt):
    reasons = [REASON, "too short: 0.3 s, at least 2 weave cycles are needed", "x" * 120, REASON * 3]
    fits = [_fit(k, False, reasons[k % len(reasons)]) for k in range(9)]
    for fig in _sheets(fits) + _sheets(fits[:1]):
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        notes = 0
        for ax in fig.axes:
            box = ax.get_window_extent(renderer)
            for text in ax.texts:
                extent = text.get_window_extent(renderer)
                assert box.x0 <= extent.x0 and extent.x1 <= box.x1, text.get_text()
                assert box.y0 <= extent.y0 and extent.y1 <= box.y1, text.get_text()
                assert text.get_fontsize() >= 7
                notes += text.get_text().startswith("left out: ")
        assert notes == sum(ax.has_data() for ax in fig.axes)
    # a reason too long for its panel is shortened, visibly
    long = _sheets(fits)[0].axes[3].texts[0].get_text()
    assert long.endswith("...") and len(long) < len(REASON * 3)


def test_a_single_record_is_not_a_thin_strip(plt):
    label = "steer_friction+steer_damping (T_coulomb 0.19, c_viscous 0.0496, c_steer 0.123)"
    fig = record_sheets([_fit(0, True)], {}, label)[0]
    width, height = fig.get_size_inches()
    assert len(fig.axes) == 1 and 0.6 <= height / width <= 1.2
    # the key, with the selected model's long name, fits on the figure
    fig.canvas.draw()
    key = fig.legends[0].get_window_extent(fig.canvas.get_renderer())
    assert key.x0 >= 0 and key.x1 <= fig.bbox.width and key.y1 <= fig.bbox.height
