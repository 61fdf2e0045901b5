"""Issue 12, inputs: what a fuzzing run and an audit found the readers crash on, accept silently, or
refuse without need.  Each test names the case; each failed before its fix.

* the one guard every reader opens its file through (``bikerider.io.input_file``): FIFOs, folders,
  empty paths and oversized files refused, naming the file;
* numbers no float holds, uncertainties that say nothing, denormal lengths and masses: errors, not
  tracebacks or NaN;
* what bikerider leaves out or changes, and values possible but unusual: notes, at default
  verbosity and in every ``--json`` output;
* one validation path (``sensitivity`` checks what ``estimate`` checks; ``sensitivity --inputs``
  reads benchmark files as ``benchmark`` does);
* every error of a file at once.
"""

from __future__ import annotations

import json
import os
import re
import threading
from importlib import resources
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import meijaard_values, run_cli, signal_csv

from bikerider.benchmark import rules
from bikerider.errors import FileFormatError, InputError, InputErrors
from bikerider.estimate import default_files
from bikerider.io.chain_inputs import paper_files

BICYCLE_TOML, RIDER_TOML = default_files()
BICYCLE, RIDER = BICYCLE_TOML.read_text(), RIDER_TOML.read_text()
BP = Path(str(resources.files("bikerider") / "data" / "bicycleparameters" / "bicycles"))
SHIPPED_BENCHMARK = {name: BP / name / "Parameters" / f"{name}Benchmark.txt" for name in ("Rigid", "Silver", "Browser")}
DATA = Path(__file__).parent / "data"


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _bicycle(tmp_path: Path, old: str, new: str) -> Path:
    assert old in BICYCLE, old
    return _write(tmp_path, "bicycle.toml", BICYCLE.replace(old, new))


def _rider(tmp_path: Path, old: str, new: str) -> Path:
    assert old in RIDER, old
    return _write(tmp_path, "rider.toml", RIDER.replace(old, new))


def _benchmark_text(tmp_path: Path, **changes) -> Path:
    values = {**meijaard_values(), **changes}
    return _write(tmp_path, "TestBenchmark.txt", "".join(f"{k} = {v}\n" for k, v in values.items() if v is not None))


def _benchmark_toml(tmp_path: Path, extra: str = "", **changes) -> Path:
    values = {**meijaard_values(), **changes}
    body = "".join(f"{k} = {v if isinstance(v, str) else repr(v)}\n" for k, v in values.items() if v is not None)
    return _write(tmp_path, "bench.toml", f"[benchmark]\n{body}{extra}")


def _json(out: str) -> dict:
    return json.loads(out)


# ------------------------------------------------------------------------------------------
# One guard for every input file
# ------------------------------------------------------------------------------------------
READERS = {
    "bicycle_toml": ("bikerider.io.toml_input", "load_bicycle_toml"),
    "rider_toml": ("bikerider.io.toml_input", "load_rider_toml"),
    "benchmark": ("bikerider.io.benchmark_file", "load_benchmark_parameters"),
    "name_value": ("bikerider.io.name_value_file", "read_name_value_file"),
    "detect_format": ("bikerider.io.bicycleparameters", "detect_format"),
    "signal_csv": ("bikerider.io.signal_csv", "read_signal_csv"),
}


def _reader(kind: str):
    module, name = READERS[kind]
    return getattr(__import__(module, fromlist=[name]), name)


def _within(seconds: float, function, *args):
    """``function(*args)`` on a thread; fail (instead of hanging the suite) if it takes longer."""
    outcome: dict = {}

    def target():
        try:
            outcome["value"] = function(*args)
        except BaseException as exc:  # noqa: BLE001 - handed to the test
            outcome["error"] = exc

    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), f"{function.__name__} still reading after {seconds} s"
    return outcome


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
@pytest.mark.parametrize("kind", sorted(READERS))
def test_a_fifo_is_refused_not_read_forever(tmp_path, kind):
    fifo = tmp_path / "input.toml"
    os.mkfifo(fifo)
    outcome = _within(10, _reader(kind), fifo)
    error = outcome.get("error")
    assert isinstance(error, FileFormatError), outcome
    assert str(fifo) in str(error) and "FIFO" in str(error) and "not a regular file" in str(error)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
def test_a_fifo_on_the_command_line_ends_in_a_message(tmp_path):
    fifo = tmp_path / "bicycle.toml"
    os.mkfifo(fifo)
    outcome = _within(20, run_cli, ["estimate", "--bicycle", str(fifo)])
    code, _, err = outcome["value"]
    assert code == 2 and "FIFO" in err and str(fifo) in err


@pytest.mark.parametrize("kind", sorted(READERS))
def test_a_file_beyond_the_limit_is_refused_naming_its_size(tmp_path, kind):
    from bikerider.io.input_file import DATA_LIMIT, TEXT_LIMIT

    path = tmp_path / "big.txt"
    size = (DATA_LIMIT if kind == "signal_csv" else TEXT_LIMIT) + 1
    with open(path, "wb") as stream:  # sparse: no disk used, and the reader must not read it
        stream.truncate(size)
    with pytest.raises(FileFormatError, match=r"MiB: expected an input file of at most") as info:
        _reader(kind)(path)
    assert str(path) in str(info.value)


@pytest.mark.parametrize("kind", sorted(READERS))
def test_an_empty_path_is_no_file(kind):
    with pytest.raises(InputError, match="an empty path names no file"):
        _reader(kind)("")


@pytest.mark.parametrize(
    "argv",
    [
        ["estimate", "--bicycle", ""],
        ["estimate", "--rider", ""],
        ["sensitivity", "weave_speed", "--bicycle", "", "--rider", str(RIDER_TOML)],
        ["sensitivity", "weave_speed", "--inputs", ""],
        ["benchmark", ""],
    ],
    ids=["estimate-bicycle", "estimate-rider", "sensitivity-bicycle", "sensitivity-inputs", "benchmark"],
)
def test_an_empty_path_never_means_the_default(argv):
    code, out, err = run_cli(argv)
    assert code == 2 and "empty path" in err, (code, out[:200], err)


def test_an_empty_name_value_file_is_one_error_not_every_value_missing(tmp_path):
    path = _write(tmp_path, "EmptyBenchmark.txt", "# to be measured\n")
    code, _, err = run_cli(["benchmark", str(path)])
    assert (
        code == 2
        and err.strip()
        == f"bikerider benchmark: error: {path}: no 'name = value' entries: the file is empty or holds only comments"
    )


def test_an_empty_control_file_is_not_no_control(tmp_path):
    from bikerider.io.gap_data import read_control

    for text in ("", "# gains to follow\n"):
        path = _write(tmp_path, "control.toml", text)
        with pytest.raises(FileFormatError, match="no values: the file is empty"):
            read_control(path)
    gap = Path(str(resources.files("bikerider") / "data" / "gap_examples"))
    model = Path(str(resources.files("bikerider") / "data" / "gap" / "kooijman2008_bicycle.toml"))
    for control in ("", str(path)):
        argv = ["gap", "--model", str(model), "--data", str(gap / "eigenvalues.csv"), "--control", control]
        code, _, err = run_cli(argv + ["--effects", "parameters"])
        assert code == 2 and ("empty path" in err or "no values" in err), err


# ------------------------------------------------------------------------------------------
# Numbers no float holds; uncertainties that say nothing; denormals
# ------------------------------------------------------------------------------------------
def test_a_huge_integer_in_any_toml_number_is_an_error_not_a_traceback(tmp_path):
    huge = "1" * 400
    cases = [
        (["estimate", "--bicycle", str(_bicycle(tmp_path, "g = 9.81", f"g = {huge}"))], "environment.g"),
        (["estimate", "--rider", str(_rider(tmp_path, "l_to = 0.48", f"l_to = {huge}"))], "measurements.l_to"),
        (["benchmark", str(_benchmark_toml(tmp_path, g=huge))], "g"),
    ]
    for argv, name in cases:
        code, _, err = run_cli(argv)
        assert code == 2 and f"{name} = 'an integer of about 400 digits'" in err, err
        assert "expected a number within floating-point range" in err
    path = _bicycle(tmp_path, "g = 9.81", "g = " + "9" * 5000)  # beyond the digits Python converts
    assert "not a number bikerider can read" in run_cli(["estimate", "--bicycle", str(path)])[2]


def test_a_huge_integer_control_gain_is_an_error(tmp_path):
    from bikerider.io.gap_data import read_control

    with pytest.raises(InputError, match=r"k_phid = .*(about 400 digits|\(400 digits\)).*expected"):
        read_control(_write(tmp_path, "control.toml", "[control]\nk_phid = " + "1" * 400 + "\n"))


def test_a_huge_sigma_on_an_angle_is_an_error_not_inf_or_an_overflow(tmp_path):
    path = _bicycle(tmp_path, 'lam_ht_deg = "68.5 +/- 0.5"', 'lam_ht_deg = "68.5 +/- 1e300"')
    for argv in (
        ["estimate", "--bicycle", str(path)],
        ["sensitivity", "weave_speed", "--bicycle", str(path), "--rider", str(RIDER_TOML)],
    ):
        code, out, err = run_cli(argv)
        assert code == 2 and "lam_ht_deg uncertainty = 1e+300: expected at most 180 degrees" in err, err
        assert "inf" not in out and "nan" not in out
    benchmark = _benchmark_toml(tmp_path, lam=None, lam_deg='"18 +/- 1e300"')
    code, _, err = run_cli(["benchmark", str(benchmark)])
    assert code == 2 and "lam uncertainty" in err


@pytest.mark.parametrize(
    "which, old, new, name, unit",
    [
        ("rider", "l_to = 0.48", "l_to = 5e-324", "l_to", "m"),
        ("rider", "mass = 72.0", "mass = 5e-324", "mBr", "kg"),
        ("bicycle", 'l_s = "0.250 +/- 0.002"', "l_s = 1e-320", "l_s", "m"),
        ("bicycle", 'mass = "4.35 +/- 0.02"', "mass = 5e-324", "mH", "kg"),
    ],
)
def test_denormal_lengths_and_masses_are_errors(tmp_path, which, old, new, name, unit):
    path = (_rider if which == "rider" else _bicycle)(tmp_path, old, new)
    code, _, err = run_cli(["estimate", f"--{which}", str(path)])
    assert code == 2 and re.search(rf"{name} = [\d.e-]+: expected at least 1e-06 {unit} \(", err), err
    assert "Traceback" not in err and "LinAlgError" not in err


def test_denormal_masses_in_a_benchmark_file_are_errors(tmp_path):
    code, _, err = run_cli(["benchmark", str(_benchmark_text(tmp_path, mH="5e-324"))])
    assert code == 2 and "mH = 4.94066e-324: expected at least 1e-06 kg" in err


def test_a_megabyte_csv_cell_is_an_error(tmp_path):
    path = _write(tmp_path, "trial.csv", "time,rate\n0.0,1.0\n0.01," + "1" * (1 << 20) + "\n")
    code, _, err = run_cli(["period", str(path)])
    assert code == 2 and f"{path}:3" in err and "Traceback" not in err, err


# ------------------------------------------------------------------------------------------
# Notes: what is left out or changed, and what is unusual, shown by default and in --json
# ------------------------------------------------------------------------------------------
def test_an_impossible_iyy_left_out_of_a_benchmark_file_is_a_note_in_text_and_json():
    path = SHIPPED_BENCHMARK["Browser"]  # BicycleParameters' own: IByy breaks the triangle inequality
    code, out, err = run_cli(["benchmark", str(path)])
    assert code == 0 and "bikerider benchmark: note:" in err and "IByy = 1.3164" in err and "left out" in err
    code, out, err = run_cli(["benchmark", "--json", str(path)])
    notes = _json(out)["notes"]
    assert any("IByy" in n and "left out" in n for n in notes) and "note:" not in err  # shown once, in the JSON


@pytest.mark.parametrize("value", ["-1", "0", "1e308"])
def test_a_negative_zero_or_huge_iyy_is_an_error(tmp_path, value):
    code, _, err = run_cli(["benchmark", str(_benchmark_text(tmp_path, IByy=value))])
    assert code == 2 and "IB" in err and ("principal moments" in err or "at most 10000" in err), err


def test_every_json_output_has_notes(tmp_path):
    trial = tmp_path / "trial.csv"
    trial.write_bytes(signal_csv())
    runs = [
        ["benchmark", "--json", "--bicycle", "Benchmark"],
        ["estimate", "--json"],
        ["sweep", "--json", "--bicycle", "Benchmark", "--vary", "c=0.05:0.1:2"],
        ["period", "--json", str(trial)],
    ]
    for argv in runs:
        code, out, err = run_cli(argv)
        assert code == 0, err
        assert isinstance(_json(out)["notes"], list), argv
    # The estimate's own notes and the readers' notes, each once
    notes = _json(run_cli(["estimate", "--json"])[1])["notes"]
    assert len(notes) == len(set(notes)) and any("IRyy = 0.16" in n for n in notes)


def test_radians_under_lam_deg_and_a_head_tube_at_179_degrees_are_notes(tmp_path):
    code, out, _ = run_cli(["benchmark", "--json", str(_benchmark_toml(tmp_path, lam=None, lam_deg=0.3665))])
    assert code == 0 and any("lam_deg = 0.3665 looks like radians" in n for n in _json(out)["notes"])
    path = _bicycle(tmp_path, 'lam_ht_deg = "68.5 +/- 0.5"', "lam_ht_deg = 179")
    code, out, _ = run_cli(["estimate", "--json", "--no-rider", "--bicycle", str(path)])
    assert code == 0 and any("lam_ht_deg = 179" in n and "outside the 45 to 90" in n for n in _json(out)["notes"])


def test_a_sigma_a_thousand_times_the_value_is_a_note(tmp_path):
    code, out, _ = run_cli(["benchmark", "--json", str(_benchmark_toml(tmp_path, mR='"2 +/- 1000"'))])
    assert code == 0 and any(
        "mR = 2 +/- 1e+03: its uncertainty is 500 times the value" in n for n in _json(out)["notes"]
    )
    path = _rider(tmp_path, "c_h = 0.58", 'c_h = "0.58 +/- 2.9"')
    code, out, _ = run_cli(["estimate", "--json", "--rider", str(path)])
    assert code == 0 and any("c_h" in n and "5 times the value" in n for n in _json(out)["notes"])


def test_sigmas_on_mass_fractions_are_a_note_not_ignored_silently(tmp_path):
    path = _rider(tmp_path, "head = 0.068", 'head = "0.068 +/- 0.01"')
    code, out, _ = run_cli(["estimate", "--json", "--rider", str(path)])
    assert code == 0 and any("mass_fractions.head" in n and "not used" in n for n in _json(out)["notes"])


# ------------------------------------------------------------------------------------------
# Values that cannot be: wheels, lam beside lam_deg, unknown tables and fields
# ------------------------------------------------------------------------------------------
def test_a_wheel_with_ixx_beyond_m_r2_is_an_error(tmp_path):
    path = _bicycle(tmp_path, 'Ixx = { torsional_period = "0.79 +/- 0.06" }', "Ixx = 0.5")
    code, _, err = run_cli(["estimate", "--bicycle", str(path)])
    assert code == 2 and "IRxx = 0.5: expected at most mR*rR^2 = 0.364928" in err, err
    code, _, err = run_cli(["benchmark", str(_benchmark_text(tmp_path, IFxx=0.5, IFyy=0.3))])
    assert code == 2 and "IFxx = 0.5: expected at most mF*rF^2 = 0.3675" in err, err


def test_lam_beside_lam_deg_is_an_error(tmp_path):
    code, _, err = run_cli(["benchmark", str(_benchmark_toml(tmp_path, lam_deg=18.0))])
    assert code == 2 and "lam_deg = 18: expected either lam (radians) or lam_deg (degrees), not both" in err


def test_unknown_tables_and_fields_are_reported(tmp_path):
    code, _, err = run_cli(["benchmark", str(_benchmark_toml(tmp_path, extra="[foo]\nx = 1\n"))])
    assert code == 2 and "foo = {'x': 1}: expected [benchmark] beside" in err, err
    measured = (BP / "Browser" / "RawData" / "BrowserMeasured.txt").read_text() + "foo = 1\n"
    code, _, err = run_cli(["estimate", "--no-rider", "--bicycle", str(_write(tmp_path, "XMeasured.txt", measured))])
    assert code == 2 and "foo = 1: expected a field of a BicycleParameters Measured file" in err, err
    code, _, err = run_cli(["estimate", "--bicycle", str(_write(tmp_path, "b.toml", BICYCLE + "[bicycle.x]\n"))])
    assert code == 2 and "bicycle.x = {}: expected one of the keys name, notes, source" in err, err


# ------------------------------------------------------------------------------------------
# One validation path
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "which, old, new, expected",
    [
        ("rider", "l_ll = 0.46", "l_ll = 0.2", "legs are 0.110 m too short"),
        ("rider", "l_ll = 0.46", "l_ll = 1.3", "the knee cannot close"),
        ("bicycle", 'l_cs = "0.460 +/- 0.002"', "l_cs = 0.01", "l_cs = 0.01: expected more than |rR - h_bb|"),
        ("bicycle", 'Iyy = "0.16 +/- 0.03"', "Iyy = 0.3", "IRyy = 0.3: expected at most 2*IRxx"),
    ],
)
def test_sensitivity_checks_what_estimate_checks(tmp_path, which, old, new, expected):
    path = (_rider if which == "rider" else _bicycle)(tmp_path, old, new)
    files = {"bicycle": str(BICYCLE_TOML), "rider": str(RIDER_TOML), which: str(path)}
    estimate = run_cli(["estimate", "--bicycle", files["bicycle"], "--rider", files["rider"]])
    sensitivity = run_cli(["sensitivity", "weave_speed", "--bicycle", files["bicycle"], "--rider", files["rider"]])
    for code, out, err in (estimate, sensitivity):
        assert code == 2 and expected in err, err
    assert estimate[2].split("error: ", 1)[1] == sensitivity[2].split("error: ", 1)[1]


@pytest.mark.parametrize("name", ["Rigid", "Silver"])
def test_sensitivity_inputs_reads_the_shipped_benchmark_files_as_benchmark_does(name):
    code, out, err = run_cli(["sensitivity", "weave_speed", "--inputs", str(SHIPPED_BENCHMARK[name]), "--top", "3"])
    assert code == 0, err
    assert ("IRzz dropped" in err or "IFzz dropped" in err) if name == "Silver" else "measured apart" in err


def test_sensitivity_inputs_reads_yb_zero(tmp_path):
    path = _write(tmp_path, "YBenchmark.txt", (DATA / "BenchmarkBenchmark.txt").read_text() + "yB = 0\n")
    code, _, err = run_cli(["sensitivity", "capsize_speed", "--inputs", str(path)])
    assert code == 0 and "yB = 0 m dropped" in err, err
    both = _write(tmp_path, "Both.txt", "lam_deg = 18\n" + (DATA / "BenchmarkBenchmark.txt").read_text())
    code, _, err = run_cli(["sensitivity", "capsize_speed", "--inputs", str(both)])
    assert code == 2 and "either lam (radians) or lam_deg (degrees), not both" in err


# ------------------------------------------------------------------------------------------
# The Moon
# ------------------------------------------------------------------------------------------
def test_a_bicycle_on_the_moon_is_modelled(tmp_path):
    code, out, err = run_cli(["benchmark", "--json", str(_benchmark_toml(tmp_path, g=1.62))])
    assert code == 0 and _json(out)["speeds"]["weave"] is not None, err
    # Measured on Earth, ridden on the Moon: the pendulum's gravity is g_lab.
    moon = _bicycle(tmp_path, "g = 9.81", "g = 1.62\ng_lab = 9.81")
    earth = run_cli(["estimate", "--json"])
    rider = str(paper_files()[1])  # --bicycle alone seats no rider; the Earth run seats the paper's
    code, out, err = run_cli(["estimate", "--json", "--bicycle", str(moon), "--rider", rider])
    assert code == 0, err
    weave_earth, weave_moon = _json(earth[1])["speeds"]["weave"], _json(out)["speeds"]["weave"]
    assert weave_moon == pytest.approx(weave_earth * (1.62 / 9.81) ** 0.5, rel=1e-9)  # v ~ sqrt(g L)
    # Without g_lab, the pendulums are taken to have swung on Earth, and a note says so.
    alone = _bicycle(tmp_path, "g = 9.81", "g = 1.62")
    code, out, err = run_cli(["estimate", "--json", "--bicycle", str(alone), "--rider", rider])
    assert code == 0 and _json(out)["speeds"]["weave"] == weave_moon, err
    assert any("reduced at g_lab = 9.81 m/s^2 (on Earth)" in n for n in _json(out)["notes"])
    # A pendulum that swung on the Moon with the periods of an Earth one cannot be: the message says why.
    swung = _bicycle(tmp_path, "g = 9.81", "g = 1.62\ng_lab = 1.62")
    code, _, err = run_cli(["estimate", "--bicycle", str(swung)])
    assert code == 2 and "at g = 1.62 m/s^2" in err and "g_lab" in err


# ------------------------------------------------------------------------------------------
# Every error of a file at once
# ------------------------------------------------------------------------------------------
def test_every_error_of_a_bicycle_file_at_once(tmp_path):
    from bikerider.io.toml_input import load_bicycle_toml

    text = (
        BICYCLE.replace('w = "1.120 +/- 0.002"', "w = 1120")
        .replace('mass = "3.12 +/- 0.02"', "mass = -3.12")
        .replace('c = "0.055 +/- 0.002"', 'c = "x"')
        .replace('h_bb = "0.295', 'hbb = "0.295')
        + "[foo]\nx = 1\n"
    )
    with pytest.raises(InputErrors) as info:
        load_bicycle_toml(_write(tmp_path, "bicycle.toml", text))
    names = [e.name for e in info.value.errors]
    assert set(names) == {"foo", "geometry.hbb", "geometry.c", "w", "mR"}, names
    message = str(info.value)
    assert message.startswith("5 input errors:\n") and message.count("bicycle.toml") == 5


def test_every_error_of_a_rider_file_at_once(tmp_path):
    from bikerider.io.toml_input import load_rider_toml

    text = (
        RIDER.replace("l_to = 0.48", "l_to = -1")
        .replace("c_h = 0.58", "c_h = 5800")
        .replace("torso = 0.510", "torso = 0.6")
    )
    with pytest.raises(InputErrors) as info:
        load_rider_toml(_write(tmp_path, "rider.toml", text))
    assert [e.name for e in info.value.errors] == ["c_h", "l_to", "mass fractions"]


def test_every_error_of_a_benchmark_file_at_once(tmp_path):
    from bikerider.io.benchmark_file import load_benchmark_parameters

    path = _benchmark_text(tmp_path, w=1020, mR=-2, zH=0.7, foo=1)
    with pytest.raises(InputErrors) as info:
        load_benchmark_parameters(path)
    assert [e.name for e in info.value.errors] == ["foo", "mR", "w", "zH"]
    code, _, err = run_cli(["benchmark", str(path)])
    assert code == 2 and err.startswith("bikerider benchmark: error: 4 input errors:\n") and err.count(str(path)) == 4


def test_every_line_that_cannot_be_read_at_once(tmp_path):
    from bikerider.io.name_value_file import read_name_value_file

    path = _write(tmp_path, "X.txt", "w = 1\nc = x\n3d = 1\nlam = 0.3\nlam = 0.4\n")
    with pytest.raises(
        FileFormatError, match=r"3 lines cannot be read:\n  .*:2: c: .*\n  .*:3: .*\n  .*:5: lam is given twice"
    ):
        read_name_value_file(path)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.sets(st.sampled_from(rules.POSITIVE), min_size=1, max_size=6), st.sampled_from(["-1", "0", "5e-324"]))
def test_each_impossible_value_of_a_benchmark_file_is_named_once(tmp_path_factory, names, bad):
    """Values that must be positive, made zero, negative or denormal in any combination: the error
    names each of them (and nothing else), one line each.  (A denormal moment of inertia is
    positive; the wheel's rules refuse it, naming the wheel's other moment: left out here.)"""
    from bikerider.io.benchmark_file import load_benchmark_parameters

    if bad == "5e-324":
        names = {n for n in names if not n.startswith("I")} or {"mR"}
    values = {**meijaard_values(), **dict.fromkeys(names, bad)}
    path = tmp_path_factory.mktemp("all") / "b.toml"
    path.write_text("".join(f"{k} = {v}\n" for k, v in values.items()))
    with pytest.raises(InputError) as info:
        load_benchmark_parameters(path)
    reported = [e.name for e in getattr(info.value, "errors", [info.value])]
    assert sorted(reported) == sorted(names), (reported, names)
    assert str(info.value).count(str(path)) == len(names)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    st.sampled_from(["l_to", "l_ll", "l_ul", "c_ch", "l_hh", "c_h", "l_ss", "c_ua"]),
    st.sampled_from(["5e-324", "1e-310", "-0.4", "1" * 400, '"0.4 +/- 1e300"']),
)
def test_a_hostile_rider_measurement_is_an_error_for_estimate_and_sensitivity(tmp_path_factory, name, bad):
    """Fuzzed cases of the issue (denormals, huge integers and sigmas) on every rider length: the same
    one-line error from both commands, naming the file and the measurement; never a traceback."""
    line = next(line for line in RIDER.splitlines() if line.startswith(f"{name} ="))
    path = tmp_path_factory.mktemp("rider") / "rider.toml"
    path.write_text(RIDER.replace(line, f"{name} = {bad}"))
    errors = []
    for command in (["estimate"], ["sensitivity", "weave_speed"]):
        code, out, err = run_cli([*command, "--bicycle", str(BICYCLE_TOML), "--rider", str(path)])
        assert code == 2 and str(path) in err and name in err and "Traceback" not in err, err
        errors.append(err.split("error: ", 1)[1])
    assert errors[0] == errors[1]
