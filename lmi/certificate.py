"""Certificates: every LMI of the Kothare problem recomputed in numpy from ``Q``, ``Y``, ``gamma``.

The certificate does not trust the solver: it forms each LMI in its original form (Kothare,
Balakrishnan & Morari 1996, eqs. (13), (14), (28)/(29), (34)) from the returned matrices and
reports the smallest eigenvalue of each, divided by the matrix's spectral norm (a relative
margin). Every margin is invariant to the scaling of the state (``Q``, ``Y`` and ``gamma`` scale
with ``|x|^2``): the vertex and input LMIs are then multiplied by a scalar, and the state LMI is
checked at the normalised state, ``[[1, x'/|x|], [x/|x|, Q/|x|^2]]`` (a congruence of
``[[1, x'], [x, Q]]``, so the same matrices pass; formed from the raw matrix, its relative
margin shrank like ``|x|^2`` and could not show a violation at small states). The input-peak and
output bounds are checked in their exact per-axis form ``(Y Q^-1 Y')_jj <= u_j^2``, which is
what the LMIs with ``X``/``Z`` guarantee.
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


def _rel_min_eigs(mats: np.ndarray) -> list[float]:
    lam = np.linalg.eigvalsh(0.5 * (mats + np.swapaxes(mats, -1, -2)))
    scale = np.maximum(np.max(np.abs(lam), axis=-1), np.finfo(float).tiny)
    return [float(v) for v in lam[..., 0] / scale]


def _vertex_stack(
    top: np.ndarray, g: np.ndarray, Q: np.ndarray, Y: np.ndarray, q1h: np.ndarray,
    rh: np.ndarray, gam: float,
) -> np.ndarray:
    """``[[top, G', Q Q1h', Y' Rh'], [G, Q, 0, 0], [Q1h Q, 0, gam I, 0], [Rh Y, 0, 0, gam I]]``."""
    count, n = g.shape[0], Q.shape[0]
    p, m = q1h.shape[0], rh.shape[0]
    size = 2 * n + p + m
    out = np.zeros((count, size, size))
    out[:, :n, :n] = top
    out[:, n : 2 * n, :n] = g
    out[:, :n, n : 2 * n] = np.swapaxes(g, 1, 2)
    out[:, n : 2 * n, n : 2 * n] = Q
    cq, cu = q1h @ Q, rh @ Y
    out[:, 2 * n : 2 * n + p, :n] = cq
    out[:, :n, 2 * n : 2 * n + p] = cq.T
    out[:, 2 * n + p :, :n] = cu
    out[:, :n, 2 * n + p :] = cu.T
    diag = np.arange(2 * n, size)
    out[:, diag, diag] = gam
    return out


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
    m = data.m
    margins: dict[str, float] = {}
    if not (np.all(np.isfinite(Q)) and np.all(np.isfinite(Y)) and np.isfinite(gamma)):
        return Certificate({"finite": -np.inf}, tol)
    norm = float(np.linalg.norm(x))
    scale = 1.0 / norm if norm > 0.0 else 1.0
    margins["state"] = _rel_min_eig(
        np.block([[np.ones((1, 1)), scale * x[None, :]], [scale * x[:, None], scale**2 * Q]])
    )
    q1h, rh = data.Q1h, data.Rh
    # The vertex LMIs, all vertices stacked (one batched eigenvalue call per form), as printed
    # and after the exact congruence of the delta form (see lmi.backends.conic): at small dt
    # the printed form's relative margin hides violations of order dt (a "standard" 8-vertex
    # solve 4e-5 below the optimum had margin -2.4e-9 there but -1.2e-5 in the delta form), so
    # both must hold.
    dt = data.dt
    g = data.A @ Q + data.B @ Y  # (N, n, n)
    h = (g - Q) / dt
    printed = _vertex_stack(Q, g, Q, Y, q1h, rh, gamma)
    delta = _vertex_stack(-(h + np.swapaxes(h, 1, 2)), np.sqrt(dt) * h, Q, Y, q1h, rh, dt * gamma)
    for j, (m_p, m_d) in enumerate(zip(_rel_min_eigs(printed), _rel_min_eigs(delta), strict=True)):
        margins[f"vertex_{j}"] = m_p
        margins[f"vertex_{j}_delta"] = m_d
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
