"""Documents written by scripts are the scripts' current output.

``docs/reproduction.md``, ``docs/sensitivity.md`` and ``docs/gap_real_data.md`` are produced by
``docs/scripts/`` (``make docs``) from the code and the shipped data; a change that moves any figure
in them must regenerate them, or the documents would quote results the code no longer gives.  (The
blind gap validation, ``docs/gap_validation.md``, takes minutes and is left to ``make docs``.)
"""

from __future__ import annotations

import importlib.util
import logging
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = {
    "reproduction.md": "reproduction.py",
    "sensitivity.md": "sensitivity_report.py",
    "gap_real_data.md": "gap_real_data.py",
    "gallery.md": "gallery.py",
}


def _script(name: str):
    path = ROOT / "docs" / "scripts" / name
    spec = importlib.util.spec_from_file_location(f"docs_script_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


@pytest.mark.parametrize("document", sorted(SCRIPTS))
def test_document_is_its_scripts_output(document, caplog):
    caplog.set_level(logging.ERROR)
    expected = _script(SCRIPTS[document]).build()
    committed = (ROOT / "docs" / document).read_text(encoding="utf-8")
    assert committed == expected, (
        f"docs/{document} is not what docs/scripts/{SCRIPTS[document]} writes now: "
        "run `make docs` (or that script) and commit the result"
    )


def test_every_gallery_image_is_committed():
    import re

    text = (ROOT / "docs" / "gallery.md").read_text(encoding="utf-8")
    images = re.findall(r"!\[[^\]]*\]\((gallery/[^)]+\.png)\)", text)
    assert len(images) >= 9
    for image in images:
        data = (ROOT / "docs" / image).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) < 60_000, image  # small PNGs
