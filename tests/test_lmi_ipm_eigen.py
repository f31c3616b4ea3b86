"""The NT scaling's symmetric eigensolver (:func:`lmi.ipm.kernels.eigen.symmetric_eigen`).

Against numpy's LAPACK ``eigh`` and against the C core's ``dense_sym_eig`` (the algorithm it
ports, called from the built extension through ctypes):

* eigenvalues ascending and within ``8 k eps ||a||`` of LAPACK's (both methods are backward
  stable; measured worst over the draws below 17 ``eps ||a||``, the bound is 224 at order 28);
* eigenvectors orthonormal to ``8 k eps`` and ``a vt' = vt' diag(w)`` to ``8 k eps ||a||``
  (measured worst 29 ``eps`` and 7.7 ``eps ||a||``);
* the C core's eigenvalues and vectors within ``4 eps`` of the numba ones (the same operations
  in the same order: equal bit for bit on this machine's gcc ``-std=c99`` build, which contracts
  no multiply-add; a compiler that does may round differently);
* the matrices the solver meets near an optimum: eigenvalues spanning 1e-10 .. 1e4, repeated
  eigenvalues (identity, ties), a zero matrix, order 1;
* a NaN or an infinity anywhere is reported (-1), not an answer.
"""

from __future__ import annotations

import ctypes
import shutil

import numpy as np
import pytest

from lmi.ccore import runtime
from lmi.ipm.kernels.eigen import symmetric_eigen

EPS = np.finfo(float).eps


def _eigen(a: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    k = a.shape[0]
    w, vt = np.full(k, np.nan), np.full((k, k), np.nan)
    code = symmetric_eigen(a, k, w, vt, np.empty((k, k)), np.empty(k))
    return code, w, vt


def _random_symmetric(rng: np.random.Generator, k: int, spread: float) -> np.ndarray:
    """A symmetric matrix with eigenvalues ``10**u``, ``u`` uniform on ``[-spread, 4]``, and
    random eigenvectors (the scaled points near an optimum span many orders of magnitude)."""
    q, _ = np.linalg.qr(rng.normal(size=(k, k)))
    w = 10.0 ** rng.uniform(-spread, 4.0, size=k)
    a = (q * w) @ q.T
    return 0.5 * (a + a.T)


def _check(a: np.ndarray) -> None:
    k = a.shape[0]
    code, w, vt = _eigen(a)
    assert code == 0
    scale = max(np.abs(np.linalg.eigvalsh(a)).max(), np.finfo(float).tiny)
    tol = 8 * k * EPS * scale
    assert np.all(np.diff(w) >= 0.0)
    assert np.abs(w - np.linalg.eigvalsh(a)).max() <= tol
    assert np.abs(vt @ vt.T - np.eye(k)).max() <= 8 * k * EPS
    assert np.abs(a @ vt.T - vt.T * w).max() <= tol


@pytest.mark.parametrize("k", [1, 2, 3, 7, 12, 16, 28])
@pytest.mark.parametrize("seed", range(4))
def test_eigenpairs_against_lapack(k, seed):
    rng = np.random.default_rng(seed)
    _check(_random_symmetric(rng, k, 0.0))
    _check(_random_symmetric(rng, k, 10.0))
    g = rng.normal(size=(k, k))
    _check(0.5 * (g + g.T))  # indefinite


@pytest.mark.parametrize("k", [2, 5, 12])
def test_repeated_and_zero_eigenvalues(k):
    _check(np.eye(k))
    _check(np.zeros((k, k)))
    _check(np.diag(np.repeat([1.0, 2.0], (k + 1) // 2)[:k]))
    q, _ = np.linalg.qr(np.random.default_rng(k).normal(size=(k, k)))
    a = (q * np.repeat([1e-6, 3.0], (k + 1) // 2)[:k]) @ q.T
    _check(0.5 * (a + a.T))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("where", [(0, 0), (2, 4), (4, 2)])
def test_a_non_finite_entry_is_reported(bad, where):
    a = np.eye(5)
    a[where] = bad
    code, _, _ = _eigen(a)
    assert code == -1


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler: pip builds no C core")
@pytest.mark.parametrize("k", [1, 2, 7, 12, 16])
def test_the_c_core_computes_the_same_eigenpairs(k):
    lib = runtime.core_library()
    assert lib is not None, runtime.core_status()
    fn = lib.dense_sym_eig
    ptr = ctypes.POINTER(ctypes.c_double)
    fn.argtypes = [ptr, ctypes.c_int, ctypes.c_int, ptr, ptr, ctypes.c_int, ptr, ptr]
    fn.restype = ctypes.c_int
    rng = np.random.default_rng(100 + k)
    for spread in (0.0, 10.0):
        a = np.ascontiguousarray(_random_symmetric(rng, k, spread))
        w_c, v_c, e_c = np.empty(k), np.empty((k, k)), np.empty(k)
        code = fn(a.ctypes.data_as(ptr), k, k, w_c.ctypes.data_as(ptr), v_c.ctypes.data_as(ptr), k,
                  e_c.ctypes.data_as(ptr), None)
        assert code == 0
        got, w, vt = _eigen(a)
        assert got == 0
        assert np.abs(w - w_c).max() <= 4 * EPS * np.abs(w).max()
        assert np.abs(vt.T - v_c).max() <= 4 * EPS * k
