"""Readers of gap data, the project's copies of published data, and the weave extraction."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import bikerider
from bikerider.errors import FileFormatError, FitError, InputError
from bikerider.gap.measured.extraction import weave_eigenvalue
from bikerider.gap.measured.records import fit_record
from bikerider.io import gap_data as gd
from bikerider.io.gap_model import load_model

DATA = Path(bikerider.__file__).parent / "data"
GAP = DATA / "gap"
EXAMPLES = DATA / "gap_examples"


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# -- eigenvalues ---------------------------------------------------------------------------------
def test_eigenvalue_file_with_comments_gains_and_defaults(tmp_path):
    path = _write(
        tmp_path,
        "e.csv",
        "# group = dayA\n# k_phid = 1.5\nspeed,real,imag,real_sigma,imag_sigma,mode\n"
        "4.0,-0.5,3.0,0.1,0.2,\n5.0,-2.0,0,0.1,,\n",
    )
    e = gd.read_eigenvalues(path)
    assert e.speed.tolist() == [4.0, 5.0]
    assert e.value[0] == complex(-0.5, 3.0)
    assert e.mode == ["weave", "auto"]
    assert e.group == ["dayA", "dayA"]
    assert e.gains[:, 1].tolist() == [1.5, 1.5]
    assert e.law == ["k_phid = 1.5", "k_phid = 1.5"]  # constant gains are a law named by its gains
    assert math.isnan(e.imag_sigma[1])
    assert e.sigma_source == ["stated", "none"]
    assert e.source[1].endswith("e.csv:5")


@pytest.mark.parametrize(
    "text, message, line",
    [
        ("speed,real,imag\n4.0,-0.5\n", "expected 3 comma-separated values", 2),
        ("speed,real,imag\n4.0,abc,1\n", "real = 'abc': expected a number", 2),
        ("speed,real,imag\n4.0,nan,1\n", "real = nan: expected a finite number", 2),
        ("speed,real,imag\n4.0,1,inf\n", "imag = inf: expected a finite number", 2),
        ("speed,real,imag\n-3.0,1,1\n", "speed = -3.0: expected a positive number", 2),
        ("speed,real,imag\n0,1,1\n", "speed = 0: expected a positive number", 2),
        ("speed,real,imag,real_sigma\n3,1,1,-0.1\n", "real_sigma = -0.1: expected a positive number", 2),
        ("speed,real,imag,colour\n3,1,1,red\n", "unknown column 'colour'", 1),
        ("speed,real\n3,1\n", "missing column 'imag'", 1),
        ("speed,real,imag,mode\n3,1,1,capsize\n", "only the weave mode oscillates", 2),
        ("speed,real,imag,mode\n3,1,0,wobble\n", "mode = 'wobble'", 2),
        ("# nothing\n", "no header line", None),
    ],
)
def test_malformed_eigenvalue_files_name_file_and_line(tmp_path, text, message, line):
    path = _write(tmp_path, "bad.csv", text)
    with pytest.raises(FileFormatError) as info:
        gd.read_eigenvalues(path)
    assert message in str(info.value)
    assert str(path) in str(info.value)
    assert info.value.line == line


def test_missing_file_is_a_file_format_error(tmp_path):
    with pytest.raises(FileFormatError, match="no such file"):
        gd.read_eigenvalues(tmp_path / "absent.csv")


# -- perturbation runs ------------------------------------------------------------------------
def _run(omega=3.0, sigma=0.8, capsize=-0.3, noise=0.005, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(0.3, 6.0, 0.01)
    y = (
        0.3 * np.exp(-sigma * t) * np.sin(omega * t + 0.4)
        + 0.08 * np.exp(capsize * t)
        + noise * rng.standard_normal(t.size)
    )
    return t, y


def test_weave_extraction_with_a_capsize_mode_is_unbiased():
    # a damped oscillation plus a real mode: the two-mode fit finds -sigma + i omega within a few
    # standard errors, where a drift stand-in for the real mode is off by many
    from bikerider.fitting.damped_oscillation import fit_damped_oscillation

    t, y = _run()
    est = weave_eigenvalue(t, y)
    assert abs(est.eigenvalue.real + 0.8) < 4 * est.real_sigma
    assert abs(est.eigenvalue.imag - 3.0) < 4 * est.imag_sigma
    assert est.extra_mode == pytest.approx(-0.3, abs=0.05)
    plain = fit_damped_oscillation(t, y, drift=True)
    assert abs(plain.eigenvalue.imag - 3.0) > 4 * plain.omega_d_se  # the bias the refinement removes


def test_weave_extraction_refuses_noise():
    rng = np.random.default_rng(1)
    t = np.arange(0, 5, 0.01)
    with pytest.raises(FitError):
        weave_eigenvalue(t, 0.01 * rng.standard_normal(t.size))


def test_perturbation_file_gives_one_record_and_its_weave(tmp_path):
    t, y = _run(seed=2)
    text = "# speed = 6.5\n# group = r1\ntime,roll_rate\n" + "\n".join(f"{a:.3f},{b:.6f}" for a, b in zip(t, y))
    run = gd.read_perturbation(_write(tmp_path, "run.csv", text))
    assert run.speed == 6.5 and run.group == "r1" and run.law.is_zero
    fit = fit_record(run)
    assert fit.used and abs(fit.estimate.eigenvalue - complex(-0.8, 3.0)) < 0.05
    assert 0.9 < fit.estimate.r2 <= 1 and fit.estimate.cycles > 2


def test_perturbation_speed_column_and_errors(tmp_path):
    t, y = _run(seed=3)
    text = "time,roll_rate,speed\n" + "\n".join(
        f"{a:.3f},{b:.6f},{5 + 0.01 * (k % 3)}" for k, (a, b) in enumerate(zip(t, y))
    )
    run = gd.read_perturbation(_write(tmp_path, "run.csv", text))
    assert run.speed == pytest.approx(5.01, abs=0.001)
    assert run.speed_sigma > 0
    no_speed = _write(tmp_path, "nospeed.csv", "time,roll_rate\n" + "\n".join(f"{a},{b}" for a, b in zip(t, y)))
    with pytest.raises(FileFormatError, match="no speed"):
        gd.read_perturbation(no_speed)
    with pytest.raises(InputError, match="speed"):
        gd.read_perturbation(no_speed, speed=-1.0)
    # a stamp going back is a logger's, repaired when the record is fitted (bikerider.gap.measured.repair) ...
    backwards = _write(tmp_path, "back.csv", "# speed = 5\ntime,roll_rate\n0.0,0.1\n0.2,0.2\n0.1,0.3\n")
    assert gd.read_perturbation(backwards).time.tolist() == [0.0, 0.2, 0.1]
    # ... but a time that never advances is no time series
    still = _write(tmp_path, "still.csv", "# speed = 5\ntime,roll_rate\n1.0,0.1\n1.0,0.2\n1.0,0.3\n")
    with pytest.raises(FileFormatError, match="time = 1 throughout: expected increasing time stamps"):
        gd.read_perturbation(still)


def test_a_run_of_noise_is_left_out_with_its_reason(tmp_path):
    # before: read_perturbation raised FitError and the whole diagnosis stopped
    noisy = _write(
        tmp_path,
        "noise.csv",
        "# speed = 5\ntime,roll_rate\n"
        + "\n".join(
            f"{a:.2f},{b:.5f}"
            for a, b in zip(np.arange(0, 5, 0.01), 0.01 * np.random.default_rng(0).standard_normal(500))
        ),
    )
    fit = fit_record(gd.read_perturbation(noisy))
    assert not fit.used and "no oscillation" in fit.reason


def test_example_perturbation_run_is_read():
    fit = fit_record(gd.read_perturbation(EXAMPLES / "perturbation_run.csv"))
    assert fit.record.speed == 7.0
    assert fit.used and fit.estimate.eigenvalue.imag > 0 and fit.estimate.real_sigma > 0


# -- identified canonical entries ---------------------------------------------------------------
def test_moore_copy_is_read_and_lateral_force_rows_left_out():
    c = gd.read_canonical(GAP / "moore2012_canonical_id.csv", groups=["J-P"])
    assert len(c) == 8  # Moore (2012) Tables 11.2-11.9 identify 8 matrix entries per subset (+ H_deltaF)
    assert c.speed_range["J-P"] == (1.5, 9.0)
    k = c.entry.index("C1_deltaphi")
    assert c.value[k] == -1.09 and c.sigma[k] == 0.01  # J-P, C1deltaphi = -1.09 +/- 0.01 (Table 11.x)


def test_canonical_file_errors(tmp_path):
    head = "rider,environment,coefficient,identified,sigma\n"
    with pytest.raises(FileFormatError, match="no speed range"):
        gd.read_canonical(_write(tmp_path, "a.csv", head + "J,P,Mphidelta,2.5,0.02\n"))
    with pytest.raises(FileFormatError, match="sigma = 0"):
        gd.read_canonical(
            _write(tmp_path, "b.csv", "# speed_min = 1\n# speed_max = 5\n" + head + "J,P,Mphidelta,2.5,0\n")
        )
    with pytest.raises(FileFormatError, match="speed_max = 1.0 is not above"):
        gd.read_canonical(
            _write(tmp_path, "c.csv", "# speed_min = 2\n# speed_max = 1\n" + head + "J,P,Mphidelta,2.5,1\n")
        )


def test_control_file(tmp_path):
    laws = gd.read_control(EXAMPLES / "control.toml")
    (law,) = laws.values()
    assert law([3.0, 6.0]).tolist() == [[0.0, 5.0, -2.0, -0.5]] * 2
    with pytest.raises(InputError, match="k_roll"):
        gd.read_control(_write(tmp_path, "c.toml", "[control]\nk_roll = 1\n"))


def test_kind_detection(tmp_path):
    assert gd.detect_kind(EXAMPLES / "eigenvalues.csv") == "eigenvalues"
    assert gd.detect_kind(EXAMPLES / "perturbation_run.csv") == "perturbation"
    assert gd.detect_kind(EXAMPLES / "canonical.csv") == "canonical"
    with pytest.raises(FileFormatError, match="cannot tell"):
        gd.detect_kind(_write(tmp_path, "x.csv", "a,b\n1,2\n"))


# -- the project's copy of Kooijman et al. (2008) -------------------------------------------------
def test_kooijman_bicycle_reproduces_their_equation_5():
    from bikerider.benchmark import WhippleModel

    model = load_model(GAP / "kooijman2008_bicycle.toml")
    w = WhippleModel.from_parameters(model.parameters)
    # Kooijman, Schwab, Meijaard (2008) Multibody Syst Dyn 19:115, Eq. (5) (K0 there includes g)
    np.testing.assert_allclose(w.M, [[7.98981, 0.89569], [0.89569, 0.29857]], atol=6e-6)
    np.testing.assert_allclose(w.C1, [[0, 7.17025], [-0.59389, 1.3261]], atol=6e-6)
    np.testing.assert_allclose(9.81 * w.K0, [[-109.91168, -13.45745], [-13.45745, -4.82272]], atol=6e-6)
    np.testing.assert_allclose(w.K2, [[0, 11.19798], [0, 1.422]], atol=6e-6)
    # ... and its weave and capsize speeds, 4.0 and 7.9 m/s as the paper reports them (1 decimal)
    speeds = w.critical_speeds()
    assert speeds.weave == pytest.approx(4.0, abs=0.05) and speeds.capsize == pytest.approx(7.9, abs=0.05)
    assert model.geometry.upper_body is None


def test_model_file_errors(tmp_path):
    with pytest.raises(FileFormatError, match="no such file"):
        load_model(tmp_path / "absent.toml")
    bad = _write(tmp_path, "m.toml", "[benchmark]\nw = 1.0\n\n[grips]\nx_grip = 0.8\n")
    with pytest.raises(InputError):
        load_model(bad)
    text = (GAP / "kooijman2008_bicycle.toml").read_text() + "\n[upper_body]\nm_u = 1.0\n"
    with pytest.raises(InputError, match="upper_body.x_u"):
        load_model(_write(tmp_path, "k.toml", text))
