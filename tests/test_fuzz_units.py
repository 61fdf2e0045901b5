"""Mixed units and impossible values in real input files: a message that names the value and, for a
likely unit slip, the unit it was probably given in.  Each case edits one line of a valid file."""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

import pytest
from strategies import run_cli

from bikerider.errors import InputError
from bikerider.estimate import default_files

BP = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
TESTS = Path(__file__).parent
BICYCLE_TOML, RIDER_TOML = default_files()


def _edited(tmp_path: Path, base: Path, pattern: str, replacement: str, name: str | None = None) -> Path:
    text = base.read_text()
    new, count = re.subn(pattern, replacement, text, count=1, flags=re.MULTILINE)
    assert count == 1, f"{pattern!r} not in {base.name}"
    path = tmp_path / (name or base.name)
    path.write_text(new)
    return path


BICYCLE_CASES = [
    # (line pattern, replacement, words the message must hold)
    (r"^w = .*$", 'w = "1120 +/- 2"', ["w = 1120", "mm", "1.12 m"]),
    (r"^rF = .*$", "rF = 34.2", ["rF = 34.2", "cm", "0.342 m"]),
    (r"^lam_ht_deg = .*$", "lam_ht_deg = 1.2", ["lam_ht_deg = 1.2", "looks like radians", "68.75 deg"]),
    (r"^lam_st_deg = .*$", "lam_st_deg = 200", ["lam_st_deg = 200", "between 0 and 180 degrees"]),
    (r"^g = .*$", "g = 981", ["g = 981", "cm/s^2", "9.81 m/s^2"]),
    (r"^g = .*$", "g = 0", ["g = 0", "positive"]),
    (r"^g = .*$", "g = -9.81", ["g = -9.81", "positive"]),
    (r"^k_t = .*$", 'k_t = "-5.01"', ["k_t = -5.01", "positive torsional stiffness"]),
    (r'^Ixx = \{ torsional_period = "0.79', 'Ixx = { torsional_period = "790', ["790", "ms", "0.79 s"]),
    (r'^mass = "14.05 \+/- 0.02"', 'mass = "14050"', ["mBf = 14050", "in g", "14.05 kg"]),
    (
        r'com = \{ x = "0.25 \+/- 0.02", z = "-0.62',
        'com = { x = "0.25 +/- 0.02", z = "0.62',
        ["zBf = 0.62", "z points down", "z < 0"],
    ),
    (r"^c = .*$", 'c = "55 +/- 2"', ["c = 55", "mm", "0.055 m"]),
]


@pytest.mark.parametrize("pattern, replacement, words", BICYCLE_CASES, ids=[c[1] for c in BICYCLE_CASES])
def test_bicycle_toml_unit_slips(tmp_path, pattern, replacement, words):
    from bikerider.io.toml_input import load_bicycle_toml

    path = _edited(tmp_path, BICYCLE_TOML, pattern, replacement, "bicycle.toml")
    with pytest.raises(InputError) as info:
        load_bicycle_toml(path)
    message = str(info.value)
    assert str(path) in message
    for word in words:
        assert word in message, message


RIDER_CASES = [
    (r"^mass = .*$", "mass = 72000", ["mBr = 72000", "in g", "72 kg"]),
    (r"^l_ll = .*$", "l_ll = 460", ["l_ll = 460", "mm", "0.46 m"]),
    (r"^c_ch = .*$", "c_ch = 94", ["c_ch = 94", "cm", "0.94 m"]),
    (r"^lam_fl_deg = .*$", "lam_fl_deg = 1.447", ["lam_fl_deg = 1.447", "looks like radians", "82.91 deg"]),
    (r"^l_ua = .*$", "l_ua = 0", ["l_ua = 0", "positive"]),
]


@pytest.mark.parametrize("pattern, replacement, words", RIDER_CASES, ids=[c[1] for c in RIDER_CASES])
def test_rider_toml_unit_slips(tmp_path, pattern, replacement, words):
    from bikerider.io.toml_input import load_rider_toml

    path = _edited(tmp_path, RIDER_TOML, pattern, replacement, "rider.toml")
    with pytest.raises(InputError) as info:
        load_rider_toml(path)
    message = str(info.value)
    assert str(path) in message
    for word in words:
        assert word in message, message


BENCHMARK_CASES = [
    (r"^w = .*$", "w = 1020+/-0.0", ["w = 1020", "mm", "1.02 m"]),
    (r"^lam = .*$", "lam = 18+/-0.0", ["lam = 18", "looks like degrees", "lam_deg", "0.314159 rad"]),
    (r"^zB = .*$", "zB = 0.9+/-0.0", ["zB = 0.9", "z points down"]),
    (r"^mB = .*$", "mB = 85000+/-0.0", ["mB = 85000", "in g", "85 kg"]),
    (r"^rR = .*$", "rR = 1e-9+/-0.0", ["rR = 1e-09", "at least 0.001 m"]),
    (r"^IRyy = .*$", "IRyy = 1.2+/-0.0", ["IRyy = 1.2", "triangle inequality"]),
]


@pytest.mark.parametrize("pattern, replacement, words", BENCHMARK_CASES, ids=[c[1] for c in BENCHMARK_CASES])
def test_benchmark_text_unit_slips(tmp_path, pattern, replacement, words):
    path = _edited(tmp_path, TESTS / "data" / "BenchmarkBenchmark.txt", pattern, replacement)
    code, out, err = run_cli(["benchmark", str(path)])
    assert code == 2 and "Traceback" not in err
    assert str(path) in err
    for word in words:
        assert word in err, err


MEASURED_CASES = [
    (r"^w = .*$", "w = 1121+/-2", ["w = 1121", "mm", "1.121 m"]),
    (r"^gamma = .*$", "gamma = 1.171+/-0.003", ["gamma = 1.171", "looks like radians"]),
    (r"^TcB1 = .*$", "TcB1 = 1717.3", ["TcB1 = 1717.3", "ms", "1.7173 s"]),
    (r"^mB = .*$", "mB = 9860+/-20", ["mB = 9860", "in g", "9.86 kg"]),
    (r"^g = .*$", "g = 0", ["g = 0", "positive"]),
    (r"^lamst = .*$", "lamst = 68.5", ["lamst = 68.5", "6.28319 rad"]),
]


@pytest.mark.parametrize("pattern, replacement, words", MEASURED_CASES, ids=[c[1] for c in MEASURED_CASES])
def test_measured_file_unit_slips(tmp_path, pattern, replacement, words):
    from bikerider.io.bicycleparameters import read_measured_file

    base = BP / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt"
    path = _edited(tmp_path, base, pattern, replacement)
    with pytest.raises(InputError) as info:
        read_measured_file(path)
    message = str(info.value)
    assert f"{path}:" in message  # the file and the line
    for word in words:
        assert word in message, message


def test_unit_slip_through_the_command_line_exits_2_with_one_line(tmp_path):
    path = _edited(tmp_path, BICYCLE_TOML, r"^w = .*$", 'w = "1120 +/- 2"', "bicycle.toml")
    code, out, err = run_cli(["estimate", "--bicycle", str(path), "--json"])
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("bikerider estimate: error: ") and "1.12 m" in err


def test_plausible_extremes_are_still_accepted(tmp_path):
    """The limits are far from real bicycles: a long cargo bike, a tall rider and a slack head angle pass."""
    from bikerider.io.toml_input import load_bicycle_toml, load_rider_toml

    bicycle = _edited(tmp_path, BICYCLE_TOML, r"^lam_ht_deg = .*$", 'lam_ht_deg = "45 +/- 0.5"', "b1.toml")
    assert load_bicycle_toml(bicycle)["lam_ht"] == pytest.approx(0.7853981633974483)
    bicycle = _edited(tmp_path, bicycle, r"^w = .*$", 'w = "2.6 +/- 0.002"', "b2.toml")
    assert load_bicycle_toml(bicycle)["w"] == 2.6
    rider = _edited(tmp_path, RIDER_TOML, r"^mass = .*$", "mass = 160.0", "r1.toml")
    assert load_rider_toml(rider)["mBr"] == 160.0
