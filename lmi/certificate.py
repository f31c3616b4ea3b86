"""Certificates: every LMI of the Kothare problem recomputed in numpy from ``Q``, ``Y``, ``gamma``.

The certificate does not trust the solver: it forms each LMI in its original form (Kothare,
Balakrishnan & Morari 1996, eqs. (13), (14), (28)/(29), (34)) from the returned matrices and
reports the smallest eigenvalue of each, divided by the matrix's spectral norm (a relative
margin, invariant to the scaling of the state). The input-peak and output bounds are checked in
their exact per-axis form ``(Y Q^-1 Y')_jj <= u_j^2``, which is what the LMIs with ``X``/``Z``
guarantee.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lmi.data import KothareData

__all__ = ["Certificate", "certify"]


@dataclass(frozen=True)
class Certificate:
    """Relative margins of each recomputed LMI; ``ok`` when all are ``>= -tol``."""

    margins: dict[str, float]
    tol: float

    @property
    def worst(self) -> float:
        """The smallest margin."""
        return min(self.margins.values())

    @property
    def ok(self) -> bool:
        return bool(np.isfinite(self.worst) and self.worst >= -self.tol)


def _rel_min_eig(mat: np.ndarray) -> float:
    sym = 0.5 * (mat + mat.T)
    lam = np.linalg.eigvalsh(sym)
    scale = max(float(np.max(np.abs(lam))), np.finfo(float).tiny)
    return float(lam[0] / scale)


def certify(
    data: KothareData, x: np.ndarray, gamma: float, Q: np.ndarray, Y: np.ndarray, tol: float = 1e-7
) -> Certificate:
    """Recompute the LMIs at the state ``x`` and return their relative margins.

    Margins: ``"state"`` for ``[[1, x'], [x, Q]]``; ``"vertex_j"`` for the cost LMI of vertex
    ``j`` as printed and ``"vertex_j_delta"`` for the same LMI after the delta congruence with
    the problem's ``dt`` (better conditioned at small ``dt``; both must hold);
    ``"input"`` (ellipsoid: ``[[u^2 I, Y], [Y', Q]]``) or ``"input_j"`` (peak: relative
    slack ``1 - (Y Q^-1 Y')_jj / u_j^2``); ``"output_r"`` for output bounds over every vertex.
    """
    n, m = data.n, data.m
    margins: dict[str, float] = {}
    if not (np.all(np.isfinite(Q)) and np.all(np.isfinite(Y)) and np.isfinite(gamma)):
        return Certificate({"finite": -np.inf}, tol)
    margins["state"] = _rel_min_eig(np.block([[np.ones((1, 1)), x[None, :]], [x[:, None], Q]]))
    q1h, rh = data.Q1h, data.Rh
    p = q1h.shape[0]
    for j in range(data.n_vertices):
        g = data.A[j] @ Q + data.B[j] @ Y
        mat = np.block(
            [
                [Q, g.T, Q @ q1h.T, Y.T @ rh.T],
                [g, Q, np.zeros((n, p)), np.zeros((n, m))],
                [q1h @ Q, np.zeros((p, n)), gamma * np.eye(p), np.zeros((p, m))],
                [rh @ Y, np.zeros((m, n)), np.zeros((m, p)), gamma * np.eye(m)],
            ]
        )
        margins[f"vertex_{j}"] = _rel_min_eig(mat)
        # The same LMI after the exact congruence of the delta form (see lmi.backend_clarabel):
        # at small dt the printed form's relative margin hides violations of order dt (a
        # "standard" 8-vertex solve 4e-5 below the optimum had margin -2.4e-9 here but -1.2e-5
        # in this form), so both must hold.
        dt = data.dt
        h = ((data.A[j] - np.eye(n)) @ Q + data.B[j] @ Y) / dt
        sq = np.sqrt(dt)
        mat_delta = np.block(
            [
                [-(h + h.T), sq * h.T, Q @ q1h.T, Y.T @ rh.T],
                [sq * h, Q, np.zeros((n, p)), np.zeros((n, m))],
                [q1h @ Q, np.zeros((p, n)), dt * gamma * np.eye(p), np.zeros((p, m))],
                [rh @ Y, np.zeros((m, n)), np.zeros((m, p)), dt * gamma * np.eye(m)],
            ]
        )
        margins[f"vertex_{j}_delta"] = _rel_min_eig(mat_delta)
    try:
        q_inv = np.linalg.inv(Q)
    except np.linalg.LinAlgError:
        return Certificate({**margins, "Q_invertible": -np.inf}, tol)
    if data.input_constraint == "ellipsoid":
        u2 = float(data.u_max[0]) ** 2
        margins["input"] = _rel_min_eig(np.block([[u2 * np.eye(m), Y], [Y.T, Q]]))
    elif data.input_constraint == "peak":
        peak = np.einsum("ij,jk,ik->i", Y, q_inv, Y)
        for i in range(m):
            margins[f"input_{i}"] = float(1.0 - peak[i] / data.u_max[i] ** 2)
    if data.C_out is not None:
        for r in range(data.C_out.shape[0]):
            worst = 0.0
            for j in range(data.n_vertices):
                row = data.C_out[r] @ (data.A[j] @ Q + data.B[j] @ Y)
                worst = max(worst, float(row @ q_inv @ row))
            margins[f"output_{r}"] = float(1.0 - worst / data.y_max[r] ** 2)
    return Certificate(margins, tol)
