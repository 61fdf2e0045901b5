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


def test_benchmark_plot_draws_the_files_sigmas_and_says_where(tmp_path, capsys, monkeypatch):
    """issue 24: `benchmark --plot` drew no uncertainty band though the file had sigmas, and did not
    say where the figures went."""
    drawn = {}
    write = plotting.write_figures

    def spy(*args, **kwargs):
        drawn["band"] = kwargs.get("uncertainty")
        return write(*args, **kwargs)

    monkeypatch.setattr(plotting, "write_figures", spy)
    assert main(["benchmark", "--bicycle", "Browser", "--rider", "Jason", "--plot", str(tmp_path / "b")]) == 0
    assert f"Figures written to {tmp_path / 'b'}/" in capsys.readouterr().out
    band = drawn["band"]
    assert band is not None and band.sigma_real.shape[0] == 101 and np.nanmax(band.sigma_real) > 0
    assert main(["benchmark", "--bicycle", "Benchmark", "--plot", str(tmp_path / "a")]) == 0  # no sigmas
    assert drawn["band"] is None


def test_side_view_holds_the_whole_inertia_ellipses(bench, paper_result):
    """issue 24: the side view from benchmark parameters cut the rear body's ellipse at the top."""
    from matplotlib.patches import Ellipse

    for parameters, points in ((bench, None), (paper_result.parameters, paper_result.rider_model.grid_points)):
        fig, ax = _axes()
        plotting.plot_side_view(ax, parameters, points)
        x0, x1 = ax.get_xlim()
        y0, y1 = ax.get_ylim()
        ellipses = [p for p in ax.patches if type(p) is Ellipse]
        assert len(ellipses) == 2
        for e in ellipses:
            corners = e.get_patch_transform().transform(e.get_path().vertices)  # in data coordinates
            assert corners[:, 0].min() >= x0 and corners[:, 0].max() <= x1
            assert corners[:, 1].min() >= y0 and corners[:, 1].max() <= y1
        plotting.pyplot().close(fig)


def test_benchmark_figures_are_titled_by_the_bicycle_not_the_path(tmp_path):
    from bikerider.commands.benchmark import figure_title

    bp = tmp_path / "BrowserBenchmark.txt"
    bp.write_text("w = 1.0\n")
    assert figure_title(str(bp)) == "Browser"
    named_file = tmp_path / "mine.toml"
    named_file.write_text('name = "My bicycle"\n[benchmark]\nw = 1.0\n')
    assert figure_title(str(named_file)) == "My bicycle"
    (tmp_path / "plain.toml").write_text("[benchmark]\nw = 1.0\n")
    assert figure_title(str(tmp_path / "plain.toml")) == "plain"


def test_bode_default_speeds_include_a_self_stable_one_and_mark_it(paper_result, model):
    """issue 24: the Bode figure's speeds (25/55/85 % of the range: 2.5, 5.5, 8.5 m/s) all missed the
    paper bicycle's self-stable range (5.66-8.36 m/s); the figure showed only unstable systems."""
    for m in (paper_result.model, model):
        speeds = plotting._bode_speeds(m, np.linspace(0, 10, 11))
        stable = m.stability().is_stable(speeds)
        assert len(speeds) == 3 and stable.sum() >= 1 and not stable.all()  # stable ones, and the others
        fig = plotting.bode_figure(m, speeds)
        labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
        assert sum(label.endswith("(self-stable)") for label in labels) == stable.sum()
        plotting.pyplot().close(fig)


def _design_slice(valid, fixed, base):
    from bikerider.design.summary import DesignSlice

    nx, ny = valid.shape
    lower = np.where(valid, 4.0 + np.arange(nx)[:, None] * 0.1 + np.zeros((1, ny)), np.nan)[..., None]
    upper = np.where(valid, 6.0 + np.arange(ny)[None, :] * 0.1 + np.zeros((nx, 1)), np.nan)[..., None]
    nan = np.full((nx, ny), np.nan)
    x, y = ("c", np.linspace(0.0, 0.15, nx)), ("lam", np.radians(np.linspace(0, 36, ny)))
    return DesignSlice(x, y, fixed, valid, lower, upper, nan, nan, nan, base)


def test_design_map_key_and_base_star_say_what_the_slice_shows():
    """issue 24: the map's "base design" star sat on a slice that did not hold the base, and its key
    listed "impossible design" where there were none."""
    from bikerider.plotting import design as figures

    base = {"c": 0.08, "lam": 0.3, "w": 1.02, "xB": 0.3}
    valid = np.ones((5, 4), bool)
    on = _design_slice(valid, {"w": 1.02, "xB": 0.3}, base)
    fig = figures.design_slice_figure(on, (), "t")
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "impossible design" not in labels and "never self-stable" not in labels
    assert "base design" in labels
    stars = [line for line in fig.axes[0].get_lines() if line.get_marker() == "*" and len(line.get_xdata())]
    assert len(stars) == 1 and stars[0].get_markerfacecolor() == "w"
    plotting.pyplot().close(fig)

    holes = valid.copy()
    holes[0, 0] = False
    off = _design_slice(holes, {"w": 0.9868, "xB": 0.3}, base)  # the grid's w nearest the base's 1.02
    assert figures.base_on_slice(off) is False
    fig = figures.design_slice_figure(off, (), "t")
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "impossible design" in labels and "base design" not in labels
    assert any("the base is off this slice: w = 1.02 m" in label for label in labels)
    stars = [line for line in fig.axes[0].get_lines() if line.get_marker() == "*" and len(line.get_xdata())]
    assert len(stars) == 1 and stars[0].get_markerfacecolor() == "none"
    plotting.pyplot().close(fig)
    assert figures.base_on_slice(_design_slice(valid, {"w": 1.02}, {**base, "c": 0.5})) is None  # outside


def test_stability_map_key_lists_only_what_the_map_shows(bench):
    """issue 24: "impossible design" in the key of a map without one; the star where the base is not."""
    fig, ax = _axes()
    result = stability_map(bench, ("c", np.linspace(0.02, 0.15, 6)), ("lam", np.radians(np.linspace(10, 30, 5))))
    assert result.valid.all()
    plotting.plot_stability_map(ax, result, colorbar=False)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "impossible design" not in labels and "base design" in labels
    plotting.pyplot().close(fig)
    fig, ax = _axes()
    away = stability_map(bench, ("c", np.linspace(0.1, 0.15, 4)), ("mB", np.linspace(-10.0, 120.0, 3)))
    plotting.plot_stability_map(ax, away, colorbar=False)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "impossible design" in labels and "base design" not in labels  # the base's c = 0.08 is off the map
    assert not [line for line in ax.get_lines() if line.get_marker() == "*" and len(line.get_xdata())]
    plotting.pyplot().close(fig)


def test_estimate_figures_of_a_benchmark_file_are_titled_by_its_name(tmp_path, monkeypatch):
    from pathlib import Path

    bp = Path(plotting.__file__).parents[1] / "data" / "bicycleparameters" / "bicycles" / "Fisher" / "Parameters"
    titles = []
    write = plotting.write_figures

    def spy(*args, **kwargs):
        titles.append(kwargs.get("title", args[4] if len(args) > 4 else ""))
        return write(*args, **kwargs)

    monkeypatch.setattr(plotting, "write_figures", spy)
    assert main(["estimate", "--bicycle", str(bp / "FisherBenchmark.txt"), "--plot", str(tmp_path)]) == 0
    assert titles == ["Fisher"]  # not the path, and no "+ no rider"
