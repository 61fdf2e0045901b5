"""The gap's terminal summary says what each number measures and prints values as they are (issue 24)."""

from __future__ import annotations

from bikerider.gap.text import _interval_text, _law_text, _values, summary_text


def _result(parameter_fit: bool = True) -> dict:
    # the numbers of the steer-by-wire diagnosis (docs/gap_real_data.md, section 3)
    result = {
        "verdict": "structural",
        "gap": {
            "test": {
                "chi2": 196.7,
                "dof": 108,
                "p_value": 4e-7,
                "rms_z": 0.89,
                "data_only": {"chi2": 1216.1, "p_value": 7.6e-187},
            },
            "map": [],
        },
        "laws": {"k_phid = 5, k_delta = -2": "k_phid = 5; k_delta = -2", "sil": "k_phid = 2 (6.5 - v)"},
        "ranking": [],
        "notes": [],
        "selected": [],
    }
    if parameter_fit:
        result["parameter_fit"] = {
            "test": {"chi2": 211.8, "dof": 108, "p_value": 9.9e-9, "prior_chi2": 16.1, "prior_dof": 23}
        }
    return result


def test_each_chi2_is_shown_on_its_own_scale():
    """ "Parameters alone: chi2 = 211.8" under "Gap: chi2 = 196.7" read as worse than doing nothing: the
    first is against the data's noise alone (where the nominal model has 1216.1), the second against
    the combined uncertainty; and "RMS normalised residual 0.89" sat beside chi2/n = 1.82."""
    lines = summary_text(_result()).splitlines()
    combined = lines.index(next(line for line in lines if line.startswith("Gap against the combined uncertainty")))
    assert "chi2 = 196.7 on 108 observations, chi2/n = 1.82" in lines[combined + 1]
    assert "correlation left out" in lines[combined + 2] and lines[combined + 2].endswith("RMS 0.89")
    data = lines.index("Gap against the data's noise alone (the parameters taken as exact):")
    assert lines[data + 1].startswith("  nominal parameters: chi2 = 1216.1")
    fitted = lines[data + 2]
    assert fitted.startswith("  parameters fitted within their uncertainty: chi2 = 211.8")
    assert "data 195.7 + prior 16.1 on 23 parameters" in fitted
    assert not any(line.startswith(("Gap: chi2", "Parameters alone")) for line in lines)
    without_fit = summary_text(_result(False)).splitlines()
    assert any(line.startswith("  nominal parameters: chi2 = 1216.1") for line in without_fit)
    assert not any("fitted within their uncertainty" in line for line in without_fit)


def test_a_control_law_named_by_its_gains_is_printed_once():
    assert _law_text("k_phid = 5, k_delta = -2", "k_phid = 5; k_delta = -2") == "Control law: k_phid = 5; k_delta = -2"
    assert _law_text("sil", "k_phid = 2 (6.5 - v)") == "Control law sil: k_phid = 2 (6.5 - v)"
    text = summary_text(_result())
    assert "Control law: k_phid = 5; k_delta = -2" in text and text.count("k_delta = -2") == 1


def test_fitted_values_zero_and_narrow_intervals():
    # the optimiser's 1.6e-20 for a value at its bound 0 is 0
    assert _interval_text(1.6e-20, 0.0, 0.593) == "0 [0, 0.593]"
    assert _interval_text(1.5e-17, 0.0, 0.00653) == "0 [0, 0.00653]"
    # a well determined value: enough digits that the interval's ends differ
    assert _interval_text(11.47110331, 11.47106417, 11.47114245) == "11.4711 [11.47106, 11.47114]"
    assert _interval_text(0.306, 0.23, 0.382) == "0.306 [0.23, 0.382]"
    assert _interval_text(200.0, 2.0, 200.0) == "200 [2, 200]"  # at a bound: equal ends stay equal
    values = {"c_lean": {"value": 4.78012, "ci95": [4.78001, 4.78023], "unit": "N m s/rad"}}
    assert _values(values) == "c_lean = 4.7801 [4.78, 4.7802] N m s/rad"


def test_the_ranking_axis_spans_a_decade_with_plain_labels():
    """issue 24: ranking.png's log axis spanned less than a decade, labelled "6x10^-1"."""
    from bikerider.plotting.gap import plot_ranking, pyplot

    def row(effect, after, data_after, plausible):
        return {
            "effect": effect,
            "heldout_error_before": 0.89,
            "heldout_error_after": after,
            "data_error_before": 3.36,
            "data_error_after": data_after,
            "plausible": plausible,
        }

    result = {"ranking": [row("steer_friction", 0.43, 1.2, True), row("steer_damping", 0.68, 2.0, True)], "pairs": []}
    fig = plot_ranking(result)
    fig.canvas.draw()
    for ax in fig.axes:
        lo, hi = ax.get_xlim()
        assert hi / lo >= 10 * (1 - 1e-9)
        labels = [t.get_text() for t in ax.get_xticklabels() if lo <= t.get_position()[0] <= hi]
        assert len(labels) >= 3 and all(label.replace(".", "").isdigit() for label in labels), labels
    pyplot().close(fig)
