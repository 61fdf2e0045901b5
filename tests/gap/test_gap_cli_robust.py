"""``bikerider gap`` on long and awkward runs: progress, --quiet, Ctrl-C, and a plan that cannot be made."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest
from gap_support import MODEL

import bikerider
from bikerider import progress
from bikerider.cli import main

DATA = Path(bikerider.__file__).parent / "data"
BP = DATA / "bicycleparameters"
EXAMPLE = str(DATA / "gap_examples" / "eigenvalues.csv")
TWO = ["--effects", "steer_damping,steer_inertia"]
# below 1 m/s the benchmark bicycle's weave grows under every rival: no free decay can be recorded
NOWHERE = ["--next", "--next-speeds", "0.5:1.0:2", "--next-no-sweeps"]


@pytest.fixture(scope="module")
def unplannable():
    """The example diagnosed with a plan that cannot be made, as text and as JSON (one run each)."""
    out = {}
    for kind in ("text", "json"):
        stdout, stderr = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            code = main(["gap", *MODEL, "--data", EXAMPLE, *TWO, *NOWHERE] + (["--json"] if kind == "json" else []))
        out[kind] = (code, stdout.getvalue(), stderr.getvalue())
    return out


def test_next_without_any_experiment_keeps_the_diagnosis_and_says_why(unplannable):
    code, text, _ = unplannable["text"]
    assert code == 0
    assert "Verdict:" in text and "steer_damping" in text  # the diagnosis, printed as usual
    assert "What to measure next: no experiment can be planned: none of the 8 experiments considered" in text
    assert "grows there" in text and "--next-speeds" in text
    code, text, _ = unplannable["json"]
    result = json.loads(text)
    assert code == 0 and result["verdict"] == "structural"
    assert result["next"]["planned"] is False and "grows there" in result["next"]["reason"]


def test_a_log_file_gets_a_line_per_stage_that_takes_a_while(monkeypatch):
    # not a terminal: a stage of a second or more leaves a line when it ends, one running 5 s a
    # progress line (then one every 30 s); a quick run, or an error found at once, leaves none
    clock = [0.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: clock[0])
    stream = io.StringIO()
    with progress.reporting(stream=stream, name="x"):
        progress.begin("reading the inputs")
        clock[0] += 0.2
        progress.begin("candidates", 10, "fold fits")
        for _ in range(10):
            clock[0] += 1.0
            progress.advance()
        progress.begin("selecting")
        clock[0] += 1.5
    lines = stream.getvalue().splitlines()
    assert lines[0].startswith("x: candidates [############") and "5/10 fold fits (50%), 1/s" in lines[0]
    assert "0:05 left" in lines[0]
    assert lines[1:] == ["x: candidates: 10 fold fits done in 0:10", "x: selecting: done in 0:02"]


def test_an_error_found_at_once_is_the_first_line_on_stderr(capsys, tmp_path):
    assert main(["gap", *MODEL, "--data", str(tmp_path / "missing.csv")]) == 2
    assert capsys.readouterr().err.startswith("bikerider gap: error: ")


def test_quiet_silences_the_progress(capsys):
    assert main(["gap", *MODEL, "--data", EXAMPLE, "--effects", "steer_damping", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "bikerider gap: reading" not in err and "fold fits" not in err


def test_ctrl_c_stops_with_a_message_saying_what_was_kept(monkeypatch, capsys, tmp_path):
    from bikerider import diagnose as pipeline

    def interrupted(*args):
        progress.begin("candidates", 10, "fold fits")
        progress.advance(3)
        raise KeyboardInterrupt

    monkeypatch.setattr(pipeline, "run_diagnosis", interrupted)
    report = tmp_path / "report"
    assert main(["gap", *MODEL, "--data", EXAMPLE, "--report", str(report)]) == 130
    err = capsys.readouterr().err
    assert "interrupted during candidates (3 of 10 fold fits): nothing was kept" in err
    assert not report.exists()


def test_the_bar_on_a_terminal_shows_rate_and_time_left():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    stream = Tty()
    with progress.reporting(stream=stream, name="x") as reporter:
        progress.begin("records", 4, "records")
        for _ in range(4):
            progress.advance()
        assert reporter.where() == "records (4 of 4 records)"
    text = stream.getvalue()
    assert "\rx: records [" in text and "4/4 records (100%)" in text and "left" in text


def test_outside_a_command_progress_is_silent(capsys):
    progress.begin("records", 3, "records")
    progress.advance()
    progress.end()
    assert progress.current() is None
    assert capsys.readouterr().err == ""


def test_the_text_lists_every_repaired_record(unplannable):
    from bikerider.gap.text import summary_text

    records = {
        "total": 3,
        "used": 2,
        "left_out": 1,
        "reasons": [{"record": "c", "reason": "no oscillation found"}],
        "repaired": [{"record": "b", "repairs": ["3 missing roll_rate samples dropped", "resampled to 10 ms"]}],
    }
    result = json.loads(unplannable["json"][1])
    text = summary_text({**result, "records": records})
    assert "Records: 2 of 3 used (1 of them repaired), 1 left out" in text
    assert "  repaired b: 3 missing roll_rate samples dropped; resampled to 10 ms" in text
    assert "  left out c: no oscillation found" in text
