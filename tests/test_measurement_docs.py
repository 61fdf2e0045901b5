"""docs/input_format.md defines every measurement, with a figure drawn from the model's geometry (issue 12)."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "input_format.md"
SCRIPT = ROOT / "docs" / "scripts" / "measurement_figure.py"


def _section() -> str:
    text = DOC.read_text()
    return re.search(r"## What each measurement is\n(.*?)\n## ", text, re.S).group(1)


def _defined() -> set[str]:
    """Keys in the first column of the section's tables."""
    keys = set()
    for row in re.findall(r"^\| (`[^|]+) \|", _section(), re.M):
        keys.update(re.findall(r"`([^`]+)`", row))
    return keys


def test_every_table_1_and_table_7_key_is_defined():
    from bikerider.io import toml_input

    expected = set(toml_input._GEOMETRY_KEYS) | {f"{a}_deg" for a in toml_input._GEOMETRY_ANGLES}
    expected |= set(toml_input._RIDER_KEYS) | {"lam_fl_deg", "mass"}
    assert expected <= _defined(), sorted(expected - _defined())


def test_angles_say_what_they_are_measured_from():
    rows = {
        key: row
        for row in _section().splitlines()
        if row.startswith("| `")
        for key in re.findall(r"`([^`]+)`", row.split("|")[1])
    }
    for key in ("lam_st_deg", "lam_ht_deg", "lam_fl_deg"):
        assert "horizontal" in rows[key], key


def test_the_figure_labels_what_the_tables_define_and_is_committed():
    spec = importlib.util.spec_from_file_location("measurement_figure", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    assert set(module.LABELS) <= _defined()
    assert "![Every measurement on the model's own geometry](figures/measurements.png)" in _section()
    data = (ROOT / "docs" / "figures" / "measurements.png").read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) < 200_000
    # drawn from the model's grid points: the script's points are the generated function's
    points, args = module._points()
    assert points[6][0] == args["w"] and points[2][1] == args["rR"]
