"""What the page offers for download: parameter files, CSV tables and figures.

* Parameters as a TOML file (``[benchmark]``, ``"value +/- sigma"``), a BicycleParameters
  ``<Name>Benchmark.txt`` (``name = value+/-sigma``) and JSON, by the package's exporters
  (:mod:`bikerider.io.export`): each reads back through ``bikerider benchmark FILE`` to the same
  values.
* The eigenvalues at 0-10 m/s with their first-order sigmas and condition numbers (CSV, as
  ``estimate --json`` lists them), the tracked modes (CSV), and the stability map's designs (CSV, as
  ``bikerider sweep`` writes them).
* Figures drawn by the package's matplotlib functions (those of ``--plot``) as PNG, SVG or PDF.
"""

from __future__ import annotations

import math
import re

from bikerider.app import dynamics
from bikerider.benchmark import BenchmarkParameters, WhippleModel
from bikerider.errors import InputError
from bikerider.io import export

PARAMETER_FORMATS = {"toml": "application/toml", "txt": "text/plain", "json": "application/json"}
FIGURE_FORMATS = {"png": "image/png", "svg": "image/svg+xml", "pdf": "application/pdf"}
FIGURES = ("eigenvalues", "side_view", "mode_shapes", "bode", "map")
TABLES = ("eigenvalues", "modes", "map")


def bicycle_name(name: str) -> str:
    """A BicycleParameters bicycle name from the page's name (letters, digits and ``_``, a letter
    first): ``"Browser + Jason"`` gives ``"BrowserJason"``."""
    cleaned = re.sub(r"[^A-Za-z0-9_]", "", str(name))
    return cleaned if cleaned[:1].isalpha() else f"Bicycle{cleaned}"


def parameter_file(parameters: BenchmarkParameters, fmt: str, name: str = "bicycle") -> tuple[str, str]:
    """``(file name, text)`` of ``parameters`` in format ``fmt`` (``toml``, ``txt``, ``json``), written
    by the package's exporters (:mod:`bikerider.io.export`), which every reader reads back bit for bit."""
    if fmt == "toml":
        return f"{bicycle_name(name)}.toml", export.parameters_to_toml(parameters, name)
    if fmt == "txt":
        short = bicycle_name(name)
        return export.benchmark_txt_filename(short), export.parameters_to_benchmark_txt(parameters, short)
    if fmt == "json":
        return f"{bicycle_name(name)}.json", export.parameters_to_json(parameters)
    raise InputError("format", fmt, f"one of {', '.join(PARAMETER_FORMATS)}")


def _csv(rows: list[dict]) -> str:
    return export.rows_to_csv(rows)


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
