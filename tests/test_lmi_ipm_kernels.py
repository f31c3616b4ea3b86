"""The compiled kernels of the interior-point solver (:mod:`lmi.ipm.kernels`) against numpy/LAPACK.

Each kernel is checked on its own, with the packed layout built by the solver's
``PackedLayout``, against references that share no code with it:

* ``smallest_eigenvalue`` (Householder tridiagonalisation and Sturm bisection) against LAPACK's
  ``eigvalsh`` and against the Rayleigh quotient of LAPACK's eigenvector evaluated in exact
  rational arithmetic (an upper bound on the true smallest eigenvalue, free of rounding), on
  random, low-rank, diagonal, zero, repeated-eigenvalue and padded matrices, and against the
  closed-form spectra of two tridiagonal matrices; also its ``upper`` and ``rtol`` arguments;
* ``pack``/``unpack`` against the toolkit's svec convention (:func:`lmi.affine.svec_matrix`),
  the trace inner product and a round trip on arbitrary floats (hypothesis);
* ``cholesky_blocks`` against ``numpy.linalg.cholesky``;
* ``scaling_and_schur_rows`` against the defining identities of the Nesterov-Todd scaling
  (``K S K' = K^-T Z K^-1 = diag(lambda)``), the closed-form NT point of the pair, the
  eigenvalues of ``S Z`` from numpy, and ``K A_ij K'`` packed by plain numpy;
* ``residuals`` against the formulas written out in numpy.

Tolerances are multiples of the double precision unit ``eps`` times a natural scale of each
quantity; each test's docstring gives the measured worst case behind its bound. Every kernel
input is padded with NaN outside the ``[:k, :k]`` part it may use, so a read outside it shows.
Hypothesis runs derandomised: the bounds are a few units of rounding from the measured worst
cases, and a test that failed only on some runs would say nothing reliable.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from lmi.affine import smat_matrix, svec_indices, svec_matrix
from lmi.ipm import kernels
from lmi.ipm.blocks import PackedLayout

EPS = np.finfo(float).eps
SQRT2 = np.sqrt(2.0)
DETERMINISTIC = settings(derandomize=True, database=None, deadline=None)


# -- helpers -------------------------------------------------------------------------------------
def _sym(mat: np.ndarray) -> np.ndarray:
    return 0.5 * (mat + np.swapaxes(mat, -1, -2))


def _rand_pd(rng: np.random.Generator, k: int) -> np.ndarray:
    g = rng.normal(size=(k, k))
    return g @ g.T / k + 0.5 * np.eye(k)


def _padded(blocks: list[np.ndarray], fill: float = np.nan) -> np.ndarray:
    """The kernels' ``(nb, kmax, kmax)`` array of ``blocks``, ``fill`` outside each ``[:k, :k]``."""
    kmax = max(b.shape[0] for b in blocks)
    out = np.full((len(blocks), kmax, kmax), fill)
    for j, b in enumerate(blocks):
        out[j, :b.shape[0], :b.shape[0]] = b
    return out


def _packed_block(mat: np.ndarray) -> np.ndarray:
    """The layout of :mod:`lmi.ipm.kernels` written out: upper triangle row by row, off-diagonal
    entries times sqrt(2)."""
    rows, cols = np.triu_indices(mat.shape[0])
    return mat[rows, cols] * np.where(rows == cols, 1.0, SQRT2)


def _exact_rayleigh(a: np.ndarray, v: np.ndarray) -> float:
    """``v'Av / v'v`` evaluated exactly (integers) and rounded once: an upper bound, to half an
    ulp, on the smallest eigenvalue of ``a``, for any ``v``.

    Every double is an integer multiple of ``2**-1074``; scaled by ``2**1100`` all the sums and
    products are exact Python integers.
    """
    def fixed(t: float) -> int:
        num, den = float(t).as_integer_ratio()  # den a power of two <= 2**1074
        return (num << 1100) // den

    k = a.shape[0]
    xs = [fixed(t) for t in v]
    ax = [sum(fixed(a[i, j]) * xs[j] for j in range(k)) for i in range(k)]
    num = sum(x * y for x, y in zip(xs, ax, strict=True))
    den = sum(x * x for x in xs) << 1100
    return num / den  # int / int is correctly rounded in Python


def _check_smallest_eigenvalue(a: np.ndarray, c_two_sided: float = 16.0, c_over: float = 8.0) -> float:
    """Assert the kernel's result on ``a`` against ``eigvalsh`` and the exact Rayleigh quotient;
    return the kernel's value."""
    k = a.shape[0]
    w, v = np.linalg.eigh(a)
    got = kernels.smallest_eigenvalue(a.copy(), k)
    scale = max(float(np.max(np.abs(w))), 1e-300)
    assert abs(got - w[0]) <= c_two_sided * EPS * scale, (got, w[0], (got - w[0]) / (EPS * scale))
    upper = _exact_rayleigh(a, v[:, 0])
    assert got <= upper + c_over * EPS * scale, (got, upper, (got - upper) / (EPS * scale))
    return got


def _random_matrix(rng: np.random.Generator, kind: str, k: int) -> np.ndarray:
    """A symmetric test matrix of order ``k`` and norm about 1."""
    if kind == "gaussian":
        return _sym(rng.normal(size=(k, k)))
    if kind == "low rank minus shift":
        u = rng.normal(size=(k, int(rng.integers(0, k + 1))))
        return _sym(u @ u.T) - rng.uniform(0.1, 2.0) * np.eye(k)
    if kind == "repeated":
        q, _ = np.linalg.qr(rng.normal(size=(k, k)))
        return _sym((q * rng.choice(rng.normal(size=2), size=k)) @ q.T)
    if kind == "shifted uniform":
        return _sym(rng.uniform(-1.0, 1.0, size=(k, k))) + rng.uniform(-3.0, 3.0) * np.eye(k)
    raise AssertionError(kind)


KINDS = ("gaussian", "low rank minus shift", "repeated", "shifted uniform")


def _sparse_coefficients(coefs: list[np.ndarray]) -> tuple:
    """``sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col`` built, by plain loops,
    from the layout described in the module docstring of :mod:`lmi.ipm.kernels`: one entry per
    non-zero ``A_ij[a, b]``, ``a <= b``, pointing at its position pair. The entries are in
    position order (the solver's ``_refresh`` puts them in variable order), so the kernel is
    also checked not to depend on that order."""
    sp_off, sp_var, sp_pair, sp_val = [0], [], [], []
    pair_off, pair_row, pair_col = [0], [], []
    for coef in coefs:
        n, k, _ = coef.shape
        pair_of: dict[tuple[int, int], int] = {}
        for a in range(k):
            for b in range(a, k):
                for i in range(n):
                    if coef[i, a, b] != 0.0:
                        if (a, b) not in pair_of:
                            pair_of[a, b] = len(pair_row)
                            pair_row.append(a)
                            pair_col.append(b)
                        sp_var.append(i)
                        sp_pair.append(pair_of[a, b])
                        sp_val.append(coef[i, a, b])
        sp_off.append(len(sp_var))
        pair_off.append(len(pair_row))

    def ints(xs):
        return np.asarray(xs, dtype=np.int64)

    return (ints(sp_off), ints(sp_var), ints(sp_pair), np.asarray(sp_val, dtype=float),
            ints(pair_off), ints(pair_row), ints(pair_col))


def _schur_rows(s_blocks: list[np.ndarray], z_blocks: list[np.ndarray], coefs: list[np.ndarray]):
    """Run ``scaling_and_schur_rows`` on ``S_j`` (given as matrices; their numpy Cholesky factors
    are passed), ``Z_j`` and ``A_j`` ``(n, k, k)``; outputs start as NaN.

    Returns ``(ok, K blocks, lambda blocks, P (size, n))``.
    """
    orders = [s.shape[0] for s in s_blocks]
    n = coefs[0].shape[0]
    lay = PackedLayout(orders)
    s_chol = _padded([np.linalg.cholesky(s) for s in s_blocks])  # exact zeros above the diagonal
    z = _padded(z_blocks)
    nb, kmax = len(orders), max(orders)
    kk = np.full((nb, kmax, kmax), np.nan)
    lam = np.full((nb, kmax), np.nan)
    pt = np.full((n, lay.size), np.nan)
    ok = kernels.scaling_and_schur_rows(s_chol, z, *lay.arrays, *_sparse_coefficients(coefs), kk,
                                        lam, pt)
    p = pt.T
    blocks_k = [kk[j, :k, :k] for j, k in enumerate(orders)]
    blocks_lam = [lam[j, :k] for j, k in enumerate(orders)]
    return ok, blocks_k, blocks_lam, p


def _psd_sqrt(a: np.ndarray) -> np.ndarray:
    w, v = np.linalg.eigh(a)
    return (v * np.sqrt(w)) @ v.T


# -- smallest_eigenvalue -------------------------------------------------------------------------
@pytest.mark.parametrize("kind", KINDS)
def test_smallest_eigenvalue_matches_lapack_over_orders_and_scales(kind):
    """Orders 1-16, scales 1e-6 to 1e6, two matrices each: within 16 eps max|eig| of
    ``eigvalsh``, and at most 8 eps max|eig| above the true smallest eigenvalue.

    The second bound is the documented one-sidedness ("a lower bound, tight to rounding"),
    checked against an exact Rayleigh quotient (an upper bound on the true value), because
    ``eigvalsh`` is itself up to ~6 eps max|eig| off here. Measured on 340,000 such matrices:
    at most 4.5 eps max|eig| above the true value (the Householder reduction's rounding), at
    most 14.3 below it, and at most 13.5 from ``eigvalsh``. The part below is by design: the
    bisection stops at a bracket of 4 eps times its larger end, which for a tridiagonal matrix
    is up to sqrt(3) max|eig| (7 eps max|eig|); the reduction's rounding adds as much again.
    A wrong reduction or Sturm count would be off by far more than these bounds.
    """
    rng = np.random.default_rng(KINDS.index(kind))
    for k in range(1, 17):
        for scale in 10.0 ** np.arange(-6, 7):
            for _ in range(2):
                _check_smallest_eigenvalue(scale * _random_matrix(rng, kind, k))


@DETERMINISTIC
@given(k=st.integers(1, 16), exponent=st.floats(-6.0, 6.0), seed=st.integers(0, 2**32 - 1),
       kind=st.sampled_from(KINDS))
def test_smallest_eigenvalue_bounds_hold_for_generated_matrices(k, exponent, seed, kind):
    """The same two bounds as above on matrices generated by hypothesis (order, scale, kind)."""
    rng = np.random.default_rng(seed)
    _check_smallest_eigenvalue(10.0**exponent * _random_matrix(rng, kind, k))


def test_smallest_eigenvalue_is_exact_on_diagonal_zero_and_scalar_matrices():
    """With no off-diagonal entries the Gershgorin interval is the spectrum's hull and the
    bisection never moves its lower end: the result is the smallest diagonal entry exactly (0
    for the zero matrix, ``c`` for ``c I``, ``a[0, 0]`` at order 1). Not exact would mean the
    reduction touched a diagonal matrix or the bracket's lower end moved past an eigenvalue."""
    rng = np.random.default_rng(5)
    for k in range(1, 17):
        diag = rng.normal(size=k) * 10.0 ** rng.uniform(-6, 6)
        assert kernels.smallest_eigenvalue(np.diag(diag), k) == np.min(diag)
        assert kernels.smallest_eigenvalue(np.zeros((k, k)), k) == 0.0
        assert kernels.smallest_eigenvalue(-2.5 * np.eye(k), k) == -2.5
        assert kernels.smallest_eigenvalue(np.diag(np.full(k, 1e-300)), k) == 1e-300


def test_smallest_eigenvalue_on_repeated_and_clustered_eigenvalues():
    """Multiple eigenvalues (a k-fold one, and low rank minus a shift, whose smallest eigenvalue
    ``-shift`` has multiplicity ``k - rank``) and a cluster 1e-12 apart: the same bounds as the
    random matrices; repeated roots are where a Sturm count with a zero pivot goes wrong."""
    rng = np.random.default_rng(6)
    for k in range(2, 17):
        q, _ = np.linalg.qr(rng.normal(size=(k, k)))
        _check_smallest_eigenvalue(_sym(q @ (3.0 * np.eye(k)) @ q.T))
        ev = np.r_[np.full(k // 2, -1.0), np.linspace(0.5, 2.0, k - k // 2)]
        _check_smallest_eigenvalue(_sym((q * ev) @ q.T))
        _check_smallest_eigenvalue(_sym((q * (1.0 + 1e-12 * np.arange(k))) @ q.T))
        for rank in (0, 1, k // 2, k - 1):
            u = rng.normal(size=(k, rank))
            a = _sym(u @ u.T) - 0.7 * np.eye(k)
            got = _check_smallest_eigenvalue(a)
            assert got == pytest.approx(-0.7, abs=16 * EPS * np.max(np.abs(np.linalg.eigvalsh(a))))


def test_smallest_eigenvalue_of_tridiagonal_matrices_with_known_spectra():
    """The path graph's adjacency matrix (zero diagonal, ones beside it; smallest eigenvalue
    ``-2 cos(pi / (k + 1))``) and the second difference ``tridiag(-1, 2, -1)``
    (``2 - 2 cos(pi / (k + 1))``), orders 1-16: within 16 eps of the closed form (itself
    rounded) and at most 8 eps above it; measured at most 4.1 eps below and 1 eps above (the
    closed form's own rounding). The first puts exact zero pivots into the Sturm count (its
    first bisection point is 0 = ``d[0]``), the case the count's zero-pivot rule is there for.
    """
    for k in range(1, 17):
        off = np.eye(k, k=1) + np.eye(k, k=-1)
        for a, want in ((off, -2.0 * np.cos(np.pi / (k + 1))),
                        (2.0 * np.eye(k) - off, 2.0 - 2.0 * np.cos(np.pi / (k + 1)))):
            scale = max(float(np.max(np.abs(np.linalg.eigvalsh(a)))), 1.0)  # [[0]] at k = 1
            got = kernels.smallest_eigenvalue(a.copy(), k)
            assert abs(got - want) <= 16 * EPS * scale, (k, got, want)
            assert got <= want + 8 * EPS * scale, (k, got, want)


def test_smallest_eigenvalue_of_a_block_inside_a_larger_padded_array():
    """``a[:k, :k]`` of a larger array whose other entries are NaN: the same value, bit for bit,
    as on the ``(k, k)`` matrix alone (the kernel must read nothing outside ``[:k, :k]``), and
    correct against ``eigvalsh``."""
    rng = np.random.default_rng(7)
    for k in range(1, 16):
        block = _sym(rng.normal(size=(k, k)))
        big = np.full((16, 16), np.nan)
        big[:k, :k] = block
        got = kernels.smallest_eigenvalue(big, k)
        assert got == kernels.smallest_eigenvalue(block.copy(), k)
        w = np.linalg.eigvalsh(block)
        assert abs(got - w[0]) <= 16 * EPS * np.max(np.abs(w))


def test_smallest_eigenvalue_with_an_upper_cap_and_a_coarse_tolerance():
    """The arguments the step-length search uses: ``upper`` is returned when the smallest
    eigenvalue is not below it (so the result stays a lower bound), otherwise the result is the
    eigenvalue; with ``rtol`` 1e-9 it is a lower bound within 2e-9 max|eig| (the bracket is at
    most ``rtol`` times sqrt(3) max|eig| wide)."""
    rng = np.random.default_rng(8)
    for k in range(1, 17):
        a = _sym(rng.normal(size=(k, k)))
        w = np.linalg.eigvalsh(a)
        scale = np.max(np.abs(w))
        below = w[0] - 0.25 * scale  # smallest eigenvalue not below this cap: returns the cap
        assert kernels.smallest_eigenvalue(a.copy(), k, below) == below
        got = kernels.smallest_eigenvalue(a.copy(), k, w[0] + 0.25 * scale)
        assert abs(got - w[0]) <= 16 * EPS * scale
        coarse = kernels.smallest_eigenvalue(a.copy(), k, np.inf, 1e-9)
        assert w[0] - 2e-9 * scale <= coarse <= w[0] + 16 * EPS * scale


# -- pack / unpack -------------------------------------------------------------------------------
FINITE = st.floats(-1e300, 1e300, allow_nan=False, allow_subnormal=False).map(
    lambda t: 0.0 if abs(t) < 1e-300 else t)


@DETERMINISTIC
@given(orders=st.lists(st.integers(1, 8), min_size=1, max_size=5), data=st.data())
def test_unpack_then_pack_round_trips_any_packed_vector(orders, data):
    """Any packed vector of finite doubles (|v| <= 1e300, no subnormals) comes back from
    ``pack(unpack(v))`` exactly on the diagonal and within one ulp off it (``v / sqrt(2) *
    sqrt(2)`` rounds twice; it differs from ``v`` for ~15 % of doubles, by at most 0.71 ulp
    measured); ``unpack`` gives symmetric blocks, zero outside ``[:k, :k]``."""
    lay = PackedLayout(orders)
    vec = data.draw(hnp.arrays(np.float64, lay.size, elements=FINITE))
    kmax = max(orders)
    mats = kernels.unpack(vec, *lay.arrays, kmax)
    assert mats.shape == (len(orders), kmax, kmax)
    for j, k in enumerate(orders):
        assert np.array_equal(mats[j], mats[j].T)
        assert not np.any(mats[j, k:, :]) and not np.any(mats[j, :, k:])
    back = kernels.pack(mats, *lay.arrays)
    assert np.all(np.abs(back - vec) <= EPS * np.abs(vec))
    on_diag = lay.ent_row == lay.ent_col
    assert np.array_equal(back[on_diag], vec[on_diag])


@DETERMINISTIC
@given(orders=st.lists(st.integers(1, 8), min_size=1, max_size=5), data=st.data())
def test_pack_then_unpack_round_trips_symmetric_blocks(orders, data):
    """Symmetric blocks of any finite doubles come back from ``unpack(pack(M))`` within one ulp
    (exactly on the diagonal); entries outside ``[:k, :k]`` (NaN here) are never read."""
    blocks = []
    for k in orders:
        g = data.draw(hnp.arrays(np.float64, (k, k), elements=FINITE))
        blocks.append(np.triu(g) + np.triu(g, 1).T)
    lay = PackedLayout(orders)
    vec = kernels.pack(_padded(blocks), *lay.arrays)
    assert np.all(np.isfinite(vec))
    back = kernels.unpack(vec, *lay.arrays, max(orders))
    for j, (k, b) in enumerate(zip(orders, blocks, strict=True)):
        assert np.all(np.abs(back[j, :k, :k] - b) <= EPS * np.abs(b))
        assert np.array_equal(np.diag(back[j, :k, :k]), np.diag(b))


@pytest.mark.parametrize("orders", [(1,), (2,), (3,), (1, 2, 3), (7, 1, 15, 4), (5, 5, 12)])
def test_pack_is_the_svec_of_each_block_in_row_by_row_order(orders):
    """The packed vector is, block after block, the svec of each block with sqrt(2) on the
    off-diagonal entries, like :func:`lmi.affine.svec_matrix`, but in the other order: the upper
    triangle row by row (``numpy.triu_indices``, i.e. the lower triangle column by column, SCS's
    order) where ``svec_matrix`` goes column by column (Clarabel's). The two orders coincide
    only for orders 1 and 2, so concatenated ``svec_matrix`` equals ``pack`` only then.
    ``unpack`` is ``smat_matrix`` after undoing the reordering, and ``pack``/``unpack`` agree
    with the layout arrays of ``PackedLayout``."""
    rng = np.random.default_rng(sum(orders))
    blocks = [_sym(rng.normal(size=(k, k))) for k in orders]
    lay = PackedLayout(list(orders))
    vec = kernels.pack(_padded(blocks), *lay.arrays)
    svecs = []
    for j, (k, b) in enumerate(zip(orders, blocks, strict=True)):
        part = vec[lay.rows(j)]
        assert np.array_equal(part, _packed_block(b))
        rows, cols = np.triu_indices(k)
        assert np.array_equal(lay.ent_row[lay.rows(j)], rows)
        assert np.array_equal(lay.ent_col[lay.rows(j)], cols)
        # position in svec_matrix's (column-by-column) order of each row-by-row entry
        s_rows, s_cols = svec_indices(k)
        where = {(int(r), int(c)): t for t, (r, c) in enumerate(zip(s_rows, s_cols, strict=True))}
        perm = np.array([where[int(r), int(c)] for r, c in zip(rows, cols, strict=True)])
        svec = svec_matrix(b)
        assert np.array_equal(part, svec[perm])
        assert np.array_equal(perm, np.arange(perm.size)) == (k <= 2)
        inverse = np.empty_like(perm)
        inverse[perm] = np.arange(perm.size)
        np.testing.assert_allclose(smat_matrix(part[inverse], k),
                                   kernels.unpack(vec, *lay.arrays, max(orders))[j, :k, :k],
                                   rtol=EPS, atol=0)
        svecs.append(svec)
    assert np.array_equal(np.concatenate(svecs), vec) == all(k <= 2 for k in orders)


@pytest.mark.parametrize("seed", range(5))
def test_packed_inner_product_is_the_trace_inner_product(seed):
    """``pack(S) . pack(Z) = sum_j tr(S_j Z_j)`` for symmetric blocks of mixed orders (what the
    sqrt(2) weights are for: the duality gap ``s'z`` of the kernels is the block trace inner
    product). Equal within 2 m eps sum|S_j||Z_j| (m = entries; the two sums round differently)."""
    rng = np.random.default_rng(seed)
    orders = [int(k) for k in rng.integers(1, 13, size=rng.integers(1, 6))]
    s_blocks = [_sym(rng.normal(size=(k, k))) for k in orders]
    z_blocks = [_sym(rng.normal(size=(k, k))) for k in orders]
    lay = PackedLayout(orders)
    got = kernels.pack(_padded(s_blocks), *lay.arrays) @ kernels.pack(_padded(z_blocks), *lay.arrays)
    want = sum(float(np.trace(s @ z)) for s, z in zip(s_blocks, z_blocks, strict=True))
    bound = sum(float(np.sum(np.abs(s) * np.abs(z))) for s, z in zip(s_blocks, z_blocks, strict=True))
    assert abs(got - want) <= 2 * sum(k * k for k in orders) * EPS * bound


# -- cholesky_blocks -----------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(6))
def test_cholesky_blocks_match_numpy_on_positive_definite_blocks(seed):
    """Positive definite blocks of mixed orders, condition numbers 1 to 1e8, scales 1e-6 to 1e6:
    ``True``; each factor lower triangular with an exact-zero upper part, ``L L' = A`` within
    8 eps ||A|| (backward stability; measured 2.4), and equal to numpy's factor within
    8 eps sqrt(cond A) ||L|| (measured 1.3; both are backward stable, so they differ by the
    conditioning of the factor)."""
    rng = np.random.default_rng(seed)
    orders = [int(k) for k in rng.integers(1, 16, size=rng.integers(1, 6))]
    blocks = []
    for k in orders:
        q, _ = np.linalg.qr(rng.normal(size=(k, k)))
        ev = np.logspace(0, rng.uniform(0, 8), k) * 10.0 ** rng.uniform(-6, 6)
        blocks.append(_sym((q * ev) @ q.T))
    kmax = max(orders)
    out = np.full((len(orders), kmax, kmax), np.nan)
    assert kernels.cholesky_blocks(_padded(blocks), np.asarray(orders, dtype=np.int64), out)
    for j, (k, a) in enumerate(zip(orders, blocks, strict=True)):
        got = out[j, :k, :k]
        assert not np.any(np.triu(got, 1))
        assert np.max(np.abs(got @ got.T - a)) <= 8 * EPS * np.linalg.norm(a, 2)
        want = np.linalg.cholesky(a)
        assert np.linalg.norm(got - want, 2) <= (
            8 * EPS * np.sqrt(np.linalg.cond(a)) * np.linalg.norm(want, 2))


def _with_corner(mat: np.ndarray, value: float) -> np.ndarray:
    """``mat`` with ``value`` at ``[k-1, 0]`` and ``[0, k-1]`` (the last pivot sees it)."""
    mat[-1, 0] = mat[0, -1] = value
    return mat


NOT_PD = {
    "indefinite": lambda k: np.diag(np.r_[np.ones(k - 1), -1e-3]),
    "negative definite": lambda k: -np.eye(k),
    "singular PSD": lambda k: np.ones((k, k)),
    "zero": lambda k: np.zeros((k, k)),
    "NaN on the diagonal": lambda k: np.diag(np.r_[np.ones(k - 1), np.nan]),
    "NaN off the diagonal": lambda k: _with_corner(np.eye(k), np.nan),
}


@pytest.mark.parametrize("case", list(NOT_PD))
@pytest.mark.parametrize("where", [0, 1, 2])
def test_cholesky_blocks_rejects_a_block_that_is_not_positive_definite(case, where):
    """One bad block (first, middle or last of three, orders 3, 5, 4) among positive definite ones:
    ``False``. Indefinite, singular and zero blocks end on a non-positive pivot, NaN on a NaN
    pivot; a ``True`` would hand the scaling a factor that is not one."""
    rng = np.random.default_rng(9)
    blocks = [_rand_pd(rng, 3), _rand_pd(rng, 5), _rand_pd(rng, 4)]
    blocks[where] = NOT_PD[case](blocks[where].shape[0])
    out = np.zeros((3, 5, 5))
    assert not kernels.cholesky_blocks(_padded(blocks), np.array([3, 5, 4], dtype=np.int64), out)


def test_cholesky_blocks_rejects_an_infinite_diagonal_entry():
    """A non-finite pivot is rejected: ``diag(inf, 1)`` gives ``False`` (a test ``s > 0`` alone
    let ``+inf`` through, with the factor ``diag(inf, 1)``; an infinite off-diagonal entry makes
    a later pivot -inf)."""
    out = np.zeros((1, 2, 2))
    assert not kernels.cholesky_blocks(np.diag([np.inf, 1.0])[None], np.array([2], dtype=np.int64), out)


# -- scaling_and_schur_rows ----------------------------------------------------------------------
def _coefficients(rng: np.random.Generator, structure: str, n: int, k: int) -> np.ndarray:
    """``A_j`` ``(n, k, k)``: dense, diagonal, or sparse (~10 % of the upper entries, so some
    variables have no entry in a block), all symmetric."""
    coef = _sym(rng.normal(size=(n, k, k)))
    if structure == "diagonal":
        coef = coef * np.eye(k)
    elif structure == "sparse":
        keep = np.triu(rng.uniform(size=(n, k, k)) < 0.1)
        coef = np.where(keep | np.swapaxes(keep, 1, 2), coef, 0.0)
    return coef


@pytest.mark.parametrize("structure", ["dense", "diagonal", "sparse"])
@pytest.mark.parametrize("seed", range(4))
def test_nt_scaling_and_schur_rows_match_numpy(structure, seed):
    """Random positive definite ``S_j``, ``Z_j`` (condition numbers up to ~50, scales 1e-3 to
    1e3), 1-4 blocks of orders 1-12, 1-8 variables; block 0 has all-zero coefficients in the
    sparse case. Checks, for every block, with ``lambda_max`` the largest ``lambda``:

    * ``lambda`` positive and ascending, equal to ``sqrt(eig(S Z))`` from ``numpy.linalg.eigvals``
      within 32 eps lambda_max;
    * ``K S K' = diag(lambda)`` within 64 eps lambda_max and, with ``R = K^-1``,
      ``R' Z R = diag(lambda)`` within 64 eps lambda_max;
    * ``K'K = W^-1`` for the NT point ``W = S^1/2 (S^1/2 Z S^1/2)^-1/2 S^1/2``, the unique
      positive definite ``W`` with ``W Z W = S``, computed here from eigen-decompositions:
      within 64 eps cond(S) ||W^-1||;
    * column ``i`` of ``P`` is the packed ``K A_ij K'``, computed with plain numpy, within
      8 eps ||K||^2 ||A_ij||_F; a variable absent from a block gives exact zeros.

    Measured worst cases over 900 such draws (300 seeds, each structure): 10.6, 23, 11.4, 6.8
    and 1.1 respectively (the products with ``S`` and ``Z`` lose a factor of their condition
    numbers, up to ~50 here).
    """
    rng = np.random.default_rng(seed)
    orders = [int(k) for k in rng.integers(1, 13, size=rng.integers(1, 5))]
    n = int(rng.integers(1, 9))
    s_blocks = [_rand_pd(rng, k) * 10.0 ** rng.uniform(-3, 3) for k in orders]
    z_blocks = [_rand_pd(rng, k) * 10.0 ** rng.uniform(-3, 3) for k in orders]
    coefs = [_coefficients(rng, structure, n, k) for k in orders]
    if structure == "sparse":
        coefs[0][:] = 0.0
    ok, ks, lams, p = _schur_rows(s_blocks, z_blocks, coefs)
    assert ok
    lay = PackedLayout(orders)
    for j, (s, z, kj, lam) in enumerate(zip(s_blocks, z_blocks, ks, lams, strict=True)):
        top = lam[-1]
        assert np.all(lam > 0) and np.all(np.diff(lam) >= 0)
        want_lam = np.sort(np.sqrt(np.linalg.eigvals(s @ z).real))
        assert np.max(np.abs(lam - want_lam)) <= 32 * EPS * top
        assert np.max(np.abs(kj @ s @ kj.T - np.diag(lam))) <= 64 * EPS * top
        r = np.linalg.inv(kj)
        assert np.max(np.abs(r.T @ z @ r - np.diag(lam))) <= 64 * EPS * top
        root = _psd_sqrt(s)
        w_inv = np.linalg.solve(root, np.linalg.solve(root, _psd_sqrt(_sym(root @ z @ root))).T).T
        assert np.max(np.abs(kj.T @ kj - w_inv)) <= 64 * EPS * np.linalg.cond(s) * np.linalg.norm(w_inv, 2)
        for i in range(n):
            want = _packed_block(kj @ coefs[j][i] @ kj.T)
            got = p[lay.rows(j), i]
            if not np.any(coefs[j][i]):
                assert np.array_equal(got, np.zeros_like(got))
            assert np.max(np.abs(got - want), initial=0.0) <= (
                8 * EPS * np.linalg.norm(kj, 2) ** 2 * np.linalg.norm(coefs[j][i]))


@pytest.mark.parametrize("cond", [1e4, 1e8])
def test_nt_scaling_near_the_central_path_with_ill_conditioned_slacks(cond):
    """``S`` with condition number ``cond`` and ``Z = mu L^-T (I + E) L^-1`` (``S = L L'``,
    ``||E|| <= 0.2``), as near the central path, where the docstring says the eigenproblem of
    ``L'ZL`` stays well conditioned although ``S`` and ``Z`` are not:

    * ``lambda`` within 10 % of ``sqrt(mu)`` (measured 6 %), and equal to ``sqrt`` of numpy's
      eigenvalues of ``L'ZL`` within 16 eps lambda_max whatever ``cond`` (measured 2.9 for
      ``cond`` 1 to 1e10);
    * ``K S K' = diag(lambda)``, formed as ``(K L)(K L)'`` with the factor the kernel was given,
      and ``R' Z R = diag(lambda)`` with ``R = K^-1 = L (K L)^-1``, within 4 eps cond
      lambda_max (measured 0.38 and 0.27). The error grows like eps cond: ``K = diag(lambda)^-1
      R'Z`` is a product with ``Z``, whose entries (of size ``mu ||L^-1||^2``) are ``cond``
      times those of the result, so its rounding shows; an unstable scaling would lose more.
    """
    rng = np.random.default_rng(int(np.log10(cond)))
    orders = [12, 7, 3]
    s_blocks, z_blocks, mus = [], [], []
    for k in orders:
        q, _ = np.linalg.qr(rng.normal(size=(k, k)))
        s = _sym((q * np.logspace(0, np.log10(cond), k)) @ q.T) * 10.0 ** rng.uniform(-3, 3)
        ell_inv = np.linalg.inv(np.linalg.cholesky(s))
        mu = 10.0 ** rng.uniform(-8, 0)
        e = 0.2 * _sym(rng.uniform(-1, 1, size=(k, k))) / k
        s_blocks.append(s)
        mus.append(mu)
        z_blocks.append(_sym(mu * ell_inv.T @ (np.eye(k) + e) @ ell_inv))
    coefs = [_sym(rng.normal(size=(2, k, k))) for k in orders]
    ok, ks, lams, _ = _schur_rows(s_blocks, z_blocks, coefs)
    assert ok
    for s, z, mu, kj, lam in zip(s_blocks, z_blocks, mus, ks, lams, strict=True):
        top, bound = lam[-1], 4 * EPS * np.linalg.cond(s) * lam[-1]
        assert np.all(np.abs(lam / np.sqrt(mu) - 1.0) <= 0.1)
        ell = np.linalg.cholesky(s)
        assert np.max(np.abs(lam - np.sqrt(np.linalg.eigvalsh(_sym(ell.T @ z @ ell))))) <= 16 * EPS * top
        kl = kj @ ell
        assert np.max(np.abs(kl @ kl.T - np.diag(lam))) <= bound
        r = ell @ np.linalg.inv(kl)
        assert np.max(np.abs(r.T @ z @ r - np.diag(lam))) <= bound


@pytest.mark.parametrize("case", ["indefinite", "negative definite", "zero"])
@pytest.mark.parametrize("where", [0, 1, 2])
def test_scaling_returns_false_when_a_z_block_is_not_positive_definite(case, where):
    """One ``Z_j`` not positive definite (first, middle or last of three blocks): ``False``, the
    signal the solver turns into ``"numerical_error"``; ``True`` would mean a ``lambda`` of zero
    or a NaN square root in the scaling."""
    rng = np.random.default_rng(10)
    orders = [3, 5, 4]
    s_blocks = [_rand_pd(rng, k) for k in orders]
    z_blocks = [_rand_pd(rng, k) for k in orders]
    z_blocks[where] = NOT_PD[case](orders[where])
    coefs = [_sym(rng.normal(size=(2, k, k))) for k in orders]
    assert not _schur_rows(s_blocks, z_blocks, coefs)[0]


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_scaling_returns_false_on_a_non_finite_z_block(bad):
    """A NaN or inf in ``Z_j`` returns ``False`` (the solver then stops as
    ``"numerical_error"``); it used to raise ``numpy.linalg.LinAlgError`` from numba's ``eigh``,
    which ``BlockLMISolver`` did not catch there."""
    rng = np.random.default_rng(11)
    orders = [3, 4]
    z_blocks = [_rand_pd(rng, k) for k in orders]
    z_blocks[1][0, 2] = z_blocks[1][2, 0] = bad
    coefs = [_sym(rng.normal(size=(2, k, k))) for k in orders]
    assert _schur_rows([_rand_pd(rng, k) for k in orders], z_blocks, coefs)[0] is False


# -- residuals -----------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(4))
def test_residuals_match_numpy_formulas(seed):
    """``rd = G'z + c``, ``rp = G x + s - h``, ``gap = s'z`` (= ``sum_j tr(S_j Z_j)``), the costs
    ``c'x`` and ``-h'z`` and the five norms, with ``s, z`` the blocks packed by numpy. Each sum
    is within 2 m eps of the sum of its terms' magnitudes (m terms; the standard bound for two
    differently ordered summations), the norms within 1e-14 relative."""
    rng = np.random.default_rng(seed)
    orders = [int(k) for k in rng.integers(1, 13, size=rng.integers(1, 6))]
    n = int(rng.integers(1, 10))
    lay = PackedLayout(orders)
    m = lay.size
    s_blocks = [_sym(rng.normal(size=(k, k))) for k in orders]
    z_blocks = [_sym(rng.normal(size=(k, k))) for k in orders]
    x, cvec = rng.normal(size=n), rng.normal(size=n)
    g_mat, h_vec = rng.normal(size=(m, n)), rng.normal(size=m)
    # G dense: the sparse coefficients (used only when G has no rows) empty
    no_sparse = (np.zeros(len(orders) + 1, dtype=np.int64), *(np.zeros(0, dtype=np.int64),) * 2, np.zeros(0),
                 np.zeros(len(orders) + 1, dtype=np.int64), *(np.zeros(0, dtype=np.int64),) * 2)
    got = kernels.residuals(_padded(s_blocks), _padded(z_blocks), x, g_mat, h_vec, cvec, *lay.arrays,
                            *no_sparse)
    rd, rp, gap, pcost, dcost, n_rp, n_gx, n_sp, n_rd, n_gtz = got

    sp = np.concatenate([_packed_block(s) for s in s_blocks])
    zp = np.concatenate([_packed_block(z) for z in z_blocks])
    want_rd = g_mat.T @ zp + cvec
    want_rp = g_mat @ x + sp - h_vec
    assert np.all(np.abs(rd - want_rd) <= 2 * (m + 1) * EPS * (np.abs(g_mat).T @ np.abs(zp) + np.abs(cvec)))
    assert np.all(np.abs(rp - want_rp) <= 2 * (n + 2) * EPS * (
        np.abs(g_mat) @ np.abs(x) + np.abs(sp) + np.abs(h_vec)))
    trace_gap = sum(float(np.trace(s @ z)) for s, z in zip(s_blocks, z_blocks, strict=True))
    assert abs(gap - trace_gap) <= 2 * sum(k * k for k in orders) * EPS * float(np.abs(sp) @ np.abs(zp))
    assert abs(pcost - cvec @ x) <= 2 * n * EPS * float(np.abs(cvec) @ np.abs(x))
    assert abs(dcost + h_vec @ zp) <= 2 * m * EPS * float(np.abs(h_vec) @ np.abs(zp))
    for value, vec in ((n_rp, want_rp), (n_gx, g_mat @ x), (n_sp, sp), (n_rd, want_rd),
                       (n_gtz, g_mat.T @ zp)):
        assert value == pytest.approx(np.linalg.norm(vec), rel=1e-14)
