"""Command-line arguments: the fuzzing run's crashes, now clear errors, and -v after the subcommand
(issue 12).  Each error names the option, its value and what was expected."""

from __future__ import annotations

import logging
import time

import pytest
from strategies import run_cli


@pytest.mark.parametrize(
    "argv, option",
    [
        (["estimate", "--speeds", "0:1e308:3"], "--speeds"),  # was: LinAlgError from the eigenvalue sigmas
        (["benchmark", "--bicycle", "Browser", "--speeds", "0:1e308:3"], "--speeds"),
        (["sensitivity", "weave_speed", "--monte-carlo", "10", "--seed", "-1"], "--seed"),  # was: ValueError
        (["sweep", "--bicycle", "Benchmark", "--vary", "c=0.05:0.1", "--random", "3", "--seed", "-1"], "--seed"),
        (["estimate", "--seed", "-1"], "--seed"),
        (["sensitivity", "weave_speed", "--monte-carlo", "1000000000"], "--monte-carlo"),  # was: no end
        (["estimate", "--monte-carlo", "1000000000"], "--monte-carlo"),
        (["sensitivity", "weave_speed", "--top", "0"], "--top"),
        (["sensitivity", "a0", "--speed", "1e308"], "--speed"),
        (["gap", "--model", "m.toml", "--data", "d.csv", "--speed", "1e308"], "--speed"),
        (["sweep", "--bicycle", "Benchmark", "--vary", "c=0:1:3", "--weave-speeds", "0:1e308:3"], "--weave-speeds"),
    ],
)
def test_out_of_range_arguments_are_clear_errors(argv, option):
    started = time.monotonic()
    code, out, err = run_cli(argv)
    assert code == 2 and "Traceback" not in err
    last = err.strip().splitlines()[-1]
    assert option in last and "expected" in last, last
    assert time.monotonic() - started < 10  # refused, not run


def test_speeds_up_to_below_the_speed_of_light_still_run():
    """The limit is what cannot work (a Newtonian model past the speed of light), not what is unusual."""
    code, out, err = run_cli(["benchmark", "--bicycle", "Benchmark", "--speeds", "0:2.9e8:3"])
    assert code == 0, err
    assert "290000000.000" in out


@pytest.mark.parametrize("argv", [["estimate", "-v"], ["-v", "estimate"], ["estimate", "--json", "-vv"]])
def test_verbose_before_or_after_the_subcommand(argv, monkeypatch):
    """`-v` was refused after the subcommand (`unrecognized arguments: -v`)."""
    levels = []
    monkeypatch.setattr(logging, "basicConfig", lambda **kw: levels.append(kw["level"]))
    code, _, err = run_cli(argv)
    assert code == 0, err
    assert levels == [logging.DEBUG if "-vv" in argv else logging.INFO]
