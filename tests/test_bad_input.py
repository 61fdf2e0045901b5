"""Bad input gets a clear error naming the measurement, its value and what was expected."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from bikerider.benchmark import BenchmarkParameters
from bikerider.bicycle import BicycleBodies
from bikerider.bicycle.pendulum import compound_inertia, inertia_from_orientations
from bikerider.errors import FileFormatError, InputError, ReachError
from bikerider.estimate import default_files, estimate
from bikerider.io.toml_input import load_bicycle_toml, load_rider_toml
from bikerider.quantity import Quantity, parse_quantity
from bikerider.rider import RiderMeasurements, seat_rider


@pytest.fixture(scope="module")
def paper():
    bicycle_path, rider_path = default_files()
    return load_bicycle_toml(bicycle_path), load_rider_toml(rider_path)


def _rider_with(rider: RiderMeasurements, **changes) -> RiderMeasurements:
    values = dict(rider.values)
    values.update({k: Quantity(v) for k, v in changes.items()})
    return replace(rider, values=values)


def test_legs_too_short_name_the_distance_needed(paper):
    bicycle, rider = paper
    with pytest.raises(ReachError) as info:
        seat_rider(bicycle, _rider_with(rider, l_ll=0.30, l_ul=0.30))
    message = str(info.value)
    assert "l_ll + l_ul" in message and "0.6" in message and "pedals" in message
    assert "0.770 m" in message  # hip to pedal axis on the paper's Browser (limb_reach)


def test_arms_too_short_name_the_distance_needed(paper):
    bicycle, rider = paper
    with pytest.raises(ReachError, match=r"l_ua \+ l_la.*grips"):
        seat_rider(bicycle, _rider_with(rider, l_ua=0.20, l_la=0.20))


@pytest.mark.parametrize("name", ["mR", "mBf", "mH"])
def test_non_positive_masses(paper, name):
    bicycle, _ = paper
    values = dict(bicycle.values)
    values[name] = Quantity(-1.0)
    with pytest.raises(InputError, match=rf"{name} = -1: expected a positive value"):
        BicycleBodies(values, "test")


def test_zero_rider_mass(paper):
    _, rider = paper
    with pytest.raises(InputError, match="mBr = 0"):
        _rider_with(rider, mBr=0.0)


def test_impossible_angles(paper):
    bicycle, _ = paper
    values = dict(bicycle.values)
    values["lam_ht"] = Quantity(math.radians(200))
    with pytest.raises(InputError, match="lam_ht_deg = 200"):
        BicycleBodies(values, "test")
    with pytest.raises(InputError, match="steer axis tilt"):
        BenchmarkParameters.from_mapping({**_benchmark(), "lam": 2.0})


def _benchmark() -> dict[str, float]:
    return dict(
        w=1.02,
        c=0.08,
        lam=math.pi / 10,
        g=9.81,
        rR=0.3,
        mR=2.0,
        IRxx=0.0603,
        IRyy=0.12,
        xB=0.3,
        zB=-0.9,
        mB=85.0,
        IBxx=9.2,
        IByy=11.0,
        IBzz=2.8,
        IBxz=2.4,
        xH=0.9,
        zH=-0.7,
        mH=4.0,
        IHxx=0.05892,
        IHyy=0.06,
        IHzz=0.00708,
        IHxz=-0.00756,
        rF=0.35,
        mF=3.0,
        IFxx=0.1405,
        IFyy=0.28,
    )


def test_pendulum_angles_that_leave_eq6_singular():
    periods = [Quantity(3.6), Quantity(3.4), Quantity(2.5)]
    angles = [Quantity(math.radians(a)) for a in (41, 81, 221)]  # 41 and 221 deg: the same axis
    with pytest.raises(InputError, match=r"rear_frame.inertia.alpha_deg.*singular"):
        inertia_from_orientations(Quantity(5.01), periods, angles, "rear_frame")


def test_too_few_orientations():
    with pytest.raises(InputError, match="at least three"):
        inertia_from_orientations(Quantity(5.01), [Quantity(3.6)] * 2, [Quantity(0.1), Quantity(1.0)], "rear_frame")


def test_compound_period_too_short_for_a_positive_inertia():
    with pytest.raises(InputError, match="compound_period = 0.5: expected more than 1.10"):
        compound_inertia(Quantity(0.5), Quantity(2.0), Quantity(0.303), Quantity(9.81))


def test_inertia_tensor_violating_triangle_inequality():
    with pytest.raises(InputError, match="triangle inequality"):
        BenchmarkParameters.from_mapping({**_benchmark(), "IBxx": 1.0, "IBzz": 1.0, "IBxz": 0.0, "IByy": 5.0})
    with pytest.raises(InputError, match="positive definite"):
        BenchmarkParameters.from_mapping({**_benchmark(), "IBxz": 6.0})


def test_missing_fields(tmp_path):
    path = tmp_path / "bike.toml"
    bicycle_path, _ = default_files()
    text = bicycle_path.read_text().replace('w = "1.120 +/- 0.002"         # wheelbase\n', "")
    path.write_text(text)
    with pytest.raises(InputError, match=r"geometry.w = missing"):
        load_bicycle_toml(path)
    with pytest.raises(InputError, match=r"IFyy = missing: expected a value"):
        BenchmarkParameters.from_mapping({k: v for k, v in _benchmark().items() if k != "IFyy"})


def test_malformed_toml_names_file_and_line(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[geometry]\nw = = 1\n")
    with pytest.raises(FileFormatError, match=r"bad.toml:2"):
        load_bicycle_toml(path)


def test_quantity_parsing():
    assert parse_quantity("0.79 +/- 0.06", "T") == Quantity(0.79, 0.06)
    assert parse_quantity({"value": 1, "sigma": 0.1}, "x") == Quantity(1.0, 0.1)
    for bad in ("nan", "inf", "1 +/- -2", True, "abc", [1]):
        with pytest.raises(InputError):
            parse_quantity(bad, "x")


def test_input_files_are_not_written(paper, tmp_path):
    bicycle_path, rider_path = default_files()
    before = bicycle_path.read_bytes(), rider_path.read_bytes()
    estimate(*paper)
    assert (bicycle_path.read_bytes(), rider_path.read_bytes()) == before


def _bicycle_with_com_lines(tmp_path, lines: str):
    bicycle_path, _ = default_files()
    text = bicycle_path.read_text().replace(
        'com = { x = "0.25 +/- 0.02", z = "-0.62 +/- 0.02" }', f"com = {{ lines = [{lines}] }}"
    )
    path = tmp_path / "lines.toml"
    path.write_text(text)
    return load_bicycle_toml(path)


def test_centre_of_mass_from_hanging_lines(tmp_path):
    # Three lines through (0.25, -0.62) at 41, 81 and 150 degrees (the paper's Table 4 angles).
    lines = ", ".join(
        f"{{ point = [{0.25 + 0.3 * math.cos(math.radians(a))}, {-0.62 - 0.3 * math.sin(math.radians(a))}], "
        f'angle_deg = "{a} +/- 1" }}'
        for a in (41, 81, 150)
    )
    bicycle = _bicycle_with_com_lines(tmp_path, lines)
    assert bicycle["xBf"] == pytest.approx(0.25, abs=1e-12)
    assert bicycle["zBf"] == pytest.approx(-0.62, abs=1e-12)
    assert 0 < bicycle.get("xBf").sigma < 0.02  # one degree on lines 0.3 m from the point


def test_hanging_lines_that_do_not_meet(tmp_path):
    from bikerider.errors import FitError

    lines = (
        "{ point = [0.25, -0.62], angle_deg = 41 }, { point = [0.25, -0.62], angle_deg = 81 }, "
        "{ point = [0.45, -0.62], angle_deg = 150 }"
    )
    with pytest.raises(FitError, match=r"rear_frame.com.*do not meet"):
        _bicycle_with_com_lines(tmp_path, lines)
