"""BLAS and LAPACK called from compiled code (:mod:`lmi.ipm.kernels`): the Schur complement and
its Cholesky factor without a return to Python.

numba's own linear algebra allocates its results and has no symmetric rank-k update, and a
call through scipy from Python costs several microseconds of wrapping per call. Here the
routines of scipy's Cython BLAS/LAPACK (``scipy.linalg.cython_blas``, ``cython_lapack``, the
library scipy itself calls) are registered with LLVM under fixed names
(:func:`llvmlite.binding.add_symbol`, at import) and declared to numba as external functions,
so a kernel calls them like any C function; the compiled kernels refer to the names, not to
addresses, and therefore stay cacheable across processes (the registration is repeated by
every import). Arrays are passed as pointers to their data: C-ordered arrays are their
transposes for the Fortran routines.

The results are those of the calls the solver made from Python before (measured bitwise on
paper P's iterates): :func:`schur_complement` equals numpy's ``pt @ pt.T`` (numpy forms it by
the same ``dsyrk`` and mirrors the triangle) and :func:`cholesky_upper` equals
``scipy.linalg.lapack.dpotrf(h, lower=0, clean=1)`` and :func:`householder_qr` equals numpy's
``qr(pt.T, mode="raw")`` (the same ``dgeqrf`` with the workspace it asks for).
"""

from __future__ import annotations

import llvmlite.binding as llvm
import numpy as np
from numba import njit, types
from numba.extending import get_cython_function_address

from lmi.ipm.kernels.packed import JIT
from lmi.ipm.kernels.schur import TRANSPOSE_TILE

__all__ = ["arrow_cholesky", "cholesky_upper", "householder_qr", "schur_complement", "triangular_solve_blas"]


def _register(name: str, module: str, routine: str) -> None:
    """Make ``module.routine`` callable from compiled code as the external symbol ``name``."""
    llvm.add_symbol(name, get_cython_function_address(module, routine))


_register("lmi_ipm_dsyrk", "scipy.linalg.cython_blas", "dsyrk")
_register("lmi_ipm_dpotrf", "scipy.linalg.cython_lapack", "dpotrf")
_register("lmi_ipm_dgeqrf", "scipy.linalg.cython_lapack", "dgeqrf")
_register("lmi_ipm_dtrsm", "scipy.linalg.cython_blas", "dtrsm")
_register("lmi_ipm_dtrsv", "scipy.linalg.cython_blas", "dtrsv")
_PTR = types.voidptr
# dsyrk(uplo, trans, n, k, alpha, a, lda, beta, c, ldc); dpotrf(uplo, n, a, lda, info)
_dsyrk = types.ExternalFunction("lmi_ipm_dsyrk", types.void(*([_PTR] * 10)))
_dpotrf = types.ExternalFunction("lmi_ipm_dpotrf", types.void(*([_PTR] * 5)))
# dgeqrf(m, n, a, lda, tau, work, lwork, info)
_dgeqrf = types.ExternalFunction("lmi_ipm_dgeqrf", types.void(*([_PTR] * 8)))
# dtrsm(side, uplo, transa, diag, m, n, alpha, a, lda, b, ldb)
_dtrsm = types.ExternalFunction("lmi_ipm_dtrsm", types.void(*([_PTR] * 11)))
# dtrsv(uplo, trans, diag, n, a, lda, x, incx)
_dtrsv = types.ExternalFunction("lmi_ipm_dtrsv", types.void(*([_PTR] * 8)))
_LOWER, _UPPER, _TRANS = ord("L"), ord("U"), ord("T")
_NO, _RIGHT = ord("N"), ord("R")


@njit(**JIT)
def schur_complement(pt, h_out):
    """``h_out = pt @ pt.T`` (``pt`` C-ordered ``(n, m)``, ``h_out`` ``(n, n)``), symmetric.

    One ``dsyrk`` on the Fortran view (``pt`` is the ``(m, n)`` matrix ``P``, ``H = P'P``, its
    lower triangle the C upper one), then the upper triangle mirrored, as numpy does.
    """
    n, m = pt.shape
    chars = np.array([_LOWER, _TRANS], dtype=np.uint8)
    ints = np.array([n, m], dtype=np.int32)
    scalars = np.array([1.0, 0.0])
    _dsyrk(chars[0:].ctypes, chars[1:].ctypes, ints[0:].ctypes, ints[1:].ctypes, scalars[0:].ctypes,
           pt.ctypes, ints[1:].ctypes, scalars[1:].ctypes, h_out.ctypes, ints[0:].ctypes)
    for i in range(n):
        for j in range(i):
            h_out[i, j] = h_out[j, i]


@njit(**JIT)
def cholesky_upper(h, work, r_out):
    """Upper Cholesky factor ``R`` of the symmetric ``h`` (``R'R = h``) into ``r_out``, zeros
    below the diagonal; ``h`` is left as it is, ``work`` (``n x n``) is overwritten. Returns
    LAPACK's ``info`` (0 on success, else the order of the first non-positive minor).

    ``dpotrf`` with ``uplo = 'U'`` on the Fortran view of ``work`` (a copy of ``h``) leaves
    ``R'`` in the C lower triangle, which is transposed into ``r_out``.
    """
    n = h.shape[0]
    for i in range(n):
        for j in range(n):
            work[i, j] = h[i, j]
    chars = np.array([_UPPER], dtype=np.uint8)
    ints = np.array([n, 0], dtype=np.int32)
    _dpotrf(chars.ctypes, ints[0:].ctypes, work.ctypes, ints[0:].ctypes, ints[1:].ctypes)
    for i in range(n):
        for j in range(i):
            r_out[i, j] = 0.0
        for j in range(i, n):
            r_out[i, j] = work[j, i]
    return ints[1]


@njit(**JIT)
def householder_qr(pt, qr_h, qr_tau, r_out):
    """QR factorisation of ``P`` (``pt`` C-ordered ``(n, m)``, ``m >= n``, is ``P'``) by
    ``dgeqrf``: the reflectors into ``qr_h`` (``(n, m)``, as numpy's ``qr(pt.T, mode="raw")``
    returns them) and ``qr_tau`` (``n``), the upper factor ``R`` (``P = Q [R; 0]``) into ``r_out``
    (``(n, n)``, zeros below the diagonal). Returns LAPACK's ``info`` (0 on success).

    The Fortran view of ``qr_h`` (a copy of ``pt``) is ``P`` itself; ``R[t, i]`` is then
    ``qr_h[i, t]`` for ``t <= i``. The workspace is the optimal one ``dgeqrf`` reports.
    """
    n, m = pt.shape
    for i in range(n):
        for t in range(m):
            qr_h[i, t] = pt[i, t]
    ints = np.array([m, n, -1, 0], dtype=np.int32)
    query = np.zeros(1)
    _dgeqrf(ints[0:].ctypes, ints[1:].ctypes, qr_h.ctypes, ints[0:].ctypes, qr_tau.ctypes, query.ctypes,
            ints[2:].ctypes, ints[3:].ctypes)
    lwork = max(1, int(query[0]))
    work = np.empty(lwork)
    ints[2] = lwork
    _dgeqrf(ints[0:].ctypes, ints[1:].ctypes, qr_h.ctypes, ints[0:].ctypes, qr_tau.ctypes, work.ctypes,
            ints[2:].ctypes, ints[3:].ctypes)
    for t in range(n):
        for i in range(t):
            r_out[t, i] = 0.0
        for i in range(t, n):
            r_out[t, i] = qr_h[i, t]
    return ints[3]


@njit(**JIT)
def triangular_solve_blas(r_fac, b):
    """``x`` with ``R'R x = b`` for upper triangular ``R`` (``r_fac``, C-ordered), by two
    ``dtrsv`` on its Fortran view ``R'`` (lower): ``R' y = b``, then ``R x = y``."""
    n = b.shape[0]
    x = b.copy()
    chars = np.array([_LOWER, _NO, _TRANS], dtype=np.uint8)
    ints = np.array([n, 1], dtype=np.int32)
    _dtrsv(chars[0:].ctypes, chars[1:].ctypes, chars[1:].ctypes, ints[0:].ctypes, r_fac.ctypes,
           ints[0:].ctypes, x.ctypes, ints[1:].ctypes)
    _dtrsv(chars[0:].ctypes, chars[2:].ctypes, chars[1:].ctypes, ints[0:].ctypes, r_fac.ctypes,
           ints[0:].ctypes, x.ctypes, ints[1:].ctypes)
    return x


@njit(**JIT)
def arrow_cholesky(hp, grp_off, r_out, work):
    """Upper Cholesky factor ``R`` (``R'R = H_p``) of a block-arrow ``H_p`` (``hp``, left as it is;
    only its lower triangle is read, :func:`~lmi.ipm.kernels.schur.scaling_and_schur_blockwise`
    forms no more):
    the groups ``grp_off[g]:grp_off[g + 1]`` are coupled to no other group, only to the border
    (the variables from ``grp_off[-1]`` on). Each group's block ``D_g = R_g'R_g`` is factored on
    its own, its border rows ``X_g = R_g'^-1 E_g`` (``E_g`` the group's rows of the border
    columns, one ``dtrsm``) and the border block updated, ``F - X_g'X_g`` (one ``dsyrk``); then
    that is factored. ``R`` is the factor of a Cholesky of ``H_p`` (zero between groups);
    ``sum_g n_g^3/3 + n_g^2 n_b + n_g n_b^2`` operations instead of ``n^3 / 3``. Returns 0, or
    LAPACK's ``info`` of the first factorisation that failed (offset by the group's first row).

    The border block ``F`` lives in ``work`` (``n x n``, overwritten) and is factored there in
    place; its factor is transposed into ``R`` by tiles. ``dpotrf`` (``uplo = 'U'`` on the
    Fortran view) reads and writes only ``F``'s C lower triangle, the one formed and updated,
    so the upper one is neither mirrored nor copied. Measured on the flexible satellite's
    vertex-pair form (1184 variables, no group: all border): 31.6 ms per factorisation, of which
    ``dpotrf`` 17, the rest two fresh ``n x n`` arrays (page faults), a mirror and a transpose
    that went down columns. The tiles are :data:`~lmi.ipm.kernels.schur.TRANSPOSE_TILE`'s.
    """
    n = hp.shape[0]
    for a in range(n):
        for b in range(n):
            r_out[a, b] = 0.0
    nbor = grp_off[grp_off.shape[0] - 1]
    nb = n - nbor
    fmat = work.reshape(work.size)[: nb * nb].reshape((nb, nb))  # a view: no allocation
    for a in range(nb):
        src = hp[nbor + a]
        row = fmat[a]
        for b in range(a + 1):
            row[b] = src[nbor + b]
    chars = np.array([_RIGHT, _LOWER, _TRANS, _NO, _UPPER], dtype=np.uint8)
    scalars = np.array([1.0, -1.0])
    for g in range(grp_off.shape[0] - 1):
        lo, hi = grp_off[g], grp_off[g + 1]
        ng = hi - lo
        if ng == 0:
            continue
        dmat = np.ascontiguousarray(hp[lo:hi, lo:hi])
        rg = np.empty((ng, ng))
        info = cholesky_upper(dmat, np.empty((ng, ng)), rg)
        if info != 0:
            return lo + info
        r_out[lo:hi, lo:hi] = rg
        if nb == 0:
            continue
        # X_g (ng x nb, C-ordered) = R_g'^-1 E_g: its Fortran view X_g' = E_g' R_g^-1, with
        # R_g's Fortran view R_g' lower: side R, uplo L, transa T. E_g from the lower triangle
        xg = np.empty((ng, nb))
        for b in range(nb):
            src = hp[nbor + b]
            for a in range(ng):
                xg[a, b] = src[lo + a]
        ints = np.array([nb, ng], dtype=np.int32)
        _dtrsm(chars[0:].ctypes, chars[1:].ctypes, chars[2:].ctypes, chars[3:].ctypes, ints[0:].ctypes,
               ints[1:].ctypes, scalars[0:].ctypes, rg.ctypes, ints[1:].ctypes, xg.ctypes, ints[0:].ctypes)
        r_out[lo:hi, nbor:] = xg
        # F -= X_g'X_g: on the Fortran views, C := C - A A' with A = X_g' (nb x ng), uplo U
        # (the C lower triangle of F)
        _dsyrk(chars[4:].ctypes, chars[3:].ctypes, ints[0:].ctypes, ints[1:].ctypes, scalars[1:].ctypes,
               xg.ctypes, ints[0:].ctypes, scalars[0:].ctypes, fmat.ctypes, ints[0:].ctypes)
    if nb == 0:
        return 0
    ints = np.array([nb, 0], dtype=np.int32)
    _dpotrf(chars[4:].ctypes, ints[0:].ctypes, fmat.ctypes, ints[0:].ctypes, ints[1:].ctypes)
    if ints[1] != 0:
        return nbor + ints[1]
    for a0 in range(0, nb, TRANSPOSE_TILE):  # R's border block (upper) from F's C lower triangle
        for b0 in range(a0, nb, TRANSPOSE_TILE):
            for a in range(a0, min(a0 + TRANSPOSE_TILE, nb)):
                row = r_out[nbor + a]
                for b in range(max(a, b0), min(b0 + TRANSPOSE_TILE, nb)):
                    row[nbor + b] = fmat[b, a]
    return 0
