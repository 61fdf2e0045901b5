"""Item 4: one bicycle from raw measurements and a rider to the benchmark parameters.

The same data for both tools: BicycleParameters' ``bicycles/Browser/RawData/BrowserMeasured.txt``
(raw geometry, masses, pendulum periods, hanging angles) and the rider Jason as the lumped body of
``riders/Jason/Parameters/JasonBrowserBenchmark.txt`` (the data has no Yeadon measurements, so
BicycleParameters' ``add_rider`` reads that file too).  Both propagate the measurement
uncertainties to every parameter.  Timed warm (imports done):

* bikerider: ``load_measured_bicycle`` (read, check, reduce with first-order uncertainties: the
  generated stages of ``derive/measured_reduction.py`` - for this file's layout, BicycleParameters'
  template, the one stage ``standard_layout`` - run by the uncertainty engine with their exact
  Jacobians) + ``read_lumped_rider`` + ``merge_rider`` (Eqs. 15-16) -> ``BenchmarkParameters``;
* BicycleParameters 1.5.2: ``Bicycle('Browser', pathToData, forceRawCalc=True)`` +
  ``add_rider('Jason')`` (its uncertainties package propagates the sigmas);
* the two in alternating rounds (BicycleParameters in a worker process kept running, then
  bikerider, ...), the ratio the median of the rounds' ratios: the machine's speed can change by a
  factor of two within seconds, which separate runs would read as a change of ratio;
* for information, the reduction of a file in another layout (Rigid: heights-and-diameters
  geometry, handlebar and fork hung apart, bodies in five orientations: the stages one by one and
  the numeric least-squares stage).
"""

from __future__ import annotations

import statistics

from common import DATA, Context, Row, fmt_time, loops_for, measure, time_loop

GOAL = 10.0
MEASURED = DATA / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt"
RIDER = DATA / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt"
OTHER = DATA / "bicycles" / "Rigid" / "RawData" / "RigidMeasured.txt"


def bikerider_parameters():
    from bikerider.io.bicycleparameters import load_measured_bicycle, merge_rider, read_lumped_rider

    return merge_rider(load_measured_bicycle(MEASURED), read_lumped_rider(RIDER))


def other_layout():
    """The reduction of Rigid's Measured file (another layout); None when the module's API differs."""
    try:
        from bikerider.io.bicycleparameters import read_measured_file
    except ImportError:
        return None
    return lambda: read_measured_file(OTHER)


def run(ctx: Context) -> list[Row]:
    from bikerider.benchmark import BENCHMARK_NAMES

    rounds = 5 if ctx.quick else 15
    item = "one bicycle: raw measurements + rider -> benchmark parameters"
    goal = f">= {GOAL:.0f}x BicycleParameters"
    loops = loops_for(bikerider_parameters)
    general = other_layout()
    notes = [
        "compared: reading the raw file, reducing it with uncertainty propagation, reading the lumped "
        "rider and combining it with the rear frame, to the 25 benchmark parameters with sigmas - in "
        "both tools"
    ]
    server = ctx.bp_server()
    if isinstance(server, str):
        ours = [time_loop(bikerider_parameters, loops) for _ in range(rounds)]
        notes.append(server)
        return [
            Row(item, f"{fmt_time(statistics.median(ours))} (median of {rounds}x{loops})", [], "-", goal, None, notes)
        ]
    theirs: list[float] = []
    ours = []
    with server:
        first = server.call("raw", repeats=3)  # warm-up, and the values to compare
        if "error" in first:
            notes.append(first["error"])
            return [Row(item, "-", [], "-", goal, None, notes)]
        for _ in range(rounds):
            reply = server.call("raw", repeats=5)
            if "error" in reply:
                notes.append(reply["error"])
                return [Row(item, "-", [], "-", goal, None, notes)]
            theirs.append(reply["seconds"])
            ours.append(time_loop(bikerider_parameters, loops))
    ratios = sorted(t / o for t, o in zip(theirs, ours))
    ratio = statistics.median(ratios)
    baselines = [
        (
            "BicycleParameters Bicycle(forceRawCalc=True) + add_rider",
            f"{fmt_time(statistics.median(theirs))} (median of {rounds} rounds of 5)",
        )
    ]
    ratio_texts = [
        f"{ratio:.1f}x vs BicycleParameters (median of {rounds} interleaved rounds; {ratios[0]:.1f}x-{ratios[-1]:.1f}x)"
    ]
    if general is not None:
        general_t = measure(general, 5 if ctx.quick else 9)
        baselines.append(
            ("(info) bikerider, a Measured file in another layout (Rigid), reading and reduction", general_t.text())
        )
        notes.append(
            f"this file is in BicycleParameters' template layout, which the reduction takes in one generated "
            f"stage (derive/measured_reduction.py: values and the exact Jacobian in one plain-float "
            f"function); every other layout runs the stages one by one (Rigid: heights-and-diameters "
            f"geometry, handlebar and fork apart, five orientations by the numeric least-squares stage), "
            f"{fmt_time(general_t.median)} to read and reduce"
        )
    params = bikerider_parameters()
    gaps = []
    for name in BENCHMARK_NAMES:
        ours_v, theirs_v = params.values.get(name), first["parameters"].get(name)
        if ours_v is None or theirs_v is None:
            continue
        gaps.append((abs(float(ours_v) - theirs_v[0]) / max(abs(theirs_v[0]), 1e-12), name))
    worst = max(gaps)
    notes.append(
        f"largest relative difference of the {len(gaps)} shared values: {worst[0]:.1e} ({worst[1]}); "
        "bikerider locates centres of mass by least squares over all hanging lines, BicycleParameters "
        "by the mean of pairwise intersections"
    )
    return [
        Row(
            item,
            f"{fmt_time(statistics.median(ours))} (median of {rounds}x{loops})",
            baselines,
            "; ".join(ratio_texts),
            goal,
            ratio >= GOAL,
            notes,
        )
    ]
