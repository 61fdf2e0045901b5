"""Names, units and LaTeX of the chain's nodes, and the aliases the command line accepts."""
from __future__ import annotations

import re

from bikerider.errors import InputError
from bikerider.generated.symbol_table import SYMBOLS

ALIASES = {
    "weave_speed": "v_weave", "weave": "v_weave",
    "capsize_speed": "v_capsize", "capsize": "v_capsize",
}
"""User-facing output names for the speed nodes."""

_RAW = {
    "T_Bf": ("rear frame torsional period, orientation {i}", "s", "T_{{Bf,{i}}}"),
    "alpha_Bf": ("rear frame pendulum axis angle, orientation {i}", "rad", r"\alpha_{{Bf,{i}}}"),
    "T_H": ("handlebar/fork torsional period, orientation {i}", "s", "T_{{H,{i}}}"),
    "alpha_H": ("handlebar/fork pendulum axis angle, orientation {i}", "rad", r"\alpha_{{H,{i}}}"),
}
_WHEEL = {
    "T_{w}xx": ("{wheel} wheel torsional period about a diameter", "s", "T_{{{w}xx}}"),
    "T_{w}yy": ("{wheel} wheel compound pendulum period", "s", "T_{{{w}yy}}"),
    "l_p{w}": ("{wheel} wheel compound pendulum length", "m", "l_{{p{w}}}"),
}


def _raw_table() -> dict[str, tuple[str, str, str]]:
    out: dict[str, tuple[str, str, str]] = {}
    for prefix, (desc, unit, latex) in _RAW.items():
        for i in (1, 2, 3):
            out[f"{prefix}{i}"] = (desc.format(i=i), unit, latex.format(i=i))
    for pattern, (desc, unit, latex) in _WHEEL.items():
        for w, wheel in (("R", "rear"), ("F", "front")):
            out[pattern.format(w=w)] = (desc.format(wheel=wheel), unit, latex.format(w=w))
    return out


TABLE: dict[str, tuple[str, str, str]] = {**SYMBOLS, **_raw_table()}
"""Node name -> (description, unit, LaTeX)."""


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
        raise InputError(what, name, f"a node of the estimate chain (e.g. weave_speed, capsize_speed, M_phidelta, xB{hint})")
    return node
