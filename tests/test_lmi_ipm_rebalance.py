"""The IPM's rebalanced retry (``solver_options["rebalance"]``, :mod:`lmi.backends.ipm`).

The plant is a small analogue of the flexible satellite on its 8-vertex 'groups' polytope: one
axis, a hub of inertia ``J`` (``20 / 0.8`` and ``20 / 1.2`` kg m^2) carrying one lightly damped
mode (``0.8 rad/s x 0.9, 1.1``, damping ``0.005 x 0.5, 2``, coupling 1), sampled at 0.5 s,
weights ``400`` on the hub angle and rate and ``0.1`` on the mode, peak bound 0.5 N m, a 20 deg
initial angle at rest. The input bound squeezes the optimal ellipsoid along the modal
coordinates, which the nominal Riccati diagonal (:mod:`lmi.scaling`) does not predict: the
balanced coordinates leave ``Q~``'s diagonal spanning about three decades. The IPM crawled
until its stall test, which then fired when the worst of the residuals and gap had not halved
over the window, stopped it
("insufficient_progress" after 29 iterations), and the retry balanced on that run's ``Q~`` ended
"optimal". The stall test now fires only when none of them has halved
(:data:`lmi.ipm.solver.STALL_WINDOW`), and the run converges without the retry.

The retry itself (coordinates ``x = T x~`` from the Cholesky factor of the failed run's ``Q~``)
is checked on its own: the coordinates it picks balance ``Q~`` exactly, it is refused when there
is nothing to gain, and a problem held in full-matrix coordinates gives the answers of the
original one.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.linalg import expm

from lmi import KothareProblem
from lmi.backends.base import RawResult

DT = 0.5
U_MAX = 0.5


def _vertex(inertia: float, freq: float, damping: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold model of ``[theta, eta, omega, eta']`` (hub angle, modal coordinate)."""
    mass = np.array([[inertia, 1.0], [1.0, 1.0]])  # coupling 1 between hub and mode
    stiff = np.diag([0.0, freq**2])
    damp = np.diag([0.0, 2.0 * damping * freq])
    inv = np.linalg.inv(mass)
    a = np.block([[np.zeros((2, 2)), np.eye(2)], [-inv @ stiff, -inv @ damp]])
    b = np.concatenate([np.zeros(2), inv[:, 0]])[:, None]
    big = expm(np.block([[a, b], [np.zeros((1, 5))]]) * DT)
    return big[:4, :4], big[:4, 4:]


def _problem(**kw):
    vertices = [_vertex(20.0 / sj, 0.8 * sw, 0.005 * sz)
                for sj, sw, sz in itertools.product((0.8, 1.2), (0.9, 1.1), (0.5, 2.0))]
    a = [v[0] for v in vertices]
    b = [v[1] for v in vertices]
    return KothareProblem(a, b, np.diag([400.0, 0.1, 400.0, 0.1]), np.eye(1), dt=DT,
                          input_constraint="peak", u_max=U_MAX, **kw)


X0 = np.array([np.deg2rad(20.0), 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def reference():
    """cvxpy + Clarabel at 1e-9 on the delta form (at 1e-10 it ends "inaccurate")."""
    opts = {"tol_gap_abs": 1e-9, "tol_gap_rel": 1e-9, "tol_feas": 1e-9, "max_iter": 500}
    sol = _problem(backend="cvxpy", solver="CLARABEL", formulation="delta",
                   solver_options=opts).solve(X0)
    assert sol.status == "optimal", sol.solver_status
    return sol


def test_the_ipm_alone_solves_the_squeezed_problem(reference):
    """Without fallback the IPM ends "optimal" (certified); gamma agrees with cvxpy + Clarabel.

    The agreement is 1e-6 relative, not 1e-8: Clarabel's point is infeasible by about 3e-11
    (its certificate margin) and on this thin ellipsoid that buys it a lower gamma, 1.6e-7 below
    the IPM's certified one (measured); the IPM's margins are at rounding level."""
    sol = _problem(solver_options={"fallback": False}).solve(X0)
    assert sol.status == "optimal", sol.solver_status
    assert sol.certificate.ok and min(sol.margins.values()) > -1e-12
    assert sol.gamma == pytest.approx(reference.gamma, rel=1e-6)
    assert sol.gamma >= reference.gamma  # Clarabel's slightly infeasible point is below
    # the feedback keeps the state in its ellipsoid: x' Q^-1 x <= 1
    assert X0 @ np.linalg.solve(sol.Q, X0) <= 1.0 + 1e-9


def test_without_rebalance_the_ipm_converges_too():
    """The same problem with ``rebalance=False``: the main run converges (it stalled after 29
    iterations when the stall test fired on the worst measure alone)."""
    sol = _problem(solver_options={"fallback": False, "phase_one": False,
                                   "rebalance": False}).solve(X0)
    assert sol.status == "optimal"
    assert sol.solver_status == "optimal"


def _raw(q_mat: np.ndarray) -> RawResult:
    return RawResult("numerical_error", "insufficient_progress", 1.0, q_mat, np.zeros((1, 4)), 30, 0.0)


def _as_matrix(t: np.ndarray) -> np.ndarray:
    return np.diag(t) if t.ndim == 1 else t


XS = np.array([0.5, -0.5, 0.5, 0.5])  # a normalised state in the current coordinates


def test_the_retry_coordinates_balance_q_and_keep_the_state_length():
    """From a failed run's ``Q~`` at the normalised state ``xs`` (current coordinates ``T``),
    ``T_new = T L ||L^-1 xs||`` (``Q~ = L L'``): in the new coordinates that ``Q~`` is a multiple of
    the identity and ``xs`` keeps its length (the objective the solver sees keeps its size)."""
    backend = _problem(solver_options={"fallback": False})._backend
    backend._last_residual = 1e-6
    t_old = _as_matrix(backend._t)
    basis = np.linalg.qr(np.random.default_rng(4).normal(size=(4, 4)))[0]
    q_tilde = basis @ np.diag([1e-3, 0.1, 2.0, 50.0]) @ basis.T
    step = np.linalg.solve(t_old, backend._rebalanced_scaling(_raw(q_tilde), XS))
    balanced = np.linalg.solve(step, np.linalg.solve(step, q_tilde).T)
    level = float(np.mean(np.diag(balanced)))
    # measured 5.1e-13 relative (Q~ has condition number 5e4)
    assert np.max(np.abs(balanced - level * np.eye(4))) <= 1e-11 * level
    assert np.linalg.norm(np.linalg.solve(step, XS)) == pytest.approx(1.0, rel=1e-12)


def test_the_retry_is_refused_when_there_is_nothing_to_gain():
    backend = _problem(solver_options={"fallback": False})._backend
    backend._last_residual = 1e-6
    assert backend._rebalanced_scaling(_raw(np.diag([1.0, 2.0, 5.0, 19.0])), XS) is None  # cond < MIN_SPREAD
    assert backend._rebalanced_scaling(_raw(np.diag([1e-3, 2.0, 5.0, -19.0])), XS) is None  # not PD
    assert backend._rebalanced_scaling(_raw(np.diag([1e-3, 2.0, 5.0, 19.0])), XS) is not None
    backend._last_residual = 1e-2  # the run did not come near feasibility
    assert backend._rebalanced_scaling(_raw(np.diag([1e-3, 2.0, 5.0, 19.0])), XS) is None


def test_full_matrix_coordinates_give_the_original_answers():
    """The problem held in coordinates ``x = T x~`` with a full ``T`` (as a retry leaves it, and
    keeps for the next solves): the answer, mapped back, is the original problem's, certified in
    the caller's coordinates; a reset returns to the coordinates of the construction."""
    prob = _problem(solver_options={"fallback": False, "warm_start": False})
    plain = prob.solve(X0)
    backend = prob._backend
    initial = backend._t.copy()
    t_full = np.eye(4) + 0.3 * np.random.default_rng(5).normal(size=(4, 4))
    backend._build(_as_matrix(initial) @ t_full)
    moved = prob.solve(X0)
    assert moved.status == "optimal", moved.solver_status
    assert moved.certificate.ok and min(moved.margins.values()) > -1e-12
    assert moved.gamma == pytest.approx(plain.gamma, rel=1e-8)  # both optimal to 1e-8
    prob.reset()
    assert np.array_equal(backend._t, initial)


def test_rebalance_is_a_checked_setting():
    from toolkit_common.errors import InvalidArgumentError

    with pytest.raises(InvalidArgumentError, match="rebalance"):
        _problem(solver_options={"rebalance": 1})
