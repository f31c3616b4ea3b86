"""Kernels of the NT scaling and the Schur complement ``H = P'P`` (:mod:`lmi.ipm.kernels`).

:func:`scaling_and_schur_rows` forms ``P`` from the sparse coefficients and leaves ``H`` to
LAPACK; :func:`scaling_and_schur_blockwise` does the same block by block on each block's own
variables (``H`` block-arrow shaped: the vertex forms); :func:`scaling_and_schur_direct` and
:func:`scaling_and_schur_grouped` form ``H`` from the factored coefficients, the vertex blocks of
a group summed together.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from lmi.ipm.kernels.eigen import symmetric_eigen
from lmi.ipm.kernels.packed import JIT

__all__ = [
    "scaling_and_schur_blockwise", "scaling_and_schur_direct", "scaling_and_schur_grouped",
    "scaling_and_schur_rows",
]


@njit(**JIT)
def _nt_block(s_chol, z, j, k, kk_out, lam_out):
    """NT scaling of block ``j`` (see :func:`scaling_and_schur_rows`) into ``kk_out[j]`` and
    ``lam_out[j]``; ``False`` if the block lost positive definiteness. The block's matrices in
    one work array, the products BLAS calls into it (``np.dot`` with ``out``) and the scalings
    loops: the operations of ``ell.T @ (zj @ ell)``, ``(ell @ qv) / sqrt(lambda)`` and ``(rr.T @
    zj) / lambda`` in the same order, without their temporaries. The eigenvalues and vectors of
    ``ell.T zj ell`` come from :func:`~lmi.ipm.kernels.eigen.symmetric_eigen` (the C core's
    algorithm; a non-finite matrix or a QL iteration that does not converge is a lost block)."""
    size = k * k
    work = np.empty(7 * size + 2 * k)
    ell = work[:size].reshape((k, k))
    zj = work[size: 2 * size].reshape((k, k))
    prod = work[2 * size: 3 * size].reshape((k, k))
    out = work[3 * size: 4 * size].reshape((k, k))
    m = work[4 * size: 5 * size].reshape((k, k))
    qvt = work[5 * size: 6 * size].reshape((k, k))  # the eigenvectors as rows
    v_work = work[6 * size: 7 * size].reshape((k, k))
    d = work[7 * size: 7 * size + k]
    e_work = work[7 * size + k:]
    for a in range(k):
        for b in range(k):
            ell[a, b] = s_chol[j, a, b]
            zj[a, b] = z[j, a, b]
    np.dot(zj, ell, prod)
    np.dot(ell.T, prod, out)
    for a in range(k):
        for b in range(k):
            value = 0.5 * (out[a, b] + out[b, a])
            if not np.isfinite(value):
                return False
            m[a, b] = value
    if symmetric_eigen(m, k, d, qvt, v_work, e_work) != 0 or not d[0] > 0.0:
        return False
    lam = np.sqrt(d)
    root = np.sqrt(lam)
    rr = prod
    np.dot(ell, qvt.T, rr)
    for a in range(k):
        for b in range(k):
            rr[a, b] /= root[b]  # columns scaled
    np.dot(rr.T, zj, out)
    for a in range(k):
        for b in range(k):
            kk_out[j, a, b] = out[a, b] / lam[a]  # rows scaled
    lam_out[j, :k] = lam
    return True


#: The packing weight of an off-diagonal entry (:class:`lmi.ipm.blocks.PackedLayout`).
_SQRT2 = float(np.sqrt(2.0))


@njit(**JIT)
def _pair_basis(ka, kb, same, k, out):
    """The packed ``K (e_a e_b' + e_b e_a') K'`` (halved for ``a = b``, ``same``) into ``out``,
    from ``ka = K[:, a]`` and ``kb = K[:, b]``: row ``p`` of the upper triangle is
    ``w (ka[p] kb[p:] + kb[p] ka[p:])`` (``w`` 1 on the diagonal, sqrt(2) off it), contiguous,
    so the inner loop vectorises; each entry is computed as the packed layout's entry-by-entry
    formula ``w (K[p, a] K[r, b] + K[p, b] K[r, a])`` (``w K[p, a] K[r, a]`` when ``same``)
    computes it, in the same order."""
    t = 0
    for p in range(k):
        kap = ka[p]
        if same:
            out[t] = 1.0 * kap * ka[p]
            wap = _SQRT2 * kap
            for r in range(p + 1, k):
                out[t + r - p] = wap * ka[r]
        else:
            kbp = kb[p]
            out[t] = 1.0 * (kap * kb[p] + kbp * ka[p])
            for r in range(p + 1, k):
                out[t + r - p] = _SQRT2 * (kap * kb[r] + kbp * ka[r])
        t += k - p


@njit(**JIT)
def scaling_and_schur_rows(s_chol, z, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var,
                           sp_pair, sp_val, pair_off, pair_row, pair_col, kk_out, lam_out, pt_out):
    """Nesterov-Todd scaling of every block and the Schur complement factor ``P'`` (``pt_out``).

    For block ``j``, with ``S = L L'`` (``s_chol``) and ``L' Z L = Q diag(d) Q'`` (as in
    SDPT3): ``lambda = sqrt(d)``, ``R = L Q diag(lambda)^-1/2``, ``K = diag(lambda)^-1 R' Z``,
    so that ``K S K' = R' Z R = diag(lambda)``. Near the central path ``L' Z L`` is close to
    ``mu I``, so the eigen-decomposition is well conditioned even when ``S`` and ``Z`` are
    not.

    Then ``pt_out[i, t]`` is entry ``t`` of the packed ``K A_ij K'``. By linearity it is a sum,
    over the non-zero entries ``A_ij[a, b]`` (``a <= b``), of ``A_ij[a, b]`` times the packed
    ``K (e_a e_b' + e_b e_a') K'`` (halved for ``a = b``); those packed matrices are formed once
    per pair ``(a, b)`` that occurs (``pair_*``) and each entry is one contiguous multiply-add.
    The Kothare blocks have 1-5 % non-zero coefficient entries, so this is several times less
    arithmetic than two dense products per block. Returns ``False`` if a block lost positive
    definiteness.
    """
    n = pt_out.shape[0]
    for j in range(orders.shape[0]):
        k = orders[j]
        if not _nt_block(s_chol, z, j, k, kk_out, lam_out):
            return False
        lo, hi = offsets[j], offsets[j + 1]
        for i in range(n):
            for t in range(lo, hi):
                pt_out[i, t] = 0.0
        _block_rows(kk_out, j, k, hi - lo, pair_off, pair_row, pair_col, sp_off, sp_var, sp_pair, sp_val,
                    pt_out, lo)
    return True


@njit(**JIT)
def _block_rows(kk_out, j, k, size, pair_off, pair_row, pair_col, sp_off, sp_row, sp_pair, sp_val, out, col0):
    """Add block ``j``'s scaled coefficients ``K A_ij K'`` (packed, ``size`` entries) into the rows
    ``sp_row[e]`` of ``out`` from column ``col0`` on (zeroed by the caller): the packed pair
    bases of :func:`scaling_and_schur_rows`, then one contiguous multiply-add per coefficient
    entry, in entry order."""
    kk = np.ascontiguousarray(kk_out[j, :k, :k])  # contiguous, as computed: same rounding
    kt = np.ascontiguousarray(kk.T)  # kt[a, p] = K[p, a]
    first = pair_off[j]
    basis = np.empty((pair_off[j + 1] - first, size))
    for q in range(first, pair_off[j + 1]):
        _pair_basis(kt[pair_row[q]], kt[pair_col[q]], pair_row[q] == pair_col[q], k, basis[q - first])
    for e in range(sp_off[j], sp_off[j + 1]):
        v = sp_val[e]
        row = out[sp_row[e]]
        src = basis[sp_pair[e] - first]
        for t in range(size):
            row[col0 + t] += v * src[t]


#: The side of the tiles in which :func:`_block_gram` transposes ``U'`` (``nj x p``, 1.8 MB for
#: a vertex-pair block of order 28 on the flexible satellite): 32 took 16.5 ms per iteration over
#: that form's 97 blocks where the row-by-row transpose took 35.5 (8: 25, 16: 21).
TRANSPOSE_TILE = 32


@njit(**JIT)
def _pair_gram(w, first, p, k, pair_row, pair_col, gram):
    """The Gram matrix ``M`` of :func:`_block_gram` (``p x p``, into ``gram``) from ``W = K'K``:
    ``M_qr = 2 h_q h_r (W_cb W_ad + W_cd W_ab)`` for ``q = (a, c)``, ``r = (b, d)``.

    Row ``q`` is formed on and right of its diagonal, then the lower triangle is mirrored by
    ``TRANSPOSE_TILE`` tiles (writing ``M_rq`` with each ``M_qr`` went down a column: a line
    of cache per entry). A block whose pairs are every position of its upper triangle (``p =
    k (k + 1) / 2``; the pairs are the positions in packed row order) has row ``q`` from runs
    of contiguous ``d`` (the positions ``(b, d)``, ``d`` from the first in the row to
    ``k - 1``), so that its inner loop reads ``W``'s rows contiguously and vectorises; other
    blocks read ``(b, d)`` from the pair lists. Each entry is the same expression in the same
    order as the entry-by-entry formula (bit for bit)."""
    complete = p == k * (k + 1) // 2
    for q in range(p):
        a, c = pair_row[first + q], pair_col[first + q]
        hq = 0.5 if a == c else 1.0
        wa, wc = w[a], w[c]
        row = gram[q]
        if complete:
            r = q
            while r < p:
                b = pair_row[first + r]
                start = pair_col[first + r]
                wcb, wab = wc[b], wa[b]
                for t in range(k - start):
                    d = start + t
                    hr = 0.5 if b == d else 1.0
                    row[r + t] = 2.0 * hq * hr * (wcb * wa[d] + wc[d] * wab)
                r += k - start
        else:
            for r in range(q, p):
                b, d = pair_row[first + r], pair_col[first + r]
                hr = 0.5 if b == d else 1.0
                row[r] = 2.0 * hq * hr * (wc[b] * wa[d] + wc[d] * wa[b])
    for q0 in range(0, p, TRANSPOSE_TILE):
        for r0 in range(q0, p, TRANSPOSE_TILE):
            for q in range(q0, min(q0 + TRANSPOSE_TILE, p)):
                for r in range(max(r0, q + 1), min(r0 + TRANSPOSE_TILE, p)):
                    gram[r, q] = gram[q, r]


@njit(**JIT)
def _entry_rows(lo, hi, sp_loc, sp_pair, sp_val, first, src, out, lower):
    """``out[i] += sum_e v_e src[q_e - first]`` over the entries ``lo:hi`` (``i = sp_loc[e]``,
    ``q_e = sp_pair[e]``), each row over its first ``i + 1`` columns if ``lower``, else all.

    A variable's entries are consecutive (sorted by variable): they are added four at a time
    into the row, each element receiving its products in entry order, so the sums are those
    of one entry at a time bit for bit while the row is loaded and stored once per four
    entries (2.0 -> 1.6 ms per iteration of a vertex-pair block of the flexible satellite).
    Entries of a variable that are not consecutive still add in entry order."""
    cols = out.shape[1]
    e = lo
    while e < hi:
        i = sp_loc[e]
        stop = e
        while stop < hi and sp_loc[stop] == i:
            stop += 1
        row = out[i]
        width = i + 1 if lower else cols
        while e + 4 <= stop:
            v0, v1, v2, v3 = sp_val[e], sp_val[e + 1], sp_val[e + 2], sp_val[e + 3]
            s0 = src[sp_pair[e] - first]
            s1 = src[sp_pair[e + 1] - first]
            s2 = src[sp_pair[e + 2] - first]
            s3 = src[sp_pair[e + 3] - first]
            for t in range(width):
                row[t] = (((row[t] + v0 * s0[t]) + v1 * s1[t]) + v2 * s2[t]) + v3 * s3[t]
            e += 4
        while e < stop:
            v = sp_val[e]
            s0 = src[sp_pair[e] - first]
            for t in range(width):
                row[t] += v * s0[t]
            e += 1


@njit(**JIT)
def _block_gram(kk_out, j, k, pair_off, pair_row, pair_col, sp_off, sp_loc, sp_pair, sp_val, nj, work, hj):
    """``P_j'P_j`` of block ``j`` on its ``nj`` own variables into the lower triangle of ``hj``
    (the strict upper triangle is not written), without ``P_j``.

    Row ``i`` of ``P_j'`` is ``sum_e v_e b_(q_e)`` over the block's entries of variable ``i``
    (:func:`_block_rows`), ``b_q`` the packed ``K S_q K'`` of position pair ``q = (a, c)`` (``S_q =
    e_a e_c' + e_c e_a'``, halved for ``a = c``). So ``P_j'P_j = V' M V`` with ``V`` the entries
    (``p x nj``, ``p`` the block's position pairs) and ``M`` the Gram matrix of the bases: for
    ``q = (a, c)`` and ``r = (b, d)``, ``M_qr = <K S_q K', K S_r K'> = tr(S_q W S_r W) = 2 h_q h_r
    (W_cb W_ad + W_cd W_ab)`` with ``W = K'K`` (``h`` 1/2 on a diagonal pair, else 1): ``p^2`` entries
    (:func:`_pair_gram`), then ``U = M V`` (one contiguous multiply-add of length ``p`` per entry)
    and ``V'U`` (one of length ``nj`` per entry; both :func:`_entry_rows`), instead of ``nj x size``
    rows of ``P_j'`` and an ``nj^2 size`` ``dsyrk``: 22 times less arithmetic on the flexible
    satellite's vertex forms over 8 vertices. ``V'U`` is formed on and below the diagonal only
    (``H`` is symmetric; its factor reads that triangle), about half of that product's ``e_j nj``.
    ``work`` holds ``M``, ``U'`` and ``U`` (``p^2 + 2 p nj``)."""
    kj = np.ascontiguousarray(kk_out[j, :k, :k])
    w = kj.T @ kj
    first = pair_off[j]
    p = pair_off[j + 1] - first
    gram = work[: p * p].reshape((p, p))
    _pair_gram(w, first, p, k, pair_row, pair_col, gram)
    ut = work[p * p: p * p + nj * p].reshape((nj, p))  # U' = V'M, row i: sum_e v_e M[q_e]
    ut[:, :] = 0.0
    _entry_rows(sp_off[j], sp_off[j + 1], sp_loc, sp_pair, sp_val, first, gram, ut, False)
    u = work[p * p + nj * p: p * p + 2 * nj * p].reshape((p, nj))
    for i0 in range(0, nj, TRANSPOSE_TILE):  # U = (U')' by tiles: both sides' lines stay in cache
        for t0 in range(0, p, TRANSPOSE_TILE):
            for i in range(i0, min(i0 + TRANSPOSE_TILE, nj)):
                for t in range(t0, min(t0 + TRANSPOSE_TILE, p)):
                    u[t, i] = ut[i, t]
    for i in range(nj):
        for t in range(i + 1):
            hj[i, t] = 0.0
    # V'U, row i: sum_e v_e U[q_e], up to the diagonal
    _entry_rows(sp_off[j], sp_off[j + 1], sp_loc, sp_pair, sp_val, first, u, hj, True)


@njit(**JIT)
def scaling_and_schur_blockwise(s_chol, z, orders, sp_off, sp_pair, sp_val, pair_off, pair_row, pair_col,
                                bv_off, bv_var, sp_loc, run_off, runs, kk_out, lam_out, gram_work, h_work,
                                h_out):
    """NT scaling of every block and ``H = P'P`` formed block by block on each block's own variables.

    Only the lower triangle of ``H`` is formed (the strict upper triangle of ``h_out`` is not
    written; :func:`~lmi.ipm.kernels.lapack.arrow_cholesky` reads the lower one). Block ``j``
    holds only the variables ``bv_var[bv_off[j]:bv_off[j + 1]]`` (``n_j`` of them, ascending,
    so that each block's lower triangle lands in ``H``'s; ``sp_loc[e]`` is entry ``e``'s
    position among them): its ``P_j'P_j`` (``n_j x n_j``,
    in ``h_work``; :func:`_block_gram`, from the Gram matrix of the block's position pairs, ``P_j``
    never formed; ``gram_work`` its workspace) is added into ``H`` at those variables (``bv_var``
    their indices; the solver passes their positions in the order of its block-arrow factor,
    forming ``H`` in that order), one contiguous run of them at a time: the runs
    ``runs[run_off[j]:run_off[j + 1]]``, each ``(first, position, length)``, are the block's
    variables ``first .. first + length - 1`` (among its own), whose positions are ``position ..
    position + length - 1`` (1-3 runs per block in the vertex forms, where a block holds one or
    two vertices' Lyapunov matrices and the shared variables). A vertex form's blocks each hold
    one vertex's Lyapunov matrix and the shared variables, so that ``H`` is block-arrow shaped.
    Measured on the 14-state flexible satellite over 8 vertices (1184 variables): forming
    ``P_j'`` and one ``dsyrk`` per block took ``sum_j n_j^2 size_j`` = 1.0e9 operations (33 ms at
    the solver's iterates) where the rows formula's ``n^2 size`` was 1.06e10 (170 ms); the Gram
    formula's ``p_j^2 + e_j (p_j + n_j)`` is 4.6e7 (25 ms, the scatter into ``H`` included).
    Returns ``False`` if a block lost positive definiteness.
    """
    n = h_out.shape[0]
    for a in range(n):
        for b in range(a + 1):
            h_out[a, b] = 0.0
    for j in range(orders.shape[0]):
        k = orders[j]
        if not _nt_block(s_chol, z, j, k, kk_out, lam_out):
            return False
        lo = bv_off[j]
        nj = bv_off[j + 1] - lo
        if nj == 0:
            continue
        hj = h_work[: nj * nj].reshape((nj, nj))
        _block_gram(kk_out, j, k, pair_off, pair_row, pair_col, sp_off, sp_loc, sp_pair, sp_val, nj,
                    gram_work, hj)
        for a in range(nj):  # ascending positions: the lower triangle lands in the lower triangle
            hrow = h_out[bv_var[lo + a]]
            hja = hj[a]
            for r in range(run_off[j], run_off[j + 1]):
                first = runs[r, 0]
                if first > a:
                    break
                position = runs[r, 1]
                for t in range(min(runs[r, 2], a + 1 - first)):  # contiguous on both sides
                    hrow[position + t] += hja[first + t]
    return True


@njit(**JIT)
def scaling_and_schur_direct(s_chol, z, orders, dict_mat, dict_dims, fe_off, fe_var, fe_p, fe_q,
                             fe_val, kk_out, lam_out, h_out):
    """NT scaling of every block (as :func:`scaling_and_schur_rows`) and the Schur complement
    ``H = P'P`` itself (``h_out``, ``n x n``), formed without ``P``.

    Block ``j``'s coefficients are given in factored form ``A_ij = D_j N_ij D_j'`` with a
    dictionary ``D_j`` (``dict_mat[j, :k, :d]``, ``d = dict_dims[j]``) shared by every variable
    and sparse symmetric ``N_ij``: entry ``e`` (``fe_off[j]:fe_off[j + 1]``, sorted by variable)
    adds ``N_ij[p, q] = N_ij[q, p] = v`` (``p = fe_p[e] <= q = fe_q[e]``, ``i = fe_var[e]``),
    stored as ``fe_val[e] = v sqrt(2) h`` with ``h = 1`` (``p < q``) or ``1/2`` (``p = q``).
    With ``G = (K D)'(K D)``, ``H_ik = sum_j tr(A_ij W^-1 A_kj W^-1)`` (``W^-1 = K'K``) is a sum
    over pairs of entries of ``fe_val fe_val' (G_pr G_qs + G_ps G_qr)``: the cost is the square
    of the number of entries, not ``rows x n^2``. With ``D = I`` this is the sparse formula of
    SDPA (Fujisawa, Kojima, Nakata 1997); with the Kothare blocks' dictionaries
    (:mod:`lmi.kothare_factors`) a vertex block of order ``2n`` has about ``5 n^2 / 2`` entries.
    Returns ``False`` if a block lost positive definiteness. Every block is its own group of
    :func:`scaling_and_schur_grouped` (the same arithmetic, in the same order).
    """
    nb = orders.shape[0]
    return scaling_and_schur_grouped(s_chol, z, orders, dict_mat, dict_dims, fe_off, fe_var, fe_p,
                                     fe_q, fe_val, np.arange(nb + 1), np.arange(nb), kk_out,
                                     lam_out, h_out)


@njit(**JIT)
def scaling_and_schur_grouped(s_chol, z, orders, dict_mat, dict_dims, fe_off, fe_var, fe_p, fe_q,
                              fe_val, grp_off, grp_blk, kk_out, lam_out, h_out):
    """:func:`scaling_and_schur_direct` with blocks that share their entries summed together.

    The blocks ``grp_blk[grp_off[g]:grp_off[g + 1]]`` of group ``g`` have the same order,
    dictionary width and entries (``fe_var``, ``fe_p``, ``fe_q``, ``fe_val``; those of the
    group's first block are used); only their dictionaries ``D_j`` and NT points differ, as for
    the vertex blocks of a Kothare problem (only ``A_j``, ``B_j`` change from vertex to vertex).
    Their ``G_j`` are stacked ``(d, d, members)``, so a pair of entries reads its indices once
    and the group's ``G`` values from contiguous memory: ``c = v v' sum_j (G_j,pr G_j,qs +
    G_j,ps G_j,qr)``, the sum over ``j`` compiled with re-association allowed (vectorised; its
    rounding differs from the block-by-block sum). A group of one block does the arithmetic of
    :func:`scaling_and_schur_direct` bit for bit. Groups are summed into ``H`` in their order.
    """
    n = h_out.shape[0]
    for a in range(n):
        for b in range(n):
            h_out[a, b] = 0.0
    for g in range(grp_off.shape[0] - 1):
        first = grp_blk[grp_off[g]]
        members = grp_off[g + 1] - grp_off[g]
        k = orders[first]
        d = dict_dims[first]
        gs = np.empty((d, d, members))
        for jj in range(members):
            j = grp_blk[grp_off[g] + jj]
            if not _nt_block(s_chol, z, j, k, kk_out, lam_out):
                return False
            kd = np.ascontiguousarray(kk_out[j, :k, :k]) @ np.ascontiguousarray(dict_mat[j, :k, :d])
            gj = kd.T @ kd
            if members == 1:
                _pair_sum(gj, fe_off[first], fe_off[first + 1], fe_var, fe_p, fe_q, fe_val, h_out)
            else:
                for a in range(d):
                    for b in range(d):
                        gs[a, b, jj] = gj[a, b]
        if members > 1:
            _pair_sum_group(gs, fe_off[first], fe_off[first + 1], fe_var, fe_p, fe_q, fe_val, h_out)
    for a in range(n):
        for b in range(a + 1, n):
            h_out[b, a] = h_out[a, b]
    return True


@njit(**JIT)
def _pair_sum(g, lo, hi, fe_var, fe_p, fe_q, fe_val, h_out):
    """One block's pairs of entries ``lo:hi`` into the upper triangle of ``h_out`` (see
    :func:`scaling_and_schur_direct`)."""
    for e1 in range(lo, hi):
        i1 = fe_var[e1]
        p, q = fe_p[e1], fe_q[e1]
        v1 = fe_val[e1]
        gp = g[p]
        gq = g[q]
        hrow = h_out[i1]
        # the pair (e1, e1) once, pairs (e1, e2 > e1) of the same variable twice (for
        # (e2, e1)), pairs with a later variable once (H is mirrored by the caller)
        hrow[i1] += v1 * v1 * (gp[p] * gq[q] + gp[q] * gq[p])
        for e2 in range(e1 + 1, hi):
            r, t = fe_p[e2], fe_q[e2]
            c = v1 * fe_val[e2] * (gp[r] * gq[t] + gp[t] * gq[r])
            i2 = fe_var[e2]
            if i2 == i1:
                c *= 2.0
            hrow[i2] += c


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract", "nsz"})
def _pair_sum_group(gs, lo, hi, fe_var, fe_p, fe_q, fe_val, h_out):
    """:func:`_pair_sum` for a group of blocks with the same entries, ``gs`` ``(d, d, members)``;
    the sum over the members may be re-associated (vectorised)."""
    members = gs.shape[2]
    for e1 in range(lo, hi):
        i1 = fe_var[e1]
        p, q = fe_p[e1], fe_q[e1]
        v1 = fe_val[e1]
        gp = gs[p]
        gq = gs[q]
        hrow = h_out[i1]
        s = 0.0
        for jj in range(members):
            s += gp[p, jj] * gq[q, jj] + gp[q, jj] * gq[p, jj]
        hrow[i1] += v1 * v1 * s
        for e2 in range(e1 + 1, hi):
            r, t = fe_p[e2], fe_q[e2]
            s = 0.0
            for jj in range(members):
                s += gp[r, jj] * gq[t, jj] + gp[t, jj] * gq[r, jj]
            c = v1 * fe_val[e2] * s
            i2 = fe_var[e2]
            if i2 == i1:
                c *= 2.0
            hrow[i2] += c
