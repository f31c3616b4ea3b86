"""How far along a slew axis the robust MPC's LMIs reach: the largest certified initial state.

Kothare's problem at ``x`` is feasible when some ellipsoid ``E(Q) = {z : z' Q^-1 z <= 1}``
holds ``x``, is invariant for every vertex under ``u = Y Q^-1 z`` with the cost decrease the
bound ``gamma`` asks for, and keeps the input bound on ``E(Q)``. For a fixed ``gamma`` the
largest ``t`` with ``t d`` in such an ellipsoid is one semidefinite program (the containment
LMI ``[[1, t d'], [t d, Q]] >= 0`` is linear in ``t`` and ``Q``); the feasible states are
star-shaped, so ``t`` is the reach along ``d``. :func:`slew_reach` solves it (cvxpy + Clarabel,
the delta form of :mod:`lmi.backends.cvxpy` with ``gamma_s = dt gamma``) and checks the answer
without the solver: ``Acl_j' Q^-1 Acl_j <= Q^-1`` on every vertex, the peak input over ``E(Q)``
and the level of ``t d``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["SlewReach", "slew_reach"]


@dataclass(frozen=True)
class SlewReach:
    """The reach of the LMIs along one direction at one cost bound.

    Attributes
    ----------
    gamma_s : float
        The cost bound (``dt gamma``).
    status : str
        cvxpy's status (``"optimal"``, ``"optimal_inaccurate"``, or the solver error's name).
    t : float or None
        The largest certified multiple of the direction.
    angle_deg : float or None
        ``2 asin(t)`` in degrees: the slew angle when the direction is a unit ``q_v``.
    contraction : float or None
        Largest eigenvalue of ``L' Acl_j' Q^-1 Acl_j L`` over the vertices (``Q = L L'``):
        at most 1 for an invariant ellipsoid.
    peak_input : float or None
        Largest ``max_{z in E(Q)} |(F z)_r| / u_max_r`` (at most 1).
    """

    gamma_s: float
    status: str
    t: float | None
    angle_deg: float | None
    contraction: float | None
    peak_input: float | None

    @property
    def certified(self) -> bool:
        """Whether the checks hold (invariance and the input bound to 1e-6)."""
        return (
            self.contraction is not None
            and self.peak_input is not None
            and self.contraction <= 1.0 + 1e-6
            and self.peak_input <= 1.0 + 1e-6
        )


def slew_reach(
    polytope: Any, Q: np.ndarray, R: np.ndarray, u_max: float, direction: np.ndarray, gamma_s: float
) -> SlewReach:
    """The largest ``t`` with ``t direction`` feasible for Kothare's LMIs at ``gamma_s`` (peak bound).

    Parameters
    ----------
    polytope : models.PolytopicModel
        The vertices ``(A_j, B_j)`` and ``dt``.
    Q, R : ndarray
        The state and input weights.
    u_max : float
        The per-axis peak bound on ``u``.
    direction : (n,) ndarray
        The direction of the initial state (unit norm for an angle).
    gamma_s : float
        The cost bound ``dt gamma``.
    """
    import cvxpy as cp

    a_list, b_list, dt = polytope.A, polytope.B, polytope.dt
    n, m = b_list[0].shape
    d = np.asarray(direction, dtype=float).reshape(n, 1)
    vals, vecs = np.linalg.eigh(Q)
    q1h, rh = (vecs * np.sqrt(np.clip(vals, 0.0, None))).T, np.linalg.cholesky(R).T
    q = cp.Variable((n, n), symmetric=True)
    y = cp.Variable((m, n))
    w = cp.Variable((n, n), symmetric=True)
    t = cp.Variable()
    cons = [cp.bmat([[np.ones((1, 1)), t * d.T], [t * d, q]]) >> 0]
    cq, cu = q @ q1h.T, y.T @ rh.T
    cost = cp.bmat(
        [
            [w, cq, cu],
            [cq.T, gamma_s * np.eye(n), np.zeros((n, m))],
            [cu.T, np.zeros((m, n)), gamma_s * np.eye(m)],
        ]
    )
    cons.append(0.5 * (cost + cost.T) >> 0)
    for a, b in zip(a_list, b_list, strict=True):
        h = ((a - np.eye(n)) / dt) @ q + (b / dt) @ y
        blk = cp.bmat([[-(h + h.T) - w, np.sqrt(dt) * h.T], [np.sqrt(dt) * h, q]])
        cons.append(0.5 * (blk + blk.T) >> 0)
    x = cp.Variable((m, m), symmetric=True)
    cons += [cp.bmat([[x, y / u_max], [y.T / u_max, q]]) >> 0, cp.diag(x) <= 1.0]
    problem = cp.Problem(cp.Maximize(t), cons)
    try:
        problem.solve(solver="CLARABEL")
    except cp.error.SolverError as exc:
        return SlewReach(gamma_s, type(exc).__name__, None, None, None, None)
    if problem.status not in ("optimal", "optimal_inaccurate") or t.value is None:
        return SlewReach(gamma_s, str(problem.status), None, None, None, None)
    qv = 0.5 * (q.value + q.value.T)
    f = y.value @ np.linalg.inv(qv)
    low = np.linalg.cholesky(qv)
    q_inv = np.linalg.inv(qv)
    worst = 0.0
    for a, b in zip(a_list, b_list, strict=True):
        acl = low.T @ (a + b @ f).T
        mat = acl @ q_inv @ acl.T
        worst = max(worst, float(np.linalg.eigvalsh(0.5 * (mat + mat.T)).max()))
    peak = float(np.sqrt(np.diag(f @ qv @ f.T)).max() / u_max)
    tv = float(t.value)
    angle = float(np.degrees(2.0 * np.arcsin(min(tv, 1.0))))
    return SlewReach(float(gamma_s), str(problem.status), tv, angle, worst, peak)
