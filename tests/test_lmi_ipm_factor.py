"""The factors of the IPM's Newton systems, computed by BLAS and LAPACK from compiled code
(:mod:`lmi.ipm.kernels.lapack`): ``H = P'P`` (``dsyrk``), its upper Cholesky factor
(``dpotrf``) with the pivot test that switches to QR (:func:`lmi.ipm.kernels.iteration._factor_ok`),
and the QR factorisation of ``P`` (``dgeqrf``) with its Householder reflectors. Each is the
same, bit for bit, as the numpy / scipy call the solver made from Python before (the solver's
iterates on paper P were measured bitwise equal), and each reproduces what it factors."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg.lapack import dpotrf

from lmi.ipm.kernels.iteration import _factor_ok
from lmi.ipm.kernels.lapack import cholesky_upper, householder_qr, schur_complement
from lmi.ipm.kernels.step import _householder, _newton_qr
from lmi.ipm.solver import QR_SWITCH

RNG = np.random.default_rng(7)
P_GOOD = RNG.standard_normal((5, 12))  # P' (n = 5 variables, packed size 12)


def _schur(pt: np.ndarray) -> np.ndarray:
    h = np.full((pt.shape[0], pt.shape[0]), np.nan)
    schur_complement(np.ascontiguousarray(pt), h)
    return h


def _cholesky(h: np.ndarray) -> tuple[int, np.ndarray]:
    r_fac = np.full_like(h, np.nan)
    info = cholesky_upper(h, np.empty_like(h), r_fac)
    return int(info), r_fac


def _qr(pt: np.ndarray) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    n, m = pt.shape
    qr_h, qr_tau, r_fac = np.full((n, m), np.nan), np.full(n, np.nan), np.full((n, n), np.nan)
    info = householder_qr(np.ascontiguousarray(pt), qr_h, qr_tau, r_fac)
    return int(info), qr_h, qr_tau, r_fac


@pytest.mark.parametrize("shape", [(5, 12), (61, 349), (3, 3)])
def test_the_schur_complement_is_numpys_product(shape: tuple[int, int]) -> None:
    pt = np.random.default_rng(shape[0]).standard_normal(shape)
    h = _schur(pt)
    assert np.array_equal(h, h.T)
    assert np.array_equal(h, pt @ pt.T)  # numpy forms P'P by the same dsyrk


@pytest.mark.parametrize("shape", [(5, 12), (61, 349)])
def test_the_cholesky_factor_is_lapacks_and_reproduces_h(shape: tuple[int, int]) -> None:
    pt = np.random.default_rng(shape[0]).standard_normal(shape)
    h = pt @ pt.T
    h_before = h.copy()
    info, r_fac = _cholesky(h)
    assert info == 0 and np.array_equal(h, h_before)  # h itself is left as it was
    assert np.array_equal(r_fac, dpotrf(h, lower=0, clean=1)[0])
    assert np.all(np.tril(r_fac, -1) == 0.0)
    # measured 1.3e-16 relative to max |H| (5 x 12); bound with a margin of ~40
    assert np.max(np.abs(r_fac.T @ r_fac - h)) <= 1e-14 * np.max(np.abs(h))
    assert _factor_ok(h, r_fac, QR_SWITCH)


@pytest.mark.parametrize("row", [0, 2, 4])
def test_a_singular_complement_goes_to_qr(row: int) -> None:
    """A zero row of ``P'`` (a variable without coefficients at this iterate): Cholesky fails or
    leaves a zero pivot, and the pivot test says "QR"."""
    p = P_GOOD.copy()
    p[row] = 0.0
    h = p @ p.T
    info, r_fac = _cholesky(h)
    assert info != 0 or not _factor_ok(h, r_fac, QR_SWITCH)


def test_the_pivot_test_measures_relative_pivots() -> None:
    """Two nearly parallel rows of ``P'``: the second pivot relative to ``sqrt(H_22)`` is the
    sine of their angle, so the test passes a decade above the switch (1e-6) and fails a decade
    below it. Both sines keep the pivot far above rounding (its square, ``sine^2 H_22``, is
    1e-14 of ``H_22`` or more, against errors of a few ``eps`` in forming ``H``), so Cholesky
    succeeds on any CPU. Further below (1e-9: the squared pivot under ``eps``) rounding decides
    whether Cholesky stops (``info > 0``, as with OpenBLAS's Katmai kernels) or leaves a pivot
    the test refuses (SkylakeX): either way the solve goes to QR."""
    p = P_GOOD[:2].copy()
    direction = P_GOOD[2] / np.linalg.norm(P_GOOD[2])
    for sine, ok in ((10 * QR_SWITCH, True), (0.1 * QR_SWITCH, False)):
        p[1] = p[0] + sine * np.linalg.norm(p[0]) * direction
        h = p @ p.T
        info, r_fac = _cholesky(h)
        assert info == 0 and bool(_factor_ok(h, r_fac, QR_SWITCH)) is ok
    p[1] = p[0] + 1e-9 * np.linalg.norm(p[0]) * direction
    h = p @ p.T
    info, r_fac = _cholesky(h)
    assert info != 0 or not _factor_ok(h, r_fac, QR_SWITCH)
    h = P_GOOD @ P_GOOD.T
    _, r_fac = _cholesky(h)
    r_fac[1, 3] = np.nan  # a non-finite factor is never accepted
    assert not _factor_ok(h, r_fac, QR_SWITCH)


def test_the_qr_factors_are_numpys() -> None:
    info, qr_h, qr_tau, r_fac = _qr(P_GOOD)
    h_raw, tau = np.linalg.qr(P_GOOD.T, mode="raw")
    assert info == 0
    assert np.array_equal(qr_h, h_raw) and np.array_equal(qr_tau, tau)
    assert np.array_equal(r_fac, np.triu(h_raw[:, :5].T))
    # R'R = P'P: measured 2.6e-16 relative to max |H|; bound with a margin of ~40
    h = P_GOOD @ P_GOOD.T
    assert np.max(np.abs(r_fac.T @ r_fac - h)) <= 1e-14 * np.max(np.abs(h))


def _apply_q(h: np.ndarray, tau: np.ndarray, y: np.ndarray, transpose: bool) -> np.ndarray:
    out = y.copy()
    _householder(h, tau, out, transpose)
    return out


def test_the_householder_factors_reproduce_p_and_are_orthogonal() -> None:
    _, h, tau, r_fac = _qr(P_GOOD)
    m, n = P_GOOD.shape[1], P_GOOD.shape[0]
    # Q [R; 0] = P' column by column, and Q'Q = I (measured 4.4e-16 and 3.3e-16)
    cols = [_apply_q(h, tau, np.concatenate([r_fac[:, i], np.zeros(m - n)]), False) for i in range(n)]
    assert np.max(np.abs(np.array(cols).T - P_GOOD.T)) <= 1e-14 * np.max(np.abs(P_GOOD))
    eye = np.array([_apply_q(h, tau, _apply_q(h, tau, e, False), True) for e in np.eye(m)])
    assert np.max(np.abs(eye - np.eye(m))) <= 1e-14


@pytest.mark.parametrize("cond", [1e6, 1e12])
def test_the_qr_phase_newton_solve_meets_the_dual_equation_on_ill_conditioned_p(cond: float) -> None:
    """``P' dz~ = -r_d`` and ``dz~ = P dx + v`` by the orthogonal factor: on ``P`` (60 x 12) with
    singular values spanning ``cond`` measured ``|P'dz~ + r_d| / |r_d|`` of 2.8e-8 (1e6) and 1.9e-5
    (1e12); through the normal equations with the same ``R`` (:func:`_newton`) 3.8e-8 and 1.1e3:
    at 1e12 the residual is a thousand times ``r_d`` itself."""
    rng = np.random.default_rng(3)
    m, n = 60, 12
    u_mat, _ = np.linalg.qr(rng.normal(size=(m, n)))
    v_mat, _ = np.linalg.qr(rng.normal(size=(n, n)))
    p = u_mat @ np.diag(np.logspace(0.5 * np.log10(cond), -0.5 * np.log10(cond), n)) @ v_mat.T
    pt = np.ascontiguousarray(p.T)
    rd, v = 1e-6 * rng.normal(size=n), rng.normal(size=m)
    _, h, tau, r_fac = _qr(pt)
    dx, ds, dz = _newton_qr(pt, h, tau, r_fac, rd, np.zeros(m), v, 1.0)
    assert np.linalg.norm(pt @ dz + rd) <= 1e-3 * np.linalg.norm(rd)
    assert np.array_equal(ds, v - dz)
    # P dx = dz~ - v to the accuracy of dx, about eps cond (measured 1.2e-11 and 1.4e-5 relative
    # to |v|)
    assert np.linalg.norm(p @ dx - (dz - v)) <= np.finfo(float).eps * cond * np.linalg.norm(v)
