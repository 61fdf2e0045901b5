"""``bikerider sweep`` on a design space: many parameters, random designs, raw measurements, a store.

The options here turn a sweep into a design-space run (:mod:`bikerider.design`): more than two
``--vary``, ``--random``/``--monte-carlo``, ``--measured``, ``--store``, ``--dask``,
``--weave-speeds``.  Without them ``bikerider sweep`` works as before (one parameter, or a map of
two, in memory).
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import sys
import time
from contextlib import contextmanager
from pathlib import Path

from bikerider import notes
from bikerider.commands import argument_types
from bikerider.commands.benchmark import load_parameters
from bikerider.commands.sweep_options import angle_name, cell, degree_names, in_degrees, parse_vary
from bikerider.errors import InputError
from bikerider.io.atomic import atomic_write_text
from bikerider.progress import format_duration

MAX_ROWS = 1_000_000
"""Designs a run without --store may print as rows."""


def add_design_options(p) -> None:
    """The design-space options of ``bikerider sweep``."""
    g = p.add_argument_group("design spaces (docs/design_space.md)")
    g.add_argument(
        "--measured",
        nargs="*",
        metavar="FILE",
        help="vary raw measurements through the whole estimate: a bicycle and a rider TOML file "
        "(none: the paper's); --vary then names inputs of the estimate chain (l_sp, mBf, ...)",
    )
    g.add_argument(
        "--random",
        type=int,
        metavar="N",
        help="N random designs instead of a grid; each --vary is NAME=LOW:HIGH (uniform) or NAME=MEAN+/-SIGMA (normal)",
    )
    g.add_argument(
        "--monte-carlo",
        type=int,
        metavar="N",
        help="N random designs, every base value with an uncertainty drawn normally (no --vary)",
    )
    g.add_argument("--seed", type=argument_types.seed, default=0, help="seed of the random designs (default 0)")
    g.add_argument(
        "--store",
        metavar="DIR",
        help="write the results chunk by chunk to a Zarr store in DIR and print a "
        "summary; an interrupted run given the same DIR resumes (needs bikerider[design])",
    )
    g.add_argument("--restart", action="store_true", help="with --store: discard what DIR holds and start again")
    g.add_argument(
        "--weave-speeds",
        metavar="START:STOP:N",
        help="speeds [m/s] at which to report the weave frequency and damping ratio",
    )
    g.add_argument("--chunk-size", type=int, metavar="N", help="designs per chunk (default 262144)")
    g.add_argument(
        "--engine",
        choices=("auto", "compiled", "numpy"),
        default="auto",
        help="fused C kernels (compiled at first use) or the NumPy reference (default: compiled where a "
        "C compiler is found)",
    )
    g.add_argument(
        "--threads",
        type=argument_types.whole_number(1, 4096),
        metavar="N",
        help="threads of the compiled engine (default: every core)",
    )
    g.add_argument(
        "--dask",
        nargs="?",
        const="local",
        metavar="ADDRESS",
        help="run on Dask: a LocalCluster on this machine, or the scheduler at ADDRESS (needs bikerider[distributed])",
    )
    g.add_argument(
        "--workers",
        type=argument_types.whole_number(1, 4096),
        metavar="N",
        help="with --dask: workers of the local cluster (default: cores)",
    )
    g.add_argument(
        "--target-weave-speed",
        type=argument_types.speed,
        metavar="V",
        help="also report the self-stable design whose weave speed is closest to V m/s",
    )
    g.add_argument(
        "--slice",
        metavar="X,Y",
        help="with --plot: the two parameters of the stability map "
        "(default the first two varied; the others at the value nearest the base)",
    )
    g.add_argument("--quiet", action="store_true", help="no progress bar on standard error")


def is_design_run(args: argparse.Namespace) -> bool:
    """Whether the options ask for a design-space run."""
    return bool(
        args.store
        or args.random is not None
        or args.monte_carlo is not None
        or args.measured is not None
        or args.dask
        or args.weave_speeds
        or (args.vary and len(args.vary) > 2)
    )


def parse_draw(text: str):
    """``NAME=LOW:HIGH`` or ``NAME=MEAN+/-SIGMA`` to ``(name, (distribution, a, b))`` (``_deg``: degrees)."""
    name, _, spec = text.partition("=")
    try:
        if "+/-" in spec:
            mean, sigma = (float(x) for x in spec.split("+/-"))
            draw = ("normal", mean, sigma)
        else:
            low, high = (float(x) for x in spec.split(":"))
            draw = ("uniform", low, high)
        if not name:
            raise ValueError
    except ValueError:
        raise InputError(
            "--vary", text, "NAME=LOW:HIGH (uniform) or NAME=MEAN+/-SIGMA (normal) with --random"
        ) from None
    if name.strip().endswith("_deg"):
        name = angle_name(name, text)
        draw = (draw[0], math.radians(draw[1]), math.radians(draw[2]))
    return name.strip(), draw


def _base(args: argparse.Namespace):
    """The base of the design space and its name."""
    if args.measured is None:
        return load_parameters(args)
    if args.file or args.bicycle:
        raise InputError(
            "--measured",
            args.file or args.bicycle,
            "no FILE or --bicycle with --measured (the measurements are the bicycle)",
        )
    if len(args.measured) not in (0, 2):
        raise InputError("--measured", args.measured, "a bicycle and a rider TOML file, or none for the paper's")
    from bikerider.estimate import estimate_from_files

    result = estimate_from_files(*(args.measured or (None, None)))
    return result, (" + ".join(args.measured) if args.measured else "paper's bicycle and rider")


def _space(args: argparse.Namespace, base, name: str):
    from bikerider import design

    if args.monte_carlo is not None:
        if args.vary or args.random is not None:
            raise InputError(
                "--monte-carlo",
                args.monte_carlo,
                "no --vary and no --random with it (it draws every value that has an uncertainty)",
            )
        return design.monte_carlo(base, args.monte_carlo, args.seed, name)
    if not args.vary:
        raise InputError("--vary", "missing", "at least one parameter to vary (or --monte-carlo N)")
    if args.random is not None:
        draws = [parse_draw(text) for text in args.vary]
        if len(dict(draws)) != len(draws):
            raise InputError("--vary", args.vary, "each parameter once")
        return design.random_designs(base, dict(draws), args.random, args.seed, name)
    axes = [parse_vary(text) for text in args.vary]
    if len(dict(axes)) != len(axes):
        raise InputError("--vary", args.vary, "each parameter once")
    return design.grid(base, dict(axes), name)


def run_design(args: argparse.Namespace) -> int:
    """Run a design space; print rows (small, in memory) or a summary (``--store``)."""
    import numpy as np

    from bikerider import design
    from bikerider.design import summary as summaries
    from bikerider.design.distribution import speed_distributions
    from bikerider.report import parse_speeds

    base, name = _base(args)
    space = _space(args, base, name)
    speeds = parse_speeds(args.speeds) if args.speeds else np.empty(0)
    weave_speeds = parse_speeds(args.weave_speeds, "--weave-speeds") if args.weave_speeds else np.empty(0)
    if args.rows == "speeds":
        raise InputError(
            "--rows",
            "speeds",
            "--rows designs with a design space (the stability at each speed is the store's 'stable' array)",
        )
    if args.store is None and space.size > MAX_ROWS:
        raise InputError(
            "--store", "missing", f"a folder for the results: {space.size:,} designs are more than {MAX_ROWS:,} rows"
        )
    if args.workers is not None and args.dask != "local":
        raise InputError("--workers", args.workers, "--dask without an address (a local cluster)")
    stages = Stages(args.quiet)
    store = None
    try:
        # the lock is kept until the store has been read back: a run started meanwhile with --restart would
        # otherwise remove its files under the summary (CI: KeyError 'upper' in one of three runs at once)
        store = design.explore(
            space,
            args.store,
            speeds,
            weave_speeds,
            chunk_size=args.chunk_size,
            engine=args.engine,
            threads=args.threads,
            restart=args.restart,
            quiet=args.quiet,
            scheduler=args.dask,
            workers=args.workers,
            keep_lock=True,
        )
        closest = None
        if args.target_weave_speed is not None:
            with stages.bar(
                f"finding the design whose weave speed is closest to {args.target_weave_speed:g} m/s", store
            ):
                closest = summaries.closest_to_weave_speed(store, args.target_weave_speed, progress=stages.update)
        summary = None
        if args.store is not None or args.plot:
            with stages.bar("summarising the store (self-stable fractions, sensitivity indices)", store):
                summary = summaries.summarize(store, progress=stages.update)
        if args.plot:
            _plots(args, store, name, summary, stages)
        sample = args.monte_carlo is not None or args.random is not None
        distributions = speed_distributions(store) if sample else None  # a sample: the speeds' distribution
        if args.plot and distributions is not None:
            _distribution_plot(args, distributions, f"{name}: {space.size:,} designs", stages)
        if args.store is None:
            text = _rows_text(args, store, closest, distributions)
        else:
            if args.json:
                out = {"store": str(args.store), "base": name, "kind": space.kind, **summary.as_dict()}
                if distributions is not None:
                    out["distribution"] = {k: d.as_dict() for k, d in distributions.items()}
                if args.target_weave_speed is not None:
                    out["closest_to_weave_speed"] = _closest_dict(closest, degree_names(args.vary))
                out["notes"] = notes.shown_with()
                text = json.dumps(out, indent=2, allow_nan=False) + "\n"
            else:
                text = _summary_text(store, summary, closest, args.target_weave_speed, degree_names(args.vary))
                if distributions is not None:
                    text += "\n" + "".join(d.text() + "\n" for d in distributions.values())
    except KeyboardInterrupt:
        stages.interrupted(args.store, space)
        raise
    finally:
        if store is not None:
            store.close()
    if args.out:
        atomic_write_text(args.out, text)
        stages.note(f"wrote {args.out}")
    else:
        print(text, end="")
    stages.note(f"sweep: done in {format_duration(time.monotonic() - stages.started)} (the whole command)")
    return 0


class Stages:
    """What a design run does after its progress bar, on stderr (nothing with ``--quiet``): a line
    per stage and a bar over each pass through the store, so no stage runs in silence; after Ctrl-C,
    how much of the run is stored and how to resume it."""

    def __init__(self, quiet: bool) -> None:
        self.quiet = quiet
        self.started = time.monotonic()
        self.progress = None

    def note(self, text: str) -> None:
        if not self.quiet:
            print(text, file=sys.stderr, flush=True)

    @contextmanager
    def bar(self, what: str, store):
        from bikerider.design.progress import Progress

        total = sum(stop - start for start, stop, _ in store.chunks())
        self.note(f"{what} ...")
        self.progress = Progress(total, quiet=self.quiet, label="designs read")
        try:
            yield self.progress
        finally:
            self.progress.close()
            self.progress = None

    def update(self, n: int) -> None:
        if self.progress is not None:
            self.progress.update(n)

    def interrupted(self, folder, space) -> None:
        """Say, on Ctrl-C, how many chunks the store holds and that the same command resumes."""
        if folder is None:
            print("\nbikerider sweep: interrupted; nothing kept (no --store)", file=sys.stderr, flush=True)
            return
        from bikerider.design import open_store

        try:
            store = open_store(folder)
        except (InputError, OSError, KeyError, ValueError):  # not made yet, or its attributes not written
            print(f"\nbikerider sweep: interrupted before {folder} held a chunk", file=sys.stderr, flush=True)
            return
        total = store.spec.n_chunks
        done = total - len(store.pending())
        if done < total:
            text = f"{done} of {total} chunks stored in {folder}: rerun the same command to resume"
        else:
            text = (
                f"all {total} chunks stored in {folder}: rerun the same command for the summary (nothing is recomputed)"
            )
        print(f"\nbikerider sweep: interrupted; {text}", file=sys.stderr, flush=True)


def _closest_dict(closest, degrees: frozenset[str] = frozenset()) -> dict | None:
    if closest is None:
        return None
    return {
        "index": closest.index,
        "values": in_degrees(dict(closest.values), degrees),
        "weave_speed": closest.weave_speed,
        "capsize_speed": closest.capsize_speed if math.isfinite(closest.capsize_speed) else None,
        "stable_intervals": [[lo, hi if math.isfinite(hi) else None] for lo, hi in closest.stable_intervals],
    }


def _summary_text(store, summary, closest, target, degrees: frozenset[str] = frozenset()) -> str:
    import numpy as np

    space = store.spec.space
    lo, hi = summary.speed_range
    lines = [
        f"{space.size:,} designs ({'grid ' + ' x '.join(map(str, space.shape)) if space.is_grid else 'random'}) "
        f"over {', '.join(space.names)} of {space.name or 'the base'} ({space.kind}); store {store.path}",
        f"valid: {summary.valid:,}; self-stable within {lo:g}-{hi:g} m/s: {summary.stable:,} "
        f"({summary.stable / max(summary.valid, 1):.1%} of the valid)",
    ]
    for text, count in sorted(summary.reasons.items(), key=lambda kv: -kv[1]):
        lines.append(f"  invalid, {count:,}: {text}")
    lines.append("")
    lines.append(f"{'parameter':<12} {'self-stable fraction (min - max)':<34} S(weave)  S(capsize)  S(width)")
    for p in summary.parameters:
        frac = p.stable_fraction
        span = f"{np.nanmin(frac):.3f} - {np.nanmax(frac):.3f}" if np.isfinite(frac).any() else "-"
        s = p.sensitivity
        lines.append(f"{p.name:<12} {span:<34} {s['weave_speed']:8.3f}  {s['capsize_speed']:10.3f}  {s['width']:8.3f}")
    if target is not None:
        lines.append("")
        if closest is None:
            lines.append(f"no self-stable design has a weave speed (target {target:g} m/s)")
        else:
            values = ", ".join(f"{k} = {v:.6g}" for k, v in in_degrees(dict(closest.values), degrees).items())
            lines.append(
                f"closest to a weave speed of {target:g} m/s: design {closest.index} ({values}): weave "
                f"{closest.weave_speed:.4f} m/s, capsize {closest.capsize_speed:.4f} m/s"
            )
    return "\n".join(lines) + "\n"


def _distribution_plot(args, distributions, title: str, stages: Stages) -> None:
    """``speed_distribution.<format>``: the histograms of the weave and capsize speeds."""
    from bikerider.plotting.common import save_figure
    from bikerider.plotting.distribution import speed_distribution_figure

    out = Path(args.plot)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"speed_distribution.{args.format}"
    stages.note(f"writing {path}")
    save_figure(speed_distribution_figure(distributions, title), path, args.format, args.dpi)


def _rows_text(args, store, closest, distributions=None) -> str:
    """Per-design rows (CSV or JSON) of a run held in memory."""
    import numpy as np

    n = store.spec.space.size
    values = store.varied_values(0, n)
    data = {
        name: store.read(name)
        for name in (
            "valid",
            "reason",
            "lower",
            "upper",
            "weave_speed",
            "capsize_speed",
            "weave_frequency",
            "weave_frequency_at",
            "weave_damping_at",
        )
    }
    reasons = store.reason_texts(data["reason"])
    rows = []
    for i in range(n):
        row: dict[str, object] = in_degrees({k: float(v[i]) for k, v in values.items()}, degree_names(args.vary))
        row["valid"] = bool(data["valid"][i])
        row["reason"] = reasons[i]
        for key in ("weave_speed", "capsize_speed", "weave_frequency"):
            x = float(data[key][i])
            row[key] = x if np.isfinite(x) else None
        row["stable_intervals"] = [
            [float(lo), float(hi) if np.isfinite(hi) else None]
            for lo, hi in zip(data["lower"][i], data["upper"][i])
            if np.isfinite(lo)
        ]
        for k, v in enumerate(store.spec.weave_speeds):
            for key, column in (("weave_frequency", "weave_frequency_at"), ("weave_damping_ratio", "weave_damping_at")):
                x = float(data[column][i, k])
                row[f"{key}@{v:g}"] = x if np.isfinite(x) else None
        rows.append(row)
    if args.json:
        out = {"base": store.spec.space.name, "kind": store.spec.space.kind, "designs": rows}
        if store.spec.speeds.size:
            out["speeds"] = store.spec.speeds.tolist()
            out["stable"] = store.stable().tolist()
        if distributions is not None:
            out["distribution"] = {k: d.as_dict() for k, d in distributions.items()}
        if args.target_weave_speed is not None:
            out["closest_to_weave_speed"] = _closest_dict(closest, degree_names(args.vary))
        out["notes"] = notes.shown_with()
        return json.dumps(out, indent=2, allow_nan=False) + "\n"
    buffer = io.StringIO()
    for row in rows:
        row["stable_intervals"] = ";".join(
            f"{cell(lo)}:{cell(hi if hi is not None else float('inf'))}" for lo, hi in row["stable_intervals"]
        )  # type: ignore[union-attr]
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows({k: cell(v) for k, v in row.items()} for row in rows)
    return buffer.getvalue()


def _plots(args, store, name: str, summary, stages: Stages) -> None:
    from bikerider.design import summary as summaries
    from bikerider.plotting import design as figures
    from bikerider.plotting.common import save_figure

    out = Path(args.plot)
    out.mkdir(parents=True, exist_ok=True)
    space = store.spec.space
    title = f"{name}: {space.size:,} designs"
    if space.is_grid and len(space.names) >= 2:
        if args.slice:
            x, _, y = args.slice.partition(",")
            if not y:
                raise InputError("--slice", args.slice, "two varied parameters X,Y")
        else:
            x, y = space.names[:2]
    elif args.slice:
        raise InputError("--slice", args.slice, "a grid over at least two parameters")
    else:
        x = y = ""
    path = out / f"stable_fraction.{args.format}"
    stages.note(f"writing {path}")
    save_figure(figures.stable_fraction_figure(summary, space.base, title), path, args.format, args.dpi)
    path = out / f"sensitivity.{args.format}"
    stages.note(f"writing {path}")
    save_figure(figures.interval_sensitivity_figure(summary, space.base, title), path, args.format, args.dpi)
    if x:
        stages.note(f"reading the slice over {x.strip()} and {y.strip()}")
        cut = summaries.design_slice(store, x.strip(), y.strip())
        path = out / f"map_{cut.x[0]}_{cut.y[0]}.{args.format}"
        stages.note(f"writing {path}")
        save_figure(
            figures.design_slice_figure(cut, store.spec.speeds, f"{name}: {cut.x[0]} and {cut.y[0]}"),
            path,
            args.format,
            args.dpi,
        )
