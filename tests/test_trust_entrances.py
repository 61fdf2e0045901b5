"""Trust at the entrances added after issue 12 (issue 23): design stores, experiment manifests, raw
logs, ``gap --next`` and ``sweep --dask``.

One section per group of the issue; every test failed before its fix (the issue's runs: a
traceback, a hang, an input deleted, a silent acceptance or a wrong refusal).  The Hypothesis
fuzz tests of the same entrances are in tests/test_fuzz_trust.py.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import threading
from importlib import resources
from pathlib import Path

import pytest
from strategies import run_cli

pytest.importorskip("zarr")

DATA = Path(str(resources.files("bikerider") / "data"))
PAPER = DATA / "paper"
KOOIJMAN = ["--model", str(DATA / "gap" / "kooijman2008_bicycle.toml")]
EXAMPLES = DATA / "gap_examples"
G = ["--bicycle", "Benchmark", "--vary", "c=0:0.15:4", "--vary", "lam_deg=0:30:3", "--vary", "w=0.9:1.2:2"]
"""The issue's design space: a grid of 24 designs."""

MANIFEST = """\
[experiment]
sample_rate = 100.0
logs = "{logs}"
windows = "{windows}"
fit = ["roll_rate"]

[columns]
roll_rate = "lean_rate"
speed = "speed"
"""


def _log(n: int = 800) -> str:
    import numpy as np

    t = np.arange(n) / 100.0
    decay = np.exp(-1.2 * (t % 4.0)) * np.sin(5.0 * (t % 4.0))
    return "lean_rate,speed\n" + "\n".join(f"{0.4 * d:.5f},4.2" for d in decay) + "\n"


def _experiment(folder: Path, logs: str = "logs", windows: str = "windows.csv", rows: int = 2) -> Path:
    """A manifest in ``folder`` whose logs and windows file are where ``logs`` and ``windows`` say."""
    (folder / logs).mkdir(parents=True, exist_ok=True)
    (folder / logs / "run.log").write_text(_log())
    (folder / windows).parent.mkdir(parents=True, exist_ok=True)
    (folder / windows).write_text("file,start,end\n" + "run.log,10,300\n" * rows)
    manifest = folder / "experiment.toml"
    manifest.write_text(MANIFEST.format(logs=logs, windows=windows))
    return manifest


def _error(err: str, command: str) -> str:
    assert err.startswith(f"bikerider {command}: error: ") and "Traceback" not in err, err
    return err


# ------------------------------------------------------------------------------------------
# 1. A report never deletes an input: logs and windows files are inputs of the run
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("inside", ["logs", "windows"])
@pytest.mark.parametrize("through_link", [False, True])
def test_a_report_folder_holding_a_log_or_windows_file_is_refused(tmp_path, inside, through_link):
    # before: the report replaced the folder, exit 0, and the raw logs were gone (also via a symlink)
    report = tmp_path / "rep"
    report.mkdir()
    (report / ".bikerider-report").write_text("an earlier report\n")
    if through_link:
        (tmp_path / "link").symlink_to(report)
    holder = "link" if through_link else "rep"
    manifest = _experiment(
        tmp_path,
        logs=f"{holder}/logs" if inside == "logs" else "logs",
        windows=f"{holder}/windows.csv" if inside == "windows" else "windows.csv",
    )
    kept = report / ("logs/run.log" if inside == "logs" else "windows.csv")
    before = kept.read_bytes()
    code, _, err = run_cli(["gap", *KOOIJMAN, "--experiment", str(manifest), "--report", str(report)])
    assert code == 2
    assert "holds the input" in _error(err, "gap")
    assert kept.read_bytes() == before


# ------------------------------------------------------------------------------------------
# 2. The number of records is bounded, before any log is read
# ------------------------------------------------------------------------------------------
def test_more_records_than_the_limit_are_refused_with_the_count(tmp_path, monkeypatch):
    from bikerider.io import experiment

    # before: 100,000 windows of one decay were cut and fitted (over an hour, 15 GB)
    manifest = _experiment(tmp_path, rows=experiment.MAX_RECORDS + 1)
    calls = []
    monkeypatch.setattr(experiment, "read_log", lambda *a, **k: calls.append(a))
    code, _, err = run_cli(["gap", *KOOIJMAN, "--experiment", str(manifest)])
    assert code == 2 and not calls
    assert f"records = '{experiment.MAX_RECORDS + 1:,}'" in _error(err, "gap")
    assert f"at most {experiment.MAX_RECORDS:,} records" in err


# ------------------------------------------------------------------------------------------
# 3. A damaged store: what is damaged, and --restart; never a traceback or a hang
# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def finished_store(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("store") / "s"
    code, out, err = run_cli(["sweep", *G, "--store", str(folder), "--quiet"])
    assert code == 0, err
    return folder


def _damage(store: Path, how: str) -> None:
    if how == "garbled zarr.json":
        (store / "zarr.json").write_text("{{{")
    elif how == "truncated zarr.json":
        (store / "zarr.json").write_bytes((store / "zarr.json").read_bytes()[:100])
    elif how == "empty zarr.json":
        (store / "zarr.json").write_text("")
    elif how == "missing array":
        import shutil

        shutil.rmtree(store / "valid")
    elif how == "garbled chunk":
        next(p for p in (store / "lower" / "c").rglob("*") if p.is_file()).write_text("garbage")
    elif how == "truncated chunk":
        chunk = next(p for p in (store / "weave_speed" / "c").rglob("*") if p.is_file())
        chunk.write_bytes(chunk.read_bytes()[:5])
    elif how == "changed shape":
        meta = json.loads((store / "lower" / "zarr.json").read_text())
        meta["shape"][0] += 1
        (store / "lower" / "zarr.json").write_text(json.dumps(meta))
    elif how == "zarr.json is /dev/zero":
        (store / "zarr.json").unlink()
        (store / "zarr.json").symlink_to("/dev/zero")
    elif how == "zarr.json is a FIFO":
        (store / "zarr.json").unlink()
        os.mkfifo(store / "zarr.json")
    elif how == "chunks deleted, markers kept":
        import shutil

        shutil.rmtree(store / "valid" / "c")
    elif how == "zarr.json deleted":
        (store / "zarr.json").unlink()


DAMAGES = [
    ("garbled zarr.json", "zarr.json is not valid JSON"),
    ("truncated zarr.json", "zarr.json is not valid JSON"),
    ("empty zarr.json", "zarr.json is empty"),
    ("missing array", "the array valid is missing"),
    ("garbled chunk", "chunk 0 cannot be read"),
    ("truncated chunk", "chunk 0 cannot be read"),
    ("changed shape", "the array lower has shape [25, 3]"),
    ("zarr.json is /dev/zero", "zarr.json is not a regular file"),
    ("zarr.json is a FIFO", "zarr.json is not a regular file"),
    ("chunks deleted, markers kept", "chunk 0 of the array valid is not what the run wrote"),
    ("zarr.json deleted", "zarr.json, the store's metadata, is missing"),
]


def _in_thread(target, seconds: float = 60.0):
    """Run ``target`` in a thread; fail (instead of hanging the suite) when it does not return."""
    result = {}
    thread = threading.Thread(target=lambda: result.update(value=target()), daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), "hangs"
    return result["value"]


@pytest.mark.parametrize("how, says", DAMAGES, ids=[d for d, _ in DAMAGES])
def test_a_damaged_store_is_refused_saying_what_and_how_to_recover(finished_store, tmp_path, how, says):
    import shutil

    # before: JSONDecodeError, KeyError, Zstd RuntimeError, MemoryError, a hang on the FIFO, and
    # exit 0 "valid: 0" over deleted chunks
    store = tmp_path / "s"
    shutil.copytree(finished_store, store, symlinks=True)
    _damage(store, how)
    code, _, err = _in_thread(lambda: run_cli(["sweep", *G, "--store", str(store), "--quiet"]))
    assert code == 2
    assert says in _error(err, "sweep") and "give --restart" in err
    code, out, err = _in_thread(lambda: run_cli(["sweep", *G, "--store", str(store), "--quiet", "--restart"]))
    assert code == 0, err
    assert "valid: 24" in out


@pytest.mark.parametrize("how, says", DAMAGES[:4] + DAMAGES[9:10], ids=[d for d, _ in DAMAGES[:4] + DAMAGES[9:10]])
def test_open_store_checks_the_store_as_a_resumed_run_does(finished_store, tmp_path, how, says):
    import shutil

    from bikerider.design import open_store
    from bikerider.errors import InputError

    store = tmp_path / "s"
    shutil.copytree(finished_store, store, symlinks=True)
    _damage(store, how)
    with pytest.raises(InputError, match=re.escape(says)):
        open_store(store)


def test_an_intact_store_resumes_and_its_markers_hold_checksums(finished_store, tmp_path):
    import shutil

    store = tmp_path / "s"
    shutil.copytree(finished_store, store, symlinks=True)
    marker = json.loads((store / "done" / "0").read_text())
    assert set(marker) >= {"valid", "reason", "lower", "weave_speed"}
    code, out, err = run_cli(["sweep", *G, "--store", str(store), "--quiet"])
    assert code == 0 and "valid: 24" in out, err


def test_a_store_with_older_empty_markers_still_resumes_computing_their_chunks_again(finished_store, tmp_path):
    import shutil

    store = tmp_path / "s"
    shutil.copytree(finished_store, store, symlinks=True)
    (store / "done" / "0").write_text("")  # the markers stores had before their checksums
    code, out, err = run_cli(["sweep", *G, "--store", str(store), "--quiet"])
    assert code == 0 and "valid: 24" in out, err
    # its chunk was computed again: the marker now holds checksums
    assert set(json.loads((store / "done" / "0").read_text())) >= {"valid", "lower"}


def test_a_changed_value_under_an_emptied_marker_does_not_reach_the_results(finished_store, tmp_path):
    """Found by tests/test_fuzz_trust.py: a marker emptied and a byte of its chunk changed gave a summary
    with other sensitivities (S(capsize) of c 0.906 against 0.911); the chunk is now computed again."""
    import shutil

    code, reference, err = run_cli(["sweep", *G, "--store", str(finished_store), "--quiet"])
    assert code == 0, err
    store = tmp_path / "s"
    shutil.copytree(finished_store, store, symlinks=True)
    (store / "done" / "0").write_text("")
    chunk = store / "upper" / "c" / "0" / "0"
    data = chunk.read_bytes()
    chunk.write_bytes(data[:17] + bytes([0]) + data[18:])
    code, out, err = run_cli(["sweep", *G, "--store", str(store), "--quiet"])
    assert code == 0, err
    assert out.replace(str(store), "S") == reference.replace(str(finished_store), "S")


# ------------------------------------------------------------------------------------------
# 4. One run holds a store at a time
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("restart", [False, True])
def test_a_second_run_on_a_held_store_is_refused_naming_the_holder(tmp_path, restart):
    from bikerider.design.store_check import StoreLock

    # before: three runs at once into one store ended in tracebacks (ContainsArrayError) 10 times in 10
    store = tmp_path / "cs"
    store.mkdir()
    lock = StoreLock(store).acquire()  # another run holds it
    try:
        code, _, err = run_cli(["sweep", *G, "--store", str(store), "--quiet"] + ["--restart"] * restart)
    finally:
        lock.release()
    assert code == 2
    assert f"the process {os.getpid()} holds it" in _error(err, "sweep")
    code, out, err = run_cli(["sweep", *G, "--store", str(store), "--quiet"])  # released: it runs
    assert code == 0, err


def test_three_runs_at_once_one_computes_the_others_are_refused(tmp_path):
    store = tmp_path / "cs"
    argv = [sys.executable, "-m", "bikerider.cli", "sweep", *G, "--store", str(store), "--restart", "--quiet"]
    runs = [subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(3)]
    results = [(p.wait(120), *p.communicate()) for p in runs]
    for code, _, err in results:
        assert code in (0, 2) and "Traceback" not in err, err
        if code == 2:
            assert "expected a store no other run is writing" in err
    assert any(code == 0 for code, _, _ in results)
    code, out, err = run_cli(["sweep", *G, "--store", str(store), "--quiet"])
    assert code == 0 and "valid: 24" in out, err


# ------------------------------------------------------------------------------------------
# 5. Hostile numbers: clear errors
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "line, says",
    [
        ("detector = { min_rate = 1e308 }", "experiment.detector.min_rate = 1e+308: expected at most 1e+06"),
        ("detector = { max_duration = 1e308 }", "experiment.detector.max_duration = 1e+308: expected at most 3600"),
        ('delimiter = ",,"', "experiment.delimiter = ',,': expected one character"),
        ("delimiter = '\"'", "experiment.delimiter = '\"': expected one character"),
        ('delimiter = "\\n"', "experiment.delimiter = '\\n': expected one character"),
        ('delimiter = "1"', "experiment.delimiter = '1': expected one character"),
    ],
)
def test_hostile_manifest_settings_are_refused(tmp_path, line, says):
    # before: OverflowError and LinAlgError (1e308), TypeError (',,'), "no column" for a quote
    manifest = _experiment(tmp_path)
    manifest.write_text(manifest.read_text().replace("sample_rate = 100.0", "sample_rate = 100.0\n" + line))
    code, _, err = run_cli(["gap", *KOOIJMAN, "--experiment", str(manifest)])
    assert code == 2
    assert says in _error(err, "gap"), err


def test_a_sample_rate_beyond_a_megahertz_is_refused(tmp_path):
    # before: LinAlgError (SVD did not converge) after the logs were read
    manifest = _experiment(tmp_path)
    manifest.write_text(manifest.read_text().replace("sample_rate = 100.0", "sample_rate = 1e308"))
    code, _, err = run_cli(["gap", *KOOIJMAN, "--experiment", str(manifest)])
    assert code == 2 and "sample_rate = 1e+308: expected a sampling rate from 0.001 to 1e+06 Hz" in _error(err, "gap")
    code, _, err = run_cli(
        ["gap", *KOOIJMAN, "--experiment", str(tmp_path / "windows.csv"), "--columns", "roll_rate=lean_rate"]
        + ["--sample-rate", "1e308"]
    )
    assert code == 2 and "--sample-rate = 1e+308: expected a sampling rate from 0.001 to 1e+06 Hz" in err


def test_a_log_header_cell_beyond_the_csv_field_limit_is_refused_naming_the_line(tmp_path):
    # before: _csv.Error: field larger than field limit (131072)
    manifest = _experiment(tmp_path)
    log = tmp_path / "logs" / "run.log"
    log.write_text(log.read_text().replace("lean_rate,speed", "lean_rate," + "x" * 140_000 + ",speed", 1))
    code, _, err = run_cli(["gap", *KOOIJMAN, "--experiment", str(manifest)])
    assert code == 2
    assert "run.log:1: not a comma-separated line (field larger than field limit" in _error(err, "gap")


@pytest.mark.parametrize(
    "options, says",
    [
        (
            ["--next-speeds", "1:1e308"],
            "--next-speeds = '1:1e308': expected LO:HI or LO:HI:N with 0 < LO < HI <= 1e+06",
        ),
        (
            ["--next-noise", "roll_rate=1e308"],
            "--next-noise = 'roll_rate=1e308': expected a positive standard deviation",
        ),
        (["--next-torque", "1e-300"], "--next-torque = 1e-300: expected a peak steer torque from 0.001 to 50 N m"),
    ],
)
def test_hostile_next_options_are_refused_before_the_diagnosis(monkeypatch, options, says):
    from bikerider import diagnose as pipeline

    # before: LinAlgError (speeds), OverflowError (noise), a NumPy RuntimeWarning (torque), each
    # after the whole diagnosis
    monkeypatch.setattr(pipeline, "run_diagnosis", lambda *a: pytest.fail("the diagnosis ran"))
    code, _, err = run_cli(["gap", *KOOIJMAN, "--data", str(EXAMPLES / "eigenvalues.csv"), "--next", *options])
    assert code == 2 and says in _error(err, "gap")


@pytest.mark.parametrize(
    "vary, says",
    [
        (
            "mB=-1e308:1e308",
            "mB = '-1e+308:1e+308': expected a range LOW:HIGH whose width HIGH - LOW is a finite number",
        ),
        ("mB=1e308+/-1e307", "expected a mean and sigma whose draws stay finite"),
    ],
)
def test_random_ranges_that_overflow_are_refused(vary, says):
    # before: OverflowError: high - low range exceeds valid bounds
    code, _, err = run_cli(["sweep", "--bicycle", "Benchmark", "--random", "50", "--vary", vary, "--quiet"])
    assert code == 2 and says in _error(err, "sweep")


@pytest.mark.parametrize("address", ["", "not an address", "foo://127.0.0.1:8786", "tcp://host", "tcp://h:99999"])
def test_a_bad_dask_address_is_refused_before_the_run(monkeypatch, address):
    from bikerider.design import run

    # before: ValueError tracebacks from dask.distributed
    monkeypatch.setattr(run, "run_on_dask", lambda *a: pytest.fail("Dask was asked"))
    code, _, err = run_cli(["sweep", *G, "--dask", address, "--quiet"])
    assert code == 2
    assert f"--dask = {address!r}: expected the address of a Dask scheduler, [PROTOCOL://]HOST:PORT" in _error(
        err, "sweep"
    )


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:8786", "127.0.0.1:8786", "tls://[::1]:8786", "inproc://x"])
def test_a_well_formed_dask_address_passes_the_check(address):
    from bikerider.commands.sweep_checks import check_dask

    check_dask(address)


# ------------------------------------------------------------------------------------------
# 6. Wrong refusals and acceptances
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "argv",
    [
        ["sweep", "--bicycle", "Browser", "--vary", "c=0:0.1:3", "--out", "Browser"],
        ["sweep", "--bicycle", "Browser", "--rider", "Jason", "--vary", "c=0:0.1:3", "--out", "Jason"],
        ["sweep", *G, "--store", "Benchmark", "--quiet"],
        ["sweep", *G, "--store", ".", "--quiet"],
    ],
    ids=["out Browser", "out Jason", "store Benchmark", "store ."],
)
def test_shipped_names_are_not_input_files(tmp_path, monkeypatch, argv):
    # before: `--out Browser`: "an output that is not one of the command's inputs"; `--store .` alike
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(argv)
    assert code == 0, err


@pytest.mark.parametrize(
    "argv",
    [
        ["--vary", "c_deg=0:10:3"],
        ["--vary", "mB_deg=0:10:3"],
        ["--random", "5", "--vary", "c_deg=0:10"],
        ["--random", "5", "--vary", "mB_deg=1+/-2"],
    ],
)
def test_degrees_on_a_length_or_mass_are_refused(argv):
    # before: silently converted to radians
    code, _, err = run_cli(["sweep", "--bicycle", "Benchmark", *argv, "--quiet"])
    assert code == 2 and "expected _deg only on an angle (lam_deg, lam_ht_deg" in _error(err, "sweep")


def test_degrees_on_an_angle_are_converted():
    """lam_deg is converted once for the model (the same results as lam in radians) and shown back
    in degrees (issue 24: degrees in, degrees out)."""
    code, out, err = run_cli(["sweep", "--bicycle", "Benchmark", "--vary", "lam_deg=0:30:2", "--json"])
    assert code == 0, err
    code, out_rad, err = run_cli(["sweep", "--bicycle", "Benchmark", "--vary", "lam=0:0.5235987755982988:2", "--json"])
    assert code == 0, err
    degrees, radians = json.loads(out), json.loads(out_rad)
    assert degrees.pop("parameters") == {"lam_deg": [0.0, 30.0]}
    assert radians.pop("parameters")["lam"] == pytest.approx([0.0, 0.5235987755982988])
    degrees.pop("notes", None), radians.pop("notes", None)
    for shown, given in zip(degrees.pop("designs"), radians.pop("designs"), strict=True):
        assert math.radians(shown.pop("lam_deg")) == pytest.approx(given.pop("lam"), rel=1e-12)
        assert shown == given  # the same model: lam converted once at the input
    assert degrees == radians


def test_monte_carlo_zero_is_blamed_on_monte_carlo():
    code, _, err = run_cli(["sweep", "--bicycle", "Benchmark", "--monte-carlo", "0", "--quiet"])
    assert code == 2 and "--monte-carlo = 0: expected a whole number of designs" in _error(err, "sweep")


def test_a_zero_target_weave_speed_is_refused_before_the_run(monkeypatch):
    from bikerider import design

    monkeypatch.setattr(design, "explore", lambda *a, **k: pytest.fail("the run started"))
    code, _, err = run_cli(["sweep", *G, "--target-weave-speed", "0", "--quiet"])
    assert code == 2 and "--target-weave-speed = 0: expected a positive speed" in _error(err, "sweep")


def test_an_empty_experiment_path_is_the_empty_path_error():
    code, _, err = run_cli(["gap", *KOOIJMAN, "--experiment", ""])
    assert code == 2
    assert "path = '': expected the path of a file (an empty path names no file" in _error(err, "gap")


def test_an_existing_empty_folder_is_a_new_store(tmp_path):
    (tmp_path / "ef").mkdir()
    code, out, err = run_cli(["sweep", *G, "--store", str(tmp_path / "ef"), "--quiet"])
    assert code == 0 and "valid: 24" in out, err


def test_a_folder_of_other_files_is_never_a_store_even_with_restart(tmp_path):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    for extra in ([], ["--restart"]):
        code, _, err = run_cli(["sweep", *G, "--store", str(folder), "--quiet", *extra])
        assert code == 2 and "is not a bikerider design store" in _error(err, "sweep")
    assert sorted(p.name for p in folder.iterdir()) == ["notes.txt"]


@pytest.mark.parametrize("option", ["--out", "--plot"])
def test_an_output_inside_the_store_is_refused(finished_store, tmp_path, option):
    import shutil

    # before: `--store s --out s/zarr.json` wrote the summary over the store's metadata, exit 0
    store = tmp_path / "s"
    shutil.copytree(finished_store, store)
    before = (store / "zarr.json").read_bytes()
    target = store / "zarr.json" if option == "--out" else store / "figures"
    code, _, err = run_cli(["sweep", *G, "--store", str(store), option, str(target), "--quiet"])
    assert code == 2 and "a path outside the --store folder" in _error(err, "sweep")
    assert (store / "zarr.json").read_bytes() == before


@pytest.mark.parametrize(
    "argv, says",
    [
        (["sweep", *G, "--restart"], "--restart = 'given': expected --store DIR as well"),
        (["sweep", *G, "--slice", "c,w"], "--slice = 'c,w': expected --plot DIR as well"),
        (
            ["gap", *KOOIJMAN, "--data", str(EXAMPLES / "eigenvalues.csv"), "--next-repeats", "3"],
            "--next-repeats = 3: expected --next as well",
        ),
    ],
)
def test_an_option_without_the_one_it_works_with_is_refused(monkeypatch, argv, says):
    from bikerider import diagnose as pipeline

    monkeypatch.setattr(pipeline, "run_diagnosis", lambda *a: pytest.fail("the diagnosis ran"))
    code, _, err = run_cli(argv)
    assert code == 2 and says in _error(err, argv[0])


# ------------------------------------------------------------------------------------------
# 7. Older readers
# ------------------------------------------------------------------------------------------
def test_an_error_several_checks_meet_is_listed_once(tmp_path):
    text = (PAPER / "browser_bicycle.toml").read_text()
    bicycle = tmp_path / "bicycle.toml"
    bicycle.write_text(re.sub(r"(?m)^k_t = .*$", "k_t = 0", text))
    code, _, err = run_cli(["estimate", "--bicycle", str(bicycle)])
    assert code == 2
    assert _error(err, "estimate").count("k_t = 0: expected a positive torsional stiffness") == 1, err


def test_a_centre_of_mass_given_twice_is_refused(tmp_path):
    text = (PAPER / "browser_bicycle.toml").read_text()
    old = 'com = { x = "0.25 +/- 0.02", z = "-0.62 +/- 0.02" }'
    assert old in text
    lines = "[{ point = [0.0, -1.0], angle_deg = 60 }, { point = [0.5, -1.0], angle_deg = 120 }]"
    bicycle = tmp_path / "bicycle.toml"
    bicycle.write_text(text.replace(old, old[:-2] + f", lines = {lines} }}"))
    code, _, err = run_cli(["estimate", "--bicycle", str(bicycle)])
    assert code == 2
    assert "com = 'x, z and lines': expected either x and z or the hanging lines" in _error(err, "estimate")


def test_gap_refuses_an_unknown_table_of_a_model_file(tmp_path):
    model = tmp_path / "model.toml"
    model.write_text((DATA / "gap" / "kooijman2008_bicycle.toml").read_text() + "\n[foo]\nx = 1\n")
    code, _, err = run_cli(["gap", "--model", str(model), "--data", str(EXAMPLES / "eigenvalues.csv")])
    assert code == 2 and "foo = {'x': 1}: expected one of the tables [benchmark]" in _error(err, "gap")


def test_sensitivity_inputs_note_lam_deg_in_radians_and_inputs_that_change_nothing(tmp_path):
    text = (Path(__file__).parent / "data" / "BenchmarkBenchmark.txt").read_text()
    inputs = tmp_path / "inputs.txt"
    inputs.write_text(re.sub(r"(?m)^lam *=.*$", "lam_deg = 0.3", text) + "h_bb = 0.3\n")
    code, _, err = run_cli(["sensitivity", "weave_speed", "--inputs", str(inputs)])
    assert code == 0, err
    assert "lam_deg = 0.3 looks like radians" in err
    assert "h_bb: no output depends on them" in err


def test_a_numeric_comment_is_checked_beside_a_column(tmp_path):
    from bikerider.errors import FileFormatError
    from bikerider.io.gap_data import read_perturbation

    lines = (EXAMPLES / "perturbation_run.csv").read_text().splitlines()
    out, header = [], True
    for line in lines:
        if line.startswith("#"):
            out.append(line.replace("# speed = 7.0", "# speed = abc"))
        elif header:
            out.append(line + ",speed")
            header = False
        else:
            out.append(line + ",7.0")
    path = tmp_path / "run.csv"
    path.write_text("\n".join(out) + "\n")
    with pytest.raises(FileFormatError, match=r"speed = 'abc': expected a number"):
        read_perturbation(path)


def test_a_canonical_row_named_like_a_matrix_entry_is_a_typo(tmp_path):
    from bikerider.errors import FileFormatError
    from bikerider.io.gap_data import read_canonical

    path = tmp_path / "canonical.csv"
    path.write_text((EXAMPLES / "canonical.csv").read_text().replace("Mphidelta", "Mfoo", 1))
    with pytest.raises(FileFormatError, match=r"coefficient = 'Mfoo': expected one of the canonical-matrix"):
        read_canonical(path)
    read_canonical(EXAMPLES / "canonical.csv")  # other matrices' rows (HdeltaF) are still left out


# ------------------------------------------------------------------------------------------
# 8. One manifest limit; --dask quiet; no leaked RuntimeWarning
# ------------------------------------------------------------------------------------------
def test_the_manifest_size_limit_is_the_one_the_docs_state(tmp_path):
    from bikerider.io.input_file import TEXT_LIMIT

    doc = " ".join((Path(__file__).parents[1] / "docs" / "gap.md").read_text().split())
    assert "TOML manifests 1 MiB" in doc and "manifests and windows files 200 MB" not in doc
    assert TEXT_LIMIT == 1 << 20
    manifest = _experiment(tmp_path)
    manifest.write_text(manifest.read_text() + "# " + "x" * TEXT_LIMIT + "\n")
    code, _, err = run_cli(["gap", *KOOIJMAN, "--experiment", str(manifest)])
    assert code == 2 and "expected an input file of at most 1.0 MiB" in _error(err, "gap")


@pytest.mark.slow
def test_dask_is_quiet_at_default_verbosity(tmp_path):
    pytest.importorskip("dask.distributed")
    argv = [sys.executable, "-m", "bikerider.cli", "sweep", *G, "--dask", "--workers", "1", "--quiet"]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "INFO" not in done.stderr and done.stderr.strip() == "", done.stderr


def test_a_benchmark_file_with_a_huge_integer_is_an_error_not_a_traceback(tmp_path):
    """A name = value file whose value has more digits than Python converts to int (found by the
    benchmark fuzz test): the format detection's TOML attempt raised ValueError past the reader."""
    path = tmp_path / "BigBenchmark.txt"
    path.write_text("w = " + "7" * 5000 + "+/-0.0\nc = 0.08+/-0.0\n")
    code, _, err = run_cli(["benchmark", str(path)])
    assert code == 2 and "Traceback" not in err
    assert err.startswith(f"bikerider benchmark: error: {path}:1: w")
