"""Names, units and LaTeX of the chain's nodes (the one symbol table), and the aliases the command line accepts."""

from __future__ import annotations

import re

from bikerider.errors import InputError
from bikerider.generated.symbol_table import SYMBOLS

ALIASES = {
    "weave_speed": "v_weave",
    "weave": "v_weave",
    "capsize_speed": "v_capsize",
    "capsize": "v_capsize",
}
"""User-facing output names for the speed nodes."""

TABLE: dict[str, tuple[str, str, str]] = SYMBOLS
"""Node name -> (description, unit, LaTeX): the symbol table of ``derive/symbols.py``."""


def canonical_name(name: str) -> str:
    """The node name of an output or input as the user may write it (aliases resolved)."""
    return ALIASES.get(name, name)


def describe(name: str) -> tuple[str, str, str]:
    """``(description, unit, latex)`` of a node; a readable fallback for unknown names."""
    if name in TABLE:
        return TABLE[name]
    return (name, "", re.sub(r"_(\w+)$", r"_{\1}", name))


def unit(name: str) -> str:
    return describe(name)[1]


def latex(name: str) -> str:
    return describe(name)[2]


def check_name(name: str, known: set[str], what: str) -> str:
    """Resolve an alias and check ``name`` is in ``known``; :class:`InputError` otherwise."""
    node = canonical_name(name)
    if node not in known:
        close = sorted(n for n in known if n.lower().startswith(name[:2].lower()))[:10]
        hint = f"; names starting alike: {', '.join(close)}" if close else ""
        raise InputError(
            what, name, f"a node of the estimate chain (e.g. weave_speed, capsize_speed, M_phidelta, xB{hint})"
        )
    return node
