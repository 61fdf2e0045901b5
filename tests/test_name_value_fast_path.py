"""The name-value reader's one-match path for plain lines reads exactly what its general path reads.

A trailing comment sends a line through the general path (the one-match pattern admits no ``#``),
so each line is parsed both ways and the entries, or the errors, must be the same.
"""

from __future__ import annotations

import pytest

from bikerider.errors import FileFormatError
from bikerider.io.name_value_file import parse_name_value_text

LINES = [
    "a = 1",
    "a=1+/-0.1",
    "  a\t=  -1.5e-3 ± 2E-4  ",
    "_x1 = .5 +/- 5.",
    "a = +7 +/- 0",
    "a = 1 +/- -0",  # a negative zero sigma is not negative
    "a = 1 +/- -0.1",  # negative sigma
    "a = 1e999",  # overflows to inf
    "a = 1 +/- 1e999",
    "a = nan",
    "1a = 2",
    "a = 1 2",
    "a = ",
    "a = 1.e5 +/- 2E-1",
    "a = 1e+5",
    "a = e5",
    "a = 1e",
    "a = +-1",
    "a = .",
    "a = 1..2",
    "a = 1 +/- .e1",
    "a = 1-2",
]


def _outcome(text: str):
    try:
        data = parse_name_value_text(text, "f.txt")
    except FileFormatError as exc:
        return "error", str(exc)
    return "ok", [(e.name, e.value, e.repeats, e.line) for e in data.entries.values()]


@pytest.mark.parametrize("line", LINES)
def test_plain_line_reads_as_with_a_comment(line):
    plain = _outcome(f"# header\n{line}\n")
    commented = _outcome(f"# header\n{line}   # forces the general path\n")
    assert plain == commented


def test_a_name_given_twice_on_plain_lines_is_reported_with_both_lines():
    with pytest.raises(FileFormatError, match=r"a is given twice \(first on line 1\)") as info:
        parse_name_value_text("a = 1+/-0.1\na = 2+/-0.1\n", "f.txt")
    assert info.value.line == 2


def test_plain_lines_keep_their_values_sigmas_and_line_numbers():
    data = parse_name_value_text("\nmR = 3.11+/-0.02\nnF = 13\n", "f.txt")
    assert (data["mR"].value, data["mR"].sigma, data.entries["mR"].line) == (3.11, 0.02, 2)
    assert (data["nF"].value, data["nF"].sigma, data.entries["nF"].line) == (13.0, 0.0, 3)
    assert data.entries["mR"].repeats == (data["mR"],)


@pytest.mark.parametrize("line", LINES)
@pytest.mark.parametrize("ending", ["\n", "\r\n"])
def test_a_text_of_plain_lines_reads_as_line_by_line(line, ending):
    """A text whose every line is plain is read by one match over the whole text (no comment or
    blank line sends it line by line): the same entries, line numbers and errors."""
    plain = _outcome(f"b = 2 +/- 0.1{ending}{line}{ending}c = 3{ending}")
    commented = _outcome(f"b = 2 +/- 0.1{ending}{line}   # forces the general path{ending}c = 3{ending}")
    assert plain == commented
