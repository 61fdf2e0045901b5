"""Items 3 and 7: raw measurements to critical speeds for a batch of 100000 perturbed measurement
sets, and the peak memory of that batch.

Input sets: the paper's bicycle and rider as raw measurements (pendulum periods and angles,
geometry, rider lengths; ``bikerider.uncertainty.inputs.paper_inputs``), every measurement with a
sigma drawn from a normal distribution (seed 0).  Some sets put the rider's hands out of reach of
the grips with these sigmas; they give NaN and are counted.

* bikerider: ``bikerider.uncertainty.chain.Chain.evaluate`` on the whole batch at once - the
  generated pendulum reductions, grid points and closures, rider, rear body, canonical matrices,
  critical-speed polynomials, and the quadratics in ``u = v^2`` solved for all sets
  (``bikerider.uncertainty.speeds``);
* SymPy: the same derivations (``derive.pendulum``, ``derive.combination.benchmark_chain``,
  ``derive.benchmark_model``) lambdified without common-subexpression elimination, composed, and
  the same quadratic solver, on a smaller batch (its rate is per set);
* BicycleParameters has no batch path; one set costs it what item 4 measures.

Peak memory: a fresh subprocess draws the 100000 sets and evaluates them; the peak resident set
size of that process (``ru_maxrss``) is reported, and its growth during the evaluation.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
from common import BENCH, ROOT, Context, Row, measure, ratio_text

N = 100_000
GOAL_RATE, GOAL_MEMORY = 100_000, 2**30


def draw(n: int, seed: int = 0):
    """``(chain, values)``: the paper's inputs with ``n`` normal draws of every measured value."""
    from bikerider.io.chain_inputs import paper_inputs
    from bikerider.uncertainty.chain import Chain, prepare_values

    quantities = paper_inputs().quantities
    values = prepare_values(quantities)
    rng = np.random.default_rng(seed)
    for name, q in quantities.items():
        if q.sigma > 0:
            values[name] = q.value + q.sigma * rng.standard_normal(n)
    return Chain(values), values


def lambdified_chain():
    """The derivations composed as lambdified functions (no CSE): ``f(values) -> (v_weave, v_capsize)``."""
    import sympy as sp

    from bikerider.benchmark.roots import quadratic_roots
    from derive import benchmark_model, combination, pendulum
    from derive.symbols import sym

    def lam(args, expr):
        return sp.lambdify(args, expr, modules="numpy", cse=False)

    three, _ = pendulum.three_orientation_solution()
    three_args = sorted(three.free_symbols, key=lambda s: s.name)
    f_three = lam(three_args, list(three))
    torsional = pendulum.torsional_inertia()
    torsional_args = sorted(torsional.free_symbols, key=lambda s: s.name)
    f_torsional = lam(torsional_args, torsional)
    compound = pendulum.compound_inertia()
    compound_args = sorted(compound.free_symbols, key=lambda s: s.name)
    f_compound = lam(compound_args, compound)
    chain_args, chain = combination.benchmark_chain()
    f_chain = lam(chain_args, list(chain))
    mats = benchmark_model.canonical_matrices()
    canon_args = sorted(set().union(*(m.free_symbols for m in mats.values())), key=lambda s: s.name)
    f_mats = {name: [lam(canon_args, e) for e in m] for name, m in mats.items()}
    polys = benchmark_model.critical_speed_polynomials()
    entry_args = benchmark_model.matrix_entry_args() + [sym("g")]
    f_polys = {name: [lam(entry_args, c) for c in coeffs] for name, coeffs in polys.items()}
    from bikerider.benchmark import BENCHMARK_NAMES

    def evaluate(values: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        v = dict(values)
        by_name = {s.name: s for s in three_args}
        for body, prefix in (("Bf", "Bf"),):
            kw = {
                "k_t": v["k_t"],
                **{f"T_{i}": v[f"T_{prefix}{i}"] for i in (1, 2, 3)},
                **{f"alpha_{i}": v[f"alpha_{prefix}{i}"] for i in (1, 2, 3)},
            }
            ixx, ixz, izz = f_three(*(kw[s] for s in by_name))
            v[f"I{body}xx"], v[f"I{body}xz"], v[f"I{body}zz"] = ixx, ixz, izz
        for wheel in ("R", "F"):
            if f"T_{wheel}xx" in v:
                kw = {"k_t": v["k_t"], "T": v[f"T_{wheel}xx"]}
                v[f"I{wheel}xx"] = f_torsional(*(kw[s.name] for s in torsional_args))
            if f"T_{wheel}yy" in v:
                kw = {"T": v[f"T_{wheel}yy"], "m_p": v[f"m{wheel}"], "g": v["g"], "l_p": v[f"l_p{wheel}"]}
                v[f"I{wheel}yy"] = f_compound(*(kw[s.name] for s in compound_args))
        v.setdefault("IHyy", np.nan)
        v.setdefault("IBfyy", np.nan)
        out = f_chain(*(v[s.name] for s in chain_args))
        bench = dict(zip(BENCHMARK_NAMES, out))
        entries = []
        for name in ("M", "C1", "K0", "K2"):
            entries += [f(*(bench[s.name] for s in canon_args)) for f in f_mats[name]]
        entries.append(bench["g"])
        c = {name: [f(*entries) for f in fs] for name, fs in f_polys.items()}
        low, high = quadratic_roots(*c["capsize"]) if len(c["capsize"]) == 3 else quadratic_roots(0.0, *c["capsize"])
        with np.errstate(invalid="ignore", divide="ignore"):
            capsize = np.where(low > 0, low, np.where(high > 0, high, np.nan))
            roots = quadratic_roots(*c["weave"])
            a1 = c["a1_over_v"]
            a3 = c["a3_over_v"]
            a3_at = a3[-1] if len(a3) == 1 else None

            def omega2(u):
                a1u = a1[0] * u + a1[1] if len(a1) == 2 else a1[0]
                a3u = a3_at if a3_at is not None else a3[0] * u + a3[1]
                return a1u / a3u

            ok = [(u > 0) & np.isfinite(omega2(u)) & (omega2(u) > 0) for u in roots]
            weave = np.where(ok[0], roots[0], np.where(ok[1], roots[1], np.nan))
            return np.sqrt(weave), np.sqrt(capsize)

    return evaluate


def peak_rss() -> int:
    """Peak resident set size of this process in bytes (``VmHWM``; unlike ``ru_maxrss`` it is not
    inherited from the parent across fork and exec)."""
    for line in open("/proc/self/status", encoding="ascii"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def memory_child(n: int) -> None:
    """Run in a subprocess: draw ``n`` sets, evaluate, print peak RSS before and after as JSON."""
    chain, values = draw(n)
    chain.evaluate({k: v[:10] if v.ndim else v for k, v in values.items()})  # import and warm up
    before = peak_rss()
    nodes = chain.evaluate(values)
    after = peak_rss()
    print(json.dumps({"before": before, "after": after, "valid": int(np.isfinite(nodes["v_weave"]).sum())}))


def run(ctx: Context) -> list[Row]:
    import time

    chain, values = draw(N)
    repeats = 3 if ctx.quick else 5
    ours = measure(lambda: chain.evaluate(values), repeats, min_sample=0.0)
    nodes = chain.evaluate(values)
    weave, capsize = nodes["v_weave"], nodes["v_capsize"]
    rate = N / ours.median
    notes = [
        f"{N} sets; weave speed found in {int(np.isfinite(weave).sum())}, capsize in "
        f"{int(np.isfinite(capsize).sum())} (the rest: the rider's hands cannot reach the grips, "
        f"elbow closure NaN in {int((~np.isfinite(nodes['rX23'])).sum())})",
        f"median weave {np.nanmedian(weave):.4f} m/s, capsize {np.nanmedian(capsize):.4f} m/s",
    ]

    m = 2000 if ctx.quick else 10_000
    small = {k: (v[:m] if v.ndim else v) for k, v in values.items()}
    t0 = time.perf_counter()
    lam = lambdified_chain()
    build = time.perf_counter() - t0
    lam_t = measure(lambda: lam(small), 3 if not ctx.quick else 1, min_sample=0.0)
    lam_weave, lam_capsize = lam(small)
    both = np.isfinite(lam_weave) & np.isfinite(weave[:m])
    same_nan = bool(np.array_equal(np.isfinite(lam_weave), np.isfinite(weave[:m])))
    gap = float(np.max(np.abs(lam_weave[both] - weave[:m][both]) / weave[:m][both])) if both.any() else float("nan")
    notes.append(
        f"sympy.lambdify baseline on the first {m} sets: building the functions took {build:.1f} s "
        f"(not in the ratio); weave speeds agree to {gap:.1e} relative, same sets without a speed: {same_nan}"
    )
    lam_rate = m / lam_t.median
    rows = [
        Row(
            f"raw measurements -> critical speeds, batch of {N}",
            f"{rate:,.0f} sets/s ({ours.text()} per batch)",
            [
                (f"sympy.lambdify (no CSE), {m} sets", f"{lam_rate:,.0f} sets/s ({lam_t.text()} per batch)"),
                ("BicycleParameters", "no batch path (one set: see 'one bicycle from raw measurements')"),
            ],
            f"{ratio_text(1 / lam_rate, 1 / rate)} vs lambdify",
            f">= {GOAL_RATE:,} sets/s",
            rate >= GOAL_RATE,
            notes,
        )
    ]

    proc = subprocess.run(
        [sys.executable, str(BENCH / "bench_batch.py"), "--memory", str(N)],
        capture_output=True,
        text=True,
        cwd=str(ROOT),
        timeout=600,
    )
    try:
        mem = json.loads(proc.stdout.strip().splitlines()[-1])
        peak, growth = mem["after"], mem["after"] - mem["before"]
        rows.append(
            Row(
                f"peak memory, batch of {N}",
                f"{peak / 2**20:.0f} MiB peak RSS of the process (+{growth / 2**20:.0f} MiB during the evaluation)",
                [],
                "-",
                "< 1 GiB",
                peak < GOAL_MEMORY,
                [
                    "whole batch evaluated at once in a fresh process (peak RSS = VmHWM, including the "
                    "interpreter, NumPy and the drawn inputs); the Monte Carlo command evaluates in chunks "
                    "of 20000 and needs less"
                ],
            )
        )
    except (json.JSONDecodeError, IndexError, KeyError):
        rows.append(
            Row(
                f"peak memory, batch of {N}",
                "FAILED: " + (proc.stderr.strip().splitlines() or ["no output"])[-1],
                met=False,
            )
        )
    return rows


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    if len(sys.argv) == 3 and sys.argv[1] == "--memory":
        memory_child(int(sys.argv[2]))
