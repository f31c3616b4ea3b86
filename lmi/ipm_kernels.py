"""Compiled kernels of the interior-point iterations of :mod:`lmi.ipm` (numba, ``nopython``).

The blocks of the Kothare problems are small (orders 7-15) and few (5-11), so a numpy
implementation of an iteration is dominated by the fixed cost of its ~250 array calls, not by
arithmetic (measured on paper P at 2 vertices: 0.55 of 0.8 ms per iteration). These kernels do
one iteration's work in three calls: :func:`residuals`, :func:`scaling_and_schur_rows` and
:func:`newton_step`; the Schur complement itself is factored by LAPACK from Python (in
:mod:`lmi.ipm`). Matrix products and eigen-decompositions are BLAS/LAPACK calls made from
compiled code; the Cholesky factorisations of the blocks and the smallest eigenvalues of the
step-length test are plain loops.

Layout shared by every kernel. ``nb`` blocks of orders ``orders[j]``; block matrices are held
in ``(nb, kmax, kmax)`` arrays, only ``[:k, :k]`` used. A packed vector holds, block after
block (``offsets[j]:offsets[j + 1]``), the upper triangle of each block row by row (the order
of ``numpy.triu_indices``) scaled by ``w`` (1 on the diagonal, sqrt(2) off it), entry ``t`` at
row ``ent_row[t]`` and column ``ent_col[t]``.
The coefficients, with the variable scaling applied, are held as their non-zero upper-triangle
entries: entry ``e`` (block ``j``'s entries are ``sp_off[j]:sp_off[j + 1]``) is
``A_ij[a, b] = sp_val[e]`` with ``i = sp_var[e]`` and ``(a, b)`` the position pair
``sp_pair[e]``; the distinct pairs of block ``j`` are ``pair_off[j]:pair_off[j + 1]``, pair
``q`` being ``(pair_row[q], pair_col[q])`` with ``a <= b``. The
Schur complement is ``H = P'P``; its factor is held transposed, ``pt`` ``(n, size)``, so that
the rows the kernels write are contiguous.

Compiled on first use and cached next to this file (``cache=True``): the first process after
an install pays the compilation (about 10-20 s here), later ones load it (well under 1 s).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "cholesky_blocks", "newton_step", "pack", "residuals", "scaling_and_schur_direct",
    "scaling_and_schur_grouped", "scaling_and_schur_rows", "smallest_eigenvalue", "unpack",
]

#: At most this many steps of iterative refinement per Newton solve (each stops early once
#: the residual of ``P' dz = -r_d`` stops shrinking).
REFINE_STEPS = 3

_JIT = {"cache": True, "nogil": True}


@njit(**_JIT)
def _unpack_block(vec, j, k, offsets, ent_row, ent_col, ent_w):
    """Block ``j`` (order ``k``) of a packed vector as a full symmetric ``(k, k)`` matrix."""
    out = np.empty((k, k))
    for t in range(offsets[j], offsets[j + 1]):
        v = vec[t] / ent_w[t]
        out[ent_row[t], ent_col[t]] = v
        out[ent_col[t], ent_row[t]] = v
    return out


@njit(**_JIT)
def _pack_block(mat, j, offsets, ent_row, ent_col, ent_w, out):
    for t in range(offsets[j], offsets[j + 1]):
        out[t] = mat[ent_row[t], ent_col[t]] * ent_w[t]


@njit(**_JIT)
def pack(mats, orders, offsets, ent_row, ent_col, ent_w):
    """Packed vector of the blocks ``mats`` ``(nb, kmax, kmax)``."""
    out = np.empty(offsets[-1])
    for j in range(orders.shape[0]):
        _pack_block(mats[j], j, offsets, ent_row, ent_col, ent_w, out)
    return out


@njit(**_JIT)
def unpack(vec, orders, offsets, ent_row, ent_col, ent_w, kmax):
    """Blocks ``(nb, kmax, kmax)`` (zero outside ``[:k, :k]``) of a packed vector."""
    out = np.zeros((orders.shape[0], kmax, kmax))
    for j in range(orders.shape[0]):
        k = orders[j]
        out[j, :k, :k] = _unpack_block(vec, j, k, offsets, ent_row, ent_col, ent_w)
    return out


@njit(**_JIT)
def _cholesky_into(a, k, out):
    """Lower Cholesky factor of ``a[:k, :k]`` into ``out[:k, :k]``; ``False`` if not positive
    definite (a non-positive or non-finite pivot)."""
    for j in range(k):
        for i in range(j):
            out[i, j] = 0.0
        s = a[j, j]
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


@njit(**_JIT)
def cholesky_blocks(mats, orders, out):
    """Cholesky factors of every block into ``out``; ``False`` if one is not positive definite."""
    for j in range(orders.shape[0]):
        if not _cholesky_into(mats[j], orders[j], out[j]):
            return False
    return True


@njit(**_JIT)
def residuals(s, z, x, g_mat, h_vec, cvec, orders, offsets, ent_row, ent_col, ent_w):
    """Residuals and norms at ``(x, S, Z)``.

    Returns ``rd = G'z + c``, ``rp = G x + s - h``, ``gap = s'z``, the primal and dual costs,
    and the norms of ``rp, G x, s, rd, G'z``.
    """
    sp = pack(s, orders, offsets, ent_row, ent_col, ent_w)
    zp = pack(z, orders, offsets, ent_row, ent_col, ent_w)
    gx = g_mat @ x
    gtz = g_mat.T @ zp
    rd = gtz + cvec
    rp = gx + sp - h_vec
    gap = float(sp @ zp)
    pcost = float(cvec @ x)
    dcost = -float(h_vec @ zp)
    return (rd, rp, gap, pcost, dcost, np.linalg.norm(rp), np.linalg.norm(gx), np.linalg.norm(sp),
            np.linalg.norm(rd), np.linalg.norm(gtz))


@njit(**_JIT)
def _nt_block(s_chol, z, j, k, kk_out, lam_out):
    """NT scaling of block ``j`` (see :func:`scaling_and_schur_rows`) into ``kk_out[j]`` and
    ``lam_out[j]``; ``False`` if the block lost positive definiteness."""
    ell = np.ascontiguousarray(s_chol[j, :k, :k])
    zj = np.ascontiguousarray(z[j, :k, :k])
    m = ell.T @ (zj @ ell)
    m = 0.5 * (m + m.T)
    if not np.all(np.isfinite(m)):
        return False
    d, qv = np.linalg.eigh(m)
    if not d[0] > 0.0:
        return False
    lam = np.sqrt(d)
    rr = (ell @ qv) / np.sqrt(lam)  # columns scaled
    kk_out[j, :k, :k] = (rr.T @ zj) / lam.reshape(k, 1)  # rows scaled
    lam_out[j, :k] = lam
    return True


@njit(**_JIT)
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
        kk = np.ascontiguousarray(kk_out[j, :k, :k])  # contiguous, as computed: same rounding
        kt = np.ascontiguousarray(kk.T)  # kt[a, p] = K[p, a]
        lo, hi = offsets[j], offsets[j + 1]
        size = hi - lo
        first = pair_off[j]
        basis = np.empty((pair_off[j + 1] - first, size))
        for q in range(first, pair_off[j + 1]):
            a, b = pair_row[q], pair_col[q]
            out = basis[q - first]
            for t in range(size):
                p, r = ent_row[lo + t], ent_col[lo + t]
                if a == b:
                    out[t] = ent_w[lo + t] * kt[a, p] * kt[a, r]
                else:
                    out[t] = ent_w[lo + t] * (kt[a, p] * kt[b, r] + kt[b, p] * kt[a, r])
        for i in range(n):
            for t in range(lo, hi):
                pt_out[i, t] = 0.0
        for e in range(sp_off[j], sp_off[j + 1]):
            v = sp_val[e]
            row = pt_out[sp_var[e]]
            src = basis[sp_pair[e] - first]
            for t in range(size):
                row[lo + t] += v * src[t]
    return True


@njit(**_JIT)
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


@njit(**_JIT)
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


@njit(**_JIT)
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


@njit(**_JIT)
def _pt_times(pt, v, kk, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val,
              pair_off, pair_row, pair_col, n):
    """``P' v`` for a packed ``v``: ``pt @ v`` if ``P`` is formed (``pt`` has columns), else
    ``sum_j <A_ij, K_j' V_j K_j>`` from the sparse coefficients: ``M = K_j' V_j K_j``, then
    ``M_ab + M_ba`` (``M_aa`` on the diagonal) once per position pair, then one multiply-add
    per coefficient entry."""
    if pt.shape[1] > 0:
        return pt @ v
    out = np.zeros(n)
    mp = np.empty(pair_row.shape[0])
    for j in range(orders.shape[0]):
        k = orders[j]
        kj = np.ascontiguousarray(kk[j, :k, :k])
        m = kj.T @ _unpack_block(v, j, k, offsets, ent_row, ent_col, ent_w) @ kj
        for q in range(pair_off[j], pair_off[j + 1]):
            a, b = pair_row[q], pair_col[q]
            mp[q] = m[a, a] if a == b else m[a, b] + m[b, a]
        for e in range(sp_off[j], sp_off[j + 1]):
            out[sp_var[e]] += sp_val[e] * mp[sp_pair[e]]
    return out


@njit(**_JIT)
def _p_times(pt, dx, kk, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val,
             pair_off, pair_row, pair_col):
    """``P dx`` (packed): ``pt.T @ dx`` if ``P`` is formed, else the packed
    ``K_j (sum_i dx_i A_ij) K_j'`` from the sparse coefficients (summed per position pair, in
    entry order)."""
    if pt.shape[1] > 0:
        return pt.T @ dx
    out = np.empty(offsets[-1])
    acc_pair = np.zeros(pair_row.shape[0])
    for j in range(orders.shape[0]):
        k = orders[j]
        for e in range(sp_off[j], sp_off[j + 1]):
            acc_pair[sp_pair[e]] += sp_val[e] * dx[sp_var[e]]
        acc = np.zeros((k, k))
        for q in range(pair_off[j], pair_off[j + 1]):
            a, b = pair_row[q], pair_col[q]
            acc[a, b] = acc_pair[q]
            acc[b, a] = acc_pair[q]
        kj = np.ascontiguousarray(kk[j, :k, :k])
        _pack_block(kj @ acc @ kj.T, j, offsets, ent_row, ent_col, ent_w, out)
    return out


@njit(**_JIT)
def _triangular_solve(r_fac, b):
    """``x`` with ``R'R x = b`` for upper triangular ``R``."""
    n = b.shape[0]
    y = b.copy()
    for i in range(n):  # R' y = b (forward), by rows of R: the subtractions of a row-by-column
        y[i] = y[i] / r_fac[i, i]  # loop in the same order (p ascending), contiguous reads
        for p in range(i + 1, n):
            y[p] -= r_fac[i, p] * y[i]
    x = np.empty(n)
    for i in range(n - 1, -1, -1):  # R x = y (backward)
        s = y[i]
        for p in range(i + 1, n):
            s -= r_fac[i, p] * x[p]
        x[i] = s / r_fac[i, i]
    return x


@njit(**_JIT)
def _newton(pt, r_fac, rd, rpt, u, ref_scale, kk, orders, offsets, ent_row, ent_col, ent_w, sp):
    """Scaled Newton step ``(dx, ds~, dz~)`` for the complementarity right-hand side ``u``.

    Solves ``P'P dx = -r_d - P'(u + r~_p)``, ``dz~ = P dx + u + r~_p``, ``ds~ = u - dz~``, then
    refines on the exact equation ``P' dz~ = -r_d`` while its residual shrinks. ``sp`` holds the
    sparse coefficients ``(sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col)`` used for the
    products with ``P`` when ``P`` is not formed (see :func:`_pt_times`).
    """
    n = rd.shape[0]
    lay = (orders, offsets, ent_row, ent_col, ent_w)
    v = u + rpt
    dx = _triangular_solve(r_fac, -rd - _pt_times(pt, v, kk, *lay, *sp, n))
    dzt = _p_times(pt, dx, kk, *lay, *sp) + v
    err = _pt_times(pt, dzt, kk, *lay, *sp, n) + rd
    err_norm = np.linalg.norm(err)
    for _ in range(REFINE_STEPS):
        if err_norm <= 1e-14 * ref_scale:
            break
        ddx = _triangular_solve(r_fac, -err)
        dzt_new = dzt + _p_times(pt, ddx, kk, *lay, *sp)
        err_new = _pt_times(pt, dzt_new, kk, *lay, *sp, n) + rd
        new_norm = np.linalg.norm(err_new)
        if new_norm >= err_norm:
            break
        dx, dzt, err, err_norm = dx + ddx, dzt_new, err_new, new_norm
    return dx, u - dzt, dzt


@njit(**_JIT)
def _sturm_count(d, e, k, sigma):
    """Number of eigenvalues below ``sigma`` of the tridiagonal matrix ``(d, e)`` (LDL' inertia)."""
    count = 0
    q = d[0] - sigma
    for i in range(k):
        if i > 0:
            if q == 0.0:
                q = 1e-300
            q = d[i] - sigma - e[i - 1] * e[i - 1] / q
        if q < 0.0:
            count += 1
    return count


@njit(**_JIT)
def _tridiagonalize(a, k):
    """Diagonal ``d`` and sub-diagonal ``e`` of a tridiagonal matrix similar to symmetric
    ``a[:k, :k]`` (Householder reflections; overwrites ``a``)."""
    d = np.empty(k)
    e = np.zeros(k)
    v = np.zeros(k)
    w = np.zeros(k)
    for c in range(k - 2):
        s = 0.0
        for i in range(c + 1, k):
            s += a[i, c] * a[i, c]
        if s == 0.0:
            e[c] = 0.0
            continue
        alpha = -np.sqrt(s) if a[c + 1, c] > 0.0 else np.sqrt(s)
        for i in range(c + 1, k):
            v[i] = a[i, c]
        v[c + 1] -= alpha
        vv = s - a[c + 1, c] * a[c + 1, c] + v[c + 1] * v[c + 1]
        beta = 2.0 / vv
        for i in range(c + 1, k):  # w = beta A v - (beta^2 v'Av / 2) v
            t = 0.0
            for j in range(c + 1, k):
                t += a[i, j] * v[j]
            w[i] = beta * t
        half = 0.0
        for i in range(c + 1, k):
            half += v[i] * w[i]
        half *= 0.5 * beta
        for i in range(c + 1, k):
            w[i] -= half * v[i]
        for i in range(c + 1, k):  # H A H = A - v w' - w v'
            for j in range(c + 1, k):
                a[i, j] -= v[i] * w[j] + w[i] * v[j]
        e[c] = alpha
    for i in range(k):
        d[i] = a[i, i]
    if k >= 2:
        e[k - 2] = a[k - 1, k - 2]
    return d, e


@njit(**_JIT)
def smallest_eigenvalue(a, k, upper=np.inf, rtol=4.0 * 2.220446049250313e-16):
    """A lower bound on the smallest eigenvalue of symmetric ``a[:k, :k]`` (overwrites ``a``).

    Householder reduction to tridiagonal form, then bisection on Sturm counts from the
    Gershgorin interval until the bracket is narrower than ``rtol`` times its largest end. The
    lower end of the bracket is returned, so a step length ``-1 / lambda`` computed from it is
    never too long. If the smallest eigenvalue is not below ``upper``, ``upper`` is returned
    after one Sturm count (the step-length search only needs eigenvalues below ``-1 / cap``).
    For the small blocks here this is several times faster than a LAPACK eigenvalue call from
    compiled code, whose fixed cost (copies, workspace queries) dominates.
    """
    d, e = _tridiagonalize(a, k)
    lo, hi = np.inf, -np.inf
    for i in range(k):
        radius = (abs(e[i - 1]) if i > 0 else 0.0) + (abs(e[i]) if i < k - 1 else 0.0)
        lo = min(lo, d[i] - radius)
        hi = max(hi, d[i] + radius)
    if upper < hi:
        if _sturm_count(d, e, k, upper) == 0:
            return upper
        hi = upper
    if not lo < hi:
        return lo
    width = rtol * max(abs(lo), abs(hi)) + 1e-300
    for _ in range(200):
        if hi - lo <= width:
            break
        mid = 0.5 * (lo + hi)
        if _sturm_count(d, e, k, mid) >= 1:
            hi = mid
        else:
            lo = mid
    return lo


#: Step lengths are computed up to this cap (the callers use ``min(1, a)`` and
#: ``min(1, 0.99 a)``), to this relative accuracy (a lower bound, never too long).
_STEP_CAP = 1.0 / 0.99
_STEP_RTOL = 1e-9


@njit(**_JIT)
def _max_step(lam, ds, dz, orders, offsets, ent_row, ent_col, ent_w):
    """Largest ``a`` (up to ``_STEP_CAP``) with ``diag(lambda) + a d >= 0`` for ``d`` = ``ds``
    and ``dz``, every block."""
    alpha = _STEP_CAP
    for j in range(orders.shape[0]):
        k = orders[j]
        isq = 1.0 / np.sqrt(lam[j, :k])
        for vec in (ds, dz):
            dd = _unpack_block(vec, j, k, offsets, ent_row, ent_col, ent_w)
            for a in range(k):
                for b in range(k):
                    dd[a, b] *= isq[a] * isq[b]
            t = smallest_eigenvalue(dd, k, -1.0 / alpha, _STEP_RTOL)
            if t < -1.0 / alpha:
                alpha = -1.0 / t
    return alpha


@njit(**_JIT)
def newton_step(pt, r_fac, kk, lam, x, theta, r0, rd, rp, g_mat, h_vec, mu, ref_scale,
                orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val, pair_off,
                pair_row, pair_col, s_out, z_out, chol_out):
    """One predictor-corrector step from ``(x, S, Z)`` (Mehrotra, as in CVXOPT's ``coneqp``).

    The new ``S`` is recomputed from ``x`` as ``h - G x + theta r0`` (``theta`` decays by
    ``1 - alpha``), so the primal residual decays exactly; its Cholesky factors go to
    ``chol_out`` (reused by the next scaling). If rounding leaves that ``S`` not positive
    definite, the step is shortened (at most five times by 0.8).

    ``pt`` is ``P'`` (``n x size``) when it was formed (QR phase), or ``n x 0`` when only ``H``
    was (:func:`scaling_and_schur_direct`); then the products with ``P`` come from the sparse
    coefficients ``sp_*``, ``pair_*`` (layout of :func:`scaling_and_schur_rows`).

    Returns ``(code, x_new, theta_new, alpha_aff, sigma, alpha)``; ``code`` 0 on success, 1 if
    the step length is not finite or <= 1e-12, 2 if no shortened step kept ``S`` positive
    definite.
    """
    nb = orders.shape[0]
    m = offsets[-1]
    # scaled primal residual K rp K'
    rpt = np.empty(m)
    for j in range(nb):
        k = orders[j]
        kj = np.ascontiguousarray(kk[j, :k, :k])
        rj = _unpack_block(rp, j, k, offsets, ent_row, ent_col, ent_w)
        _pack_block(kj @ rj @ kj.T, j, offsets, ent_row, ent_col, ent_w, rpt)
    # predictor: u = lambda^{o-1}(-lambda o lambda) = -diag(lambda)
    u = np.zeros(m)
    for j in range(nb):
        k = orders[j]
        for a in range(k):
            u[_diagonal_entry(offsets, j, k, a)] = -lam[j, a]
    sp = (sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col)
    _dx, dsa, dza = _newton(pt, r_fac, rd, rpt, u, ref_scale, kk, orders, offsets, ent_row, ent_col,
                            ent_w, sp)
    alpha_aff = min(1.0, _max_step(lam, dsa, dza, orders, offsets, ent_row, ent_col, ent_w))
    sigma = (1.0 - alpha_aff) ** 3
    # corrector: u = lambda^{o-1}(sigma mu e - lambda o lambda - ds_a o dz_a)
    u_cor = np.empty(m)
    for j in range(nb):
        k = orders[j]
        da = _unpack_block(dsa, j, k, offsets, ent_row, ent_col, ent_w)
        db = _unpack_block(dza, j, k, offsets, ent_row, ent_col, ent_w)
        prod = da @ db
        rc = -0.5 * (prod + prod.T)
        for a in range(k):
            rc[a, a] += sigma * mu - lam[j, a] * lam[j, a]
        for a in range(k):
            for b in range(k):
                rc[a, b] *= 2.0 / (lam[j, a] + lam[j, b])
        _pack_block(rc, j, offsets, ent_row, ent_col, ent_w, u_cor)
    dx, dst, dzt = _newton(pt, r_fac, rd, rpt, u_cor, ref_scale, kk, orders, offsets, ent_row,
                           ent_col, ent_w, sp)
    alpha = min(1.0, 0.99 * _max_step(lam, dst, dzt, orders, offsets, ent_row, ent_col, ent_w))
    if not (np.isfinite(alpha) and alpha > 1e-12):
        return 1, x, theta, alpha_aff, sigma, alpha
    for _ in range(6):
        x_new = x + alpha * dx
        theta_new = theta * (1.0 - alpha)
        s_vec = h_vec - g_mat @ x_new + theta_new * r0
        ok = True
        for j in range(nb):
            k = orders[j]
            s_out[j, :k, :k] = _unpack_block(s_vec, j, k, offsets, ent_row, ent_col, ent_w)
            if not _cholesky_into(s_out[j], k, chol_out[j]):
                ok = False
                break
        if not ok:
            alpha *= 0.8
            continue
        for j in range(nb):
            k = orders[j]
            kj = np.ascontiguousarray(kk[j, :k, :k])
            lz = alpha * _unpack_block(dzt, j, k, offsets, ent_row, ent_col, ent_w)
            for a in range(k):
                lz[a, a] += lam[j, a]
            zn = kj.T @ lz @ kj
            z_out[j, :k, :k] = 0.5 * (zn + zn.T)
        return 0, x_new, theta_new, alpha_aff, sigma, alpha
    return 2, x, theta, alpha_aff, sigma, alpha


@njit(**_JIT)
def _diagonal_entry(offsets, j, k, a):
    """Packed position of entry ``(a, a)`` of block ``j`` (upper triangle, row by row)."""
    return offsets[j] + a * k - (a * (a - 1)) // 2
