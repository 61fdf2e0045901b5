"""``bikerider sensitivity OUTPUT [--wrt INPUT]``: closed-form sensitivities and uncertainty ranking."""

from __future__ import annotations

import argparse

from bikerider.errors import InputError
from bikerider.generated.manifest import BENCHMARK_NAMES
from bikerider.quantity import DEG, Quantity

EPILOG = """\
OUTPUT is a benchmark parameter (w, c, lam, xB, IBxx, ...), a matrix entry (M_phidelta, K2_deltadelta,
...), weave_speed, capsize_speed, a rider quantity (xBr, zBr, IBrxx, ...), a pendulum result (IBfxz,
IFyy, ...) or a characteristic coefficient a0..a4 (with --speed).

INPUT is any input name: Table 1 geometry (h_bb, lam_ht, ...), masses (mR, mBf, ...), centres of mass
(xBf, zH, ...), pendulum measurements (k_t, T_Bf1..3, alpha_Bf1..3, T_Rxx, T_Fxx, T_Fyy, l_pF), rider
measurements (l_ll, c_ch, mBr, lam_fl, f_to, ...), or an intermediate quantity (IFyy, xB, M_phiphi).

Default inputs: the paper's Batavus Browser and rider (bikerider/data/paper/*.toml) with the paper's
stated accuracies (Tables 1-6) and, for the rider, whose accuracy the paper does not state, assumed
sigmas (0.01 m, 1 deg, 0.1 kg; --no-rider-sigmas makes them exact).
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
    src.add_argument("--bicycle", metavar="TOML", help="bicycle TOML file (with --rider)")
    p.add_argument("--rider", metavar="TOML", help="rider TOML file (with --bicycle)")
    p.add_argument(
        "--no-rider-sigmas", action="store_true", help="do not assume sigmas for rider measurements given without one"
    )
    p.add_argument("--speed", metavar="V", type=float, help="speed [m/s] for the characteristic coefficients a0..a4")
    p.add_argument("--top", metavar="N", type=int, default=None, help="show only the N largest contributions")
    p.add_argument(
        "--monte-carlo",
        metavar="N",
        type=int,
        default=None,
        help="also draw N input sets and compare the first-order sigma with the Monte Carlo one",
    )
    p.add_argument("--seed", metavar="S", type=int, default=0, help="random seed for --monte-carlo (default 0)")
    p.set_defaults(run=run)


def _inputs(args: argparse.Namespace):
    # The readers and the chain (NumPy, the generated code) are imported when the command runs:
    # `bikerider --help` and the other commands start in 0.06 s instead of 0.4 s (python -X importtime).
    from bikerider.io import chain_inputs
    from bikerider.uncertainty import inputs as inp

    if args.rider is not None and args.bicycle is None:
        raise InputError("--rider", args.rider, "a --bicycle file to go with it")
    if args.inputs is not None:
        quantities = _file_inputs(args.inputs)
        sources = {n: f"stated: {args.inputs}" if q.sigma else "exact (no sigma given)" for n, q in quantities.items()}
        return inp.InputSet(quantities, sources, str(args.inputs))
    if args.bicycle is not None:
        if args.rider is None:
            raise InputError("--bicycle", args.bicycle, "a --rider file to go with it")
        from bikerider.estimate import estimate
        from bikerider.io.toml_input import load_bicycle_toml, load_rider_toml

        bicycle, rider = load_bicycle_toml(args.bicycle), load_rider_toml(args.rider)
        estimate(bicycle, rider)  # the checks `estimate` makes: the rider seated (reach, knee, elbow), the values
        quantities = inp.chain_raw_inputs(bicycle, rider)
        sources = {n: f"stated: {args.bicycle}" if q.sigma else "exact (no sigma given)" for n, q in quantities.items()}
        if not args.no_rider_sigmas:
            quantities = inp.with_assumed_rider_sigmas(quantities, sources)
        return inp.InputSet(quantities, sources, f"{args.bicycle} + {args.rider}")
    return chain_inputs.paper_inputs(assume_rider_sigmas=not args.no_rider_sigmas)


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
            scaled = entry.value.scaled(DEG)
            entry = NameValueEntry(base, scaled, tuple(q.scaled(DEG) for q in entry.repeats), entry.line)
        entries[entry.name] = entry
    converted = NameValueFile(data.path, entries)
    if set(entries) <= set(BENCHMARK_NAMES) | set(BENCHMARK_EXTRAS):
        read = benchmark_from_values(converted)
        return inp.benchmark_inputs(read.parameters)
    return converted.as_dict()


def run(args: argparse.Namespace) -> int:
    # The chain (NumPy, the generated code) is imported when the command runs (see _inputs).
    from bikerider.uncertainty import names, text
    from bikerider.uncertainty.chain import Chain, prepare_values
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
    known = set(result.output_names) | set(result.input_names)
    output = names.check_name(args.output, known, "OUTPUT")
    print(f"Inputs: {input_set.name}")
    if args.wrt:
        expr = sensitivity_expression(output, args.wrt, quantities)
        values = prepare_values(quantities)
        point = {k: float(v) for k, v in Chain(values).evaluate(values).items()}
        value = expr.evaluate(point)
        print(f"d {output} / d {expr.wrt}\n")
        print(text.expression_text(expr, value, latex=args.latex, full=args.full))
        y = point.get(output)
        x = point.get(expr.wrt)
        if y and x is not None and y == y:
            print(f"elasticity (x/y) dy/dx: {x / y * value:.4g}")
    else:
        if output in result.input_names:
            raise InputError("OUTPUT", args.output, "a computed quantity, not one of the inputs")
        print(text.ranking_text(result, output, args.top))
    if args.monte_carlo is not None:
        mc = monte_carlo(quantities, args.monte_carlo, outputs=[output], seed=args.seed)
        print(f"\nMonte Carlo, {args.monte_carlo} input sets (seed {args.seed}):")
        print(text.table(text.COMPARISON_HEADER, text.comparison_rows(compare(result, mc, quantities))))
    return 0
