"""README's Python section runs as written."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_readme_python_section_runs(tmp_path, monkeypatch):
    """Every Python block of the section, in order, in one namespace (files it writes go to a
    temporary folder)."""
    monkeypatch.chdir(tmp_path)
    text = (ROOT / "README.md").read_text()
    section = re.search(r"## From Python\n(.*?)\n## ", text, re.S).group(1)
    code = "\n".join(re.findall(r"```python\n(.*?)```", section, re.S))  # run as written (issue 24)
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - the project's own README
    result = namespace["result"]
    assert round(result.model.critical_speeds().weave, 2) == 5.66  # README: 5.66 +/- 0.55 m/s
    assert "canonical_matrices" in namespace and "FUNCTIONS" in namespace
    assert (tmp_path / "eigenvalues.pdf").stat().st_size > 0 and namespace["store"].spec.space.size == 8000
    assert namespace["ss"].B.shape == (2, 4, 2) and namespace["trail"].shape == (61,)
    assert namespace["system"].critical_speeds().weave < namespace["model"].critical_speeds().weave
    assert (tmp_path / "BrowserJasonBenchmark.txt").read_text().startswith("IBxx = ")


def test_the_first_lines_say_how_to_run_the_command():
    """After `make demo` the command is in .venv/bin, not on the PATH (issue 12)."""
    head = "\n".join((ROOT / "README.md").read_text().splitlines()[:10])
    assert "make demo" in head and ".venv/bin/bikerider" in head and ".venv/bin/activate" in head
    makefile = (ROOT / "Makefile").read_text()
    assert "$(VENV)/bin/bikerider --help" in makefile.split("demo: $(STAMP)")[1].split("\n\n")[0]


def test_the_readme_quotes_what_make_demo_prints():
    from bikerider.cli import main

    text = " ".join((ROOT / "README.md").read_text().split())
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["estimate"]) == 0
    lines = {line.split()[0]: line for line in out.getvalue().splitlines() if line.endswith(")") and "speed" in line}
    weave = re.search(
        r"Weave speed +(\S+) \+/- (\S+) m/s \(Monte Carlo, \d+ samples: 68 % within (\S+); first order \+/- (\S+)\)",
        lines["Weave"],
    )
    capsize = re.search(
        r"Capsize speed +(\S+) \+/- (\S+) m/s \(Monte Carlo, \d+ samples: 68 % within (\S+); first order \+/- (\S+)\)",
        lines["Capsize"],
    )
    v, s, interval, fo = weave.groups()
    assert f"{float(v):.2f} +/- {s} m/s (68 % within {interval}; first order +/- {fo})" in text
    v, s, interval, fo = capsize.groups()
    assert f"{float(v):.2f} +/- {s} m/s ({interval}; first order +/- {fo})" in text


def test_every_public_name_resolves():
    import bikerider

    for name in bikerider.__all__:
        assert getattr(bikerider, name) is not None, name
