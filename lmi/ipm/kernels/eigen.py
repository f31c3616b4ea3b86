"""Eigenvalues of the small symmetric matrices of the interior-point kernels (:mod:`lmi.ipm.kernels`),
as the C core's ``lmi/ccore/dense.c`` has them: all eigenpairs for the NT scaling
(:func:`symmetric_eigen`), a lower bound on the smallest eigenvalue for the step length
(:func:`smallest_eigenvalue`).

:func:`symmetric_eigen` is the C core's ``dense_sym_eig`` (``lmi/ccore/dense.c``) in numba:
Householder reduction to tridiagonal form with the transformation accumulated (``tred2``), then
implicit QL with the rotations applied to the eigenvectors (``tql2``), as in EISPACK (Smith et al.,
*Matrix Eigensystem Routines - EISPACK Guide*) and the Numerical Recipes routines of the same
names: the C core's operations in the same order. The eigenvectors are kept as rows while the
rotations act on them, so that each rotation reads two contiguous rows.

Why not ``np.linalg.eigh``: on the blocks of the LMI forms (orders 7-16) LAPACK's ``dsyevd`` spends
most of its time in the calls between its level-2 routines, not in arithmetic. Measured over 64
random positive definite matrices per order, the two called alternately 40 times in one process
(single-threaded BLAS, a test run busy on the other core): ``np.linalg.eigh`` from compiled code
against this function, order 7 7.8 -> 3.7 us, 12 19.2 -> 10.2 us, 16 33.9 -> 18.2 us, 28 96 -> 69 us
(paired ratios 0.47, 0.53, 0.53, 0.72; an idle run earlier had them even at order 28).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from lmi.ipm.kernels.packed import JIT

__all__ = ["EIGEN_SWEEPS", "smallest_eigenvalue", "symmetric_eigen"]

#: :func:`symmetric_eigen` gives up (returns -1) when one eigenvalue needs more QL sweeps than this.
EIGEN_SWEEPS = 60

_EPS = 2.220446049250313e-16


@njit(**JIT)
def _pythag(a, b):
    """``sqrt(a^2 + b^2)`` without overflow."""
    x, y = abs(a), abs(b)
    if x < y:
        x, y = y, x
    if x == 0.0:
        return 0.0
    r = y / x
    return x * np.sqrt(1.0 + r * r)


@njit(**JIT)
def _tred2(v, k, d, e):
    """Householder reduction of symmetric ``v[:k, :k]`` (overwritten) to tridiagonal form: ``d``
    the diagonal, ``e`` the sub-diagonal (``e[0] = 0``), ``v`` the accumulated transformation."""
    for j in range(k):
        d[j] = v[k - 1, j]
    for i in range(k - 1, 0, -1):
        scale = 0.0
        h = 0.0
        for m in range(i):
            scale += abs(d[m])
        if scale == 0.0:
            e[i] = d[i - 1]
            for j in range(i):
                d[j] = v[i - 1, j]
                v[i, j] = 0.0
                v[j, i] = 0.0
        else:
            for m in range(i):
                d[m] /= scale
                h += d[m] * d[m]
            f = d[i - 1]
            g = np.sqrt(h)
            if f > 0.0:
                g = -g
            e[i] = scale * g
            h = h - f * g
            d[i - 1] = f - g
            for j in range(i):
                e[j] = 0.0
            for j in range(i):
                f = d[j]
                v[j, i] = f
                g = e[j] + v[j, j] * f
                for m in range(j + 1, i):
                    g += v[m, j] * d[m]
                    e[m] += v[m, j] * f
                e[j] = g
            f = 0.0
            for j in range(i):
                e[j] /= h
                f += e[j] * d[j]
            hh = f / (h + h)
            for j in range(i):
                e[j] -= hh * d[j]
            for j in range(i):
                f = d[j]
                g = e[j]
                for m in range(j, i):
                    v[m, j] -= f * e[m] + g * d[m]
                d[j] = v[i - 1, j]
                v[i, j] = 0.0
        d[i] = h
    for i in range(k - 1):
        v[k - 1, i] = v[i, i]
        v[i, i] = 1.0
        h = d[i + 1]
        if h != 0.0:
            for m in range(i + 1):
                d[m] = v[m, i + 1] / h
            for j in range(i + 1):
                g = 0.0
                for m in range(i + 1):
                    g += v[m, i + 1] * v[m, j]
                for m in range(i + 1):
                    v[m, j] -= g * d[m]
        for m in range(i + 1):
            v[m, i + 1] = 0.0
    for j in range(k):
        d[j] = v[k - 1, j]
        v[k - 1, j] = 0.0
    v[k - 1, k - 1] = 1.0
    e[0] = 0.0


@njit(**JIT)
def _tql2(vt, k, d, e):
    """Implicit QL on the tridiagonal ``(d, e)`` of :func:`_tred2`, rotating the rows of ``vt``
    (the transformation's columns); eigenvalues sorted ascending with their rows. Returns -1 when
    an eigenvalue takes more than :data:`EIGEN_SWEEPS` sweeps or the iteration overflows."""
    f = 0.0
    tst1 = 0.0
    for i in range(1, k):
        e[i - 1] = e[i]
    e[k - 1] = 0.0
    for low in range(k):
        t = abs(d[low]) + abs(e[low])
        if t > tst1:
            tst1 = t
        m = low
        while m < k - 1:
            if abs(e[m]) <= _EPS * tst1:
                break
            m += 1
        if m > low:
            sweeps = 0
            while True:
                sweeps += 1
                if sweeps > EIGEN_SWEEPS:
                    return -1
                g = d[low]
                p = (d[low + 1] - g) / (2.0 * e[low])
                r = _pythag(p, 1.0)
                if p < 0:
                    r = -r
                d[low] = e[low] / (p + r)
                d[low + 1] = e[low] * (p + r)
                dl1 = d[low + 1]
                h = g - d[low]
                for i in range(low + 2, k):
                    d[i] -= h
                f = f + h
                p = d[m]
                c = 1.0
                c2 = c
                c3 = c
                el1 = e[low + 1]
                s = 0.0
                s2 = 0.0
                for i in range(m - 1, low - 1, -1):
                    c3 = c2
                    c2 = c
                    s2 = s
                    g = c * e[i]
                    h = c * p
                    r = _pythag(p, e[i])
                    e[i + 1] = s * r
                    s = e[i] / r
                    c = p / r
                    p = c * d[i] - s * g
                    d[i + 1] = h + s * (c * g + s * d[i])
                    ra = vt[i]
                    rb = vt[i + 1]
                    for j in range(k):
                        h = rb[j]
                        rb[j] = s * ra[j] + c * h
                        ra[j] = c * ra[j] - s * h
                p = -s * s2 * c3 * el1 * e[low] / dl1
                e[low] = s * p
                d[low] = c * p
                if not (abs(e[low]) == abs(e[low])) or not (tst1 < np.inf):
                    return -1
                if not abs(e[low]) > _EPS * tst1:
                    break
        d[low] = d[low] + f
        e[low] = 0.0
    for i in range(k - 1):
        p = d[i]
        at = i
        for j in range(i + 1, k):
            if d[j] < p:
                at = j
                p = d[j]
        if at != i:
            d[at] = d[i]
            d[i] = p
            for j in range(k):
                t = vt[i, j]
                vt[i, j] = vt[at, j]
                vt[at, j] = t
    return 0


@njit(**JIT)
def symmetric_eigen(a, k, w, vt, v_work, e_work):
    """Eigenvalues ``w[:k]`` (ascending) and eigenvectors of symmetric ``a[:k, :k]`` (read only),
    the eigenvector of ``w[i]`` in row ``i`` of ``vt`` (``a = vt' diag(w) vt``).

    ``v_work`` (at least ``k x k``) and ``e_work`` (``k``) are workspaces. Returns 0, or -1 if
    ``a`` holds a NaN or an infinity or the QL iteration did not converge (see :func:`_tql2`).

    Examples
    --------
    >>> import numpy as np
    >>> a = np.array([[2.0, 1.0], [1.0, 2.0]])
    >>> w, vt = np.empty(2), np.empty((2, 2))
    >>> symmetric_eigen(a, 2, w, vt, np.empty((2, 2)), np.empty(2))
    0
    >>> w
    array([1., 3.])
    >>> bool(np.allclose(vt.T @ np.diag(w) @ vt, a))
    True
    """
    for i in range(k):
        for j in range(k):
            value = a[i, j]
            if not (value - value == 0.0):
                return -1
            v_work[i, j] = value
    if k == 1:
        w[0] = v_work[0, 0]
        vt[0, 0] = 1.0
        return 0
    _tred2(v_work, k, w, e_work)
    for i in range(k):
        for j in range(k):
            vt[i, j] = v_work[j, i]
    return _tql2(vt, k, w, e_work)


@njit(**JIT)
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


@njit(**JIT)
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


@njit(**JIT)
def smallest_eigenvalue(a, k, upper=np.inf, rtol=4.0 * _EPS):
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
