"""``bikerider convert``: a parameter set written as a project TOML file, a BicycleParameters
``<Name>Benchmark.txt`` or JSON (each read back unchanged), or its eigenvalues as CSV."""

from __future__ import annotations

import argparse

from bikerider.commands.benchmark import add_shipped_options, load_parameters
from bikerider.errors import InputError
from bikerider.io.atomic import atomic_write_text

FORMATS = ("toml", "bicycleparameters", "json", "eigenvalues")


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "convert",
        help="write a parameter set as TOML, a BicycleParameters Benchmark.txt or JSON, or its eigenvalues as CSV",
        description=(
            "Read a bicycle (any file estimate reads: TOML, JSON, a BicycleParameters <Name>Benchmark.txt or "
            "<Name>Measured.txt, a gap model file; or a shipped --bicycle NAME [--rider NAME]) and write its 25 "
            "benchmark parameters and g, with their standard uncertainties: --to toml (the project's format), "
            "--to bicycleparameters (name = value+/-sigma lines, as BicycleParameters reads them; save it as "
            "<Name>Benchmark.txt), --to json.  Every value and uncertainty is written in full precision, so "
            "reading the file back gives the same numbers.  --to eigenvalues writes the eigenvalues at --speeds "
            "as CSV (one row per speed: the real and imaginary part of each mode, and the mode names)."
        ),
    )
    p.add_argument("file", metavar="FILE", nargs="?", help="the bicycle file (or --bicycle NAME)")
    add_shipped_options(p)
    p.add_argument("--to", choices=FORMATS, required=True, help="what to write")
    p.add_argument(
        "--name",
        metavar="NAME",
        help="the bicycle's name (--to toml: the name entry; --to bicycleparameters: checked to fit "
        "<NAME>Benchmark.txt; default: --bicycle's name, or Bicycle)",
    )
    p.add_argument(
        "--speeds", metavar="START:STOP:N", default="0:10:101", help="--to eigenvalues: speeds [m/s] (default 0:10:101)"
    )
    p.add_argument("--out", metavar="FILE", help="write to FILE instead of standard output")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from bikerider.io.export import (  # the model and NumPy: imported when the command runs (cli.py)
        eigenvalue_rows,
        parameters_to_benchmark_txt,
        parameters_to_json,
        parameters_to_toml,
        rows_to_csv,
    )
    from bikerider.io.output_guard import file_output, refuse_inputs

    if args.out is not None:
        refuse_inputs("--out", args.out, [file_output("--out", args.out)])
    params, source = load_parameters(args)
    name = args.name if args.name is not None else (args.bicycle or "Bicycle")
    if args.to == "toml":
        text = parameters_to_toml(params, name=name)
    elif args.to == "bicycleparameters":
        text = parameters_to_benchmark_txt(params, name)
    elif args.to == "json":
        text = parameters_to_json(params)
    else:
        from bikerider.benchmark import WhippleModel
        from bikerider.report import parse_speeds

        speeds = parse_speeds(args.speeds)
        if speeds.size == 0:
            raise InputError("--speeds", args.speeds, "at least one speed")
        text = rows_to_csv(eigenvalue_rows(WhippleModel.from_parameters(params).eigenvalues(speeds)))
    if args.out:
        atomic_write_text(args.out, text)
    else:
        print(text, end="")
    return 0
