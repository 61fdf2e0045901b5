"""Hostile input at the entrances of issue 23: manifest settings, the log reader, design stores and
``sweep``'s arguments.

Contract: a value is read into finite numbers or refused with a :class:`~bikerider.errors.BikeriderError`
naming the file or option; a store that is resumed after any change to its files either gives the
same results as before or is refused naming the store (and ``--restart``); never a traceback, never
a hang.  Hypothesis runs derandomised in CI (tests/conftest.py); the fixed cases are in
tests/test_trust_entrances.py.
"""

from __future__ import annotations

import json
import os
import re
import shutil
from pathlib import Path
from unittest import mock

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from strategies import assert_all_finite, assert_names_file, check_json_output, run_cli

from bikerider.errors import BikeriderError, InputError

pytest.importorskip("zarr")

FUZZ = settings(
    max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
G = ["--bicycle", "Benchmark", "--vary", "c=0:0.15:4", "--vary", "lam_deg=0:30:3", "--vary", "w=0.9:1.2:2"]

HOSTILE_NUMBERS = st.one_of(
    st.sampled_from(["nan", "inf", "-inf", "1e308", "-1e308", "5e-324", "0", "-1", "1" + "0" * 400, "0.0"]),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.floats(1e-3, 1e3).map(repr),  # unusual but possible: the settings must take them or name them
    st.integers(-(10**30), 10**30).map(str),
)
"""TOML number texts a hostile manifest may hold."""


def _toml_text(text: str) -> str:
    """``text`` as a TOML basic string."""
    return json.dumps(text)


def _log(delimiter: str = ",") -> str:
    t = np.arange(600) / 100.0
    decay = np.exp(-1.2 * (t % 3.0)) * np.sin(5.0 * (t % 3.0))
    rows = [delimiter.join((f"{0.4 * d:.5f}", f"{0.05 * d:.5f}", "4.2")) for d in decay]
    return delimiter.join(("lean_rate", "fork_angle", "speed")) + "\n" + "\n".join(rows) + "\n"


def _clean_error(code: int, err: str, command: str) -> None:
    assert code in (0, 2), err
    assert "Traceback" not in err, err
    if code == 2 and err.startswith("usage: "):  # argparse: the usage, then one line naming the argument
        assert err.strip().splitlines()[-1].startswith(f"bikerider {command}: error: "), err
    elif code == 2:
        assert err.startswith(f"bikerider {command}: error: "), err
        lines = err.strip().splitlines()
        if not re.search(r"\d+ input errors:$", lines[0]):
            assert len(lines) <= 3, err


# ------------------------------------------------------------------------------------------
# Manifest settings: sampling rate, detector, delimiter, scale, calibration
# ------------------------------------------------------------------------------------------
SETTINGS = ("sample_rate", "detector", "delimiter", "scale", "gain", "offset")
"""The settings a fuzzed manifest may make hostile (one or two at a time, the others usable)."""


def _setting(draw, key: str, hostile: bool) -> str:
    if key == "delimiter":
        return _toml_text(draw(st.text(max_size=3)) if hostile else ",")
    if key == "detector":
        keys = ["threshold", "min_rate", "gap", "max_duration", "min_duration", "margin"]
        chosen = draw(st.lists(st.sampled_from(keys), min_size=1, unique=True)) if hostile else []
        return "{ " + ", ".join(f"{k} = {draw(HOSTILE_NUMBERS)}" for k in chosen) + " }"
    usable = {"sample_rate": "100.0", "scale": "1.0", "gain": "1.05", "offset": "-0.1"}[key]
    return draw(HOSTILE_NUMBERS) if hostile else usable


MANIFEST = """\
[experiment]
sample_rate = {sample_rate}
detector = {detector}
delimiter = {delimiter}
logs = "."
fit = ["roll_rate"]

[columns]
roll_rate = "lean_rate"
steer_angle = "fork_angle"
speed = "speed"

[columns.scale]
roll_rate = {scale}

[speed]
source = "column"
calibration = {{ gain = {gain}, offset = {offset} }}

[[file]]
path = "run.log"
{windows}
"""


@FUZZ
@given(st.data(), st.sets(st.sampled_from(SETTINGS), max_size=2), st.booleans())
def test_manifest_settings(tmp_path_factory, data, hostile, detect):
    from bikerider.diagnose import load_records
    from bikerider.gap.measured.records import fit_record
    from bikerider.io.experiment import read_experiment

    values = {key: _setting(data.draw, key, key in hostile) for key in SETTINGS}
    folder = tmp_path_factory.mktemp("manifest")
    manifest = folder / "experiment.toml"
    manifest.write_text(
        MANIFEST.format(**values, windows="detect = true" if detect else "windows = [[10, 290], [310, 590]]")
    )
    (folder / "run.log").write_text(_log())
    what = f"{values}; detect {detect}"
    try:
        records = load_records(*read_experiment(manifest))
    except BikeriderError as exc:
        event("refused")
        assert_names_file(exc, manifest, folder / "run.log")
        return
    event(f"{sum(r.problem is None for r in records)} records cut")
    for r in records:
        if r.problem is None:
            assert_all_finite([r.time, r.speed, r.speed_sigma], what)
            fit = fit_record(r)
            if fit.used:
                assert_all_finite([fit.estimate.eigenvalue], what)


# ------------------------------------------------------------------------------------------
# The log reader: delimiters and headers
# ------------------------------------------------------------------------------------------
HEADER_CELLS = st.one_of(
    st.sampled_from(["lean_rate", "fork_angle", "speed", '"lean_rate"', '"', "", "#", "x" * 140_000]),
    st.text(max_size=12),
)


@FUZZ
@given(st.text(min_size=0, max_size=3), st.lists(HEADER_CELLS, min_size=1, max_size=5), st.booleans())
def test_log_reader_with_hostile_delimiters_and_headers(tmp_path_factory, delimiter, header, keep_data):
    from bikerider.io.experiment import check_delimiter, read_log

    path = tmp_path_factory.mktemp("log") / "run.log"
    body = _log(delimiter if len(delimiter) == 1 and delimiter not in "\r\n" else ",").split("\n", 1)[1]
    path.write_text(
        (delimiter or ",").join(header) + "\n" + (body if keep_data else ""), encoding="utf-8", errors="surrogatepass"
    )
    what = f"delimiter {delimiter!r}, header {[h[:20] for h in header]}"
    try:
        check_delimiter(delimiter)
        log = read_log(path, ["lean_rate"], delimiter)
    except BikeriderError as exc:
        message = str(exc)
        assert "Traceback" not in message
        assert "delimiter" in message or path.name in message, (what, message)
        return
    except UnicodeEncodeError:  # a lone surrogate the file cannot hold: no such log exists
        return
    values = log.columns["lean_rate"]
    assert values[np.isfinite(values)].size + np.isnan(values).sum() == values.size, what


# ------------------------------------------------------------------------------------------
# Design stores: any change to their files is found, or changes nothing
# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def finished_store(tmp_path_factory) -> tuple[Path, str]:
    folder = tmp_path_factory.mktemp("store") / "s"
    code, out, err = run_cli(["sweep", *G, "--store", str(folder), "--quiet"])
    assert code == 0, err
    return folder, out


@st.composite
def store_damage(draw, files: list[str]) -> tuple[str, object]:
    name = draw(st.sampled_from(files))
    kind = draw(st.sampled_from(["truncate", "byte", "delete", "empty", "junk", "json"]))
    if kind == "truncate":
        return name, ("truncate", draw(st.integers(0, 400)))
    if kind == "byte":
        return name, ("byte", draw(st.integers(0, 10_000)), draw(st.integers(0, 255)))
    if kind == "junk":
        return name, ("junk", draw(st.binary(max_size=64)))
    if kind == "json":
        return name, ("json", draw(st.sampled_from(['{"a": 1}', "[]", "null", '{"shape": [1e308]}', "1e999"])))
    return name, (kind,)


def _apply(path: Path, damage) -> None:
    kind = damage[0]
    data = path.read_bytes()
    if kind == "truncate":
        path.write_bytes(data[: damage[1]])
    elif kind == "byte":
        k = damage[1] % max(len(data), 1)
        path.write_bytes(data[:k] + bytes([damage[2]]) + data[k + 1 :])
    elif kind == "delete":
        path.unlink()
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "junk":
        path.write_bytes(damage[1])
    elif kind == "json":
        path.write_text(damage[1])


def _summary(text: str) -> str:
    return re.sub(r"store \S+", "store S", text)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(st.data())
def test_a_changed_store_gives_the_same_results_or_is_refused(finished_store, tmp_path_factory, data):
    original, summary = finished_store
    files = sorted(str(p.relative_to(original)) for p in original.rglob("*") if p.is_file())
    damages = data.draw(st.lists(store_damage(files), min_size=1, max_size=3))
    store = tmp_path_factory.mktemp("damaged") / "s"
    shutil.copytree(original, store)
    for name, damage in damages:
        if (store / name).exists():
            _apply(store / name, damage)
    code, out, err = run_cli(["sweep", *G, "--store", str(store), "--quiet"])
    _clean_error(code, err, "sweep")
    if code == 0:  # harmless (a marker deleted: its chunk computed again; whitespace in JSON) or repaired
        assert _summary(out) == _summary(summary), (damages, out)
    else:
        assert "--store" in err and str(store) in err, (damages, err)
        code, out, err = run_cli(["sweep", *G, "--store", str(store), "--quiet", "--restart"])
        assert code == 0 and _summary(out) == _summary(summary), (damages, err)


# ------------------------------------------------------------------------------------------
# sweep's arguments
# ------------------------------------------------------------------------------------------
NUMBERS = st.sampled_from(["0", "-1", "1", "2", "0.5", "nan", "inf", "1e308", "-1e308", "5e-324", "1e-300", "", "x"])
NAMES = st.sampled_from(["c", "w", "mB", "lam", "lam_deg", "c_deg", "mB_deg", "lam_ht_deg", "IByy", "foo", "", " c"])
COUNTS = st.sampled_from(["0", "-1", "1", "3", "nan", "1e3", "10000000000000", "x"])
"""Design counts: small, or refused (never a run of 1e12 designs)."""


@st.composite
def sweep_arguments(draw) -> list[str]:
    argv: list[str] = ["sweep"]
    argv += draw(st.sampled_from([["--bicycle", "Benchmark"], ["--bicycle", "Browser", "--rider", "Jason"], []]))
    random = draw(st.sampled_from([None, "--random", "--monte-carlo"]))
    for _ in range(draw(st.integers(0, 3))):
        name = draw(NAMES)
        if random == "--random":
            spec = draw(st.sampled_from(["{a}:{b}", "{a}+/-{b}", "{a}"]))
        else:
            spec = draw(st.sampled_from(["{a}:{b}:{n}", "{a}:{b}", "{a}:{b}:{n}:{n}"]))
        argv += ["--vary", f"{name}=" + spec.format(a=draw(NUMBERS), b=draw(NUMBERS), n=draw(COUNTS))]
    if random is not None:
        argv += [random, draw(COUNTS)]
    for option, values in (
        ("--store", st.sampled_from(["s", "", ".", "s/zarr.json", "out.csv"])),
        ("--dask", st.one_of(st.text(max_size=20), st.sampled_from(["tcp://127.0.0.1:1", "foo://a:1", "local"]))),
        ("--target-weave-speed", NUMBERS),
        ("--chunk-size", COUNTS),
        ("--speeds", st.sampled_from(["0:10:3", "1:0:3", "0:1e308:3", "nan:1:2", "x"])),
        ("--weave-speeds", st.sampled_from(["4:6:2", "6:4:2", "0:inf:2"])),
        ("--slice", st.sampled_from(["c,w", "c", "foo,bar", ""])),
        ("--out", st.sampled_from(["out.csv", "s/zarr.json", "", "Benchmark"])),
        ("--seed", NUMBERS),
    ):
        if draw(st.integers(0, 3)) == 0:
            argv += [option, draw(values)]
    for flag in ("--restart", "--json"):
        if draw(st.integers(0, 3)) == 0:
            argv.append(flag)
    return argv + ["--quiet"]


def _unreachable(store, pending, engine, scheduler, workers, progress):
    """What ``run_on_dask`` does when no scheduler answers (none is started here: it takes seconds)."""
    raise InputError("--dask", str(scheduler), "the address of a running Dask scheduler (no answer)")


@FUZZ
@given(sweep_arguments())
def test_sweep_arguments(tmp_path_factory, argv):
    folder = tmp_path_factory.mktemp("sweep")
    before = os.getcwd()
    os.chdir(folder)
    try:
        with mock.patch("bikerider.design.run.run_on_dask", _unreachable):
            code, out, err = run_cli(argv)
    finally:
        os.chdir(before)
    _clean_error(code, err, "sweep")
    if code == 0 and "--json" in argv and "--out" not in argv:
        check_json_output(out, " ".join(argv))
