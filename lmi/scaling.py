"""A diagonal change of state coordinates that balances the Kothare problem for the IPM.

The Kothare LMIs are invariant under a change of state coordinates ``x = T x~``: with
``A~ = T^-1 A T``, ``B~ = T^-1 B``, ``Q1~ = T' Q1 T`` (and ``C~ = C T`` for output bounds) the
problem at ``x~ = T^-1 x`` has the solution ``Q~ = T^-1 Q T^-T``, ``Y~ = Y T^-T`` and the same
``gamma``. A primal-dual interior-point method with Nesterov-Todd scaling is invariant to
such congruences of its blocks too, except for its starting point: the default start (slacks
and duals near multiples of the identity) is centred only if the solution is not too
unbalanced between the coordinates.

On the 14-state flexible satellite it is: the optimal ``Q`` (the invariant ellipsoid) has
diagonal entries from 2e-3 (body rates) to 18 (modal velocities), and the IPM started at the
identity crawled (step lengths 0.01-0.3, centrality ``lambda^2/mu`` spread over 1e-2..50 in
the first iterations) until its stall test stopped it. :func:`state_scaling` picks
``T = diag(t)`` from the nominal LQR problem, whose cost matrix ``P`` (Riccati, vertex-mean
model) predicts that imbalance: ``t_i = sqrt(min_k P_kk / P_ii)``, so that ``T' P T`` has a
constant diagonal; no coordinate is enlarged (``t_i <= 1``). It is applied only when the
diagonal of ``P`` spans more than :data:`MIN_SPREAD`: on paper P's satellite it spans a factor
7.6, and scaling anyway cost one more iteration per warm solve at 2 vertices (measured: 9
instead of 8, median of 30 states) and two more cold at 8; on the flexible satellite it spans
4200. The rigid hub of the flexible model (its hub inertia,
``Ts = 0.05`` s, ``Q1 = 100 I``, ``R = I``, peak bound 2 N m, 10 deg off) spans 47 and needs it
too: without it the cold solve ended ``"inaccurate"`` after 41 (2 vertices) and 50 (8)
iterations, the dual residual growing from 5e-9 to 3e-5 as the gap closed; with it, optimal
in 29 and 31. Hence a threshold of 20, between the two.

The Riccati diagonal knows the weights, not the constraints. When an input (or output) bound
is active the optimal ellipsoid is squeezed along directions the state does not occupy: on the
flexible satellite's 8-vertex polytope at 0.5 s with a 2 N m peak bound, 14 deg off, the
optimal ``Q~`` in these coordinates still spans 1e-4 (modal coordinates) to 20 (attitude). The
IPM back-end then retries a failed solve in coordinates balanced on its own last iterate
(``rebalance`` in :data:`lmi.backends.ipm.DEFAULT_IPM_OPTIONS`).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_discrete_are

from lmi.data import KothareData, build_kothare_data

__all__ = ["MIN_SPREAD", "scale_data", "state_scaling"]

#: The scaling is used only if ``max P_ii / min P_ii`` exceeds this (see the module docstring).
MIN_SPREAD = 20.0

#: Relative regularisation of ``Q1`` in the Riccati equation (``Q1`` may be singular).
_REGULARISATION = 1e-9


def state_scaling(data: KothareData) -> np.ndarray:
    """The diagonal ``t`` of ``T`` (all ones if the nominal Riccati equation has no solution).

    Parameters
    ----------
    data : KothareData
        The problem; its vertex-mean model ``(mean A_j, mean B_j)`` and weights are used.

    Returns
    -------
    (n,) ndarray
        ``t_i = sqrt(min_k P_kk / P_ii)`` in ``(0, 1]``; all ones if the diagonal of ``P`` spans
        at most :data:`MIN_SPREAD`.
    """
    a, b = data.A.mean(axis=0), data.B.mean(axis=0)
    n = data.n
    q1 = data.Q1 + _REGULARISATION * max(float(np.trace(data.Q1)) / n, 1.0) * np.eye(n)
    try:
        p = solve_discrete_are(a, b, q1, data.R)
    except (np.linalg.LinAlgError, ValueError):
        return np.ones(n)
    diag = np.diag(p)
    if not (np.all(np.isfinite(p)) and np.all(diag > 0.0)):
        return np.ones(n)
    if float(np.max(diag)) <= MIN_SPREAD * float(np.min(diag)):
        return np.ones(n)
    return np.sqrt(float(np.min(diag)) / diag)


def scale_data(data: KothareData, t: np.ndarray) -> KothareData:
    """The problem in the coordinates ``x~ = T^-1 x``, ``T = diag(t)`` for ``t`` of shape ``(n,)``
    or ``T = t`` of shape ``(n, n)`` (invertible; see the module docstring)."""
    if t.ndim == 2:
        t_inv = np.linalg.inv(t)
        a = t_inv[None] @ data.A @ t[None]
        b = t_inv[None] @ data.B
        q1 = t.T @ data.Q1 @ t
        c_out = None if data.C_out is None else data.C_out @ t
    else:
        a = data.A * (1.0 / t)[None, :, None] * t[None, None, :]
        b = data.B * (1.0 / t)[None, :, None]
        q1 = data.Q1 * np.outer(t, t)
        c_out = None if data.C_out is None else data.C_out * t[None, :]
    u_max = None if data.input_constraint is None else (
        float(data.u_max[0]) if data.input_constraint == "ellipsoid" else data.u_max)
    return build_kothare_data(
        a, b, 0.5 * (q1 + q1.T), data.R, dt=data.dt, input_constraint=data.input_constraint,
        u_max=u_max, output_matrix=c_out, y_max=None if c_out is None else data.y_max,
        formulation=data.formulation,
    )
