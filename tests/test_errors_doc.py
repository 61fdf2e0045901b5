"""docs/errors.md lists every error a user can meet: each error class, each exit status, each
field name the code raises InputError/ReachError for, and each FileFormatError/FitError message.

The raise sites are found by reading the source (``ast``), so a new error without documentation
fails here.  Names computed at run time (a variable) are covered by the generic rows of the page.
"""

from __future__ import annotations

import ast
import inspect
import re
from pathlib import Path

import pytest

import bikerider.errors as errors

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "bikerider"
DOC = (ROOT / "docs" / "errors.md").read_text()
SPANS = [
    span.replace("\\|", "|")
    for span in re.findall(r"`([^`]+)`", re.sub(r"^```.*?^```", "", DOC, flags=re.MULTILINE | re.DOTALL))
]
"""Every backticked span of the page."""
PLACEHOLDER = r"(?:<[^>]+>|[\w.]+|\.\.\.|i, j)"
"""What a ``{...}`` of an f-string may be written as on the page: ``<body>``, ``B``, ``...``."""


def _raises() -> list[tuple[str, int, str, ast.expr]]:
    """``(file, line, class, argument)``: the name argument of InputError/ReachError, the message
    of FileFormatError/FitError, for every ``Class(...)`` in src/: raised at once, or collected to
    be raised with the other errors of a file (``errors.add(InputError(...))``)."""
    out = []
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)):
                continue
            cls, args = node.func.id, node.args
            if cls in ("InputError", "ReachError") and args:
                out.append((str(path.relative_to(ROOT)), node.lineno, cls, args[0]))
            elif cls == "FileFormatError" and len(args) > 1:
                out.append((str(path.relative_to(ROOT)), node.lineno, cls, args[1]))
            elif cls == "FitError" and args:
                out.append((str(path.relative_to(ROOT)), node.lineno, cls, args[0]))
    return out


RAISES = _raises()


def _pattern(arg: ast.expr) -> str | None:
    """A regex for a literal or f-string argument; None when it is computed."""
    if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
        return re.escape(arg.value)
    if isinstance(arg, ast.JoinedStr):
        parts = [re.escape(v.value) if isinstance(v, ast.Constant) else PLACEHOLDER for v in arg.values]
        return "".join(parts)
    return None


def test_the_raise_sites_were_found():
    classes = {cls for _, _, cls, _ in RAISES}
    assert classes == {"InputError", "ReachError", "FileFormatError", "FitError"}
    assert len(RAISES) > 150


@pytest.mark.parametrize(
    "cls",
    [c for _, c in inspect.getmembers(errors, inspect.isclass) if issubclass(c, errors.BikeriderError)],
    ids=lambda c: c.__name__,
)
def test_every_error_class_is_documented(cls):
    assert f"`{cls.__name__}`" in DOC


def _exit_codes() -> set[int]:
    codes: set[int] = set()
    files = [SRC / "cli.py", *sorted((SRC / "commands").glob("*.py"))]
    for path in files:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Return) and node.value is not None:
                for sub in ast.walk(node.value):
                    if isinstance(sub, ast.Constant) and type(sub.value) is int:
                        codes.add(sub.value)
    codes.add(2)  # argparse's usage errors
    return codes


def test_every_exit_status_is_documented():
    codes = _exit_codes()
    assert {0, 1, 2, 130} <= codes
    table = re.findall(r"^\| (\d+) \|", DOC, flags=re.MULTILINE)
    assert codes <= {int(c) for c in table}, f"exit statuses without a row: {codes - {int(c) for c in table}}"


NAMED = [(f, line, cls, arg) for f, line, cls, arg in RAISES if cls in ("InputError", "ReachError") and _pattern(arg)]


@pytest.mark.parametrize(
    "where, cls, arg",
    [(f"{f}:{line}", cls, arg) for f, line, cls, arg in NAMED],
    ids=[f"{Path(f).stem}:{line}" for f, line, _, _ in NAMED],
)
def test_every_field_name_is_documented(where, cls, arg):
    pattern = re.compile(rf"(?<![\w<]){_pattern(arg)}(?![\w>])")
    assert any(pattern.search(span) for span in SPANS), (
        f"{where}: {cls} for {ast.unparse(arg)} is not in a `...` span of docs/errors.md"
    )


MESSAGES = [
    (f, line, cls, arg) for f, line, cls, arg in RAISES if cls in ("FileFormatError", "FitError") and _pattern(arg)
]


def _key_words(arg: ast.expr) -> str:
    """The first literal piece of a message with three words or more (else the longest), its first
    four words: what a user would search the page for."""
    pieces = (
        [arg.value] if isinstance(arg, ast.Constant) else [v.value for v in arg.values if isinstance(v, ast.Constant)]
    )
    tokens = [re.findall(r"[A-Za-z0-9_'=<>-]+", piece) for piece in pieces]
    words = next((t for t in tokens if len(t) >= 3), max(tokens, key=len))
    return " ".join(words[:4])


@pytest.mark.parametrize(
    "where, cls, arg",
    [(f"{f}:{line}", cls, arg) for f, line, cls, arg in MESSAGES],
    ids=[f"{Path(f).stem}:{line}" for f, line, _, _ in MESSAGES],
)
def test_every_file_and_fit_message_is_documented(where, cls, arg):
    words = _key_words(arg)
    flat = re.sub(r"[^A-Za-z0-9_'=<>-]+", " ", DOC.replace("\\|", "|"))
    assert words in flat, f"{where}: {cls} message '{words} ...' is not in docs/errors.md"
