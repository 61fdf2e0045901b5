"""Figures: every plotting function draws on the axes it is given and returns it; nothing is
clipped silently; legends and keys sit outside the data; PNG, PDF and SVG."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bikerider import plotting
from bikerider.benchmark import WhippleModel
from bikerider.benchmark.frequency_response import frequency_response
from bikerider.benchmark.mode_shapes import mode_shapes
from bikerider.benchmark.sweep import stability_map, sweep
from bikerider.cli import main
from bikerider.shipped import named

MAGIC = {"png": b"\x89PNG\r\n\x1a\n", "pdf": b"%PDF", "svg": b"<?xml"}


@pytest.fixture(scope="module")
def bench():
    return named("Benchmark")


@pytest.fixture(scope="module")
def model(bench):
    return WhippleModel.from_parameters(bench)


def _axes():
    fig, ax = plotting.common.new_figure()
    return fig, ax


def _outside(fig, legend, ax) -> bool:
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    return legend.get_window_extent(renderer).x0 >= ax.get_window_extent(renderer).x1


def test_eigenvalues_are_lines_per_tracked_mode_with_the_stable_interval_shaded(model):
    fig, ax = _axes()
    assert plotting.plot_eigenvalues(ax, model, np.linspace(0, 10, 11)) is ax
    lines = [line for line in ax.get_lines() if line.get_label().endswith("part")]
    assert {line.get_label() for line in lines} >= {
        "weave, real part",
        "weave, imaginary part",
        "capsize, real part",
        "castor, real part",
    }
    assert all(line.get_linestyle() == "-" for line in lines if "real" in line.get_label())
    assert all(line.get_linestyle() == "--" for line in lines if "imaginary" in line.get_label())
    assert all(len(line.get_xdata()) == 401 for line in lines)  # a fine grid, not the 11 speeds given
    shaded = [p for p in ax.patches if p.get_label() == "self-stable"]
    x0 = shaded[0].get_x()
    x1 = x0 + shaded[0].get_width()
    assert x0 == pytest.approx(4.292382, abs=1e-6) and x1 == pytest.approx(6.024262, abs=1e-6)  # Meijaard 2007
    assert _outside(fig, ax.get_legend(), ax)
    plotting.pyplot().close(fig)


def test_a_line_that_leaves_the_axes_is_marked_and_described(model):
    fig, ax = _axes()
    plotting.plot_eigenvalues(ax, model)  # the castor mode reaches -24 1/s at 10 m/s
    lo, _ = ax.get_ylim()
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("castor real part below the axes" in t for t in texts)
    assert any(line.get_marker() == "v" and line.get_ydata()[0] == lo for line in ax.get_lines())
    fig2, ax2 = _axes()
    plotting.plot_eigenvalues(ax2, model, ylim="all")
    assert not any("below the axes" in t.get_text() for t in ax2.get_legend().get_texts())
    assert ax2.get_ylim()[0] < -24
    plotting.pyplot().close(fig)
    plotting.pyplot().close(fig2)


def test_uncertainty_band_and_two_panels(paper_result):
    from bikerider.estimate import estimate_uncertainty

    uncertainty = estimate_uncertainty(paper_result, np.linspace(0, 10, 21)).eigenvalues
    fig, (ax, imag_ax) = plotting.common.new_figure(nrows=2)
    plotting.plot_eigenvalues(ax, paper_result.model, imag_ax=imag_ax, uncertainty=uncertainty)
    assert any("uncertainty" in c.get_label() for c in ax.collections)
    assert any(line.get_label() == "weave, imaginary part" for line in imag_ax.get_lines())
    plotting.pyplot().close(fig)


def test_side_view_has_a_key_centres_of_mass_and_inertia_ellipses(bench, paper_result):
    from matplotlib.patches import Ellipse, Wedge

    fig, ax = _axes()
    assert plotting.plot_side_view(ax, bench) is ax
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "rear body B: centre of mass and inertia ellipse" in labels and "whole bicycle: centre of mass" in labels
    assert sum(type(p) is Ellipse for p in ax.patches) == 2  # Circle (wheels, symbols) is an Ellipse too
    assert sum(isinstance(p, Wedge) for p in ax.patches) == 5 * 4  # five quartered symbols
    assert _outside(fig, ax.get_legend(), ax)
    plotting.pyplot().close(fig)
    # with the rider's grid points; the title is not cut when saved
    fig = plotting.side_view_figure(paper_result.parameters, paper_result.rider_model.grid_points, "a long title " * 4)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    title = fig.axes[0].title.get_window_extent(renderer)
    tight = fig.get_tightbbox(renderer).transformed(fig.dpi_scale_trans)
    assert title.x1 / fig.dpi <= tight.x1 + 1e-6 and title.y1 / fig.dpi <= tight.y1 + 1e-6
    assert not any(t.get_text().isdigit() for t in fig.axes[0].texts)  # no grid point numbers by default
    plotting.pyplot().close(fig)


def test_inertia_ellipse_of_a_uniform_ellipsoid():
    # a uniform solid ellipsoid with semi-axes a (x), b (y), c (z): I = m/5 (b^2+c^2, a^2+c^2, a^2+b^2)
    m, a, b, c = 2.0, 0.3, 0.1, 0.2
    Ixx, Iyy, Izz = m / 5 * (b * b + c * c), m / 5 * (a * a + c * c), m / 5 * (a * a + b * b)
    first, second, angle = plotting.side_view.inertia_ellipse(m, Ixx, Izz, 0.0, Iyy)
    assert sorted([first, second]) == pytest.approx([c, a])
    turned = plotting.side_view.inertia_ellipse(m, (Ixx + Izz) / 2, (Ixx + Izz) / 2, (Izz - Ixx) / 2, Iyy)
    assert sorted(turned[:2]) == pytest.approx([c, a])  # the same body turned by 45 degrees


def test_mode_bode_and_sweep_plots_return_their_axes(model, bench):
    plt = plotting.pyplot()
    shapes = mode_shapes(model, np.linspace(0, 10, 201))
    fig = plt.figure()
    polar = fig.add_subplot(projection="polar")
    assert plotting.plot_mode_phasors(polar, shapes, 5.0, "weave") is polar
    fig2, (a, b) = plotting.common.new_figure(ncols=2)
    assert plotting.plot_mode_shape_speeds(a, shapes, b) is a
    response = frequency_response(model, [3.0, 5.0], np.logspace(-1, 2, 50), inputs=("T_delta",))
    fig3, (m, p) = plotting.common.new_figure(nrows=2)
    assert plotting.plot_bode(m, response, "phi", "T_delta", phase_ax=p) is m
    assert len(m.get_lines()) == 2 and len(p.get_lines()) == 2
    fig4, ax = _axes()
    one = sweep(bench, {"c": np.linspace(0, 0.2, 21)}, eigenvalues=False)
    assert plotting.plot_stability_sweep(ax, one) is ax
    fig5, ax5 = _axes()
    two = stability_map(bench, ("c", np.linspace(0, 0.2, 15)), ("mB", np.linspace(-10, 120, 14)))
    assert plotting.plot_stability_map(ax5, two) is ax5
    for f in (fig, fig2, fig3, fig4, fig5):
        plt.close(f)


def test_several_bicycles_on_one_figure():
    models = {name: WhippleModel.from_parameters(named(name)) for name in ("Benchmark", "Browser", "Yellow")}
    fig = plotting.eigenvalue_comparison_figure(models)
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[:3] == ["Benchmark", "Browser", "Yellow"]
    assert len(fig.axes[2].get_lines()) == 3  # one stable-interval bar per bicycle
    plotting.pyplot().close(fig)


@pytest.mark.parametrize("fmt", ["png", "pdf", "svg"])
def test_write_figures_in_every_format_and_resolution(tmp_path, model, bench, fmt):
    written = plotting.write_figures(
        tmp_path,
        model,
        np.linspace(0, 10, 5),
        None,
        "Benchmark",
        parameters=bench,
        figures=plotting.FIGURES,
        fmt=fmt,
        dpi=60,
    )
    assert [p.name for p in written] == [f"{n}.{fmt}" for n in plotting.FIGURES]
    for path in written:
        assert path.read_bytes()[: len(MAGIC[fmt])] == MAGIC[fmt]
    if fmt != "png":  # vector files carry no date: the same figure is the same file
        again = plotting.write_figures(
            tmp_path / "again",
            model,
            np.linspace(0, 10, 5),
            None,
            "Benchmark",
            parameters=bench,
            figures=("eigenvalues",),
            fmt=fmt,
        )
        assert again[0].read_bytes() == written[0].read_bytes()


def test_png_resolution_follows_dpi(tmp_path, model):
    from matplotlib.image import imread

    small = plotting.write_figures(tmp_path / "a", model, [0, 10], None, fmt="png", dpi=50)[0]
    large = plotting.write_figures(tmp_path / "b", model, [0, 10], None, fmt="png", dpi=100)[0]
    ratio = imread(large).shape[1] / imread(small).shape[1]
    assert ratio == pytest.approx(2.0, rel=0.03)


def test_cli_figures_and_bad_format(tmp_path, capsys):
    assert main(["benchmark", "--bicycle", "Benchmark", "--plot", str(tmp_path), "--format", "pdf"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(f"{n}.pdf" for n in plotting.FIGURES)
    with pytest.raises(SystemExit):
        main(["benchmark", "--bicycle", "Benchmark", "--plot", str(tmp_path), "--format", "jpg"])
    assert main(["benchmark", "--bicycle", "Benchmark", "--plot", str(tmp_path), "--dpi", "5"]) == 2
    assert "--dpi" in capsys.readouterr().err


def test_sweep_command_csv_json_and_map(tmp_path, capsys):
    assert main(["sweep", "--bicycle", "Benchmark", "--vary", "c=0.0:0.2:5"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "c,valid,reason,weave_speed,capsize_speed,weave_frequency,stable_intervals"
    assert len(lines) == 6 and lines[3].startswith("0.1,true,,4.507")
    assert (
        main(
            [
                "sweep",
                "--bicycle",
                "Benchmark",
                "--vary",
                "lam_deg=0:30:4",
                "--vary",
                "mB=-10:120:3",
                "--speeds",
                "4:6:3",
                "--json",
                "--plot",
                str(tmp_path),
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert out["parameters"]["lam_deg"] == [0.0, 10.0, 20.0, 30.0]  # degrees in, degrees out
    assert len(out["designs"]) == 12 and np.shape(out["stable"]) == (4, 3, 3)
    invalid = [d for d in out["designs"] if not d["valid"]]
    assert len(invalid) == 4 and all("mB = -10" in d["reason"] for d in invalid)
    assert (tmp_path / "sweep.png").exists()
    assert (
        main(
            [
                "sweep",
                "--bicycle",
                "Benchmark",
                "--vary",
                "c=0.06:0.1:2",
                "--speeds",
                "5:5:1",
                "--rows",
                "speeds",
                "--out",
                str(tmp_path / "rows.csv"),
            ]
        )
        == 0
    )
    rows = (tmp_path / "rows.csv").read_text().splitlines()
    assert rows[0].startswith("c,speed,stable,weave_real,weave_imag") and rows[1].split(",")[2] == "true"
    assert main(["sweep", "--bicycle", "Benchmark", "--vary", "trail=0:1:3"]) == 2
    assert "one of the benchmark names" in capsys.readouterr().err
