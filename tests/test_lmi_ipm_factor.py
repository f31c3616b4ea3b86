"""The factor of the IPM's Schur complement (:func:`lmi.ipm.solver._factor`): ``R`` with
``R'R = P P'``, by Cholesky of ``H = P P'`` or by QR of ``P'``, and a ``LinAlgError`` (which the
solver turns into the status ``numerical_error``) when ``H`` is singular or not finite; and
:func:`lmi.ipm.solver._cholesky`, which factors a well-conditioned ``H`` and hands a singular one
to QR."""

from __future__ import annotations

import numpy as np
import pytest

from lmi.ipm.solver import _cholesky, _factor

RNG = np.random.default_rng(7)
P_GOOD = RNG.standard_normal((5, 12))


@pytest.mark.parametrize("use_qr", [False, True])
def test_the_factor_reproduces_the_schur_complement(use_qr: bool) -> None:
    r_fac, qr_used = _factor(P_GOOD, use_qr)
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
