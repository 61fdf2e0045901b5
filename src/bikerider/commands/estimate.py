"""``bikerider estimate``: the paper's whole method on a bicycle and rider (default: the paper's)."""
from __future__ import annotations

import argparse


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "estimate",
        help="estimate bicycle+rider benchmark parameters and the Whipple model",
        description=(
            "Run the method of Moore et al. (2009) on a bicycle and a seated rider and print the 25 "
            "benchmark parameters, the rider's mass, centre of mass and inertia, the matrices M, C1, "
            "K0, K2, the weave and capsize speeds and the eigenvalues against speed. Without files: "
            "the paper's 2008 Batavus Browser and 72 kg rider."
        ),
    )
    p.add_argument("--bicycle", metavar="FILE", help="bicycle file (project TOML); default: the paper's bicycle")
    p.add_argument("--rider", metavar="FILE", help="rider file (project TOML); default: the paper's rider")
    p.add_argument("--speeds", metavar="START:STOP:N", default="0:10:11",
                   help="speeds for the eigenvalues, m/s, N points (default 0:10:11)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.add_argument("--plot", metavar="DIR", help="write eigenvalues.png and side_view.png into DIR")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    import json

    import numpy as np

    from bikerider import report
    from bikerider.estimate import default_files, estimate
    from bikerider.io.toml_input import load_bicycle_toml, load_rider_toml

    default_bicycle, default_rider = default_files()
    speeds = report.parse_speeds(args.speeds)
    bicycle = load_bicycle_toml(args.bicycle or default_bicycle)
    rider = load_rider_toml(args.rider or default_rider)
    result = estimate(bicycle, rider)
    eig = result.model.eigenvalues(speeds)
    rm = result.rider_model
    if args.plot:
        from bikerider import plotting

        plotting.write_figures(args.plot, result.model, eig, rm.grid_points, title=f"{bicycle.name} + {rider.name}")
    if args.json:
        out = report.model_json(result.parameters, result.model, eig)
        out["rider"] = {
            "mass": rm.mass,
            "com": rm.com.tolist(),
            "inertia": rm.inertia.tolist(),
            "grid_points": {str(i + 1): p.tolist() for i, p in enumerate(rm.grid_points)},
        }
        out["notes"] = result.notes
        print(json.dumps(out, indent=2, allow_nan=False))
        return 0
    np.set_printoptions(precision=4, suppress=True)
    print(f"Bicycle: {bicycle.name} ({bicycle.source})")
    print(f"Rider:   {rider.name} ({rider.source})")
    print()
    print("Rider (Moore et al. 2009, Eqs. 8 and 14)")
    print(f"  mass {rm.mass:.3f} kg")
    print(f"  centre of mass [x, y, z] = [{rm.com[0]:.4f}, {rm.com[1]:.4f}, {rm.com[2]:.4f}] m")
    for i, row in enumerate(rm.inertia):
        label = "  inertia about it =" if i == 0 else "                    "
        print(f"{label} [{row[0]:9.4f} {row[1]:9.4f} {row[2]:9.4f}] kg m^2")
    print()
    print(report.model_text(result.parameters, result.model, eig))
    for note in result.notes:
        print(f"Note: {note}")
    if args.plot:
        print(f"\nFigures written to {args.plot}/eigenvalues.png and {args.plot}/side_view.png")
    return 0
