"""Write docs/gallery.md and its figures (docs/gallery/*.png): every figure bikerider draws.

Run with ``make docs`` (or ``python docs/scripts/gallery.py [STEM ...]``, only those figures redrawn).  :func:`build` returns the page's
text without drawing (the test of current documents compares it); :func:`main` draws the figures
too.  The figures are small PNGs (90 dpi) so that the repository stays light; the commands write
them at 200 dpi, or as PDF or SVG.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "gallery"
DPI = 90


def _figures():
    """``(file stem, caption, code, function that makes the figure)`` for every figure of the page."""
    from bikerider import plotting
    from bikerider.benchmark import WhippleModel
    from bikerider.benchmark.closed_loop import closed_loop, lqr_law
    from bikerider.benchmark.control import ControlLaw, GainSchedule
    from bikerider.benchmark.sweep import stability_map, sweep
    from bikerider.estimate import estimate_default, estimate_uncertainty
    from bikerider.plotting.distribution import speed_distribution_figure as distribution_figure
    from bikerider.shipped import named

    logging.getLogger("bikerider").setLevel(logging.ERROR)
    paper = estimate_default()
    bench = named("Benchmark")
    bench_model = WhippleModel.from_parameters(bench)
    browser = named("Browser", rider="Jason")
    browser_model = WhippleModel.from_parameters(browser)
    speeds = np.linspace(0.0, 10.0, 101)

    def eigenvalues_paper():
        band = estimate_uncertainty(paper, speeds).eigenvalues
        return plotting.eigenvalue_figure(
            paper.model, speeds, "Batavus Browser + rider (Moore et al. 2009)", uncertainty=band
        )

    def bode_browser():
        from bikerider.benchmark.state_space import LateralForce

        force = LateralForce(browser.values["xB"], browser.values["zB"])  # type: ignore[arg-type]
        return plotting.bode_figure(
            browser_model, (3.0, 5.5, 8.0), lateral_force=force, title="Browser + Jason (BicycleParameters)"
        )

    def compare():
        models = {
            name: WhippleModel.from_parameters(named(name)) for name in ("Benchmark", "Browser", "Fisher", "Yellow")
        }
        return plotting.eigenvalue_comparison_figure(models, title="Shipped bicycles without rider")

    def trail_sweep():
        result = sweep(bench, {"c": np.linspace(-0.02, 0.2, 111)}, eigenvalues=False)
        return plotting.sweep_figure(result, "Benchmark bicycle: self-stable speeds against trail")

    def trail_tilt_map():
        result = stability_map(bench, ("c", np.linspace(0.0, 0.2, 101)), ("lam", np.radians(np.linspace(0, 40, 101))))
        return plotting.sweep_figure(result, "Benchmark bicycle: trail and steer axis tilt")

    runs: dict = {}

    def six_parameters():
        """The design space of the bench's 6.4e7-design map, at 8 values a parameter (262144 designs)."""
        from bikerider import design

        if "six" not in runs:
            axes = {
                "c": (0.0, 0.15),
                "lam": (0.0, np.radians(36.0)),
                "w": (0.8, 1.3),
                "IHzz": (0.002, 0.03),
                "IFyy": (0.1, 0.28),
                "xB": (0.1, 0.6),
            }
            space = design.grid(bench, {k: np.linspace(lo, hi, 8) for k, (lo, hi) in axes.items()})
            runs["six"] = design.explore(space, None, np.linspace(0.0, 10.0, 100))
        return runs["six"]

    def design_fraction():
        from bikerider.design import summary
        from bikerider.plotting import design as figures

        store = six_parameters()
        return figures.stable_fraction_figure(
            summary.summarize(store), store.spec.space.base, "Benchmark bicycle, 6 parameters at 8 values"
        )

    def design_sensitivity():
        from bikerider.design import summary
        from bikerider.plotting import design as figures

        store = six_parameters()
        return figures.interval_sensitivity_figure(
            summary.summarize(store), store.spec.space.base, "Benchmark bicycle, 6 parameters at 8 values"
        )

    def design_map():
        from bikerider import design
        from bikerider.design import summary
        from bikerider.plotting import design as figures

        space = design.grid(
            bench,
            {
                "c": np.linspace(-0.02, 0.16, 73),
                "lam": np.radians(np.linspace(0, 36, 73)),
                "w": np.linspace(0.9, 1.2, 3),
                "IFyy": np.linspace(0.14, 0.28, 3),
            },
        )
        store = design.explore(space, None, np.linspace(0.0, 10.0, 100))
        cut = summary.design_slice(store, "c", "lam", {"w": 1.05, "IFyy": 0.28})
        return figures.design_slice_figure(cut, store.spec.speeds, "Benchmark bicycle: trail and steer axis tilt")

    roll_rate = ControlLaw("k_phid = 2 (6.5 - v) below 6.5 m/s", {"k_phid": GainSchedule.make_ramp(2.0, 6.5, "below")})

    def closed_loop_eigenvalues():
        return plotting.eigenvalue_figure(
            closed_loop(bench_model, roll_rate), speeds, "Benchmark bicycle under roll-rate feedback"
        )

    def lqr_gains():
        law = lqr_law(bench_model, np.linspace(0.5, 10.0, 39), Q=np.diag([10.0, 1.0, 1.0, 1.0]), R=0.1)
        stable = [(i.lower, i.upper) for i in closed_loop(bench_model, law).stability().intervals]
        title = "Benchmark bicycle: gains on the steer torque"
        return plotting.gains_figure([law, roll_rate], speeds, title, stable, "LQR closed loop stable")

    def speed_distribution():
        from bikerider import design
        from bikerider.design.distribution import speed_distributions

        store = design.explore(design.monte_carlo(browser, 20000, 1, "Browser + Jason"), None, quiet=True)
        return distribution_figure(speed_distributions(store), "Browser + Jason: 20,000 Monte Carlo draws")

    return [
        (
            "eigenvalues",
            "Eigenvalues against speed of the paper's bicycle and rider, with the first-order "
            "uncertainty that the paper's stated measurement accuracies give (`bikerider estimate --plot DIR`). "
            "Lines per tracked mode, real parts solid and imaginary parts dashed (Meijaard et al. 2007 Fig. 3, "
            "Moore et al. 2009 Fig. 5); the self-stable interval shaded; the castor mode leaves the chosen range, "
            "which the marker on the edge and the note in the legend say.",
            "plotting.eigenvalue_figure(model, speeds, title, uncertainty=estimate_uncertainty(result, speeds).eigenvalues)",
            eigenvalues_paper,
        ),
        (
            "eigenvalues_two_panel",
            "The benchmark bicycle (Meijaard et al. 2007) with real and imaginary parts on two "
            'panels and every line in range (`ylim="all"`).',
            'plotting.eigenvalue_figure(model, speeds, title, two_panel=True, ylim="all")',
            lambda: plotting.eigenvalue_figure(
                bench_model, speeds, "Benchmark bicycle (Meijaard et al. 2007)", two_panel=True, ylim="all"
            ),
        ),
        (
            "side_view",
            "Side view of the paper's bicycle and seated rider (Moore et al. 2009 Fig. 4): the bicycle "
            "through its grid points, the rider's segments, the centre of mass of the rear body (frame and rider), "
            "of the front assembly and of the whole bicycle, and the inertia ellipses (the section of the uniform "
            "solid ellipsoid with the body's mass and inertia).",
            "plotting.side_view_figure(result.parameters, result.rider_model.grid_points, title)",
            lambda: plotting.side_view_figure(
                paper.parameters, paper.rider_model.grid_points, "Batavus Browser + rider (Moore et al. 2009)"
            ),
        ),
        (
            "side_view_benchmark",
            "Side view from benchmark parameters alone (`bikerider benchmark --plot DIR`): "
            "schematic frame and fork on the wheels and the steer axis.",
            "plotting.side_view_figure(parameters, None, title)",
            lambda: plotting.side_view_figure(bench, None, "Benchmark bicycle (Meijaard et al. 2007)"),
        ),
        (
            "mode_shapes",
            "Mode shapes of the benchmark bicycle at 5 m/s as phasors (length: relative amplitude of "
            "roll and steer; angle: phase, steer relative to roll) and against speed.",
            "plotting.mode_shape_figure(model, 5.0, speeds, title)",
            lambda: plotting.mode_shape_figure(bench_model, 5.0, speeds, "Benchmark bicycle"),
        ),
        (
            "bode",
            "Frequency responses of the Browser with rider Jason from steer torque and from a lateral force at "
            "the rear body's centre of mass to roll and steer, at three speeds (self-stable ones marked).",
            "plotting.bode_figure(model, (3.0, 5.5, 8.0), lateral_force=LateralForce(xB, zB), title=title)",
            bode_browser,
        ),
        (
            "compare",
            "Several bicycles on one figure: real parts (one colour per bicycle, one line style per mode), "
            "the weave frequency and the self-stable intervals.",
            "plotting.eigenvalue_comparison_figure({name: model, ...}, title=title)",
            compare,
        ),
        (
            "sweep",
            "Self-stable speeds of the benchmark bicycle against its trail (`bikerider sweep --bicycle "
            "Benchmark --vary c=-0.02:0.2:111 --plot DIR`).",
            'plotting.sweep_figure(sweep(parameters, {"c": trails}))',
            trail_sweep,
        ),
        (
            "stability_map",
            "Stability map over trail and steer axis tilt: where the first self-stable interval "
            "begins (colour) and ends (contours); hatched: never self-stable (`bikerider sweep --bicycle Benchmark "
            "--vary c=0:0.2:101 --vary lam_deg=0:40:101 --plot DIR`).",
            'plotting.sweep_figure(stability_map(parameters, ("c", trails), ("lam", tilts)))',
            trail_tilt_map,
        ),
        (
            "design_stable_fraction",
            "A design space of six parameters of the benchmark bicycle (trail, steer axis tilt, "
            "wheelbase, front-assembly inertia, front-wheel spin inertia, rear-body centre of mass), 8 values each: the "
            "share of the valid designs that is self-stable somewhere in 0-10 m/s, against each parameter, with the share "
            "of impossible designs (`bikerider sweep ... --store DIR --plot DIR`; [design_space.md](design_space.md)).",
            "figures.stable_fraction_figure(summary.summarize(store), space.base, title)",
            design_fraction,
        ),
        (
            "design_sensitivity",
            "Sensitivity of the stable interval over the same space: median and interquartile range "
            "of the weave and capsize speeds (the ends of the first self-stable interval) over the other five parameters, "
            "against each, and each speed's first-order sensitivity index.",
            "figures.interval_sensitivity_figure(summary.summarize(store), space.base, title)",
            design_sensitivity,
        ),
        (
            "design_map",
            "A slice of a design space over trail, steer axis tilt, wheelbase and front-wheel spin "
            "inertia: where the first self-stable interval begins and ends, and the share of 100 speeds (0-10 m/s) at "
            "which each design is self-stable.",
            'figures.design_slice_figure(summary.design_slice(store, "c", "lam", fixed), store.spec.speeds, title)',
            design_map,
        ),
        (
            "closed_loop_eigenvalues",
            "The benchmark bicycle under a control law on the steer torque, roll-rate feedback that fades out "
            "at 6.5 m/s (`closed_loop(model, law)`; [dynamics.md](dynamics.md)): its eigenvalues, named by "
            "continuation as the open loop's, and the speeds where the closed loop is stable (from 3.26 m/s instead "
            "of 4.29 m/s).",
            "plotting.eigenvalue_figure(closed_loop(model, law), speeds, title)",
            closed_loop_eigenvalues,
        ),
        (
            "gains",
            "Gains on the steer torque against speed: an LQR schedule (`lqr_law(model, speeds, Q, R)`, the "
            "Riccati equation solved at 39 speeds, linear in between) and the roll-rate law above; shaded where the "
            "LQR closed loop is stable (as BicycleParameters' `plot_gains`).",
            'plotting.gains_figure([lqr_law(model, design_speeds, Q, R), law], speeds, title, stable, "LQR closed loop stable")',
            lqr_gains,
        ),
        (
            "speed_distribution",
            "The weave and capsize speeds over 20,000 Monte Carlo draws of the Browser with rider Jason, every "
            "value drawn within the uncertainty its file states (`bikerider sweep --bicycle Browser --rider Jason "
            "--monte-carlo 20000 --store DIR --plot DIR`): median, central 68 % and 95 %.",
            "plotting.distribution.speed_distribution_figure(speed_distributions(store), title)",
            speed_distribution,
        ),
    ]


HEADER = """# Gallery

Produced by `python docs/scripts/gallery.py` (`make docs`); do not edit by hand.  Every figure
bikerider draws, made by the code shown (the `bikerider.plotting` functions; each `plot_*` function
draws on an `ax` it is given and returns it, each `*_figure` function makes a whole figure).  The
commands write the same figures with `--plot DIR`, as PNG (200 dpi by default, `--dpi`), PDF or SVG
(`--format`).  The images here are small PNGs ({dpi} dpi).  Definitions (tracked modes, mode-shape
normalisation, stable intervals, inertia ellipses) are in [dynamics.md](dynamics.md).

"""


def build() -> str:
    """The text of docs/gallery.md (no drawing)."""
    lines = [HEADER.format(dpi=DPI)]
    for stem, caption, code, _ in _figures():
        title = stem.replace("_", " ")
        lines.append(f"## {title}\n\n![{stem}](gallery/{stem}.png)\n\n{caption}\n\n```python\n{code}\n```\n")
    return "\n".join(lines)


def main(only: tuple[str, ...] = ()) -> None:
    """Draw every figure (or those named in ``only``) and write the page."""
    from bikerider import plotting

    OUT.mkdir(parents=True, exist_ok=True)
    for stem, _, _, make in _figures():
        if only and stem not in only:
            continue
        path = plotting.save_figure(make(), OUT / f"{stem}.png", "png", DPI)
        _palette(path)
    (ROOT / "docs" / "gallery.md").write_text(build(), encoding="utf-8")


def _palette(path: Path) -> None:
    """Re-save a PNG with a 128-colour palette (a third of the size; the figures use few colours)."""
    from PIL import Image

    with Image.open(path) as image:
        small = image.convert("RGB").quantize(colors=128, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    small.save(path, optimize=True)


if __name__ == "__main__":
    import sys

    main(tuple(sys.argv[1:]))  # stems to redraw (all when none are given)
