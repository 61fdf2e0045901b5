"""``bikerider gap``: where a bicycle's measurements depart from its model, and why."""

from __future__ import annotations

import argparse

from bikerider.commands import argument_types


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "gap",
        help="diagnose the sim-to-real gap: where measurements depart from the model and which effect explains it",
        description=(
            "Compare measured eigenvalues, perturbation runs or identified canonical matrices with the "
            "Whipple model of the bicycle: map the gap against the combined uncertainty of data and "
            "parameters, test whether plausible parameter errors explain it, rank candidate unmodelled "
            "effects (steer damping, inertia, stiffness, passive arms, rider lean, tyre slip) by their "
            "error on held-out groups of data, and report how much of the gap the selected effects remove. "
            "See docs/gap.md."
        ),
    )
    p.add_argument(
        "--model",
        metavar="FILE",
        required=True,
        help="benchmark parameters: a TOML file with the 25 benchmark names (values 'v +/- sigma'; "
        "optional [rider], [upper_body], [grips] tables) or a BicycleParameters <Name>Benchmark.txt",
    )
    p.add_argument(
        "--rider",
        metavar="FILE",
        help="BicycleParameters lumped rider (<Rider><Bike>Benchmark.txt) to add to the rear body",
    )
    p.add_argument(
        "--rider-rel-sigma",
        metavar="X",
        type=float,
        default=0.0,
        help="relative standard uncertainty to give the rider's values when its file has none (default 0)",
    )
    p.add_argument(
        "--data",
        metavar="FILE",
        nargs="+",
        required=True,
        help="data files (CSV): measured eigenvalues (speed, real, imag, ...), perturbation runs "
        "(time, roll_rate, ...) or identified canonical entries (rider, environment, coefficient, "
        "identified, sigma); the kind is detected from the header",
    )
    p.add_argument(
        "--control",
        metavar="FILE",
        help="TOML with the known control gains k_phi, k_phid, k_delta, k_deltad for rows that give none",
    )
    p.add_argument(
        "--speed", metavar="V", type=argument_types.speed, help="speed [m/s] of perturbation runs whose file gives none"
    )
    p.add_argument(
        "--groups",
        metavar="G1,G2",
        help="keep only these rider-environment groups of identified canonical entries (e.g. J-H,J-P)",
    )
    p.add_argument(
        "--effects",
        metavar="E1,E2",
        help="candidate effects (default: all of parameters, steer_damping, steer_inertia, steer_stiffness, "
        "passive_arms, rider_lean, tyre_slip)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.add_argument(
        "--report",
        metavar="DIR",
        help="write report.md and PNG figures into DIR (new, empty, or an earlier report's folder, which is "
        "replaced whole)",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    import json
    import math

    import numpy as np

    from bikerider.errors import InputError
    from bikerider.gap import data as gap_data
    from bikerider.gap.diagnosis import diagnose
    from bikerider.gap.effects import EFFECT_NAMES, effect
    from bikerider.gap.model_input import load_model
    from bikerider.gap.report import summary_text, write_report
    from bikerider.io.output_guard import ReportFolder, folder_output

    report_folder = ReportFolder(folder_output("--report", args.report)) if args.report is not None else None
    if report_folder is not None:
        report_folder.check()  # before the work: never over an input, never over files no report wrote
    if not (math.isfinite(args.rider_rel_sigma) and 0 <= args.rider_rel_sigma < 1):
        raise InputError("--rider-rel-sigma", args.rider_rel_sigma, "a relative uncertainty in [0, 1)")
    model = load_model(args.model, args.rider, rider_rel_sigma=args.rider_rel_sigma)
    gains = gap_data.read_control(args.control) if args.control else None
    groups = [g.strip() for g in args.groups.split(",")] if args.groups is not None else None
    eigen, canonical = [], []
    for path in args.data:
        kind = gap_data.detect_kind(path)
        if kind == "eigenvalues":
            eigen.append(gap_data.read_eigenvalues(path, gains))
        elif kind == "perturbation":
            eigen.append(gap_data.read_perturbation(path, args.speed, gains).eigenvalues)
        else:
            canonical.append(gap_data.read_canonical(path, groups))
    effects = EFFECT_NAMES
    if args.effects:
        effects = tuple(e.strip() for e in args.effects.split(","))
        for name in effects:
            effect(name)
    diagnosis = diagnose(
        model, gap_data.EigenvalueData.concatenate(eigen), gap_data.CanonicalData.concatenate(canonical), effects
    )
    result = diagnosis.as_dict()
    if report_folder is not None:
        with report_folder as staging:
            path = write_report(diagnosis, staging, title=f"Sim-to-real gap: {args.model}")
        result["report"] = str(report_folder.final(path))
    if args.json:
        print(json.dumps(_plain(result, np), indent=2, allow_nan=False))
    else:
        print(summary_text(result))
        if args.report:
            print(f"\nReport: {result['report']}")
    return 0


def _plain(value, np):
    """JSON-ready: NumPy scalars to Python, non-finite floats to None."""
    import math

    if isinstance(value, dict):
        return {str(k): _plain(v, np) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v, np) for v in value]
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value
