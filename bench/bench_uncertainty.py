"""Monte Carlo throughput: 100 000 raw measurement sets of the paper's bicycle and rider through the
whole chain (pendulum reductions, grid points, closures, rider, rear body, matrices, weave and
capsize speeds), vectorised, against a per-sample loop measured in the same run.

Run: ``.venv/bin/python bench/bench_uncertainty.py [--n 100000]``.  Prints sets/second, the wall
time and the peak memory traced by ``tracemalloc`` (NumPy buffers included), and the speed-up over
the loop (extrapolated from 200 samples).
"""

from __future__ import annotations

import argparse
import json
import time
import tracemalloc

import numpy as np
from bikerider.generated import benchmark_model, combination, pendulum

from bikerider.benchmark import WhippleModel
from bikerider.engine import arguments
from bikerider.io.chain_inputs import paper_inputs
from bikerider.uncertainty.montecarlo import sample_outputs
from bikerider.uncertainty.stages import CANONICAL

CHAIN = arguments("combination.estimate_chain")


def vectorised(n: int) -> dict[str, float]:
    quantities = paper_inputs().quantities
    sample_outputs(quantities, 1000, seed=0)  # warm up imports and caches
    tracemalloc.start()
    start = time.perf_counter()
    out, failures = sample_outputs(quantities, n, seed=0)
    elapsed = time.perf_counter() - start
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    finite = np.isfinite(out["v_weave"]) & np.isfinite(out["v_capsize"])
    return {
        "n": n,
        "seconds": elapsed,
        "sets_per_second": n / elapsed,
        "peak_MB": peak / 1e6,
        "valid_fraction": float(finite.mean()),
        "failures": failures,
    }


def loop(n: int) -> dict[str, float]:
    """One sample at a time: pendulum reductions, the generated chain, WhippleModel.critical_speeds."""
    q = paper_inputs().quantities
    rng = np.random.default_rng(0)
    start = time.perf_counter()
    for _ in range(n):
        x = {k: v.value + v.sigma * rng.standard_normal() for k, v in q.items()}
        inertia, _ = pendulum.inertia_from_three_orientations(
            k_t=x["k_t"],
            T_1=x["T_Bf1"],
            T_2=x["T_Bf2"],
            T_3=x["T_Bf3"],
            alpha_1=x["alpha_Bf1"],
            alpha_2=x["alpha_Bf2"],
            alpha_3=x["alpha_Bf3"],
        )
        x.update(
            IBfxx=inertia[0],
            IBfxz=inertia[1],
            IBfzz=inertia[2],
            IBfyy=np.nan,
            IHyy=np.nan,
            IRxx=pendulum.torsional_inertia(k_t=x["k_t"], T=x["T_Rxx"]),
            IFxx=pendulum.torsional_inertia(k_t=x["k_t"], T=x["T_Fxx"]),
            IFyy=pendulum.compound_inertia(T=x["T_Fyy"], m_p=x["mF"], g=x["g"], l_p=x["l_pF"]),
        )
        with np.errstate(invalid="ignore"):
            values = combination.estimate_chain(**{k: x[k] for k in CHAIN})
        params = dict(
            zip(
                (
                    "w c lam g rR mR IRxx IRyy xB zB mB IBxx IByy IBzz IBxz xH zH mH IHxx IHyy IHzz IHxz "
                    "rF mF IFxx IFyy"
                ).split(),
                values,
            )
        )
        if not np.isfinite(params["xB"]):
            continue
        WhippleModel(*benchmark_model.canonical_matrices(**{k: params[k] for k in CANONICAL})).critical_speeds()
    elapsed = time.perf_counter() - start
    return {"n": n, "seconds": elapsed, "sets_per_second": n / elapsed}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100_000, help="input sets (default 100000)")
    parser.add_argument("--loop", type=int, default=200, help="samples for the per-sample baseline (default 200)")
    args = parser.parse_args()
    fast = vectorised(args.n)
    slow = loop(args.loop)
    fast["speedup_over_loop"] = fast["sets_per_second"] / slow["sets_per_second"]
    print(
        f"vectorised chain, raw measurements to critical speeds: {fast['n']} sets in {fast['seconds']:.2f} s "
        f"= {fast['sets_per_second']:.0f} sets/s, peak traced memory {fast['peak_MB']:.0f} MB"
    )
    print(f"per-sample loop baseline: {slow['sets_per_second']:.0f} sets/s; speed-up {fast['speedup_over_loop']:.0f}x")
    print(json.dumps({"vectorised": fast, "loop": slow}))


if __name__ == "__main__":
    main()
