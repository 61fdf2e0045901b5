"""``bikerider benchmark FILE``: the Whipple model from the 25 benchmark parameters."""

from __future__ import annotations

import argparse
import json

from bikerider import notes
from bikerider.commands.estimate import (
    add_figure_options,
    add_uncertainty_options,
    check_figure_outputs,
    figure_title,
    print_notes,
)
from bikerider.errors import InputError
from bikerider.io.shipped_files import BICYCLES, RIDERS


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "benchmark",
        help="matrices, critical speeds and eigenvalues from benchmark parameters",
        description=(
            "Read the 25 benchmark parameters (a TOML file with the Meijaard et al. 2007 names, a "
            "BicycleParameters 'name = value+/-sigma' Benchmark.txt file, or a shipped bicycle with "
            "--bicycle NAME) and print M, C1, K0, K2, the weave and capsize speeds, the self-stable speed "
            "intervals and the eigenvalues against speed."
        ),
    )
    p.add_argument(
        "file",
        metavar="FILE",
        nargs="?",
        help="a bicycle file as estimate reads it: benchmark parameters (.toml, .json, a BicycleParameters "
        "<Name>Benchmark.txt, a gap model file) or raw measurements (.toml, <Name>Measured.txt: the bicycle "
        "alone); or --bicycle NAME",
    )
    add_shipped_options(p)
    p.add_argument(
        "--speeds",
        metavar="START:STOP:N",
        default="0:10:11",
        help="speeds for the eigenvalues, m/s, N points (default 0:10:11)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.add_argument(
        "--plot", metavar="DIR", help="write the figures eigenvalues, side_view, mode_shapes and bode into DIR"
    )
    add_figure_options(p)
    add_uncertainty_options(p)
    p.set_defaults(run=run)


def add_shipped_options(p) -> None:
    """``--bicycle NAME`` and ``--rider NAME``: a parameter set shipped with bikerider (also ``sweep``)."""
    p.add_argument(
        "--bicycle",
        metavar="NAME",
        help=f"a shipped bicycle instead of FILE: {', '.join(BICYCLES)} (BicycleParameters data)",
    )
    p.add_argument("--rider", metavar="NAME", help=f"with --bicycle: seat a shipped rider on it ({', '.join(RIDERS)})")
    # Their values are names of data shipped with bikerider, not files: never inputs an output could overwrite.
    p.set_defaults(shipped_names=("bicycle", "rider"))


def load_parameters(args: argparse.Namespace):
    """The parameters of FILE or of ``--bicycle``/``--rider``, and a name for titles."""
    if (args.file is None) == (args.bicycle is None):
        raise InputError("FILE / --bicycle", args.file or args.bicycle, "either a parameter file or --bicycle NAME")
    if args.rider is not None and args.bicycle is None:
        raise InputError("--rider", args.rider, "--bicycle NAME as well (a shipped rider on a shipped bicycle)")
    if args.bicycle is not None:
        from bikerider.shipped import named

        parameters = named(args.bicycle, args.rider)
        return parameters, parameters.source.split(" (")[0]
    from bikerider.benchmark import BenchmarkParameters  # heavy: imported when a command runs (cli.py)
    from bikerider.bicycle.to_benchmark import bicycle_benchmark_parameters
    from bikerider.io.bicycleparameters import load_bicycle_file

    bicycle = load_bicycle_file(args.file)  # the reader of estimate: every bicycle file it reads
    if isinstance(bicycle, BenchmarkParameters):
        return bicycle, str(args.file)
    notes.note(f"{args.file}: raw measurements reduced to the benchmark parameters of the bicycle alone (no rider)")
    return bicycle_benchmark_parameters(bicycle), str(args.file)


def run(args: argparse.Namespace) -> int:
    # The pipeline (NumPy, the generated code) is imported when the command runs: `bikerider --help`
    # and the other commands start in 0.06 s instead of 0.4 s (python -X importtime).
    from bikerider import report
    from bikerider.benchmark import WhippleModel
    from bikerider.uncertainty import benchmark_inputs, propagate
    from bikerider.uncertainty.headline import headline_uncertainty

    speeds = report.parse_speeds(args.speeds)
    check_figure_outputs(args)
    params, name = load_parameters(args)
    model = WhippleModel.from_parameters(params)
    eig = model.eigenvalues(speeds)
    # The sigmas the file states, propagated as `estimate` propagates them (Monte Carlo first).
    inputs = benchmark_inputs(params)
    uncertainty = propagate(inputs, speeds=speeds)
    headline = headline_uncertainty(inputs, uncertainty, samples=args.monte_carlo, seed=args.seed)
    if args.plot:
        import numpy as np

        from bikerider import plotting  # matplotlib: only when figures are asked for

        # The band of the eigenvalue figure: the file's sigmas, first order, on a fine speed grid
        # (as `estimate` draws it); none without sigmas, and none in the key.
        band = (
            propagate(inputs, speeds=np.linspace(speeds.min(), speeds.max(), 101)).eigenvalues
            if speeds.max() > speeds.min()
            else None
        )
        if band is not None and not (np.isfinite(band.sigma_real).any() and np.nanmax(band.sigma_real) > 0):
            band = None
        plotting.write_figures(
            args.plot,
            model,
            eig,
            None,
            title=name if args.file is None else figure_title(args.file),
            parameters=params,
            figures=plotting.FIGURES,
            fmt=args.format,
            dpi=args.dpi,
            uncertainty=band,
        )
    if args.json:
        out = report.model_json(params, model, eig)
        out["uncertainty"] = report.uncertainty_json(uncertainty, headline)
        out["notes"] = notes.shown_with()
        print(json.dumps(out, indent=2, allow_nan=False))
    else:
        print(f"Benchmark parameters from {params.source or name}\n")
        print(report.model_text(params, model, eig, headline.speeds, headline.samples))
        if args.plot:
            print(f"\nFigures written to {args.plot}/")
        print_notes("benchmark", [*uncertainty.notes, *headline.notes])
    return 0
