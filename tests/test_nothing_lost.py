"""Nothing lost: inputs are never written, outputs appear whole or not at all, a batch survives a bad bicycle."""

from __future__ import annotations

import os
import shutil
import stat
from importlib import resources
from pathlib import Path

import pytest
from strategies import run_cli, signal_csv

from bikerider.estimate import default_files
from bikerider.io.atomic import atomic_write_bytes, atomic_write_text

BP = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
TESTS = Path(__file__).parent


def _snapshot(paths) -> dict[Path, tuple[bytes, int, int]]:
    """Bytes, modification time (ns) and mode of each file."""
    out = {}
    for p in paths:
        st = p.stat()
        out[p] = (p.read_bytes(), st.st_mtime_ns, st.st_mode)
    return out


@pytest.fixture()
def inputs(tmp_path):
    """Copies of every kind of input file, made read-only as a user's archive might be."""
    folder = tmp_path / "inputs"
    folder.mkdir()
    bicycle, rider = default_files()
    files = {
        "bicycle": shutil.copy(bicycle, folder / "bicycle.toml"),
        "rider": shutil.copy(rider, folder / "rider.toml"),
        "benchmark": shutil.copy(TESTS / "data" / "BenchmarkBenchmark.txt", folder / "BenchmarkBenchmark.txt"),
        "measured": shutil.copy(
            BP / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt", folder / "BrowserMeasured.txt"
        ),
        "lumped": shutil.copy(
            BP / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt", folder / "JasonBrowserBenchmark.txt"
        ),
    }
    trial = folder / "trial.csv"
    trial.write_bytes(signal_csv())
    files["trial"] = trial
    paths = {k: Path(v) for k, v in files.items()}
    for p in paths.values():
        p.chmod(0o444)
    yield paths
    for p in paths.values():
        p.chmod(0o644)


def test_no_command_writes_its_inputs(inputs, tmp_path):
    before = _snapshot(inputs.values())
    out = tmp_path / "out"
    runs = [
        [
            "estimate",
            "--json",
            "--bicycle",
            str(inputs["bicycle"]),
            "--rider",
            str(inputs["rider"]),
            "--plot",
            str(out),
        ],
        ["estimate", "--bicycle", str(inputs["measured"]), "--rider", str(inputs["lumped"])],
        ["benchmark", str(inputs["benchmark"]), "--json", "--plot", str(out)],
        ["period", str(inputs["trial"]), "--json", "--plot", str(out / "period.png")],
    ]
    for argv in runs:
        code, stdout, err = run_cli(argv)
        assert code == 0, (argv, err)
    assert _snapshot(inputs.values()) == before
    assert sorted(p.name for p in out.iterdir()) == [
        "bode.png",
        "eigenvalues.png",
        "mode_shapes.png",
        "period.png",
        "side_view.png",
    ]


def test_batch_does_not_touch_the_data_folder(tmp_path):
    data = tmp_path / "bp"
    shutil.copytree(BP, data)
    files = sorted(p for p in data.rglob("*") if p.is_file())
    before = _snapshot(files)
    prefix = tmp_path / "table"
    code, _, err = run_cli(["batch", str(data), "--out", str(prefix)])
    assert code == 0, err
    assert _snapshot(files) == before
    assert sorted(p for p in data.rglob("*") if p.is_file()) == files  # nothing added either


def test_an_output_that_would_overwrite_an_input_is_refused(tmp_path):
    data = tmp_path / "bp"
    shutil.copytree(BP / "bicycles", data / "bicycles")
    target = data / "bicycles" / "Browser" / "Parameters" / "BrowserBenchmark"
    before = (target.with_suffix(".txt")).read_bytes()
    code, _, err = run_cli(["batch", str(data), "--out", str(target)])
    assert code == 2 and "--out" in err and "BrowserBenchmark.txt" in err
    assert target.with_suffix(".txt").read_bytes() == before


def test_batch_over_a_folder_with_one_corrupted_bicycle(tmp_path):
    data = tmp_path / "bp"
    shutil.copytree(BP, data)
    bad = data / "bicycles" / "Fisher" / "RawData" / "FisherMeasured.txt"
    raw = bad.read_bytes()
    bad.write_bytes(raw[: len(raw) // 2] + b"\xff\xfe\x00garbage\n" + raw[len(raw) // 2 :])
    prefix = tmp_path / "table"
    code, out, err = run_cli(["batch", str(data), "--out", str(prefix)])
    assert code == 1  # some bicycle failed; the table still lists the others
    assert "Fisher failed" in err and "Traceback" not in err
    assert out == ""  # --out: the table goes to the files only (issue 24)
    out = prefix.with_suffix(".txt").read_text()
    failed = out.split("failed:")[1]
    assert "Fisher: " in failed and "FisherMeasured.txt" in failed and "not UTF-8" in failed
    header = out.splitlines()[0].split()
    assert header == ["Benchmark", "Browser", "Browserins", "Rigid", "Silver", "Yellow"]
    csv_lines = prefix.with_suffix(".csv").read_text().splitlines()
    rows = {line.split(",")[0]: line for line in csv_lines[1:]}
    assert set(rows) == {"Benchmark", "Browser", "Browserins", "Fisher", "Rigid", "Silver", "Yellow"}
    assert rows["Fisher"].split(",")[1] == ""  # no source, an error instead
    assert "not UTF-8" in rows["Fisher"]
    assert rows["Browser"].split(",")[1] == "raw"


# ------------------------------------------------------------------------------------------
# Atomic writes
# ------------------------------------------------------------------------------------------
def test_atomic_write_replaces_whole_and_keeps_permissions(tmp_path):
    path = tmp_path / "table.txt"
    atomic_write_text(path, "first\n")
    assert path.read_text() == "first\n"
    path.chmod(0o640)
    atomic_write_text(path, "second\nline\r\n")
    assert path.read_bytes() == b"second\nline\r\n"  # newlines exactly as given
    assert stat.S_IMODE(path.stat().st_mode) == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.txt"]  # no temporary left behind


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "figure.png"
    path.write_bytes(b"old figure")

    def broken_replace(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError):
        atomic_write_bytes(path, b"new figure that never lands")
    assert path.read_bytes() == b"old figure"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["figure.png"]


def test_a_figure_that_fails_to_render_leaves_the_old_figure(tmp_path, monkeypatch):
    import matplotlib.figure

    from bikerider.estimate import estimate_default
    from bikerider.plotting import write_figures

    result = estimate_default()
    eig = result.model.eigenvalues([0.0, 5.0, 10.0])
    write_figures(tmp_path, result.model, eig, None)
    good = (tmp_path / "eigenvalues.png").read_bytes()

    def half_written(self, target, *args, **kwargs):
        target.write(b"\x89PNG partial")
        raise RuntimeError("renderer crashed")

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", half_written)
    with pytest.raises(RuntimeError):
        write_figures(tmp_path, result.model, eig, None)
    assert (tmp_path / "eigenvalues.png").read_bytes() == good
    assert sorted(p.name for p in tmp_path.iterdir()) == ["eigenvalues.png"]


def test_writing_into_a_missing_folder_is_a_clear_error(tmp_path):
    code, _, err = run_cli(["batch", str(BP), "--out", str(tmp_path / "nowhere" / "table")])
    assert code == 2 and "--out" in err and "does not exist" in err
    code, _, err = run_cli(["period", str(tmp_path / "missing.csv")])
    assert code == 2 and "missing.csv" in err and "Traceback" not in err


def test_a_gap_report_that_fails_midway_leaves_the_old_report(tmp_path, monkeypatch):
    import matplotlib.figure

    gap = Path(str(resources.files("bikerider") / "data" / "gap"))
    argv = [
        "gap",
        "--model",
        str(gap / "kooijman2008_bicycle.toml"),
        "--data",
        str(gap / "kooijman2008_run52.csv"),
        "--effects",
        "parameters",
        "--report",
        str(tmp_path / "report"),
    ]
    code, _, err = run_cli(argv)
    assert code == 0, err
    before = {p.name: p.read_bytes() for p in (tmp_path / "report").iterdir()}

    def half_written(self, target, *args, **kwargs):
        if hasattr(target, "write"):
            target.write(b"\x89PNG partial")
        else:
            Path(target).write_bytes(b"\x89PNG partial")
        raise RuntimeError("renderer crashed")

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", half_written)
    with pytest.raises(RuntimeError):
        run_cli(argv)
    after = {p.name: p.read_bytes() for p in (tmp_path / "report").iterdir()}
    assert after == before
