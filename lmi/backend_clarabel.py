"""Direct Clarabel back-end: the conic data built once, only ``b`` changes per state.

The Kothare LMIs are written as affine matrices (:mod:`lmi.affine`) in the variables
``z = [gamma_s, svec(Q), vec(Y), svec(X), svec(Z)]`` and handed to Clarabel as
``A z + s = b``, ``s`` in PSD triangle and non-negative cones, minimising ``gamma_s``. The
state enters only the constant part of the first LMI and the bounds enter only constants, so
each solve rebuilds the few entries of ``b`` and calls Clarabel; the matrix ``A`` and the cones
never change.

Formulations (see ``docs/theory.rst``):

``"delta"`` (default)
    The vertex LMI after the congruence ``[[I, -I], [0, I]]`` on its first two block rows and
    the scaling ``diag(1/sqrt(dt), I, sqrt(dt) I, sqrt(dt) I)``; with
    ``H_j = (A_j - I)/dt Q + B_j/dt Y`` and ``gamma_s = dt gamma`` it reads
    ``[[-(H_j + H_j'), sqrt(dt) H_j', Q Q1h', Y' Rh'], [sqrt(dt) H_j, Q, 0, 0],
    [Q1h Q, 0, gamma_s I, 0], [Rh Y, 0, 0, gamma_s I]] >= 0``. Same feasible set, well
    conditioned when ``A_j`` is close to ``I`` (small sample times).
``"standard"``
    Kothare's eq. (14) as printed, with ``gamma_s = gamma``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import clarabel
import numpy as np
from scipy import sparse

from lmi.affine import AffineMatrix, svec_matrix
from lmi.data import KothareData
from lmi.status import CLARABEL_STATUS_MAP, SOLVER_ERROR
from toolkit_common.errors import InvalidArgumentError

__all__ = ["ClarabelKothare", "RawResult", "clarabel_settings"]

#: Tolerances, chosen deliberately: 1e-8 gap and feasibility gave status "Solved" with recomputed
#: relative LMI margins >= -1.1e-8 on 20 random states of paper P's satellite with 2 and 8
#: vertices; 1e-9 and 1e-10 made Clarabel stop with "AlmostSolved" on up to 80 % of the 8-vertex
#: solves (the delta formulation's conditioning limit), with no gain in the certificate.
DEFAULT_CLARABEL_OPTIONS: dict[str, Any] = {
    "tol_gap_abs": 1e-8,
    "tol_gap_rel": 1e-8,
    "tol_feas": 1e-8,
    "max_iter": 200,
    "verbose": False,
}


@dataclass
class RawResult:
    """What a back-end returns for the normalised problem (before rescaling)."""

    status: str
    solver_status: str
    gamma: float
    Q: np.ndarray | None
    Y: np.ndarray | None
    iterations: int | None
    solve_time: float


def clarabel_settings(options: dict[str, Any] | None) -> Any:
    """Clarabel ``DefaultSettings`` from the defaults above and ``options``.

    Unknown keys raise :class:`InvalidArgumentError` naming them.
    """
    settings = clarabel.DefaultSettings()
    known = {name for name in dir(settings) if not name.startswith("_") and name != "default"}
    merged = {**DEFAULT_CLARABEL_OPTIONS, **(options or {})}
    unknown = sorted(set(merged) - known)
    if unknown:
        raise InvalidArgumentError(
            "solver_options", f"Clarabel settings (e.g. {', '.join(sorted(known)[:6])}, ...)",
            f"unknown setting(s) {unknown}",
        )
    for key, value in merged.items():
        try:
            setattr(settings, key, value)
        except (TypeError, ValueError) as err:
            raise InvalidArgumentError(
                f"solver_options[{key!r}]", "a valid value", f"{value!r} ({err})"
            ) from None
    return settings


class ClarabelKothare:
    """The Kothare problem as fixed conic data for Clarabel's own API."""

    name = "clarabel"

    def __init__(self, data: KothareData, options: dict[str, Any] | None = None) -> None:
        self.data = data
        self.settings = clarabel_settings(options)
        n, m = data.n, data.m
        self._n_q = n * (n + 1) // 2
        self._n_y = m * n
        self._n_x = m * (m + 1) // 2 if data.input_constraint == "peak" else 0
        p_out = 0 if data.C_out is None else data.C_out.shape[0]
        self._n_z = p_out * (p_out + 1) // 2
        nv = 1 + self._n_q + self._n_y + self._n_x + self._n_z
        self.n_vars = nv
        o_q, o_y = 1, 1 + self._n_q
        o_x, o_z = o_y + self._n_y, o_y + self._n_y + self._n_x
        self._slices = (o_q, o_y)
        q = AffineMatrix.symmetric_variable(n, o_q, nv)
        y = AffineMatrix.full_variable(m, n, o_y, nv)
        self._q_affine, self._y_affine = q, y

        blocks: list[tuple[np.ndarray, np.ndarray, Any]] = []  # (A rows, b static, cone)
        # 1. state LMI [[1, x'], [x, Q]]: constant part filled per solve
        state = AffineMatrix.bmat([[AffineMatrix.zeros(1, 1, nv), None], [None, q]], nv)
        self._state_rows = self._psd_rows(state)
        blocks.append((self._state_rows[0], None, clarabel.PSDTriangleConeT(n + 1)))
        # 2. one cost LMI per vertex
        for j in range(data.n_vertices):
            mat = self._vertex_lmi(data.A[j], data.B[j], q, y, nv)
            a_rows, b_rows = self._psd_rows(mat)
            blocks.append((a_rows, b_rows, clarabel.PSDTriangleConeT(mat.shape[0])))
        # 3. input constraint
        self._input_index = None
        if data.input_constraint == "ellipsoid":
            mat = AffineMatrix.bmat([[AffineMatrix.zeros(m, m, nv), y], [y.T, q]], nv)
            self._input_index = len(blocks)
            blocks.append((self._psd_rows(mat)[0], None, clarabel.PSDTriangleConeT(m + n)))
        elif data.input_constraint == "peak":
            xv = AffineMatrix.symmetric_variable(m, o_x, nv)
            mat = AffineMatrix.bmat([[xv, y], [y.T, q]], nv)
            a_rows, b_rows = self._psd_rows(mat)
            blocks.append((a_rows, b_rows, clarabel.PSDTriangleConeT(m + n)))
            # u_j^2 - X_jj >= 0
            diag_rows = np.zeros((m, nv))
            for i in range(m):
                diag_rows[i] = xv.coef[1:, i, i]
            self._input_index = len(blocks)
            blocks.append((diag_rows, None, clarabel.NonnegativeConeT(m)))
        # 4. output constraints [[Z, C G_j], [G_j' C', Q]] >= 0, y_r^2 - Z_rr >= 0
        self._output_index = None
        if data.C_out is not None:
            zv = AffineMatrix.symmetric_variable(p_out, o_z, nv)
            for j in range(data.n_vertices):
                g = q.lmul(data.A[j]) + y.lmul(data.B[j])
                cg = g.lmul(data.C_out)
                mat = AffineMatrix.bmat([[zv, cg], [cg.T, q]], nv)
                a_rows, b_rows = self._psd_rows(mat)
                blocks.append((a_rows, b_rows, clarabel.PSDTriangleConeT(p_out + n)))
            diag_rows = np.zeros((p_out, nv))
            for r in range(p_out):
                diag_rows[r] = zv.coef[1:, r, r]
            self._output_index = len(blocks)
            blocks.append((diag_rows, None, clarabel.NonnegativeConeT(p_out)))

        self._offsets = np.cumsum([0] + [blk[0].shape[0] for blk in blocks])
        a_full = np.vstack([blk[0] for blk in blocks])
        a_full[np.abs(a_full) < 1e-300] = 0.0
        self._A = sparse.csc_matrix(a_full)
        self._b_static = np.concatenate(
            [blk[1] if blk[1] is not None else np.zeros(blk[0].shape[0]) for blk in blocks]
        )
        self._cones = [blk[2] for blk in blocks]
        self._P = sparse.csc_matrix((nv, nv))
        self._q = np.zeros(nv)
        self._q[0] = 1.0

    # -- construction helpers ----------------------------------------------------------
    def _vertex_lmi(
        self, a: np.ndarray, b: np.ndarray, q: AffineMatrix, y: AffineMatrix, nv: int
    ) -> AffineMatrix:
        d = self.data
        n, m = d.n, d.m
        p = d.Q1h.shape[0]
        gam = AffineMatrix.scalar_variable_times(np.eye(p), 0, nv)
        gam_m = AffineMatrix.scalar_variable_times(np.eye(m), 0, nv)
        cost_q = q.rmul(d.Q1h.T)  # Q Q1h'  (n x p)
        cost_u = y.T.rmul(d.Rh.T)  # Y' Rh'  (n x m)
        if d.formulation == "standard":
            g = q.lmul(a) + y.lmul(b)
            return AffineMatrix.bmat(
                [[q, g.T, cost_q, cost_u], [g, q, None, None], [cost_q.T, None, gam, None],
                 [cost_u.T, None, None, gam_m]], nv,
            )
        dt = d.dt
        h = q.lmul((a - np.eye(n)) / dt) + y.lmul(b / dt)
        sq = np.sqrt(dt)
        return AffineMatrix.bmat(
            [[-(h + h.T), h.T * sq, cost_q, cost_u], [h * sq, q, None, None],
             [cost_q.T, None, gam, None], [cost_u.T, None, None, gam_m]], nv,
        )

    @staticmethod
    def _psd_rows(mat: AffineMatrix) -> tuple[np.ndarray, np.ndarray]:
        """``(A rows, b)`` with ``svec(M(z)) = b - A z``."""
        sv = svec_matrix(mat.coef)  # (nv + 1, L)
        return -sv[1:].T, sv[0]

    # -- solving -----------------------------------------------------------------------
    def _b_vector(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray) -> np.ndarray:
        d = self.data
        n, m = d.n, d.m
        b = self._b_static.copy()
        const = np.zeros((n + 1, n + 1))
        const[0, 0] = 1.0
        const[0, 1:] = x
        const[1:, 0] = x
        b[self._offsets[0] : self._offsets[1]] = svec_matrix(const)
        if d.input_constraint == "ellipsoid":
            i = self._input_index
            mat = np.zeros((m + n, m + n))
            mat[:m, :m] = u_max[0] ** 2 * np.eye(m)
            b[self._offsets[i] : self._offsets[i + 1]] = svec_matrix(mat)
        elif d.input_constraint == "peak":
            i = self._input_index
            b[self._offsets[i] : self._offsets[i + 1]] = u_max**2
        if self._output_index is not None:
            i = self._output_index
            b[self._offsets[i] : self._offsets[i + 1]] = y_max**2
        return b

    def solve(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray) -> RawResult:
        """Solve at the (normalised) state ``x`` with the (normalised) bounds."""
        b = self._b_vector(x, u_max, y_max)
        start = time.perf_counter()
        try:
            solver = clarabel.DefaultSolver(self._P, self._q, self._A, b, self._cones, self.settings)
            sol = solver.solve()
        except BaseException as err:
            if isinstance(err, KeyboardInterrupt):
                raise
            return RawResult(SOLVER_ERROR, repr(err), np.nan, None, None, None, time.perf_counter() - start)
        elapsed = time.perf_counter() - start
        raw = str(sol.status)
        status = CLARABEL_STATUS_MAP.get(raw, SOLVER_ERROR)
        z = np.asarray(sol.x)
        q_mat = self._q_affine.value(z)
        y_mat = self._y_affine.value(z)
        gamma = float(z[0])
        if self.data.formulation == "delta":
            gamma /= self.data.dt
        return RawResult(status, raw, gamma, q_mat, y_mat, int(sol.iterations), elapsed)


