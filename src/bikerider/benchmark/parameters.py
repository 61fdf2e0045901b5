"""The 26 benchmark values (Meijaard et al. 2007, Table 1; 25 parameters plus gravity)."""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from bikerider.benchmark import rules
from bikerider.errors import MISSING, InputError
from bikerider.generated.manifest import BENCHMARK_NAMES
from bikerider.inertia import TRIANGLE_TOLERANCE, check_plane_symmetric_inertia
from bikerider.quantity import DEG, Quantity, check_magnitude

BENCHMARK_NAMES: tuple[str, ...] = BENCHMARK_NAMES
"""Names in the order of Meijaard et al. (2007), Table 1 (``derive/symbols.py``)."""

OPTIONAL_NAMES = frozenset({"IByy", "IHyy"})
"""Values the linear model does not need; ``None`` when the inputs do not determine them."""

LOG = logging.getLogger(__name__)

_NAME_SET = frozenset(BENCHMARK_NAMES)


@dataclass(frozen=True)
class BenchmarkParameters:
    """The benchmark values in SI units, with standard uncertainties.

    Attributes
    ----------
    values : dict
        Name to value; ``None`` for ``IByy``/``IHyy`` when not determined.
    sigmas : dict
        Name to standard uncertainty (0 when unknown).
    source : str or None
        Where the values came from, for error messages.
    """

    values: dict[str, float | None]
    sigmas: dict[str, float] = field(default_factory=dict)
    source: str | None = None

    @classmethod
    def from_mapping(cls, mapping: Mapping[str, object], source: str | None = None) -> BenchmarkParameters:
        """Build from a mapping of names to numbers or :class:`Quantity`; validate.

        Raises
        ------
        InputError
            A missing or unknown name, a non-finite value, a non-positive mass, length or wheel
            inertia, an impossible steer axis tilt, or an impossible inertia tensor.
        """
        if not _NAME_SET.issuperset(mapping):
            unknown = sorted(set(mapping) - _NAME_SET)
            raise InputError(
                unknown[0], mapping[unknown[0]], f"one of the benchmark names {', '.join(BENCHMARK_NAMES)}", source
            )
        values: dict[str, float | None] = {}
        sigmas: dict[str, float] = {}
        get, isfinite = mapping.get, math.isfinite
        for name in BENCHMARK_NAMES:
            raw = get(name)
            if raw is None:
                if name in OPTIONAL_NAMES:
                    values[name], sigmas[name] = None, 0.0
                    continue
                if name == "g":
                    values[name], sigmas[name] = 9.81, 0.0
                    continue
                raise InputError(name, MISSING, "a value (all 25 benchmark parameters are needed)", source)
            q = raw if isinstance(raw, Quantity) else Quantity(float(raw))  # type: ignore[arg-type]
            if not isfinite(q.value):
                raise InputError(name, q.value, "a finite number", source)
            values[name], sigmas[name] = q.value, q.sigma
        params = cls(values, sigmas, source)
        params.validate()
        return params

    def validate(self) -> None:
        """Raise :class:`InputError` for values no real bicycle can have (the rules of
        :mod:`bikerider.benchmark.rules`, in their order)."""
        v, src = self.values, self.source
        for name in rules.POSITIVE:
            if v[name] <= 0:  # type: ignore[operator]
                raise InputError(name, v[name], "a positive value", src)
        for name, (limit, unit) in rules.LIMITS.items():
            if v[name] is not None and not abs(v[name]) <= limit:  # type: ignore[arg-type]
                check_magnitude(name, v[name], limit, unit, src)  # type: ignore[arg-type]
        for name in rules.DIVISORS:  # the model divides by these
            if v[name] < rules.MIN_DIVISOR:  # type: ignore[operator]
                raise InputError(name, v[name], rules.DIVISOR_EXPECTED, src)
        if not -math.pi / 2 < v["lam"] < math.pi / 2:  # type: ignore[operator]
            hint = (
                f" ({v['lam']:g} looks like degrees: give lam_deg = {v['lam']:g} in a TOML file, "
                f"or {v['lam'] * DEG:.6g} rad)"
                if abs(v["lam"]) <= 90
                else ""
            )  # type: ignore[arg-type]
            raise InputError("lam", v["lam"], f"{rules.TILT_EXPECTED}{hint}", src)
        for name in rules.BELOW_GROUND:
            if not v[name] < 0:  # type: ignore[operator]
                raise InputError(name, v[name], rules.BELOW_GROUND_EXPECTED, src)
        for body in rules.BODIES:
            check_plane_symmetric_inertia(
                rules.tensor_name(body),
                *(v[k] for k in rules.tensor_entries(body)),  # type: ignore[arg-type]
                src,
            )
        for wheel in rules.WHEELS:
            check_wheel_inertia(
                wheel,
                v[f"I{wheel}xx"],
                v[f"I{wheel}yy"],  # type: ignore[arg-type]
                self.sigmas.get(f"I{wheel}xx", 0.0),
                self.sigmas.get(f"I{wheel}yy", 0.0),
                src,
            )

    def with_values(self, **changes: float | Quantity) -> BenchmarkParameters:
        """A copy with some values changed, validated; the others keep their values and uncertainties.

        Parameters
        ----------
        **changes : float or Quantity
            New values by benchmark name (SI units, ``lam`` in radians); a :class:`Quantity` sets
            the uncertainty too, a plain number makes it zero.

        Raises
        ------
        InputError
            An unknown name, or a changed set no bicycle can have (the message names the value).

        Examples
        --------
        >>> longer_trail = parameters.with_values(c=0.1)  # doctest: +SKIP
        """
        unknown = sorted(set(changes) - _NAME_SET)
        if unknown:
            raise InputError(
                unknown[0], changes[unknown[0]], f"one of the benchmark names {', '.join(BENCHMARK_NAMES)}", self.source
            )
        mapping: dict[str, object] = {
            name: (None if self.values[name] is None else Quantity(self.values[name], self.sigmas.get(name, 0.0)))  # type: ignore[arg-type]
            for name in BENCHMARK_NAMES
        }
        mapping.update(changes)
        changed = ", ".join(f"{k}={v.value if isinstance(v, Quantity) else v:g}" for k, v in changes.items())
        source = f"{self.source or 'parameters'} with {changed}" if changes else self.source
        return BenchmarkParameters.from_mapping({k: v for k, v in mapping.items() if v is not None}, source)

    def __getitem__(self, name: str) -> float | None:
        return self.values[name]

    def as_dict(self) -> dict[str, float | None]:
        """Name to value, in Table 1 order (``None`` where not determined)."""
        return {name: self.values[name] for name in BENCHMARK_NAMES}


def check_wheel_inertia(
    wheel: str, Ixx: float, Iyy: float, sigma_xx: float, sigma_yy: float, source: str | None = None
) -> None:
    """Triangle inequality of an axisymmetric wheel: ``I_yy <= 2 I_xx`` (``2 I_xx - I_yy = 2 int y^2 dm``).

    A violation within the combined standard uncertainty of the two values is logged (printed
    values are rounded: the paper's I_Ryy = 0.16 with I_Rxx = 0.079); a larger one is an error.
    """
    excess = Iyy - 2 * Ixx
    if excess <= TRIANGLE_TOLERANCE * Iyy:
        return
    allowed = math.hypot(sigma_yy, 2 * sigma_xx)
    message = (
        f"at most 2*I{wheel}xx = {2 * Ixx:.6g} (triangle inequality of an axisymmetric wheel; "
        f"exceeded by {excess:.3g} kg m^2, combined uncertainty {allowed:.3g})"
    )
    if excess > allowed:
        raise InputError(f"I{wheel}yy", Iyy, message, source)
    LOG.warning("I%syy = %.6g is not %s; accepted within its uncertainty", wheel, Iyy, message)
