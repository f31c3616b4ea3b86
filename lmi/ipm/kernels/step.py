"""Kernels of the Newton step (:mod:`lmi.ipm.kernels`): the refined Newton solve, the smallest
eigenvalue of the step-length test and the predictor-corrector step itself."""

from __future__ import annotations

import numpy as np
from numba import njit

from lmi.ipm.kernels.eigen import smallest_eigenvalue
from lmi.ipm.kernels.lapack import triangular_solve_blas
from lmi.ipm.kernels.packed import JIT, cholesky_into, diagonal_entry, g_times, pack_block, unpack_block_into

__all__ = ["REFINE_STEPS", "REFINE_TARGET", "STEP_INACCURATE", "newton_step"]

#: :func:`newton_step`'s code for a corrector whose dual equation missed the accuracy asked
#: (outside the QR phase); no step was taken.
STEP_INACCURATE = 5

#: At most this many steps of iterative refinement per Newton solve (each stops early once
#: the residual of ``P' dz = -r_d`` stops shrinking or meets :data:`REFINE_TARGET`).
REFINE_STEPS = 3

#: Iterative refinement of a Newton solve stops once the residual of ``P' dz = -r_d`` is at most
#: this fraction of the solver's reference scale (``max(||c||, ||G' z||)``). The solver asks the
#: dual residual for ``tol_feas`` (1e-8) of that scale, so 1e-12 leaves four orders of magnitude.
#: Measured at the iterates of warm solves: paper W's vertex form's residual cannot be evaluated
#: below 2-4e-14 of the scale, so a target of 1e-14 (before) ran every refinement to its limit and
#: discarded the last step (49 refinement steps in 9 iterations; 18 with 1e-12, the residuals
#: reached 2e-14..9e-13 of the scale); on paper P's vertex forms 28 -> 24 and 50 -> 42.
REFINE_TARGET = 1e-12


@njit(**JIT)
def _square(work, slot, k):
    """Slot ``slot`` of the flat work array ``work`` (``slots x kmax^2``) as a contiguous ``(k, k)``
    matrix (a view: no allocation)."""
    return work[slot * k * k: (slot + 1) * k * k].reshape((k, k))


@njit(**JIT)
def _squares(work, k):
    """The four slots of ``work`` as ``(k, k)`` matrices (:func:`_square`)."""
    return _square(work, 0, k), _square(work, 1, k), _square(work, 2, k), _square(work, 3, k)


@njit(**JIT)
def _contiguous_scaling(kk, j, k, out):
    """``out = kk[j, :k, :k]`` (contiguous ``(k, k)``), as ``np.ascontiguousarray`` copies it."""
    for a in range(k):
        for b in range(k):
            out[a, b] = kk[j, a, b]


@njit(**JIT)
def _pt_times(pt, v, kk, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val,
              pair_off, pair_row, pair_col, n):
    """``P' v`` for a packed ``v``: ``pt @ v`` if ``P`` is formed (``pt`` has columns), else
    ``sum_j <A_ij, K_j' V_j K_j>`` from the sparse coefficients: ``M = K_j' V_j K_j``, then
    ``M_ab + M_ba`` (``M_aa`` on the diagonal) once per position pair, then one multiply-add
    per coefficient entry. The blocks' matrices live in one work array (:func:`_square`) and
    the products are BLAS calls into it (``np.dot`` with ``out``): no allocation per block."""
    if pt.shape[1] > 0:
        return pt @ v
    out = np.zeros(n)
    mp = np.empty(pair_row.shape[0])
    work = np.empty(4 * kk.shape[1] * kk.shape[2])
    for j in range(orders.shape[0]):
        k = orders[j]
        kj, vj, left, m = _squares(work, k)
        _contiguous_scaling(kk, j, k, kj)
        unpack_block_into(v, j, offsets, ent_row, ent_col, ent_w, vj)
        np.dot(kj.T, vj, left)
        np.dot(left, kj, m)
        for q in range(pair_off[j], pair_off[j + 1]):
            a, b = pair_row[q], pair_col[q]
            mp[q] = m[a, a] if a == b else m[a, b] + m[b, a]
        for e in range(sp_off[j], sp_off[j + 1]):
            out[sp_var[e]] += sp_val[e] * mp[sp_pair[e]]
    return out


@njit(**JIT)
def _p_times(pt, dx, kk, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val,
             pair_off, pair_row, pair_col):
    """``P dx`` (packed): ``pt.T @ dx`` if ``P`` is formed, else the packed
    ``K_j (sum_i dx_i A_ij) K_j'`` from the sparse coefficients (summed per position pair, in
    entry order; the products in a work array, see :func:`_pt_times`)."""
    if pt.shape[1] > 0:
        return pt.T @ dx
    out = np.empty(offsets[-1])
    acc_pair = np.zeros(pair_row.shape[0])
    work = np.empty(4 * kk.shape[1] * kk.shape[2])
    for j in range(orders.shape[0]):
        k = orders[j]
        kj, acc, left, m = _squares(work, k)
        _block_p_times(kk, j, k, dx, acc_pair, sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col,
                       kj, acc, left, m)
        pack_block(m, j, offsets, ent_row, ent_col, ent_w, out)
    return out


@njit(**JIT)
def _block_p_times(kk, j, k, dx, acc_pair, sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col, kj,
                   acc, left, m):
    """Block ``j`` of ``P dx``, unpacked into ``m``: ``K_j (sum_i dx_i A_ij) K_j'``, the sum per
    position pair in entry order (``acc_pair``), ``K_j`` copied into ``kj``, ``acc`` and ``left``
    work arrays (of :func:`_squares`)."""
    for e in range(sp_off[j], sp_off[j + 1]):
        acc_pair[sp_pair[e]] += sp_val[e] * dx[sp_var[e]]
    acc[:, :] = 0.0
    for q in range(pair_off[j], pair_off[j + 1]):
        a, b = pair_row[q], pair_col[q]
        acc[a, b] = acc_pair[q]
        acc[b, a] = acc_pair[q]
    _contiguous_scaling(kk, j, k, kj)
    np.dot(kj, acc, left)
    np.dot(left, kj.T, m)


@njit(**JIT)
def _p_then_pt(pt, dx, base, kk, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val,
               pair_off, pair_row, pair_col, n):
    """``(dz, P' dz)`` with ``dz = base + P dx`` (packed): :func:`_p_times`, the sum and
    :func:`_pt_times` block by block in one pass (each block's ``dz`` entries formed, stored and
    unpacked at once, its ``K`` copied once), the same operations in the same order as the three
    calls, so the same results bit for bit."""
    if pt.shape[1] > 0:
        dz = base + pt.T @ dx
        return dz, pt @ dz
    dz = np.empty(offsets[-1])
    out = np.zeros(n)
    acc_pair = np.zeros(pair_row.shape[0])
    mp = np.empty(pair_row.shape[0])
    work = np.empty(4 * kk.shape[1] * kk.shape[2])
    for j in range(orders.shape[0]):
        k = orders[j]
        kj, acc, left, m = _squares(work, k)
        _block_p_times(kk, j, k, dx, acc_pair, sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col,
                       kj, acc, left, m)  # block j of P dx, unpacked
        vj = acc
        for t in range(offsets[j], offsets[j + 1]):
            r, c = ent_row[t], ent_col[t]
            value = base[t] + m[r, c] * ent_w[t]
            dz[t] = value
            value = value / ent_w[t]
            vj[r, c] = value
            vj[c, r] = value
        np.dot(kj.T, vj, left)
        np.dot(left, kj, m)  # K' dz_j K
        for q in range(pair_off[j], pair_off[j + 1]):
            a, b = pair_row[q], pair_col[q]
            mp[q] = m[a, a] if a == b else m[a, b] + m[b, a]
        for e in range(sp_off[j], sp_off[j + 1]):
            out[sp_var[e]] += sp_val[e] * mp[sp_pair[e]]
    return dz, out


@njit(**JIT)
def _forward(r_fac, b):
    """``y`` with ``R' y = b`` for upper triangular ``R``."""
    n = b.shape[0]
    y = b.copy()
    for i in range(n):  # by rows of R: the subtractions of a row-by-column loop in the same
        y[i] = y[i] / r_fac[i, i]  # order (p ascending), contiguous reads
        for p in range(i + 1, n):
            y[p] -= r_fac[i, p] * y[i]
    return y


@njit(**JIT)
def _backward(r_fac, b):
    """``x`` with ``R x = b`` for upper triangular ``R``."""
    n = b.shape[0]
    x = np.empty(n)
    for i in range(n - 1, -1, -1):
        s = b[i]
        for p in range(i + 1, n):
            s -= r_fac[i, p] * x[p]
        x[i] = s / r_fac[i, i]
    return x


@njit(**JIT)
def _triangular_solve(r_fac, b):
    """``x`` with ``R'R x = b`` for upper triangular ``R``."""
    return _backward(r_fac, _forward(r_fac, b))


@njit(**JIT)
def _factor_solve(r_fac, perm, b):
    """``x`` with ``H x = b``: ``R'R x = b`` (``perm`` empty), or, with the factor of ``H`` in the
    variable order ``perm`` (``R'R = H[perm][:, perm]``, :func:`~lmi.ipm.kernels.lapack.arrow_cholesky`),
    ``x[perm] = (R'R)^-1 b[perm]`` by BLAS (``dtrsv``)."""
    if perm.shape[0] == 0:
        return _triangular_solve(r_fac, b)
    y = triangular_solve_blas(r_fac, b[perm])
    x = np.empty_like(y)
    x[perm] = y
    return x


@njit(**JIT)
def _newton(pt, r_fac, perm, rd, rpt, u, ref_scale, kk, orders, offsets, ent_row, ent_col, ent_w, sp):
    """Scaled Newton step ``(dx, ds~, dz~, e)`` for the complementarity right-hand side ``u``.

    Solves ``P'P dx = -r_d - P'(u + r~_p)`` (``R'R = P'P``, or with ``perm`` see
    :func:`_factor_solve`), ``dz~ = P dx + u + r~_p``, ``ds~ = u - dz~``, then
    refines on the exact equation ``P' dz~ = -r_d`` while its residual shrinks; ``e`` is the norm
    of that residual, ``||P' dz~ + r_d||``, at the end. ``sp`` holds the
    sparse coefficients ``(sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col)`` used for the
    products with ``P`` when ``P`` is not formed (see :func:`_pt_times`).
    """
    n = rd.shape[0]
    lay = (orders, offsets, ent_row, ent_col, ent_w)
    v = u + rpt
    dx = _factor_solve(r_fac, perm, -rd - _pt_times(pt, v, kk, *lay, *sp, n))
    dzt, ptz = _p_then_pt(pt, dx, v, kk, *lay, *sp, n)  # P dx + v and P' of it
    err = ptz + rd
    err_norm = np.linalg.norm(err)
    for _ in range(REFINE_STEPS):
        if err_norm <= REFINE_TARGET * ref_scale:
            break
        ddx = _factor_solve(r_fac, perm, -err)
        dzt_new, ptz = _p_then_pt(pt, ddx, dzt, kk, *lay, *sp, n)
        err_new = ptz + rd
        new_norm = np.linalg.norm(err_new)
        if new_norm >= err_norm:
            break
        dx, dzt, err, err_norm = dx + ddx, dzt_new, err_new, new_norm
    return dx, u - dzt, dzt, err_norm


@njit(**JIT)
def _householder(qr_h, qr_tau, y, transpose):
    """``Q' y`` (``transpose``) or ``Q y`` in place, ``Q = H_0 ... H_{n-1}`` the orthogonal factor
    of ``P`` as LAPACK's ``geqrf`` leaves it (numpy's ``qr(mode="raw")``): reflector ``k`` is
    ``H_k = I - tau_k v_k v_k'`` with ``v_k[k] = 1`` and ``v_k[k + 1:] = qr_h[k, k + 1:]``."""
    n, m = qr_h.shape
    for step in range(n):
        k = step if transpose else n - 1 - step
        s = y[k]
        for t in range(k + 1, m):
            s += qr_h[k, t] * y[t]
        s *= qr_tau[k]
        y[k] -= s
        for t in range(k + 1, m):
            y[t] -= s * qr_h[k, t]


@njit(**JIT)
def _newton_qr(pt, qr_h, qr_tau, r_fac, rd, rpt, u, ref_scale):
    """:func:`_newton` with the orthogonal factor of ``P = Q [R; 0]`` (the QR phase, ``P`` formed).

    The equations ``P' dz~ = -r_d``, ``dz~ = P dx + v`` (``v = u + r~_p``) are solved as a
    projection: with ``t = Q' v`` and ``R' w = r_d``, ``dz~ = Q [-w; t_2]`` (``t_2`` the rows of
    ``t`` below ``n``) and ``R dx = -(w + t_1)``. Then ``P' dz~ + r_d`` is of the order of the
    rounding of ``P`` and ``v``. Through the normal equations (``R'R dx = -r_d - P' v``, as
    :func:`_newton` does) it is of the order ``eps ||P||^2 ||dx||``, which refinement cannot
    reduce once ``eps cond(P)^2 > 1``: measured on a 12-state unstable Kothare problem, it grew
    to 40 times ``||r_d||`` over the last iterations and the dual residual with it, from 3e-8 to
    1 (see :mod:`dev.generic_stress`). One refinement step on ``P' dz~ = -r_d`` (with the
    formed ``P``) follows while it shrinks the residual.
    """
    n, m = qr_h.shape
    v = u + rpt
    w = _forward(r_fac, rd)
    t = v.copy()
    _householder(qr_h, qr_tau, t, True)
    dx = _backward(r_fac, -(w + t[:n]))
    y = t.copy()
    for i in range(n):
        y[i] = -w[i]
    _householder(qr_h, qr_tau, y, False)
    dzt = y
    err = pt @ dzt + rd
    err_norm = np.linalg.norm(err)
    for _ in range(REFINE_STEPS):
        if err_norm <= REFINE_TARGET * ref_scale:
            break
        corr = np.zeros(m)
        cw = _forward(r_fac, err)
        for i in range(n):
            corr[i] = cw[i]
        _householder(qr_h, qr_tau, corr, False)
        dzt_new = dzt - corr
        err_new = pt @ dzt_new + rd
        new_norm = np.linalg.norm(err_new)
        if new_norm >= err_norm:
            break
        dx = dx - _backward(r_fac, cw)
        dzt, err, err_norm = dzt_new, err_new, new_norm
    return dx, u - dzt, dzt


#: Step lengths are computed up to this cap (the callers use ``min(1, a)`` and
#: ``min(1, 0.99 a)``), to this relative accuracy (a lower bound, never too long).
_STEP_CAP = 1.0 / 0.99
_STEP_RTOL = 1e-9


@njit(**JIT)
def _max_step(lam, ds, dz, orders, offsets, ent_row, ent_col, ent_w):
    """Largest ``a`` (up to ``_STEP_CAP``) with ``diag(lambda) + a d >= 0`` for ``d`` = ``ds``
    and ``dz``, every block.

    With ``D = diag(lambda)^-1/2 d diag(lambda)^-1/2``, a block limits the step below the current
    ``a`` only if the smallest eigenvalue of ``D`` is below ``-1 / a``. Most blocks do not: a
    Cholesky factorisation of ``D + I / a`` (``k^3 / 6`` operations) shows it, and
    :func:`smallest_eigenvalue` (a tridiagonalisation, ``4 k^3 / 3``, and a bisection) is called
    only for a block whose shifted matrix is not positive definite; it returns ``-1 / a`` itself
    for a block that rounding alone failed there."""
    alpha = _STEP_CAP
    kmax = lam.shape[1]
    dd = np.empty((kmax, kmax))
    work = np.empty((kmax, kmax))
    for j in range(orders.shape[0]):
        k = orders[j]
        isq = 1.0 / np.sqrt(lam[j, :k])
        for vec in (ds, dz):
            unpack_block_into(vec, j, offsets, ent_row, ent_col, ent_w, dd)
            for a in range(k):
                for b in range(k):
                    dd[a, b] *= isq[a] * isq[b]
            if cholesky_into(dd, k, work, 1.0 / alpha):  # D + I / a positive definite
                continue
            t = smallest_eigenvalue(dd, k, -1.0 / alpha, _STEP_RTOL)
            if t < -1.0 / alpha:
                alpha = -1.0 / t
    return alpha


@njit(**JIT)
def newton_step(pt, r_fac, perm, qr_h, qr_tau, kk, lam, x, z, theta, r0, rd, rp, g_mat, h_vec, mu,
                ref_scale, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val,
                pair_off, pair_row, pair_col, s_out, z_out, chol_out, err_limit):
    """One predictor-corrector step from ``(x, S, Z)`` (Mehrotra, as in CVXOPT's ``coneqp``).

    The new ``S`` is recomputed from ``x`` as ``h - G x + theta r0`` (``theta`` decays by
    ``1 - alpha``), so the primal residual decays exactly; its Cholesky factors go to
    ``chol_out`` (reused by the next scaling). If rounding leaves that ``S`` not positive
    definite, the step is shortened (at most five times by 0.8). The new ``Z`` is
    ``Z + alpha K' dz~ K`` (``z``, the current dual blocks), so the dual residual decays by
    ``1 - alpha`` up to the rounding of the step; formed through the scaling,
    ``K'(lambda + alpha dz~) K``, each iterate was rounded afresh with ``K``, whose condition
    number reaches 1e8 near the optimum of badly scaled problems (measured on a 12-state unstable
    Kothare problem: the dual residual then grew from 2e-8 to 1e-5 over the last 8 iterations
    instead of decaying). If rounding leaves ``Z + alpha dZ`` not positive definite (checked by
    Cholesky), that block is formed through the scaling, positive definite by the step length.
    In the QR phase (``qr_h``, ``qr_tau``: the Householder factors of ``P``, else empty) the
    Newton equations are solved by :func:`_newton_qr`, otherwise by :func:`_newton` with the
    Cholesky factor ``r_fac`` of ``H`` (of ``H`` in the variable order ``perm`` unless ``perm`` is
    empty, see :func:`_factor_solve`).

    ``pt`` is ``P'`` (``n x size``) when it was formed (QR phase), or ``n x 0`` when only ``H``
    was (:func:`scaling_and_schur_direct`); then the products with ``P`` come from the sparse
    coefficients ``sp_*``, ``pair_*`` (layout of :func:`scaling_and_schur_rows`). So do the
    products with ``G`` when ``g_mat`` has no rows (:func:`~lmi.ipm.kernels.packed.g_times`).

    Outside the QR phase, a corrector whose dual equation is met only to more than
    ``err_limit`` (``||P' dz~ + r_d||``, :func:`_newton`) is not taken: the Cholesky factor of
    ``H`` has lost the accuracy the step needs, and the caller goes on with the QR phase.

    Returns ``(code, x_new, theta_new, alpha_aff, sigma, alpha)``; ``code`` 0 on success, 1 if
    the step length is not finite or <= 1e-12, 2 if no shortened step kept ``S`` positive
    definite, :data:`STEP_INACCURATE` if the corrector missed ``err_limit`` (nothing written).
    """
    nb = orders.shape[0]
    m = offsets[-1]
    # the blocks' matrices in one work array (_square), the products BLAS calls into it
    work = np.empty(4 * kk.shape[1] * kk.shape[2])
    # scaled primal residual K rp K'
    rpt = np.empty(m)
    for j in range(nb):
        k = orders[j]
        kj, rj, left, prod = _squares(work, k)
        _contiguous_scaling(kk, j, k, kj)
        unpack_block_into(rp, j, offsets, ent_row, ent_col, ent_w, rj)
        np.dot(kj, rj, left)
        np.dot(left, kj.T, prod)
        pack_block(prod, j, offsets, ent_row, ent_col, ent_w, rpt)
    # predictor: u = lambda^{o-1}(-lambda o lambda) = -diag(lambda)
    u = np.zeros(m)
    for j in range(nb):
        k = orders[j]
        for a in range(k):
            u[diagonal_entry(offsets, j, k, a)] = -lam[j, a]
    sp = (sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col)
    if qr_h.shape[0] > 0:
        _dx, dsa, dza = _newton_qr(pt, qr_h, qr_tau, r_fac, rd, rpt, u, ref_scale)
    else:
        _dx, dsa, dza, _err = _newton(pt, r_fac, perm, rd, rpt, u, ref_scale, kk, orders, offsets, ent_row,
                                      ent_col, ent_w, sp)
    alpha_aff = min(1.0, _max_step(lam, dsa, dza, orders, offsets, ent_row, ent_col, ent_w))
    sigma = (1.0 - alpha_aff) ** 3
    # corrector: u = lambda^{o-1}(sigma mu e - lambda o lambda - ds_a o dz_a)
    u_cor = np.empty(m)
    for j in range(nb):
        k = orders[j]
        da, db, prod = _square(work, 0, k), _square(work, 1, k), _square(work, 2, k)
        unpack_block_into(dsa, j, offsets, ent_row, ent_col, ent_w, da)
        unpack_block_into(dza, j, offsets, ent_row, ent_col, ent_w, db)
        np.dot(da, db, prod)
        rc = _square(work, 3, k)
        for a in range(k):  # the upper triangle, which the packing reads
            for b in range(a, k):
                value = -0.5 * (prod[a, b] + prod[b, a])
                if a == b:
                    value += sigma * mu - lam[j, a] * lam[j, a]
                rc[a, b] = value * (2.0 / (lam[j, a] + lam[j, b]))
        pack_block(rc, j, offsets, ent_row, ent_col, ent_w, u_cor)
    if qr_h.shape[0] > 0:
        dx, dst, dzt = _newton_qr(pt, qr_h, qr_tau, r_fac, rd, rpt, u_cor, ref_scale)
    else:
        dx, dst, dzt, err = _newton(pt, r_fac, perm, rd, rpt, u_cor, ref_scale, kk, orders, offsets, ent_row,
                                    ent_col, ent_w, sp)
        if not err <= err_limit:
            return STEP_INACCURATE, x, theta, alpha_aff, sigma, 0.0
    alpha = min(1.0, 0.99 * _max_step(lam, dst, dzt, orders, offsets, ent_row, ent_col, ent_w))
    if not (np.isfinite(alpha) and alpha > 1e-12):
        return 1, x, theta, alpha_aff, sigma, alpha
    scratch = np.empty((z.shape[1], z.shape[2]))
    for _ in range(6):
        x_new = x + alpha * dx
        theta_new = theta * (1.0 - alpha)
        s_vec = h_vec - g_times(g_mat, x_new, orders, offsets, ent_w, *sp) + theta_new * r0
        ok = True
        for j in range(nb):
            k = orders[j]
            unpack_block_into(s_vec, j, offsets, ent_row, ent_col, ent_w, s_out[j])
            if not cholesky_into(s_out[j], k, chol_out[j]):
                ok = False
                break
        if not ok:
            alpha *= 0.8
            continue
        for j in range(nb):
            k = orders[j]
            kj, dj, left, dz = _squares(work, k)
            _contiguous_scaling(kk, j, k, kj)
            unpack_block_into(dzt, j, offsets, ent_row, ent_col, ent_w, dj)
            np.dot(kj.T, dj, left)
            np.dot(left, kj, dz)
            for a in range(k):
                for b in range(k):
                    z_out[j, a, b] = z[j, a, b] + (0.5 * alpha) * (dz[a, b] + dz[b, a])
            if not cholesky_into(z_out[j], k, scratch):
                # rounding left Z + alpha dZ not positive definite: the same point through the
                # scaling, K'(lambda + alpha dz~)K, positive definite by the step length
                unpack_block_into(dzt, j, offsets, ent_row, ent_col, ent_w, dj)
                for a in range(k):
                    for b in range(k):
                        dj[a, b] = alpha * dj[a, b]
                for a in range(k):
                    dj[a, a] += lam[j, a]
                np.dot(kj.T, dj, left)
                np.dot(left, kj, dz)
                for a in range(k):
                    for b in range(k):
                        z_out[j, a, b] = 0.5 * (dz[a, b] + dz[b, a])
        return 0, x_new, theta_new, alpha_aff, sigma, alpha
    return 2, x, theta, alpha_aff, sigma, alpha
