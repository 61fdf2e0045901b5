"""The command line of the toolbox as a user meets it: degrees out, speed rows, readers, convert."""

from __future__ import annotations

import csv
import io
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from strategies import run_cli

import bikerider
from bikerider.io.benchmark_file import load_benchmark_parameters


def _csv(text: str) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(text)))


def test_degrees_in_degrees_out():
    code, out, _ = run_cli(["sweep", "--bicycle", "Benchmark", "--vary", "lam_deg=10:30:3"])
    assert code == 0
    rows = _csv(out)
    assert [r["lam_deg"] for r in rows] == ["10", "20", "30"] and "lam" not in rows[0]
    code, out, _ = run_cli(["sweep", "--bicycle", "Benchmark", "--vary", "lam_deg=10:30:3", "--json"])
    data = json.loads(out)
    assert data["parameters"] == {"lam_deg": [10.0, 20.0, 30.0]}
    assert [d["lam_deg"] for d in data["designs"]] == [10.0, 20.0, 30.0]
    # SI stays SI
    code, out, _ = run_cli(["sweep", "--bicycle", "Benchmark", "--vary", "lam=0.2:0.3:2"])
    assert [r["lam"] for r in _csv(out)] == ["0.2", "0.3"]


def test_speed_rows_keep_the_real_weave_pair():
    """At 0 m/s the benchmark bicycle's eigenvalues are +/-3.13 and +/-5.53: all four are in the rows."""
    code, out, _ = run_cli(
        ["sweep", "--bicycle", "Benchmark", "--vary", "c=0.08:0.08:1", "--speeds", "0:5:2", "--rows", "speeds"]
    )
    assert code == 0
    row = _csv(out)[0]
    values = sorted(float(row[f"{k}_real"]) for k in ("weave", "weave2", "capsize", "castor"))
    expected = sorted(
        bikerider.WhippleModel.from_parameters(bikerider.named("Benchmark")).eigenvalues([0]).values[0].real
    )
    np.testing.assert_allclose(values, expected, rtol=1e-9)
    assert any(math.isclose(v, 3.1316, abs_tol=1e-3) for v in values)
    assert row["modes"] == "weave weave capsize castor"


DATA = Path(__file__).resolve().parents[1] / "src" / "bikerider" / "data"
SBW = str(DATA / "gap" / "pasma2024_sbw" / "sbw_bicycle.toml")
BP = str(DATA / "bicycleparameters")


@pytest.mark.parametrize(
    "argv",
    [
        ["benchmark", SBW, "--monte-carlo", "0"],
        ["sweep", SBW, "--vary", "c=0.05:0.1:2"],
        ["estimate", "--bicycle", SBW, "--monte-carlo", "0"],
        ["sensitivity", "weave_speed", "--bicycle", SBW, "--top", "2"],
        ["sensitivity", "weave_speed", "--bicycle", f"{BP}/bicycles/Browser/RawData/BrowserMeasured.txt", "--top", "2"],
        [
            "sensitivity",
            "capsize_speed",
            "--bicycle",
            f"{BP}/bicycles/Browser/Parameters/BrowserBenchmark.txt",
            "--rider",
            f"{BP}/riders/Jason/Parameters/JasonBrowserBenchmark.txt",
            "--top",
            "2",
        ],
        ["benchmark", f"{BP}/bicycles/Browser/RawData/BrowserMeasured.txt", "--monte-carlo", "0"],
    ],
    ids=lambda argv: " ".join(a.rsplit("/", 1)[-1] for a in argv[:3]),
)
def test_every_command_reads_every_bicycle_file(argv):
    code, out, err = run_cli(argv)
    assert code == 0, err
    assert out


def test_sensitivity_reads_a_benchmark_file_as_estimate_does():
    """The same weave speed from the same BicycleParameters file through estimate and sensitivity."""
    path = f"{BP}/bicycles/Browser/Parameters/BrowserBenchmark.txt"
    weave = bikerider.estimate_from_files(path, with_rider=False).model.critical_speeds().weave
    code, out, _ = run_cli(["sensitivity", "weave_speed", "--bicycle", path, "--top", "1"])
    assert code == 0 and f"= {weave:.4f} m/s" in out


@pytest.mark.parametrize(
    "to, filename", [("toml", "b.toml"), ("bicycleparameters", "BJBenchmark.txt"), ("json", "b.json")]
)
def test_convert_writes_what_reads_back_unchanged(tmp_path, to, filename):
    out = tmp_path / filename
    code, _, err = run_cli(
        ["convert", "--bicycle", "Browser", "--rider", "Jason", "--to", to, "--name", "BJ", "--out", str(out)]
    )
    assert code == 0, err
    original = bikerider.named("Browser", rider="Jason")
    back = load_benchmark_parameters(out)
    assert back.values == original.values
    assert all(back.sigmas[k] == original.sigmas[k] for k, v in original.values.items() if v is not None)
    # and a second conversion of the written file gives the same text
    again = tmp_path / ("again" + out.suffix if to != "bicycleparameters" else "BJ2Benchmark.txt")
    assert run_cli(["convert", str(out), "--to", to, "--name", "BJ", "--out", str(again)])[0] == 0
    assert _without_source(again.read_text()) == _without_source(out.read_text())


def _without_source(text: str) -> list[str]:
    """The lines of a written file but the one naming where the values were read."""
    return [line for line in text.splitlines() if not line.startswith(("source", '  "source"'))]


def test_convert_eigenvalues_as_csv_and_refuses_to_overwrite_its_input(tmp_path):
    code, out, _ = run_cli(["convert", "--bicycle", "Benchmark", "--to", "eigenvalues", "--speeds", "0:10:11"])
    rows = _csv(out)
    assert code == 0 and len(rows) == 11 and rows[0]["modes"] == "weave weave capsize castor"
    model = bikerider.WhippleModel.from_parameters(bikerider.named("Benchmark"))
    assert float(rows[5]["weave_imag"]) == pytest.approx(model.eigenvalues([5.0]).values[0, 0].imag, rel=1e-12)
    source = tmp_path / "b.toml"
    assert run_cli(["convert", "--bicycle", "Benchmark", "--to", "toml", "--out", str(source)])[0] == 0
    code, _, err = run_cli(["convert", str(source), "--to", "toml", "--out", str(source)])
    assert code == 2 and "--out" in err
    code, _, err = run_cli(["convert", "--bicycle", "Benchmark", "--to", "bicycleparameters", "--name", "my bike"])
    assert code == 2 and "bicycle name" in err


def test_the_package_docstring_names_only_what_exists():
    """Every :func:`name` the docstring lists is exported by bikerider or by the module it names."""
    names = re.findall(r":func:`(\w+)`", bikerider.__doc__)
    assert names
    for name in names:
        assert hasattr(bikerider, name), name


def test_sweep_under_a_control_file():
    control = str(DATA / "gap_examples" / "control.toml")
    code, out, err = run_cli(["sweep", "--bicycle", "Benchmark", "--vary", "c=0.08:0.08:1", "--control", control])
    assert code == 0, err
    law = bikerider.ControlLaw.constant([0.0, 5.0, -2.0, -0.5])
    model = bikerider.WhippleModel.from_parameters(bikerider.named("Benchmark"))
    expected = bikerider.closed_loop(model, law).critical_speeds().weave
    assert float(_csv(out)[0]["weave_speed"]) == pytest.approx(expected, rel=1e-8)
    code, _, err = run_cli(["sweep", "--bicycle", "Benchmark", "--monte-carlo", "3", "--control", control])
    assert code == 2 and "--control" in err
