"""The wheel must contain every subpackage: pyproject.toml lists them explicitly."""

from __future__ import annotations

import glob
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_every_subpackage_is_listed_in_pyproject():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(config["packages"])
    on_disk = {
        ".".join(p.parent.relative_to(ROOT / "src").parts) for p in (ROOT / "src" / "bikerider").rglob("__init__.py")
    }
    assert on_disk - listed == set(), "add these to [tool.setuptools] packages in pyproject.toml"
    assert "bikerider.generated" in listed and config["package-dir"]["bikerider.generated"] == "generated"


def test_paper_data_is_package_data():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert "data/**/*" in config["package-data"]["bikerider"]


def test_a_fresh_install_is_quiet():
    """`make demo` on a fresh clone printed ~850 lines of setuptools warnings (issue 12): one
    'Package ... is absent from the packages configuration' per data folder, which setuptools takes
    for a package when include-package-data picks up the files git tracks, and a deprecation of
    `license` as a table.  Data files are named by package-data alone; the license is an SPDX string."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    config = project["tool"]["setuptools"]
    assert config["include-package-data"] is False
    assert isinstance(project["project"]["license"], str)
    assert any(r.replace(" ", "").startswith("setuptools>=7") for r in project["build-system"]["requires"])
    # Without include-package-data every data file must match package-data itself (setuptools
    # expands the patterns with glob, recursively, from the package's folder).
    package = ROOT / "src" / "bikerider"
    files = {p for p in (package / "data").rglob("*") if p.is_file() and "__pycache__" not in p.parts}
    matched = {
        Path(p)
        for pattern in config["package-data"]["bikerider"]
        for p in glob.glob(str(package / pattern), recursive=True)
        if Path(p).is_file()
    }
    assert files and files <= matched
