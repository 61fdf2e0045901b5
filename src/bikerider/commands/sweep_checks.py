"""Checks of ``bikerider sweep``'s options that need no computation: run before any work.

* options that only act together with another (``--restart`` with ``--store``, ``--slice`` with
  ``--plot``) are refused alone, as the other such options are, never ignored;
* a value that can only be refused (``--target-weave-speed 0``) is refused before the run, not
  after it;
* ``--dask ADDRESS`` must be the address of a scheduler (``[PROTOCOL://]HOST:PORT``), checked
  before Dask is asked to connect;
* no output (``--out``, ``--plot``) may lie inside the ``--store`` folder, which the run writes
  (and ``--restart`` clears).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from bikerider.errors import InputError

DASK_PROTOCOLS = ("tcp", "tls", "ws", "wss", "inproc", "ucx")
"""Protocols of a Dask scheduler address (``dask.distributed``'s comm backends)."""
_ADDRESS = re.compile(
    r"^(?:(?P<protocol>[a-z]+)://)?(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+)(?::(?P<port>[0-9]{1,5}))?$"
)


def check_pairs(args: argparse.Namespace) -> None:
    """Refuse an option given without the option it works with."""
    if args.restart and args.store is None:
        raise InputError("--restart", "given", "--store DIR as well (--restart discards what the store holds)")
    if args.slice is not None and args.plot is None:
        raise InputError("--slice", args.slice, "--plot DIR as well (the slice is a figure)")
    target = args.target_weave_speed
    if target is not None and not target > 0:
        raise InputError("--target-weave-speed", target, "a positive speed [m/s] (a weave speed is above 0)")


def check_dask(value: str | None) -> None:
    """``--dask``: none, ``local`` or ``[PROTOCOL://]HOST:PORT``."""
    if value is None or value == "local":
        return
    match = _ADDRESS.match(value)
    protocol = match["protocol"] if match else None
    if (
        match is None
        or (protocol is not None and protocol not in DASK_PROTOCOLS)
        or (protocol != "inproc" and (match["port"] is None or not 0 < int(match["port"]) < 65536))
    ):
        raise InputError(
            "--dask",
            value,
            "the address of a Dask scheduler, [PROTOCOL://]HOST:PORT such as tcp://127.0.0.1:8786 (protocols "
            f"{', '.join(DASK_PROTOCOLS)}), or no value for a local cluster",
        )


def check_outside_store(args: argparse.Namespace) -> None:
    """Refuse ``--out`` and ``--plot`` inside the ``--store`` folder (the run's own output)."""
    if args.store is None:
        return
    try:
        store = Path(args.store).resolve()
    except (OSError, RuntimeError):
        return
    for option in ("out", "plot"):
        value = getattr(args, option)
        if value is None:
            continue
        try:
            target = Path(value).resolve()
        except (OSError, RuntimeError):
            continue
        if target == store or target.is_relative_to(store):
            raise InputError(
                f"--{option}",
                value,
                f"a path outside the --store folder {args.store} (the run writes the store, and --restart clears it)",
            )


def check_sweep_options(args: argparse.Namespace) -> None:
    """Every check of this module."""
    check_pairs(args)
    check_dask(args.dask)
    check_outside_store(args)


__all__ = ["DASK_PROTOCOLS", "check_dask", "check_outside_store", "check_pairs", "check_sweep_options"]
