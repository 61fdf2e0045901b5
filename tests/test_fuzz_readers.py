"""Hostile input for every reader: one random mutation of a valid file at a time.

Mutations (tests/strategies.py ``mutated``): a number replaced by NaN, infinity, a huge, tiny,
negative or zero value, a unit slip or text; truncation; a changed byte; deleted, doubled,
swapped or junk lines; bytes that are not UTF-8.  Each reader, and the chain behind it, must either
give finite results or raise a BikeriderError that names the file; never another exception and
never a RuntimeWarning (an error under this project's pytest settings).
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import assert_all_finite, assert_names_file, meijaard_values, mutated, run_cli, signal_csv

from bikerider.benchmark import WhippleModel
from bikerider.errors import BikeriderError
from bikerider.estimate import default_files, estimate

FUZZ = settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
BP = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
BICYCLE_TOML, RIDER_TOML = default_files()
TESTS = Path(__file__).parent


def _write(tmp_path: Path, name: str, data: bytes) -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


def _check_model(model: WhippleModel, what: str) -> None:
    eig = model.eigenvalues(np.linspace(0, 10, 6))
    assert_all_finite(eig.values, f"{what} eigenvalues")
    speeds = model.critical_speeds()
    for v in (speeds.weave, speeds.capsize, speeds.weave_frequency):
        assert v is None or math.isfinite(v), what


# ------------------------------------------------------------------------------------------
# The project's TOML files
# ------------------------------------------------------------------------------------------
@FUZZ
@given(st.data())
def test_bicycle_toml(tmp_path_factory, data):
    from bikerider.io.toml_input import load_bicycle_toml, load_rider_toml

    what, text = data.draw(mutated(BICYCLE_TOML.read_bytes()))
    path = _write(tmp_path_factory.mktemp("fuzz"), "bicycle.toml", text)
    try:
        bicycle = load_bicycle_toml(path)
        assert_all_finite(bicycle.values, what)
        result = estimate(bicycle, load_rider_toml(RIDER_TOML))
    except BikeriderError as exc:
        assert_names_file(exc, path, RIDER_TOML)  # a rider who cannot reach is named by the rider file
        return
    assert_all_finite(result.parameters.values, what)
    _check_model(result.model, what)


@FUZZ
@given(st.data())
def test_rider_toml(tmp_path_factory, data):
    from bikerider.io.toml_input import load_bicycle_toml, load_rider_toml

    what, text = data.draw(mutated(RIDER_TOML.read_bytes()))
    path = _write(tmp_path_factory.mktemp("fuzz"), "rider.toml", text)
    try:
        rider = load_rider_toml(path)
        assert_all_finite(rider.values, what)
        result = estimate(load_bicycle_toml(BICYCLE_TOML), rider)
    except BikeriderError as exc:
        assert_names_file(exc, path)
        return
    assert_all_finite(result.parameters.values, what)
    assert_all_finite(result.rider_model.inertia, what)
    _check_model(result.model, what)


def _benchmark_toml() -> bytes:
    lines = ["# Meijaard et al. (2007) Table 1", "[benchmark]"]
    lines += [f"{k} = {v!r}" for k, v in meijaard_values().items()]
    return ("\n".join(lines) + "\n").encode()


@FUZZ
@given(st.data())
def test_benchmark_toml(tmp_path_factory, data):
    from bikerider.io.benchmark_file import load_benchmark_parameters

    what, text = data.draw(mutated(_benchmark_toml()))
    path = _write(tmp_path_factory.mktemp("fuzz"), "benchmark.toml", text)
    try:
        params = load_benchmark_parameters(path)
        model = WhippleModel.from_parameters(params)
    except BikeriderError as exc:
        assert_names_file(exc, path)
        return
    assert_all_finite(params.values, what)
    _check_model(model, what)


# ------------------------------------------------------------------------------------------
# name = value+/-sigma files (BicycleParameters)
# ------------------------------------------------------------------------------------------
@FUZZ
@given(st.data())
def test_benchmark_text(tmp_path_factory, data):
    from bikerider.io.benchmark_file import load_benchmark_parameters

    what, text = data.draw(mutated((TESTS / "data" / "BenchmarkBenchmark.txt").read_bytes()))
    path = _write(tmp_path_factory.mktemp("fuzz"), "BenchmarkBenchmark.txt", text)
    try:
        params = load_benchmark_parameters(path)
        model = WhippleModel.from_parameters(params)
    except BikeriderError as exc:
        assert_names_file(exc, path)
        return
    assert_all_finite(params.values, what)
    _check_model(model, what)


@FUZZ
@given(st.data(), st.sampled_from(["Browser", "Fisher", "Yellow", "Silver"]))
def test_bicycleparameters_benchmark_file(tmp_path_factory, data, name):
    from bikerider.io.bicycleparameters import read_benchmark_file

    base = BP / "bicycles" / name / "Parameters" / f"{name}Benchmark.txt"
    what, text = data.draw(mutated(base.read_bytes()))
    path = _write(tmp_path_factory.mktemp("fuzz"), base.name, text)
    try:
        read = read_benchmark_file(path)
        model = WhippleModel.from_parameters(read.parameters)
    except BikeriderError as exc:
        assert_names_file(exc, path)
        return
    assert_all_finite(read.parameters.values, what)
    assert_all_finite(read.extras, what)
    _check_model(model, what)


@FUZZ
@given(st.data(), st.sampled_from(["Browser", "Browserins", "Fisher", "Rigid", "Yellow"]))
def test_measured_file(tmp_path_factory, data, name):
    from bikerider.bicycle.to_benchmark import bicycle_benchmark_parameters
    from bikerider.io.bicycleparameters import read_measured_file

    base = BP / "bicycles" / name / "RawData" / f"{name}Measured.txt"
    what, text = data.draw(mutated(base.read_bytes()))
    path = _write(tmp_path_factory.mktemp("fuzz"), base.name, text)
    try:
        reduction = read_measured_file(path)
        params = bicycle_benchmark_parameters(reduction.bodies)
        model = WhippleModel.from_parameters(params)
    except BikeriderError as exc:
        assert_names_file(exc, path)
        return
    assert_all_finite(reduction.bodies.values, what)
    assert_all_finite(params.values, what)
    _check_model(model, what)


@FUZZ
@given(st.data())
def test_lumped_rider_file(tmp_path_factory, data):
    from bikerider.io.bicycleparameters import merge_rider, read_benchmark_file, read_lumped_rider

    base = BP / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt"
    what, text = data.draw(mutated(base.read_bytes()))
    path = _write(tmp_path_factory.mktemp("fuzz"), base.name, text)
    bicycle = read_benchmark_file(BP / "bicycles" / "Browser" / "Parameters" / "BrowserBenchmark.txt").parameters
    try:
        rider = read_lumped_rider(path)
        params = merge_rider(bicycle, rider)
        model = WhippleModel.from_parameters(params)
    except BikeriderError as exc:
        assert_names_file(exc, path)
        return
    assert_all_finite(rider.values, what)
    assert_all_finite(params.values, what)
    _check_model(model, what)


@settings(max_examples=150, deadline=None)
@given(st.binary(max_size=300))
def test_name_value_reader_on_arbitrary_bytes(tmp_path_factory, raw):
    from bikerider.io.name_value_file import read_name_value_file

    path = _write(tmp_path_factory.mktemp("fuzz"), "values.txt", raw)
    try:
        values = read_name_value_file(path)
    except BikeriderError as exc:
        assert_names_file(exc, path)
        return
    assert_all_finite(values.as_dict(), repr(raw))


# ------------------------------------------------------------------------------------------
# Rate records of the period command
# ------------------------------------------------------------------------------------------
@FUZZ
@given(st.data())
def test_signal_csv_and_fit(tmp_path_factory, data):
    from bikerider.fitting.damped_oscillation import fit_damped_oscillation
    from bikerider.io.signal_csv import read_signal_csv

    what, text = data.draw(mutated(signal_csv()))
    path = _write(tmp_path_factory.mktemp("fuzz"), "trial.csv", text)
    try:
        time, rate = read_signal_csv(path)
    except BikeriderError as exc:
        assert_names_file(exc, path)
        return
    assert_all_finite([time, rate], what)
    try:
        fit = fit_damped_oscillation(time, rate)
    except BikeriderError:
        return  # the period command adds the file name to fit errors (tested through the CLI)
    assert_all_finite(fit.as_dict(), what)


# ------------------------------------------------------------------------------------------
# Files that are not what they claim: empty, binary, huge, a folder
# ------------------------------------------------------------------------------------------
HUGE = b"w = 1.02\n" + b"# padding " * 200_000 + b"\n" + b"x" * 2_000_000


@pytest.mark.parametrize(
    "content",
    [b"", b"\x00" * 64, bytes(range(256)), b"\xef\xbb\xbf", HUGE],
    ids=["empty", "nul", "all-bytes", "bom-only", "huge"],
)
@pytest.mark.parametrize(
    "reader",
    ["bicycle_toml", "rider_toml", "benchmark_toml", "benchmark_text", "measured", "lumped_rider", "signal_csv"],
)
def test_readers_on_files_that_are_not_input(tmp_path, content, reader):
    from bikerider.io.benchmark_file import load_benchmark_parameters
    from bikerider.io.bicycleparameters import read_lumped_rider, read_measured_file
    from bikerider.io.signal_csv import read_signal_csv
    from bikerider.io.toml_input import load_bicycle_toml, load_rider_toml

    readers = {
        "bicycle_toml": (load_bicycle_toml, "b.toml"),
        "rider_toml": (load_rider_toml, "r.toml"),
        "benchmark_toml": (load_benchmark_parameters, "p.toml"),
        "benchmark_text": (load_benchmark_parameters, "p.txt"),
        "measured": (read_measured_file, "XMeasured.txt"),
        "lumped_rider": (read_lumped_rider, "JXBenchmark.txt"),
        "signal_csv": (read_signal_csv, "t.csv"),
    }
    function, name = readers[reader]
    path = _write(tmp_path, name, content)
    with pytest.raises(BikeriderError) as info:
        function(path)
    assert_names_file(info.value, path)
    # A folder or a missing file in place of a file: a clear error too (FileFormatError or OSError
    # the CLI reports), never a traceback from deep inside.
    folder = tmp_path / ("dir_" + name)
    folder.mkdir()
    with pytest.raises((BikeriderError, OSError)) as info:
        function(folder)
    assert folder.name in str(info.value)


# ------------------------------------------------------------------------------------------
# Data of the gap diagnosis
# ------------------------------------------------------------------------------------------
GAP = Path(str(resources.files("bikerider") / "data"))
GAP_FILES = {
    "eigenvalues": GAP / "gap_examples" / "eigenvalues.csv",
    "canonical": GAP / "gap_examples" / "canonical.csv",
    "control": GAP / "gap_examples" / "control.toml",
    "model": GAP / "gap" / "kooijman2008_bicycle.toml",
}


def _gap_read(kind: str, path: Path):
    from bikerider.io import gap_data
    from bikerider.io.gap_model import load_model

    if kind == "eigenvalues":
        d = gap_data.read_eigenvalues(path)
        # an empty or missing real_sigma / imag_sigma is NaN, "not given" (the diagnosis takes the scatter
        # of replicates then); any given one is a positive number
        for sigma in (d.real_sigma, d.imag_sigma):
            given = sigma[~np.isnan(sigma)]
            assert np.all(np.isfinite(given) & (given > 0)), sigma
        return [d.speed, d.value, d.speed_sigma, d.gains]
    if kind == "canonical":
        d = gap_data.read_canonical(path)
        return [d.value, d.sigma, list(d.speed_range.values())]
    if kind == "control":
        return [law([1.0, 5.0]) for law in gap_data.read_control(path).values()]
    model = load_model(path)
    return model.parameters.values


@FUZZ
@given(st.data(), st.sampled_from(sorted(GAP_FILES)))
def test_gap_data_readers(tmp_path_factory, data, kind):
    base = GAP_FILES[kind]
    what, text = data.draw(mutated(base.read_bytes()))
    path = _write(tmp_path_factory.mktemp("fuzz"), base.name, text)
    try:
        values = _gap_read(kind, path)
    except BikeriderError as exc:
        assert_names_file(exc, path)
        return
    assert_all_finite(values, f"{kind}: {what}")


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(st.data())
def test_gap_perturbation_run(tmp_path_factory, data):
    from bikerider.io import gap_data

    base = GAP / "gap_examples" / "perturbation_run.csv"
    what, text = data.draw(mutated(base.read_bytes()))
    path = _write(tmp_path_factory.mktemp("fuzz"), base.name, text)
    try:
        run = gap_data.read_perturbation(path)
    except BikeriderError as exc:
        assert_names_file(exc, path)
        return
    from bikerider.gap.measured.records import fit_record

    fit = fit_record(run)  # a run that cannot be fitted is left out with a reason, never an exception
    assert_all_finite([run.speed, run.speed_sigma, run.time, run.signals], what)
    if fit.used:
        e = fit.estimate
        assert_all_finite([e.eigenvalue, e.real_sigma, e.imag_sigma], what)
    else:
        assert fit.reason


def test_gap_speed_uncertainty_larger_than_the_speed_is_refused(tmp_path):
    """Found by fuzzing: speed_sigma = 1120 for a 5.1 m/s run made the diagnosis evaluate the model at
    a negative speed and fail with an error naming no file."""
    from bikerider.errors import FileFormatError

    path = _write(tmp_path, "run.csv", b"speed,real,imag,speed_sigma,group\n5.1,-1.16,5.44,1120,run52\n")
    code, out, err = run_cli(
        [
            "gap",
            "--model",
            str(GAP / "gap" / "kooijman2008_bicycle.toml"),
            "--data",
            str(path),
            "--effects",
            "parameters",
        ]
    )
    assert code == 2 and f"{path}:2" in err and "speed_sigma = 1120" in err and "below the speed" in err
    with pytest.raises(FileFormatError, match="uncertainty below the speed"):
        from bikerider.io.gap_data import read_perturbation

        run = (
            (GAP / "gap_examples" / "perturbation_run.csv")
            .read_text()
            .replace("# speed = 7.0", "# speed = 7.0\n# speed_sigma = 7.5")
        )
        read_perturbation(_write(tmp_path, "run7.csv", run.encode()))


def test_gap_with_a_crawling_speed_names_the_file(tmp_path):
    path = _write(tmp_path, "run.csv", b"speed,real,imag,speed_sigma,group\n0.0005,-1.16,5.44,0.0001,run52\n")
    code, out, err = run_cli(
        [
            "gap",
            "--model",
            str(GAP / "gap" / "kooijman2008_bicycle.toml"),
            "--data",
            str(path),
            "--effects",
            "parameters",
        ]
    )
    assert code == 0 or str(path) in err, err
