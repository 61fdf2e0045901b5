"""Hostile input for ``bikerider gap``: its readers (eigenvalue tables, control files, experiment
manifests, logs), its paths and its options.

Each input is either read into finite values or refused with a :class:`~bikerider.errors.BikeriderError`
naming the file (or the option); never a traceback, never a hang, never an input overwritten.
Hypothesis runs derandomised in CI (tests/conftest.py); the fixed cases are the ones a fuzzing run
found (issue 12).
"""

from __future__ import annotations

import os
import threading
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import assert_all_finite, assert_names_file, check_json_output, mutated, run_cli

from bikerider.errors import BikeriderError, FileFormatError, InputError

FUZZ = settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
DATA = Path(str(resources.files("bikerider") / "data"))
EXAMPLES = DATA / "gap_examples"
KOOIJMAN = ["--model", str(DATA / "gap" / "kooijman2008_bicycle.toml")]
RUN52 = str(DATA / "gap" / "kooijman2008_run52.csv")
HUGE_INT = "1" + "0" * 400
"""An integer too large for a float: TOML reads it as an int (float() of it raises OverflowError)."""

CONTROL = """\
# named laws with every kind of gain
[control.sil]
description = "steer into lean"
k_phid = { K = 2.0, v0 = 6.5, when = "below" }
k_phi = { K = 0.7, v0 = 6.5, when = "above" }
k_delta = { speed = [0.0, 3.0, 6.0], gain = [-2.0, -1.0, 0.0] }
k_deltad = -0.5

[control.hands_off]
k_phid = 0.0
"""

MANIFEST = """\
[experiment]
name = "fuzz"
sample_rate = 100.0
logs = "."
control = "sil"
fit = ["roll_rate"]

[columns]
roll_rate = "lean_rate"
steer_angle = "fork_angle"
speed = "speed"

[speed]
source = "column"
calibration = { gain = 1.05, offset = -0.1 }

[control.sil]
k_phid = { K = 2.0, v0 = 6.5, when = "below" }

[[file]]
path = "run.log"
windows = [[10, 300], [400, 700]]
group = "day 1"
"""

WINDOWS = "file,start,end,group,speed\nrun.log,10,300,a,4.2\nrun.log,400,700,b,4.3\n"


def _log() -> str:
    t = np.arange(800) / 100.0
    decay = np.exp(-1.2 * (t % 4.0)) * np.sin(5.0 * (t % 4.0))
    rows = [f"{0.4 * d:.5f},{0.05 * d:.5f},{4.2 + 0.01 * np.cos(t_):.4f}" for d, t_ in zip(decay, t)]
    return "lean_rate,fork_angle,speed\n" + "\n".join(rows) + "\n"


def _with_huge_ints(data: bytes, draw) -> tuple[str, bytes]:
    """Replace one number by a 400-digit integer (the fuzzing run's OverflowError)."""
    import re

    text = data.decode()
    numbers = list(re.finditer(r"(?<![\w.])\d+(?:\.\d+)?", text))
    m = numbers[draw(st.integers(0, len(numbers) - 1))]
    return f"{m.group()} -> a 400-digit integer", (text[: m.start()] + HUGE_INT + text[m.end() :]).encode()


def _hostile(draw, data: bytes) -> tuple[str, bytes]:
    if draw(st.integers(0, 4)) == 0:
        return _with_huge_ints(data, draw)
    return draw(mutated(data))


# ------------------------------------------------------------------------------------------
# Control files: read, evaluated, and closed around a model
# ------------------------------------------------------------------------------------------
@FUZZ
@given(st.data())
def test_control_files(tmp_path_factory, data):
    from bikerider.gap.candidates.effect_model import EffectModel
    from bikerider.io.gap_data import read_control
    from bikerider.io.gap_model import load_model

    what, text = _hostile(data.draw, CONTROL.encode())
    path = tmp_path_factory.mktemp("fuzz") / "control.toml"
    path.write_bytes(text)
    try:
        laws = read_control(path)
    except BikeriderError as exc:
        assert_names_file(exc, path)
        return
    model = load_model(DATA / "gap" / "kooijman2008_bicycle.toml")
    whipple = EffectModel({k: float(v) for k, v in model.parameters.values.items()}, model.geometry)
    speeds = np.array([0.5, 4.0, 9.0])
    for law in laws.values():
        gains = law(speeds)
        assert_all_finite(gains, what)
        assert_all_finite(whipple.eigenvalues(speeds, gains), what)


# ------------------------------------------------------------------------------------------
# Experiment manifests (TOML and CSV) and the logs they cut
# ------------------------------------------------------------------------------------------
def _experiment(folder: Path, manifest: bytes, windows: bytes, log: bytes):
    from bikerider.io.experiment import load_records, read_experiment

    (folder / "experiment.toml").write_bytes(manifest)
    (folder / "windows.csv").write_bytes(windows)
    (folder / "run.log").write_bytes(log)
    out = []
    for path, columns, rate in (
        (folder / "experiment.toml", None, None),
        (folder / "windows.csv", "roll_rate=lean_rate,steer_angle=fork_angle,speed=speed", 100.0),
    ):
        settings_, windows_ = read_experiment(path, columns, rate)
        out += load_records(settings_, windows_)
    return out


@FUZZ
@given(st.data(), st.sampled_from(["manifest", "windows", "log"]))
def test_experiment_manifests_and_logs(tmp_path_factory, data, target):
    files = {"manifest": MANIFEST.encode(), "windows": WINDOWS.encode(), "log": _log().encode()}
    what, files[target] = _hostile(data.draw, files[target])
    folder = tmp_path_factory.mktemp("fuzz")
    try:
        records = _experiment(folder, files["manifest"], files["windows"], files["log"])
    except BikeriderError as exc:
        assert_names_file(exc, folder / "experiment.toml", folder / "windows.csv", folder / "run.log")
        return
    from bikerider.gap.measured.records import fit_record

    for r in records:  # a record with a problem is left out with it; every other one is finite
        if r.problem is None:
            values = [r.time, r.speed, r.speed_sigma, r.law([r.controller_speed])]
            assert_all_finite(values, f"{target}: {what}")
            # an empty log cell is a missing sample (docs/gap.md): the fit leaves such a record out
            # with its reason, or fits it to finite values
            fit = fit_record(r)
            if fit.used:
                assert_all_finite([fit.estimate.eigenvalue, fit.estimate.real_sigma, fit.estimate.imag_sigma], what)
            else:
                assert fit.reason
        else:
            assert isinstance(r.problem, str) and r.problem


# ------------------------------------------------------------------------------------------
# The command line: options and hostile control files, end to end
# ------------------------------------------------------------------------------------------
@settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(st.data())
def test_gap_command_with_a_hostile_control_file(tmp_path_factory, data):
    what, text = _hostile(data.draw, (EXAMPLES / "control.toml").read_bytes())
    path = tmp_path_factory.mktemp("fuzz") / "control.toml"
    path.write_bytes(text)
    code, out, err = run_cli(["gap", *KOOIJMAN, "--data", RUN52, "--control", str(path), *FEW, "--json"])
    assert code in (0, 2), (what, err)
    if code == 0:
        check_json_output(out, what)
    else:  # the file refused, or a diagnosis the law makes impossible (e.g. no weave left to compare)
        assert err.startswith("bikerider gap: error: ") and "Traceback" not in err, (what, err)


FEW = ["--effects", "steer_damping"]


@pytest.mark.parametrize("speed", ["1e308", "inf", "nan", "-1", "0", "1e7"])
def test_an_impossible_speed_is_refused_naming_it(speed):
    # before: --speed 1e308 ended in numpy.linalg.LinAlgError: Array must not contain infs or NaNs.
    # The command line's one speed type refuses what no speed can be (below 0, beyond light, not a
    # number); the gap command refuses what no perturbation run can have (0, beyond 1e6 m/s).
    run = str(EXAMPLES / "perturbation_run.csv")
    code, out, err = run_cli(["gap", *KOOIJMAN, "--data", run, "--speed", speed, *FEW])
    assert code == 2 and "--speed" in err and (f"{speed!r}" in err or "positive speed of at most 1e+06 m/s" in err), err
    assert "Traceback" not in err


@pytest.mark.parametrize(
    "text",
    [
        "[control]\nk_phid = 1e308\n",
        f"[control]\nk_phid = {HUGE_INT}\n",
        f"[control]\nk_delta = -{HUGE_INT}\n",
        f'[control.sil]\nk_phid = {{ K = {HUGE_INT}, v0 = 6.5, when = "below" }}\n',
        f'[control.sil]\nk_phid = {{ K = 2.0, v0 = {HUGE_INT}, when = "below" }}\n',
        "[control.sil]\nk_delta = { speed = [0.0, 3.0], gain = [1e300, 0.0] }\n",
        '[control]\nk_phid = "1e308 +/- 1"\n',
    ],
)
def test_an_impossible_gain_is_refused_naming_it(tmp_path, text):
    # before: k_phid = 1e308 ended in LinAlgError, a 400-digit gain in OverflowError (tracebacks)
    path = tmp_path / "control.toml"
    path.write_text(text)
    code, out, err = run_cli(["gap", *KOOIJMAN, "--data", RUN52, "--control", str(path), *FEW])
    assert code == 2 and str(path) in err and "Traceback" not in err, err
    assert "k_" in err and "magnitude at most 1e+06" in err, err


# ------------------------------------------------------------------------------------------
# Paths: not regular files, empty, too large
# ------------------------------------------------------------------------------------------
@pytest.fixture
def fifo(tmp_path):
    """A FIFO with a writer that would unblock a reader (and end it at EOF), so a test fails, not hangs."""
    path = tmp_path / "pipe.csv"
    os.mkfifo(path)

    def writer():
        with open(path, "wb"):
            pass

    thread = threading.Thread(target=writer, daemon=True)
    thread.start()
    yield path
    if thread.is_alive():  # nobody opened it: release the writer
        os.close(os.open(path, os.O_RDONLY | os.O_NONBLOCK))
        thread.join(5)


@pytest.mark.parametrize("option", ["--data", "--model", "--rider", "--control", "--experiment"])
def test_a_fifo_is_refused_as_any_input(fifo, option):
    argv = {
        "--data": ["gap", *KOOIJMAN, "--data", str(fifo)],
        "--model": ["gap", "--model", str(fifo), "--data", RUN52],
        "--rider": ["gap", *KOOIJMAN, "--rider", str(fifo), "--data", RUN52],
        "--control": ["gap", *KOOIJMAN, "--data", RUN52, "--control", str(fifo)],
        "--experiment": ["gap", *KOOIJMAN, "--experiment", str(fifo), "--columns", "roll_rate=a", "--sample-rate", "1"],
    }[option]
    code, out, err = run_cli(argv)
    assert code == 2 and f"{fifo}: is a FIFO (named pipe), not a regular file" in err, err


def test_a_fifo_named_as_a_log_by_a_manifest_is_refused(tmp_path, fifo):
    from bikerider.io.experiment import load_records, read_experiment

    (tmp_path / "experiment.toml").write_text(MANIFEST.replace('"run.log"', f'"{fifo.name}"'))
    settings_, windows = read_experiment(tmp_path / "experiment.toml")
    with pytest.raises(FileFormatError, match="FIFO"):
        load_records(settings_, windows)


@pytest.mark.parametrize("option", ["--control", "--rider", "--data"])
def test_an_empty_path_is_refused_not_taken_as_none(option):
    # before: --control "" silently meant no control
    extra = {"--control": ["--data", RUN52, "--control", ""], "--rider": ["--data", RUN52, "--rider", ""]}
    code, out, err = run_cli(["gap", *KOOIJMAN, *extra.get(option, ["--data", ""]), *FEW])
    assert code == 2 and "empty path" in err, err


def test_a_50_mb_eigenvalue_table_is_refused_with_its_size(tmp_path):
    # before: read in full (a sparse 50 MB file of NUL bytes: a minute and no useful message)
    path = tmp_path / "eigenvalues.csv"
    with open(path, "wb") as stream:
        stream.truncate(50_000_000)
    code, out, err = run_cli(["gap", *KOOIJMAN, "--data", str(path)])
    assert code == 2 and f"{path}: 47.7 MiB (50000000 bytes): expected a data table of at most 15.3 MiB" in err, err


def test_tables_longer_than_the_diagnosis_can_take_are_refused_with_their_length(tmp_path, monkeypatch):
    from bikerider.io import gap_data

    monkeypatch.setattr(gap_data, "MAX_EIGENVALUE_ROWS", 10)
    monkeypatch.setattr(gap_data, "MAX_RECORD_SAMPLES", 100)
    with pytest.raises(FileFormatError, match="18 rows: expected at most 10 measured eigenvalues"):
        gap_data.read_eigenvalues(EXAMPLES / "eigenvalues.csv")
    with pytest.raises(FileFormatError, match=r"\d+ samples: expected one free decay of at most 100 samples"):
        gap_data.read_perturbation(EXAMPLES / "perturbation_run.csv")


def test_long_work_is_announced_before_it_starts(monkeypatch, caplog):
    # before: a large table ran for minutes without a line of output (shown at default verbosity)
    import logging

    from bikerider import diagnose as pipeline

    monkeypatch.setattr(pipeline, "LONG_WORK_ROWS", 10)
    with caplog.at_level(logging.WARNING, logger="bikerider"):
        code, out, err = run_cli(["gap", *KOOIJMAN, "--data", str(EXAMPLES / "eigenvalues.csv"), *FEW])
    assert code == 0, err
    assert any(
        r.levelno == logging.WARNING and "18 eigenvalue rows and 0 records, candidates steer_damping" in r.getMessage()
        for r in caplog.records
    )


def test_a_window_longer_than_a_record_is_refused(tmp_path, monkeypatch):
    from bikerider.io import experiment

    monkeypatch.setattr(experiment, "MAX_RECORD_SAMPLES", 100)
    (tmp_path / "experiment.toml").write_text(MANIFEST)
    (tmp_path / "run.log").write_text(_log())
    settings_, windows = experiment.read_experiment(tmp_path / "experiment.toml")
    with pytest.raises(FileFormatError, match="holds 290 samples: expected one free decay of at most 100"):
        experiment.load_records(settings_, windows)


def test_a_gzipped_log_that_unpacks_too_large_is_refused(tmp_path, monkeypatch):
    import gzip

    from bikerider.io import experiment

    monkeypatch.setattr(experiment, "MAX_LOG_BYTES", 10_000)
    path = tmp_path / "run.log.gz"
    path.write_bytes(gzip.compress(_log().encode()))  # 5 kB packed, 20 kB unpacked
    with pytest.raises(FileFormatError, match="unpacks to more than"):
        experiment.read_text(path)


# ------------------------------------------------------------------------------------------
# Outputs: never over an input; a report folder holds one run
# ------------------------------------------------------------------------------------------
def test_the_report_never_overwrites_its_own_data(tmp_path):
    # before: gap --data rep/report.md --report rep replaced the data with the report
    folder = tmp_path / "rep"
    folder.mkdir()
    data = folder / "report.md"
    data.write_bytes(Path(RUN52).read_bytes())
    before = data.read_bytes()
    code, out, err = run_cli(["gap", *KOOIJMAN, "--data", str(data), "--report", str(folder), *FEW])
    assert code == 2 and "--report" in err and f"it holds the input {data}" in err, err
    assert data.read_bytes() == before and sorted(p.name for p in folder.iterdir()) == ["report.md"]


def test_a_reused_report_folder_keeps_no_figure_of_the_previous_run(tmp_path):
    # before: figures of the first run stayed beside a report.md that no longer linked them.  A report
    # folder is replaced whole (bikerider.io.output_guard.ReportFolder); a folder holding files no
    # report wrote is refused, never emptied.
    folder = tmp_path / "rep"
    code, out, err = run_cli(["gap", *KOOIJMAN, "--data", RUN52, "--report", str(folder), *FEW])
    assert code == 0, err
    (folder / "old_figure.png").write_bytes(b"\x89PNG old")  # as if an earlier report had drawn it
    code, out, err = run_cli(["gap", *KOOIJMAN, "--data", RUN52, "--report", str(folder), *FEW])
    assert code == 0, err
    report = (folder / "report.md").read_text()
    pngs = {p.name for p in folder.glob("*.png")}
    assert "old_figure.png" not in pngs and all(f"({name})" in report for name in pngs)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    code, out, err = run_cli(["gap", *KOOIJMAN, "--data", RUN52, "--report", str(mine), *FEW])
    assert code == 2 and "no .bikerider-report" in err and (mine / "notes.txt").read_text() == "mine", err


def test_a_report_that_would_remove_an_input_as_a_stale_figure_is_refused(tmp_path):
    # the previous report links table.png; here table.png is this run's data (a CSV by another name):
    # removing it as the old run's figure would destroy an input
    folder = tmp_path / "rep"
    folder.mkdir()
    data = folder / "table.png"
    data.write_bytes(Path(RUN52).read_bytes())
    (folder / "report.md").write_text("# old\n\n![Old](table.png)\n")
    code, out, err = run_cli(["gap", *KOOIJMAN, "--data", str(data), "--report", str(folder), *FEW])
    assert code == 2 and f"it holds the input {data}" in err, err
    assert data.read_bytes() == Path(RUN52).read_bytes() and (folder / "report.md").read_text().startswith("# old")


def test_inputs_are_checked_before_the_work(tmp_path, monkeypatch):
    from bikerider.io import gap_report

    folder = tmp_path / "rep"
    folder.mkdir()
    (folder / "report.md").write_text("![x](fig.png)\n")
    (folder / "fig.png").write_bytes(b"png")
    with pytest.raises(InputError, match="fig.png is one of the inputs"):
        gap_report.check_report_folder(folder, [folder / "fig.png"])
    gap_report.check_report_folder(tmp_path / "absent", [folder / "fig.png"])  # nothing there yet: fine
