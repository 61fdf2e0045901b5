"""Every example command of README's list of shipped inputs, of docs/dynamics.md and docs/period.md
runs as written (from the repository's root; outputs go to a temporary folder)."""

from __future__ import annotations

import glob
import re
import shlex
from pathlib import Path

import pytest
from strategies import run_cli

ROOT = Path(__file__).resolve().parents[1]


def _blocks(path: Path) -> list[str]:
    """The lines of a document's sh code blocks."""
    text = path.read_text()
    return [line for block in re.findall(r"```sh\n(.*?)```", text, re.S) for line in block.splitlines()]


def _commands() -> list[str]:
    readme = (ROOT / "README.md").read_text()
    shipped = readme.split("each\n  of these runs as written", 1)[1].split("```sh", 1)[1].split("```", 1)[0]
    lines = [line.strip() for line in shipped.splitlines()]
    lines += _blocks(ROOT / "docs" / "dynamics.md") + _blocks(ROOT / "docs" / "period.md")
    return [line.split(" #")[0].strip() for line in lines if line.strip().startswith("bikerider ")]


COMMANDS = _commands()


def test_the_examples_are_found():
    assert len(COMMANDS) >= 12
    assert {c.split()[1] for c in COMMANDS} >= {
        "estimate",
        "benchmark",
        "sweep",
        "convert",
        "batch",
        "period",
        "sensitivity",
        "gap",
    }


@pytest.mark.parametrize("command", COMMANDS)
def test_a_documented_example_runs(command, tmp_path, monkeypatch):
    argv = []
    for word in shlex.split(command)[1:]:
        if word.startswith("src/"):
            word = str(ROOT / word)
            matches = sorted(glob.glob(word))
            argv += matches or [word]
        else:
            argv.append(word)
    monkeypatch.chdir(tmp_path)  # out/, fits.png, BrowserJasonBenchmark.txt are written here
    code, out, err = run_cli(argv)
    assert code == 0, f"{command}\n{err}"
    assert out or any(tmp_path.iterdir())
