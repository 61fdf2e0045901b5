"""The stiff-tyre limit of ``tyre_slip`` (derive/gap_effects.py, ``tyre_descriptor``) with a pneumatic trail.

As the cornering stiffness ``c_alpha`` grows the slip velocity of each contact vanishes but its slip
force does not: it becomes the lateral reaction of rolling without slip, and the model keeps applying
it ``t_p`` behind the contact.  The limit is therefore the no-slip (Whipple) kinematics with the slip
forces as Lagrange multipliers acting through the partial velocities of their points of application
(``Papp`` in the derivation), not the Whipple model (whose reactions act at the contacts and do no
work).  Here that limit is built from the same generated descriptor, the slip-force rows replaced by
the no-slip constraints ``slip @ x = 0``; its finite generalized eigenvalues are the limit's.
"""

from __future__ import annotations

import inspect

import numpy as np
import pytest
import scipy.linalg
from bikerider.generated import gap_effects as gen

from bikerider.gap.candidates.effect_model import BENCH_ARGS, EffectModel, RiderGeometry

GEOMETRY = RiderGeometry(
    dict(m_u=40.0, x_u=0.3, z_u=-1.2, IUxx=1.5, IUxz=0.3, IUzz=1.0, z_lean=-0.95),
    dict(x_grip=0.85, z_grip=-1.05, b_grip=0.3),
)
NO_LEAN = [0, 1, 3, 4, 5, 6]
"""States phi, delta, u, r, phid, deltad of the descriptor (the upper body does not lean)."""


@pytest.fixture(scope="module")
def values(benchmark_values):
    return dict({k: benchmark_values[k] for k in BENCH_ARGS}, g=9.81)


def tyre(values, c_alpha, t_p, c_gamma=0.8, sigma_t=0.2) -> EffectModel:
    params = {"c_alpha": c_alpha, "c_gamma": c_gamma, "sigma_t": sigma_t, "t_p": t_p}
    return EffectModel(values, GEOMETRY, {"tyre_slip": params})


def stiff_limit(values, speed, t_p, c_gamma=0.8, sigma_t=0.2) -> np.ndarray:
    """Eigenvalues of rolling without slip with the slip forces applied ``t_p`` behind the contacts."""
    model = tyre(values, 1.0, t_p, c_gamma, sigma_t)
    args = dict(model._args(), **model._upper(), k_lean=1.0, c_lean=0.0)
    args.update(c_alpha=1.0, c_gamma=c_gamma, sigma_t=sigma_t, t_p=t_p, v=np.array([speed]))
    E, A, _ = (m[0] for m in gen.tyre_slip_descriptor(**args))
    wanted = inspect.signature(gen.tyre_slip_contacts).parameters
    slip = np.reshape(gen.tyre_slip_contacts(**{k: x for k, x in args.items() if k in wanted})[0], (-1, 2, 10))[0]
    n = len(NO_LEAN)
    E_limit, A_limit = np.zeros((n + 2, n + 2)), np.zeros((n + 2, n + 2))
    E_limit[:n, :n] = E[np.ix_(NO_LEAN, NO_LEAN)]
    A_limit[:n, :n] = A[np.ix_(NO_LEAN, NO_LEAN)]
    A_limit[:n, n:] = A[np.ix_(NO_LEAN, [8, 9])]  # the slip forces, now multipliers, through Papp
    A_limit[n:, :n] = slip[:, NO_LEAN]  # no slip: slip @ x = 0
    eigenvalues = scipy.linalg.eigvals(A_limit, E_limit)
    return np.sort_complex(eigenvalues[np.isfinite(eigenvalues)])


def nearest(eigenvalues: np.ndarray, targets: np.ndarray) -> np.ndarray:
    return np.array([eigenvalues[np.argmin(np.abs(eigenvalues - x))] for x in targets])


@pytest.mark.parametrize("speed", [3.0, 5.0, 8.0])
def test_stiff_tyres_with_a_pneumatic_trail_tend_to_the_trailed_reaction_limit_not_to_whipple(values, speed):
    whipple = np.sort_complex(EffectModel(values, GEOMETRY).eigenvalues([speed])[0])
    limit = stiff_limit(values, speed, t_p=0.02)
    assert limit.size == 4  # roll, steer and their rates: the tyre states have left
    errors = []
    for c_alpha in (1e4, 1e5, 1e6):
        eigenvalues = tyre(values, c_alpha, t_p=0.02).eigenvalues([speed])[0]
        errors.append(np.max(np.abs(nearest(eigenvalues, limit) - limit)))
        # ... and away from the Whipple model by far more than the convergence error
        assert np.max(np.abs(nearest(eigenvalues, whipple) - whipple)) > 0.3
    assert errors[-1] < 1e-4 * np.max(np.abs(limit))
    assert errors[1] < 0.2 * errors[0] and errors[2] < 0.2 * errors[1]  # converging as 1 / c_alpha


def test_the_limit_is_whipple_only_without_pneumatic_trail(values):
    speed = 5.0
    whipple = np.sort_complex(EffectModel(values, GEOMETRY).eigenvalues([speed])[0])
    np.testing.assert_allclose(stiff_limit(values, speed, t_p=0.0), whipple, atol=1e-9)
    # Meijaard et al. (2007) Table 2 at 5 m/s: weave -0.7753 +/- 4.4649i.  With t_p = 20 mm (and the
    # camber stiffness 0.8 /rad the candidate holds) the limit's weave is -0.92 +/- 4.03i (docs/gap.md).
    weave = [x for x in stiff_limit(values, speed, t_p=0.02) if x.imag > 0][0]
    assert weave == pytest.approx(-0.9215 + 4.0313j, abs=1e-3)


def test_relaxation_drops_out_of_the_limit_but_camber_thrust_does_not(values):
    # The relaxation length only lags a force the constraint now sets; the camber thrust acts at the
    # contact while the reaction acts t_p behind it, so their split changes the aligning moment.
    speed = 5.0
    base = stiff_limit(values, speed, t_p=0.02, c_gamma=0.8, sigma_t=0.2)
    np.testing.assert_allclose(stiff_limit(values, speed, t_p=0.02, c_gamma=0.8, sigma_t=0.05), base, atol=1e-10)
    assert np.max(np.abs(stiff_limit(values, speed, t_p=0.02, c_gamma=0.0) - base)) > 0.5
