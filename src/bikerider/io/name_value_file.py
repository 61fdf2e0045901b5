"""Reader of ``name = value+/-sigma`` text files (the BicycleParameters format).

One entry a line::

    # a comment line
    mR = 3.11+/-0.02            # trailing comments are allowed too
    g = 9.81 +/- 0.01
    nF = 13                     # no uncertainty: sigma = 0
    dF = 21.078+/-0.001, 21.086+/-0.001, 21.090+/-0.001

Blank lines and lines whose first non-blank character is ``#`` are skipped; ``±`` may stand for
``+/-``.  A name appears at most once in a file.

Repeated measurements
---------------------
Comma-separated values are repeats of one measurement.  Their value is the plain mean
``m = sum(x_i) / n`` (as BicycleParameters takes it), and its standard uncertainty is the larger of

* the stated uncertainties carried through the mean, ``sqrt(sum(sigma_i^2)) / n``, and
* the standard error of the scatter, ``s / sqrt(n)`` with ``s`` the sample standard deviation.

The first is what the mean would have if the stated sigmas were the whole story; the second is what
the repeats themselves show.  Taking the larger never lets a scatter beyond the stated sigmas go
unreported (BicycleParameters keeps only the first, which is why its uncertainties on averaged
values can be smaller than ours).  The individual repeats stay available
(:attr:`NameValueEntry.repeats`) for callers that apply a rule of their own, such as the
period-trial check of :mod:`bikerider.bicycle.raw_measurements`.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

from bikerider.errors import FileFormatError, listing
from bikerider.io.input_file import read_input_text
from bikerider.quantity import Quantity

_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
_VALUE = re.compile(rf"^\s*({_NUMBER})\s*(?:(?:\+/-|±)\s*({_NUMBER}))?\s*$")
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
MAX_NAME = 64
"""Longest name, in characters (BicycleParameters' longest is 7): a longer one is a damaged line."""
_SIMPLE_LINE = re.compile(r"\s*([A-Za-z_]\w*)\s*=\s*([-+.\deE]+)\s*(?:(?:\+/-|±)\s*([-+.\deE]+))?\s*", re.ASCII)
"""The common line, one ``name = value[+/-sigma]`` without comment or repeats, read in one match.
Over these characters ``float`` accepts exactly the strings ``_NUMBER`` matches, so what it reads
the general path reads the same way; anything else (a number ``float`` rejects, any value that
would raise) goes through the general path."""
_SIMPLE_LINES = re.compile(
    r"^[ \t]*([A-Za-z_]\w*)[ \t]*=[ \t]*([-+.\deE]+)[ \t]*(?:(?:\+/-|±)[ \t]*([-+.\deE]+))?[ \t]*$", re.ASCII | re.M
)
r""":data:`_SIMPLE_LINE` over a whole text, one line after another (within a line of
``str.splitlines`` the only characters ``\s`` matches are spaces and tabs)."""


@dataclass(frozen=True, init=False)
class NameValueEntry:
    """One line of a name-value file.

    Attributes
    ----------
    name : str
        The name left of ``=``.
    value : Quantity
        The value; the mean of the repeats when there are several (see the module docstring).
    repeats : tuple of Quantity
        Every comma-separated value as written.
    line : int
        Line number (1-based) in the file, for messages.
    """

    name: str
    value: Quantity
    repeats: tuple[Quantity, ...]
    line: int

    def __init__(self, name: str, value: Quantity, repeats: tuple[Quantity, ...], line: int) -> None:
        # The frozen dataclass __init__, without its four object.__setattr__ calls (one entry a line).
        fields = self.__dict__
        fields["name"] = name
        fields["value"] = value
        fields["repeats"] = repeats
        fields["line"] = line


@dataclass(frozen=True)
class NameValueFile(Mapping[str, Quantity]):
    """The entries of one file; maps each name to its :class:`Quantity`.

    Attributes
    ----------
    path : str
        The file read (or a label for text parsed from memory).
    entries : dict of str to NameValueEntry
        Every entry in file order.
    """

    path: str
    entries: dict[str, NameValueEntry]

    def __getitem__(self, name: str) -> Quantity:
        return self.entries[name].value

    def __iter__(self) -> Iterator[str]:
        return iter(self.entries)

    def __len__(self) -> int:
        return len(self.entries)

    def where(self, name: str) -> str:
        """``"path:line"`` of an entry, or the path alone when the name is not in the file."""
        entry = self.entries.get(name)
        return f"{self.path}:{entry.line}" if entry else self.path

    def as_dict(self) -> dict[str, Quantity]:
        """A plain dict of name to :class:`Quantity`."""
        return {name: entry.value for name, entry in self.entries.items()}


def mean_of_repeats(repeats: list[Quantity] | tuple[Quantity, ...]) -> Quantity:
    """Combine repeats of one measurement into a mean and its standard uncertainty.

    The uncertainty is ``max(sqrt(sum(sigma_i^2)) / n, s / sqrt(n))`` (see the module docstring).

    Parameters
    ----------
    repeats : sequence of Quantity
        At least one repeat.

    Returns
    -------
    Quantity
    """
    n = len(repeats)
    if n == 0:
        raise ValueError("mean_of_repeats needs at least one value")
    if n == 1:
        return repeats[0]
    mean = math.fsum(q.value for q in repeats) / n
    stated = math.sqrt(math.fsum(q.sigma**2 for q in repeats)) / n
    sample_sd = math.sqrt(math.fsum((q.value - mean) ** 2 for q in repeats) / (n - 1))
    return Quantity(mean, max(stated, sample_sd / math.sqrt(n)))


def _parse_value(text: str, path: str, line: int, name: str) -> Quantity:
    match = _VALUE.match(text)
    if not match:
        raise FileFormatError(path, f"{name}: cannot read {text.strip()!r} as a number or 'value+/-sigma'", line)
    value = float(match.group(1))
    sigma = float(match.group(2)) if match.group(2) is not None else 0.0
    if not (math.isfinite(value) and math.isfinite(sigma)):
        raise FileFormatError(path, f"{name}: {text.strip()!r} is not a finite number", line)
    if sigma < 0:
        raise FileFormatError(path, f"{name}: uncertainty {sigma:g} is negative; expected sigma >= 0", line)
    return Quantity(value, sigma)


def parse_name_value_text(text: str, path: str = "<text>") -> NameValueFile:
    """Parse the text of a name-value file.

    Parameters
    ----------
    text : str
        The whole file.
    path : str
        Name used in messages.

    Raises
    ------
    FileFormatError
        A line that is not ``name = value[+/-sigma][, ...]``, a bad name, a number that cannot be
        read, a negative uncertainty or a name given twice; the message names the line, and every
        such line of the text at once (``N lines cannot be read:``, one line each).
    """
    lines = text.splitlines()
    every_line = _simple_text(lines)
    if every_line is not None:
        return NameValueFile(path, every_line)
    entries: dict[str, NameValueEntry] = {}
    problems: list[FileFormatError] = []
    simple = _SIMPLE_LINE.fullmatch
    isfinite = math.isfinite
    for number, raw in enumerate(lines, start=1):
        match = simple(raw)
        if match is not None:
            name, value_text, sigma_text = match.groups()
            try:
                value = float(value_text)
                sigma = 0.0 if sigma_text is None else float(sigma_text)
            except ValueError:
                value = sigma = math.nan  # not a number: the general path says so
            if name not in entries and sigma >= 0 and isfinite(value) and isfinite(sigma) and len(name) <= MAX_NAME:
                quantity = Quantity(value, sigma)
                entries[name] = NameValueEntry(name, quantity, (quantity,), number)
                continue
        try:
            entry = _parse_line(raw, number, path, entries)
        except FileFormatError as exc:
            problems.append(exc)
            continue
        if entry is not None:
            entries[entry.name] = entry
    if len(problems) == 1:
        raise problems[0]
    if problems:
        raise FileFormatError(path, f"{len(problems)} lines cannot be read:\n" + listing(problems))
    return NameValueFile(path, entries)


def _simple_text(lines: list[str]) -> dict[str, NameValueEntry] | None:
    """The entries of a text whose every line is the common ``name = value[+/-sigma]`` line,
    read by one regular expression over the whole text; ``None`` for any other text, and for
    any value the line path would question (then :func:`parse_name_value_text` reads it line by
    line, and says what is wrong)."""
    found = _SIMPLE_LINES.findall("\n".join(lines))
    if not found or len(found) != len(lines):  # a blank line, a comment, repeats, a line to complain about
        return None
    names, value_texts, sigma_texts = zip(*found)
    try:
        values = list(map(float, value_texts))
        sigmas = [float(text) if text else 0.0 for text in sigma_texts]
    except ValueError:
        return None
    # A finite sum has no term that is not finite (one that overflows goes line by line).
    if not (
        math.isfinite(sum(values))
        and math.isfinite(sum(sigmas))
        and min(sigmas) >= 0
        and max(map(len, names)) <= MAX_NAME
    ):
        return None
    # One Quantity and one entry a line, built by map (no Python loop); zip(quantities) gives each
    # line's repeats, the 1-tuple (quantity,).
    quantities = list(map(Quantity, values, sigmas))
    entries = dict(zip(names, map(NameValueEntry, names, quantities, zip(quantities), itertools.count(1))))
    return entries if len(entries) == len(found) else None  # a name given twice: line by line


def _parse_line(raw: str, number: int, path: str, entries: dict[str, NameValueEntry]) -> NameValueEntry | None:
    """The entry of one line that is not the common case (``None`` for a blank or comment line)."""
    content = raw.split("#", 1)[0].strip()
    if not content:
        return None
    if "=" not in content:
        raise FileFormatError(path, f"expected 'name = value+/-sigma', got {raw.strip()!r}", number)
    name, _, rhs = content.partition("=")
    name = name.strip()
    if len(name) > MAX_NAME:
        raise FileFormatError(
            path, f"a name of {len(name)} characters ({name[:20]!r}...): expected at most {MAX_NAME}", number
        )
    if not _NAME.match(name):
        raise FileFormatError(
            path, f"{name!r} is not a name (letters, digits and _, not starting with a digit)", number
        )
    if not rhs.strip():
        raise FileFormatError(path, f"{name}: no value after '='", number)
    if name in entries:
        raise FileFormatError(path, f"{name} is given twice (first on line {entries[name].line})", number)
    repeats = tuple(_parse_value(part, path, number, name) for part in rhs.split(","))
    try:
        mean = mean_of_repeats(repeats)
    except OverflowError:
        raise FileFormatError(path, f"{name}: repeated values too large to average", number) from None
    return NameValueEntry(name, mean, repeats, number)


def read_name_value_file(path: str | Path) -> NameValueFile:
    """Read a ``name = value+/-sigma`` file (UTF-8, an optional byte-order mark allowed), through
    :func:`bikerider.io.input_file.read_input_text` (a regular file of bounded size).

    Raises
    ------
    FileFormatError
        Not a regular file, too large, not UTF-8 text (the message gives the line of the first bad
        byte), a line that cannot be read (see :func:`parse_name_value_text`), or no entry at all.
    OSError
        The file cannot be opened.
    """
    text = read_input_text(path)
    if "\x00" in text:
        raise FileFormatError(
            path,
            "contains NUL bytes: a binary file, not a name = value text file",
            text.count("\n", 0, text.index("\x00")) + 1,
        )
    data = parse_name_value_text(text, str(path))
    if not data:  # an empty file never stands for "nothing to say"
        raise FileFormatError(path, "no 'name = value' entries: the file is empty or holds only comments")
    return data
