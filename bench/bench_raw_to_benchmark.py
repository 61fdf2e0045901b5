"""Item 4: one bicycle from raw measurements and a rider to the benchmark parameters.

The same data for both tools: BicycleParameters' ``bicycles/Browser/RawData/BrowserMeasured.txt``
(raw geometry, masses, pendulum periods, hanging angles) and the rider Jason as the lumped body of
``riders/Jason/Parameters/JasonBrowserBenchmark.txt`` (the data has no Yeadon measurements, so
BicycleParameters' ``add_rider`` reads that file too).  Both propagate the measurement
uncertainties to every parameter.  Timed warm (imports done), median over repeats:

* bikerider: ``load_measured_bicycle`` (read, reduce, first-order uncertainty by a numerical
  Jacobian of the whole reduction) + ``read_lumped_rider`` + ``merge_rider`` (Eqs. 15-16) ->
  ``BenchmarkParameters``;
* BicycleParameters 1.5.2: ``Bicycle('Browser', pathToData, forceRawCalc=True)`` +
  ``add_rider('Jason')`` (its uncertainties package propagates the sigmas);
* for information, bikerider's reduction of the nominal values alone (no uncertainty), which is
  the part of the work that does not depend on how uncertainties are propagated.
"""
from __future__ import annotations

from common import DATA, Context, Row, fmt_time, measure_together, ratio_text

GOAL = 10.0
MEASURED = DATA / "bicycles" / "Browser" / "RawData" / "BrowserMeasured.txt"
RIDER = DATA / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt"


def bikerider_parameters():
    from bikerider.bicycle.raw_measurements import load_measured_bicycle
    from bikerider.io.bicycleparameters import merge_rider, read_lumped_rider

    return merge_rider(load_measured_bicycle(MEASURED), read_lumped_rider(RIDER))


def nominal_reduction():
    """A callable reducing the nominal values only, or None when the module's API differs."""
    try:
        from bikerider.bicycle.raw_measurements import detect_layout, evaluate_measured
        from bikerider.io.name_value_file import read_name_value_file
    except ImportError:
        return None
    data = read_name_value_file(MEASURED)
    values = data.as_dict()
    layout = detect_layout(values, str(MEASURED))
    nominal = {k: q.value for k, q in values.items()}
    reduce = lambda: evaluate_measured(nominal, layout)  # noqa: E731
    reduce.with_sigma = sum(q.sigma > 0 for q in values.values())  # type: ignore[attr-defined]
    return reduce


def run(ctx: Context) -> list[Row]:
    from bikerider.benchmark import BENCHMARK_NAMES

    repeats = 5 if ctx.quick else 15
    nominal = nominal_reduction()
    fns = {"ours": bikerider_parameters}
    if nominal is not None:
        fns["nominal"] = nominal
    timings = measure_together(fns, repeats)
    ours = timings["ours"]
    notes = ["compared: reading the raw file, reducing it with uncertainty propagation, reading the lumped "
             "rider and combining it with the rear frame, to the 25 benchmark parameters with sigmas - in "
             "both tools"]
    baselines: list[tuple[str, str]] = []
    if nominal is not None:
        nominal_t = timings["nominal"]
        baselines.append(("(info) bikerider reduction, nominal values only", nominal_t.text()))
    bp = ctx.bp("raw", repeats=15)
    if "error" in bp:
        notes.append(bp["error"])
        return [Row("one bicycle: raw measurements + rider -> benchmark parameters", ours.text(), baselines,
                    "-", f">= {GOAL:.0f}x BicycleParameters", None, notes)]
    baselines.insert(0, ("BicycleParameters Bicycle(forceRawCalc=True) + add_rider",
                         f"{fmt_time(bp['seconds'])} (median of {bp['repeats']})"))
    ratio = bp["seconds"] / ours.median
    ratios = [f"{ratio_text(bp['seconds'], ours.median)} vs BicycleParameters"]
    if nominal is not None:
        ratios.append(f"(nominal-only reduction: {ratio_text(bp['seconds'], nominal_t.median)})")
        k = nominal.with_sigma
        notes.append(f"where bikerider's time goes: the file has {k} values with a sigma; the first-order "
                     f"propagation (bikerider.bicycle.propagation, central differences) evaluates the reduction "
                     f"2 x {k} + 1 times: {2 * k + 1} x {fmt_time(nominal_t.median)} = "
                     f"{fmt_time((2 * k + 1) * nominal_t.median)} of the {fmt_time(ours.median)} (timed interleaved); "
                     "BicycleParameters "
                     "carries the sigmas through one pass with the uncertainties package")
    params = bikerider_parameters()
    gaps = []
    for name in BENCHMARK_NAMES:
        ours_v, theirs = params.values.get(name), bp["parameters"].get(name)
        if ours_v is None or theirs is None:
            continue
        gaps.append((abs(float(ours_v) - theirs[0]) / max(abs(theirs[0]), 1e-12), name))
    worst = max(gaps)
    notes.append(f"largest relative difference of the {len(gaps)} shared values: {worst[0]:.1e} ({worst[1]}); "
                 "bikerider locates centres of mass by least squares over all hanging lines, BicycleParameters "
                 "by the mean of pairwise intersections")
    return [Row("one bicycle: raw measurements + rider -> benchmark parameters", ours.text(), baselines,
                "; ".join(ratios), f">= {GOAL:.0f}x BicycleParameters", ratio >= GOAL, notes)]
