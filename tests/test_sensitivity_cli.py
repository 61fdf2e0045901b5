"""``bikerider sensitivity``: ranking, closed forms, LaTeX, other inputs, Monte Carlo, errors."""

from __future__ import annotations

import math
from importlib import resources

import pytest

from bikerider.cli import main

BROWSER = str(resources.files("bikerider") / "data/bicycleparameters/bicycles/Browser/Parameters/BrowserBenchmark.txt")


def run(capsys, *argv):
    status = main(["sensitivity", *argv])
    out = capsys.readouterr()
    return status, out.out, out.err


def test_ranking_of_the_capsize_speed_names_the_most_important_measurement(capsys):
    status, out, _ = run(capsys, "capsize_speed", "--top", "5")
    assert status == 0
    assert "v_capsize" in out and "first-order sigma" in out
    rows = [line.split() for line in out.splitlines() if line[:1].isdigit()]
    assert len(rows) == 5 and rows[0][1] == "T_Fyy"
    assert "Measurement that matters most: T_Fyy" in out
    assert "assumed" in out or "stated" in out


def test_closed_form_with_respect_to_an_input(capsys):
    status, out, _ = run(capsys, "M_phiphi", "--wrt", "mH")
    assert status == 0
    assert "dM_phiphi/dmH = zH**2" in out
    assert "value at the inputs: 0.6084" in out  # z_H^2 with z_H = -0.78 m (Table 3)


def test_latex_uses_the_symbol_table(capsys):
    status, out, _ = run(capsys, "xB", "--wrt", "xBf", "--latex")
    assert status == 0
    assert r"\frac{d x_B}{d x_{Bf}}" in out and r"m_{Bf}" in out


def test_speed_derivative_prints_its_condition(capsys):
    status, out, _ = run(capsys, "weave_speed", "--wrt", "IHxz")
    assert status == 0
    assert "F[v_weave]" in out and "root of F = 0" in out


def test_benchmark_file_inputs_and_monte_carlo(capsys):
    status, out, _ = run(capsys, "weave_speed", "--inputs", BROWSER, "--monte-carlo", "4000")
    assert status == 0
    assert "BrowserBenchmark.txt" in out and "Monte Carlo, 4000 input sets" in out
    assert "agree" in out


def test_bad_names_exit_2_with_a_message(capsys):
    status, _, err = run(capsys, "weave_sped")
    assert status == 2 and "OUTPUT = 'weave_sped'" in err
    status, _, err = run(capsys, "xB", "--wrt", "nothing")
    assert status == 2 and "--wrt = 'nothing'" in err
    status, _, err = run(capsys, "w")
    assert status == 2 and "a computed quantity" in err
    status, _, err = run(capsys, "xB", "--rider", "r.toml")  # --rider alone: on the paper's bicycle
    assert status == 2 and "r.toml: no such file" in err
    status, _, err = run(capsys, "xB", "--inputs", "x.txt", "--no-rider")
    assert status == 2 and "--no-rider" in err and "--inputs" in err


def test_no_rider_is_the_bicycle_alone_as_estimate_has_it(capsys):
    """issue 12: sensitivity had no --no-rider; the bicycle alone matches `estimate --no-rider`."""
    from bikerider.estimate import estimate_from_files, estimate_uncertainty
    from bikerider.io.chain_inputs import paper_files

    bicycle, _ = paper_files()
    alone = estimate_uncertainty(estimate_from_files(bicycle, with_rider=False))
    for argv in (["--no-rider"], ["--bicycle", str(bicycle)]):
        status, out, _ = run(capsys, "weave_speed", *argv, "--top", "2")
        assert status == 0 and "(no rider)" in out.splitlines()[0]
        headline = next(line for line in out.splitlines() if line.startswith("v_weave"))
        assert f"= {alone.values['v_weave']:.4f} m/s, first-order sigma {alone.sigmas['v_weave']:.3g} m/s" in headline
        assert ("Note: no --rider given: the bicycle alone" in out) == (argv[0] == "--bicycle")


@pytest.mark.parametrize(
    "typed, node, per_degree",
    [
        ("lam_ht_deg", "lam_ht", True),
        ("compound_period", "T_Fyy", False),  # the paper's rear wheel gives I_yy itself: one compound period
        ("front_wheel.mass", "mF", False),
        ("rear_frame.inertia.periods.2", "T_Bf2", False),
        ("lam_fl_deg", "lam_fl", True),
    ],
)
def test_wrt_takes_the_keys_of_the_toml_files(capsys, typed, node, per_degree):
    """issue 12: --wrt refused lam_ht_deg and compound_period, the names users type."""
    status, out, _ = run(capsys, "weave_speed", "--wrt", typed)
    assert status == 0
    assert f"d v_weave / d {node}" in out and f"Note: --wrt {typed} is the input {node}" in out
    value = float(next(line for line in out.splitlines() if line.startswith("value at the inputs")).split()[4])
    if per_degree:  # the closed form stays per radian; the degree a user typed gets its own line
        line = next(line for line in out.splitlines() if line.startswith(f"per degree of {typed}"))
        assert float(line.split()[4]) == pytest.approx(value * math.pi / 180, rel=1e-5)


def test_wrt_key_that_names_several_inputs_lists_them(capsys):
    status, _, err = run(capsys, "weave_speed", "--wrt", "mass")
    assert status == 2 and "--wrt = 'mass'" in err
    for node in ("mR", "mF", "mBf", "mH", "mBr"):
        assert f"({node})" in err


def test_bicycle_and_rider_files_without_rider_sigmas(capsys):
    from bikerider.io.chain_inputs import paper_files

    bicycle, rider = paper_files()
    status, out, _ = run(capsys, "xB", "--bicycle", str(bicycle), "--rider", str(rider), "--no-rider-sigmas")
    assert status == 0
    assert "assumed" not in out
    rows = {line.split()[1]: line for line in out.splitlines() if line[:1].isdigit()}
    assert "l_to" in rows and " 0.0% " in rows["l_to"]  # rider lengths are exact: no share of the variance
    # the seat tube angle (0.5 deg, Table 1) places the 72 kg rider's hip: it leads x_B
    assert rows["lam_st"].split()[0] == "1"


def test_characteristic_coefficients_need_a_speed(capsys):
    status, _, err = run(capsys, "a0")
    assert status == 2 and "--speed = missing" in err
    status, out, _ = run(capsys, "a0", "--speed", "5", "--top", "3")
    assert status == 0 and "a0 (coefficient of s^0" in out


def test_every_value_of_the_paper_files_has_its_toml_path():
    """names.TOML_PATHS (what --wrt accepts) against the files the readers read."""
    import tomllib

    from bikerider.io.chain_inputs import paper_files, raw_inputs_from_toml
    from bikerider.uncertainty.names import TOML_PATHS

    bicycle, rider = paper_files()
    inputs = raw_inputs_from_toml(bicycle, rider)

    def leaves(table, prefix=""):
        for key, value in table.items():
            path = f"{prefix}{key}"
            if isinstance(value, dict):
                yield from leaves(value, path + ".")
            elif isinstance(value, list):
                yield from (f"{path}.{i}" for i in range(1, len(value) + 1))
            elif key not in ("name", "source"):
                yield path

    paths = [p for f in (bicycle, rider) for p in leaves(tomllib.loads(f.read_text()))]
    assert len(paths) > 40
    for path in paths:
        assert TOML_PATHS.get(path) in inputs, path
