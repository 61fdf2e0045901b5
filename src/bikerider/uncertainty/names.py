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


def _toml_paths() -> dict[str, str]:
    """Every value of the bicycle and rider TOML files (``docs/input_format.md``), by its dotted
    path in the file, to the chain node it becomes (``*_deg`` keys: the node in radians)."""
    paths = {"environment.g": "g", "torsional_pendulum.k_t": "k_t", "rider.mass": "mBr"}
    for key in ("w", "c", "rR", "rF", "h_bb", "l_cs", "l_f", "w_fh", "l_hb", "w_rh", "l_sp", "l_st", "l_s"):
        paths[f"geometry.{key}"] = key
    paths["geometry.lam_ht_deg"], paths["geometry.lam_st_deg"] = "lam_ht", "lam_st"
    for section, w in (("rear_wheel", "R"), ("front_wheel", "F")):
        paths[f"{section}.mass"] = f"m{w}"
        paths[f"{section}.Ixx"] = f"I{w}xx"
        paths[f"{section}.Ixx.torsional_period"] = f"T_{w}xx"
        paths[f"{section}.Iyy"] = f"I{w}yy"
        paths[f"{section}.Iyy.compound_period"] = f"T_{w}yy"
        paths[f"{section}.Iyy.pendulum_length"] = f"l_p{w}"
    for section, b in (("rear_frame", "Bf"), ("handlebar_fork", "H")):
        paths[f"{section}.mass"] = f"m{b}"
        paths[f"{section}.com.x"], paths[f"{section}.com.z"] = f"x{b}", f"z{b}"
        for axes in ("xx", "xz", "zz", "yy"):
            paths[f"{section}.inertia.I{axes}"] = f"I{b}{axes}"
        for i in (1, 2, 3):
            paths[f"{section}.inertia.periods.{i}"] = f"T_{b}{i}"
            paths[f"{section}.inertia.alpha_deg.{i}"] = f"alpha_{b}{i}"
    for key in ("c_ch", "c_h", "l_hh", "c_la", "l_la", "c_ll", "l_ll", "l_ss", "l_to", "c_ua", "l_ua", "c_ul", "l_ul"):
        paths[f"measurements.{key}"] = key
    paths["measurements.lam_fl_deg"] = "lam_fl"
    for key, node in (("head", "f_h"), ("lower_arm", "f_la"), ("lower_leg", "f_ll"), ("torso", "f_to")):
        paths[f"mass_fractions.{key}"] = node
    paths["mass_fractions.upper_arm"], paths["mass_fractions.upper_leg"] = "f_ua", "f_ul"
    return paths


TOML_PATHS: dict[str, str] = _toml_paths()
"""Dotted key path in the project's TOML files -> chain node (``--wrt`` accepts either)."""


def input_name(name: str, inputs: set[str], known: set[str]) -> tuple[str, str | None]:
    """The chain node ``--wrt NAME`` means, and a note when it was translated.

    ``NAME`` may be a node (``lam_ht``, ``T_Fyy``), a key as the TOML files spell it
    (``lam_ht_deg``, ``compound_period``), or a dotted path to it, whole or in part
    (``front_wheel.compound_period``, ``rear_frame.inertia.periods.2``).  A key that names several
    of the run's inputs (``mass``) is an :class:`InputError` listing them.

    Parameters
    ----------
    name : str
    inputs : set of str
        The run's input nodes (a key is looked up among them).
    known : set of str
        Every node the chain knows (a node name is taken as it is).
    """
    node = canonical_name(name)
    if node in known:
        return node, None
    parts = name.split(".")
    matches = sorted(
        {n for path, n in TOML_PATHS.items() if _matches(parts, path.split(".")) and n in inputs},
        key=list(TOML_PATHS.values()).index,
    )
    if not matches and name.endswith("_deg") and name[: -len("_deg")] in inputs:
        matches = [name[: -len("_deg")]]
    if len(matches) > 1:
        shown = ", ".join(f"{_path_of(m)} ({m})" for m in matches)
        raise InputError("--wrt", name, f"one input; {name} names several: {shown}")
    if not matches:
        return check_name(name, known, "--wrt"), None
    node = matches[0]
    note = f"--wrt {name} is the input {node}" + (
        " (in radians; the files give it in degrees)" if "_deg" in name or "_deg" in _path_of(node) else ""
    )
    return node, note


def _matches(parts: list[str], path: list[str]) -> bool:
    """``parts`` names ``path``, or the list ``path`` is an entry of (``periods`` for ``periods.2``)."""
    return _in_order(parts, path) or (path[-1].isdigit() and _in_order(parts, path[:-1]))


def _in_order(parts: list[str], path: list[str]) -> bool:
    """Whether ``parts`` ends ``path`` and appears in it in order (``a.c`` matches ``a.b.c``)."""
    if not parts or parts[-1] != path[-1]:
        return False
    it = iter(path)
    return all(any(p == q for q in it) for p in parts)


def _path_of(node: str) -> str:
    return next((path for path, n in TOML_PATHS.items() if n == node), node)


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
        close = sorted(n for n in known if name and n.lower().startswith(name[:2].lower()))[:10]
        hint = f"; names starting alike: {', '.join(close)}" if close else ""
        raise InputError(
            what, name, f"a node of the estimate chain (e.g. weave_speed, capsize_speed, M_phidelta, xB{hint})"
        )
    return node
