"""README's Python section runs as written (with the file names pointed at the shipped data)."""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))


def test_the_readme_python_section_runs(tmp_path, monkeypatch):
    """Every Python block of the section, in order, in one namespace (files it writes go to a
    temporary folder)."""
    monkeypatch.chdir(tmp_path)
    text = (ROOT / "README.md").read_text()
    section = re.search(r"## From Python\n(.*?)\n## ", text, re.S).group(1)
    code = "\n".join(re.findall(r"```python\n(.*?)```", section, re.S))
    code = code.replace(
        '"BrowserMeasured.txt"', repr(str(DATA / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt"))
    )
    code = code.replace(
        '"JasonBrowserBenchmark.txt"', repr(str(DATA / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt"))
    )
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - the project's own README
    result = namespace["result"]
    assert round(result.model.critical_speeds().weave, 2) == 5.66  # README: 5.66 +/- 0.53 m/s
    assert "canonical_matrices" in namespace and "FUNCTIONS" in namespace
    assert (tmp_path / "eigenvalues.pdf").stat().st_size > 0 and namespace["store"].spec.space.size == 8000
    assert namespace["ss"].B.shape == (2, 4, 2) and namespace["trail"].shape == (61,)


def test_every_public_name_resolves():
    import bikerider

    for name in bikerider.__all__:
        assert getattr(bikerider, name) is not None, name
