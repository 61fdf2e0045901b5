"""``bikerider sensitivity OUTPUT [--wrt INPUT]``: closed-form sensitivities and uncertainty ranking."""

from __future__ import annotations

import argparse
import math

from bikerider.commands import argument_types
from bikerider.errors import InputError
from bikerider.generated.manifest import BENCHMARK_NAMES
from bikerider.notes import note
from bikerider.quantity import DEG, Quantity, check_degrees

EPILOG = """\
OUTPUT is a benchmark parameter (w, c, lam, xB, IBxx, ...), a matrix entry (M_phidelta, K2_deltadelta,
...), weave_speed, capsize_speed, a rider quantity (xBr, zBr, IBrxx, ...), a pendulum result (IBfxz,
IFyy, ...) or a characteristic coefficient a0..a4 (with --speed).

INPUT is any input name: Table 1 geometry (h_bb, lam_ht, ...), masses (mR, mBf, ...), centres of mass
(xBf, zH, ...), pendulum measurements (k_t, T_Bf1..3, alpha_Bf1..3, T_Rxx, T_Fxx, T_Fyy, l_pF), rider
measurements (l_ll, c_ch, mBr, lam_fl, f_to, ...), or an intermediate quantity (IFyy, xB, M_phiphi);
or a key as the TOML files spell it (lam_ht_deg, compound_period, front_wheel.mass,
rear_frame.inertia.periods.2; a key several inputs share is refused with the list).

Default inputs: the paper's Batavus Browser and rider (bikerider/data/paper/*.toml) with the paper's
stated accuracies (Tables 1-6) and, for the rider, whose accuracy the paper does not state, assumed
sigmas (0.01 m, 1 deg, 0.1 kg; --no-rider-sigmas makes them exact).  --bicycle alone, or --no-rider:
the bicycle without a rider; --rider alone: that rider on the paper's bicycle (a note says so).
"""


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "sensitivity",
        help="closed-form sensitivities, uncertainty ranking and Monte Carlo check",
        description=(
            "With --wrt: print d OUTPUT / d INPUT in closed form (SymPy; --latex for LaTeX) and its value. "
            "Without: rank every input by its share of OUTPUT's first-order variance, with elasticities "
            "(p/y) dy/dp."
        ),
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("output", metavar="OUTPUT", help="the quantity whose sensitivity to print")
    p.add_argument("--wrt", metavar="INPUT", help="print the closed-form derivative with respect to INPUT")
    p.add_argument("--latex", action="store_true", help="print expressions as LaTeX")
    p.add_argument("--full", action="store_true", help="print long expressions in full")
    src = p.add_mutually_exclusive_group()
    src.add_argument(
        "--inputs",
        metavar="FILE",
        help="name = value+/-sigma file of chain inputs (e.g. a BicycleParameters Benchmark.txt)",
    )
    src.add_argument(
        "--bicycle",
        metavar="FILE",
        help="bicycle file, as estimate reads it: TOML, BicycleParameters <Name>Measured.txt or <Name>Benchmark.txt "
        "(default: the paper's)",
    )
    rider = p.add_mutually_exclusive_group()
    rider.add_argument(
        "--rider",
        metavar="FILE",
        help="rider file, as estimate reads it: TOML or a BicycleParameters lumped rider (default: the paper's, "
        "unless --bicycle is given)",
    )
    rider.add_argument("--no-rider", action="store_true", help="the bicycle alone")
    p.add_argument(
        "--no-rider-sigmas", action="store_true", help="do not assume sigmas for rider measurements given without one"
    )
    p.add_argument(
        "--speed", metavar="V", type=argument_types.speed, help="speed [m/s] for the characteristic coefficients a0..a4"
    )
    p.add_argument(
        "--top",
        metavar="N",
        type=argument_types.whole_number(1, 10**6),
        default=None,
        help="show only the N largest contributions",
    )
    p.add_argument(
        "--monte-carlo",
        metavar="N",
        type=argument_types.whole_number(2, argument_types.MAX_MONTE_CARLO, "a number of samples"),
        default=None,
        help="also draw N input sets (2 to 10,000,000) and compare the first-order sigma with the Monte Carlo one",
    )
    p.add_argument(
        "--seed", metavar="S", type=argument_types.seed, default=0, help="random seed for --monte-carlo (default 0)"
    )
    p.set_defaults(run=run)


def _inputs(args: argparse.Namespace):
    # The readers and the chain (NumPy, the generated code) are imported when the command runs:
    # `bikerider --help` and the other commands start in 0.06 s instead of 0.4 s (python -X importtime).
    from bikerider.io import chain_inputs
    from bikerider.uncertainty import inputs as inp

    if args.inputs is not None and (args.rider is not None or args.no_rider):
        raise InputError(
            "--rider" if args.rider is not None else "--no-rider",
            args.rider if args.rider is not None else True,
            "no --inputs with it (--inputs gives every chain input, the rider's included)",
        )
    if args.inputs is not None:
        quantities = _file_inputs(args.inputs)
        sources = {n: f"stated: {args.inputs}" if q.sigma else "exact (no sigma given)" for n, q in quantities.items()}
        return inp.InputSet(quantities, sources, str(args.inputs))
    if args.bicycle is None and args.rider is None and not args.no_rider:
        return chain_inputs.paper_inputs(assume_rider_sigmas=not args.no_rider_sigmas)
    if not _both_toml(args):
        return _estimate_inputs(args)
    # The same checks as `estimate` (chain_inputs.raw_inputs_from_toml seats the rider: reach, knee, elbow).
    bicycle, rider = chain_inputs.paper_files()
    bicycle = args.bicycle if args.bicycle is not None else bicycle
    if args.no_rider or (args.bicycle is not None and args.rider is None):
        quantities = chain_inputs.raw_inputs_from_toml(bicycle, None)
        sources = {n: f"stated: {bicycle}" if q.sigma else "exact (no sigma given)" for n, q in quantities.items()}
        return inp.InputSet(quantities, sources, f"{bicycle} (no rider)")
    rider = args.rider if args.rider is not None else rider
    quantities = chain_inputs.raw_inputs_from_toml(bicycle, rider)
    sources = {n: f"stated: {bicycle}" if q.sigma else "exact (no sigma given)" for n, q in quantities.items()}
    if not args.no_rider_sigmas:
        quantities = inp.with_assumed_rider_sigmas(quantities, sources)
    return inp.InputSet(quantities, sources, f"{bicycle} + {rider}")


def _both_toml(args: argparse.Namespace) -> bool:
    """Whether the bicycle and rider given are project TOML files (or the paper's)."""
    from bikerider.io.bicycleparameters import detect_format

    given = [path for path in (args.bicycle, args.rider) if path is not None]
    return all(detect_format(path) == "toml" for path in given)  # raw-measurement TOML files


def _estimate_inputs(args: argparse.Namespace):
    """The chain inputs of any bicycle and rider ``estimate`` reads (BicycleParameters Measured,
    Benchmark and lumped rider files too), read by the same reader as ``estimate``
    (:func:`bikerider.estimate.estimate_from_files`, :func:`bikerider.estimate.uncertainty_inputs`)."""
    from bikerider.estimate import estimate_from_files, uncertainty_inputs
    from bikerider.uncertainty import inputs as inp

    with_rider = not args.no_rider and not (args.bicycle is not None and args.rider is None)
    result = estimate_from_files(args.bicycle, args.rider, with_rider=with_rider)
    quantities = uncertainty_inputs(result)
    named = " + ".join(str(p) for p in (args.bicycle, args.rider if with_rider else None) if p is not None)
    source = named or "the paper's bicycle"
    sources = {n: f"stated: {source}" if q.sigma else "exact (no sigma given)" for n, q in quantities.items()}
    if with_rider and result.rider_model is not None and not args.no_rider_sigmas:
        quantities = inp.with_assumed_rider_sigmas(quantities, sources)
    return inp.InputSet(quantities, sources, source if with_rider else f"{source} (no rider)")


def _notes(args: argparse.Namespace) -> list[str]:
    """What was taken for the files not given (as ``estimate`` says it)."""
    from bikerider.io.chain_inputs import paper_files

    bicycle, rider = paper_files()
    if args.bicycle is not None and args.rider is None and not args.no_rider:
        return [f"no --rider given: the bicycle alone (--rider FILE seats a rider; the paper's is {rider})"]
    if args.rider is not None and args.bicycle is None:
        return [f"no --bicycle given: the rider seated on the paper's bicycle ({bicycle})"]
    return []


def _file_inputs(path: str) -> dict[str, Quantity]:
    """The chain inputs of a ``name = value+/-sigma`` file (``NAME_deg`` in degrees).

    A file of benchmark parameters (a BicycleParameters ``<Name>Benchmark.txt``, with the extras
    those files carry) is read and checked as ``bikerider benchmark`` reads it
    (:func:`bikerider.io.bicycleparameters.benchmark_from_values`): what no bicycle can have is
    refused, an impossible ``I_yy`` the model does not use, ``yB = 0``, ``IRzz`` and the split
    handlebar and fork are left out with a note.
    """
    from bikerider.io.bicycleparameters import BENCHMARK_EXTRAS, benchmark_from_values
    from bikerider.io.name_value_file import NameValueEntry, NameValueFile, read_name_value_file
    from bikerider.uncertainty import inputs as inp

    data = read_name_value_file(path)
    entries: dict[str, NameValueEntry] = {}
    for name, entry in data.entries.items():
        if name.endswith("_deg"):
            base = name[:-4]
            if base in data.entries:
                raise InputError(
                    name,
                    entry.value.value,
                    f"either {base} (radians) or {name} (degrees), not both ({base} on line {data.entries[base].line})",
                    data.where(name),
                )
            _degrees_check(name, entry.value.value, data.where(name))
            scaled = entry.value.scaled(DEG)
            entry = NameValueEntry(base, scaled, tuple(q.scaled(DEG) for q in entry.repeats), entry.line)
        entries[entry.name] = entry
    converted = NameValueFile(data.path, entries)
    if set(entries) <= set(BENCHMARK_NAMES) | set(BENCHMARK_EXTRAS):
        read = benchmark_from_values(converted)
        return inp.benchmark_inputs(read.parameters)
    return converted.as_dict()


def _degrees_check(name: str, degrees: float, where: str) -> None:
    """A ``NAME_deg`` that looks like radians: a note for ``lam_deg`` (a steer axis tilt of a few
    degrees is possible), an error for the tube and lean angles (:func:`check_degrees`), as the
    other readers do."""
    if name == "lam_deg":
        if 0 < degrees <= math.pi:
            note(
                f"{where}: lam_deg = {degrees:g} looks like radians ({degrees:g} rad = {math.degrees(degrees):.4g} "
                f"deg); taken as degrees, a steer axis tilt of {degrees:g} deg"
            )
    else:
        check_degrees(name, degrees, where)


def _unused_inputs_note(result, given: str) -> None:
    """A note naming the inputs of the file that no computed output depends on (a Table 1 length
    beside the benchmark parameters it would have fed): they are accepted, and change nothing."""
    import numpy as np  # heavy: imported when the command runs

    jacobian = np.asarray(result.jacobian)
    unused = []
    for j, name in enumerate(result.input_names):
        if name in BENCHMARK_NAMES:  # IByy, IHyy: part of every benchmark set, unused by the linear model
            continue
        rows = [i for i, out in enumerate(result.output_names) if out != name]
        if not np.any(np.abs(jacobian[rows, j]) > 0):  # NaN (an output not defined here) is no dependence
            unused.append(name)
    if unused:
        note(f"{given}: {', '.join(unused)}: no output depends on them (the other values given replace what they feed)")


def run(args: argparse.Namespace) -> int:
    # The chain (NumPy, the generated code) is imported when the command runs (see _inputs).
    from bikerider.uncertainty import names, text
    from bikerider.uncertainty.chain import Chain, known_names, prepare_values
    from bikerider.uncertainty.montecarlo import compare, monte_carlo
    from bikerider.uncertainty.propagation import propagate
    from bikerider.uncertainty.stages import COEFFICIENTS
    from bikerider.uncertainty.symbolic import sensitivity_expression

    input_set = _inputs(args)
    if names.canonical_name(args.output) in COEFFICIENTS and args.speed is None:
        raise InputError("--speed", "missing", f"a speed in m/s at which to take the coefficient {args.output}")
    quantities = dict(input_set.quantities)
    if args.speed is not None:
        quantities["v"] = Quantity(args.speed)
    try:
        result = propagate(quantities, sources=input_set.sources)
    except InputError as exc:  # a value missing from, or wrong in, the input files: name them
        if exc.source is not None:
            raise
        raise InputError(exc.name, exc.value, exc.expected, input_set.name) from None
    if args.inputs is not None:
        _unused_inputs_note(result, args.inputs)
    known = set(result.output_names) | set(result.input_names)
    output = names.check_name(args.output, known, "OUTPUT")
    print(f"Inputs: {input_set.name}")
    notes = _notes(args)
    if args.wrt is not None:
        wrt, note = names.input_name(args.wrt, set(quantities), known_names())
        notes += [note] if note else []
        expr = sensitivity_expression(output, wrt, quantities)
        values = prepare_values(quantities)
        point = {k: float(v) for k, v in Chain(values).evaluate(values).items()}
        value = expr.evaluate(point)
        print(f"d {output} / d {expr.wrt}\n")
        print(text.expression_text(expr, value, latex=args.latex, full=args.full))
        y = point.get(output)
        x = point.get(expr.wrt)
        if y and x is not None and y == y:
            print(f"elasticity (x/y) dy/dx: {x / y * value:.4g}")
        if args.wrt.endswith("_deg") and "_deg" not in expr.wrt:
            print(f"per degree of {args.wrt}: {value * DEG:.6g} {names.unit(output)}/deg")
    else:
        if output in result.input_names:
            raise InputError("OUTPUT", args.output, "a computed quantity, not one of the inputs")
        print(text.ranking_text(result, output, args.top))
    if args.monte_carlo is not None:
        mc = monte_carlo(quantities, args.monte_carlo, outputs=[output], seed=args.seed)
        print(f"\nMonte Carlo, {args.monte_carlo} input sets (seed {args.seed}):")
        print(text.table(text.COMPARISON_HEADER, text.comparison_rows(compare(result, mc, quantities))))
    for note in notes:
        print(f"Note: {note}")
    return 0
