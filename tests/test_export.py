"""Benchmark parameters written as TOML, BicycleParameters text and JSON read back unchanged."""

from __future__ import annotations

import json

import pytest

import bikerider
from bikerider.errors import FileFormatError, InputError
from bikerider.io.benchmark_file import load_benchmark_parameters
from bikerider.io.export import (
    benchmark_txt_filename,
    parameters_to_benchmark_txt,
    parameters_to_json,
    parameters_to_toml,
    rows_to_csv,
)

SETS = [("Browser", None), ("Benchmark", None), ("Rigid", "Jason"), ("Fisher", None)]


def _write_and_read(tmp_path, params, kind):
    if kind == "toml":
        path = tmp_path / "bike.toml"
        path.write_text(parameters_to_toml(params, name="bike"))
    elif kind == "txt":
        path = tmp_path / benchmark_txt_filename("Bike")
        path.write_text(parameters_to_benchmark_txt(params, "Bike"))
    else:
        path = tmp_path / "bike.json"
        path.write_text(parameters_to_json(params))
    return load_benchmark_parameters(path)


@pytest.mark.parametrize("kind", ["toml", "txt", "json"])
@pytest.mark.parametrize("bicycle, rider", SETS)
def test_a_written_parameter_set_reads_back_bit_for_bit(tmp_path, kind, bicycle, rider):
    params = bikerider.named(bicycle, rider=rider)
    back = _write_and_read(tmp_path, params, kind)
    assert back.values == params.values  # floats compared exactly, None for what is not determined
    assert {k: s for k, s in back.sigmas.items() if back.values[k] is not None} == {
        k: s for k, s in params.sigmas.items() if params.values[k] is not None
    }


@pytest.mark.parametrize("kind", ["toml", "txt", "json"])
def test_an_estimated_set_with_first_order_sigmas_reads_back(tmp_path, kind):
    result = bikerider.estimate_default()
    sigmas = bikerider.estimate_uncertainty(result).benchmark
    params = bikerider.BenchmarkParameters(
        result.parameters.values, {k: float(sigmas.get(k) or 0.0) for k in result.parameters.values}, "estimate"
    )
    assert any(v > 0 for v in params.sigmas.values())
    back = _write_and_read(tmp_path, params, kind)
    for name, value in params.values.items():
        assert back.values[name] == value
        if value is not None:
            assert back.sigmas[name] == params.sigmas[name]


def test_the_text_file_is_what_bicycleparameters_writes():
    params = bikerider.named("Browser")
    lines = parameters_to_benchmark_txt(params, "Browser").splitlines()
    assert [line.split(" = ")[0] for line in lines] == sorted(line.split(" = ")[0] for line in lines)
    assert "c = 0.0685808540382+/-0.00169464113488" in lines
    assert len(lines) == sum(v is not None for v in params.values.values())  # what the set determines


def test_the_json_names_its_format_and_units():
    doc = json.loads(parameters_to_json(bikerider.named("Benchmark")))
    assert doc["format"] == "bikerider.benchmark_parameters" and doc["units"].startswith("SI")
    assert doc["values"]["w"] == 1.02 and doc["sigmas"]["w"] == 0.0


def test_a_bad_bicycle_name_and_a_foreign_json_are_refused(tmp_path):
    with pytest.raises(InputError, match="bicycle name"):
        parameters_to_benchmark_txt(bikerider.named("Benchmark"), "my bike")
    path = tmp_path / "x.json"
    path.write_text('{"a": 1}')
    with pytest.raises(FileFormatError, match="bikerider.benchmark_parameters"):
        load_benchmark_parameters(path)
    path.write_text("{")
    with pytest.raises(FileFormatError, match="not JSON"):
        load_benchmark_parameters(path)


def test_csv_rows_keep_floats_and_leave_none_empty():
    text = rows_to_csv([{"a": 0.1, "b": None, "c": "x"}])
    assert text == "a,b,c\n0.1,,x\n"
