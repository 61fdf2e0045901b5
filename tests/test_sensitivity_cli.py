"""``bikerider sensitivity``: ranking, closed forms, LaTeX, other inputs, Monte Carlo, errors."""

from __future__ import annotations

from importlib import resources

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
    status, _, err = run(capsys, "xB", "--rider", "r.toml")
    assert status == 2 and "--bicycle" in err


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
