"""Direct Clarabel back-end: the conic data built once, a few entries updated per state.

The Kothare LMIs are written as affine matrices (:mod:`lmi.affine`) in the variables
``z = [gamma_s, svec(Q), vec(Y), svec(X), svec(Z)]`` and handed to Clarabel as
``A z + s = b``, ``s`` in PSD triangle and non-negative cones, minimising ``gamma_s``. The
state enters only the constant part of the first LMI (``b``); the input and output bounds enter
as scalings of the rows of their off-diagonal blocks, ``[[I, Y/u], [Y'/u, Q]] >= 0`` instead of
``[[u^2 I, Y], [Y', Q]] >= 0`` (a congruence), so a large normalised bound near the origin never
becomes a huge constant. Each solve rescales those rows of ``A`` and rebuilds ``b``; the
sparsity pattern and the cones never change.

Formulations (see ``docs/theory.rst``):

``"delta"``
    The vertex LMI after the congruence ``[[I, -I], [0, I]]`` on its first two block rows and
    the scaling ``diag(1/sqrt(dt), I, sqrt(dt) I, sqrt(dt) I)``; with
    ``H_j = (A_j - I)/dt Q + B_j/dt Y`` and ``gamma_s = dt gamma`` it reads
    ``[[-(H_j + H_j'), sqrt(dt) H_j', Q Q1h', Y' Rh'], [sqrt(dt) H_j, Q, 0, 0],
    [Q1h Q, 0, gamma_s I, 0], [Rh Y, 0, 0, gamma_s I]] >= 0``. Same feasible set, well
    conditioned when ``A_j`` is close to ``I`` (small sample times).
``"delta_shared"`` (default)
    The delta form with the common ``Q1``/``R`` part lifted into one shared block: a variable
    ``W`` with ``[[W, Q Q1h', Y' Rh'], [Q1h Q, gamma_s I, 0], [Rh Y, 0, gamma_s I]] >= 0`` and,
    per vertex, ``[[-(H_j + H_j') - W, sqrt(dt) H_j'], [sqrt(dt) H_j, Q]] >= 0``. By a Schur
    complement this is the same feasible set in ``(Q, Y, gamma)`` (the best ``W`` is
    ``(Q Q1 Q + Y' R Y)/(dt gamma)``), and each vertex cone shrinks from ``2n + p + m`` to ``2n``.
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

from lmi.affine import AffineMatrix, svec_indices, svec_matrix
from lmi.data import KothareData
from lmi.infeasibility import InfeasibilityCertificate
from lmi.status import CLARABEL_STATUS_MAP, INFEASIBLE, SOLVER_ERROR, UNBOUNDED
from lmi.threads import SingleThreadBlas
from toolkit_common.errors import InvalidArgumentError

__all__ = ["ClarabelKothare", "RawResult", "clarabel_settings"]

#: Tolerances, chosen deliberately: 1e-8 gap and feasibility gave status "Solved" with recomputed
#: relative LMI margins >= -1.1e-8 on 20 random states of paper P's satellite with 2 and 8
#: vertices; 1e-9 and 1e-10 made Clarabel stop with "AlmostSolved" on up to 80 % of the 8-vertex
#: solves (the delta formulation's conditioning limit), with no gain in the certificate.
#: Chordal decomposition is off: the LMI cones are dense, and with it on, Clarabel took 51 ms
#: instead of 30 ms per solve of paper P's 2-vertex problem (and refuses data updates).
DEFAULT_CLARABEL_OPTIONS: dict[str, Any] = {
    "chordal_decomposition_enable": False,
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
    #: A checked proof of infeasibility (the IPM's phase one), when the status is "infeasible".
    infeasibility: InfeasibilityCertificate | None = None


def clarabel_settings(options: dict[str, Any] | None) -> Any:
    """Clarabel ``DefaultSettings`` from the defaults above and ``options``.

    Unknown keys raise :class:`~toolkit_common.errors.InvalidArgumentError` naming them.
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
        self._blas = SingleThreadBlas()
        n, m = data.n, data.m
        self._n_q = n * (n + 1) // 2
        self._n_y = m * n
        self._n_x = m * (m + 1) // 2 if data.input_constraint == "peak" else 0
        p_out = 0 if data.C_out is None else data.C_out.shape[0]
        self._n_z = p_out * (p_out + 1) // 2
        self._n_w = self._n_q if data.formulation == "delta_shared" else 0
        nv = 1 + self._n_q + self._n_y + self._n_x + self._n_z + self._n_w
        self.n_vars = nv
        o_q, o_y = 1, 1 + self._n_q
        o_x, o_z = o_y + self._n_y, o_y + self._n_y + self._n_x
        o_w = o_z + self._n_z
        q = AffineMatrix.symmetric_variable(n, o_q, nv)
        y = AffineMatrix.full_variable(m, n, o_y, nv)
        self._q_affine, self._y_affine = q, y
        self._w = AffineMatrix.symmetric_variable(n, o_w, nv) if self._n_w else None

        blocks: list[tuple[np.ndarray, np.ndarray, Any]] = []  # (A rows, b static, cone)
        # 1. state LMI [[1, x'], [x, Q]]: constant part filled per solve
        state = AffineMatrix.bmat([[AffineMatrix.zeros(1, 1, nv), None], [None, q]], nv)
        self._state_rows = self._psd_rows(state)
        blocks.append((self._state_rows[0], None, clarabel.PSDTriangleConeT(n + 1)))
        # 2. one cost LMI per vertex (plus the shared cost block of "delta_shared")
        if self._w is not None:
            mat = self._shared_cost_lmi(q, y, self._w, nv)
            a_rows, b_rows = self._psd_rows(mat)
            blocks.append((a_rows, b_rows, clarabel.PSDTriangleConeT(mat.shape[0])))
        for j in range(data.n_vertices):
            mat = self._vertex_lmi(data.A[j], data.B[j], q, y, nv)
            a_rows, b_rows = self._psd_rows(mat)
            blocks.append((a_rows, b_rows, clarabel.PSDTriangleConeT(mat.shape[0])))
        # Bounds enter as row scalings of the off-diagonal blocks (see _bounded_block), never
        # as large constants: [[u^2 I, Y], [Y', Q]] >= 0 is solved as [[I, Y/u], [Y'/u, Q]] >= 0.
        # Row groups scaled per solve: (first row in the stacked A, rows, bound index, kind).
        scaled_rows: list[tuple[int, np.ndarray, np.ndarray, str]] = []

        def add_bounded(top: AffineMatrix, off: AffineMatrix, kind: str) -> None:
            size = top.shape[0]
            mat = AffineMatrix.bmat([[top, off], [off.T, q]], nv)
            a_rows, b_rows = self._psd_rows(mat)
            rows_i, cols_j = svec_indices(size + n)
            sel = np.flatnonzero((rows_i < size) & (cols_j >= size))
            start = sum(blk[0].shape[0] for blk in blocks)
            scaled_rows.append((start, sel, rows_i[sel], kind))
            blocks.append((a_rows, b_rows, clarabel.PSDTriangleConeT(size + n)))

        def add_unit_diagonal(var: AffineMatrix) -> None:
            size = var.shape[0]
            diag_rows = np.array([var.coef[1:, i, i] for i in range(size)])
            blocks.append((diag_rows, np.ones(size), clarabel.NonnegativeConeT(size)))

        # 3. input constraint
        if data.input_constraint == "ellipsoid":
            add_bounded(AffineMatrix.constant(np.eye(m), nv), y, "u")
        elif data.input_constraint == "peak":
            xv = AffineMatrix.symmetric_variable(m, o_x, nv)
            add_bounded(xv, y, "u")
            add_unit_diagonal(xv)  # 1 - X_jj >= 0
        # 4. output constraints [[Z, D C G_j], [G_j' C' D, Q]] >= 0, 1 - Z_rr >= 0, D = 1/y_max
        if data.C_out is not None:
            zv = AffineMatrix.symmetric_variable(p_out, o_z, nv)
            for j in range(data.n_vertices):
                g = q.lmul(data.A[j]) + y.lmul(data.B[j])
                add_bounded(zv, g.lmul(data.C_out), "y")
            add_unit_diagonal(zv)
        self._scaled_rows = scaled_rows

        self._offsets = np.cumsum([0] + [blk[0].shape[0] for blk in blocks])
        a_full = np.vstack([blk[0] for blk in blocks])
        a_full[np.abs(a_full) < 1e-300] = 0.0
        self._A = sparse.csc_matrix(a_full)
        self._A.sort_indices()
        self._A_data = self._A.data.copy()
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
        if self._w is not None:
            return AffineMatrix.bmat([[-(h + h.T) - self._w, h.T * sq], [h * sq, q]], nv)
        return AffineMatrix.bmat(
            [[-(h + h.T), h.T * sq, cost_q, cost_u], [h * sq, q, None, None],
             [cost_q.T, None, gam, None], [cost_u.T, None, None, gam_m]], nv,
        )

    def _shared_cost_lmi(
        self, q: AffineMatrix, y: AffineMatrix, w: AffineMatrix, nv: int
    ) -> AffineMatrix:
        """``[[W, Q Q1h', Y' Rh'], [Q1h Q, gamma_s I, 0], [Rh Y, 0, gamma_s I]] >= 0``."""
        d = self.data
        p, m = d.Q1h.shape[0], d.m
        gam = AffineMatrix.scalar_variable_times(np.eye(p), 0, nv)
        gam_m = AffineMatrix.scalar_variable_times(np.eye(m), 0, nv)
        cost_q = q.rmul(d.Q1h.T)
        cost_u = y.T.rmul(d.Rh.T)
        return AffineMatrix.bmat(
            [[w, cost_q, cost_u], [cost_q.T, gam, None], [cost_u.T, None, gam_m]], nv
        )

    @staticmethod
    def _psd_rows(mat: AffineMatrix) -> tuple[np.ndarray, np.ndarray]:
        """``(A rows, b)`` with ``svec(M(z)) = b - A z``."""
        sv = svec_matrix(mat.coef)  # (nv + 1, L)
        return -sv[1:].T, sv[0]

    # -- solving -----------------------------------------------------------------------
    def _b_vector(self, x: np.ndarray) -> np.ndarray:
        n = self.data.n
        b = self._b_static.copy()
        const = np.zeros((n + 1, n + 1))
        const[0, 0] = 1.0
        const[0, 1:] = x
        const[1:, 0] = x
        b[self._offsets[0] : self._offsets[1]] = svec_matrix(const)
        return b

    def _a_matrix(self, u_max: np.ndarray, y_max: np.ndarray) -> sparse.csc_matrix:
        """``A`` with the rows of the bounded off-diagonal blocks divided by their bound."""
        row_scale = np.ones(self._A.shape[0])
        for start, sel, bound_index, kind in self._scaled_rows:
            bounds = u_max if kind == "u" else y_max
            if bounds.size == 1:
                row_scale[start + sel] = 1.0 / bounds[0]
            else:
                row_scale[start + sel] = 1.0 / bounds[bound_index]
        a_mat = self._A.copy()
        a_mat.data = self._A_data * row_scale[self._A.indices]
        return a_mat

    def solve(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray) -> RawResult:
        """Solve at the (normalised) state ``x`` with the (normalised) bounds."""
        b = self._b_vector(x)
        a_mat = self._a_matrix(u_max, y_max)
        start = time.perf_counter()
        try:
            with self._blas.limit():
                solver = clarabel.DefaultSolver(self._P, self._q, a_mat, b, self._cones, self.settings)
                sol = solver.solve()
        except BaseException as err:
            if isinstance(err, KeyboardInterrupt):
                raise
            return RawResult(SOLVER_ERROR, repr(err), np.nan, None, None, None, time.perf_counter() - start)
        elapsed = time.perf_counter() - start
        raw = str(sol.status)
        status = CLARABEL_STATUS_MAP.get(raw, SOLVER_ERROR)
        if status in (INFEASIBLE, UNBOUNDED):  # the last iterate is no answer: return none
            return RawResult(status, raw, np.nan, None, None, int(sol.iterations), elapsed)
        z = np.asarray(sol.x)
        q_mat = self._q_affine.value(z)
        y_mat = self._y_affine.value(z)
        gamma = float(z[0])
        if self.data.formulation != "standard":
            gamma /= self.data.dt
        return RawResult(status, raw, gamma, q_mat, y_mat, int(sol.iterations), elapsed)


