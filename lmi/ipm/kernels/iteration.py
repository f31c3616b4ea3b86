"""One interior-point iteration in one compiled call (:mod:`lmi.ipm.kernels`).

The NT scaling and the Schur complement (:mod:`lmi.ipm.kernels.schur`), the factorisation
(Cholesky of ``H``, or QR of ``P`` once a relative pivot of that Cholesky factor falls below the
switch, see :data:`lmi.ipm.solver.QR_SWITCH`) and the predictor-corrector step
(:func:`lmi.ipm.kernels.step.newton_step`), without a return to Python in between; BLAS and
LAPACK are called from compiled code (:mod:`lmi.ipm.kernels.lapack`). The arithmetic is that of
the separate calls the solver made before, in the same order (paper P's closed-loop solves
are bitwise the same); what goes is the Python between them: scipy's and numpy's wrappers, the
pivot test in numpy, the copies of the QR factors and the argument checks of several calls.

Three forms of the Schur complement, one kernel each: :func:`rows_iteration` (``P`` formed,
one ``dsyrk``), :func:`blockwise_iteration` (``P_j'P_j`` per block on its own variables) and
:func:`grouped_iteration` (from the factored coefficients).

Each returns ``(code, x, theta, alpha_aff, sigma, alpha, use_qr)``: ``code`` is
:data:`STEP_OK`, a code of :func:`~lmi.ipm.kernels.step.newton_step` (1: step length not
finite or <= 1e-12, 2: no shortened step kept ``S`` positive definite),
:data:`STEP_LOST_DEFINITENESS` or :data:`STEP_SINGULAR`; ``use_qr`` whether the QR phase has
begun (it lasts for the rest of the solve).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from lmi.ipm.kernels.lapack import arrow_cholesky, cholesky_upper, householder_qr, schur_complement
from lmi.ipm.kernels.packed import JIT
from lmi.ipm.kernels.schur import (
    scaling_and_schur_blockwise,
    scaling_and_schur_grouped,
    scaling_and_schur_rows,
)
from lmi.ipm.kernels.step import STEP_INACCURATE, newton_step

__all__ = [
    "STEP_LOST_DEFINITENESS", "STEP_OK", "STEP_SINGULAR", "blockwise_iteration", "grouped_iteration",
    "rows_iteration",
]

#: The step was taken.
STEP_OK = 0
#: A block of the NT scaling lost positive definiteness (``numerical_error``).
STEP_LOST_DEFINITENESS = 3
#: The QR factor of ``P`` is singular or not finite (``numerical_error``).
STEP_SINGULAR = 4


@njit(**JIT)
def _factor_ok(h, r_fac, qr_switch):
    """Whether the upper factor ``r_fac`` of ``h`` keeps every pivot relative to ``sqrt(h_ii)``
    above ``qr_switch`` (a scale-invariant measure of the accuracy lost), every entry finite."""
    n = h.shape[0]
    low = np.inf
    for i in range(n):
        rel = abs(r_fac[i, i]) / np.sqrt(max(h[i, i], 1e-300))
        if rel < low or rel != rel:
            low = rel
        for j in range(i, n):
            if not np.isfinite(r_fac[i, j]):
                return False
    return low >= qr_switch


@njit(**JIT)
def _qr_step(s_chol, z, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val, pair_off,
             pair_row, pair_col, kk, lam, pt, formed, qr_h, qr_tau, r_fac, x, theta, r0, rd, rp, g_mat, h_vec,
             mu, ref_scale, s_out, z_out, chol_out):
    """The step of the QR phase: ``P`` formed (unless ``formed``), factored by QR, its orthogonal
    factor in the Newton solves (:func:`~lmi.ipm.kernels.step._newton_qr`)."""
    if not formed and not scaling_and_schur_rows(s_chol, z, orders, offsets, ent_row, ent_col, ent_w,
                                                 sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row,
                                                 pair_col, kk, lam, pt):
        return STEP_LOST_DEFINITENESS, x, theta, 0.0, 0.0, 0.0
    no_perm = np.zeros(0, dtype=np.int64)
    if householder_qr(pt, qr_h, qr_tau, r_fac) != 0:
        return STEP_SINGULAR, x, theta, 0.0, 0.0, 0.0
    n = r_fac.shape[0]
    for i in range(n):
        if r_fac[i, i] == 0.0:
            return STEP_SINGULAR, x, theta, 0.0, 0.0, 0.0
        for j in range(i, n):
            if not np.isfinite(r_fac[i, j]):
                return STEP_SINGULAR, x, theta, 0.0, 0.0, 0.0
    return newton_step(pt, r_fac, no_perm, qr_h, qr_tau, kk, lam, x, z, theta, r0, rd, rp, g_mat, h_vec, mu,
                       ref_scale, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair,
                       sp_val, pair_off, pair_row, pair_col, s_out, z_out, chol_out, np.inf)


@njit(**JIT)
def _cholesky_or_qr_step(ok, step_pt, r_fac, perm, pt, formed, s_chol, z, orders, offsets, ent_row, ent_col,
                         ent_w, sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col, kk, lam, qr_h,
                         qr_tau, no_qr_h, no_qr_tau, x, theta, r0, rd, rp, g_mat, h_vec, mu, ref_scale, s_out,
                         z_out, chol_out, err_limit):
    """The step every iteration kernel ends with: from the Cholesky factor ``r_fac`` of ``H`` (in
    the variable order ``perm``, empty for the given one) when ``ok`` (it was formed and its
    pivots passed), the products with ``P`` from ``step_pt`` (``P'``, or ``(n, 0)``: from the
    sparse coefficients); else, or when that step missed ``err_limit``, the QR phase's step
    (:func:`_qr_step`; ``P`` in ``pt``, formed there unless ``formed``). Returns ``(code, x, theta,
    alpha_aff, sigma, alpha, use_qr)``."""
    if ok:
        out = newton_step(step_pt, r_fac, perm, no_qr_h, no_qr_tau, kk, lam, x, z, theta, r0, rd, rp, g_mat,
                          h_vec, mu, ref_scale, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var,
                          sp_pair, sp_val, pair_off, pair_row, pair_col, s_out, z_out, chol_out, err_limit)
        if out[0] != STEP_INACCURATE:
            return out[0], out[1], out[2], out[3], out[4], out[5], False
    out = _qr_step(s_chol, z, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val,
                   pair_off, pair_row, pair_col, kk, lam, pt, formed, qr_h, qr_tau, r_fac, x, theta, r0, rd,
                   rp, g_mat, h_vec, mu, ref_scale, s_out, z_out, chol_out)
    return out[0], out[1], out[2], out[3], out[4], out[5], True


@njit(**JIT)
def rows_iteration(s_chol, z, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val,
                   pair_off, pair_row, pair_col, kk, lam, pt, h, work, r_fac, qr_h, qr_tau, no_qr_h,
                   no_qr_tau, use_qr, x, theta, r0, rd, rp, g_mat, h_vec, mu, ref_scale, qr_switch, s_out,
                   z_out, chol_out, err_limit):
    """One iteration with ``P`` formed (:func:`~lmi.ipm.kernels.schur.scaling_and_schur_rows`):
    ``H = P'P`` and its Cholesky factor, or (``use_qr``, or once a pivot of that factor falls
    below ``qr_switch``) the QR factorisation of ``P``. Returns ``(code, x, theta, alpha_aff,
    sigma, alpha, use_qr)``, see the module notes. ``h``, ``work``, ``r_fac`` (``(n, n)``),
    ``qr_h`` (``(n, size)``) and ``qr_tau`` (``n``) are workspaces; ``no_qr_h``, ``no_qr_tau``
    empty."""
    if not scaling_and_schur_rows(s_chol, z, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var,
                                  sp_pair, sp_val, pair_off, pair_row, pair_col, kk, lam, pt):
        return STEP_LOST_DEFINITENESS, x, theta, 0.0, 0.0, 0.0, use_qr
    ok = False
    if not use_qr:
        schur_complement(pt, h)
        ok = cholesky_upper(h, work, r_fac) == 0 and _factor_ok(h, r_fac, qr_switch)
    return _cholesky_or_qr_step(ok, pt, r_fac, np.zeros(0, dtype=np.int64), pt, True, s_chol, z, orders,
                                offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val, pair_off,
                                pair_row, pair_col, kk, lam, qr_h, qr_tau, no_qr_h, no_qr_tau, x, theta, r0,
                                rd, rp, g_mat, h_vec, mu, ref_scale, s_out, z_out, chol_out, err_limit)


@njit(**JIT)
def grouped_iteration(s_chol, z, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair,
                      sp_val, pair_off, pair_row, pair_col, dict_mat, dict_dims, fe_off, fe_var, fe_p,
                      fe_q, fe_val, grp_off, grp_blk, kk, lam, pt, no_pt, h, work, r_fac, qr_h, qr_tau,
                      no_qr_h, no_qr_tau, use_qr, x, theta, r0, rd, rp, g_mat, h_vec, mu, ref_scale,
                      qr_switch, s_out, z_out, chol_out, err_limit):
    """One iteration with ``H`` formed from the factored coefficients
    (:func:`~lmi.ipm.kernels.schur.scaling_and_schur_grouped`), ``P`` not formed (``no_pt``
    ``(n, 0)``), until the QR phase, which forms ``P`` in ``pt``; see :func:`rows_iteration`."""
    ok = False
    if not use_qr:
        if not scaling_and_schur_grouped(s_chol, z, orders, dict_mat, dict_dims, fe_off, fe_var, fe_p,
                                         fe_q, fe_val, grp_off, grp_blk, kk, lam, h):
            return STEP_LOST_DEFINITENESS, x, theta, 0.0, 0.0, 0.0, use_qr
        ok = cholesky_upper(h, work, r_fac) == 0 and _factor_ok(h, r_fac, qr_switch)
    return _cholesky_or_qr_step(ok, no_pt, r_fac, np.zeros(0, dtype=np.int64), pt, False, s_chol, z, orders,
                                offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val, pair_off,
                                pair_row, pair_col, kk, lam, qr_h, qr_tau, no_qr_h, no_qr_tau, x, theta, r0,
                                rd, rp, g_mat, h_vec, mu, ref_scale, s_out, z_out, chol_out, err_limit)


@njit(**JIT)
def blockwise_iteration(s_chol, z, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair,
                        sp_val, pair_off, pair_row, pair_col, bv_off, bv_pos, sp_loc, run_off, runs, perm,
                        arrow_off,
                        gram_work, hj_work, kk, lam, pt, no_pt, h, work, r_fac, qr_h, qr_tau, no_qr_h,
                        no_qr_tau, use_qr, x, theta, r0, rd, rp, g_mat, h_vec, mu, ref_scale, qr_switch,
                        s_out, z_out, chol_out, err_limit):
    """One iteration with ``H`` formed block by block on each block's own variables
    (:func:`~lmi.ipm.kernels.schur.scaling_and_schur_blockwise`; ``gram_work`` and ``hj_work`` its
    workspaces), ``P`` not formed (``no_pt`` ``(n, 0)``: the Newton step's products come from the
    sparse coefficients) until the QR phase, which forms ``P`` in ``pt``; see
    :func:`rows_iteration`. ``H`` is formed in the variable order ``perm`` (block ``j``'s variables
    at ``bv_pos[bv_off[j]:bv_off[j + 1]]`` of that order, in the contiguous runs ``run_off``,
    ``runs``) and factored there as a block arrow (the
    groups ``arrow_off``, :func:`~lmi.ipm.kernels.lapack.arrow_cholesky`); the Newton solves map
    their vectors through ``perm``. ``work`` (``n x n``) is the factor's workspace."""
    ok = False
    if not use_qr:
        if not scaling_and_schur_blockwise(s_chol, z, orders, sp_off, sp_pair, sp_val, pair_off, pair_row,
                                           pair_col, bv_off, bv_pos, sp_loc, run_off, runs, kk, lam,
                                           gram_work, hj_work, h):
            return STEP_LOST_DEFINITENESS, x, theta, 0.0, 0.0, 0.0, use_qr
        ok = arrow_cholesky(h, arrow_off, r_fac, work) == 0 and _factor_ok(h, r_fac, qr_switch)
    return _cholesky_or_qr_step(ok, no_pt, r_fac, perm, pt, False, s_chol, z, orders, offsets, ent_row,
                                ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col,
                                kk, lam, qr_h, qr_tau, no_qr_h, no_qr_tau, x, theta, r0, rd, rp, g_mat, h_vec,
                                mu, ref_scale, s_out, z_out, chol_out, err_limit)
