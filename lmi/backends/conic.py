"""The Kothare LMIs as conic data ``A z + s = b``, built once and updated per state.

The LMIs are written as affine matrices (:mod:`lmi.affine`) in the variables
``z = [gamma_s, svec(Q), vec(Y), svec(X), svec(Z), svec(W)]``: ``A z + s = b``, ``s`` in PSD
triangle and non-negative cones, minimising ``gamma_s``. The state enters only the constant part
of the first LMI (``b``); the input and output bounds enter as scalings of the rows of their
off-diagonal blocks, ``[[I, Y/u], [Y'/u, Q]] >= 0`` instead of ``[[u^2 I, Y], [Y', Q]] >= 0``
(a congruence), so a large normalised bound near the origin never becomes a huge constant. Each
solve rescales those rows of ``A`` and rebuilds ``b``; the sparsity pattern and the cones never
change.

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

:class:`KothareConic` is the data shared by the Clarabel back-end
(:class:`~lmi.backends.clarabel.ClarabelKothare`, which hands it to Clarabel) and the
interior-point back-end (:class:`~lmi.backends.ipm.IPMKothare`, which keeps each cone as a
matrix and falls back to a Clarabel back-end on the same data).

The off-line nested design (:class:`lmi.offline.NestedKothareProblem`, Wan & Kothare 2003) adds
one block with ``nesting=True``: ``Q_outer - Q >= 0``, its constant ``Q_outer`` (the previous
ellipsoid's ``Q`` at the normalised state, in these data's coordinates) given per solve like
the state (:meth:`KothareConic.b_vector`). It is the last cone, so the other cones, their
offsets and rows are those of the problem without it.
"""

from __future__ import annotations

from typing import Any

import clarabel
import numpy as np
from scipy import sparse

from lmi.affine import AffineMatrix, svec_indices, svec_matrix
from lmi.data import KothareData
from toolkit_common.errors import InvalidArgumentError

__all__ = ["KothareConic"]


class KothareConic:
    """The Kothare LMIs of one :class:`~lmi.KothareData` as conic data, built once.

    ``svec(M(z)) = b - A z`` per cone, in the variables ``z = [gamma_s, svec(Q), vec(Y),
    svec(X), svec(Z), svec(W)]`` (``X`` only for the peak bound, ``Z`` only with output
    constraints, ``W`` only for ``"delta_shared"``), minimising :attr:`objective` ``' z =
    gamma_s``. The state enters :meth:`b_vector` only, the bounds :meth:`a_matrix` only.

    Attributes
    ----------
    data : KothareData
    n_vars : int
        Length of ``z``.
    n_q, n_y, n_x, n_z, n_w : int
        Sizes of the parts of ``z`` after ``gamma_s``.
    A : scipy.sparse.csc_matrix
        The stacked cone rows with unit bounds (sorted indices).
    b_static : ndarray
        The constant part, the state block's rows left zero.
    cones : list
        Clarabel cones, one per LMI or diagonal block.
    offsets : ndarray
        Row offsets of the cones in ``A`` and ``b`` (``len(cones) + 1`` entries).
    scaled_rows : list of (int, ndarray, ndarray, str)
        Row groups of the bounded blocks: ``(first row of the cone, rows within it, bound index,
        "u" or "y")``.
    objective : ndarray
        ``c`` with ``c' z = gamma_s``.
    P : scipy.sparse.csc_matrix
        The zero quadratic term (Clarabel's ``P``).
    q_affine, y_affine : AffineMatrix
        ``Q`` and ``Y`` as affine functions of ``z``.
    nesting : bool
        Whether the last cone is the nesting block ``Q_outer - Q >= 0`` (constructor argument;
        its constant is given to :meth:`b_vector`).
    """

    def __init__(self, data: KothareData, *, nesting: bool = False) -> None:
        self.data = data
        self.nesting = bool(nesting)
        n, m = data.n, data.m
        self.n_q = n * (n + 1) // 2
        self.n_y = m * n
        self.n_x = m * (m + 1) // 2 if data.input_constraint == "peak" else 0
        p_out = 0 if data.C_out is None else data.C_out.shape[0]
        self.n_z = p_out * (p_out + 1) // 2
        self.n_w = self.n_q if data.formulation == "delta_shared" else 0
        nv = 1 + self.n_q + self.n_y + self.n_x + self.n_z + self.n_w
        self.n_vars = nv
        o_q, o_y = 1, 1 + self.n_q
        o_x, o_z = o_y + self.n_y, o_y + self.n_y + self.n_x
        o_w = o_z + self.n_z
        q = AffineMatrix.symmetric_variable(n, o_q, nv)
        y = AffineMatrix.full_variable(m, n, o_y, nv)
        self.q_affine, self.y_affine = q, y
        self.w_affine = AffineMatrix.symmetric_variable(n, o_w, nv) if self.n_w else None

        blocks: list[tuple[np.ndarray, np.ndarray, Any]] = []  # (A rows, b static, cone)
        # 1. state LMI [[1, x'], [x, Q]]: constant part filled per solve
        state = AffineMatrix.bmat([[AffineMatrix.zeros(1, 1, nv), None], [None, q]], nv)
        self._state_rows = self._psd_rows(state)
        blocks.append((self._state_rows[0], None, clarabel.PSDTriangleConeT(n + 1)))
        # 2. one cost LMI per vertex (plus the shared cost block of "delta_shared")
        if self.w_affine is not None:
            mat = self._shared_cost_lmi(q, y, self.w_affine, nv)
            a_rows, b_rows = self._psd_rows(mat)
            blocks.append((a_rows, b_rows, clarabel.PSDTriangleConeT(mat.shape[0])))
        for j in range(data.n_vertices):
            mat = self._vertex_lmi(data.A[j], data.B[j], q, y, nv)
            a_rows, b_rows = self._psd_rows(mat)
            blocks.append((a_rows, b_rows, clarabel.PSDTriangleConeT(mat.shape[0])))
        # Bounds enter as row scalings of the off-diagonal blocks (see add_bounded), never
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
        self.scaled_rows = scaled_rows
        # 5. the nesting Q_outer - Q >= 0 (off-line design): constant filled per solve, last cone
        if self.nesting:
            blocks.append((self._psd_rows(-q)[0], None, clarabel.PSDTriangleConeT(n)))

        self.offsets = np.cumsum([0] + [blk[0].shape[0] for blk in blocks])
        a_full = np.vstack([blk[0] for blk in blocks])
        a_full[np.abs(a_full) < 1e-300] = 0.0
        self.A = sparse.csc_matrix(a_full)
        self.A.sort_indices()
        self._a_data = self.A.data.copy()
        self.b_static = np.concatenate(
            [blk[1] if blk[1] is not None else np.zeros(blk[0].shape[0]) for blk in blocks]
        )
        self.cones = [blk[2] for blk in blocks]
        self.P = sparse.csc_matrix((nv, nv))
        self.objective = np.zeros(nv)
        self.objective[0] = 1.0

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles hold the cones as ``(kind, dimension)`` (Clarabel's cone objects do
        not pickle); :meth:`__setstate__` builds them again."""
        state = dict(self.__dict__)
        state["cones"] = [
            ("psd" if isinstance(cone, clarabel.PSDTriangleConeT) else "nonneg", int(stop - start))
            for cone, start, stop in zip(self.cones, self.offsets[:-1], self.offsets[1:], strict=True)
        ]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        specs = state["cones"]
        self.__dict__.update(state)
        # a PSD triangle cone of order k has k (k + 1) / 2 rows
        self.cones = [
            clarabel.PSDTriangleConeT(round((np.sqrt(8 * dim + 1) - 1) / 2)) if kind == "psd"
            else clarabel.NonnegativeConeT(dim)
            for kind, dim in specs
        ]

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
        if self.w_affine is not None:
            return AffineMatrix.bmat([[-(h + h.T) - self.w_affine, h.T * sq], [h * sq, q]], nv)
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

    # -- per solve ----------------------------------------------------------------------
    def b_vector(self, x: np.ndarray, outer: np.ndarray | None = None) -> np.ndarray:
        """``b`` at the (normalised) state ``x``: the state block ``[[1, x'], [x, 0]]``; with the
        nesting block, its constant ``outer`` (``Q_outer`` in these data's coordinates, at the
        normalised state), required then and refused otherwise."""
        n = self.data.n
        b = self.b_static.copy()
        const = np.zeros((n + 1, n + 1))
        const[0, 0] = 1.0
        const[0, 1:] = x
        const[1:, 0] = x
        b[self.offsets[0] : self.offsets[1]] = svec_matrix(const)
        if (outer is None) == self.nesting:
            raise InvalidArgumentError(
                "outer", "Q_outer with the nesting block, None without it",
                "None" if outer is None else "a matrix for data without the nesting block",
            )
        if outer is not None:
            b[self.offsets[-2] : self.offsets[-1]] = svec_matrix(0.5 * (outer + outer.T))
        return b

    def a_matrix(self, u_max: np.ndarray, y_max: np.ndarray) -> sparse.csc_matrix:
        """``A`` with the rows of the bounded off-diagonal blocks divided by their bound."""
        row_scale = np.ones(self.A.shape[0])
        for start, sel, bound_index, kind in self.scaled_rows:
            bounds = u_max if kind == "u" else y_max
            if bounds.size == 1:
                row_scale[start + sel] = 1.0 / bounds[0]
            else:
                row_scale[start + sel] = 1.0 / bounds[bound_index]
        a_mat = self.A.copy()
        a_mat.data = self._a_data * row_scale[self.A.indices]
        return a_mat

    def variables(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(Q, Y)`` at a solver's ``z``."""
        return self.q_affine.value(z), self.y_affine.value(z)
