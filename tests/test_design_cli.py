"""``bikerider sweep`` on design spaces: stores, random designs, raw measurements, errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bikerider import explore
from bikerider.cli import main
from bikerider.design import monte_carlo
from bikerider.design.distribution import speed_distributions
from bikerider.shipped import named

pytest.importorskip("zarr")
GRID = [
    "--bicycle",
    "Benchmark",
    "--vary",
    "c=0:0.15:8",
    "--vary",
    "lam_deg=0:30:6",
    "--vary",
    "w=0.9:1.2:3",
    "--speeds",
    "0:10:21",
    "--weave-speeds",
    "4:6:2",
    "--quiet",
]


def test_a_grid_into_a_store_prints_a_summary_and_resumes(tmp_path, capsys):
    store = tmp_path / "store"
    assert main(["sweep", *GRID, "--store", str(store), "--json", "--target-weave-speed", "5"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert first["designs"] == 144 and first["valid"] == 144 and 0 < first["self_stable"] < 144
    assert [p["name"] for p in first["parameters"]] == ["c", "lam", "w"]
    assert 4.5 < first["closest_to_weave_speed"]["weave_speed"] < 5.5
    assert (store / "zarr.json").exists() and len(list((store / "done").iterdir())) == 1
    assert main(["sweep", *GRID, "--store", str(store), "--json", "--target-weave-speed", "5"]) == 0
    assert json.loads(capsys.readouterr().out) == first  # the finished store is read, not recomputed
    assert main(["sweep", *GRID, "--store", str(store)]) == 0
    text = capsys.readouterr().out
    assert "144 designs (grid 8 x 6 x 3) over c, lam, w" in text and "S(weave)" in text


def test_plots_of_a_store(tmp_path, capsys):
    assert (
        main(["sweep", *GRID, "--store", str(tmp_path / "s"), "--plot", str(tmp_path / "fig"), "--slice", "lam,w"]) == 0
    )
    assert sorted(p.name for p in (tmp_path / "fig").iterdir()) == [
        "map_lam_w.png",
        "sensitivity.png",
        "stable_fraction.png",
    ]


def test_random_designs_as_rows(capsys):
    assert (
        main(
            [
                "sweep",
                "--bicycle",
                "Benchmark",
                "--random",
                "6",
                "--vary",
                "c=0:0.2",
                "--vary",
                "mB=85+/-10",
                "--weave-speeds",
                "5:5:1",
                "--quiet",
            ]
        )
        == 0
    )
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0].startswith("c,mB,valid,reason,weave_speed") and lines[0].endswith("weave_damping_ratio@5")
    assert len(lines) == 7


def test_raw_measurements_through_the_estimate(capsys):
    assert (
        main(
            [
                "sweep",
                "--measured",
                "--vary",
                "l_sp=0.18:0.22:3",
                "--vary",
                "mBr=60:80:2",
                "--vary",
                "lam_ht_deg=70:72:2",
                "--json",
                "--quiet",
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert out["kind"] == "measurements" and len(out["designs"]) == 12
    assert all(d["valid"] and d["weave_speed"] is not None for d in out["designs"])


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--vary", "trail=0:1:3", "--vary", "c=0:1:3", "--vary", "w=1:2:3"], "--vary = 'trail': expected one of the"),
        (["--vary", "c=0:0.1:0", "--vary", "w=1:2:3", "--vary", "mB=1:2:3"], "1 <= N"),
        (["--random", "5", "--vary", "c=0.2:0.1"], "c = '0.2:0.1': expected a range LOW:HIGH"),
        (["--random", "5", "--vary", "c=0.2"], "NAME=LOW:HIGH (uniform) or NAME=MEAN+/-SIGMA"),
        (["--monte-carlo", "5", "--vary", "c=0:1:2"], "--monte-carlo = 5: expected no --vary"),
        (
            ["--vary", "c=0:0.1:200", "--vary", "w=1:2:100", "--vary", "mB=1:2:100"],
            "--store = missing: expected a folder",
        ),
        (["--vary", "c=0:0.1:3", "--vary", "w=1:2:3", "--vary", "mB=1:2:3", "--workers", "2"], "--workers = 2"),
    ],
)
def test_bad_design_options_are_named(argv, message, capsys):
    assert main(["sweep", "--bicycle", "Benchmark", "--quiet", *argv]) == 2
    assert message in capsys.readouterr().err


def test_a_store_run_says_each_stage_and_ctrl_c_says_how_to_resume(tmp_path, capsys, monkeypatch):
    """issue 24: after the bar reached 100 % the summary, figures and target search ran in silence;
    Ctrl-C ended without "N of M chunks stored: rerun the same command to resume", and a resumed run
    did not say it resumed."""
    from bikerider.design import engine

    argv = [*[a for a in GRID if a != "--quiet"], "--store", str(tmp_path / "s"), "--chunk-size", "16"]
    original, calls = engine.evaluate, []

    def stopped(*args, **kwargs):
        calls.append(1)
        if len(calls) == 4:
            raise KeyboardInterrupt  # the user's Ctrl-C while the fourth chunk is computed
        return original(*args, **kwargs)

    monkeypatch.setattr(engine, "evaluate", stopped)
    assert main(["sweep", *argv]) == 130
    err = capsys.readouterr().err
    assert "interrupted; 3 of 9 chunks stored in" in err and "rerun the same command to resume" in err
    monkeypatch.setattr(engine, "evaluate", original)
    figures = tmp_path / "fig"
    assert main(["sweep", *argv, "--plot", str(figures), "--target-weave-speed", "5"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err[0] == f"resuming {tmp_path / 's'}: 3 of 9 chunks already stored, 6 to compute"
    stages = [
        "finding the design whose weave speed is closest to 5 m/s ...",
        "summarising the store (self-stable fractions, sensitivity indices) ...",
        f"writing {figures / 'stable_fraction.png'}",
        f"writing {figures / 'sensitivity.png'}",
        f"writing {figures / 'map_c_lam.png'}",
    ]
    positions = [err.index(line) for line in stages]
    assert positions == sorted(positions)
    assert err[-1].startswith("sweep: done in ") and err[-1].endswith("(the whole command)")
    assert main(["sweep", *argv, "--quiet"]) == 0
    assert capsys.readouterr().err == ""  # --quiet: nothing on stderr


def test_monte_carlo_reports_the_speeds_distribution(tmp_path):
    """Median and central intervals of the weave and capsize speeds over the sample, as the
    benchmark command's own Monte Carlo gives them (same draws of the same sigmas)."""
    out = tmp_path / "out.json"
    argv = ["sweep", "--bicycle", "Browser", "--monte-carlo", "2000", "--seed", "3", "--json", "--out", str(out)]
    assert main(argv + ["--plot", str(tmp_path / "figs"), "--quiet"]) == 0
    data = json.loads(out.read_text())["distribution"]
    weave = data["weave_speed"]
    assert weave["n"] == 2000 and weave["central_95"][0] < weave["central_68"][0] < weave["median"]
    assert weave["median"] < weave["central_68"][1] < weave["central_95"][1]
    # the same numbers straight from the designs' weave speeds
    params = named("Browser")
    store = explore(monte_carlo(params, 2000, 3, "Browser"), None, quiet=True)
    speeds = speed_distributions(store)["weave_speed"].values
    assert weave["median"] == np.median(speeds)
    assert weave["central_68"] == list(np.quantile(speeds, [0.16, 0.84]))
    assert (tmp_path / "figs" / "speed_distribution.png").stat().st_size > 0
