"""Steer-torque multisine records: read, repaired, estimated and used by the diagnosis.

The runs are simulated by the independent truth of ``validation/multisine.py`` (Meijaard et al.'s
matrices typed in by hand, integrated in time), with noise; the hidden effect is a steer damper of
0.6 N m s/rad on the steer-by-wire bicycle under its steer-into-lean controller.
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import assert_all_finite, assert_names_file, mutated

from bikerider.diagnose import diagnose_files, write_report
from bikerider.errors import BikeriderError, FileFormatError, InputError
from bikerider.gap import diagnose
from bikerider.gap.candidates.effect_model import BENCH_ARGS, EffectModel
from bikerider.gap.inference.frequency_response import predict_frf, predict_frf_describing, predict_frf_friction
from bikerider.gap.inference.timedomain import SMOOTHING, Layout
from bikerider.gap.measured.control import ControlLaw
from bikerider.gap.measured.multisine import FrequencyResponseData, MultisineRecord, fit_multisine
from bikerider.gap.plan.sweeps import lines_for
from bikerider.io.experiment import read_manifest
from bikerider.io.gap_model import load_model
from bikerider.io.multisine import read_multisines
from validation.multisine import damage, decay_log, multisine_log, write_log

DATA = Path(str(resources.files("bikerider") / "data" / "gap"))
SBW = DATA / "pasma2024_sbw"
EXAMPLE = DATA / "multisine_example"
C_STEER = 0.6
MODEL = load_model(SBW / "sbw_bicycle.toml")
VALUES = {k: float(MODEL.parameters.values[k]) for k in BENCH_ARGS + ("g",)}
LAW = read_manifest(SBW / "experiment.toml")[0].laws["sil"]

HEADER = """[experiment]
time_column = "time"
control = "sil"
{extra}
[columns]
roll_rate = "roll_rate"
steer_angle = "steer_angle"
steer_rate = "steer_rate"
speed = "speed"

[control.sil]
k_phid = {{ K = 2.0, v0 = 6.5, when = "below" }}
k_phi = {{ K = 0.7, v0 = 6.5, when = "above" }}
"""


def _lines(speed: float, run_time: float = 10.0) -> tuple[float, ...]:
    ev = EffectModel(VALUES, MODEL.geometry).eigenvalues([speed], LAW(speed))[0]
    return lines_for(float(np.max(ev.imag)) / (2 * math.pi), run_time)


def _record(columns, speed, name="run") -> MultisineRecord:
    signals = {k: columns[k] for k in ("roll_rate", "steer_angle", "steer_rate")}
    return MultisineRecord(name, name, columns["time"], columns["steer_torque"], signals, speed, 0.0, "g", LAW, speed)


def _write_runs(folder: Path, runs: list[tuple[str, dict, str]], decays=(), table: str = "") -> Path:
    """A manifest with multisine runs ``(file, columns, group)`` and decays ``(file, columns, group)``."""
    text = HEADER.format(extra="")
    for file, columns, group in decays:
        write_log(folder / file, columns)
        text += f'\n[[file]]\npath = "{file}"\nwindows = [[0, {len(columns["time"])}]]\ngroup = "{group}"\n'
    text += '\n[multisine]\ntorque = "steer_torque"\noutputs = ["roll_rate", "steer_angle"]\n' + table
    for file, columns, group in runs:
        write_log(folder / file, columns)
        text += f'\n[[multisine.run]]\npath = "{file}"\ngroup = "{group}"\n'
    path = folder / "experiment.toml"
    path.write_text(text)
    return path


# -- the estimate ------------------------------------------------------------------------------------
def test_the_frequency_response_agrees_with_the_model_within_its_standard_errors():
    """A run of the truth without the damper: the estimate at every line is the model's H(w) within the
    standard errors it states (they come from the noise, not from the model)."""
    rng = np.random.default_rng(1)
    z = []
    for speed in (2.5, 4.0):
        lines = _lines(speed)
        columns = multisine_log(VALUES, speed, LAW(speed), lines, 0.5, 10.0, rng=rng)
        fit = fit_multisine(_record(columns, speed))
        assert fit.used, fit.reason
        np.testing.assert_allclose(fit.lines, lines, rtol=1e-9)  # found in the torque
        frf = FrequencyResponseData.of([fit])
        predicted = predict_frf(EffectModel(VALUES, MODEL.geometry), frf)
        measured = np.column_stack([frf.value.real, frf.value.imag]).ravel()
        z.append((measured - predicted) / np.repeat(frf.sigma, 2))
    z = np.concatenate(z)
    assert 0.5 < math.sqrt(np.mean(z**2)) < 1.6, z
    assert np.max(np.abs(z)) < 4.5


def test_jitter_dropped_samples_and_missing_cells_are_repaired_and_said():
    rng = np.random.default_rng(2)
    speed = 4.0
    clean = multisine_log(VALUES, speed, LAW(speed), _lines(speed), 0.5, 10.0, rng=rng)
    fit = fit_multisine(_record(clean, speed))
    damaged = fit_multisine(_record(damage(clean, rng), speed))
    assert damaged.used, damaged.reason
    said = " | ".join(damaged.record.repairs)
    assert "missing roll_rate samples dropped" in said
    assert "gap" in said or "not uniform" in said
    assert "nothing" in said  # nothing interpolated or resampled: fitted at the recorded instants
    for name in fit.response:
        d = np.abs(damaged.response[name] - fit.response[name]) / np.hypot(fit.sigma[name], damaged.sigma[name])
        assert np.max(d) < 3.0, (name, d)


def test_a_run_with_wrong_lines_or_too_short_is_left_out_with_its_reason():
    rng = np.random.default_rng(3)
    columns = multisine_log(VALUES, 4.0, LAW(4.0), _lines(4.0), 0.5, 10.0, rng=rng)
    record = _record(columns, 4.0)
    record.lines = (0.05, 0.3)
    fit = fit_multisine(record)
    assert not fit.used and "shorter than one period" in fit.reason
    record.lines = (0.3, 0.35)
    fit = fit_multisine(record)
    assert not fit.used and "explain" in fit.reason and "check the lines" in fit.reason


# -- the diagnosis -----------------------------------------------------------------------------------
def test_the_shipped_multisine_example_finds_the_hidden_damper():
    d = diagnose_files(str(SBW / "sbw_bicycle.toml"), experiment=(str(EXAMPLE / "experiment.toml"),)).as_dict()
    assert d["verdict"] == "structural"
    assert d["selected"] == ["steer_damping"]
    c = next(r for r in d["ranking"] if r["effect"] == "steer_damping")["parameters"]["c_steer"]
    assert c["ci95"][0] <= C_STEER <= c["ci95"][1], c
    assert d["records"]["used"] == 6 and all(e["kind"] == "multisine" for e in d["records"]["list"])
    assert {c["mode"] for c in d["gap"]["map"]} == {"frf_roll_rate", "frf_steer_angle"}


def test_the_report_draws_the_multisine_records(tmp_path):
    diagnosis = diagnose_files(str(SBW / "sbw_bicycle.toml"), experiment=(str(EXAMPLE / "experiment.toml"),))
    report = write_report(diagnosis, tmp_path / "report").read_text()
    assert (tmp_path / "report" / "multisines.png").stat().st_size > 10_000
    assert "](multisines.png)" in report
    assert "multisine: response of roll rate, steer angle at 9 lines" in report


def test_damaged_copies_give_the_same_verdict(tmp_path):
    """The shipped example's runs damaged as a logger might (stamps jittered by 5 % of a step, 5 % of the
    rows dropped, three missing roll-rate cells): the same verdict and selection, the truth in the interval."""
    rng = np.random.default_rng(4)
    runs = []
    for log in sorted(EXAMPLE.glob("ms_*.csv.gz")):
        table = np.genfromtxt(log, delimiter=",", names=True)
        clean = {name: np.asarray(table[name], float) for name in table.dtype.names}
        session = log.name.split("_")[1]
        runs.append((log.name.removesuffix(".gz"), damage(clean, rng), f"session {session}"))
    manifest = _write_runs(tmp_path, runs)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    d = diagnose_files(
        str(SBW / "sbw_bicycle.toml"), experiment=(str(manifest),), effects="steer_damping,steer_inertia,parameters"
    ).as_dict()
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before  # no input changed
    assert d["verdict"] == "structural" and d["selected"] == ["steer_damping"]
    c = d["ranking"][0]["parameters"]["c_steer"]
    assert c["ci95"][0] <= C_STEER <= c["ci95"][1], c
    assert d["records"]["used"] == 6
    assert len(d["records"]["repaired"]) == 6
    assert all(any("missing roll_rate" in a for a in e["repairs"]) for e in d["records"]["repaired"])


def test_decays_and_multisines_together(tmp_path):
    rng = np.random.default_rng(5)
    decays, runs = [], []
    for session in "abc":
        for speed in (3.0, 5.0):
            columns = decay_log(VALUES, speed, LAW(speed), 3.0, c_steer=C_STEER, rng=rng)
            decays.append((f"decay_{session}_{speed}.csv", columns, f"session {session}"))
    for session in "ab":
        speed = 4.0
        columns = multisine_log(VALUES, speed, LAW(speed), _lines(speed), 0.5, 10.0, c_steer=C_STEER, rng=rng)
        runs.append((f"ms_{session}.csv", columns, f"session {session}"))
    manifest = _write_runs(tmp_path, runs, decays)
    d = diagnose_files(
        str(SBW / "sbw_bicycle.toml"), experiment=(str(manifest),), effects="steer_damping,steer_inertia"
    ).as_dict()
    kinds = [e.get("kind", "decay") for e in d["records"]["list"]]
    assert kinds.count("multisine") == 2 and kinds.count("decay") == 6
    assert d["records"]["used"] == 8
    assert d["selected"] == ["steer_damping"]
    c = d["ranking"][0]["parameters"]["c_steer"]
    assert c["ci95"][0] <= C_STEER <= c["ci95"][1], c
    modes = {c["mode"] for c in d["gap"]["map"]}
    assert {"weave", "frf_roll_rate", "frf_steer_angle"} <= modes


# -- bad input ---------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("table", "run", "error", "words"),
    [
        ("", "", InputError, ["multisine.torque", "missing"]),
        ('torque = "steer_torque"\nsettle = -1\n', 'path = "r.csv"\n', InputError, ["multisine.settle", "-1"]),
        ('torque = "steer_torque"\n', 'path = "r.csv"\nlines = [0.5, -2]\n', InputError, ["lines", "positive"]),
        ('torque = "steer_torque"\n', 'path = "r.csv"\ncontrol = "pid"\n', InputError, ["pid", "sil"]),
        ('torque = "steer_torque"\n', 'path = "r.csv"\ncolour = 1\n', InputError, ["multisine.run.colour"]),
        ('torque = "motor"\n', 'path = "r.csv"\n', FileFormatError, ["r.csv", "'motor'", "steer_torque"]),
        ('torque = "steer_torque"\noutputs = ["yaw"]\n', 'path = "r.csv"\n', InputError, ["yaw"]),
        ('torque = "steer_torque"\n', 'path = "r.csv"\nwindow = [10, 99999]\n', InputError, ["window", "99999"]),
    ],
)
def test_bad_multisine_input_gets_a_clear_error(tmp_path, table, run, error, words):
    columns = multisine_log(VALUES, 4.0, LAW(4.0), _lines(4.0), 0.5, 10.0)
    write_log(tmp_path / "r.csv", columns)
    path = tmp_path / "experiment.toml"
    path.write_text(HEADER.format(extra="") + "\n[multisine]\n" + table + "\n[[multisine.run]]\n" + run)
    settings, _ = read_manifest(path)
    with pytest.raises(error) as info:
        read_multisines(path, settings)
    message = str(info.value)
    assert str(path) in message or "r.csv" in message
    for word in words:
        assert word in message, message


def test_a_huge_torque_names_the_log_line_and_value(tmp_path):
    columns = multisine_log(VALUES, 4.0, LAW(4.0), _lines(4.0), 0.5, 10.0)
    columns["steer_torque"][7] = 5e3
    write_log(tmp_path / "r.csv", columns)
    path = tmp_path / "experiment.toml"
    path.write_text(
        HEADER.format(extra="") + '\n[multisine]\ntorque = "steer_torque"\n[[multisine.run]]\npath = "r.csv"\n'
    )
    with pytest.raises(FileFormatError, match=r"r\.csv:9.*5000.*N m"):
        read_multisines(path, read_manifest(path)[0])


def test_a_diagnosis_whose_multisines_are_all_left_out_stops_naming_them():
    """A run without torque (a motor that never moved): no line, left out; with nothing left the
    diagnosis stops with an error that names the record and its reason."""
    time = np.arange(1000) * 0.01
    rec = MultisineRecord(
        "flat.csv", "here", time, np.zeros(1000), {"roll_rate": np.sin(time)}, 4.0, 0.0, "g", LAW, 4.0
    )
    fit = fit_multisine(rec)
    assert not fit.used and "no line" in fit.reason
    with pytest.raises(InputError, match=r"1 of 1 records left out.*flat\.csv: no line"):
        diagnose(MODEL, multisines=[fit])


def test_steer_friction_predicts_a_friction_driven_run_by_simulating_it():
    """Runs of the truth with 0.19 N m Coulomb friction under the SBW controller's gains times 1.5 (what
    the plan recommends on the SBW data): the friction candidate at the truth's values, simulated with the
    run's own torque, predicts the lines to the noise when the truth's friction law is the candidate's,
    and within a few standard errors when the truth's corner is sharper; no linear damper comes as close.
    (The plan's describing function missed such runs by about 6.6 standard errors.)"""
    speed = 4.4
    law = ControlLaw.constant(1.5 * LAW(speed), "sil x1.5 at 4.4 m/s")
    layout = Layout.of(("steer_friction",))
    dampers = [
        EffectModel(VALUES, MODEL.geometry, {"steer_damping": {"c_steer": c}}) for c in np.geomspace(0.05, 10, 25)
    ]
    z = {}
    for corner in (SMOOTHING, 0.02):  # the candidate's own friction law, and a sharper one
        columns = multisine_log(
            VALUES, speed, law(speed), _lines(speed), 0.5, 10.0, c_steer=0.05, coulomb=0.19,
            rng=np.random.default_rng(6), corner=corner,
        )  # fmt: skip
        rec = _record(columns, speed)
        rec.law = law
        fit = fit_multisine(rec)
        frf = FrequencyResponseData.of([fit])
        measured = np.column_stack([frf.value.real, frf.value.imag]).ravel()
        sigma = np.repeat(frf.sigma, 2)

        def rms_z(predicted):
            return math.sqrt(np.mean(((measured - predicted) / sigma) ** 2))

        truth = np.array([0.19, 0.05])
        friction = predict_frf_friction(frf, [fit], VALUES, MODEL.geometry, layout, truth)
        describing = predict_frf_describing(frf, [fit], VALUES, MODEL.geometry, layout, truth)
        z[corner] = (rms_z(friction), min(rms_z(predict_frf(m, frf)) for m in dampers), rms_z(describing))
    # the candidate's own law: predicted to the noise (RMS z 0.84); the best damper misses by 2.0 (one run
    # at one amplitude: friction acts nearly as its linear equivalent, section "Coulomb or viscous")
    assert 0.5 < z[SMOOTHING][0] < 1.5, z
    assert z[SMOOTHING][1] > 2 * z[SMOOTHING][0], z
    # a sharper corner than the candidate's: off by about 3 standard errors, still closer than any damper
    assert z[0.02][0] < 4.0 and z[0.02][1] > z[0.02][0], z
    # the plan's describing function, at the truth's own values, misses by far more than the simulation
    assert z[SMOOTHING][2] > 3 * z[SMOOTHING][0] and z[0.02][2] > 1.5 * z[0.02][0], z


# -- hostile input: a clear error naming the file, or finite values / a reason; never a traceback -----
FUZZ_MANIFEST = """\
[experiment]
sample_rate = 50.0
control = "sil"

[columns]
roll_rate = "lean_rate"
steer_angle = "fork_angle"
speed = "speed"

[control.sil]
k_phid = { K = 2.0, v0 = 6.5, when = "below" }

[multisine]
torque = "torque"
outputs = ["roll_rate", "steer_angle"]
settle = 0.5

[[multisine.run]]
path = "run.log"
window = [0, 300]
lines = [0.5, 1.0, 2.0]
group = "g"
"""


def _fuzz_log() -> str:
    t = np.arange(300) / 50.0
    torque = sum(0.2 * np.cos(2 * math.pi * f * t + k) for k, f in enumerate((0.5, 1.0, 2.0)))
    rows = ["lean_rate,fork_angle,speed,torque"]
    rows += [f"{0.3 * u:.5f},{0.1 * u:.5f},4.0,{u:.5f}" for u in torque]
    return "\n".join(rows) + "\n"


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.data(), st.sampled_from(["manifest", "log"]))
def test_hostile_multisine_manifests_and_logs(tmp_path_factory, data, target):
    files = {"manifest": FUZZ_MANIFEST.encode(), "log": _fuzz_log().encode()}
    what, files[target] = data.draw(mutated(files[target]))
    folder = tmp_path_factory.mktemp("fuzz")
    (folder / "experiment.toml").write_bytes(files["manifest"])
    (folder / "run.log").write_bytes(files["log"])
    try:
        settings_, _ = read_manifest(folder / "experiment.toml")
        records = read_multisines(folder / "experiment.toml", settings_)
    except BikeriderError as exc:
        assert_names_file(exc, folder / "experiment.toml", folder / "run.log")
        return
    for r in records:
        fit = fit_multisine(r)
        if fit.used:
            assert_all_finite([fit.lines, *fit.response.values(), *fit.sigma.values()], f"{target}: {what}")
        else:
            assert isinstance(fit.reason, str) and fit.reason, what


def test_a_speed_sensor_error_is_found_from_multisines(tmp_path):
    """The bicycle ran 4 % faster than its wheel encoder read (the controller used the reading): the
    multisine runs, rescaled by the speed_sensor candidate, find the scale with an interval that holds it."""
    rng = np.random.default_rng(7)
    runs = []
    for session in "abc":
        recorded = 3.5
        columns = multisine_log(VALUES, 1.04 * recorded, LAW(recorded), _lines(recorded), 0.5, 10.0, rng=rng)
        columns["speed"] = recorded + 0.02 * rng.standard_normal(columns["speed"].size)
        runs.append((f"ms_{session}.csv", columns, f"session {session}"))
    manifest = _write_runs(tmp_path, runs)
    d = diagnose_files(
        str(SBW / "sbw_bicycle.toml"), experiment=(str(manifest),), effects="speed_sensor,steer_damping"
    ).as_dict()
    assert d["selected"] == ["speed_sensor"], d["selected"]
    scale = next(r for r in d["ranking"] if r["effect"] == "speed_sensor")["parameters"]["speed_scale"]
    assert scale["ci95"][0] <= 1.04 <= scale["ci95"][1], scale
