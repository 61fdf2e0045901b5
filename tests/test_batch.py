"""``bikerider batch`` over a BicycleParameters data folder."""

from __future__ import annotations

import csv
import hashlib
import io
import shutil
from importlib import resources
from pathlib import Path

import pytest

from bikerider.cli import main
from bikerider.commands import batch

DATA = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
NAMES = ["Benchmark", "Browser", "Browserins", "Fisher", "Rigid", "Silver", "Yellow"]


def _digests(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


@pytest.fixture()
def data_copy(tmp_path):
    target = tmp_path / "bp"
    shutil.copytree(DATA, target)
    return target


def _rows(text: str) -> dict[str, dict[str, str]]:
    return {row["bicycle"]: row for row in csv.DictReader(io.StringIO(text))}


def test_every_bicycle_tabulated(data_copy, tmp_path, capsys, meijaard2007):
    before = _digests(data_copy)
    prefix = tmp_path / "out" / "table"
    prefix.parent.mkdir()
    assert main(["batch", str(data_copy), "--out", str(prefix)]) == 0
    assert _digests(data_copy) == before  # inputs untouched
    rows = _rows(prefix.with_suffix(".csv").read_text())
    assert sorted(rows) == NAMES
    sources = {name: row["source"] for name, row in rows.items()}
    assert sources == {
        "Benchmark": "parameters",
        "Browser": "raw",
        "Browserins": "raw",
        "Fisher": "raw",
        "Rigid": "raw",
        "Silver": "parameters",
        "Yellow": "raw",
    }
    # Meijaard et al. (2007) Table 2(a): weave 4.29238253634111 m/s, capsize 6.02426201538837 m/s
    speeds = meijaard2007["speeds_table2a"]
    assert float(rows["Benchmark"]["weave_speed"]) == pytest.approx(speeds["v_w"]["value"], rel=1e-7)
    assert float(rows["Benchmark"]["capsize_speed"]) == pytest.approx(speeds["v_c"]["value"], rel=1e-7)
    for name, row in rows.items():
        assert row["error"] == ""
        for key in ("w", "c", "lam", "mB", "IBxx", "IHxz", "IFyy"):
            assert row[key] != "", (name, key)
    assert float(rows["Browser"]["w"]) == 1.121  # BrowserMeasured.txt: w = 1.121+/-0.002
    assert float(rows["Browser"]["w_sigma"]) == 0.002
    text = prefix.with_suffix(".txt").read_text()
    captured = capsys.readouterr()
    assert captured.out == ""  # --out writes the table, the terminal only says where
    assert f"wrote {prefix}.csv and {prefix}.txt" in captured.err
    header = text.splitlines()[0].split()
    assert header == NAMES
    assert "Silver: raw data not usable" in text
    assert not [p for p in prefix.parent.iterdir() if p.name not in ("table.csv", "table.txt")]


def test_failing_bicycle_is_reported_and_others_finish(data_copy, capsys):
    measured = data_copy / "bicycles" / "Fisher" / "RawData" / "FisherMeasured.txt"
    measured.write_text(measured.read_text().replace("TtB2 = 1.50653379762", "TtB2 = -1.50653379762"))
    before = _digests(data_copy)
    assert main(["batch", str(data_copy)]) == 1
    captured = capsys.readouterr()
    assert "Fisher failed" in captured.err
    assert "Fisher: " in captured.out and "TtB2 = -1.50653: expected a positive period" in captured.out
    header = captured.out.splitlines()[0].split()
    assert header == [n for n in NAMES if n != "Fisher"]
    assert _digests(data_copy) == before


def test_raw_error_is_not_hidden_by_the_parameters_file(data_copy):
    rows = {r.name: r for r in batch.run_batch(data_copy)}
    assert rows["Yellow"].source == "raw"
    measured = data_copy / "bicycles" / "Yellow" / "RawData" / "YellowMeasured.txt"
    measured.write_text(measured.read_text().replace("aB2 = 0.0+/-0.003", "aB2 = 0.3+/-0.003"))
    row = batch.process_bicycle(data_copy / "bicycles" / "Yellow")
    assert row.source == "" and "do not meet" in row.error


def test_bicycles_folder_itself_and_progress(data_copy, monkeypatch, capsys):
    monkeypatch.setattr(batch, "PROGRESS_AFTER", -1.0)
    assert main(["batch", str(data_copy / "bicycles")]) == 0
    err = capsys.readouterr().err
    assert "batch: [1/7] Benchmark" in err and "batch: [7/7] Yellow" in err and "done, 7 bicycles" in err


def test_output_may_not_overwrite_an_input(data_copy, capsys):
    target = data_copy / "bicycles" / "Browser" / "Parameters" / "BrowserBenchmark"
    before = _digests(data_copy)
    assert main(["batch", str(data_copy), "--out", str(target)]) == 2
    assert "an output that is not one of the command's inputs" in capsys.readouterr().err
    assert _digests(data_copy) == before


def test_not_a_data_folder(tmp_path, capsys):
    assert main(["batch", str(tmp_path)]) == 2
    assert "BicycleParameters" in capsys.readouterr().err
