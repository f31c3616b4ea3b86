"""Kernels of the packed layout (:mod:`lmi.ipm.kernels`): packing, block Cholesky, residuals."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "JIT", "blocks_within", "cholesky_blocks", "cholesky_into", "diagonal_entry", "pack", "pack_block",
    "residuals", "unpack", "unpack_block", "unpack_block_into",
]

#: numba's options for every kernel: compiled once and cached on disk, released from the GIL.
JIT = {"cache": True, "nogil": True}


@njit(**JIT)
def unpack_block_into(vec, j, offsets, ent_row, ent_col, ent_w, out):
    """Block ``j`` of a packed vector, full and symmetric, into ``out[:k, :k]`` (``k`` its order;
    no allocation: ``out`` may be a work array of any larger order, or a block of a
    ``(nb, kmax, kmax)`` array)."""
    for t in range(offsets[j], offsets[j + 1]):
        v = vec[t] / ent_w[t]
        out[ent_row[t], ent_col[t]] = v
        out[ent_col[t], ent_row[t]] = v


@njit(**JIT)
def unpack_block(vec, j, k, offsets, ent_row, ent_col, ent_w):
    """Block ``j`` (order ``k``) of a packed vector as a full symmetric ``(k, k)`` matrix."""
    out = np.empty((k, k))
    unpack_block_into(vec, j, offsets, ent_row, ent_col, ent_w, out)
    return out


@njit(**JIT)
def pack_block(mat, j, offsets, ent_row, ent_col, ent_w, out):
    for t in range(offsets[j], offsets[j + 1]):
        out[t] = mat[ent_row[t], ent_col[t]] * ent_w[t]


@njit(**JIT)
def pack(mats, orders, offsets, ent_row, ent_col, ent_w):
    """Packed vector of the blocks ``mats`` ``(nb, kmax, kmax)``."""
    out = np.empty(offsets[-1])
    for j in range(orders.shape[0]):
        pack_block(mats[j], j, offsets, ent_row, ent_col, ent_w, out)
    return out


@njit(**JIT)
def unpack(vec, orders, offsets, ent_row, ent_col, ent_w, kmax):
    """Blocks ``(nb, kmax, kmax)`` (zero outside ``[:k, :k]``) of a packed vector."""
    out = np.zeros((orders.shape[0], kmax, kmax))
    for j in range(orders.shape[0]):
        k = orders[j]
        out[j, :k, :k] = unpack_block(vec, j, k, offsets, ent_row, ent_col, ent_w)
    return out


@njit(**JIT)
def cholesky_into(a, k, out, shift=0.0):
    """Lower Cholesky factor of ``a[:k, :k] + shift I`` into ``out[:k, :k]``; ``False`` if not
    positive definite (a non-positive or non-finite pivot). (``shift`` 0 adds nothing: ``x + 0.0``
    is ``x`` for every pivot that can pass.)"""
    for j in range(k):
        for i in range(j):
            out[i, j] = 0.0
        s = a[j, j] + shift
        for p in range(j):
            s -= out[j, p] * out[j, p]
        if not 0.0 < s < np.inf:
            return False
        d = np.sqrt(s)
        out[j, j] = d
        for i in range(j + 1, k):
            s = a[i, j]
            for p in range(j):
                s -= out[i, p] * out[j, p]
            out[i, j] = s / d
    return True


@njit(**JIT)
def cholesky_blocks(mats, orders, out):
    """Cholesky factors of every block into ``out``; ``False`` if one is not positive definite."""
    for j in range(orders.shape[0]):
        if not cholesky_into(mats[j], orders[j], out[j]):
            return False
    return True


@njit(**JIT)
def residuals(s, z, x, g_mat, h_vec, cvec, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair,
              sp_val, pair_off, pair_row, pair_col):
    """Residuals and norms at ``(x, S, Z)``.

    Returns ``rd = G'z + c``, ``rp = G x + s - h``, ``gap = s'z``, the primal and dual costs,
    and the norms of ``rp, G x, s, rd, G'z``. ``G`` dense (``g_mat``), or from the sparse
    coefficients when ``g_mat`` has no rows (:func:`g_times`).
    """
    sp = pack(s, orders, offsets, ent_row, ent_col, ent_w)
    zp = pack(z, orders, offsets, ent_row, ent_col, ent_w)
    gx = g_times(g_mat, x, orders, offsets, ent_w, sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row,
                 pair_col)
    gtz = gt_times(g_mat, zp, x.shape[0], orders, offsets, ent_w, sp_off, sp_var, sp_pair, sp_val, pair_off,
                   pair_row, pair_col)
    rd = gtz + cvec
    rp = gx + sp - h_vec
    gap = float(sp @ zp)
    pcost = float(cvec @ x)
    dcost = -float(h_vec @ zp)
    return (rd, rp, gap, pcost, dcost, np.linalg.norm(rp), np.linalg.norm(gx), np.linalg.norm(sp),
            np.linalg.norm(rd), np.linalg.norm(gtz))


@njit(**JIT)
def _pair_position(offsets, orders, j, a, b):
    """Packed position of entry ``(a, b)``, ``a <= b``, of block ``j``."""
    return diagonal_entry(offsets, j, orders[j], a) + b - a


@njit(**JIT)
def _pair_positions(orders, offsets, pair_off, pair_row, pair_col):
    """Packed position of every position pair ``q`` (:func:`_pair_position`), computed once per
    pair instead of once per coefficient entry (the products with ``G`` below: about 4 entries
    per pair on the vertex forms; the integer arithmetic cost more than the multiply-adds)."""
    pos = np.empty(pair_row.shape[0], dtype=np.int64)
    for j in range(orders.shape[0]):
        for q in range(pair_off[j], pair_off[j + 1]):
            pos[q] = _pair_position(offsets, orders, j, pair_row[q], pair_col[q])
    return pos


@njit(**JIT)
def g_times(g_mat, x, orders, offsets, ent_w, sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col):
    """``G x`` (packed ``sum_i x_i A_ij``, scaled): ``g_mat @ x``, or, when ``g_mat`` has no rows
    (not formed), from the sparse coefficients (one multiply-add per entry, then the packing
    weights), which is far less work on problems whose blocks hold few of the variables."""
    if g_mat.shape[0] > 0:
        return g_mat @ x
    pos = _pair_positions(orders, offsets, pair_off, pair_row, pair_col)
    out = np.zeros(offsets[-1])
    for e in range(sp_off[-1]):
        out[pos[sp_pair[e]]] += sp_val[e] * x[sp_var[e]]
    return out * ent_w


@njit(**JIT)
def gt_times(g_mat, v, n, orders, offsets, ent_w, sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row,
             pair_col):
    """``G' v`` for a packed ``v``: ``g_mat.T @ v``, or from the sparse coefficients when ``g_mat``
    has no rows (see :func:`g_times`)."""
    if g_mat.shape[0] > 0:
        return g_mat.T @ v
    pos = _pair_positions(orders, offsets, pair_off, pair_row, pair_col)
    out = np.zeros(n)
    for e in range(sp_off[-1]):
        t = pos[sp_pair[e]]
        out[sp_var[e]] += sp_val[e] * ent_w[t] * v[t]
    return out


@njit(**JIT)
def diagonal_entry(offsets, j, k, a):
    """Packed position of entry ``(a, a)`` of block ``j`` (upper triangle, row by row)."""
    return offsets[j] + a * k - (a * (a - 1)) // 2


@njit(**JIT)
def blocks_within(s, x, rp, g_mat, h_vec, tol, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var,
                  sp_pair, sp_val, pair_off, pair_row, pair_col):
    """Whether every block's primal residual is within ``tol`` of that block's size:
    ``max |rp_j| <= tol max(max |h_j|, max (|G_j| |x|), max |s_j|)`` (max-norms, so no squares
    underflow for tiny blocks; ``|G_j| |x|``, the magnitudes of the terms of ``G_j x``, so a block
    whose terms cancel keeps its size). ``G`` from the sparse coefficients when ``g_mat`` has no
    rows (:func:`g_times`). See :meth:`lmi.ipm.BlockLMISolver.solve`."""
    sp = pack(s, orders, offsets, ent_row, ent_col, ent_w)
    n = x.shape[0]
    sparse_terms = np.zeros(0)
    if g_mat.shape[0] == 0:
        sparse_terms = g_times(g_mat, np.abs(x), orders, offsets, ent_w, sp_off, sp_var, sp_pair,
                               np.abs(sp_val), pair_off, pair_row, pair_col)
    for j in range(orders.shape[0]):
        size = 0.0
        worst = 0.0
        for t in range(offsets[j], offsets[j + 1]):
            if g_mat.shape[0] == 0:
                terms = sparse_terms[t]
            else:
                terms = 0.0
                for i in range(n):
                    terms += abs(g_mat[t, i]) * abs(x[i])
            size = max(size, abs(h_vec[t]), terms, abs(sp[t]))
            worst = max(worst, abs(rp[t]))
        if not worst <= tol * size:
            return False
    return True
