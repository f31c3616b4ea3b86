"""Kothare, Balakrishnan & Morari (1996), example 1 (angular positioning), SPEC section 4.

``x(k+1) = A(alpha) x(k) + B u(k)``, ``A = [[1, 0.1], [0, 1 - 0.1 alpha]]``, ``B = [0, 0.0787]'``,
``alpha`` in [0.1, 10] (two vertices), ``Q1 = diag(1, 0)``, ``R = 2e-5``, ``|u| <= 2``,
``x0 = [0.05, 0]``. Published (and reproduced by independent solvers): ``gamma(x0) = 9.716e-3``,
``F(x0) = [-33.21, -6.11]``.

Compared to the precision the values are printed with (:mod:`printed_digits`): gamma within half
a unit of its 4th digit (5e-7, 5.1e-5 relative), F within 0.005. Measured over the back-end /
formulation pairs (Clarabel direct and through cvxpy, SCS, the toolkit's IPM): gamma =
9.71634e-3 (spread 8e-10 between them), 3.40e-7 from 9.716e-3, so 1.6e-7 inside the bound,
200 times the spread; F[0] within 2.1e-3 of -33.21 and F[1] within 4.6e-4 of -6.11, so 2.9e-3
inside the bound, three times the spread of F[0] between back-ends (9e-4: F is set only to
about the square root of gamma's accuracy, a flat optimum).

Realised closed-loop cost over 400 steps (40 s) with the RMPC re-solving every step, divided
by gamma(x0) = 9.7163e-3: 0.817 at alpha = 9, 0.709 at alpha = 1, 0.722 at alpha = 0.1, 0.842
at alpha = 10, 0.742 for a random alpha(k) (seed 11); the tail after 40 s is below 1e-80.
The largest |u| is 1.661 (the first step), below the bound 2.
"""

from __future__ import annotations

import numpy as np
import pytest
from printed_digits import assert_rounds_to

from lmi import KothareProblem
from lmi.data import FORMULATIONS
from models import PolytopicModel
from rmpc import RMPC, simulate

DT = 0.1
Q1 = np.diag([1.0, 0.0])
R = np.array([[2e-5]])
U_MAX = 2.0
X0 = np.array([0.05, 0.0])
GAMMA_PRINTED = "9.716e-3"
F_PRINTED = ("-33.21", "-6.11")
N_STEPS = 400


def plant_at(alpha: float) -> tuple[np.ndarray, np.ndarray]:
    return np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * alpha]]), np.array([[0.0], [0.1 * 0.787]])


@pytest.fixture(scope="module")
def polytope() -> PolytopicModel:
    return PolytopicModel([plant_at(0.1), plant_at(10.0)], dt=DT)


def _controller(polytope: PolytopicModel) -> RMPC:
    return RMPC(polytope, Q=Q1, R=R, u_max=U_MAX, input_constraint="peak")


@pytest.mark.parametrize("formulation", FORMULATIONS)
@pytest.mark.parametrize(
    ("backend", "solver"), [("clarabel", None), ("cvxpy", "CLARABEL"), ("cvxpy", "SCS")]
)
def test_published_gamma_and_gain(polytope, backend, solver, formulation):
    prob = KothareProblem(
        polytope.A, polytope.B, Q1, R, dt=DT, input_constraint="peak", u_max=U_MAX,
        backend=backend, solver=solver, formulation=formulation,
    )
    sol = prob.solve(X0)
    assert sol.status == "optimal", (sol.status, sol.solver_status)
    assert_rounds_to(sol.gamma, GAMMA_PRINTED)
    assert sol.F.shape == (1, 2)
    assert_rounds_to(sol.F[0], F_PRINTED)
    # the first move respects the peak bound and the certificate holds
    assert abs(float(sol.F[0] @ X0)) <= U_MAX + 1e-6
    assert sol.certificate.worst >= -1e-7


def _realised_cost(xs: np.ndarray, us: np.ndarray) -> float:
    return float(np.einsum("ki,ij,kj->", xs, Q1, xs) + np.einsum("ki,ij,kj->", us, R, us))


@pytest.mark.parametrize("alpha", [9.0, 1.0, 0.1, 10.0])
def test_closed_loop_cost_below_gamma_fixed_alpha(polytope, alpha):
    ctrl = _controller(polytope)
    traj = simulate(ctrl, polytope, X0, n_steps=N_STEPS, true_plant=plant_at(alpha))
    gamma0 = traj.gamma[0]
    assert_rounds_to(gamma0, GAMMA_PRINTED)
    cost = _realised_cost(traj.x[:-1], traj.u_cmd)
    # after the last certified solve the controller keeps that gain; its P bounds the cost-to-go
    applied = [i.extra["solution"] for i in traj.info if not i.fallback]
    p_last = [sol for sol in applied if sol is not None][-1].P
    tail = float(traj.x[-1] @ p_last @ traj.x[-1])
    assert tail < 1e-12 * gamma0  # 40 s is long enough: the tail is negligible
    assert cost + tail <= gamma0
    assert np.max(np.abs(traj.u_cmd)) <= U_MAX + 1e-6
    assert np.linalg.norm(traj.x[-1]) < 1e-12
    # every solve away from the origin succeeded (near 1e-8 Clarabel may stop early: a fallback)
    for k, info in enumerate(traj.info):
        if np.linalg.norm(traj.x[k]) > 1e-6:
            assert info.status == "optimal" and not info.fallback, (k, info.status)


def test_closed_loop_cost_below_gamma_time_varying_alpha(polytope):
    rng = np.random.default_rng(11)
    ctrl = _controller(polytope)
    x = X0.copy()
    cost, gamma0, u_peak, p_last = 0.0, None, 0.0, None
    for _ in range(N_STEPS):
        u = ctrl.step(x)
        if gamma0 is None:
            gamma0 = ctrl.last.gamma
        sol = ctrl.last.extra.get("solution")
        if sol is not None and not ctrl.last.fallback:
            p_last = sol.P
        cost += float(x @ Q1 @ x + u @ R @ u)
        u_peak = max(u_peak, float(np.max(np.abs(u))))
        a, b = plant_at(rng.uniform(0.1, 10.0))
        x = a @ x + b @ u
    tail = float(x @ p_last @ x)
    assert tail < 1e-12 * gamma0
    assert cost + tail <= gamma0
    assert u_peak <= U_MAX + 1e-6
    assert np.linalg.norm(x) < 1e-12
