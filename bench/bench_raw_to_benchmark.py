"""Item 4: one bicycle from raw measurements and a rider to the benchmark parameters.

The same data for both tools: BicycleParameters' ``bicycles/Browser/RawData/BrowserMeasured.txt``
(raw geometry, masses, pendulum periods, hanging angles) and the rider Jason as the lumped body of
``riders/Jason/Parameters/JasonBrowserBenchmark.txt`` (the data has no Yeadon measurements, so
BicycleParameters' ``add_rider`` reads that file too).  Both propagate the measurement
uncertainties to every parameter.  Timed warm (imports done), median over repeats:

* bikerider: ``load_measured_bicycle`` (read, reduce, first-order uncertainty by a numerical
  Jacobian of the whole reduction, its 2k + 1 points evaluated in one batched NumPy call) +
  ``read_lumped_rider`` + ``merge_rider`` (Eqs. 15-16) -> ``BenchmarkParameters``;
* BicycleParameters 1.5.2: ``Bicycle('Browser', pathToData, forceRawCalc=True)`` +
  ``add_rider('Jason')`` (its uncertainties package propagates the sigmas);
* for information, bikerider's reduction of the nominal values alone (no uncertainty), and the
  reduction with its Jacobian alone (no reading, validation or rider), to show where the time goes.
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


def reductions():
    """Callables reducing the file's values: the nominal point alone, and the nominal point with
    every perturbed point of the numerical Jacobian in one batched call (what
    ``load_measured_bicycle`` does); None when the module's API differs."""
    try:
        from bikerider.bicycle.propagation import propagate
        from bikerider.bicycle.raw_measurements import _KNOWN_EXTRAS, detect_layout, evaluate_measured
        from bikerider.io.name_value_file import read_name_value_file
    except ImportError:
        return None
    data = read_name_value_file(MEASURED)
    values = data.as_dict()
    layout = detect_layout(values, str(MEASURED))
    nominal = {k: q.value for k, q in values.items()}
    used = {k: q for k, q in values.items() if k not in _KNOWN_EXTRAS}
    return {
        "nominal": lambda: evaluate_measured(nominal, layout),
        "jacobian": lambda: propagate(lambda x: evaluate_measured(x, layout, check=True), used, vectorized=True),
    }, sum(q.sigma > 0 for q in used.values())


def run(ctx: Context) -> list[Row]:
    from bikerider.benchmark import BENCHMARK_NAMES

    repeats = 5 if ctx.quick else 15
    parts = reductions()
    fns = {"ours": bikerider_parameters}
    if parts is not None:
        fns.update(parts[0])
    timings = measure_together(fns, repeats)
    ours = timings["ours"]
    notes = ["compared: reading the raw file, reducing it with uncertainty propagation, reading the lumped "
             "rider and combining it with the rear frame, to the 25 benchmark parameters with sigmas - in "
             "both tools"]
    baselines: list[tuple[str, str]] = []
    if parts is not None:
        nominal_t, jacobian_t = timings["nominal"], timings["jacobian"]
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
    if parts is not None:
        ratios.append(f"(nominal-only reduction: {ratio_text(bp['seconds'], nominal_t.median)})")
        k = parts[1]
        notes.append(f"where bikerider's time goes: the file has {k} values with a sigma; the first-order "
                     f"propagation (bikerider.bicycle.propagation, central differences) evaluates the reduction "
                     f"at 2 x {k} + 1 = {2 * k + 1} points in one batched NumPy call: "
                     f"{fmt_time(jacobian_t.median)} with the uncertainties, against {fmt_time(nominal_t.median)} "
                     f"for the nominal point alone, of the {fmt_time(ours.median)} in all (timed interleaved; the "
                     "rest is reading the two files, validating the bodies and parameters, and the rider merge, "
                     "itself a batched Jacobian); BicycleParameters carries the sigmas through one pass with the "
                     "uncertainties package")
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
