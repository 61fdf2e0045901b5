"""First-order propagation of measurement uncertainties through the whole chain.

``sigma_y^2 = sum_j (dy/dp_j)^2 sigma_j^2`` with the closed-form Jacobian of the estimate chain
(the uncertainty engine, :mod:`bikerider.engine`, over :mod:`bikerider.uncertainty.stages`); the
inputs are taken as independent.  Correlations the chain
itself creates (one pendulum stiffness in every torsional inertia, one wheel mass in its mass and
its compound pendulum) are carried exactly when the raw measurements are given (see
:mod:`bikerider.uncertainty.stages`); when already-reduced values are given their correlations
are not known and are taken as zero.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from bikerider.engine import first_order
from bikerider.errors import InputError
from bikerider.generated.manifest import BENCHMARK_NAMES
from bikerider.quantity import Quantity
from bikerider.uncertainty.chain import Chain, prepare_values
from bikerider.uncertainty.eigen import EigenSensitivity, eigen_sensitivity
from bikerider.uncertainty.stages import COEFFICIENTS, ENTRIES, SPEEDS

SPEED_NODES = dict(zip(("weave", "capsize"), SPEEDS))


@dataclass(frozen=True)
class Contribution:
    """One input's part in an output's uncertainty.

    Attributes
    ----------
    name : str
    value, sigma : float
        The input and its standard uncertainty.
    derivative : float
        ``dy/dp`` (SI units of the output per SI unit of the input).
    elasticity : float or None
        ``(p / y) dy/dp``: the percent change of the output per percent change of the input.
    variance : float
        ``(dy/dp sigma)^2``.
    share : float
        ``variance`` over the output's first-order variance (0..1).
    source : str
        Where the sigma comes from.
    """

    name: str
    value: float
    sigma: float
    derivative: float
    elasticity: float | None
    variance: float
    share: float
    source: str


@dataclass(frozen=True)
class EigenvalueUncertainty:
    """Eigenvalues at chosen speeds with first-order sigmas of their real and imaginary parts."""

    sensitivity: EigenSensitivity
    sigma_real: np.ndarray
    sigma_imag: np.ndarray

    def as_list(self) -> list[dict]:
        """One JSON-ready dict per speed and mode: ``speed, mode, real, imag, sigma_real, sigma_imag,
        condition``.  A number that is not finite (a sigma at an exactly double eigenvalue, where the
        first-order formula fails) is ``None``; a large ``condition`` warns of the same nearby."""
        out = []
        s = self.sensitivity
        for n, v in enumerate(s.speeds):
            for k in range(4):
                out.append(
                    {
                        "speed": float(v),
                        "mode": str(s.labels[n, k]),
                        "real": _finite(s.values[n, k].real),
                        "imag": _finite(s.values[n, k].imag),
                        "sigma_real": _finite(self.sigma_real[n, k]),
                        "sigma_imag": _finite(self.sigma_imag[n, k]),
                        "condition": _finite(s.condition[n, k]),
                    }
                )
        return out


def _finite(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


@dataclass(frozen=True)
class UncertaintyResult:
    """Values, first-order sigmas and the Jacobian of every output of the chain.

    Attributes
    ----------
    input_names, output_names : tuple of str
    inputs : dict of str to Quantity
    sources : dict of str to str
        Where each input's sigma comes from.
    values : dict of str to float or None
        Every output (None where not determined, e.g. IByy without the frame's I_yy).
    sigmas : dict of str to float or None
        First-order standard uncertainty of every output.
    jacobian : ndarray, shape (n_out, n_in)
    eigenvalues : EigenvalueUncertainty or None
        At the speeds asked for.
    """

    input_names: tuple[str, ...]
    output_names: tuple[str, ...]
    inputs: dict[str, Quantity]
    sources: dict[str, str]
    values: dict[str, float | None]
    sigmas: dict[str, float | None]
    jacobian: np.ndarray
    eigenvalues: EigenvalueUncertainty | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def benchmark(self) -> dict[str, float | None]:
        """Sigma of each benchmark parameter (None where not determined)."""
        return {name: self.sigmas.get(name) for name in BENCHMARK_NAMES}

    @property
    def speeds(self) -> dict[str, float | None]:
        """``{"weave": sigma, "capsize": sigma}`` (None where the speed does not exist)."""
        return {key: self.sigmas.get(node) for key, node in SPEED_NODES.items()}

    @property
    def matrices(self) -> dict[str, float | None]:
        """Sigma of each entry of M, C1, K0, K2."""
        return {name: self.sigmas.get(name) for name in ENTRIES}

    def derivative(self, output: str, wrt: str) -> float:
        """``d output / d wrt`` at the inputs."""
        return float(self.jacobian[self._row(output), self._column(wrt)])

    def _row(self, output: str) -> int:
        try:
            return self.output_names.index(output)
        except ValueError:
            raise InputError("OUTPUT", output, f"one of {', '.join(self.output_names)}") from None

    def _column(self, wrt: str) -> int:
        try:
            return self.input_names.index(wrt)
        except ValueError:
            raise InputError("--wrt", wrt, f"one of the inputs {', '.join(self.input_names)}") from None

    def contributions(self, output: str) -> list[Contribution]:
        """Every input's share of ``output``'s variance, largest first (then by |elasticity|)."""
        row = self.jacobian[self._row(output)]
        y = self.values.get(output)
        out = []
        for j, name in enumerate(self.input_names):
            q = self.inputs[name]
            d = float(row[j])
            if not math.isfinite(d):
                continue
            var = (d * q.sigma) ** 2 if q.sigma > 0 else 0.0
            elasticity = q.value / y * d if y not in (None, 0.0) and math.isfinite(q.value) else None
            out.append(Contribution(name, q.value, q.sigma, d, elasticity, var, 0.0, self.sources.get(name, "")))
        total = sum(c.variance for c in out)
        out = [
            Contribution(
                c.name,
                c.value,
                c.sigma,
                c.derivative,
                c.elasticity,
                c.variance,
                c.variance / total if total > 0 else 0.0,
                c.source,
            )
            for c in out
        ]
        out.sort(key=lambda c: (-c.share, -abs(c.elasticity or 0.0)))
        return out

    def as_dict(self) -> dict:
        """JSON-ready summary: sigmas of the benchmark values, matrices and speeds, and the inputs."""
        out = {
            "method": "first-order (closed-form Jacobian), inputs independent",
            "benchmark": self.benchmark,
            "matrices": self.matrices,
            "speeds": self.speeds,
            "speed_values": {key: self.values.get(node) for key, node in SPEED_NODES.items()},
            "inputs": {
                n: {
                    "value": q.value if math.isfinite(q.value) else None,
                    "sigma": q.sigma,
                    "source": self.sources.get(n, ""),
                }
                for n, q in self.inputs.items()
            },
        }
        if self.eigenvalues is not None:
            out["eigenvalues"] = self.eigenvalues.as_list()
        if self.notes:
            out["notes"] = list(self.notes)
        return out


def _as_quantity(name: str, raw: object) -> Quantity:
    if isinstance(raw, Quantity):
        q = raw
    elif isinstance(raw, (int, float)) and not isinstance(raw, bool):
        q = Quantity(float(raw))
    else:
        raise InputError(name, raw, "a number or a Quantity")
    if not (math.isfinite(q.sigma) and q.sigma >= 0):
        raise InputError(f"{name} uncertainty", q.sigma, "a finite, non-negative standard uncertainty")
    return q


def propagate(
    inputs: Mapping[str, Quantity | float],
    speeds: Sequence[float] | None = None,
    sources: Mapping[str, str] | None = None,
) -> UncertaintyResult:
    """First-order uncertainty of every output of the chain.

    Parameters
    ----------
    inputs : mapping of str to Quantity or float
        Chain inputs by name: the arguments of ``generated.combination.estimate_chain``
        (as ``bikerider.estimate.EstimateResult.chain_inputs`` gives them), optionally with raw
        pendulum measurements in place of reduced inertias, or the benchmark parameters
        themselves.  SI units, radians.  ``IBfyy``/``IHyy`` may be NaN (not measured).
    speeds : sequence of float, optional
        Speeds [m/s] at which to propagate to the eigenvalues too.
    sources : mapping of str to str, optional
        Where each sigma comes from, carried into the result.

    Raises
    ------
    InputError
        Unknown names, non-finite values, negative sigmas, or inputs that cannot reach the
        canonical matrices.
    """
    quantities = {name: _as_quantity(name, raw) for name, raw in inputs.items()}
    values = prepare_values(quantities)
    for name in values:
        quantities.setdefault(name, Quantity(float(values[name])))
    if "g" not in values:
        raise InputError("g", "missing", "the acceleration due to gravity (it scales K0 and sets the speeds)")
    chain = Chain(values)
    chain.require(ENTRIES)
    input_names = tuple(values)
    result = first_order(
        chain.stages,
        {name: Quantity(values[name], quantities[name].sigma) for name in input_names},
        chain,
        wrt=input_names,
    )  # every input: derivatives of the exact ones too
    nodes, grads = result.nodes, result.gradients
    output_names = tuple(n for n in _output_order(chain.available))
    J = result.jacobian(output_names)
    sig = result.sigmas
    out_values: dict[str, float | None] = {}
    sigmas: dict[str, float | None] = {}
    overflowed = []
    for name in output_names:
        y = float(nodes[name])
        with np.errstate(over="ignore", invalid="ignore"):  # a sigma near 1e308: inf, said below
            sigma = result.sigma(name, skip_nonfinite=False)
        out_values[name] = y if math.isfinite(y) else None
        sigmas[name] = sigma if math.isfinite(y) and math.isfinite(sigma) else None
        if math.isfinite(y) and math.isinf(sigma):
            overflowed.append(name)
    notes = []
    if overflowed:
        notes.append(
            f"the first-order sigmas of {', '.join(overflowed[:6])}{', ...' if len(overflowed) > 6 else ''} "
            "are beyond floating point: an input's stated uncertainty is too large"
        )
    for key, node in SPEED_NODES.items():
        if out_values.get(node) is None:
            notes.append(f"no {key} speed at positive speed: its sigma is not defined")
    eig = None
    if speeds is not None:
        if all(math.isfinite(float(nodes[k])) for k in ENTRIES):
            eig = _eigen_uncertainty(nodes, grads, input_names, sig, speeds)
        else:
            notes.append("the matrix entries are not all finite: the eigenvalues have no sigmas")
    return UncertaintyResult(
        input_names, output_names, quantities, dict(sources or {}), out_values, sigmas, J, eig, notes
    )


def _output_order(available: set[str]) -> list[str]:
    first = [n for n in BENCHMARK_NAMES if n in available] + [n for n in ENTRIES if n in available]
    first += [n for n in (*SPEEDS, *COEFFICIENTS) if n in available]
    return first + sorted(available - set(first))


def _eigen_uncertainty(nodes, grads, input_names, sig, speeds) -> EigenvalueUncertainty:
    entries = {k: float(nodes[k]) for k in ENTRIES}
    sens = eigen_sensitivity(entries, float(nodes["g"]), speeds)
    # d lambda / d inputs = d lambda / d[entries, g] . d[entries, g] / d inputs
    de = np.array([np.broadcast_to(grads[k], (len(input_names),)) for k in ENTRIES + ("g",)])
    with np.errstate(over="ignore", invalid="ignore"):  # inf where an input's sigma is too large
        dlam = sens.derivatives @ de  # (n, 4, n_in)
        sigma_real = np.sqrt(np.sum((dlam.real * sig) ** 2, axis=-1))
        sigma_imag = np.sqrt(np.sum((dlam.imag * sig) ** 2, axis=-1))
    return EigenvalueUncertainty(sens, sigma_real, sigma_imag)
