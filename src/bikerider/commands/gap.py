"""``bikerider gap``: where a bicycle's measurements depart from its model, and why."""

from __future__ import annotations

import argparse

from bikerider.commands import argument_types

DEFAULT_REPEATS = 10
"""Runs per planned experiment of ``--next`` without ``--next-repeats``."""


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "gap",
        help="diagnose the sim-to-real gap: where measurements depart from the model and which effect explains it",
        description=(
            "Compare measured eigenvalues, raw free-decay records (cut from an experiment's logs by a manifest), "
            "perturbation runs or identified canonical matrices with the Whipple model of the bicycle under the "
            "known control laws: map the gap against the combined uncertainty of data and parameters, test "
            "whether plausible parameter errors explain it, rank candidate unmodelled effects (steer damping, "
            "inertia, stiffness, friction, passive arms, rider lean, tyre slip, speed sensor) and pairs of them "
            "by their error on held-out groups of data, select by that error and each parameter's literature "
            "prior together (values outside their usual range flagged), and report how much of the gap the "
            "selected effects remove. See docs/gap.md."
        ),
    )
    p.add_argument(
        "--model",
        metavar="FILE",
        required=True,
        help="benchmark parameters: a TOML file with the 25 benchmark names (values 'v +/- sigma'; "
        "optional [rider], [upper_body], [grips], [plausible] tables) or a BicycleParameters "
        "<Name>Benchmark.txt",
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
        default=[],
        help="data files (CSV): measured eigenvalues (speed, real, imag, ...), perturbation runs "
        "(time, roll_rate, ...) or identified canonical entries (rider, environment, coefficient, "
        "identified, sigma); the kind is detected from the header",
    )
    p.add_argument(
        "--experiment",
        metavar="FILE",
        nargs="+",
        default=[],
        help="manifests of raw records: a TOML file (logs, column map, sampling rate, windows or "
        "detection, speed source, groups, control laws; steer-torque multisine runs under [multisine]) "
        "or a CSV of windows (file, start, end [, group, control, speed]) with --columns and --sample-rate",
    )
    p.add_argument(
        "--columns",
        metavar="MAP",
        help="for a CSV manifest: the logs' columns, e.g. roll_rate=lean_rate,steer_angle=fork_angle,speed=speed",
    )
    p.add_argument(
        "--sample-rate",
        metavar="HZ",
        type=float,
        help="for a CSV manifest whose logs have no time column: samples per second",
    )
    p.add_argument(
        "--control",
        metavar="FILE",
        help="TOML with the known control: [control] constant gains k_phi, k_phid, k_delta, k_deltad, or "
        "named laws [control.<name>] whose gains may change with speed; acts where the data name none",
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
        "passive_arms, rider_lean, tyre_slip, speed_sensor, steer_friction)",
    )
    p.add_argument(
        "--next",
        action="store_true",
        help="plan the next experiment: new free decays (speed, control law, signal, push) or steer-torque "
        "multisines (speed, control law, the response read), ranked by the probability that the new runs tell "
        "apart the candidates the diagnosis left tied (or the first and the runners-up), favouring the true one "
        "19 to 1; and the next single run to record before planning again (where the candidates' predictions of "
        "one run overlap least: Jensen-Renyi, the closed loop's best criterion) (docs/gap.md)",
    )
    p.add_argument(
        "--next-between",
        metavar="E1,E2",
        help="with --next: the candidates to tell apart (pairs as a+b), instead of the tied ones",
    )
    p.add_argument(
        "--next-repeats",
        metavar="N",
        type=int,
        default=None,
        help="with --next: runs (decays or multisines) per experiment the plan is ranked for (default 10)",
    )
    p.add_argument(
        "--next-speeds",
        metavar="LO:HI[:N]",
        help="with --next: the speeds to consider [m/s] (default 12 from 0.6 times the slowest to 1.25 times "
        "the fastest speed of the data)",
    )
    p.add_argument(
        "--next-noise",
        metavar="SIGNAL=SD",
        help="with --next: sample noise of signals, e.g. steer_rate=0.02,steer_angle=0.0005 (rad, rad/s; "
        "default: from the records, the larger of their sample scatter and their fits' residual, or assumed "
        "for a signal they do not hold)",
    )
    p.add_argument(
        "--next-torque",
        metavar="NM",
        type=float,
        default=None,
        help="with --next: peak steer torque of a planned multisine run [N m] (default 0.5; runs a candidate "
        "predicts to lean past 0.2 rad are left out as likely lost)",
    )
    p.add_argument(
        "--next-run-time",
        metavar="S",
        type=float,
        default=None,
        help="with --next: recorded length of one multisine run [s] (default 10)",
    )
    p.add_argument(
        "--next-no-sweeps",
        action="store_true",
        help="with --next: plan free decays only (no steer-torque multisines)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.add_argument(
        "--quiet",
        action="store_true",
        help="no progress on standard error (by default long work shows its stage, count, rate and time left)",
    )
    p.add_argument(
        "--report",
        metavar="DIR",
        help="write report.md and PNG figures into DIR (new, empty, or an earlier report's folder, which is "
        "replaced whole)",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    # heavy (NumPy, the gap): imported when the command runs, so `bikerider --help` starts fast (cli.py)
    import json
    import math
    import sys

    import numpy as np

    from bikerider import diagnose as pipeline
    from bikerider import notes, progress
    from bikerider.errors import InputError
    from bikerider.gap.measured.control import MAX_MAGNITUDE
    from bikerider.gap.text import next_text, summary_text
    from bikerider.io.experiment import check_sample_rate
    from bikerider.io.output_guard import ReportFolder, folder_output

    report_folder = ReportFolder(folder_output("--report", args.report)) if args.report is not None else None
    if report_folder is not None:
        report_folder.check()  # before the work: never over an input, never over files no report wrote
    if not (math.isfinite(args.rider_rel_sigma) and 0 <= args.rider_rel_sigma < 1):
        raise InputError("--rider-rel-sigma", args.rider_rel_sigma, "a relative uncertainty in [0, 1)")
    if not args.data and not args.experiment:
        raise InputError(
            "--data/--experiment", "missing", "data files (--data) or a manifest of records (--experiment)"
        )
    if args.sample_rate is not None:
        check_sample_rate(args.sample_rate, "--sample-rate")
    if args.speed is not None and not (0 < args.speed <= MAX_MAGNITUDE):  # also NaN
        raise InputError("--speed", args.speed, f"a positive speed of at most {MAX_MAGNITUDE:g} m/s (check the units)")
    plan_options = _next_options(args)  # checked before the work, as every option
    if report_folder is not None and args.experiment:
        _register_experiment_inputs(args)  # the logs and windows files the manifests name
        report_folder.check()
    reporter = None
    try:
        with progress.reporting(quiet=getattr(args, "quiet", False), name="bikerider gap") as reporter:
            diagnosis = pipeline.run_diagnosis(
                args.model,
                tuple(args.data),
                tuple(args.experiment),
                args.rider,
                args.rider_rel_sigma,
                args.control,
                args.speed,
                args.groups,
                args.effects,
                args.columns,
                args.sample_rate,
            )
            result = diagnosis.as_dict()
            plan = None
            if plan_options is not None:
                plan, why = pipeline.plan_or_reason(diagnosis, plan_options)
                result["next"] = plan.as_dict() if plan is not None else {"planned": False, "reason": why}
            if report_folder is not None:
                progress.begin("writing the report")
                with report_folder as staging:
                    path = pipeline.write_report(diagnosis, staging, title=f"Sim-to-real gap: {args.model}", plan=plan)
                result["report"] = str(report_folder.final(path))
            reporter.finish()
    except KeyboardInterrupt:
        where = reporter.where() if reporter is not None else None
        print(
            ("\n" if reporter is not None and reporter.tty and (reporter.bar or reporter.transient) else "")
            + "bikerider gap: interrupted"
            + (f" during {where}" if where else "")
            + ": nothing was kept (no report written, no file changed; the diagnosis is only printed at the end)",
            file=sys.stderr,
        )
        return 130
    if args.json:
        result["notes"] = notes.shown_with(result.get("notes", []))
        print(json.dumps(_plain(result, np), indent=2, allow_nan=False))
    else:
        print(summary_text(result))
        if "next" in result:
            print()
            if plan is not None:
                print(next_text(result["next"]))
            else:
                print(f"What to measure next: no experiment can be planned: {result['next']['reason']}")
        if args.report:
            print(f"\nReport: {result['report']}")
    return 0


def _register_experiment_inputs(args: argparse.Namespace) -> None:
    """Add the files the manifests name (windows files, logs) to the run's inputs, so that no report
    folder that holds one of them is replaced (the manifests are read again by the diagnosis: a
    few kB, milliseconds)."""
    # heavy (NumPy, the gap): imported when the command runs, so `bikerider --help` starts fast (cli.py)
    from bikerider.io import gap_data
    from bikerider.io.experiment import experiment_files, read_experiment
    from bikerider.io.multisine import multisine_files
    from bikerider.io.output_guard import add_inputs

    laws = gap_data.read_control(args.control) if args.control is not None else {}
    for path in args.experiment:
        add_inputs(experiment_files(*read_experiment(path, args.columns, args.sample_rate, laws)))
        add_inputs(multisine_files(path))  # the logs of the manifest's multisine runs


def _next_options(args: argparse.Namespace) -> dict | None:
    """The arguments of :func:`~bikerider.gap.plan.ranking.plan_next` the ``--next`` options give,
    checked before the diagnosis (``None`` without ``--next``)."""
    # heavy (NumPy, the gap): imported when the command runs, so `bikerider --help` starts fast (cli.py)
    import math

    import numpy as np

    from bikerider.errors import InputError

    if not args.next:
        for option in (
            "next_between",
            "next_repeats",
            "next_speeds",
            "next_noise",
            "next_torque",
            "next_run_time",
            "next_no_sweeps",
        ):
            if getattr(args, option) not in (None, False):
                raise InputError("--" + option.replace("_", "-"), getattr(args, option), "--next as well")
        return None
    # heavy (NumPy, the gap): imported when the command runs, so `bikerider --help` starts fast (cli.py)
    from bikerider.gap.measured.control import MAX_MAGNITUDE
    from bikerider.gap.measured.records import SIGNALS
    from bikerider.gap.plan.ranking import MAX_NOISE
    from bikerider.gap.plan.sweeps import DEFAULT_RUN_TIME, DEFAULT_TORQUE, MAX_TORQUE, MIN_TORQUE, RUN_TIME_RANGE

    torque = DEFAULT_TORQUE if args.next_torque is None else args.next_torque
    if not MIN_TORQUE <= torque <= MAX_TORQUE:  # also NaN
        raise InputError("--next-torque", torque, f"a peak steer torque from {MIN_TORQUE:g} to {MAX_TORQUE:g} N m")
    run_time = DEFAULT_RUN_TIME if args.next_run_time is None else args.next_run_time
    if not RUN_TIME_RANGE[0] <= run_time <= RUN_TIME_RANGE[1]:
        raise InputError(
            "--next-run-time", run_time, f"a recorded run length from {RUN_TIME_RANGE[0]:g} to {RUN_TIME_RANGE[1]:g} s"
        )

    speeds = None
    if args.next_speeds:
        parts = args.next_speeds.split(":")
        try:
            numbers = [float(x) for x in parts]
        except ValueError:
            numbers = []
        if (
            len(numbers) not in (2, 3)
            or not all(map(math.isfinite, numbers))
            or not 0 < numbers[0] < numbers[1] <= MAX_MAGNITUDE
        ):
            raise InputError(
                "--next-speeds", args.next_speeds, f"LO:HI or LO:HI:N with 0 < LO < HI <= {MAX_MAGNITUDE:g} [m/s]"
            )
        count = int(numbers[2]) if len(numbers) == 3 else 12
        if len(numbers) == 3 and (count != numbers[2] or not 2 <= count <= 100):
            raise InputError("--next-speeds", args.next_speeds, "a whole number of speeds N from 2 to 100")
        speeds = np.linspace(numbers[0], numbers[1], count)
    noise = {}
    for item in (args.next_noise or "").split(","):
        if not item.strip():
            continue
        name, _, value = item.partition("=")
        if name.strip() not in SIGNALS:  # before the diagnosis: a typo must not cost one
            raise InputError(
                "--next-noise", item, "noise signal = '" + name.strip() + "': one of " + ", ".join(SIGNALS)
            )
        try:
            noise[name.strip()] = float(value)
        except ValueError:
            raise InputError("--next-noise", item, "SIGNAL=SD, e.g. steer_rate=0.02") from None
        if not 0 < noise[name.strip()] <= MAX_NOISE:  # also NaN
            raise InputError(
                "--next-noise", item, f"a positive standard deviation of at most {MAX_NOISE:g} (rad or rad/s)"
            )
    rivals = [r.strip() for r in args.next_between.split(",")] if args.next_between else None
    repeats = DEFAULT_REPEATS if args.next_repeats is None else args.next_repeats
    return {
        "rivals": rivals,
        "speeds": speeds,
        "repeats": repeats,
        "noise": noise or None,
        "sweeps": not args.next_no_sweeps,
        "torque": torque,
        "run_time": run_time,
    }


def _plain(value, np):
    """JSON-ready: NumPy scalars to Python, non-finite floats to None."""
    # heavy (NumPy, the gap): imported when the command runs, so `bikerider --help` starts fast (cli.py)
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
