"""The diagnosis run blind on data from hidden truths (reduced set; docs/gap_validation.md has the full one).

The truths are simulated in the time domain by an implementation independent of the candidate
models (validation.cases); the weave eigenvalues are fitted from noisy roll rates.  Goals
of the full set: the hidden effect ranks first in at least 9 of 10 effect cases and parameter error
alone raises no structural verdict in at least 9 of 10 null cases.  This reduced set (the quick
protocol: 3 sessions of 4 runs) demands every case right, with fixed seeds, and the predicted
shrinkage within 0.15 of the shrinkage achieved on fresh data.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import bikerider
from bikerider.io.gap_model import load_model
from validation import cases as V

BP = Path(bikerider.__file__).parent / "data" / "bicycleparameters"
CASES = [("null", 11), ("null", 12), ("steer_damping", 13), ("rider_lean", 14), ("tyre_slip", 15)]


@pytest.fixture(scope="module")
def suite():
    model = load_model(
        BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt", BP / "riders/Jason/Parameters/JasonRigidBenchmark.txt"
    )
    return V.run_suite(model, CASES, V.QUICK)


@pytest.mark.slow
def test_hidden_effects_rank_first(suite):
    for case in suite.effect_cases:
        assert case.correct, (case.truth, case.verdict, case.ranking)
    assert suite.first_rate == (3, 3)


@pytest.mark.slow
def test_parameter_error_alone_raises_no_structural_verdict(suite):
    assert suite.false_alarms == (0, 2)


@pytest.mark.slow
def test_predicted_shrinkage_holds_on_fresh_data(suite):
    errors = suite.shrink_errors
    # every effect case selects its effect (the friction as a flagged damping, next test), and a null
    # case may select `parameters` (its verdict): every selection's predicted shrinkage holds
    selecting = [c for c in suite.cases if c.selected]
    assert errors.size == len(selecting) >= 3
    assert {c.truth for c in selecting if c.hidden} == {"steer_damping", "rider_lean", "tyre_slip"}
    assert all(c.selected == ["parameters"] for c in selecting if not c.hidden)
    assert max(abs(errors)) <= 0.15


@pytest.mark.slow
def test_friction_seen_through_eigenvalues_alone_is_selected_as_a_flagged_damping(suite):
    # The truth's Coulomb friction acts at the runs' small steer rates like a viscous damping of about
    # 0.9 N m s/rad, above the usual viscous range (0.05-0.5); eigenvalue tables carry no steer-rate
    # amplitude to judge it as Coulomb friction.  Before issue 21 the range was a wall and nothing was
    # selected; now the data determine the damping and it is selected (its flag: docs/gap.md, Priors).
    case = next(c for c in suite.cases if c.truth == "steer_damping")
    assert case.ranking[0] == "steer_damping" and "steer_damping" in case.selected
    assert case.first_parameters["c_steer"] > 0.5


@pytest.mark.slow
def test_confusion_matrix_counts_every_case(suite):
    rows, cols, table = suite.confusion()
    assert table.sum() == len(CASES)
    assert rows == ["null", "steer_damping", "rider_lean", "tyre_slip"]
    for truth in ("steer_damping", "rider_lean", "tyre_slip"):
        assert table[rows.index(truth), cols.index(truth)] == 1


# -- records of the steer-by-wire kind (part 2 of docs/gap_validation.md, reduced) ----------------
@pytest.fixture(scope="module")
def record_cases():
    riderless = load_model(BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt")
    return {
        truth: V.run_record_case(riderless, truth, seed, V.QUICK_RECORDS)
        for truth, seed in (("sbw_inertia+damping", 22), ("sbw_null", 23))
    }


@pytest.mark.slow
def test_two_effects_at_once_are_found_from_short_records(record_cases):
    # 0.03 kg m^2 of steer inertia and 0.3 N m s/rad of damping, 12 records of 1.2-2.5 s at 2.5-4.5 m/s
    # under the speed-scheduled control: the pair is selected with both values within 20 %
    case = record_cases["sbw_inertia+damping"]
    assert case.verdict == "structural"
    assert set(case.selected) == {"steer_damping", "steer_inertia"}
    assert case.first_parameters["c_steer"] == pytest.approx(0.3, rel=0.2)
    assert case.first_parameters["I_steer"] == pytest.approx(0.03, rel=0.2)
    assert abs(case.predicted_shrink - case.actual_shrink) <= 0.15


@pytest.mark.slow
def test_parameter_error_alone_in_records_selects_no_effect(record_cases):
    case = record_cases["sbw_null"]
    assert case.verdict != "structural" and set(case.selected) <= {"parameters"}


def test_the_truths_whipple_matrices_are_meijaards(tmp_path):
    # the hand-typed Appendix A of Meijaard et al. (2007) against the generated benchmark model, on
    # two bicycles: the truth shares no code with the candidates but agrees on the meaning
    import numpy as np
    from bikerider.generated import benchmark_model as bm

    from bikerider.gap.candidates.effect_model import BENCH_ARGS

    for path in (
        BP / "bicycles/Rigid/Parameters/RigidBenchmark.txt",
        Path(bikerider.__file__).parent / "data" / "gap" / "kooijman2008_bicycle.toml",
    ):
        model = load_model(path)
        values = {k: float(model.parameters.values[k]) for k in BENCH_ARGS}
        for mine, generated in zip(V.meijaard_matrices(values), bm.canonical_matrices(**values)):
            np.testing.assert_allclose(mine, generated, rtol=1e-12, atol=1e-12)
