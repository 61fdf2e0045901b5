"""The ``bikerider`` command line.

Each subcommand lives in ``bikerider/commands/<name>.py`` with ``add_parser(subparsers)`` and
``run(args) -> int``.  Command modules import nothing heavy at module level, so ``--help`` and
start-up stay fast; they import NumPy, SciPy or matplotlib inside ``run``.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys

from bikerider import __version__, notes
from bikerider.errors import BikeriderError
from bikerider.io import output_guard

COMMANDS = ("estimate", "benchmark", "sweep", "convert", "period", "batch", "sensitivity", "gap", "serve")
"""Subcommand modules under ``bikerider.commands``, in the order ``--help`` lists them."""

INPUT_OPTIONS = ("file", "files", "bicycle", "rider", "inputs", "model", "data", "experiment", "control", "measured")
"""Argument destinations that name files a command reads: the run's inputs, which no output of the
run may overwrite (``bikerider.io.output_guard``; a command adds the files it finds in an input
folder itself).  A command whose ``--bicycle``/``--rider`` name shipped data lists them in its
``shipped_names`` default: those are names, not files."""

LOG = logging.getLogger("bikerider")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bikerider",
        description=(
            "Estimate the physical properties of a bicycle and its seated rider (Moore et al. 2009), "
            "the linear Whipple model they give (Meijaard et al. 2007), and where real bicycles "
            "depart from it."
        ),
    )
    parser.add_argument("--version", action="version", version=f"bikerider {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="log more (repeat for debug)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS:
        importlib.import_module(f"bikerider.commands.{name}").add_parser(sub)
    for command in sub.choices.values():  # -v also after the subcommand: `bikerider estimate -v`
        command.add_argument(
            "-v", "--verbose", action="count", default=0, dest="verbose_after", help="log more (repeat for debug)"
        )
    return parser


def input_paths(args: argparse.Namespace) -> list[str]:
    """The files named by the options of :data:`INPUT_OPTIONS` (single values or lists)."""
    out: list[str] = []
    shipped = getattr(args, "shipped_names", ())  # `--bicycle Browser` of benchmark and sweep: a name, not a file
    for dest in INPUT_OPTIONS:
        if dest in shipped:
            continue
        value = getattr(args, dest, None)
        values = value if isinstance(value, (list, tuple)) else [value]
        out.extend(os.fspath(v) for v in values if isinstance(v, (str, os.PathLike)) and os.fspath(v))
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit status (0 ok, 2 bad input or failed fit)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    level = logging.WARNING - 10 * min(args.verbose + getattr(args, "verbose_after", 0), 2)
    logging.basicConfig(level=level, format="bikerider: %(levelname)s: %(message)s")
    try:
        with output_guard.run_inputs(input_paths(args)), notes.collecting() as collection:
            code = int(args.run(args) or 0)
            # What the run left out of or changed in its inputs, unless an output showed it already.
            for message in collection.unshown():
                print(f"bikerider {args.command}: note: {message}", file=sys.stderr)
            return code
    except BikeriderError as exc:
        print(f"bikerider {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # The reader went away (``bikerider estimate | head``): not an error; silence the flush at exit.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:
        print(
            f"bikerider {args.command}: error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "),
            file=sys.stderr,
        )
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
