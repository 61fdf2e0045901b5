"""Bicycle (and lumped rider) to benchmark parameters: the closed-form uncertainties against central differences.

``bicycle_benchmark_parameters`` takes the rear body's sigmas from the generated closed-form
Jacobian of Eqs. 15-16 at the nominal point (the uncertainty engine).  The reference here is
independent of that: the generated rear-body *values* differentiated numerically by the tests'
oracle ``measured_oracle.propagate`` (central differences at ``2 k + 1`` points).

Tolerance of the sigmas: the central differences step each input by ``h = 1e-6 max(|x|, sigma)``.
Their truncation error is ``h^2 f''' / 6``, about 1e-12 relative; their round-off is about
``eps |f| / h``, i.e. ``2e-10 |f| / (|x| |f'|)`` relative to a slope ``f'``: a few 1e-9 for these
bicycles, 2e-7 at worst among BicycleParameters' (Silver, whose rear body's ``I_zz`` moves by only
1.7e-5 kg m^2 per kg of rider).  So the two routes must agree to 1e-6 relative; values are the same
generated expressions at the same point and agree to round-off.
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import pytest
from bikerider.generated import combination
from measured_oracle import propagate

from bikerider.benchmark.parameters import BENCHMARK_NAMES, BenchmarkParameters
from bikerider.bicycle.bodies import BicycleBodies
from bikerider.bicycle.to_benchmark import RIDER_BODY_NAMES, LumpedRider, bicycle_benchmark_parameters
from bikerider.io.bicycleparameters import merge_rider, read_benchmark_file, read_lumped_rider, read_measured_file
from bikerider.quantity import Quantity

DATA = Path(str(resources.files("bikerider") / "data" / "bicycleparameters"))
JASON = DATA / "riders" / "Jason" / "Parameters" / "JasonBrowserBenchmark.txt"
FRAME = ("mBf", "xBf", "zBf", "IBfxx", "IBfyy", "IBfzz", "IBfxz")
PASS_THROUGH = (
    "w",
    "c",
    "g",
    "rR",
    "mR",
    "IRxx",
    "IRyy",
    "xH",
    "zH",
    "mH",
    "IHxx",
    "IHyy",
    "IHzz",
    "IHxz",
    "rF",
    "mF",
    "IFxx",
    "IFyy",
)


def _combine(x: dict) -> dict:
    """The benchmark values from the bodies' values and a rider's, on floats or arrays of points."""
    out = {name: x.get(name, math.nan) for name in PASS_THROUGH}
    out["lam"] = math.pi / 2 - x["lam_ht"]
    mB, xB, zB, IB = combination.rear_body(**{name: x.get(name, math.nan) for name in FRAME + RIDER_BODY_NAMES})
    out.update(mB=mB, xB=xB, zB=zB, IBxx=IB[..., 0, 0], IByy=IB[..., 1, 1], IBzz=IB[..., 2, 2], IBxz=IB[..., 0, 2])
    return out


def _central_differences(bodies: BicycleBodies, rider: LumpedRider) -> dict[str, Quantity]:
    used = PASS_THROUGH + ("lam_ht",) + FRAME
    inputs = {name: q for name, q in bodies.values.items() if name in used}
    return propagate(_combine, {**inputs, **rider.values}, vectorized=True)


def _bodies(name: str) -> BicycleBodies:
    return read_measured_file(DATA / "bicycles" / name / "RawData" / f"{name}Measured.txt").bodies


def _without(rider: LumpedRider, name: str) -> LumpedRider:
    return LumpedRider({k: q for k, q in rider.values.items() if k != name}, rider.source, rider.name)


def _with_sigmas(rider: LumpedRider) -> LumpedRider:
    """The rider with an uncertainty on every entry (the Jason file gives one on the mass alone)."""
    return LumpedRider(
        {k: Quantity(q.value, 0.01 * abs(q.value) + 1e-3) for k, q in rider.values.items()}, rider.source, rider.name
    )


RIDERS = {
    "Jason": lambda: read_lumped_rider(JASON),
    "Jason without IBryy": lambda: _without(read_lumped_rider(JASON), "IBryy"),
    "Jason with a sigma on every entry": lambda: _with_sigmas(read_lumped_rider(JASON)),
}


@pytest.mark.parametrize("bicycle", ["Browser", "Rigid"])  # Browser has no IBfyy, Rigid has one
@pytest.mark.parametrize("rider_name", sorted(RIDERS))
def test_closed_form_sigmas_agree_with_central_differences(bicycle, rider_name):
    bodies, rider = _bodies(bicycle), RIDERS[rider_name]()
    merged = bicycle_benchmark_parameters(bodies, rider)
    reference = _central_differences(bodies, rider)
    assert list(merged.values) == list(BENCHMARK_NAMES)
    for name in BENCHMARK_NAMES:
        value, expected = merged.values[name], reference[name]
        if not math.isfinite(expected.value):
            assert value is None, name
            continue
        assert value == pytest.approx(expected.value, rel=1e-12, abs=1e-15), name
        assert merged.sigmas[name] == pytest.approx(expected.sigma, rel=1e-6, abs=1e-15), name


def test_a_rider_without_iyy_leaves_only_the_rear_body_iyy_undetermined():
    bodies = _bodies("Rigid")
    assert "IBfyy" in bodies.values
    full = bicycle_benchmark_parameters(bodies, read_lumped_rider(JASON))
    partial = bicycle_benchmark_parameters(bodies, _without(read_lumped_rider(JASON), "IBryy"))
    assert full.values["IByy"] is not None and full.sigmas["IByy"] > 0
    assert partial.values["IByy"] is None and partial.sigmas["IByy"] == 0.0
    for name in BENCHMARK_NAMES:
        if name != "IByy":
            assert partial.values[name] == full.values[name], name
            assert partial.sigmas[name] == full.sigmas[name], name
            assert math.isfinite(partial.sigmas[name]), name
    # Eq. 15, mB = mBf + mBr: its sigma is the two masses' in quadrature
    rider_mass = read_lumped_rider(JASON).values["mBr"]
    assert partial.sigmas["mB"] == pytest.approx(math.hypot(bodies.values["mBf"].sigma, rider_mass.sigma), rel=1e-12)


@pytest.mark.parametrize("bicycle", ["Browser", "Rigid"])
def test_without_a_rider_every_value_passes_through(bicycle):
    bodies = _bodies(bicycle)
    params = bicycle_benchmark_parameters(bodies)
    frame = dict(zip(("mB", "xB", "zB", "IBxx", "IByy", "IBzz", "IBxz"), FRAME))
    for name in BENCHMARK_NAMES:
        if name == "lam":
            lam_ht = bodies.values["lam_ht"]
            assert params.values["lam"] == math.pi / 2 - lam_ht.value
            assert params.sigmas["lam"] == lam_ht.sigma
            continue
        source = bodies.values.get(frame.get(name, name))
        if source is None:
            assert name in ("IByy", "IHyy") and params.values[name] is None, name
            continue
        assert (params.values[name], params.sigmas[name]) == (source.value, source.sigma), name


def test_merge_rider_on_benchmark_parameters_agrees_with_central_differences():
    """A Benchmark file's rear body B taken as the frame (the IByy the file left out is undetermined)."""
    from bikerider.io.bicycleparameters import bodies_from_benchmark

    parameters = read_benchmark_file(DATA / "bicycles" / "Browser" / "Parameters" / "BrowserBenchmark.txt").parameters
    rider = _with_sigmas(read_lumped_rider(JASON))
    merged = merge_rider(parameters, rider)
    assert isinstance(merged, BenchmarkParameters)
    reference = _central_differences(bodies_from_benchmark(parameters), rider)
    for name in BENCHMARK_NAMES:
        if merged.values[name] is None:
            assert not math.isfinite(reference[name].value), name
            continue
        assert merged.values[name] == pytest.approx(reference[name].value, rel=1e-12, abs=1e-15), name
        assert merged.sigmas[name] == pytest.approx(reference[name].sigma, rel=1e-6, abs=1e-15), name
