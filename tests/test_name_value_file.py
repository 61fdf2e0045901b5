"""The ``name = value+/-sigma`` reader (BicycleParameters format)."""

from __future__ import annotations

import math

import pytest

from bikerider.errors import FileFormatError
from bikerider.io.name_value_file import mean_of_repeats, parse_name_value_text, read_name_value_file
from bikerider.quantity import Quantity


def test_values_sigmas_comments_and_blank_lines():
    text = "# header comment\n\nmR = 3.11+/-0.02   # trailing\ng = 9.81 +/- 0.01\nnF = 13\nx = -1.5e-3 ± 2e-4\n"
    data = parse_name_value_text(text, "f.txt")
    assert data["mR"] == Quantity(3.11, 0.02)
    assert data["g"] == Quantity(9.81, 0.01)
    assert data["nF"] == Quantity(13.0, 0.0)
    assert data["x"] == Quantity(-1.5e-3, 2e-4)
    assert list(data) == ["mR", "g", "nF", "x"]
    assert data.where("g") == "f.txt:4"
    assert data.entries["mR"].line == 3


def test_repeats_use_stated_sigma_when_scatter_is_small():
    data = parse_name_value_text("d = 1.0+/-0.1, 1.0+/-0.1, 1.0+/-0.1, 1.0+/-0.1")
    q = data["d"]
    assert q.value == pytest.approx(1.0)
    # stated sigmas through the mean: sqrt(4 * 0.01) / 4 = 0.05; no scatter
    assert q.sigma == pytest.approx(0.05)
    assert len(data.entries["d"].repeats) == 4


def test_repeats_use_scatter_when_it_exceeds_the_stated_sigma():
    values = [21.0780313, 21.0859688, 21.0899375]  # BicycleParameters' RigidMeasured.txt, dF
    q = mean_of_repeats([Quantity(v, 0.001) for v in values])
    mean = sum(values) / 3
    sample_sd = math.sqrt(sum((v - mean) ** 2 for v in values) / 2)
    assert q.value == pytest.approx(mean, rel=1e-15)
    assert q.sigma == pytest.approx(sample_sd / math.sqrt(3), rel=1e-12)
    assert q.sigma > math.sqrt(3) * 0.001 / 3  # larger than the stated-sigma-only value


def test_repeats_without_sigma_get_the_standard_error_of_their_scatter():
    q = parse_name_value_text("nF = 10, 12")["nF"]
    assert q.value == 11
    assert q.sigma == pytest.approx(1.0)  # s = sqrt(2), s / sqrt(2) = 1


@pytest.mark.parametrize(
    "line, fragment",
    [
        ("just words", "expected 'name = value+/-sigma'"),
        ("1x = 3", "is not a name"),
        ("w = ", "no value after"),
        ("w = abc", "cannot read 'abc'"),
        ("w = 1.0 +/- -0.1", "uncertainty -0.1 is negative"),
        ("w = nan", "cannot read"),
        ("w = 1.0, , 2.0", "cannot read ''"),
        ("w = 1.0 +/- 0.1 0.2", "cannot read"),
    ],
)
def test_unreadable_lines_name_file_and_line(line, fragment):
    with pytest.raises(FileFormatError) as info:
        parse_name_value_text(f"# ok\nc = 0.08\n{line}\n", "bike.txt")
    message = str(info.value)
    assert message.startswith("bike.txt:3: ")
    assert fragment in message
    assert info.value.line == 3


def test_a_name_given_twice_is_an_error():
    with pytest.raises(FileFormatError, match=r"f:3: w is given twice \(first on line 1\)"):
        parse_name_value_text("w = 1\nc = 2\nw = 3", "f")


def test_non_utf8_file_is_a_clear_error(tmp_path):
    path = tmp_path / "latin1.txt"
    path.write_bytes("w = 1.0\n# mesuré\n".encode("latin-1"))
    with pytest.raises(FileFormatError) as info:
        read_name_value_file(path)
    assert "not UTF-8" in str(info.value)
    assert info.value.line == 2
    assert str(path) in str(info.value)


def test_binary_file_is_a_clear_error(tmp_path):
    path = tmp_path / "data.bin"
    path.write_bytes(b"w = 1\n\x00\x01\x02")
    with pytest.raises(FileFormatError, match="NUL bytes"):
        read_name_value_file(path)


def test_utf8_with_byte_order_mark(tmp_path):
    path = tmp_path / "bom.txt"
    path.write_bytes("\ufeffw = 1.121+/-0.002\n".encode("utf-8"))
    assert read_name_value_file(path)["w"] == Quantity(1.121, 0.002)
