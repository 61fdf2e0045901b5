"""``bikerider period``: the period of a pendulum (or any damped oscillation) from rate-gyro records.

Each CSV file is one trial (columns time and angular rate, see ``docs/period.md``); the trials'
periods are combined into one value with an uncertainty that holds both the fits' standard errors
and the scatter between trials.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from bikerider import notes


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "period",
        help="fit damped oscillations to rate records and report the period",
        description="Fit y = offset + exp(-sigma t)(A sin(omega_d t) + B cos(omega_d t)) to each CSV "
        "(columns time and rate; see docs/period.md) and combine the trials' periods.",
    )
    parser.add_argument("files", nargs="+", type=Path, metavar="FILE.csv", help="one trial per file")
    parser.add_argument("--plot", metavar="PNG", help="write a plot of data and fits")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.add_argument("--drift", action="store_true", help="also fit a linear drift of the rate")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from bikerider.errors import FitError
    from bikerider.fitting.damped_oscillation import fit_damped_oscillation, period_from_trials
    from bikerider.io.output_guard import file_output, refuse_inputs
    from bikerider.io.signal_csv import read_signal_csv

    if args.plot is not None:
        refuse_inputs("--plot", args.plot, [file_output("--plot", str(args.plot))])
    records, fits = [], []
    for path in args.files:
        time, rate = read_signal_csv(path)
        try:
            fit = fit_damped_oscillation(time, rate, drift=args.drift)
        except FitError as exc:
            raise FitError(f"{path}: {exc}") from None
        records.append((path, time, rate))
        fits.append(fit)
    combined = period_from_trials(fits, names=[str(p) for p in args.files])
    if args.plot is not None:
        _plot(Path(args.plot), records, fits)
    if args.json:
        json.dump(
            {
                "period": combined.period,
                "sigma": combined.sigma,
                "scatter": combined.scatter,
                "trials": [{"file": str(p), **f.as_dict()} for (p, _, _), f in zip(records, fits)],
                "notes": notes.shown_with(),
            },
            sys.stdout,
            indent=2,
        )
        print()
        return 0
    for (path, _, _), fit in zip(records, fits):
        print(
            f"{path}: T = {fit.period:.6f} +/- {fit.period_se:.2g} s, zeta = {fit.zeta:.4g} +/- {fit.zeta_se:.2g}, "
            f"eigenvalues s = {fit.eigenvalue.real:.4g} +/- {fit.eigenvalue.imag:.5g}i 1/s, "
            f"residual rms = {fit.residual_rms:.3g} ({fit.n_samples} samples)"
        )
    print(
        f"period = {combined.period:.6f} +/- {combined.sigma:.2g} s "
        f"({combined.n_trials} trial{'s' if combined.n_trials > 1 else ''}, scatter {combined.scatter:.2g} s)"
    )
    return 0


def _plot(target: Path, records, fits) -> None:
    from bikerider.io.signal_csv import signal_unit
    from bikerider.plotting.common import save_figure
    from bikerider.plotting.period import period_figure

    units = {signal_unit(path) for path, _, _ in records}
    unit = units.pop() if len(units) == 1 else None  # one unit for every trial, or none claimed
    save_figure(period_figure(records, fits, unit), target, "png", 150)
