"""``bikerider gap`` end to end: JSON contract, text, report files, errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from gap_support import MODEL

import bikerider
from bikerider.cli import main

DATA = Path(bikerider.__file__).parent / "data"
BP = DATA / "bicycleparameters"
EXAMPLE = str(DATA / "gap_examples" / "eigenvalues.csv")
RUN = str(DATA / "gap_examples" / "perturbation_run.csv")
FEW = ["--effects", "parameters,steer_damping,steer_inertia"]


def test_json_has_the_documented_keys_and_finds_the_hidden_friction(capsys):
    # The example data hide a steer friction, 0.3 N m s/rad viscous and 0.05 N m Coulomb
    # (docs/scripts/gap_examples.py).  With the perturbation run, whose steer rate shows the amplitude
    # at which Coulomb friction acts, the linear damping it needs is plausible and is selected.
    assert main(["gap", *MODEL, "--data", EXAMPLE, RUN, *FEW, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["verdict"] == "structural"
    assert {"test", "map"} <= set(out["gap"]) and "data_only" in out["gap"]["test"]
    first = out["ranking"][0]
    assert first["effect"] == "steer_damping"
    for key in (
        "effect",
        "parameters",
        "heldout_error_before",
        "heldout_error_after",
        "shrink",
        "plausible",
        "plausibility",
        "data_error_after",
        "data_shrink",
    ):
        assert key in first
    assert out["selected"] == ["steer_damping"]
    assert out["how_far"]["heldout_error_after"] < out["how_far"]["heldout_error_before"]
    assert out["records"] == {**out["records"], "total": 1, "used": 1, "left_out": 0}
    for key in ("pairs", "selection", "best_implausible", "noise", "laws", "uncertainty"):
        assert key in out


def test_eigenvalues_alone_select_the_friction_damping_and_flag_it(capsys):
    # Without records the 1.1 N m s/rad the data need lies above the usual viscous range (0.05-0.5); the
    # data determine it, so it is selected (a prior, not a wall) and flagged with what to check.  Before
    # issue 21 it was refused as implausible and nothing was selected.
    assert main(["gap", *MODEL, "--data", EXAMPLE, "--effects", "steer_damping,steer_inertia", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["ranking"][0]["effect"] == "steer_damping" and not out["ranking"][0]["plausible"]
    assert out["selected"] == ["steer_damping"]
    flags = out["selection"]["flags"]
    assert any(f.startswith("c_steer = ") and "above the usual 0.05-0.5" in f and "check" in f for f in flags)


def test_text_and_report(tmp_path, capsys):
    report = tmp_path / "rep"
    assert main(["gap", *MODEL, "--data", EXAMPLE, *FEW, "--report", str(report)]) == 0
    text = capsys.readouterr().out
    assert "Verdict: structural" in text and "Which" in text and "Selected:" in text
    md = (report / "report.md").read_text()
    for name in ("eigenvalues.png", "gap_map.png", "ranking.png", "effects.png", "time_response.png"):
        assert (report / name).stat().st_size > 1000
        assert name in md


def test_kooijman_run_52_shows_no_gap(capsys):
    # Kooijman et al. (2008): their model fits the measured weave eigenvalue -1.16 +/- 5.44i of run 52
    assert (
        main(
            [
                "gap",
                "--model",
                str(DATA / "gap/kooijman2008_bicycle.toml"),
                "--data",
                str(DATA / "gap/kooijman2008_run52.csv"),
                "--json",
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert out["verdict"] == "none"
    assert set(out["not_applicable"]) == {"passive_arms", "rider_lean", "speed_sensor", "steer_friction"}


def test_bad_data_exits_2_naming_file_and_line(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("speed,real,imag\n4.0,-0.5,3\n-2,1,1\n")
    assert main(["gap", *MODEL, "--data", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:3" in err and "speed = -2" in err and "Traceback" not in err


@pytest.mark.parametrize(
    "args, message",
    [
        (["--effects", "wobble"], "effect = 'wobble'"),
        (["--rider-rel-sigma", "-1"], "--rider-rel-sigma"),
    ],
)
def test_bad_options_exit_2(capsys, args, message):
    assert main(["gap", *MODEL, "--data", EXAMPLE, *args]) == 2
    assert message in capsys.readouterr().err
