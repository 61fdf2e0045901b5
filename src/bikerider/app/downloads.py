"""What the page offers for download: parameter files, CSV tables and figures.

* Parameters as a TOML file (``[benchmark]``, ``"value +/- sigma"``), a BicycleParameters
  ``Benchmark.txt`` (``name = value+/-sigma``) and JSON; the first two read back through
  ``bikerider benchmark FILE`` to the same values (a test checks it).  The writers here are the
  page's own until the package has one set of exporters (``bikerider.io.export``, being written
  beside this page): then :func:`parameter_file` is the one place to switch to them.
* The eigenvalues at 0-10 m/s with their first-order sigmas and condition numbers (CSV, as
  ``estimate --json`` lists them), the tracked modes (CSV), and the stability map's designs (CSV, as
  ``bikerider sweep`` writes them).
* Figures drawn by the package's matplotlib functions (those of ``--plot``) as PNG, SVG or PDF.
"""

from __future__ import annotations

import csv
import io
import json
import math

from bikerider.app import dynamics
from bikerider.benchmark import BENCHMARK_NAMES, BenchmarkParameters, WhippleModel
from bikerider.errors import InputError

PARAMETER_FORMATS = {"toml": "application/toml", "txt": "text/plain", "json": "application/json"}
FIGURE_FORMATS = {"png": "image/png", "svg": "image/svg+xml", "pdf": "application/pdf"}
FIGURES = ("eigenvalues", "side_view", "mode_shapes", "bode", "map")
TABLES = ("eigenvalues", "modes", "map")


def _number(x: float) -> str:
    return repr(float(x))


def parameter_file(parameters: BenchmarkParameters, fmt: str, name: str = "bicycle") -> tuple[str, str]:
    """``(file name, text)`` of ``parameters`` in format ``fmt`` (``toml``, ``txt``, ``json``)."""
    v, s = parameters.values, parameters.sigmas
    present = [n for n in BENCHMARK_NAMES if v[n] is not None]
    if fmt == "toml":
        lines = [f"# {name}: benchmark parameters (Meijaard et al. 2007 names, SI units), written by bikerider serve"]
        lines += ["[benchmark]"]
        for n in present:
            sigma = float(s.get(n, 0.0) or 0.0)
            lines.append(f'{n} = "{_number(v[n])} +/- {_number(sigma)}"' if sigma else f"{n} = {_number(v[n])}")  # type: ignore[arg-type]
        return "bicycle.toml", "\n".join(lines) + "\n"
    if fmt == "txt":
        lines = []
        for n in present:
            sigma = float(s.get(n, 0.0) or 0.0)
            lines.append(f"{n} = {_number(v[n])}+/-{_number(sigma)}" if sigma else f"{n} = {_number(v[n])}")  # type: ignore[arg-type]
        return "BicycleBenchmark.txt", "\n".join(lines) + "\n"
    if fmt == "json":
        out = {
            "name": name,
            "benchmark": {n: v[n] for n in BENCHMARK_NAMES},
            "sigmas": {n: float(s.get(n, 0.0) or 0.0) for n in BENCHMARK_NAMES},
        }
        return "bicycle.json", json.dumps(out, indent=2, allow_nan=False) + "\n"
    raise InputError("format", fmt, f"one of {', '.join(PARAMETER_FORMATS)}")


def _csv(rows: list[dict]) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows({k: ("" if v is None else v) for k, v in row.items()} for row in rows)
    return buffer.getvalue()


def table_file(parameters: BenchmarkParameters, table: str, axes=None) -> tuple[str, str]:
    """``(file name, CSV text)`` of a table: ``eigenvalues`` (labelled, with first-order sigmas),
    ``modes`` (tracked columns and mode shapes) or ``map`` (the map's designs)."""
    # The uncertainty package is imported with the page's computations already.
    from bikerider.uncertainty import benchmark_inputs, propagate

    if table == "eigenvalues":
        uncertainty = propagate(benchmark_inputs(parameters), speeds=dynamics.SPEEDS)
        return "eigenvalues.csv", _csv(uncertainty.eigenvalues.as_list())
    if table == "modes":
        modes = dynamics.tracked_modes(parameters)
        rows = []
        for i, speed in enumerate(modes["speeds"]):
            for k, name in enumerate(modes["names"]):
                rows.append(
                    {
                        "speed": speed,
                        "column": k,
                        "mode": name,
                        "real": modes["real"][i][k],
                        "imag": modes["imag"][i][k],
                        "roll_amplitude": modes["roll"][i][k],
                        "steer_amplitude": modes["steer"][i][k],
                        "steer_phase_deg": modes["steer_phase_deg"][i][k],
                    }
                )
        return "modes.csv", _csv(rows)
    if table == "map":
        if not axes:
            raise InputError("map", None, "a stability map (choose its parameter first)")
        result = dynamics.map_sweep(parameters, axes)
        rows = result.design_rows()
        for row in rows:
            row["stable_intervals"] = ";".join(
                f"{i['lower']}:{'' if i['upper'] is None else i['upper']}" for i in row["stable_intervals"]
            )
        return "map.csv", _csv(rows)
    raise InputError("table", table, f"one of {', '.join(TABLES)}")


def figure_file(
    parameters: BenchmarkParameters, figure: str, fmt: str, speed: float, axes=None, title: str = ""
) -> tuple[str, bytes]:
    """``(file name, bytes)`` of a figure drawn by the package's matplotlib functions."""
    # matplotlib is imported only when a figure is downloaded: the page draws its own.
    from bikerider import plotting
    from bikerider.io.atomic import figure_bytes
    from bikerider.uncertainty import benchmark_inputs, propagate

    if fmt not in FIGURE_FORMATS:
        raise InputError("format", fmt, f"one of {', '.join(FIGURE_FORMATS)}")
    model = WhippleModel.from_parameters(parameters)
    speeds = dynamics.SPEEDS
    if figure == "eigenvalues":
        band = propagate(benchmark_inputs(parameters), speeds=speeds).eigenvalues
        if band is not None and not any(math.isfinite(x) for x in band.sigma_real.ravel()):
            band = None
        fig = plotting.eigenvalue_figure(model, speeds, title, uncertainty=band)
    elif figure == "side_view":
        fig = plotting.side_view_figure(parameters, None, title)
    elif figure == "mode_shapes":
        fig = plotting.mode_shape_figure(model, speed, speeds, title)
    elif figure == "bode":
        fig = plotting.bode_figure(model, (speed,), lateral_force=dynamics.lateral_force(parameters), title=title)
    elif figure == "map":
        if not axes:
            raise InputError("map", None, "a stability map (choose its parameter first)")
        fig = plotting.sweep_figure(dynamics.map_sweep(parameters, axes), title)
    else:
        raise InputError("figure", figure, f"one of {', '.join(FIGURES)}")
    try:
        data = figure_bytes(fig, format=fmt, dpi=plotting.DEFAULT_DPI, bbox_inches="tight", pad_inches=0.04)
    finally:
        plotting.pyplot().close(fig)
    return f"{figure}.{fmt}", data


__all__ = ["FIGURES", "FIGURE_FORMATS", "PARAMETER_FORMATS", "TABLES", "figure_file", "parameter_file", "table_file"]
