"""The factor of the IPM's Schur complement (:func:`lmi.ipm.solver._factor`): ``R`` with
``R'R = P P'``, by Cholesky of ``H = P P'`` or by QR of ``P'``, and a ``LinAlgError`` (which the
solver turns into the status ``numerical_error``) when ``H`` is singular or not finite; and
:func:`lmi.ipm.solver._cholesky`, which factors a well-conditioned ``H`` and hands a singular one
to QR."""

from __future__ import annotations

import numpy as np
import pytest

from lmi.ipm.kernels.step import _householder, _newton_qr
from lmi.ipm.solver import _cholesky, _factor

RNG = np.random.default_rng(7)
P_GOOD = RNG.standard_normal((5, 12))


@pytest.mark.parametrize("use_qr", [False, True])
def test_the_factor_reproduces_the_schur_complement(use_qr: bool) -> None:
    r_fac, qr_used, _householder = _factor(P_GOOD, use_qr)
    assert qr_used == use_qr  # a well-conditioned H keeps Cholesky, and QR stays once chosen
    assert np.allclose(np.tril(r_fac, -1), 0.0)
    h = P_GOOD @ P_GOOD.T
    # measured 1.3e-16 (Cholesky) and 2.6e-16 (QR) relative to max |H|; bound with a margin of ~40
    assert np.max(np.abs(r_fac.T @ r_fac - h)) <= 1e-14 * np.max(np.abs(h))


@pytest.mark.parametrize("use_qr", [False, True])
def test_a_variable_without_coefficients_makes_a_singular_complement(use_qr: bool) -> None:
    p = P_GOOD.copy()
    p[2] = 0.0  # a zero row of P: an exactly zero pivot, every entry finite
    with pytest.raises(np.linalg.LinAlgError, match="singular Schur complement"):
        _factor(p, use_qr)


@pytest.mark.parametrize("use_qr", [False, True])
def test_a_non_finite_complement_is_refused(use_qr: bool) -> None:
    p = P_GOOD.copy()
    p[1, 3] = np.nan  # non-finite entries, no zero pivot
    with pytest.raises(np.linalg.LinAlgError, match="singular Schur complement"):
        _factor(p, use_qr)


def test_cholesky_factors_a_well_conditioned_complement() -> None:
    h = P_GOOD @ P_GOOD.T
    r_fac, to_qr = _cholesky(h)
    assert to_qr is False and r_fac is not None
    # measured 1.3e-16 relative to max |H| (as above); bound with a margin of ~40
    assert np.max(np.abs(r_fac.T @ r_fac - h)) <= 1e-14 * np.max(np.abs(h))


@pytest.mark.parametrize("row", [0, 2, 4])
def test_cholesky_hands_a_singular_complement_to_qr(row: int) -> None:
    p = P_GOOD.copy()
    p[row] = 0.0
    assert _cholesky(p @ p.T) == (None, True)


def _apply_q(h: np.ndarray, tau: np.ndarray, y: np.ndarray, transpose: bool) -> np.ndarray:
    out = y.copy()
    _householder(h, tau, out, transpose)
    return out


def test_the_householder_factors_reproduce_p_and_are_orthogonal() -> None:
    r_fac, qr_used, householder = _factor(P_GOOD, True)
    assert qr_used and householder is not None
    h, tau = householder
    m, n = P_GOOD.shape[1], P_GOOD.shape[0]
    # Q [R; 0] = P' column by column, and Q'Q = I (measured 4.4e-16 and 3.3e-16)
    cols = [_apply_q(h, tau, np.concatenate([r_fac[:, i], np.zeros(m - n)]), False) for i in range(n)]
    assert np.max(np.abs(np.array(cols).T - P_GOOD.T)) <= 1e-14 * np.max(np.abs(P_GOOD))
    eye = np.array([_apply_q(h, tau, _apply_q(h, tau, e, False), True) for e in np.eye(m)])
    assert np.max(np.abs(eye - np.eye(m))) <= 1e-14
    # Cholesky leaves no Householder factors
    assert _factor(P_GOOD, False)[2] is None


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
    r_fac, _, (h, tau) = _factor(pt, True)
    dx, ds, dz = _newton_qr(pt, h, tau, r_fac, rd, np.zeros(m), v, 1.0)
    assert np.linalg.norm(pt @ dz + rd) <= 1e-3 * np.linalg.norm(rd)
    assert np.array_equal(ds, v - dz)
    # P dx = dz~ - v to the accuracy of dx, about eps cond (measured 1.2e-11 and 1.4e-5 relative
    # to |v|)
    assert np.linalg.norm(p @ dx - (dz - v)) <= np.finfo(float).eps * cond * np.linalg.norm(v)
