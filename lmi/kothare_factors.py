"""The Kothare LMIs' coefficients in factored form ``A_i = D N_i D'`` (for :mod:`lmi.ipm`).

Each cost LMI of :class:`lmi.backends.conic.KothareConic` is a sum of terms
``E X F' + F X' E'`` (or ``E X E'`` for a symmetric ``X``) with constant ``E``, ``F`` and a
matrix variable ``X`` (``Q``, ``Y``, ``W`` or ``gamma I``). The columns of all the ``E`` and
``F`` of a block form its dictionary ``D``; in those coordinates every variable's coefficient
``N_i`` has one to three non-zero entries. For the ``"delta_shared"`` vertex block of order
``2n``, ``[[-(H + H') - W, s H'], [s H, Q]]`` with ``H = A~ Q + B~ Y`` (``A~ = (A - I)/dt``,
``B~ = B/dt``, ``s = sqrt(dt)``), the dictionary is ``[[-A~, -B~, I, 0], [s A~, s B~, 0, I]]``
(``3n + m`` columns) and the block has about ``5 n^2 / 2 + m n`` entries, against ``n^3`` non-zero
coefficient entries in the block's own coordinates; the Schur complement's share of the block
then costs the square of the first number (:func:`lmi.ipm.kernels.scaling_and_schur_direct`).

The solver checks that each factored form reproduces the block's coefficients (to 1e-9
relative) when it is given, so a factor that does not match is an error, not a wrong answer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lmi.affine import svec_index_map
from lmi.data import KothareData

__all__ = ["VariableLayout", "cost_block_factors"]


@dataclass(frozen=True)
class VariableLayout:
    """Index maps of the matrix variables into the solver's variable vector (``-1``: none)."""

    gamma: int
    q: np.ndarray  # (n, n), symmetric
    y: np.ndarray  # (m, n)
    w: np.ndarray | None  # (n, n), symmetric ("delta_shared")

    @classmethod
    def of(cls, n: int, m: int, o_q: int, o_y: int, o_w: int | None) -> VariableLayout:
        """The layout of :class:`~lmi.backends.conic.KothareConic` (``gamma`` first, then
        ``svec(Q)`` upper triangle column by column, ``vec(Y)`` row-major, ..., ``svec(W)``)."""
        return cls(0, svec_index_map(n, o_q), o_y + np.arange(m * n).reshape(m, n),
                   None if o_w is None else svec_index_map(n, o_w))


class _Builder:
    """Collects a block's dictionary columns and entries (``N`` positions and values)."""

    def __init__(self, order: int) -> None:
        self.order = order
        self.columns: list[np.ndarray] = []
        self.width = 0
        self.var: list[np.ndarray] = []
        self.p: list[np.ndarray] = []
        self.q: list[np.ndarray] = []
        self.val: list[np.ndarray] = []

    def dictionary(self, mat: np.ndarray) -> np.ndarray:
        """Append columns; return their indices."""
        self.columns.append(mat)
        idx = self.width + np.arange(mat.shape[1])
        self.width += mat.shape[1]
        return idx

    def term(self, ce: np.ndarray, cf: np.ndarray, xmap: np.ndarray, scale: float,
             symmetric: bool) -> None:
        """``scale (E X F' + F X' E')`` (or ``scale E X E'`` when ``symmetric``, ``ce is cf``) with
        ``X[r, c]`` the variable ``xmap[r, c]``; ``ce``/``cf`` index ``E``'s/``F``'s columns."""
        rows, cols = np.nonzero(xmap >= 0)
        if symmetric:  # E X E' with X symmetric: each (r, c), r <= c, once
            keep = rows <= cols
            rows, cols = rows[keep], cols[keep]
        p, q = ce[rows], cf[cols]
        lo, hi = np.minimum(p, q), np.maximum(p, q)
        self.var.append(xmap[rows, cols])
        self.p.append(lo)
        self.q.append(hi)
        self.val.append(np.full(rows.size, float(scale)))

    def factor(self) -> tuple[np.ndarray, ...]:
        return (np.hstack(self.columns), np.concatenate(self.var), np.concatenate(self.p),
                np.concatenate(self.q), np.concatenate(self.val))


def cost_block_factors(data: KothareData, lay: VariableLayout) -> list[tuple[np.ndarray, ...]]:
    """Factored coefficients of the cost blocks, in the back-end's block order.

    ``"delta_shared"``: the shared block, then one block per vertex; ``"delta"`` and
    ``"standard"``: one block per vertex. The values are those of the solver's coefficients
    ``A_ij`` (``S_j = C_j - sum_i z_i A_ij``), i.e. minus the LMI's own.
    """
    out = []
    if data.formulation == "delta_shared":
        out.append(_shared(data, lay))
    for j in range(data.n_vertices):
        out.append(_vertex(data, lay, data.A[j], data.B[j]))
    return out


def _cost_part(data: KothareData, bld: _Builder, lay: VariableLayout, top: np.ndarray,
               first: int) -> None:
    """The rows ``[Q1h Q, gamma I, 0; Rh Y, 0, gamma I]`` below (and right of) the rows ``top``,
    starting at row ``first`` of the block."""
    n, m = data.n, data.m
    p = data.Q1h.shape[0]
    k = bld.order
    rows_q = np.zeros((k, p))
    rows_q[first:first + p] = np.eye(p)
    rows_u = np.zeros((k, m))
    rows_u[first + p:first + p + m] = np.eye(m)
    # Q Q1h' in (top, q-rows): E = top, F = rows_q Q1h  ->  top Q (rows_q Q1h)'
    ce = bld.dictionary(top)
    cq = bld.dictionary(rows_q @ data.Q1h)
    cu = bld.dictionary(rows_u @ data.Rh)
    bld.term(ce, cq, lay.q, -1.0, False)
    bld.term(ce, cu, lay.y.T, -1.0, False)  # Y' Rh': X = Y' (n x m), F = rows_u Rh
    gam = bld.dictionary(np.hstack([rows_q, rows_u]))
    bld.term(gam, gam, np.where(np.eye(p + m, dtype=bool), lay.gamma, -1), -1.0, True)
    del n


def _shared(data: KothareData, lay: VariableLayout) -> tuple[np.ndarray, ...]:
    """``[[W, Q Q1h', Y' Rh'], [Q1h Q, gamma I, 0], [Rh Y, 0, gamma I]]``."""
    n = data.n
    k = n + data.Q1h.shape[0] + data.m
    bld = _Builder(k)
    top = np.zeros((k, n))
    top[:n] = np.eye(n)
    assert lay.w is not None
    cw = bld.dictionary(top)
    bld.term(cw, cw, lay.w, -1.0, True)
    _cost_part(data, bld, lay, top, n)
    return bld.factor()


def _vertex(data: KothareData, lay: VariableLayout, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, ...]:
    n, m = data.n, data.m
    if data.formulation == "standard":
        k = 2 * n + data.Q1h.shape[0] + m
        bld = _Builder(k)
        top = np.zeros((k, n))
        top[:n] = np.eye(n)
        second = np.zeros((k, n))
        second[n:2 * n] = np.eye(n)
        # [[Q, G'], [G, Q]] with G = A Q + B Y: Q on both diagonal blocks, second G top'
        ct, cs = bld.dictionary(top), bld.dictionary(second)
        bld.term(ct, ct, lay.q, -1.0, True)
        bld.term(cs, cs, lay.q, -1.0, True)
        ca, cb = bld.dictionary(second @ a), bld.dictionary(second @ b)
        bld.term(ca, ct, lay.q, -1.0, False)
        bld.term(cb, ct, lay.y, -1.0, False)
        _cost_part(data, bld, lay, top, 2 * n)
        return bld.factor()
    dt = data.dt
    ah, bh = (a - np.eye(n)) / dt, b / dt
    s = np.sqrt(dt)
    k = 2 * n if data.formulation == "delta_shared" else 2 * n + data.Q1h.shape[0] + m
    bld = _Builder(k)
    top = np.zeros((k, n))
    top[:n] = np.eye(n)
    second = np.zeros((k, n))
    second[n:2 * n] = np.eye(n)
    # -(H + H') top-left and s H bottom-left: E = [-A~; s A~] (times Q) or [-B~; s B~] (times Y)
    ea = -top @ ah + s * second @ ah
    eb = -top @ bh + s * second @ bh
    ct, cs = bld.dictionary(top), bld.dictionary(second)
    ca, cb = bld.dictionary(ea), bld.dictionary(eb)
    bld.term(ca, ct, lay.q, -1.0, False)
    bld.term(cb, ct, lay.y, -1.0, False)
    bld.term(cs, cs, lay.q, -1.0, True)
    if data.formulation == "delta_shared":
        assert lay.w is not None
        bld.term(ct, ct, lay.w, 1.0, True)  # - W
    else:
        _cost_part(data, bld, lay, top, 2 * n)
    return bld.factor()
