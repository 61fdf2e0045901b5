"""The default ``bikerider estimate``'s uncertainty: first order alone against first order plus the
10,000 Monte Carlo draws behind the sigmas it reports (``bikerider.uncertainty.headline``).

Both on the paper's bicycle and rider, from the files (read, seat, estimate), interleaved so that
the machine's load falls on both alike.  Goal: the Monte Carlo draws cost at most 0.25 s, so the
default run stays interactive.
"""

from __future__ import annotations

import logging

from common import Context, Row, fmt_time, measure_together

GOAL_EXTRA_SECONDS = 0.25


def run(ctx: Context) -> list[Row]:
    from bikerider.estimate import estimate_from_files, estimate_headline_uncertainty, estimate_uncertainty
    from bikerider.uncertainty.headline import DEFAULT_SAMPLES

    logging.getLogger("bikerider").setLevel(logging.ERROR)

    def first_order_only():
        result = estimate_from_files()
        return estimate_uncertainty(result, [0.0, 5.0, 10.0])

    def with_monte_carlo():
        result = estimate_from_files()
        first_order = estimate_uncertainty(result, [0.0, 5.0, 10.0])
        return estimate_headline_uncertainty(result, first_order, samples=DEFAULT_SAMPLES)

    times = measure_together(
        {"first order": first_order_only, "monte carlo": with_monte_carlo}, repeats=3 if ctx.quick else ctx.repeats
    )
    base, ours = times["first order"].median, times["monte carlo"].median
    extra = ours - base
    return [
        Row(
            f"estimate's sigmas: first order + {DEFAULT_SAMPLES} Monte Carlo draws (paper's bicycle and rider)",
            fmt_time(ours),
            [("first order alone", fmt_time(base))],
            f"{ours / base:.1f}x the time",
            f"the draws add <= {GOAL_EXTRA_SECONDS} s",
            extra <= GOAL_EXTRA_SECONDS,
            [f"the draws add {fmt_time(extra)}"],
        )
    ]
