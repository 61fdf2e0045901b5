"""The command line: estimate and benchmark, text, JSON and figures."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from bikerider.cli import main

DATA = Path(__file__).parent / "data"
NAMES = [
    "w",
    "c",
    "lam",
    "g",
    "rR",
    "mR",
    "IRxx",
    "IRyy",
    "xB",
    "zB",
    "mB",
    "IBxx",
    "IByy",
    "IBzz",
    "IBxz",
    "xH",
    "zH",
    "mH",
    "IHxx",
    "IHyy",
    "IHzz",
    "IHxz",
    "rF",
    "mF",
    "IFxx",
    "IFyy",
]


def test_estimate_json_default(capsys):
    assert main(["estimate", "--json", "--speeds", "0:10:21"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert list(out["benchmark"]) == NAMES
    assert out["benchmark"]["IByy"] is None and out["benchmark"]["IHyy"] is None
    assert set(out["matrices"]) == {"M", "C1", "K0", "K2"}
    assert out["speeds"]["weave"] == pytest.approx(5.6615, abs=1e-4)
    assert out["speeds"]["capsize"] == pytest.approx(8.3581, abs=1e-4)
    assert len(out["eigenvalues"]["speeds"]) == 21
    assert all(len(row) == 4 and all(len(z) == 2 for z in row) for row in out["eigenvalues"]["values"])
    assert out["rider"]["mass"] == pytest.approx(72.0)
    # First-order uncertainty from the paper's stated accuracies: the front wheel's compound
    # pendulum period (1.37 +/- 0.06 s) dominates both critical speeds (docs/sensitivity.md).
    assert set(out["uncertainty"]["benchmark"]) == set(NAMES)
    assert out["uncertainty"]["benchmark"]["w"] == pytest.approx(0.002)  # Table 1: +/- 0.002 m
    assert 0.3 < out["uncertainty"]["speeds"]["weave"] < 1.0
    assert 0.5 < out["uncertainty"]["speeds"]["capsize"] < 2.0
    assert sorted(out["rider"]["grid_points"], key=int) == [str(i) for i in range(1, 32)]
    assert len(out["rider"]["inertia"]) == 3


def test_estimate_json_gives_each_eigenvalue_a_sigma(capsys):
    """uncertainty.eigenvalues: one entry per speed and mode, in the order of eigenvalues.values
    (found by the quartic; the sigmas' eigenvalues by eigvals and their own labelling), with the
    sigmas of the Python API and a condition number that grows near the weave pair's birth."""
    from bikerider.estimate import estimate_default, estimate_uncertainty

    v_d = estimate_default().model.weave_birth_speed()  # 0.737 m/s for the paper's bicycle and rider
    just_below = round(0.9999 * v_d, 6)
    assert main(["estimate", "--json", "--speeds", f"{just_below}:8:4"]) == 0
    out = json.loads(capsys.readouterr().out)
    entries = out["uncertainty"]["eigenvalues"]
    speeds = out["eigenvalues"]["speeds"]
    assert len(entries) == 4 * len(speeds)
    expected = estimate_uncertainty(estimate_default(), speeds).eigenvalues
    for n, v in enumerate(speeds):
        for k in range(4):
            entry = entries[4 * n + k]
            re, im = out["eigenvalues"]["values"][n][k]
            assert entry["speed"] == v and entry["mode"] == out["eigenvalues"]["labels"][n][k]
            assert entry["real"] == pytest.approx(re, abs=1e-9) and entry["imag"] == pytest.approx(im, abs=1e-9)
            assert entry["sigma_real"] == pytest.approx(float(expected.sigma_real[n, k]), rel=1e-12)
            assert entry["sigma_imag"] == pytest.approx(float(expected.sigma_imag[n, k]), rel=1e-12, abs=1e-15)
    weave_condition = {entry["speed"]: entry["condition"] for entry in entries[::4]}
    # just below v_d the two weave roots are about to meet: their first-order sigmas blow up with it
    assert weave_condition[just_below] > 10 * weave_condition[8.0]


def test_estimate_text_and_plots(tmp_path, capsys):
    assert main(["estimate", "--plot", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "Weave speed" in text and "Capsize speed" in text and "IBxz" in text
    for name in ("eigenvalues.png", "side_view.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_benchmark_on_bicycleparameters_text(capsys):
    # The Meijaard benchmark bicycle in BicycleParameters' name = value+/-sigma layout.
    assert main(["benchmark", str(DATA / "BenchmarkBenchmark.txt"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["speeds"]["weave"] == pytest.approx(4.29238253634111, abs=1e-10)  # Meijaard 2007 Table 2a


def test_bad_speeds_and_missing_file_exit_2(capsys):
    assert main(["estimate", "--speeds", "10:0:5"]) == 2
    assert "--speeds" in capsys.readouterr().err
    assert main(["benchmark", "no_such_file.txt"]) == 2
    assert "no_such_file.txt" in capsys.readouterr().err


def test_reach_error_from_command_line(tmp_path, capsys):
    from bikerider.estimate import default_files

    _, rider = default_files()
    bad = tmp_path / "short.toml"
    bad.write_text(rider.read_text().replace("l_ll = 0.46", "l_ll = 0.20"))
    assert main(["estimate", "--rider", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "too short to reach the pedals" in err


def test_console_script_help_runs():
    result = subprocess.run([sys.executable, "-m", "bikerider", "estimate", "--help"], capture_output=True, text=True)
    assert result.returncode == 0 and "--bicycle" in result.stdout


BP = Path(__file__).resolve().parents[1] / "src" / "bikerider" / "data" / "bicycleparameters"


def test_estimate_measured_file_with_the_paper_rider_model(capsys):
    # BicycleParameters' raw Browser measurements carry seating data (lcs, hbb, lsp, lst, lamst,
    # LhbF, LhbR, whb): the paper's rider model is seated on them; hub widths are not measured.
    from bikerider.estimate import default_files

    path = BP / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt"
    assert main(["estimate", "--bicycle", str(path), "--rider", str(default_files()[1]), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    for point in ("3", "4", "8", "9"):
        assert out["rider"]["grid_points"][point] is None
    assert out["rider"]["grid_points"]["14"] is not None
    # Same rider, same bicycle model: the rider's centre of mass lands within 5 mm of the lumped
    # JasonBrowserBenchmark.txt (xB 0.2909, zB -1.1091), which the paper's own code computed.
    assert out["rider"]["com"][0] == pytest.approx(0.2909, abs=5e-3)
    assert out["rider"]["com"][2] == pytest.approx(-1.1091, abs=5e-3)
    assert any("hub widths" in note for note in out["notes"])


def test_estimate_with_lumped_rider_and_without_rider(capsys):
    bicycle = BP / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt"
    rider = BP / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt"
    assert main(["estimate", "--bicycle", str(bicycle), "--rider", str(rider), "--json"]) == 0
    with_rider = json.loads(capsys.readouterr().out)
    assert with_rider["rider"]["grid_points"] is None
    assert with_rider["benchmark"]["mB"] == pytest.approx(9.86 + 72.0)  # Browser frame + Jason
    assert main(["estimate", "--bicycle", str(bicycle), "--no-rider", "--json"]) == 0
    alone = json.loads(capsys.readouterr().out)
    assert alone["rider"] is None and alone["benchmark"]["mB"] == pytest.approx(9.86)


def test_rider_model_on_benchmark_parameters_is_refused(capsys):
    from bikerider.estimate import default_files

    bicycle = BP / "bicycles" / "Fisher" / "Parameters" / "FisherBenchmark.txt"
    assert main(["estimate", "--bicycle", str(bicycle), "--rider", str(default_files()[1])]) == 2
    assert "no geometry to seat the rider model" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["Fisher/Parameters/FisherBenchmark.txt", "Browser/RawData/BrowserMeasured.txt"])
def test_bicycle_without_rider_is_the_bicycle_alone_and_says_so(capsys, name):
    """issue 12: `estimate --bicycle X` seated the paper's rider on X unasked, and on a Benchmark file
    then failed naming a rider file the user never gave.  The bicycle alone, with a note."""
    bicycle = BP / "bicycles" / name
    assert main(["estimate", "--bicycle", str(bicycle), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rider"] is None
    assert any(note.startswith("no --rider given: the bicycle alone") for note in out["notes"])
    assert main(["estimate", "--bicycle", str(bicycle)]) == 0
    captured = capsys.readouterr()  # notes on stderr, as README says; the results alone on stdout
    assert "bikerider estimate: note: no --rider given: the bicycle alone" in captured.err
    assert "no --rider" not in captured.out
    assert main(["estimate", "--bicycle", str(bicycle), "--no-rider", "--json"]) == 0  # asked for: no note
    assert not any("no --rider" in note for note in json.loads(capsys.readouterr().out)["notes"])


def test_rider_without_bicycle_sits_on_the_paper_bicycle_and_says_so(capsys):
    from bikerider.estimate import default_files

    assert main(["estimate", "--rider", str(default_files()[1]), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rider"]["mass"] == pytest.approx(72.0)
    assert any(note.startswith("no --bicycle given: the rider seated on the paper's bicycle") for note in out["notes"])


def test_benchmark_text_shows_a_capsize_castor_pair_as_other(capsys):
    """A bicycle whose capsize and castor roots meet below the weave speed (tests/test_quartic.py):
    the table shows the unborn weave pair as weave and the met pair on its own."""
    assert main(["benchmark", str(DATA / "UnbornWeaveBenchmark.txt"), "--speeds", "0.5:2:2"]) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.strip().startswith(("0.500", "2.000"))]
    assert len(rows) == 2
    assert "other pair" in rows[0] and "+/-" not in rows[0].split("other pair")[0]  # two real weave roots
    assert "other pair" not in rows[1]


def test_estimate_notes_go_to_stderr_and_verbose_logs_each_once(capsys, caplog):
    """issue 24: `estimate` printed its notes on stdout (README: stderr), and `-v` logged the paper's
    rear-wheel note twice."""
    import logging

    caplog.set_level(logging.INFO, logger="bikerider")
    assert main(["estimate", "-v"]) == 0
    captured = capsys.readouterr()
    assert "note" not in captured.out.lower()
    wheel = [line for line in captured.err.splitlines() if "IRyy = 0.16 is not at most 2*IRxx" in line]
    assert wheel == [line for line in wheel if line.startswith("bikerider estimate: note: ")] and len(wheel) == 1
    assert not [r for r in caplog.records if r.getMessage().startswith("note: ")]  # -v: printed once, not logged
    caplog.clear()
    caplog.set_level(logging.DEBUG, logger="bikerider")
    assert main(["estimate", "-vv"]) == 0
    logged = [r.getMessage() for r in caplog.records if r.getMessage().startswith("note: ")]
    assert logged and len(logged) == len(set(logged))  # -vv: when each was made, once
