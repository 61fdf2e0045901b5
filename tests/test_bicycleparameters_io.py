"""Readers of BicycleParameters Benchmark and lumped-rider files; the format detector."""

from __future__ import annotations

import logging
import math
from importlib import resources
from pathlib import Path

import pytest

from bikerider.benchmark import BenchmarkParameters
from bikerider.bicycle.bodies import BicycleBodies
from bikerider.errors import FileFormatError, InputError
from bikerider.io.bicycleparameters import (
    bodies_from_benchmark,
    detect_format,
    load_bicycle_file,
    read_benchmark_file,
    read_lumped_rider,
)

DATA = Path(str(resources.files("bikerider") / "data"))
BP = DATA / "bicycleparameters"
BENCHMARK = BP / "bicycles" / "Benchmark" / "Parameters" / "BenchmarkBenchmark.txt"


@pytest.fixture(autouse=True)
def _quiet():
    logging.getLogger("bikerider").setLevel(logging.ERROR)


@pytest.mark.parametrize(
    "path, kind",
    [
        (BP / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt", "measured"),
        (BP / "bicycles" / "Silver" / "RawData" / "SilverMeasured.txt", "measured"),
        (BP / "bicycles" / "Rigid" / "Parameters" / "RigidBenchmark.txt", "benchmark"),
        (BENCHMARK, "benchmark"),
        (BP / "riders" / "Jason" / "Parameters" / "JasonRigidBenchmark.txt", "lumped_rider"),
        (DATA / "paper" / "browser_bicycle.toml", "toml"),
    ],
)
def test_detect_format(path, kind):
    assert detect_format(path) == kind


def test_toml_content_without_suffix(tmp_path):
    path = tmp_path / "bike.conf"
    path.write_text('[bicycle]\nname = "x"\n')
    assert detect_format(path) == "toml"


def test_unrecognisable_file(tmp_path):
    path = tmp_path / "odd.txt"
    path.write_text("foo = 1\nbar = 2\n")
    with pytest.raises(FileFormatError, match="cannot tell the kind of file"):
        detect_format(path)


def test_load_bicycle_file_dispatches():
    assert isinstance(load_bicycle_file(BP / "bicycles" / "Fisher" / "RawData" / "FisherMeasured.txt"), BicycleBodies)
    params = load_bicycle_file(BENCHMARK)
    assert isinstance(params, BenchmarkParameters)
    # Meijaard et al. (2007) Table 1: w = 1.02 m, lam = pi/10, IBxz = 2.4 kg m^2
    assert (params["w"], params["lam"], params["IBxz"]) == (1.02, pytest.approx(math.pi / 10), 2.4)
    assert isinstance(load_bicycle_file(DATA / "paper" / "browser_bicycle.toml"), BicycleBodies)
    with pytest.raises(FileFormatError, match="lumped rider file"):
        load_bicycle_file(BP / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt")


def test_rigid_split_fork_entries_kept_as_extras():
    read = read_benchmark_file(BP / "bicycles" / "Rigid" / "Parameters" / "RigidBenchmark.txt")
    assert read.extras["mG"].value == 3.35 and read.extras["ISxz"].value == pytest.approx(-0.0350687985221)
    assert read.parameters["mH"] == pytest.approx(5.4)  # RigidBenchmark.txt: mH = 5.4 = mG + mS
    assert read.parameters.sigmas["mH"] == pytest.approx(0.0141421356237)


def test_silver_extras_dropped_with_notes():
    read = read_benchmark_file(BP / "bicycles" / "Silver" / "Parameters" / "SilverBenchmark.txt")
    assert read.parameters["IRxx"] == 0.078
    assert len(read.notes) == 4 and any("IRzz" in n for n in read.notes)


def _edited(tmp_path, replace: str, by: str) -> Path:
    text = (BP / "bicycles" / "Silver" / "Parameters" / "SilverBenchmark.txt").read_text()
    assert replace in text
    path = tmp_path / "EditedBenchmark.txt"
    path.write_text(text.replace(replace, by))
    return path


@pytest.mark.parametrize(
    "replace, by, name, fragment",
    [
        ("yB = 0.0+/-0.0", "yB = 0.05+/-0.0", "yB", "symmetric about the bicycle's XZ plane"),
        ("IRzz = 0.078+/-0.0", "IRzz = 0.09+/-0.0", "IRzz", "axisymmetric"),
        ("IFzz = 0.081+/-0.0", "mD = 1.5\nIFzz = 0.081", "mD", "no flywheel body"),
        ("IFzz = 0.081+/-0.0", "foo = 1", "foo", "a benchmark parameter"),
        ("w = 1.010+/-0.0\n", "", "w", "all 25 benchmark parameters"),
    ],
)
def test_benchmark_file_errors(tmp_path, replace, by, name, fragment):
    with pytest.raises(InputError) as info:
        read_benchmark_file(_edited(tmp_path, replace, by))
    assert info.value.name == name
    assert fragment in str(info.value)


def test_lumped_rider_reader():
    rider = read_lumped_rider(BP / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt")
    # JasonBrowserBenchmark.txt = Moore et al. (2009) Eqs. 8 and 14: r = (0.291, 0, -1.109) m,
    # I = [[8.00, 0, -1.93], [0, 8.07, 0], [-1.93, 0, 2.36]] kg m^2
    assert rider.values["xBr"].value == pytest.approx(0.291, abs=5e-4)
    assert rider.values["zBr"].value == pytest.approx(-1.109, abs=5e-4)
    assert rider.values["IBrxz"].value == pytest.approx(-1.93, abs=5e-3)
    assert rider.values["mBr"].sigma == 2.0


def test_lumped_rider_errors(tmp_path):
    path = tmp_path / "RiderBenchmark.txt"
    path.write_text("mB = 70\nxB = 0.3\nyB = 0.1\nzB = -1.1\nIBxx = 8\nIBxz = -2\nIByy = 8\nIBzz = 2.4\n")
    with pytest.raises(InputError, match="yB = 0.1: expected 0 within"):
        read_lumped_rider(path)
    path.write_text("mB = 70\nxB = 0.3\nzB = -1.1\nIBxx = 8\nIBxz = -5\nIBzz = 2.4\n")
    with pytest.raises(InputError, match="IBrxz = -5: expected .*positive definite"):
        read_lumped_rider(path)
    path.write_text("mB = 70\nxB = 0.3\nzB = -1.1\nIBxx = 8\nIBxz = -2\nIBzz = 2.4\nw = 1\n")
    with pytest.raises(InputError, match="lumped rider entries"):
        read_lumped_rider(path)


def test_bodies_from_benchmark_round_trip():
    from bikerider.bicycle.to_benchmark import bicycle_benchmark_parameters

    params = read_benchmark_file(BENCHMARK).parameters
    again = bicycle_benchmark_parameters(bodies_from_benchmark(params))
    for name, value in params.values.items():
        assert again[name] == pytest.approx(value, rel=1e-12, abs=1e-15), name
