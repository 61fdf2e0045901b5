"""Hostile input through the command line: mutated files and random argument lists.

Contract (bikerider.cli.main): exit status 0 (or 1 for a batch in which some bicycle failed) with
finite output, or 2 with a one-line message on stderr naming the offending file, option or value;
argparse usage errors also exit 2.  Never a traceback, never NaN or infinity in ``--json`` output.
"""

from __future__ import annotations

import os
import re
import shutil
import time
from importlib import resources
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import check_json_output, mutated, run_cli, signal_csv

from bikerider.estimate import default_files

FUZZ = settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
BP = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
BICYCLE_TOML, RIDER_TOML = default_files()
TESTS = Path(__file__).parent


def _assert_clean(code: int, out: str, err: str, path: Path | None, json_wanted: bool, allowed=(0, 2)) -> None:
    assert code in allowed, f"exit {code}: {err}"
    assert "Traceback" not in err and "Traceback" not in out
    if code == 2 and path is not None:
        assert str(path) in err or path.name in err, f"message does not name {path.name}: {err}"
    if code != 0:
        assert err.strip(), "a failure without a message"
        lines = err.strip().splitlines()
        many = re.match(r"bikerider \w+: error: (?:.*: )?(\d+) (?:input errors|lines cannot be read):$", lines[0])
        if many:  # every error of a file at once: one indented line each (at most 20, then a count)
            assert len(lines) == 1 + min(int(many.group(1)), 21) and all(line.startswith("  ") for line in lines[1:]), (
                err
            )
        else:
            assert len(lines) <= 3, f"more than a short message: {err}"
    elif json_wanted:
        check_json_output(out, "--json output")


@FUZZ
@given(st.data(), st.sampled_from(["bicycle", "rider"]))
def test_estimate_with_a_mutated_file(tmp_path_factory, data, which):
    base = BICYCLE_TOML if which == "bicycle" else RIDER_TOML
    what, text = data.draw(mutated(base.read_bytes()))
    path = tmp_path_factory.mktemp("cli") / f"{which}.toml"
    path.write_bytes(text)
    code, out, err = run_cli(["estimate", "--json", f"--{which}", str(path)])
    # A rider who cannot reach is named by the rider file even when the bicycle file changed.
    if code == 2 and which == "bicycle" and str(RIDER_TOML) in err:
        path = RIDER_TOML
    _assert_clean(code, out, err, path, json_wanted=True)


@FUZZ
@given(st.data())
def test_benchmark_with_a_mutated_file(tmp_path_factory, data):
    what, text = data.draw(mutated((TESTS / "data" / "BenchmarkBenchmark.txt").read_bytes()))
    path = tmp_path_factory.mktemp("cli") / "BenchmarkBenchmark.txt"
    path.write_bytes(text)
    code, out, err = run_cli(["benchmark", "--json", str(path), "--speeds", "0:12:7"])
    _assert_clean(code, out, err, path, json_wanted=True)


@FUZZ
@given(st.data())
def test_period_with_a_mutated_record(tmp_path_factory, data):
    what, text = data.draw(mutated(signal_csv()))
    path = tmp_path_factory.mktemp("cli") / "trial.csv"
    path.write_bytes(text)
    code, out, err = run_cli(["period", "--json", str(path)])
    _assert_clean(code, out, err, path, json_wanted=True)


@settings(
    max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(st.data(), st.sampled_from(["Browser", "Fisher", "Rigid", "Yellow"]))
def test_batch_with_one_mutated_measured_file(tmp_path_factory, data, name):
    root = tmp_path_factory.mktemp("cli") / "bp"
    shutil.copytree(BP / "bicycles", root / "bicycles")
    target = root / "bicycles" / name / "RawData" / f"{name}Measured.txt"
    what, text = data.draw(mutated(target.read_bytes()))
    target.write_bytes(text)
    code, out, err = run_cli(["batch", str(root)])
    _assert_clean(code, out, err, None, json_wanted=False, allowed=(0, 1))
    if code == 1:  # the bad bicycle is reported, naming its file, and every other one finished
        assert f"{name}: " in out and f"{name}Measured.txt" in out
        others = [n for n in ("Benchmark", "Browser", "Browserins", "Fisher", "Rigid", "Silver", "Yellow") if n != name]
        header = out.splitlines()[0].split()
        assert header == others


# ------------------------------------------------------------------------------------------
# Random argument lists
# ------------------------------------------------------------------------------------------
def _token_pool(tmp: Path) -> list[str]:
    nan_file = tmp / "nan.toml"
    nan_file.write_text("[benchmark]\nw = nan\n")
    binary = tmp / "binary.txt"
    binary.write_bytes(bytes(range(256)))
    return [
        "estimate",
        "benchmark",
        "period",
        "batch",
        "sensitivity",
        "--json",
        "--bicycle",
        "--rider",
        "--no-rider",
        "--speeds",
        "--plot",
        "--out",
        "--drift",
        "--wrt",
        "--inputs",
        "--top",
        "--speed",
        "--latex",
        "-v",
        "--help",
        "--version",
        "0:10:11",
        "10:0:5",
        "0:1e308:3",
        "nan:1:3",
        "0:10:-1",
        "a:b:c",
        "0:10",
        "5",
        "-1",
        "nan",
        "inf",
        "1e400",
        "",
        "w",
        "weave_speed",
        "capsize_speed",
        "IBxx",
        "l_ll",
        "mBr",
        str(BICYCLE_TOML),
        str(RIDER_TOML),
        str(TESTS / "data" / "BenchmarkBenchmark.txt"),
        str(BP),
        str(BP / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt"),
        str(BP / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt"),
        str(tmp / "missing.toml"),
        str(tmp),
        str(nan_file),
        str(binary),
        str(tmp / "out" / "x"),
        "\udcff",
        "é",
        "--",
        "-",
    ]


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(st.data())
def test_random_argument_lists(tmp_path_factory, data):
    tmp = tmp_path_factory.mktemp("argv")
    pool = _token_pool(tmp)
    argv = data.draw(st.lists(st.sampled_from(pool), max_size=6))
    if argv and argv[0] not in ("-v", "--help", "--version") and data.draw(st.booleans()):
        argv = [data.draw(st.sampled_from(["estimate", "benchmark", "period", "batch", "sensitivity"]))] + argv
    # Keep a run short: a Monte Carlo check or a huge speed grid is not what is being tested here.
    cwd = os.getcwd()
    os.chdir(tmp)  # `--plot 5` writes figures into ./5: a temporary folder, not the checkout
    try:
        code, out, err = run_cli(argv)
    finally:
        os.chdir(cwd)
    assert code in (0, 1, 2), f"{argv}: exit {code}: {err}"
    assert "Traceback" not in err and "Traceback" not in out, argv
    if code == 2:
        assert err.strip(), f"{argv}: exit 2 without a message"
    if code == 0 and "--json" in argv and "--help" not in argv and "--version" not in argv and out.strip():
        check_json_output(out, " ".join(argv))


@settings(
    max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(st.data(), st.sampled_from(["inputs", "bicycle", "rider"]))
def test_sensitivity_with_a_mutated_file(tmp_path_factory, data, which):
    bases = {"inputs": TESTS / "data" / "BenchmarkBenchmark.txt", "bicycle": BICYCLE_TOML, "rider": RIDER_TOML}
    what, text = data.draw(mutated(bases[which].read_bytes()))
    path = tmp_path_factory.mktemp("cli") / bases[which].name
    path.write_bytes(text)
    files = {"bicycle": str(BICYCLE_TOML), "rider": str(RIDER_TOML), which: str(path)}
    argv = (
        ["sensitivity", "weave_speed", "--inputs", files["inputs"]]
        if which == "inputs"
        else ["sensitivity", "capsize_speed", "--bicycle", files["bicycle"], "--rider", files["rider"], "--top", "3"]
    )
    code, out, err = run_cli(argv)
    if code == 2 and which == "bicycle" and str(RIDER_TOML) in err:
        path = RIDER_TOML  # a rider who cannot reach is named by the rider file
    _assert_clean(code, out, err, path, json_wanted=False)
    if code == 0:
        assert "nan" not in out.lower().replace("nanometre", ""), out
        assert " inf" not in out.lower(), out


@settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(st.data())
def test_gap_with_a_mutated_eigenvalue_file(tmp_path_factory, data):
    gap = Path(str(resources.files("bikerider") / "data" / "gap"))
    what, text = data.draw(mutated((gap / "kooijman2008_run52.csv").read_bytes()))
    path = tmp_path_factory.mktemp("cli") / "run52.csv"
    path.write_bytes(text)
    code, out, err = run_cli(
        [
            "gap",
            "--model",
            str(gap / "kooijman2008_bicycle.toml"),
            "--data",
            str(path),
            "--effects",
            "parameters,steer_damping",
            "--json",
        ]
    )
    _assert_clean(code, out, err, path, json_wanted=True)


# ------------------------------------------------------------------------------------------
# Hostile option values (issue 12): every numeric option of every command
# ------------------------------------------------------------------------------------------
HOSTILE_VALUES = [
    "-1",
    "0",
    "2",
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "",
    "1e400",
    "9" * 400,
    "18446744073709551616",
    "1000000000",
    "5e-324",
    "0:1e308:3",
    "0:3e8:2",
    "5:1:3",
    "0:10:0",
    "0:1:1e9",
    "a",
    "\udcff",
]
COMMAND_OPTIONS = {
    "estimate": (["estimate"], ["--speeds", "--dpi", "--monte-carlo", "--seed"]),
    "benchmark": (
        ["benchmark", str(TESTS / "data" / "BenchmarkBenchmark.txt")],
        ["--speeds", "--monte-carlo", "--seed"],
    ),
    "sensitivity": (["sensitivity", "weave_speed"], ["--speed", "--top", "--monte-carlo", "--seed", "--wrt"]),
    "sweep": (
        ["sweep", "--bicycle", "Benchmark", "--vary", "c=0.05:0.1:3"],
        ["--speeds", "--seed", "--target-weave-speed", "--weave-speeds", "--threads", "--chunk-size"],
    ),
    # every value drawn here is refused before the diagnosis runs (a valid one would take seconds)
    "gap": (["gap", "--model", "m.toml", "--data", "d.csv"], ["--speed", "--rider-rel-sigma"]),
}


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(st.data(), st.sampled_from(sorted(COMMAND_OPTIONS)))
def test_hostile_option_values_give_a_clear_error_or_a_clean_run(tmp_path_factory, data, command):
    """`--speeds 0:1e308:3` (LinAlgError), `--seed -1` (ValueError from NumPy) and
    `--monte-carlo 1000000000` (no end) were the fuzzing run's findings; every numeric option of
    every command now gives a result or a one-line error naming the option and its value."""
    base, options = COMMAND_OPTIONS[command]
    pairs = data.draw(
        st.lists(st.tuples(st.sampled_from(options), st.sampled_from(HOSTILE_VALUES)), min_size=1, max_size=2)
    )
    if command == "gap":
        pairs = [(o, v) for o, v in pairs if v not in ("0", "2")] or [("--speed", "-1")]
    argv = list(base) + [token for pair in pairs for token in pair] + data.draw(st.sampled_from([[], ["-v"]]))
    cwd = os.getcwd()
    os.chdir(tmp_path_factory.mktemp("hostile"))  # a stray output lands in a temporary folder
    try:
        started = time.monotonic()
        code, out, err = run_cli(argv)
        elapsed = time.monotonic() - started
    finally:
        os.chdir(cwd)
    assert code in (0, 2), f"{argv}: exit {code}: {err}"
    assert "Traceback" not in err and "Traceback" not in out, argv
    assert elapsed < 30, f"{argv} took {elapsed:.0f} s"
    if code == 2:
        last = err.strip().splitlines()[-1]
        named = any(option in last for option, _ in pairs) or ("m.toml" in last or "d.csv" in last)
        assert named, f"{argv}: the error does not name the option: {last}"
    else:
        assert "nan" not in out.lower().split("nanometre")[0] or command == "sweep", argv
