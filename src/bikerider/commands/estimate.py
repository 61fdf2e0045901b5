"""``bikerider estimate``: the paper's whole method on a bicycle and rider (default: the paper's)."""

from __future__ import annotations

import argparse
import json
import math
import sys
import tomllib
from dataclasses import replace
from pathlib import Path

from bikerider import notes


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "estimate",
        help="estimate bicycle+rider benchmark parameters and the Whipple model",
        description=(
            "Run the method of Moore et al. (2009) on a bicycle and a seated rider and print the 25 "
            "benchmark parameters, the rider's mass, centre of mass and inertia, the matrices M, C1, "
            "K0, K2, the weave and capsize speeds and the eigenvalues against speed, with sigmas (Monte "
            "Carlo for the speeds, first order beside). Without files: the paper's 2008 Batavus Browser and "
            "72 kg rider; --bicycle alone: that bicycle without a rider; --rider alone: that rider on the "
            "paper's bicycle."
        ),
    )
    p.add_argument(
        "--bicycle",
        metavar="FILE",
        help="bicycle: project TOML, or BicycleParameters <Name>Measured.txt (raw measurements) or "
        "<Name>Benchmark.txt; the format is detected. Default: the paper's bicycle",
    )
    rider = p.add_mutually_exclusive_group()
    rider.add_argument(
        "--rider",
        metavar="FILE",
        help="rider: project TOML (the paper's rider model, seated on the bicycle) or a "
        "BicycleParameters lumped rider <Rider><Bike>Benchmark.txt. Default: the paper's rider when no "
        "--bicycle is given; with --bicycle alone, no rider (a note says so)",
    )
    rider.add_argument("--no-rider", action="store_true", help="the bicycle alone")
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


def add_figure_options(p) -> None:
    """``--format`` and ``--dpi`` of the figures ``--plot`` writes (shared with ``benchmark``, ``sweep``)."""
    p.add_argument("--format", default="png", choices=("png", "pdf", "svg"), help="figure file format (default png)")
    p.add_argument("--dpi", type=float, default=None, help="resolution of PNG figures (default 200)")


def add_uncertainty_options(p) -> None:
    """``--monte-carlo N`` and ``--seed S`` of the reported sigmas (shared with ``benchmark``)."""
    from bikerider.commands import argument_types

    p.add_argument(
        "--monte-carlo",
        metavar="N",
        type=argument_types.report_samples,
        default=10_000,
        help="Monte Carlo samples behind the reported sigmas of the critical speeds (default 10000, "
        "about 0.05 s; at most 1000000; 0: first order only; first order is always printed beside)",
    )
    p.add_argument(
        "--seed",
        metavar="S",
        type=argument_types.seed,
        default=0,
        help="random seed of the Monte Carlo draw (default 0)",
    )


def check_figure_outputs(args: argparse.Namespace) -> None:
    """Refuse a ``--plot`` folder that is a file, or whose figures would overwrite an input (also
    ``benchmark``)."""
    if args.plot is not None:
        from bikerider.io.output_guard import folder_output, refuse_inputs
        from bikerider.plotting import FIGURES, figure_paths

        folder = folder_output("--plot", args.plot)
        refuse_inputs("--plot", args.plot, figure_paths(folder, FIGURES, args.format))


def figure_title(path: str) -> str:
    """A figure title for a parameter file: the ``name`` a TOML file gives (top level, ``[benchmark]``
    or ``[bicycle]``), else the file's name without the folders, suffix and BicycleParameters'
    ``Benchmark`` ending (``BrowserBenchmark.txt``: ``Browser``)."""
    file = Path(path)
    if file.suffix.lower() == ".toml":
        try:
            table = tomllib.loads(file.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
            table = {}  # the reader has accepted the file; a title is not worth an error
        for where in (table, table.get("benchmark"), table.get("bicycle")):
            if isinstance(where, dict) and isinstance(where.get("name"), str) and where["name"].strip():
                return where["name"].strip()
    stem = file.stem
    return stem[: -len("Benchmark")] if stem.endswith("Benchmark") and stem != "Benchmark" else stem


def files_to_use(args: argparse.Namespace) -> tuple[bool, list[str]]:
    """Whether to seat a rider, and notes on what was taken for files not given.

    Without files: the paper's bicycle and rider.  ``--bicycle`` alone: that bicycle alone (its
    rider is the user's to give; the paper's rider is not seated on it silently).  ``--rider``
    alone: that rider on the paper's bicycle.  Each choice made for the user is said in a note.
    """
    from bikerider.estimate import default_files

    default_bicycle, default_rider = default_files()
    if args.no_rider:
        return False, []
    if args.bicycle and not args.rider:
        return False, [
            f"no --rider given: the bicycle alone (--rider FILE seats a rider; the paper's is {default_rider})"
        ]
    if args.rider and not args.bicycle:
        return True, [f"no --bicycle given: the rider seated on the paper's bicycle ({default_bicycle})"]
    return True, []


def run(args: argparse.Namespace) -> int:
    # The pipeline (NumPy, the generated code) is imported when the command runs: `bikerider --help`
    # and the other commands start in 0.06 s instead of 0.4 s (python -X importtime).
    import numpy as np

    from bikerider import report
    from bikerider.estimate import estimate_from_files, estimate_headline_uncertainty, estimate_uncertainty

    speeds = report.parse_speeds(args.speeds)
    check_figure_outputs(args)
    with_rider, run_notes = files_to_use(args)
    result = estimate_from_files(args.bicycle, args.rider, with_rider=with_rider)
    uncertainty = estimate_uncertainty(result, speeds)
    headline = estimate_headline_uncertainty(result, uncertainty, samples=args.monte_carlo, seed=args.seed)
    sigmas = report.reported_sigmas(uncertainty, headline)
    parameters = replace(result.parameters, sigmas={**result.parameters.sigmas, **sigmas})
    run_notes += [*result.notes, *uncertainty.notes, *headline.notes]
    eig = result.model.eigenvalues(speeds)
    rm = result.rider_model
    bicycle_name = result.bicycle.name if result.bicycle is not None else str(args.bicycle)
    rider_name = result.rider.name if result.rider is not None else "no rider"
    if args.plot:
        from bikerider import plotting  # matplotlib: only when figures are asked for

        band = (
            estimate_uncertainty(result, np.linspace(speeds.min(), speeds.max(), 101)).eigenvalues
            if speeds.max() > speeds.min()
            else None
        )
        if band is not None and not np.isfinite(band.sigma_real).any():
            band = None  # no first-order sigmas (a straight limb): no band, and no band in the key
        plotting.write_figures(
            args.plot,
            result.model,
            eig,
            rm.grid_points if rm else None,
            title=_figure_title(result, args),
            parameters=result.parameters,
            figures=plotting.FIGURES,
            fmt=args.format,
            dpi=args.dpi,
            uncertainty=band,
        )
    if args.json:
        out = report.model_json(parameters, result.model, eig)
        out["uncertainty"] = report.uncertainty_json(uncertainty, headline)
        out["rider"] = _rider_json(result)
        out["notes"] = notes.shown_with(run_notes)
        print(json.dumps(out, indent=2, allow_nan=False))
        return 0
    np.set_printoptions(precision=4, suppress=True)
    print(f"Bicycle: {bicycle_name}" + (f" ({result.bicycle.source})" if result.bicycle is not None else ""))
    print(f"Rider:   {rider_name}" + (f" ({result.rider.source})" if result.rider is not None else ""))
    rider = _rider_json(result)
    if rider is not None:
        print()
        print("Rider (Moore et al. 2009, Eqs. 8 and 14)" if rm else "Rider (one rigid body)")
        print(f"  mass {rider['mass']:.3f} kg")
        com = rider["com"]
        print(f"  centre of mass [x, y, z] = [{com[0]:.4f}, {com[1]:.4f}, {com[2]:.4f}] m")
        for i, row in enumerate(rider["inertia"]):
            label = "  inertia about it =" if i == 0 else "                    "
            shown = " ".join("      n/a" if x is None else f"{x:9.4f}" for x in row)
            print(f"{label} [{shown}] kg m^2")
    print()
    print(report.model_text(parameters, result.model, eig, headline.speeds, headline.samples))
    print("  (first-order sigmas of these eigenvalues, with condition numbers: --json, uncertainty.eigenvalues)")
    if args.plot:
        print(f"\nFigures written to {args.plot}/")
    print_notes("estimate", run_notes)
    return 0


def print_notes(command: str, run_notes: list[str]) -> None:
    """The notes of a text run on stderr, each once, as ``bikerider COMMAND: note: ...`` (the results
    stay alone on stdout; ``--json`` lists them under ``notes`` instead); also ``benchmark``."""
    for note in notes.shown_with(run_notes):
        print(f"bikerider {command}: note: {note}", file=sys.stderr)


def _figure_title(result, args: argparse.Namespace) -> str:
    """The figures' title: the bicycle's name (a file's name when it names none, not its path) and
    the rider's, if any."""
    bicycle = result.bicycle.name if result.bicycle is not None else figure_title(str(args.bicycle))
    return f"{bicycle} + {result.rider.name}" if result.rider is not None else bicycle


def _rider_json(result) -> dict | None:
    """The ``rider`` object of ``--json``: the rider model, a lumped rider, or None."""
    rm = result.rider_model
    if rm is not None:
        points = {
            str(i + 1): (p.tolist() if all(math.isfinite(x) for x in p) else None) for i, p in enumerate(rm.grid_points)
        }
        return {"mass": rm.mass, "com": rm.com.tolist(), "inertia": rm.inertia.tolist(), "grid_points": points}
    if result.rider is None:
        return None
    v = result.rider.values
    yy = v["IBryy"].value if "IBryy" in v else None
    return {
        "mass": v["mBr"].value,
        "com": [v["xBr"].value, 0.0, v["zBr"].value],
        "inertia": [
            [v["IBrxx"].value, 0.0, v["IBrxz"].value],
            [0.0, yy, 0.0],
            [v["IBrxz"].value, 0.0, v["IBrzz"].value],
        ],
        "grid_points": None,
    }
