"""BicycleParameters side of the benchmarks; runs in ``bench/.venv-baseline`` (never imports bikerider).

``python bench/bp_worker.py TASK 'JSON params'`` times TASK inside this process and prints one line
of JSON; ``python bench/bp_worker.py serve`` reads ``TASK JSON`` lines from standard input and
answers each with one line of JSON (so a benchmark can interleave rounds of both tools).  Tasks:

``versions``  versions of BicycleParameters and what it runs on.
``raw``       ``Bicycle(name, pathToData, forceRawCalc=True)`` then ``add_rider(rider)`` (BicycleParameters
              reads the rider's lumped ``Parameters/<Rider><Bike>Benchmark.txt``, since the data has no
              Yeadon measurements): median seconds, and the resulting benchmark parameters.
``eig``       ``Bicycle.eig(speeds)`` for ``n`` speeds from 0 to 10 m/s on that bicycle: median seconds,
              and the eigenvalues at a few speeds.
``scan``      weave and capsize speeds the way a BicycleParameters user finds them: ``eig`` on a grid
              of ``n`` speeds, then the first grid interval where the largest real part of the
              complex (weave) eigenvalues and of the real ones changes sign, interpolated linearly.
"""

from __future__ import annotations

import contextlib
import io
import json
import statistics
import sys
import time
import warnings


def _quiet():
    warnings.simplefilter("ignore")
    return contextlib.redirect_stdout(io.StringIO())


def _median_time(fn, repeats: int) -> tuple[float, object]:
    result = None
    samples = []
    for _ in range(repeats + 1):  # the first call warms up and is not counted
        start = time.perf_counter()
        result = fn()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples[1:]), result


def _bicycle(params: dict):
    import bicycleparameters as bp

    with _quiet():
        bicycle = bp.Bicycle(params.get("bicycle", "Browser"), pathToData=params["data"], forceRawCalc=True)
        bicycle.add_rider(params.get("rider", "Jason"))
    return bicycle


def versions(params: dict) -> dict:
    import bicycleparameters
    import numpy
    import uncertainties

    return {
        "bicycleparameters": bicycleparameters.__version__,
        "numpy": numpy.__version__,
        "uncertainties": uncertainties.__version__,
        "python": sys.version.split()[0],
    }


def raw(params: dict) -> dict:
    import bicycleparameters  # noqa: F401  (import cost is not part of the timing)

    seconds, bicycle = _median_time(lambda: _bicycle(params), params.get("repeats", 15))
    values = {}
    for name, value in bicycle.parameters["Benchmark"].items():
        nominal = getattr(value, "nominal_value", value)
        values[name] = [float(nominal), float(getattr(value, "std_dev", 0.0))]
    return {"seconds": seconds, "repeats": params.get("repeats", 15), "parameters": values}


def eig(params: dict) -> dict:
    import numpy as np

    bicycle = _bicycle(params)
    speeds = np.linspace(0.0, 10.0, params.get("n", 1000))
    with _quiet():
        seconds, (values, _) = _median_time(lambda: bicycle.eig(speeds), params.get("repeats", 7))
    picks = [0, len(speeds) // 2, len(speeds) - 1]
    return {
        "seconds": seconds,
        "repeats": params.get("repeats", 7),
        "speeds": [float(speeds[i]) for i in picks],
        "eigenvalues": [[[float(z.real), float(z.imag)] for z in values[i]] for i in picks],
    }


def _crossing(speeds, signal) -> float | None:
    import numpy as np

    stable = signal < 0
    for i in range(1, len(speeds)):
        if stable[i] != stable[i - 1] and np.isfinite(signal[i]) and np.isfinite(signal[i - 1]):
            a, b = signal[i - 1], signal[i]
            return float(speeds[i - 1] + (speeds[i] - speeds[i - 1]) * a / (a - b))
    return None


def scan(params: dict) -> dict:
    import numpy as np

    bicycle = _bicycle(params)
    speeds = np.linspace(0.0, 10.0, params.get("n", 1000))

    def find():
        values, _ = bicycle.eig(speeds)
        is_complex = np.abs(values.imag) > 1e-9 * np.maximum(1.0, np.abs(values).max(axis=1, keepdims=True))
        weave = np.where(is_complex, values.real, -np.inf).max(axis=1)
        weave = np.where(np.isfinite(weave), weave, np.nan)
        real_max = np.where(~is_complex, values.real, -np.inf).max(axis=1)
        # weave: complex pair turns stable; capsize: the largest real eigenvalue turns unstable
        v_weave = _crossing(speeds[np.isfinite(weave)], weave[np.isfinite(weave)])
        above = speeds > (v_weave or 0.0)
        v_capsize = _crossing(speeds[above], real_max[above])
        return v_weave, v_capsize

    with _quiet():
        seconds, (v_weave, v_capsize) = _median_time(find, params.get("repeats", 7))
    return {
        "seconds": seconds,
        "repeats": params.get("repeats", 7),
        "weave": v_weave,
        "capsize": v_capsize,
        "resolution": float(speeds[1] - speeds[0]),
    }


TASKS = {"versions": versions, "raw": raw, "eig": eig, "scan": scan}


def serve() -> None:
    for line in sys.stdin:
        task, _, text = line.strip().partition(" ")
        print(json.dumps(TASKS[task](json.loads(text) if text else {})), flush=True)


if __name__ == "__main__":
    if sys.argv[1] == "serve":
        serve()
    else:
        task, params = sys.argv[1], json.loads(sys.argv[2]) if len(sys.argv) > 2 else {}
        print(json.dumps(TASKS[task](params)))
