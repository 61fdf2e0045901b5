"""No command writes over its inputs; a report folder holds one run's report (issue 12)."""

from __future__ import annotations

import hashlib
import os
import shutil
from importlib import resources
from pathlib import Path

import pytest
from strategies import run_cli, signal_csv

from bikerider.errors import InputError
from bikerider.io.atomic import atomic_write_text
from bikerider.io.output_guard import REPORT_MARKER, ReportFolder, run_inputs, same_file

DATA = Path(str(resources.files("bikerider") / "data"))
BENCHMARK = Path(__file__).parent / "data" / "BenchmarkBenchmark.txt"
GAP = DATA / "gap"


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_period_plot_over_its_own_record_is_refused(tmp_path):
    """`period t.csv --plot t.csv` replaced the data with a PNG and exited 0."""
    record = tmp_path / "t.csv"
    record.write_bytes(signal_csv())
    before = _digest(record)
    code, _, err = run_cli(["period", str(record), "--plot", str(record)])
    assert code == 2 and "--plot" in err and "is an input of this run" in err
    assert _digest(record) == before
    link = tmp_path / "plot.png"
    link.symlink_to(record)  # a link to an input is the input
    code, _, err = run_cli(["period", str(record), "--plot", str(link)])
    assert code == 2 and f"is the input {record}" in err and _digest(record) == before
    hard = tmp_path / "hard.png"
    os.link(record, hard)
    code, _, _ = run_cli(["period", str(record), "--plot", str(hard)])
    assert code == 2 and _digest(record) == before
    code, _, err = run_cli(["period", str(record), "--plot", str(tmp_path / "fit.png")])
    assert code == 0 and (tmp_path / "fit.png").read_bytes()[:4] == b"\x89PNG"


def test_figures_may_not_land_on_an_input(tmp_path):
    """An input named like one of the figures in the --plot folder."""
    plots = tmp_path / "plots"
    plots.mkdir()
    data = plots / "bode.png"
    shutil.copy(BENCHMARK, data)
    before = _digest(data)
    code, _, err = run_cli(["benchmark", str(data), "--plot", str(plots)])
    assert code == 2 and "--plot" in err and _digest(data) == before
    assert not (plots / "eigenvalues.png").exists()  # refused before any work


def test_sweep_out_over_its_base_file(tmp_path):
    base = tmp_path / "base.txt"
    shutil.copy(BENCHMARK, base)
    before = _digest(base)
    code, _, err = run_cli(["sweep", str(base), "--vary", "c=0.05:0.1:3", "--out", str(base)])
    assert code == 2 and "--out" in err and _digest(base) == before


def test_sweep_restart_removes_only_a_design_store(tmp_path):
    """`--store DIR --restart` removed DIR whatever it held."""
    pytest.importorskip("zarr")
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "notes.txt").write_text("keep me")
    argv = ["sweep", "--bicycle", "Benchmark", "--vary", "c=0.05:0.1:3", "--vary", "w=1:1.1:2", "--vary", "mB=80:90:2"]
    code, _, err = run_cli([*argv, "--store", str(folder), "--restart", "--quiet"])
    assert code == 2 and "--store" in err and (folder / "notes.txt").read_text() == "keep me"
    inputs = tmp_path / "store"
    code, _, err = run_cli([*argv, "--store", str(inputs), "--quiet"])
    assert code == 0, err
    shutil.copy(BENCHMARK, inputs / "base.txt")  # an input inside the store to be removed
    code, _, err = run_cli(
        ["sweep", str(inputs / "base.txt"), *argv[3:], "--store", str(inputs), "--restart", "--quiet"]
    )
    assert code == 2 and "holds the input" in err and (inputs / "base.txt").exists()


def test_gap_report_folder_holding_its_own_data_is_refused(tmp_path):
    """`gap --data rep/report.md --report rep` overwrote its own data file."""
    report = tmp_path / "rep"
    report.mkdir()
    data = report / "report.md"
    shutil.copy(GAP / "kooijman2008_run52.csv", data)
    before = _digest(data)
    code, _, err = run_cli(
        ["gap", "--model", str(GAP / "kooijman2008_bicycle.toml"), "--data", str(data), "--report", str(report)]
    )
    assert code == 2 and "--report" in err and "holds the input" in err
    assert _digest(data) == before


def test_a_reused_report_folder_holds_only_the_new_report(tmp_path):
    target = tmp_path / "report"
    with ReportFolder(target) as staging:
        for name in ("report.md", "a.png", "b.png"):
            (staging / name).write_text(f"first {name}")
    assert sorted(p.name for p in target.iterdir()) == sorted([REPORT_MARKER, "report.md", "a.png", "b.png"])
    folder = ReportFolder(target)
    with folder as staging:
        written = staging / "report.md"
        written.write_text("second")
        (staging / "a.png").write_text("second a")
    assert folder.final(written) == target / "report.md"
    assert sorted(p.name for p in target.iterdir()) == sorted([REPORT_MARKER, "report.md", "a.png"])  # b.png gone
    assert (target / "report.md").read_text() == "second"
    assert [p.name for p in tmp_path.iterdir()] == ["report"]  # no staging folders left beside it


def test_a_failed_report_leaves_the_earlier_one(tmp_path):
    target = tmp_path / "report"
    with ReportFolder(target) as staging:
        (staging / "report.md").write_text("good")
    with pytest.raises(RuntimeError), ReportFolder(target) as staging:
        (staging / "report.md").write_text("half")
        raise RuntimeError("the diagnosis failed")
    assert (target / "report.md").read_text() == "good"
    assert [p.name for p in tmp_path.iterdir()] == ["report"]


def test_a_report_never_replaces_a_folder_it_did_not_write(tmp_path):
    folder = tmp_path / "thesis"
    folder.mkdir()
    (folder / "chapter1.tex").write_text("months of work")
    with pytest.raises(InputError, match="a new or empty folder, or one an earlier report wrote"):
        ReportFolder(folder).check()
    afile = tmp_path / "file"
    afile.write_text("x")
    with pytest.raises(InputError, match="a folder for the report"):
        ReportFolder(afile).check()
    empty = tmp_path / "empty"
    empty.mkdir()
    ReportFolder(empty).check()  # an empty folder is fine


def test_every_atomic_write_refuses_an_input_of_the_run(tmp_path):
    """The second line of defence: bikerider.io.atomic checks at the moment of writing."""
    data = tmp_path / "data.csv"
    data.write_text("1,2\n")
    with run_inputs([data]), pytest.raises(InputError, match="output file"):
        atomic_write_text(tmp_path / "." / "data.csv", "over")
    assert data.read_text() == "1,2\n"
    atomic_write_text(data, "allowed outside a run")  # library use without registered inputs
    assert same_file(tmp_path / "x" / ".." / "data.csv", data)


@pytest.mark.parametrize(
    "argv, option, expected",
    [
        (["estimate", "--plot", ""], "--plot", "a folder to write into (an empty path names none)"),
        (["sweep", "--bicycle", "Benchmark", "--vary", "c=0:1:3", "--out", ""], "--out", "a file to write"),
        (["batch", str(DATA / "bicycleparameters"), "--out", ""], "--out", "a prefix for PREFIX.csv"),
        (
            ["batch", str(DATA / "bicycleparameters"), "--out", "/"],
            "--out",
            "a prefix for PREFIX.csv",
        ),  # was a traceback
        (["gap", "--model", "m.toml", "--data", "d.csv", "--report", ""], "--report", "a folder to write into"),
        (["sensitivity", "weave_speed", "--wrt", ""], "--wrt", "a node of the estimate chain"),
    ],
)
def test_an_empty_or_wrong_kind_of_output_path_is_an_error(tmp_path, argv, option, expected):
    """An empty output path silently meant no output (or a traceback, for batch's prefix '/')."""
    code, out, err = run_cli(argv)
    assert code == 2 and "Traceback" not in err
    assert f"{option} = " in err and expected in err, err


def test_file_and_folder_options_refuse_the_other_kind(tmp_path):
    record = tmp_path / "t.csv"
    record.write_bytes(signal_csv())
    code, _, err = run_cli(["period", str(record), "--plot", str(tmp_path)])
    assert code == 2 and "a file to write, not a folder" in err
    code, _, err = run_cli(["estimate", "--plot", str(record)])
    assert code == 2 and "a folder to write into (this is a file)" in err
    code, _, err = run_cli(
        ["sweep", "--bicycle", "Benchmark", "--vary", "c=0.05:0.1:2", "--plot", str(tmp_path / "new")]
    )
    assert code == 0, err  # a --plot folder is created when missing, as for estimate
    assert (tmp_path / "new" / "sweep.png").is_file()
