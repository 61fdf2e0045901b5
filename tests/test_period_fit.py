"""Damped-oscillation fits and the ``bikerider period`` command, on synthetic signals."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from bikerider.cli import main
from bikerider.errors import FileFormatError, FitError
from bikerider.fitting.damped_oscillation import fit_damped_oscillation, period_from_trials
from bikerider.io.signal_csv import read_signal_csv


def signal(
    period,
    zeta,
    noise,
    *,
    seed=0,
    duration=12.0,
    rate=200.0,
    offset=0.02,
    amplitude=1.0,
    phase=0.7,
    drift=0.0,
    jitter=False,
):
    """Samples of offset + drift t + amplitude exp(-sigma t) sin(omega_d t + phase) + white noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1.0 / rate)
    if jitter:
        t = t + rng.uniform(-0.3, 0.3, t.size) / rate
    omega_d = 2 * math.pi / period
    sigma = zeta * omega_d / math.sqrt(1 - zeta**2)
    y = offset + drift * t + amplitude * np.exp(-sigma * t) * np.sin(omega_d * t + phase)
    return t, y + noise * rng.standard_normal(t.size), omega_d, sigma


@pytest.mark.parametrize(
    "period, zeta, noise",
    [(1.894, 0.002, 0.01), (0.4212, 0.01, 0.05), (3.42, 0.05, 0.2), (2.0, 0.3, 0.005), (0.78, 0.0, 0.1)],
)
def test_recovers_period_and_damping_within_a_few_standard_errors(period, zeta, noise):
    t, y, omega_d, sigma = signal(period, zeta, noise)
    fit = fit_damped_oscillation(t, y)
    assert abs(fit.period - period) < 4 * fit.period_se
    assert abs(fit.sigma - sigma) < 4 * fit.sigma_se + 1e-12
    assert abs(fit.zeta - zeta) < 4 * fit.zeta_se + 1e-12
    assert fit.residual_rms == pytest.approx(noise, rel=0.1)
    assert fit.eigenvalue == complex(-fit.sigma, fit.omega_d)
    assert fit.frequency == fit.omega_d
    assert fit.zeta == pytest.approx(fit.sigma / math.hypot(fit.sigma, fit.omega_d))
    assert fit.amplitude == pytest.approx(1.0, abs=5 * fit.amplitude_se)


def test_standard_errors_are_calibrated():
    """Over many noise realisations the standardised period errors have unit spread."""
    z = []
    for seed in range(30):
        t, y, _, _ = signal(1.5, 0.02, 0.3, seed=seed, duration=6.0, rate=100.0)
        fit = fit_damped_oscillation(t, y)
        z.append((fit.period - 1.5) / fit.period_se)
    spread = float(np.std(z, ddof=1))
    assert 0.6 < spread < 1.5
    assert abs(float(np.mean(z))) < 3 * spread / math.sqrt(len(z))


def test_uneven_sampling_and_a_frequency_guess():
    t, y, omega_d, _ = signal(0.9, 0.01, 0.02, jitter=True)
    fit = fit_damped_oscillation(t, y, guess_frequency=1.05 * omega_d)
    assert abs(fit.omega_d - omega_d) < 4 * fit.omega_d_se


def test_drift_is_fitted_when_asked():
    t, y, omega_d, _ = signal(1.2, 0.05, 0.02, drift=0.05)
    fit = fit_damped_oscillation(t, y, drift=True)
    assert fit.drift == pytest.approx(0.05, abs=4 * math.sqrt(fit.covariance[5, 5]))
    assert abs(fit.omega_d - omega_d) < 4 * fit.omega_d_se
    assert fit_damped_oscillation(t, y).drift is None


def test_evaluate_reproduces_the_noise_free_signal():
    t, y, _, _ = signal(1.0, 0.03, 0.0, seed=3)
    fit = fit_damped_oscillation(t + 5.0, y)  # a time origin other than zero
    np.testing.assert_allclose(fit.evaluate(t + 5.0), y, atol=1e-8)
    assert fit.t0 == 5.0


@pytest.mark.parametrize(
    "make, fragment",
    [
        (lambda: (np.arange(10) * 0.1, np.sin(np.arange(10))), "too few samples"),
        (
            lambda: (np.r_[np.arange(50) * 0.1, 4.0, np.arange(51, 100) * 0.1], np.sin(np.arange(100))),
            "not strictly increasing",
        ),
        (lambda: (np.arange(100) * 0.1, np.r_[np.sin(np.arange(99)), np.nan]), "non-finite"),
        (lambda: (np.arange(500) * 0.01, np.random.default_rng(1).standard_normal(500)), "no oscillation"),
        (lambda: (np.arange(500) * 0.01, np.full(500, 0.3)), "not determined by the data"),
        (
            lambda: (np.arange(100) * 0.01, np.sin(2 * np.pi * 0.3 * np.arange(100) * 0.01)),
            "cycles|longer than the record",
        ),
        (lambda: (np.arange(100) * 0.1, np.sin(np.arange(100) * 0.1)[:50]), "equal length"),
    ],
    ids=["few", "time-order", "nan", "noise", "constant", "short", "lengths"],
)
def test_failures_are_clear_fit_errors(make, fragment):
    t, y = make()
    with pytest.raises(FitError, match=fragment):
        fit_damped_oscillation(t, y)


def test_bad_frequency_guess_is_refused():
    t, y, _, _ = signal(1.0, 0.01, 0.01)
    with pytest.raises(FitError, match="guess_frequency"):
        fit_damped_oscillation(t, y, guess_frequency=-3.0)


def test_trials_combine_standard_errors_and_scatter():
    fits = [
        fit_damped_oscillation(*signal(1.894 * (1 + d), 0.003, 0.05, seed=i)[:2])
        for i, d in enumerate((-0.001, 0.0, 0.0015))
    ]
    estimate = period_from_trials(fits)
    periods = np.array([f.period for f in fits])
    errors = np.array([f.period_se for f in fits])
    assert estimate.period == pytest.approx(periods.mean(), rel=1e-14)
    expected = math.sqrt(np.sum(errors**2) / 9 + periods.var(ddof=1) / 3)
    assert estimate.sigma == pytest.approx(expected, rel=1e-12)
    assert estimate.sigma > periods.std(ddof=1) / math.sqrt(3)  # both parts count
    assert estimate.n_trials == 3
    single = period_from_trials(fits[:1])
    assert single.sigma == pytest.approx(fits[0].period_se) and single.scatter == 0.0


def test_trial_of_another_oscillation_is_named():
    fits = [fit_damped_oscillation(*signal(p, 0.003, 0.05)[:2]) for p in (1.894, 1.895, 2.30)]
    with pytest.raises(FitError, match=r"c\.csv: period 2\.3\d* s is .* from the trials' median"):
        period_from_trials(fits, names=["a.csv", "b.csv", "c.csv"])
    with pytest.raises(FitError, match="no trials"):
        period_from_trials([])


# -- CSV files and the command -------------------------------------------------------------


def write_csv(path, t, y, header="time,rate"):
    lines = ([header] if header else []) + [f"{float(a)!r},{float(b)!r}" for a, b in zip(t, y)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("header", ["time,rate", "t,angular_rate", "Time [s];Omega (rad/s)", "time (s)\tgyro", None])
def test_csv_headers(tmp_path, header):
    t, y, _, _ = signal(1.0, 0.01, 0.0, duration=1.0, rate=50)
    if header and ";" in header:
        text = header + "\n" + "\n".join(f"{float(a)!r};{float(b)!r}" for a, b in zip(t, y))
    elif header and "\t" in header:
        text = header + "\n" + "\n".join(f"{float(a)!r}\t{float(b)!r}" for a, b in zip(t, y))
    else:
        text = ((header + "\n") if header else "") + "\n".join(f"{float(a)!r},{float(b)!r}" for a, b in zip(t, y))
    path = tmp_path / "trial.csv"
    path.write_text("# a comment\n" + text + "\n")
    time, rate = read_signal_csv(path)
    np.testing.assert_array_equal(time, t)
    np.testing.assert_array_equal(rate, y)


def test_csv_errors_name_the_line(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("time,rate\n0.0,1.0\n0.1,oops\n")
    with pytest.raises(FileFormatError, match=r"bad\.csv:3: rate 'oops' is not a number"):
        read_signal_csv(path)
    path.write_text("seconds,voltage\n0,1\n")
    with pytest.raises(FileFormatError, match="no rate column"):
        read_signal_csv(path)


def test_period_command_text_json_and_plot(tmp_path, capsys):
    files = [write_csv(tmp_path / f"trial{i}.csv", *signal(1.894, 0.004, 0.02, seed=i)[:2]) for i in range(3)]
    assert main(["period", *map(str, files)]) == 0
    out = capsys.readouterr().out
    assert out.count("T = 1.89") == 3
    assert "period = 1.89" in out and "3 trials" in out
    plot = tmp_path / "fit.png"
    assert main(["period", *map(str, files), "--json", "--plot", str(plot)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["period"] == pytest.approx(1.894, abs=4 * report["sigma"])
    assert len(report["trials"]) == 3 and report["trials"][0]["file"] == str(files[0])
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(tmp_path.glob("*.tmp")) and not list(tmp_path.glob("tmp*"))


def test_period_command_reports_a_failed_fit(tmp_path, capsys):
    noise = write_csv(tmp_path / "noise.csv", np.arange(400) * 0.01, np.random.default_rng(2).standard_normal(400))
    assert main(["period", str(noise)]) == 2
    err = capsys.readouterr().err
    assert "noise.csv" in err and "no oscillation" in err and "Traceback" not in err


def test_period_json_and_figure_say_what_they_show(tmp_path, capsys):
    """issue 24: `period --json` used "sigma" for the period's uncertainty and for each trial's decay
    rate; the figure was in matplotlib's default style, its key over the peaks, its y axis without a
    unit and no residuals."""
    from bikerider.fitting.damped_oscillation import fit_damped_oscillation
    from bikerider.plotting import pyplot
    from bikerider.plotting.period import period_figure

    t, y = signal(1.894, 0.004, 0.02, seed=1)[:2]
    path = tmp_path / "trial.csv"
    path.write_text("time [s],rate (deg/s)\n" + "\n".join(f"{float(a)!r},{float(b)!r}" for a, b in zip(t, y)) + "\n")
    assert main(["period", str(path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    trial = report["trials"][0]
    assert "sigma" not in trial and trial["decay_rate"] > 0 and trial["decay_rate_se"] > 0
    assert report["sigma"] > 0  # the period's standard uncertainty
    from bikerider.io.signal_csv import signal_unit

    assert signal_unit(path) == "deg/s"
    fit = fit_damped_oscillation(t, y)
    fig = period_figure([(path, t, y), (path, t, y)], [fit, fit], signal_unit(path))
    data, residual = fig.axes[0], fig.axes[1]
    assert len(fig.axes) == 4
    assert data.get_ylabel() == "angular rate [deg/s]" and residual.get_ylabel() == "residual [deg/s]"
    assert residual.get_xlim() == data.get_xlim()
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    key = data.get_legend().get_window_extent(renderer)
    assert key.x0 >= data.get_window_extent(renderer).x1  # beside the axes, never over a peak
    assert not data.spines["top"].get_visible()  # the house style (plotting.common.RC)
    pyplot().close(fig)
    assert period_figure([(path, t, y)], [fit]).axes[0].get_ylabel() == "angular rate [as recorded]"
