"""``bikerider sweep``: stable speed intervals (and eigenvalues) against one or two benchmark parameters."""

from __future__ import annotations

import argparse
import csv
import io
import json
from pathlib import Path

from bikerider import notes
from bikerider.commands.benchmark import add_shipped_options, load_parameters
from bikerider.commands.estimate import add_figure_options
from bikerider.commands.sweep_checks import check_sweep_options
from bikerider.commands.sweep_design import add_design_options, is_design_run, run_design
from bikerider.commands.sweep_options import cell, degree_names, in_degrees, parse_vary, to_degrees
from bikerider.errors import InputError
from bikerider.io.atomic import atomic_write_text

ROWS = ("designs", "speeds")


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "sweep",
        help="stable speeds and eigenvalues against one benchmark parameter, a stability map over two, or a design "
        "space over many",
        description=(
            "Vary one or two of the 25 benchmark parameters of a base bicycle (a parameter file or a "
            "shipped bicycle) over a range and report, for every design, the self-stable speed intervals, "
            "the weave and capsize speeds and the weave frequency (from the characteristic polynomial, "
            "no speed scan), and optionally stability and eigenvalues at given speeds. Designs no bicycle "
            "can have are reported as invalid with the reason. Output: CSV (default) or JSON. With more "
            "parameters, random designs, raw measurements or --store it runs a design space of any size "
            "(chunked, resumable, fused kernels or Dask; docs/design_space.md)."
        ),
    )
    p.add_argument("file", metavar="FILE", nargs="?", help="base benchmark parameter file (or --bicycle NAME)")
    add_shipped_options(p)
    p.add_argument(
        "--vary",
        metavar="NAME=START:STOP:N",
        action="append",
        help="a benchmark parameter and its range, SI units (NAME_deg for an angle in degrees, e.g. "
        "lam_deg=0:30:61); give --vary twice for a stability map, more often for a design space "
        "(with --random: NAME=LOW:HIGH or NAME=MEAN+/-SIGMA)",
    )
    p.add_argument(
        "--speeds",
        metavar="START:STOP:N",
        help="speeds [m/s] at which to report stability (and with --rows speeds, eigenvalues)",
    )
    p.add_argument(
        "--rows",
        choices=ROWS,
        default="designs",
        help="one row per design (default), or per design and speed (needs --speeds)",
    )
    p.add_argument(
        "--control",
        metavar="FILE",
        help="every design under a control law on the steer torque (a TOML file as gap --control reads: "
        "[control] constant gains k_phi, k_phid, k_delta, k_deltad, or one named law [control.<name>]): "
        "closed-loop stable intervals and eigenvalues (docs/dynamics.md)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object instead of CSV")
    p.add_argument("--out", metavar="FILE", help="write the CSV or JSON to FILE instead of standard output")
    p.add_argument(
        "--plot",
        metavar="DIR",
        help="write sweep.<format>: stable speeds against the parameter, or the map "
        "(with --store: stable_fraction, sensitivity and map_<x>_<y>)",
    )
    add_figure_options(p)
    add_design_options(p)
    p.set_defaults(run=run)


def check_outputs(args: argparse.Namespace) -> None:
    """Refuse ``--out``, ``--plot`` and ``--store`` paths that would overwrite or remove an input."""
    from bikerider.io.output_guard import file_output, folder_output, refuse_inputs, refuse_inputs_within

    check_sweep_options(args)
    if args.out is not None:
        refuse_inputs("--out", args.out, [file_output("--out", args.out)])
    if args.plot is not None:
        # The figures' names depend on the run (sweep, stable_fraction, sensitivity, map_X_Y): any file
        # of the figure format in the folder may be written.
        folder = folder_output("--plot", args.plot)
        refuse_inputs("--plot", args.plot, folder.glob(f"*.{args.format}") if folder.is_dir() else ())
    if args.store is not None:
        folder_output("--store", args.store)
        refuse_inputs_within("--store", args.store)


def _control_law(path: str):
    """The one control law of a control file (``gap --control``'s format)."""
    from bikerider.io.gap_data import read_control

    laws = read_control(path)
    if len(laws) != 1:
        raise InputError("--control", path, f"a file with one control law (it has {len(laws)}: {', '.join(laws)})")
    return next(iter(laws.values()))


def run(args: argparse.Namespace) -> int:
    import numpy as np  # heavy modules: imported when the command runs (cli.py)

    from bikerider.benchmark.sweep import sweep
    from bikerider.report import parse_speeds

    check_outputs(args)
    if is_design_run(args):
        if args.control is not None:
            raise InputError(
                "--control",
                args.control,
                "a sweep over one or two parameters without --store, --random or --monte-carlo "
                "(design-space runs are open loop)",
            )
        return run_design(args)
    base, name = load_parameters(args)
    if not args.vary:
        raise InputError("--vary", "missing", "NAME=START:STOP:N, at least one parameter to vary")
    if len(args.vary) > 2:
        raise InputError("--vary", args.vary, "one parameter (a sweep) or two (a stability map)")
    axes = dict(parse_vary(text) for text in args.vary)
    if len(axes) != len(args.vary):
        raise InputError("--vary", args.vary, "two different parameters")
    speeds = parse_speeds(args.speeds) if args.speeds else np.empty(0)
    if args.rows == "speeds" and not speeds.size:
        raise InputError("--rows", "speeds", "--speeds START:STOP:N as well")
    law = _control_law(args.control) if args.control is not None else None
    result = sweep(base, axes, speeds, eigenvalues=args.rows == "speeds", law=law)
    if args.plot:
        from bikerider import plotting  # matplotlib: only when figures are asked for

        what = " and ".join(result.names) + (f" under {law.name}" if law is not None else "")
        Path(args.plot).mkdir(parents=True, exist_ok=True)  # as estimate's --plot: created when missing
        plotting.save_figure(
            plotting.sweep_figure(result, f"{name}: {what}"),
            Path(args.plot) / f"sweep.{args.format}",
            args.format,
            args.dpi,
        )
    degrees = degree_names(args.vary)  # degrees in, degrees out
    if args.json:
        out = {
            "base": name,
            "parameters": {
                (f"{n}_deg" if n in degrees else n): [to_degrees(x) if n in degrees else x for x in v.tolist()]
                for n, v in zip(result.names, result.values)
            },
            "speeds": speeds.tolist(),
            "designs": [in_degrees(row, degrees) for row in result.design_rows()],
        }
        if law is not None:
            out["control"] = {"name": law.name, "law": law.describe()}
        if speeds.size:
            out["stable"] = result.stable().tolist()
        if args.rows == "speeds":
            out["speed_rows"] = [in_degrees(row, degrees) for row in result.speed_rows()]
        out["notes"] = notes.shown_with()
        text = json.dumps(out, indent=2, allow_nan=False) + "\n"
    else:
        buffer = io.StringIO()
        rows = [
            in_degrees(r, degrees) for r in (result.design_rows() if args.rows == "designs" else result.speed_rows())
        ]
        for row in rows:
            if "stable_intervals" in row:
                row["stable_intervals"] = ";".join(
                    f"{cell(i['lower'])}:{cell(i['upper'])}" for i in row["stable_intervals"]
                )  # type: ignore[union-attr]
        writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
        writer.writeheader()
        writer.writerows({k: cell(v) for k, v in row.items()} for row in rows)
        text = buffer.getvalue()
    if args.out:
        atomic_write_text(args.out, text)
    else:
        print(text, end="")
    return 0
