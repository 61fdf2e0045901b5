"""The fused C kernels (generated/design_kernels.py) against the NumPy reference.

The kernels evaluate the same SymPy expressions as the generated NumPy functions, with the
benchmark matrices' structural zeros and symmetries substituted (derive/kernels.py), and port the
interval logic of ``stability_batch`` and the closed-form quartic line by line.  The two round
differently (another order of the same sums), so they agree to 1e-12 wherever an output is
determined to 1e-12 by the matrix entries; where a one-ulp change of the entries moves an output by
``delta`` (a polynomial coefficient that cancels), both are that uncertain, and they must agree to
``8 delta``.  Found on 2e5 random designs: 48 weave speeds need the second term, at most 3.3 delta.
"""

from __future__ import annotations

import numpy as np
import pytest
from bikerider.generated import benchmark_model as gen

from bikerider.benchmark import WhippleModel
from bikerider.benchmark.model import matrix_entries
from bikerider.benchmark.stability import stability_batch
from bikerider.shipped import named

compiled = pytest.importorskip("bikerider.design.compiled")
if not compiled.available():  # pragma: no cover - CI has a compiler
    pytest.skip("no C compiler: the fused kernels cannot be built", allow_module_level=True)

from bikerider.design import engine  # noqa: E402

N = 20_000
SPEEDS = np.linspace(0.0, 10.0, 101)
FLOATS = ("lower", "upper", "weave", "capsize", "weave_frequency")
TWO_INTERVALS = [  # unusual bicycles with two self-stable intervals (found by a search over wide random designs)
    {
        "w": 0.620795,
        "c": 0.234243,
        "lam": 0.449306,
        "rR": 0.0584220,
        "mR": 2.04246,
        "IRxx": 0.0971783,
        "IRyy": 0.185346,
        "xB": 0.167507,
        "zB": -0.255922,
        "mB": 46.9052,
        "IBxx": 9.10270,
        "IBzz": 2.95335,
        "IBxz": 3.28661,
        "xH": 1.81001,
        "zH": -0.891029,
        "mH": 5.36583,
        "IHxx": 0.0566949,
        "IHzz": 0.0120683,
        "IHxz": -0.0102589,
        "rF": 0.0415094,
        "mF": 2.03050,
        "IFxx": 0.204892,
        "IFyy": 0.344371,
        "g": 9.81,
    },
    {
        "w": 0.487089,
        "c": 0.123976,
        "lam": 0.526784,
        "rR": 0.0174541,
        "mR": 3.75261,
        "IRxx": 0.109100,
        "IRyy": 0.114344,
        "xB": 0.496190,
        "zB": -0.110446,
        "mB": 110.443,
        "IBxx": 6.43474,
        "IBzz": 4.86737,
        "IBxz": 0.148607,
        "xH": 0.529202,
        "zH": -0.966683,
        "mH": 4.93205,
        "IHxx": 0.0556766,
        "IHzz": 0.00893323,
        "IHxz": -0.00318123,
        "rF": 0.480949,
        "mF": 0.185035,
        "IFxx": 0.248186,
        "IFyy": 0.169059,
        "g": 9.81,
    },
    {
        "w": 0.976444,
        "c": -0.233274,
        "lam": 0.102691,
        "rR": 0.0655273,
        "mR": 0.738111,
        "IRxx": 0.0441131,
        "IRyy": 0.0733604,
        "xB": -0.231852,
        "zB": -0.969098,
        "mB": 4.76221,
        "IBxx": 12.4829,
        "IBzz": 3.33314,
        "IBxz": 2.45938,
        "xH": 2.27193,
        "zH": -0.635948,
        "mH": 4.36277,
        "IHxx": 0.0584413,
        "IHzz": 0.00169174,
        "IHxz": -0.00153724,
        "rF": 0.0522165,
        "mF": 5.43058,
        "IFxx": 0.269723,
        "IFyy": 0.279141,
        "g": 9.81,
    },
]


def _designs(n: int, spread: float, seed: int) -> dict[str, np.ndarray]:
    base = named("Benchmark")
    rng = np.random.default_rng(seed)
    out = {k: float(base.values[k]) * (1 + spread * rng.uniform(-1, 1, n)) for k in compiled.ARGUMENTS if k != "g"}
    out["g"] = np.asarray(9.81)
    return out


@pytest.fixture(scope="module")
def random_designs():
    args = _designs(N, 0.5, 1)
    edge = {k: np.array([d[k] for d in TWO_INTERVALS]) for k in compiled.ARGUMENTS}
    return {k: np.concatenate([np.broadcast_to(args[k], (N,)), edge[k]]) for k in compiled.ARGUMENTS}


def _one_ulp_sensitivity(entries: dict[str, np.ndarray], reference) -> dict[str, np.ndarray]:
    """How far each output moves when the matrix entries move by one ulp (max of four draws)."""
    delta = {k: np.zeros(getattr(reference, k).shape[0]) for k in FLOATS}
    for seed in range(4):
        rng = np.random.default_rng(100 + seed)
        moved = {
            k: np.where(rng.random(v.shape) < 0.5, np.nextafter(v, np.inf), np.nextafter(v, -np.inf))
            for k, v in entries.items()
        }
        other = stability_batch(moved, 9.81)
        for k in FLOATS:
            with np.errstate(invalid="ignore"):
                d = np.abs(getattr(other, k) - getattr(reference, k))
            d = np.where(np.isfinite(d), d, 0.0)
            delta[k] = np.maximum(delta[k], d.max(axis=-1) if d.ndim > 1 else d)
    return delta


def test_the_stability_kernel_agrees_with_numpy(random_designs):
    n = random_designs["w"].size
    got = compiled.stability(random_designs, n, SPEEDS)
    entries = matrix_entries(*gen.canonical_matrices(**{k: v for k, v in random_designs.items() if k != "g"}))
    want = stability_batch(entries, 9.81)
    # the sample covers the cases: no stable interval, several, none bounded above, no weave or capsize speed
    n_intervals = want.n_intervals
    assert (n_intervals == 0).sum() > 100 and (n_intervals >= 2).sum() == len(TWO_INTERVALS)
    assert np.isinf(want.upper).any(axis=-1).sum() > 10
    assert np.isnan(want.weave).sum() > 100 and np.isnan(want.capsize).sum() > 100
    np.testing.assert_array_equal(got["lower_kind"], want.lower_kind)
    np.testing.assert_array_equal(got["upper_kind"], want.upper_kind)
    stable = np.unpackbits(got["stable_bits"], axis=-1, count=SPEEDS.size, bitorder="little").astype(bool)
    np.testing.assert_array_equal(stable, want.is_stable(SPEEDS))
    delta = _one_ulp_sensitivity(entries, want)
    for key in FLOATS:
        a, b = got[key], getattr(want, key)
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b), err_msg=key)
        np.testing.assert_array_equal(np.isinf(a), np.isinf(b), err_msg=key)
        finite = np.isfinite(b)
        scale = np.maximum(1.0, np.where(finite, np.abs(b), 0.0))
        error = np.where(finite, np.abs(a - np.where(finite, b, 0.0)), 0.0)
        if error.ndim > 1:
            error, scale = error.max(axis=-1), scale.max(axis=-1)
        tolerance = 1e-12 * scale + 8 * delta[key]
        assert np.all(error <= tolerance), f"{key}: {np.sum(error > tolerance)} designs differ beyond the bound"
        assert np.mean(error > 1e-12 * scale) < 1e-3, f"{key}: too many designs beyond 1e-12"


def test_the_two_interval_designs_agree_with_one_bicycle_at_a_time():
    for design in TWO_INTERVALS:
        args = {k: np.asarray(v) for k, v in design.items()}
        got = compiled.stability(args, 1, ())
        mats = gen.canonical_matrices(**{k: v for k, v in design.items() if k != "g"})
        one = WhippleModel(*mats, g=9.81).stability()
        assert len(one.intervals) == 2
        for k, interval in enumerate(one.intervals):
            assert got["lower"][0, k] == pytest.approx(interval.lower, rel=1e-12)
            assert got["upper"][0, k] == pytest.approx(interval.upper, rel=1e-12)


def test_the_mass_matrix_check_is_whipplemodels():
    args = _designs(2000, 0.9, 3)
    args["mH"] = np.where(np.arange(2000) % 7 == 0, 1e-9, args["mH"])  # weightless front assemblies
    args["mF"] = np.where(np.arange(2000) % 7 == 0, 1e-9, args["mF"])
    args["IHxx"] = args["IHzz"] = args["IFxx"] = np.where(np.arange(2000) % 7 == 0, 1e-12, args["IHxx"])
    args["c"] = np.where(np.arange(2000) % 7 == 0, 0.0, args["c"])
    got = compiled.stability(args, 2000, ())["mass_ok"]
    want = engine.numpy_stability(args, 2000)["mass_ok"]
    np.testing.assert_array_equal(got, want)
    assert (~got).sum() >= 2000 // 7


def test_the_weave_kernel_agrees_with_the_numpy_quartic():
    args = _designs(3000, 0.5, 5)
    speeds = np.random.default_rng(6).uniform(0.0, 12.0, 7)  # off the speeds where the weave pair is born
    got = compiled.weave_eigenvalues(args, 3000, speeds)
    want = engine.numpy_weave(args, 3000, speeds)
    error = np.abs(got - want) / np.maximum(1.0, np.abs(want))
    assert error.max() < 1e-12


def test_threads_split_the_work_without_changing_it(random_designs):
    n = random_designs["w"].size
    one = compiled.stability(random_designs, n, SPEEDS, threads=1)
    three = compiled.stability(random_designs, n, SPEEDS, threads=3)
    buffers = compiled.stability_outputs(n, SPEEDS.size)
    compiled.stability({k: v[::-1] for k, v in random_designs.items()}, n, SPEEDS, out=buffers)  # other values first
    reused = compiled.stability(random_designs, n, SPEEDS, out=buffers)
    for key in one:
        np.testing.assert_array_equal(one[key], three[key], err_msg=key)
        np.testing.assert_array_equal(one[key], reused[key], err_msg=key)
    with pytest.raises(ValueError, match="ascending"):
        compiled.stability(random_designs, n, SPEEDS[::-1])


def test_the_generator_and_the_runtime_use_one_quartic():
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from bikerider.generated import design_kernels
    from bikerider.generated.manifest import KERNELS

    from bikerider.benchmark import quartic
    from derive import kernels

    assert kernels.NEWTON_STEPS == quartic.NEWTON_STEPS
    assert compiled.ARGUMENTS == tuple(kernels.arguments()) == KERNELS["design_kernels.bikerider_stability"]["args"]
    assert "step < 2;" in design_kernels.C_SOURCE
