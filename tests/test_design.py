"""Design spaces, their runs into stores (chunked, resumable, on Dask), validity, summaries."""

from __future__ import annotations

import inspect
import io
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from bikerider import design
from bikerider.benchmark import WhippleModel
from bikerider.design import engine, summary, validity
from bikerider.design.progress import Progress
from bikerider.design.space import RANDOM_BLOCK
from bikerider.errors import InputError
from bikerider.shipped import named

pytest.importorskip("zarr")
ROOT = Path(__file__).resolve().parents[1]
SPEEDS = np.linspace(0.0, 10.0, 51)


@pytest.fixture(scope="module")
def bench():
    return named("Benchmark")


@pytest.fixture(scope="module")
def space(bench):
    # trail, steer axis tilt and rear-body mass: some designs impossible (mB <= 0), some never stable
    return design.grid(
        bench,
        {
            "c": np.linspace(-0.05, 0.2, 11),
            "lam": np.radians(np.linspace(-5, 40, 10)),
            "mB": np.linspace(-10.0, 120.0, 7),
        },
    )


@pytest.fixture(scope="module")
def reference(space):
    return design.explore(space, None, SPEEDS, [3.0, 6.0], engine="numpy")


def _equal_runs(a, b, rtol=0.0):
    for field in engine.FIELDS:
        x, y = a.read(field.name), b.read(field.name)
        if rtol and x.dtype.kind == "f":
            np.testing.assert_allclose(x, y, rtol=rtol, atol=rtol, equal_nan=True, err_msg=field.name)
        else:
            np.testing.assert_array_equal(x, y, err_msg=field.name)


# -- spaces -------------------------------------------------------------------------------------
def test_a_grid_is_every_combination_in_c_order(space):
    assert space.shape == (11, 10, 7) and space.size == 770
    values = space.values(0, space.size)
    c, lam, mB = np.meshgrid(*(a.values for a in space.axes), indexing="ij")
    np.testing.assert_array_equal(values["c"], c.ravel())
    np.testing.assert_array_equal(values["lam"], lam.ravel())
    np.testing.assert_array_equal(values["mB"], mB.ravel())
    part = space.values(123, 456)
    np.testing.assert_array_equal(part["lam"], lam.ravel()[123:456])


def test_random_designs_do_not_depend_on_the_chunks(bench):
    space = design.random_designs(
        bench, {"c": ("uniform", 0.0, 0.2), "mB": ("normal", 85.0, 10.0)}, 2 * RANDOM_BLOCK + 17, seed=4
    )
    whole = space.values(0, space.size)
    pieces = [space.values(a, b) for a, b in ((0, 1000), (1000, RANDOM_BLOCK + 5), (RANDOM_BLOCK + 5, space.size))]
    for name in ("c", "mB"):
        np.testing.assert_array_equal(whole[name], np.concatenate([p[name] for p in pieces]))
    assert 0.0 <= whole["c"].min() and whole["c"].max() <= 0.2
    assert whole["mB"].mean() == pytest.approx(85.0, abs=0.2)
    again = design.random_designs(
        bench, {"c": ("uniform", 0.0, 0.2), "mB": ("normal", 85.0, 10.0)}, 2 * RANDOM_BLOCK + 17, seed=4
    )
    np.testing.assert_array_equal(again.values(5, 50)["c"], whole["c"][5:50])


def test_a_space_round_trips_through_json(space, bench):
    back = design.DesignSpace.from_json(space.to_json())
    assert back.to_json() == space.to_json()
    np.testing.assert_array_equal(back.values(10, 90)["lam"], space.values(10, 90)["lam"])
    mc = design.monte_carlo(named("Browser", rider="Jason"), 100, seed=2)
    assert design.DesignSpace.from_json(mc.to_json()).values(0, 100)["mB"].tolist() == mc.values(0, 100)["mB"].tolist()


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda b: design.grid(b, {"trail": [0.1]}), "--vary = 'trail': expected one of the benchmark names"),
        (lambda b: design.grid(b, {"c": []}), "c = 'an empty range': expected at least one value"),
        (lambda b: design.grid(b, {"c": [0.1, np.nan]}), "c = .*finite values"),
        (lambda b: design.grid(b, {}), "--vary = 'nothing'"),
        (lambda b: design.grid(b, {"IByy": [1.0]}), "a base that determines IByy"),
        (lambda b: design.grid(b, {k: np.arange(1000.0) for k in ("c", "w", "mB", "mH", "mF")}), "at most 1e"),
        (
            lambda b: design.random_designs(b, {"c": ("uniform", 0.2, 0.1)}, 10),
            "c = '0.2:0.1': expected a range LOW:HIGH",
        ),
        (lambda b: design.random_designs(b, {"c": ("normal", 0.1, 0.0)}, 10), "a positive standard deviation"),
        (lambda b: design.random_designs(b, {"c": ("uniform", 0.0, 0.1)}, 0), "--random = 0"),
        (lambda b: design.monte_carlo(b, 10), "--monte-carlo = 'no uncertainties'"),
    ],
)
def test_bad_spaces_are_named(bench, make, message):
    if "IByy" in message:  # a base that leaves IByy undetermined
        from bikerider.benchmark import BenchmarkParameters

        bench = BenchmarkParameters.from_mapping({k: v for k, v in bench.values.items() if k != "IByy"}, "no IByy")
    base = bench
    with pytest.raises(InputError, match=message):
        make(base)


def test_an_unknown_measurement_is_named():
    from bikerider.estimate import estimate_default

    with pytest.raises(InputError, match="a measurement of the estimate chain"):
        design.grid(estimate_default(), {"wheelbase": [1.0]})


# -- validity -----------------------------------------------------------------------------------
def test_vectorised_validity_is_with_values(bench):
    rng = np.random.default_rng(8)
    names = [k for k in bench.values if bench.values[k] is not None and k != "g"]
    n = 600
    values = {k: np.full(n, float(v)) if v is not None else np.full(n, np.nan) for k, v in bench.values.items()}
    for i in range(n):  # two parameters of each design scaled by factors in (-2, 3): many impossible designs
        for k in rng.choice(names, 2, replace=False):
            values[k][i] *= rng.uniform(-2, 3)
    codes = validity.benchmark_reasons(values, {})
    kinds = set()
    for i in range(n):
        changes = {k: float(values[k][i]) for k in names if values[k][i] != bench.values[k]}
        try:
            bench.with_values(**changes)
            expected = None
        except InputError as exc:
            expected = (exc.name, exc.expected)
        got = validity.REASONS[codes[i]] if codes[i] else None
        if expected is None:
            assert got is None, (changes, got)
        else:
            assert got is not None and got[0] == expected[0] and expected[1].startswith(got[1].split(" (")[0]), (
                changes,
                got,
                expected,
            )
            kinds.add(got[0])
    assert len(kinds) >= 8  # masses, lengths, tilt, tensors, wheels, ... all met


def test_impossible_designs_are_reported_not_raised(reference):
    valid, reason = reference.read("valid"), reference.read("reason")
    assert (~valid).any() and valid.any()
    texts = set(reference.reason_texts(reason[~valid]))
    assert "mB: expected a positive value" in texts
    assert np.all(reason[valid] == 0) and np.all(reason[~valid] > 0)
    assert np.isnan(reference.read("weave_speed")[~valid]).all()
    assert not reference.stable()[~valid].any()


def test_valid_designs_equal_one_bicycle_at_a_time(reference, space, bench):
    values = space.values(0, space.size)
    rng = np.random.default_rng(3)
    stable = reference.stable()
    lower, upper = reference.read("lower"), reference.read("upper")
    for i in rng.choice(np.flatnonzero(reference.read("valid")), 25, replace=False):
        model = WhippleModel.from_parameters(bench.with_values(**{k: float(v[i]) for k, v in values.items()}))
        one = model.stability()
        got = [(a, b) for a, b in zip(lower[i], upper[i]) if np.isfinite(a)]
        assert len(got) == len(one.intervals)
        for (a, b), interval in zip(got, one.intervals):
            assert a == pytest.approx(interval.lower, rel=1e-12) and b == pytest.approx(interval.upper, rel=1e-12)
        np.testing.assert_array_equal(stable[i], one.is_stable(SPEEDS))


def test_the_map_equals_a_dense_eigenvalue_scan(reference, space, bench):
    from bikerider.generated import benchmark_model as gen

    values = space.values(0, space.size)
    valid = reference.read("valid")
    names = inspect.signature(gen.canonical_matrices).parameters
    args = {
        k: np.where(valid, values[k], float(bench.values[k])) if k in values else float(bench.values[k]) for k in names
    }
    model = WhippleModel(*gen.canonical_matrices(**args), g=9.81)
    scan = (np.linalg.eigvals(model.state_matrix(SPEEDS)).real < 0).all(axis=-1) & valid[:, None]
    stable = reference.stable()
    lower, upper = reference.read("lower"), reference.read("upper")
    ends = np.concatenate([lower, upper], axis=-1)
    near_an_end = (np.abs(SPEEDS[None, :, None] - ends[:, None, :]) < 1e-6).any(axis=-1)
    assert np.array_equal(stable[~near_an_end], scan[~near_an_end])


def test_a_measurement_space_goes_through_the_whole_estimate():
    from bikerider.estimate import estimate_default

    paper = estimate_default()
    l_sp = float(paper.chain_inputs["l_sp"].value)
    # the paper's rider has nearly straight arms: a seat post 5 cm longer and his hands leave the grips
    space = design.grid(paper, {"l_sp": [l_sp - 0.05, l_sp, l_sp + 0.05, 5.0], "mBr": [60.0, 72.0, -1.0]})
    result = design.explore(space, None, SPEEDS)
    valid = result.read("valid").reshape(4, 3)
    assert valid[:2, :2].all() and not valid[2:].any() and not valid[:, 2].any()
    texts = result.reason_texts(result.read("reason"))
    assert texts[2] == "mBr: expected a positive value"
    assert texts[6].startswith("l_ua + l_la: expected at least the distance from the shoulder")
    assert texts[9].startswith("l_ll + l_ul: expected at least the distance from the hip")  # a 5 m seat post
    at_base = np.flatnonzero((space.values(0, 12)["l_sp"] == l_sp) & (space.values(0, 12)["mBr"] == 72.0))[0]
    speeds = paper.model.critical_speeds()
    assert result.read("weave_speed")[at_base] == pytest.approx(speeds.weave, rel=1e-10)
    assert result.read("capsize_speed")[at_base] == pytest.approx(speeds.capsize, rel=1e-10)
    assert np.all(np.isfinite(result.read("weave_speed").reshape(4, 3)[:2, :2]))


# -- runs and stores ----------------------------------------------------------------------------
def test_chunks_engines_and_threads_give_the_same_run(space, reference, tmp_path):
    whole = design.explore(space, tmp_path / "a", SPEEDS, [3.0, 6.0], chunk_size=space.size, engine="compiled")
    pieces = design.explore(space, tmp_path / "b", SPEEDS, [3.0, 6.0], chunk_size=97, engine="compiled", threads=2)
    _equal_runs(whole, pieces)
    _equal_runs(whole, reference, rtol=1e-9)  # compiled and NumPy (tests/test_design_kernels.py: the exact bound)
    np.testing.assert_array_equal(whole.stable(), reference.stable())
    assert whole.complete and sorted(os.listdir(tmp_path / "b" / "done"), key=int) == [str(k) for k in range(8)]


def test_a_store_opens_again_and_refuses_another_run(space, tmp_path, bench):
    first = design.explore(space, tmp_path / "s", SPEEDS, chunk_size=100)
    again = design.open_store(tmp_path / "s")
    _equal_runs(first, again)
    assert again.spec.space.to_json() == space.to_json()
    other = design.grid(bench, {"c": np.linspace(0, 0.1, 3)})
    with pytest.raises(InputError, match="--store = .*its space differs;"):
        design.explore(other, tmp_path / "s", SPEEDS, chunk_size=100)
    with pytest.raises(InputError, match="its chunk_size differs;"):
        design.explore(space, tmp_path / "s", SPEEDS, chunk_size=50)
    (tmp_path / "plain").mkdir()
    (tmp_path / "plain" / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match="not a bikerider design store"):
        design.explore(space, tmp_path / "plain", SPEEDS)
    restarted = design.explore(other, tmp_path / "s", SPEEDS, restart=True)
    assert restarted.spec.space.size == 3


RUN_SCRIPT = textwrap.dedent("""
    import sys
    import numpy as np
    from bikerider import design
    from bikerider.shipped import named
    space = design.grid(named("Benchmark"), {"c": np.linspace(-0.05, 0.2, 30), "lam": np.linspace(-0.1, 0.7, 20),
                                             "mB": np.linspace(-10.0, 120.0, 40)})
    design.explore(space, sys.argv[1], np.linspace(0, 10, 51), [5.0], chunk_size=400, engine="numpy")
""")


def test_an_interrupted_run_resumes_without_redoing_chunks(tmp_path, monkeypatch):
    store = tmp_path / "run"
    script = tmp_path / "run.py"
    script.write_text(RUN_SCRIPT)
    proc = subprocess.Popen(
        [sys.executable, str(script), str(store)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    deadline = time.monotonic() + 120
    try:
        while time.monotonic() < deadline:
            done = store / "done"
            if done.exists() and len(os.listdir(done)) >= 5:
                break
            if proc.poll() is not None:
                pytest.fail("the run finished before it could be interrupted")
            time.sleep(0.01)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait(timeout=60)
    before = set(os.listdir(store / "done"))
    assert 5 <= len(before) < 60
    namespace: dict = {}
    exec(RUN_SCRIPT.split("design.explore")[0], namespace)
    space = namespace["space"]
    calls = []
    original = engine.evaluate
    monkeypatch.setattr(engine, "evaluate", lambda s, a, b, *rest: calls.append(a) or original(s, a, b, *rest))
    resumed = design.explore(space, store, np.linspace(0, 10, 51), [5.0], chunk_size=400, engine="numpy")
    assert sorted(calls) == sorted(k * 400 for k in range(60) if str(k) not in before)
    whole = design.explore(space, tmp_path / "whole", np.linspace(0, 10, 51), [5.0], chunk_size=400, engine="numpy")
    _equal_runs(resumed, whole)


@pytest.mark.slow
def test_a_dask_local_cluster_of_two_workers_gives_the_same_run(space, reference, tmp_path):
    pytest.importorskip("dask.distributed")
    on_dask = design.explore(
        space, tmp_path / "dask", SPEEDS, [3.0, 6.0], chunk_size=128, engine="numpy", scheduler="local", workers=2
    )
    assert on_dask.complete
    _equal_runs(on_dask, reference)


def test_a_wrong_scheduler_address_is_named(space, monkeypatch):
    pytest.importorskip("dask.distributed")
    from bikerider.design import distributed

    monkeypatch.setattr(distributed, "CONNECT_TIMEOUT", "1s")
    with pytest.raises(InputError, match="--dask = 'tcp://127.0.0.1:9': expected the address of a running Dask"):
        design.explore(space, None, SPEEDS, scheduler="tcp://127.0.0.1:9")


def test_memory_is_that_of_a_chunk(tmp_path):
    """Peak memory of a subprocess running 2e5 and 8e5 designs: the same within 40 MB (bench/ measures more)."""
    script = tmp_path / "mem.py"
    script.write_text(
        textwrap.dedent("""
        import resource, sys
        import numpy as np
        from bikerider import design
        from bikerider.shipped import named
        n = int(sys.argv[2])
        space = design.grid(named("Benchmark"), {"c": np.linspace(0, 0.2, n // 1000), "mB": np.linspace(40, 120, 1000)})
        design.explore(space, sys.argv[1], np.linspace(0, 10, 101), chunk_size=50_000, engine="numpy")
        print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
    """)
    )
    peaks = []
    for n in (200_000, 800_000):
        out = subprocess.run(
            [sys.executable, str(script), str(tmp_path / f"s{n}"), str(n)], capture_output=True, text=True, check=True
        )
        peaks.append(int(out.stdout.split()[-1]) / 1024)
    assert abs(peaks[1] - peaks[0]) < 40, peaks


# -- summaries ------------------------------------------------------------------------------------
def test_the_summary_counts_what_the_arrays_say(reference, space):
    s = summary.summarize(reference)
    valid = reference.read("valid")
    lower, upper = reference.read("lower"), reference.read("upper")
    stable = ((lower < 10.0) & (upper > 0.0)).any(axis=-1) & valid
    assert (s.designs, s.valid, s.stable) == (space.size, int(valid.sum()), int(stable.sum()))
    grid_valid = valid.reshape(space.shape)
    grid_stable = stable.reshape(space.shape)
    for a, p in enumerate(s.parameters):
        other = tuple(b for b in range(3) if b != a)
        np.testing.assert_array_equal(p.valid, grid_valid.sum(axis=other))
        np.testing.assert_array_equal(p.stable, grid_stable.sum(axis=other))
    # the first-order index of the weave speed, directly
    weave = reference.read("weave_speed")
    weave = np.where(weave == lower[:, 0], weave, np.nan)  # the weave speeds that begin a stable interval
    weave = np.where((weave >= 0) & (weave <= 10), weave, np.nan).reshape(space.shape)
    good = np.isfinite(weave)
    grand = weave[good].mean()
    for a, p in enumerate(s.parameters):
        other = tuple(b for b in range(3) if b != a)
        n = good.sum(axis=other)
        means = np.nansum(weave, axis=other) / np.maximum(n, 1)
        between = np.sum(n * (means - grand) ** 2) / good.sum()
        assert p.sensitivity["weave_speed"] == pytest.approx(between / weave[good].var(), rel=1e-9)
    assert s.reasons == {"mB: expected a positive value": int((~valid).sum())}


def test_the_slice_is_the_grid_cut(reference, space):
    cut = summary.design_slice(reference, "lam", "c", {"mB": 85.0})
    k = int(np.argmin(np.abs(space.axes[2].values - 85.0)))
    weave = reference.read("weave_speed").reshape(space.shape)
    np.testing.assert_array_equal(cut.weave_speed, weave[:, :, k].T)
    assert cut.fixed == {"mB": float(space.axes[2].values[k])}
    with pytest.raises(InputError, match="--slice = 'w'"):
        summary.design_slice(reference, "w", "c")


def test_the_closest_design_to_a_weave_speed(reference):
    best = summary.closest_to_weave_speed(reference, 4.0)
    weave, lower = reference.read("weave_speed"), reference.read("lower")[:, 0]
    candidates = np.where(weave == lower, np.abs(weave - 4.0), np.inf)
    assert best.index == int(np.argmin(candidates))
    assert best.stable_intervals[0][0] == pytest.approx(best.weave_speed)
    with pytest.raises(InputError, match="--target-weave-speed"):
        summary.closest_to_weave_speed(reference, -1.0)


def test_figures_draw(reference, tmp_path):
    from bikerider.plotting import design as figures
    from bikerider.plotting.common import save_figure

    s = summary.summarize(reference)
    base = reference.spec.space.base
    for name, fig in (
        ("fraction", figures.stable_fraction_figure(s, base, "t")),
        ("sensitivity", figures.interval_sensitivity_figure(s, base, "t")),
        ("map", figures.design_slice_figure(summary.design_slice(reference, "c", "lam"), SPEEDS, "t")),
    ):
        path = save_figure(fig, tmp_path / f"{name}.png")
        assert path.stat().st_size > 10_000


# -- progress -------------------------------------------------------------------------------------
def test_the_progress_bar_shows_rate_and_time_left():
    stream = io.StringIO()
    bar = Progress(1000, done_before=500, stream=stream)
    bar.start -= 2.0  # two seconds in
    bar.update(250)
    text = bar.text()
    assert "750/1,500 designs (50%)" in text and "/s" in text and "left" in text
    bar.close()
    assert stream.getvalue().endswith("left\n")
    quiet = io.StringIO()
    silent = Progress(10, quiet=True, stream=quiet)
    silent.update(10)
    silent.close()
    assert quiet.getvalue() == ""
