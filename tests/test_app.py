"""bikerider serve: the page's work as plain functions (bikerider.app), and the server's guards."""

from __future__ import annotations

import http.client
import io
import json
import math
import os
import stat
import threading
import time
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from bikerider.app import bicycle, downloads, dynamics
from bikerider.app.gap_jobs import GapJobs
from bikerider.app.server import App, make_server
from bikerider.app.steer_frame import first_order_sigmas, from_steer_frame, front_assembly, to_steer_frame
from bikerider.app.uploads import UploadFolders
from bikerider.errors import BikeriderError, InputError
from bikerider.io.benchmark_file import load_benchmark_parameters
from bikerider.io.input_file import TEXT_LIMIT

DATA = Path(str(resources.files("bikerider") / "data"))


@pytest.fixture(scope="module")
def browser_jason():
    return bicycle.load_shipped("Browser+Jason")


@pytest.fixture
def app(tmp_path):
    app = App(upload_root=tmp_path)
    yield app
    app.close()


def _cells(loaded, **changes):
    cells = bicycle.cells_of(loaded.parameters)
    for name, value in changes.items():
        cells[name] = [value, cells[name][1]]
    return cells


# -- the front assembly in the steer-axis frame ------------------------------------------------------
def test_the_steer_frame_turns_the_tensor_and_goes_back(browser_jason):
    v = {k: float(x) for k, x in browser_jason.parameters.values.items() if x is not None}
    steer = to_steer_frame(v)
    lam = v["lam"]
    axis = np.array([math.sin(lam), math.cos(lam)])  # down the steer axis in (x, z)
    tensor = np.array([[v["IHxx"], v["IHxz"]], [v["IHxz"], v["IHzz"]]])
    assert steer["IH33"] == pytest.approx(axis @ tensor @ axis, rel=1e-12)
    assert steer["IH11"] + steer["IH33"] == pytest.approx(v["IHxx"] + v["IHzz"], rel=1e-12)  # the trace
    # the centre of mass: dH from the axis line, uH up it from the ground point (w + c, 0)
    ground = np.array([v["w"] + v["c"], 0.0])
    com = np.array([v["xH"], v["zH"]])
    assert np.hypot(steer["dH"], steer["uH"]) == pytest.approx(np.linalg.norm(com - ground), rel=1e-12)
    back = from_steer_frame(v, steer)
    for name in ("xH", "zH", "IHxx", "IHzz", "IHxz"):
        assert back[name] == pytest.approx(v[name], rel=1e-12, abs=1e-15)


def test_the_front_assembly_about_the_steer_axis_adds_both_bodies(browser_jason):
    v = {k: float(x) for k, x in browser_jason.parameters.values.items() if x is not None}
    steer = to_steer_frame(v)
    assembly = front_assembly(v)
    assert assembly["mass"] == pytest.approx(v["mH"] + v["mF"])
    assert assembly["I_steer_axis"] > steer["IH33"] + v["IFxx"]  # plus the parallel-axis terms
    sigmas = first_order_sigmas(front_assembly, v, {"mF": 0.1}, ("mF",))
    d = -v["c"] * math.cos(v["lam"]) + v["rF"] * math.sin(v["lam"])
    assert sigmas["I_steer_axis"] == pytest.approx(0.1 * d**2, rel=1e-6)  # linear in mF: exact


# -- the table and its edits ---------------------------------------------------------------------------
def test_the_table_has_every_value_with_unit_and_sigma(browser_jason):
    table = bicycle.parameter_table(browser_jason.parameters)
    names = [row["name"] for row in table["rows"]]
    assert sorted(names) == sorted(browser_jason.parameters.values)
    row = next(r for r in table["rows"] if r["name"] == "mB")
    assert row["unit"] == "kg" and row["sigma"] > 0
    assert [r["name"] for r in table["steer_frame"]] == ["dH", "uH", "IH11", "IH33", "IH13"]


def test_an_edit_error_sits_next_to_its_value_worded_as_the_command_line(browser_jason):
    cells = _cells(browser_jason, mB="-3", w="abc")
    cells["rR"] = [0.34, -1]
    result = bicycle.edited_parameters(cells)
    assert result.parameters is None
    assert result.errors["mB"] == ["the parameter table: mB = -3: expected a positive value"]
    assert "w = 'abc'" in result.errors["w"][0]
    assert "rR uncertainty = -1" in result.errors["rR"][0]
    # a tensor's error is shown at each of its entries
    cells = _cells(browser_jason, IHxx=-1)
    errors = bicycle.edited_parameters(cells).errors
    assert set(errors) == {"IHxx", "IHyy", "IHzz", "IHxz"}


def test_a_table_edit_in_the_steer_frame_changes_the_benchmark_values(browser_jason):
    cells = bicycle.cells_of(browser_jason.parameters)
    steer = {r["name"]: r["value"] for r in bicycle.parameter_table(browser_jason.parameters)["steer_frame"]}
    steer["dH"] += 0.01
    edited = bicycle.edited_parameters(cells, steer).parameters
    lam = browser_jason.parameters.values["lam"]
    assert edited.values["xH"] - browser_jason.parameters.values["xH"] == pytest.approx(0.01 * math.cos(lam))
    assert edited.values["zH"] - browser_jason.parameters.values["zH"] == pytest.approx(-0.01 * math.sin(lam))
    assert edited.values["IHxx"] == pytest.approx(browser_jason.parameters.values["IHxx"])


# -- each change runs each computation once ----------------------------------------------------------------
def test_each_input_change_runs_each_computation_once(app, browser_jason):
    request = {"cells": bicycle.cells_of(browser_jason.parameters), "speed": 5.0, "map": {"x": "c"}}
    first = app.update(request).data()
    assert first["ok"]
    everything = {name: 1 for name in ("eigenvalues", "uncertainty", "side_view", "bode", "map")}
    assert dict(app.dynamics.calls) == everything  # no closed loop without gains, no Monte Carlo yet
    for _ in range(2):  # the Monte Carlo sigmas, asked for apart: once
        assert app.monte_carlo(request).data()["monte_carlo"]["samples"] == dynamics.MONTE_CARLO_SAMPLES
    assert dict(app.dynamics.calls) == {**everything, "monte_carlo": 1}
    app.dynamics.calls.pop("monte_carlo")
    app.update(request)  # the same page again: nothing runs
    assert dict(app.dynamics.calls) == everything
    app.update({**request, "speed": 6.0})  # a new speed: the Bode diagram alone
    assert dict(app.dynamics.calls) == {**everything, "bode": 2}
    app.update({**request, "cells": _cells(browser_jason, c=0.07), "speed": 6.0})  # a parameter: each once
    assert dict(app.dynamics.calls) == {"eigenvalues": 2, "uncertainty": 2, "side_view": 2, "bode": 3, "map": 2}
    app.update({**request, "speed": 6.0, "map": {"x": "c", "y": "lam"}})  # a new map: the map alone
    assert app.dynamics.calls["map"] == 3 and app.dynamics.calls["eigenvalues"] == 2
    gains = {"k_phi": "20", "k_phid": 0, "k_delta": 0, "k_deltad": 0}
    app.update({**request, "speed": 6.0, "map": {"x": "c", "y": "lam"}, "gains": gains})  # the closed loop alone
    assert dict(app.dynamics.calls) == {
        "eigenvalues": 2,
        "uncertainty": 2,
        "side_view": 2,
        "bode": 3,
        "map": 3,
        "closed_loop": 1,
    }


def test_the_closed_loop_under_constant_gains(app, browser_jason):
    from bikerider.benchmark import WhippleModel

    request = {"cells": bicycle.cells_of(browser_jason.parameters), "speed": 5.0}
    off = app.update({**request, "gains": {"k_phi": 0, "k_phid": 0, "k_delta": 0, "k_deltad": 0}}).data()
    critical = WhippleModel.from_parameters(browser_jason.parameters).critical_speeds()
    assert off["closed_loop"]["weave"] == pytest.approx(critical.weave)  # no gains: the open loop
    assert off["closed_loop"]["capsize"] == pytest.approx(critical.capsize)
    on = app.update({**request, "gains": {"k_phi": 50}}).data()["closed_loop"]
    assert on["stable_intervals"][0][0] != pytest.approx(critical.weave)
    bad = app.update({**request, "gains": {"k_phi": "x"}}).data()
    assert bad["closed_loop"] is None and bad["gains_error"].startswith(
        "the closed loop: k_phi = 'x': expected a finite"
    )


def test_a_table_with_errors_runs_nothing_and_says_why(app, browser_jason):
    reply = app.update({"cells": _cells(browser_jason, mB="-3"), "speed": 5.0}).data()
    assert not reply["ok"] and "mB" in reply["errors"]
    assert not app.dynamics.calls


def test_the_figures_data_agree_with_the_model(app, browser_jason):
    from bikerider.benchmark import WhippleModel

    reply = app.update({"cells": bicycle.cells_of(browser_jason.parameters), "speed": 5.0}).data()
    critical = WhippleModel.from_parameters(browser_jason.parameters).critical_speeds()
    assert reply["eigenvalues"]["weave"] == pytest.approx(critical.weave)
    assert reply["eigenvalues"]["capsize"] == pytest.approx(critical.capsize)
    assert reply["eigenvalues"]["speeds"][1] == pytest.approx(0.1) and len(reply["eigenvalues"]["speeds"]) == 101
    first_order = reply["uncertainty"]["speeds"]["weave"]
    sigma = app.monte_carlo({"cells": bicycle.cells_of(browser_jason.parameters)}).data()["monte_carlo"]["speeds"][
        "weave"
    ]
    assert sigma["first_order"] == pytest.approx(first_order, rel=1e-9)
    assert 0 < sigma["monte_carlo"] < 1 and sigma["monte_carlo"] == pytest.approx(first_order, rel=0.2)
    band = reply["uncertainty"]["band"]["weave"]
    assert any(s is not None and s > 0 for s in band["sigma_real"])
    assert reply["map"] is None and reply["bode"]["speed"] == 5.0


def test_map_errors_name_the_map(browser_jason):
    with pytest.raises(InputError, match="map y = 'c'"):
        dynamics.check_map({"x": "c", "y": "c"}, browser_jason.parameters)
    with pytest.raises(InputError, match="LOW < HIGH"):
        dynamics.check_map({"x": "c", "x_range": [0.2, 0.1]}, browser_jason.parameters)
    with pytest.raises(InputError, match="map x = 'IByy'"):
        dynamics.check_map({"x": "IByy"}, browser_jason.parameters)


# -- downloads -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("fmt", ["toml", "txt", "json"])
def test_downloaded_parameters_read_back_as_benchmark_reads_them(tmp_path, browser_jason, fmt):
    name, text = downloads.parameter_file(browser_jason.parameters, fmt, "Browser + Jason")
    assert name == {"toml": "BrowserJason.toml", "txt": "BrowserJasonBenchmark.txt", "json": "BrowserJason.json"}[fmt]
    path = tmp_path / name
    path.write_text(text)
    back = load_benchmark_parameters(path)
    for key, value in browser_jason.parameters.values.items():
        if value is None:
            assert back.values[key] is None
        else:
            assert back.values[key] == value
            assert back.sigmas[key] == pytest.approx(browser_jason.parameters.sigmas.get(key, 0.0))


def test_downloaded_tables_and_figures(browser_jason):
    _, text = downloads.table_file(browser_jason.parameters, "eigenvalues")
    lines = text.splitlines()
    assert lines[0].startswith("speed,mode,real,imag,sigma_real") and len(lines) == 1 + 101 * 4
    axes = dynamics.check_map({"x": "c"}, browser_jason.parameters)
    _, text = downloads.table_file(browser_jason.parameters, "map", axes)
    assert (
        text.splitlines()[0].startswith("c,valid,reason,weave_speed")
        and len(text.splitlines()) == 1 + dynamics.MAP_POINTS[1]
    )
    _, png = downloads.figure_file(browser_jason.parameters, "eigenvalues", "png", 5.0)
    assert png.startswith(b"\x89PNG")
    _, svg = downloads.figure_file(browser_jason.parameters, "bode", "svg", 5.0)
    assert b"<svg" in svg[:400]
    with pytest.raises(InputError, match="choose its parameter"):
        downloads.figure_file(browser_jason.parameters, "map", "pdf", 5.0)


def test_a_download_of_a_table_with_errors_says_which(app, browser_jason):
    with pytest.raises(InputError, match="mB = -3"):
        app.download({"cells": _cells(browser_jason, mB=-3), "kind": "parameters", "format": "toml"})


# -- uploads ---------------------------------------------------------------------------------------------
def test_uploads_go_to_a_private_folder_and_never_overwrite(tmp_path):
    uploads = UploadFolders(tmp_path)
    try:
        ident = uploads.new("experiment")
        path = uploads.write(ident, "logs/run.csv", io.BytesIO(b"a,b\n"), 4)
        assert path.is_relative_to(uploads.root) and path.read_bytes() == b"a,b\n"
        assert stat.S_IMODE(os.stat(uploads.root).st_mode) == 0o700
        assert stat.S_IMODE(os.stat(path).st_mode) == 0o600
        with pytest.raises(InputError, match="nothing is overwritten"):
            uploads.write(ident, "logs/run.csv", io.BytesIO(b"x"), 1)
        assert path.read_bytes() == b"a,b\n"
        for bad in ("../escape.txt", "/etc/passwd", "logs/../../x", "", "a\\b", "a//b"):
            with pytest.raises(InputError, match="upload"):
                uploads.write(ident, bad, io.BytesIO(b"x"), 1)
        assert not (tmp_path / "escape.txt").exists()
        with pytest.raises(InputError, match="cut short"):
            uploads.write(ident, "short.csv", io.BytesIO(b"abc"), 10)
        assert uploads.files(ident) == ["logs/run.csv"]
        small = uploads.new("bicycle")
        with pytest.raises(InputError, match=f"at most {TEXT_LIMIT} bytes"):
            uploads.check_size(small, "big.toml", TEXT_LIMIT + 1)
    finally:
        uploads.remove_all()
    assert not uploads.root.exists()


def test_an_uploaded_bicycle_goes_through_the_command_lines_readers(app, capsys):
    from bikerider.cli import main

    measured = DATA / "bicycleparameters" / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt"
    if not measured.is_file():
        measured = next((DATA / "bicycleparameters" / "bicycles").rglob("*Measured.txt"))
    folder = app.new_upload({"kind": "bicycle"}).data()["folder"]
    data = measured.read_bytes()
    app.upload(folder, measured.name, io.BytesIO(data), len(data))
    reply = app.load_files({"folder": folder, "bicycle": measured.name}).data()
    assert reply["cells"]["w"][0] > 0 and reply["name"].startswith(measured.name)
    # a bad file: the error the command line prints, every error at once
    bad = b"w = 1.0\nc = abc\n"
    app.upload(folder, "Bad.txt", io.BytesIO(bad), len(bad))
    with pytest.raises(BikeriderError) as page:
        app.load_files({"folder": folder, "bicycle": "Bad.txt"})
    path = app.uploads.path(folder, "Bad.txt")
    assert main(["estimate", "--bicycle", str(path), "--monte-carlo", "0"]) == 2
    assert f"error: {bicycle.error_text(page.value)}" in capsys.readouterr().err


# -- the gap, in the background -------------------------------------------------------------------------------
def _wait_for(job, seconds=120):
    end = time.monotonic() + seconds
    while job.step not in ("done", "failed") and time.monotonic() < end:
        time.sleep(0.05)
    return job


def test_a_diagnosis_runs_in_the_background_with_the_packages_entry_point(tmp_path):
    from bikerider.diagnose import diagnose_files

    uploads = UploadFolders(tmp_path)
    try:
        jobs = GapJobs(uploads, lambda model, data, experiment: diagnose_files(model, data, experiment))
        folder = uploads.new("experiment")
        for name in ("kooijman2008_bicycle.toml", "kooijman2008_run52.csv"):
            data = (DATA / "gap" / name).read_bytes()
            uploads.write(folder, name, io.BytesIO(data), len(data))
        job = _wait_for(
            jobs.start(folder, "kooijman2008_bicycle.toml", data=["kooijman2008_run52.csv"], next_plan=False)
        )
        status = job.status()
        assert status["step"] == "done", status["error"]
        assert status["summary"].startswith("Verdict:") and status["result"]["verdict"] is not None
        assert status["figures"] and jobs.figure(job.ident, status["figures"][0]["name"]).startswith(b"\x89PNG")
        assert job.report.is_relative_to(uploads.root)
        assert b"gap_report/report.md" in jobs.report_zip(job.ident)
    finally:
        uploads.remove_all()


def test_a_failed_diagnosis_says_why_as_the_command_line_does(tmp_path):
    def refuse(model, data, experiment):
        raise InputError("data", "empty", "at least one measured eigenvalue or identified entry")

    uploads = UploadFolders(tmp_path)
    try:
        jobs = GapJobs(uploads, refuse)
        folder = uploads.new("experiment")
        uploads.write(folder, "model.toml", io.BytesIO(b"x"), 1)
        job = _wait_for(jobs.start(folder, "model.toml", experiment=["model.toml"]))
        assert job.step == "failed"
        assert (
            job.error
            == "bikerider gap: error: data = 'empty': expected at least one measured eigenvalue or identified entry"
        )
        with pytest.raises(InputError, match="one of the uploaded files"):
            jobs.start(folder, "missing.toml", experiment=["model.toml"])
        with pytest.raises(InputError, match="--experiment"):
            jobs.start(folder, "model.toml")
    finally:
        uploads.remove_all()


# -- the server ----------------------------------------------------------------------------------------------
@pytest.fixture
def served(tmp_path):
    app = App(upload_root=tmp_path)
    server = make_server(app, "127.0.0.1", 0)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield server.server_address[1]
    server.shutdown()
    server.server_close()
    app.close()


def _request(port, method, path, body=None, headers=None):
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    connection.request(method, path, body=body, headers=headers or {})
    response = connection.getresponse()
    data = response.read()
    connection.close()
    return response, data


def test_the_server_serves_the_page_and_guards_its_doors(served):
    response, data = _request(served, "GET", "/")
    assert response.status == 200 and b"/static/app.js" in data
    assert "default-src 'self'" in response.getheader("Content-Security-Policy")
    response, data = _request(served, "GET", "/static/app.js")
    assert response.status == 200 and b"http://" not in data.replace(b"http://www.w3.org/2000/svg", b"")
    assert _request(served, "GET", "/static/../server.py")[0].status == 404
    assert _request(served, "GET", "/", headers={"Host": "evil.example:80"})[0].status == 403
    response, data = _request(served, "POST", "/api/update", b"{}", {"Content-Type": "text/plain"})
    assert response.status == 400 and b"application/json" in data
    response, data = _request(
        served, "POST", "/api/upload/new", b'{"kind": "bicycle"}', {"Content-Type": "application/json"}
    )
    folder = json.loads(data)["folder"]
    response, data = _request(served, "PUT", f"/api/upload/{folder}?name=../x.toml", b"w = 1")
    assert response.status == 400 and "no '..'" in json.loads(data)["error"]
    response, data = _request(
        served, "PUT", f"/api/upload/{folder}?name=big.toml", b"", {"Content-Length": str(TEXT_LIMIT + 1)}
    )
    assert response.status == 400 and "at most" in json.loads(data)["error"]


def test_serve_binds_this_computer_alone_by_default():
    from bikerider.cli import build_parser

    args = build_parser().parse_args(["serve"])
    assert args.host == "127.0.0.1" and args.port == 8050 and not args.open


def test_a_readers_note_is_placed_at_the_value_it_is_about(app):
    reply = app.load_shipped({"id": "Browser+Jason"}).data()
    assert any("IByy = 1.3164" in n for n in reply["note_fields"]["IByy"])
    assert any("yB = 0 m dropped" in n for n in reply["note_fields"]["*"])  # yB is no table value


def test_serve_refuses_a_port_out_of_range(capsys):
    from bikerider.cli import main

    assert main(["serve", "--port", "70000"]) == 2
    assert "--port = 70000: expected a port number from 0 to 65535" in capsys.readouterr().err


def test_uploaded_project_files_give_what_estimate_gives(app):
    """The paper's bicycle and rider TOML files uploaded: the parameters `estimate` gives, with the
    sigmas it reports."""
    from bikerider.estimate import estimate_from_files

    folder = app.new_upload({"kind": "bicycle"}).data()["folder"]
    for name in ("browser_bicycle.toml", "jason_rider.toml"):
        data = (DATA / "paper" / name).read_bytes()
        app.upload(folder, name, io.BytesIO(data), len(data))
    uploaded = app.load_files({"folder": folder, "bicycle": "browser_bicycle.toml", "rider": "jason_rider.toml"}).data()
    expected = estimate_from_files(DATA / "paper" / "browser_bicycle.toml", DATA / "paper" / "jason_rider.toml")
    assert {k: v[0] for k, v in uploaded["cells"].items()} == expected.parameters.values
    assert uploaded["cells"]["mB"][1] > 0  # the sigmas estimate reports (the files give none for mB)


def test_principal_moments_keep_the_trace_and_the_determinant(browser_jason):
    v = browser_jason.parameters.values
    for body in ("B", "H"):
        p = bicycle.parameter_table(browser_jason.parameters)["principal"][body]
        xx, zz, xz = v[f"I{body}xx"], v[f"I{body}zz"], v[f"I{body}xz"]
        assert sum(p["plane"]) == pytest.approx(xx + zz)
        assert p["plane"][0] * p["plane"][1] == pytest.approx(xx * zz - xz**2)
        c, s = math.cos(p["angle"]), math.sin(p["angle"])
        assert c * c * xx + 2 * c * s * xz + s * s * zz == pytest.approx(p["plane"][0])  # about the first axis
