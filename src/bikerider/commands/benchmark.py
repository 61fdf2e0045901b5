"""``bikerider benchmark FILE``: the Whipple model from the 25 benchmark parameters."""
from __future__ import annotations

import argparse
import json


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "benchmark",
        help="matrices, critical speeds and eigenvalues from benchmark parameters",
        description=(
            "Read the 25 benchmark parameters (a TOML file with the Meijaard et al. 2007 names, or a "
            "BicycleParameters 'name = value+/-sigma' Benchmark.txt file) and print M, C1, K0, K2, the "
            "weave and capsize speeds and the eigenvalues against speed."
        ),
    )
    p.add_argument("file", metavar="FILE", help="benchmark parameter file (.toml or name = value+/-sigma text)")
    p.add_argument("--speeds", metavar="START:STOP:N", default="0:10:11",
                   help="speeds for the eigenvalues, m/s, N points (default 0:10:11)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.add_argument("--plot", metavar="DIR", help="write eigenvalues.png into DIR")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    # The pipeline (NumPy, the generated code) is imported when the command runs: `bikerider --help`
    # and the other commands start in 0.06 s instead of 0.4 s (python -X importtime).
    from bikerider import report
    from bikerider.benchmark import WhippleModel
    from bikerider.io.benchmark_file import load_benchmark_parameters

    speeds = report.parse_speeds(args.speeds)
    params = load_benchmark_parameters(args.file)
    model = WhippleModel.from_parameters(params)
    eig = model.eigenvalues(speeds)
    if args.plot:
        from bikerider import plotting  # matplotlib: only when figures are asked for

        plotting.write_figures(args.plot, model, eig, None, title=str(args.file))
    if args.json:
        print(json.dumps(report.model_json(params, model, eig), indent=2, allow_nan=False))
    else:
        print(f"Benchmark parameters from {args.file}\n")
        print(report.model_text(params, model, eig))
    return 0
