"""Which printed values of Moore et al. (2009) the method reproduces, and why the others differ.

Every row holds a value as printed in the paper (``../shared/seed``), the value bikerider computes
from the paper's own inputs (``data/paper/*.toml``), and - when the two differ at the printed
precision - the cause found.  ``docs/scripts/reproduction.py`` writes ``docs/reproduction.md`` from
these rows; ``tests/test_paper_reproduction.py`` pins the computed values and checks every stated
cause.  The method is never adjusted to hit a printed number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bikerider.benchmark import BenchmarkParameters, WhippleModel
from bikerider.estimate import EstimateResult, estimate_default
from bikerider.generated.manifest import MATRIX_NAMES
from bikerider.quantity import DEG

#: Table 10 as printed (value column), grid points 1..31 [m].
TABLE_10 = [
    (0, 0, 0),
    (0, 0, -0.342),
    (0, 0.065, -0.342),
    (0, -0.065, -0.342),
    (0.458, 0, -0.295),
    (1.120, 0, 0),
    (1.120, 0, -0.342),
    (1.120, 0.050, -0.342),
    (1.120, -0.050, -0.342),
    (0.263, 0, -0.788),
    (0.887, 0, -0.733),
    (0.865, 0, -0.788),
    (0.175, 0, -1.011),
    (0.551, 0, -0.746),
    (0.235, 0, -1.488),
    (0.773, 0, -1.021),
    (0.773, 0.220, -1.021),
    (0.773, -0.220, -1.021),
    (0.583, 0.220, -1.021),
    (0.583, -0.220, -1.021),
    (0.235, 0.220, -1.488),
    (0.235, -0.220, -1.488),
    (0.321, 0.220, -1.222),
    (0.321, -0.220, -1.222),
    (0.246, 0, -1.579),
    (0.458, 0.130, -0.295),
    (0.458, -0.130, -0.295),
    (0.551, 0.130, -0.746),
    (0.551, -0.130, -0.746),
    (0.175, 0.130, -1.011),
    (0.175, -0.130, -1.011),
]

#: Table 12 as printed (benchmark names; I_Byy and I_Hyy are left symbolic there).
TABLE_12 = dict(
    w=1.120,
    c=0.055,
    lam=0.38,
    g=9.81,
    rR=0.342,
    mR=3.12,
    IRxx=0.08,
    IRyy=0.16,
    xB=0.28,
    zB=-1.03,
    mB=86.0,
    IBxx=11.89,
    IBzz=3.73,
    IBxz=-2.13,
    xH=0.88,
    zH=-0.78,
    mH=4.35,
    IHxx=0.35,
    IHzz=0.07,
    IHxz=-0.04,
    rF=0.342,
    mF=2.02,
    IFxx=0.08,
    IFyy=0.16,
)
TABLE_12_DECIMALS = dict(
    w=3,
    c=3,
    lam=2,
    g=2,
    rR=3,
    mR=2,
    IRxx=2,
    IRyy=2,
    xB=2,
    zB=2,
    mB=0,
    IBxx=2,
    IBzz=2,
    IBxz=2,
    xH=2,
    zH=2,
    mH=2,
    IHxx=2,
    IHzz=2,
    IHxz=2,
    rF=3,
    mF=2,
    IFxx=2,
    IFyy=2,
)

#: Eqs. 18-21 as printed.
EQS_18_21 = {
    "M": ((106.87, 1.41), (1.41, 0.22)),
    "C1": ((0.0, 27.06), (-0.57, 0.97)),
    "K0": ((-93.73, -1.58), (-1.58, -0.58)),
    "K2": ((0.0, 78.72), (0.0, 1.48)),
}
_EQ_NUMBER = {"M": 18, "C1": 19, "K0": 20, "K2": 21}

INERTIA_CAUSE = (
    "Table 12's own values give {table12} here (bikerider's computed value uses Eq. 7's I_Fyy = 0.100). "
    "Every printed entry of Eqs. 18-21 is reproduced within Table 12's rounding only with a front-wheel "
    "I_yy of about 0.19 kg m^2, neither the printed 0.16 nor Eq. 7's 0.100 (see the findings above)."
)

K0_CAUSE = (
    "Eq. 20 follows from Table 12's rounded values (they give {table12} here); bikerider keeps the "
    "unrounded m_B = 86.05 kg, z_B = -1.0292 m, x_B = 0.2842 m."
)
GRID_CAUSE = (
    "A last-digit difference ({diff:.2f} mm, under one unit of the printed 1 mm place): the point comes "
    "from a square root (fork crown, knee or elbow closure) of the rounded Table 1 and 7 inputs; the other "
    "coordinates of the same point agree."
)

CAUSES: dict[str, str] = {
    "Table 6: I_Fyy": (
        "Eq. 7 with the printed T = 1.37 s, m = 2.02 kg, l = 0.303 m gives 0.100 kg m^2; 0.16 would need "
        "T = 1.51 s. The printed period (or value) is inconsistent; bikerider keeps Eq. 7."
    ),
    "Table 12: I_Fyy": "Same as Table 6: Eq. 7 on the printed period gives 0.100 kg m^2, not 0.16.",
    "Table 12: I_Hzz": (
        "Table 12 prints 0.07 but Table 5, its source, prints I_Hzz = 0.06 (Table 4's third handlebar row, "
        "from which it came, is lost). bikerider uses Table 5."
    ),
    "Table 12: I_Bxx": (
        "The printed inputs (Table 5 rear frame from Table 4, Eq. 14 rider, Tables 2-3, Eqs. 15-16) give "
        "11.93 kg m^2; 11.89 is not reproduced by any combination of the printed values tried "
        "(rounded or unrounded centres of mass). The difference, 0.3 %, is well inside the propagated "
        "uncertainty of about +/-0.06 kg m^2 of the rear frame's I_xx alone."
    ),
    "Table 12: I_Bzz": (
        "The printed inputs give 3.719 kg m^2 (rider 2.362 + frame 1.337 + parallel-axis terms); 3.73 is "
        "not reproduced, but lies within the rear frame's +/-0.06 kg m^2 (Table 5)."
    ),
}


@dataclass(frozen=True)
class Row:
    """One printed value and its comparison."""

    label: str
    printed: float
    computed: float
    decimals: int

    @property
    def reproduced(self) -> bool:
        """Equal at the printed precision (half a unit in the last printed place)."""
        return abs(self.computed - self.printed) <= 0.5 * 10.0 ** (-self.decimals) + 1e-12

    @property
    def cause(self) -> str:
        return "" if self.reproduced else CAUSES.get(self.label, "")


def table12_model() -> WhippleModel:
    """The model built from Table 12's printed parameters (steer axis tilt from the 68.5 deg head angle)."""
    values = dict(TABLE_12)
    values["lam"] = math.pi / 2 - 68.5 * DEG
    values["IRyy"] = 2 * values["IRxx"]  # printed 0.16 = 2 x 0.08 exactly: at the wheel's physical limit
    return WhippleModel.from_parameters(BenchmarkParameters.from_mapping(values, "Moore et al. 2009, Table 12"))


def rows(result: EstimateResult | None = None) -> list[Row]:
    """Every printed value of Tables 5, 6, 10, 12 and Eqs. 8, 14, 18-21 with bikerider's value."""
    result = result or estimate_default()
    b, p, rm, model = result.bicycle, result.parameters.values, result.rider_model, result.model
    out: list[Row] = []
    # Table 5: rear frame from Table 4 periods (the handlebar tensor is an input: its period row is lost).
    for label, name, printed in (("I_Bfxx", "IBfxx", 1.12), ("I_Bfxz", "IBfxz", -0.44), ("I_Bfzz", "IBfzz", 1.34)):
        out.append(Row(f"Table 5: {label}", printed, b[name], 2))
    # Table 6: wheels.
    out.append(Row("Table 6: I_Fxx", 0.08, b["IFxx"], 2))
    out.append(Row("Table 6: I_Fyy", 0.16, b["IFyy"], 2))
    out.append(Row("Table 6: I_Rxx", 0.08, b["IRxx"], 2))
    # Table 10: grid points.
    for i, printed in enumerate(TABLE_10):
        for axis, value in zip("xyz", printed):
            out.append(Row(f"Table 10: r{i + 1}{axis}", value, float(rm.grid_points[i, "xyz".index(axis)]), 3))
    # Eq. 8 and Eq. 14.
    for axis, printed in zip("xyz", (0.291, 0.0, -1.109)):
        out.append(Row(f"Eq. 8: r_Br{axis}", printed, float(rm.com["xyz".index(axis)]), 3))
    for label, (i, j), printed in (
        ("I_Brxx", (0, 0), 8.00),
        ("I_Bryy", (1, 1), 8.07),
        ("I_Brzz", (2, 2), 2.36),
        ("I_Brxz", (0, 2), -1.93),
    ):
        out.append(Row(f"Eq. 14: {label}", printed, float(rm.inertia[i, j]), 2))
    # Table 12.
    for name, printed in TABLE_12.items():
        label = name if len(name) < 3 else f"{name[0]}_{name[1:]}"
        out.append(Row(f"Table 12: {label}", printed, float(p[name]), TABLE_12_DECIMALS[name]))  # type: ignore[arg-type]
    # Eqs. 18-21.
    t12 = table12_model()
    for mat, printed in EQS_18_21.items():
        computed = getattr(model, mat)
        for i in range(2):
            for j in range(2):
                label = f"Eq. {_EQ_NUMBER[mat]}: {mat}[{i + 1},{j + 1}]"
                out.append(Row(label, printed[i][j], float(computed[i, j]), 2))
                row = out[-1]
                if not row.reproduced and label not in CAUSES:
                    CAUSES[label] = (K0_CAUSE if mat == "K0" else INERTIA_CAUSE).format(
                        table12=f"{getattr(t12, mat)[i, j]:.2f}"
                    )
    for row in out:
        if row.label.startswith("Table 10") and not row.reproduced and row.label not in CAUSES:
            CAUSES[row.label] = GRID_CAUSE.format(diff=1000 * abs(row.computed - row.printed))
    return out


def markdown(all_rows: list[Row]) -> str:
    """The table of ``docs/reproduction.md``."""
    lines = [
        "| printed value | printed | computed | reproduced | cause when not |",
        "|---|---:|---:|:---:|---|",
    ]
    for r in all_rows:
        mark = "yes" if r.reproduced else "**no**"
        lines.append(f"| {r.label} | {r.printed:.{r.decimals}f} | {r.computed:.4f} | {mark} | {r.cause} |")
    return "\n".join(lines)


def summary(all_rows: list[Row]) -> dict[str, int]:
    """Counts of reproduced and not reproduced values."""
    n_ok = sum(r.reproduced for r in all_rows)
    return {"values": len(all_rows), "reproduced": n_ok, "not_reproduced": len(all_rows) - n_ok}


def table12_matrices() -> dict[str, np.ndarray]:
    """M, C1, K0, K2 from Table 12 as printed (for the cause analysis)."""
    m = table12_model()
    return {"M": m.M, "C1": m.C1, "K0": m.K0, "K2": m.K2}


# ------------------------------------------------------------------------------------------
# Two questions the printed values raise, answered from the paper alone
# ------------------------------------------------------------------------------------------
#: Table 4 as printed: the rear frame's periods [s] and pendulum-axis angles [deg]; Kooijman's k [N m/rad].
TABLE_4_REAR_FRAME = ((3.60, 41.0), (3.40, 81.0), (2.50, 150.0))
K_TORSIONAL = 5.01


def eq6_rear_frame() -> dict[str, float]:
    """Eqs. 1 and 6 on Table 4's printed rear-frame periods and angles, and the tensor of Eq. 3.

    Returns ``{"I_xx", "I_xz", "I_zz"}`` as Eq. 6 solves them and ``"tensor_xz"``, the
    off-diagonal entry of the tensor Eq. 3 defines (``-I_xz``): Eq. 6 gives ``I_xz = +0.437`` and
    Eq. 3 puts ``-0.437`` off the diagonal, which is what Table 5 prints (-0.44).  The sign of
    Table 5 follows from the paper's own equations; it is not an erratum.
    """
    periods = np.array([t for t, _ in TABLE_4_REAR_FRAME])
    alpha = np.radians([a for _, a in TABLE_4_REAR_FRAME])
    J = K_TORSIONAL * periods**2 / (4 * np.pi**2)  # Eq. 1
    A = np.column_stack([np.cos(alpha) ** 2, 2 * np.sin(alpha) * np.cos(alpha), np.sin(alpha) ** 2])  # Eq. 6
    Ixx, Ixz, Izz = np.linalg.solve(A, J)
    return {"I_xx": float(Ixx), "I_xz": float(Ixz), "I_zz": float(Izz), "tensor_xz": float(-Ixz)}


def _table12_box() -> tuple[list[str], np.ndarray, np.ndarray]:
    """Table 12's printed values as intervals of half a unit in the last printed place (I_Fyy apart)."""
    from bikerider.engine import arguments

    names = [n for n in arguments("benchmark_model.canonical_matrices") if n != "IFyy"]
    centre = np.array([TABLE_12[n] for n in names])
    half = np.array([0.5 * 10.0 ** -TABLE_12_DECIMALS[n] for n in names])
    return names, centre - half, centre + half


def _eqs_18_21_entries(names: list[str], values: np.ndarray, IFyy: float) -> np.ndarray:
    """The 16 entries of M, C1, K0, K2 for each row of ``values`` (shape ``(..., len(names))``)."""
    from bikerider.generated import benchmark_model as gen

    kw = {n: values[..., i] for i, n in enumerate(names)}
    matrices = gen.canonical_matrices(**kw, IFyy=np.full(values.shape[:-1], IFyy))
    return np.concatenate([np.reshape(np.asarray(m), values.shape[:-1] + (4,)) for m in matrices], axis=-1)


def eqs_18_21_misfit(IFyy: float) -> float:
    """The smallest largest difference, over every printed entry of Eqs. 18-21, between the printed
    matrices and those of benchmark parameters within Table 12's rounding, with front-wheel ``IFyy``.

    A sequential linear programme (``scipy.optimize.linprog``) over the box of Table 12's values,
    relinearised twice; the returned misfit is evaluated exactly at the final point.  Eqs. 18-21 are
    printed to two decimals: a misfit at most 0.005 means every entry is reproduced.
    """
    from scipy.optimize import linprog

    names, lo, hi = _table12_box()
    printed = np.array([x for mat in MATRIX_NAMES for row in EQS_18_21[mat] for x in row])
    x = 0.5 * (lo + hi)
    n = len(names)
    for _ in range(3):
        steps = np.maximum(1e-7 * np.abs(x), 1e-9)
        batch = np.vstack([x, x + np.diag(steps)])
        entries = _eqs_18_21_entries(names, batch, IFyy)
        f0, J = entries[0], ((entries[1:] - entries[0]) / steps[:, None]).T
        # minimise t subject to |f0 + J dx - printed| <= t and lo <= x + dx <= hi
        A = np.vstack([np.hstack([J, -np.ones((16, 1))]), np.hstack([-J, -np.ones((16, 1))])])
        b = np.concatenate([printed - f0, f0 - printed])
        solution = linprog(
            np.r_[np.zeros(n), 1.0], A_ub=A, b_ub=b, bounds=[*zip(lo - x, hi - x), (0, None)], method="highs"
        )
        x = np.clip(x + solution.x[:n], lo, hi)
    return float(np.max(np.abs(_eqs_18_21_entries(names, x[None, :], IFyy)[0] - printed)))


def front_wheel_iyy_for_eqs_18_21(bracket: tuple[float, float] = (0.10, 0.30)) -> tuple[float, float]:
    """The front-wheel I_yy [kg m^2] with which every printed entry of Eqs. 18-21 is reproduced by
    values within Table 12's rounding: ``(low, high)``, each to 1e-5 kg m^2.

    The misfit (:func:`eqs_18_21_misfit`) is convex in I_Fyy near its minimum; the interval is
    where it is at most 0.005, found by bisection on each side of the scanned minimum.
    """
    grid = np.linspace(*bracket, 41)
    misfits = [eqs_18_21_misfit(float(v)) for v in grid]
    best = float(grid[int(np.argmin(misfits))])
    if min(misfits) > 0.005:
        raise ValueError("no I_Fyy in the bracket reproduces Eqs. 18-21")

    def edge(inside: float, outside: float) -> float:
        while abs(outside - inside) > 1e-5:
            middle = 0.5 * (inside + outside)
            inside, outside = (middle, outside) if eqs_18_21_misfit(middle) <= 0.005 else (inside, middle)
        return inside

    return edge(best, bracket[0]), edge(best, bracket[1])
