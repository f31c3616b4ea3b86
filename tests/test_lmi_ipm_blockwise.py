"""The blockwise Schur formula of the interior-point solver and its block-arrow factorisation.

* :func:`lmi.ipm.kernels.scaling_and_schur_blockwise` forms the lower triangle of the same
  ``H = P'P`` as the rows formula (``P'`` formed, one ``dsyrk``) and the same NT scaling, on
  problems whose blocks hold disjoint parts of the variables plus shared ones (as the vertex
  forms' blocks do);
* :func:`lmi.ipm.blocks.arrow_order` gives groups that no block couples, and
  :func:`lmi.ipm.kernels.lapack.arrow_cholesky` the Cholesky factor of ``H`` in that order
  (checked against LAPACK's dense factor of the permuted matrix, which is unique);
* the products with ``G`` from the sparse coefficients (``g_mat`` with no rows) equal the dense
  ones, and so does the per-block residual test;
* solves with the blockwise formula forced agree with the rows formula: status, objective and
  point, on random strictly feasible and dual strictly feasible problems, and on paper P's vertex
  form over 8 vertices (Wan & Kothare's parameter-dependent Lyapunov function), which takes the
  blockwise formula by itself.

Tolerances: the two formulas add the same products in a different order (``dsyrk`` over all
blocks against one per block), so they agree to a few ``eps`` times the sum of the magnitudes;
the bounds below are about 100 times the worst differences measured.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest
from scipy.linalg import cholesky

from lmi.ipm import BlockLMISolver, kernels
from lmi.ipm.blocks import BlockData, arrow_local, arrow_order, block_variables
from lmi.ipm.kernels.lapack import arrow_cholesky, schur_complement
from lmi.ipm.kernels.packed import g_times, gt_times

EPS = np.finfo(float).eps


@contextmanager
def formula(word: str) -> Iterator[None]:
    """Every solver built inside takes the Schur formula ``word``."""
    original = BlockData._choose_formula
    BlockData._choose_formula = lambda self: word  # type: ignore[method-assign]
    try:
        yield
    finally:
        BlockData._choose_formula = original  # type: ignore[method-assign]


def _sym(mat: np.ndarray) -> np.ndarray:
    return 0.5 * (mat + np.swapaxes(mat, -1, -2))


def _rand_pd(rng: np.random.Generator, k: int) -> np.ndarray:
    g = rng.normal(size=(k, k))
    return g @ g.T / k + 0.5 * np.eye(k)


def arrow_problem(seed: int, groups: int = 4, private: int = 7, shared: int = 5, k: int = 6,
                  density: float = 0.4) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """``min c'x, C_j - sum_i x_i A_ij >= 0`` with two blocks per group, each holding the group's
    ``private`` variables and the ``shared`` ones (sparse coefficients), and one block holding
    the shared ones only; strictly feasible (``C_j`` from a point ``x0`` plus a definite part)
    and dual strictly feasible (``c_i = sum_j <A_ij, Z0_j>``), so the optimum is attained."""
    rng = np.random.default_rng(seed)
    n = groups * private + shared
    shared_vars = list(range(groups * private, n))
    holders = []
    for g in range(groups):
        own = list(range(g * private, (g + 1) * private))
        holders += [own + shared_vars, own + shared_vars]
    holders.append(shared_vars)
    x0 = rng.normal(size=n)
    blocks, c = [], np.zeros(n)
    for held in holders:
        coef = np.zeros((n, k, k))
        for i in held:
            mask = rng.random((k, k)) < density
            coef[i] = _sym(rng.normal(size=(k, k)) * (mask | mask.T))
            coef[i][0, 0] += 1.0  # every held variable appears
        const = np.einsum("i,ikl->kl", x0, coef) + _rand_pd(rng, k)
        z0 = _rand_pd(rng, k)
        c += np.einsum("ikl,kl->i", coef, z0)
        blocks.append((const, coef))
    return c, blocks


def refreshed(c: np.ndarray, blocks: list) -> BlockLMISolver:
    solver = BlockLMISolver(c, blocks)
    solver._refresh()
    return solver


def _padded(blocks: list[np.ndarray]) -> np.ndarray:
    kmax = max(b.shape[0] for b in blocks)
    out = np.zeros((len(blocks), kmax, kmax))
    for j, b in enumerate(blocks):
        out[j, :b.shape[0], :b.shape[0]] = b
    return out


@pytest.mark.parametrize("seed", range(4))
def test_blockwise_schur_equals_the_rows_formula(seed):
    """``H`` block by block equals ``P'P`` from the formed ``P`` (and the NT scalings are the same
    arithmetic): worst measured ``|H_blockwise - H_rows|`` 2e-16 of ``|P|'|P|``."""
    c, blocks = arrow_problem(seed)
    rng = np.random.default_rng(100 + seed)
    shuffle = rng.permutation(c.size)  # the shared variables among the private ones
    c, blocks = c[shuffle], [(const, coef[shuffle]) for const, coef in blocks]
    solver = refreshed(c, blocks)
    orders = solver.block_orders
    s_chol = _padded([np.linalg.cholesky(_rand_pd(rng, k)) for k in orders])
    z = _padded([_rand_pd(rng, k) for k in orders])
    lay, sp = solver._layout, solver._sparse
    nb, kmax, n = len(orders), solver._kmax, solver.n
    kk_rows, lam_rows = np.zeros((nb, kmax, kmax)), np.zeros((nb, kmax))
    pt, h_rows = np.zeros((n, lay.size)), np.zeros((n, n))
    assert kernels.scaling_and_schur_rows(s_chol, z, *lay.arrays, *sp, kk_rows, lam_rows, pt)
    schur_complement(pt, h_rows)
    kk, lam, h = np.zeros_like(kk_rows), np.zeros_like(lam_rows), np.full((n, n), np.nan)
    work = solver._workspace()
    given_order = arrow_local(solver._blockvars, sp[0], np.arange(n))
    assert kernels.scaling_and_schur_blockwise(s_chol, z, lay.orders, sp[0], *sp[2:], solver._blockvars[0],
                                               *given_order, kk, lam, work[9], work[10], h)
    np.testing.assert_array_equal(kk, kk_rows)
    np.testing.assert_array_equal(lam, lam_rows)
    lower = np.tril(np.ones((n, n), dtype=bool))
    assert np.all(np.isnan(h[~lower]))  # the lower triangle only: the strict upper one not written
    scale = np.abs(pt) @ np.abs(pt).T
    assert np.all(np.abs(h - h_rows)[lower] <= 64 * EPS * scale[lower])
    # the block structure is real: entries between two groups' private variables are exactly 0
    first, last = np.argsort(shuffle)[[0, n - 6]]  # variables 0 and n - 6 before the shuffle
    assert h[max(first, last), min(first, last)] == 0.0 and h_rows[first, last] == 0.0
    # given the variables' positions in the arrow order (ascending per block), H[perm][:, perm]
    # lands in the lower triangle
    perm = solver._arrow[0]
    assert not np.array_equal(perm, np.arange(n))
    h_perm = np.full((n, n), np.nan)
    assert kernels.scaling_and_schur_blockwise(s_chol, z, lay.orders, sp[0], *sp[2:],
                                               solver._blockvars[0], *solver._arrow_local, kk, lam,
                                               work[9], work[10], h_perm)
    assert np.all(np.isnan(h_perm[~lower]))
    want = h_rows[perm][:, perm]
    assert np.all(np.abs(h_perm - want)[lower] <= 64 * EPS * scale[perm][:, perm][lower])


def test_block_variables_and_the_arrow_order_of_a_vertex_like_problem():
    """Each block's own variables are those its coefficients hold; the arrow order takes the four
    groups of private variables as groups (no block holds two of them) and the shared ones as
    the border."""
    c, blocks = arrow_problem(0, groups=4, private=7, shared=5)
    solver = refreshed(c, blocks)
    bv_off, bv_var, sp_loc = solver._blockvars
    for j, (_, coef) in enumerate(blocks):
        held = np.flatnonzero(np.any(coef != 0.0, axis=(1, 2)))
        np.testing.assert_array_equal(bv_var[bv_off[j]:bv_off[j + 1]], held)
    sp_off, sp_var = solver._sparse[0], solver._sparse[1]
    for j in range(len(blocks)):
        lo, hi = sp_off[j], sp_off[j + 1]
        np.testing.assert_array_equal(bv_var[bv_off[j] + sp_loc[lo:hi]], sp_var[lo:hi])
    perm, grp_off = solver._arrow
    assert sorted(perm.tolist()) == list(range(solver.n))
    groups = [set(perm[grp_off[g]:grp_off[g + 1]].tolist()) for g in range(len(grp_off) - 1)]
    assert sorted(map(sorted, groups)) == [list(range(7 * g, 7 * g + 7)) for g in range(4)]
    assert set(perm[grp_off[-1]:].tolist()) == set(range(28, 33))


def test_arrow_local_positions_ascend_and_their_runs_cover_them():
    """On random structures (a block may hold no variable) and a random order: each block's
    positions ascend, each entry's place maps back to its variable, and the runs ``(first,
    position, length)`` are maximal and give every position exactly once."""
    rng = np.random.default_rng(7)
    for _ in range(50):
        n, nb = int(rng.integers(2, 30)), int(rng.integers(1, 12))
        held = [np.sort(rng.choice(n, size=int(rng.integers(0, n + 1)), replace=False)) for _ in range(nb)]
        sp_off = np.cumsum([0, *(3 * h.size for h in held)]).astype(np.int64)
        sp_var = np.concatenate([rng.permutation(np.repeat(h, 3)) for h in held]).astype(np.int64)
        blockvars = block_variables((sp_off, sp_var))
        perm = rng.permutation(n).astype(np.int64)
        position = np.argsort(perm)
        bv_pos, loc, run_off, runs = arrow_local(blockvars, sp_off, perm)
        bv_off = blockvars[0]
        for j in range(nb):
            own = bv_pos[bv_off[j]:bv_off[j + 1]]
            assert np.all(np.diff(own) > 0)
            entries = slice(sp_off[j], sp_off[j + 1])
            np.testing.assert_array_equal(own[loc[entries]], position[sp_var[entries]])
            rebuilt = []
            for first, pos, length in runs[run_off[j]:run_off[j + 1]]:
                assert len(rebuilt) == first and length >= 1
                rebuilt.extend(range(pos, pos + length))
            np.testing.assert_array_equal(rebuilt, own)
            starts = runs[run_off[j]:run_off[j + 1], 1]
            ends = starts + runs[run_off[j]:run_off[j + 1], 2]
            assert np.all(starts[1:] > ends[:-1])  # maximal: no run continues the one before


def test_arrow_order_never_groups_two_classes_a_block_couples():
    """On random structures (blocks holding random subsets), no block holds variables of two
    different groups: the factor's zero blocks between groups are exact."""
    rng = np.random.default_rng(5)
    for _ in range(50):
        n, nb = int(rng.integers(2, 30)), int(rng.integers(1, 12))
        held = [np.sort(rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False)) for _ in range(nb)]
        sp_off = np.cumsum([0, *(h.size for h in held)]).astype(np.int64)
        blockvars = block_variables((sp_off, np.concatenate(held).astype(np.int64)))
        perm, grp_off = arrow_order(blockvars, n)
        assert sorted(perm.tolist()) == list(range(n))
        group_of = np.full(n, -1)
        for g in range(len(grp_off) - 1):
            group_of[perm[grp_off[g]:grp_off[g + 1]]] = g
        for h in held:
            in_groups = set(group_of[h].tolist()) - {-1}
            assert len(in_groups) <= 1


def test_arrow_order_keeps_no_group_when_elimination_saves_little():
    """One small group beside a large border (a vertex-pair form's structure: every pair block
    couples two vertices' matrices) gives the given order and no group (one dense factor); the
    vertex-like structure keeps its groups."""
    n = 40
    held = [np.r_[8 * g: 8 * g + 8, 32:40] for g in range(4)]  # 4 groups of 8, a border of 8
    sp_off = np.cumsum([0, *(h.size for h in held)]).astype(np.int64)
    blockvars = block_variables((sp_off, np.concatenate(held).astype(np.int64)))
    perm, grp_off = arrow_order(blockvars, n)
    assert list(np.diff(grp_off)) == [8, 8, 8, 8]
    held = [np.arange(0, 2), np.arange(0, n)]  # the 2 private ones beside a border of 38
    sp_off = np.cumsum([0, *(h.size for h in held)]).astype(np.int64)
    blockvars = block_variables((sp_off, np.concatenate(held).astype(np.int64)))
    perm, grp_off = arrow_order(blockvars, n)
    np.testing.assert_array_equal(perm, np.arange(n))
    np.testing.assert_array_equal(grp_off, [0])


@pytest.mark.parametrize("seed", range(3))
def test_arrow_cholesky_is_the_cholesky_factor_of_the_permuted_matrix(seed):
    """``R`` equals LAPACK's upper Cholesky factor of ``H_p = H[perm][:, perm]`` (unique for a
    definite matrix) to 1e-12 relative (measured 2e-15), with exact zeros between groups; an
    indefinite ``H_p`` is reported (non-zero return). The blockwise kernel forms ``H_p`` itself when
    given the variables' positions in that order."""
    c, blocks = arrow_problem(seed)
    solver = refreshed(c, blocks)
    perm, grp_off = solver._arrow
    g = solver._g_mat
    h = g.T @ g + 1e-3 * np.eye(solver.n)
    hp = h[perm][:, perm]
    want = cholesky(hp, lower=False)
    hp[np.triu_indices_from(hp, 1)] = np.nan  # only the lower triangle is read
    r = np.full_like(h, np.nan)
    work = np.full_like(h, np.nan)  # the workspace's old contents are not read
    kept = hp.copy()
    assert arrow_cholesky(hp, grp_off, r, work) == 0
    assert np.max(np.abs(r - want)) <= 1e-12 * np.max(np.abs(want))
    np.testing.assert_array_equal(hp, kept)  # left as it is (the pivot test reads its diagonal)
    for a in range(len(grp_off) - 1):
        for b in range(a + 1, len(grp_off) - 1):
            assert np.all(r[grp_off[a]:grp_off[a + 1], grp_off[b]:grp_off[b + 1]] == 0.0)
    bad = hp.copy()
    bad[-1, -1] = -1.0  # a border pivot
    assert arrow_cholesky(bad, grp_off, r, work) != 0
    bad = hp.copy()
    bad[0, 0] = -1.0  # a group's pivot
    assert arrow_cholesky(bad, grp_off, r, work) != 0


@pytest.mark.parametrize("seed", range(2))
def test_arrow_cholesky_without_groups_is_dpotrf_of_the_whole_matrix_bit_for_bit(seed):
    """With no group (every variable in the border, as in the vertex-pair forms) the factor is
    ``cholesky_upper``'s of the whole symmetric matrix bit for bit, from its lower triangle alone
    (the upper one NaN, the workspace NaN), and the matrix is left as it is."""
    from lmi.ipm.kernels.lapack import cholesky_upper

    rng = np.random.default_rng(seed)
    n = 70
    h = _rand_pd(rng, n) * rng.uniform(0.5, 2.0)
    want = np.zeros((n, n))
    assert cholesky_upper(h, np.zeros((n, n)), want) == 0
    lower = h.copy()
    lower[np.triu_indices(n, 1)] = np.nan
    kept = lower.copy()
    r, work = np.full((n, n), np.nan), np.full((n, n), np.nan)
    assert arrow_cholesky(lower, np.zeros(1, dtype=np.int64), r, work) == 0
    assert np.array_equal(r, want)
    np.testing.assert_array_equal(lower, kept)


@pytest.mark.parametrize("seed", range(3))
def test_products_with_g_from_the_sparse_coefficients_equal_the_dense_ones(seed):
    """``G x``, ``G'v`` and the per-block residual test with ``G`` not formed equal those with
    the dense ``G`` (to 1e-14 of the sum of magnitudes)."""
    c, blocks = arrow_problem(seed)
    solver = refreshed(c, blocks)
    lay, sp, g = solver._layout, solver._sparse, solver._g_mat
    none = np.zeros((0, solver.n))
    rng = np.random.default_rng(seed)
    x, v = rng.normal(size=solver.n), rng.normal(size=lay.size)
    gx = g_times(none, x, lay.orders, lay.offsets, lay.ent_w, *sp)
    assert np.all(np.abs(gx - g @ x) <= 1e-14 * (np.abs(g) @ np.abs(x)))
    gtv = gt_times(none, v, solver.n, lay.orders, lay.offsets, lay.ent_w, *sp)
    assert np.all(np.abs(gtv - g.T @ v) <= 1e-14 * (np.abs(g).T @ np.abs(v)))
    s = _padded([_rand_pd(rng, k) for k in solver.block_orders])
    rp = rng.normal(size=lay.size)
    for tol in (1e-3, 1e-1, 1.0, 10.0, 100.0):
        dense = kernels.blocks_within(s, x, rp, g, solver._h_vec, tol, *lay.arrays, *sp)
        sparse = kernels.blocks_within(s, x, rp, none, solver._h_vec, tol, *lay.arrays, *sp)
        assert dense == sparse


@pytest.mark.parametrize("seed", range(5))
def test_solves_with_the_blockwise_formula_agree_with_the_rows_formula(seed, caplog):
    """The same problem solved with each formula forced: both ``"optimal"``, objectives equal to
    1e-7 relative, points to 1e-5 of their norm (measured 1e-10 and 1e-8), the iterations within
    one, every blockwise step from the Cholesky factor (none in the QR phase). The variables are
    shuffled, so the arrow order differs from the given one."""
    c, blocks = arrow_problem(seed)
    shuffle = np.random.default_rng(200 + seed).permutation(c.size)
    c, blocks = c[shuffle], [(const, coef[shuffle]) for const, coef in blocks]
    with formula("rows"):
        rows = BlockLMISolver(c, blocks).solve()
    with formula("blockwise"), caplog.at_level(logging.DEBUG, logger="lmi.ipm.solver"):
        solver = BlockLMISolver(c, blocks)
        blockwise = solver.solve()
    # every step from the block-arrow factor (a wrong factor sends the steps to the QR phase)
    steps = [r.getMessage() for r in caplog.records if "alpha_aff" in r.getMessage()]
    assert steps and not any("qr True" in m for m in steps)
    assert abs(blockwise.iterations - rows.iterations) <= 1
    assert solver._formula == "blockwise"
    assert not np.array_equal(solver._arrow[0], np.arange(c.size))
    assert rows.status == blockwise.status == "optimal"
    scale = max(1.0, abs(rows.primal_objective))
    assert abs(rows.primal_objective - blockwise.primal_objective) <= 1e-7 * scale
    assert np.linalg.norm(rows.x - blockwise.x) <= 1e-5 * max(1.0, np.linalg.norm(rows.x))


def test_paper_p_vertex_form_takes_the_blockwise_formula_and_agrees_with_rows():
    """Wan & Kothare's vertex Lyapunov form on paper P's satellite over 8 vertices (244
    variables) takes the blockwise formula; its answer at the start state equals the rows
    formula's: gamma to 1e-7 relative, both certified."""
    from benchmarks.suites.methods_problems import build_problem
    from rmpc import RMPC

    p = build_problem("paper_p_8v")
    answers = {}
    for word in ("auto", "rows"):
        with formula(word) if word != "auto" else _unchanged():
            ctrl = RMPC(p.plant, p.Q, p.R, u_max=p.u_max, input_constraint=p.input_constraint,
                        backend="ipm", lyapunov="vertex")
            sol = ctrl.problem.solve(p.x0)
        solvers = [s for s in ctrl.problem._solvers.values() if isinstance(s, BlockLMISolver)]
        assert solvers
        answers[word] = (sol, {s._formula for s in solvers})
    auto, rows = answers["auto"][0], answers["rows"][0]
    assert answers["auto"][1] == {"blockwise"}
    assert auto.status == rows.status == "optimal"
    assert auto.certificate is not None and auto.certificate.ok
    assert abs(auto.gamma - rows.gamma) <= 1e-7 * abs(rows.gamma)


@contextmanager
def _unchanged() -> Iterator[None]:
    yield


def _block_gram_reference(kk, j, k, pair_off, pair_row, pair_col, sp_off, sp_loc, sp_pair, sp_val, nj):
    """``_block_gram`` entry by entry in numpy: ``M`` by its formula (each entry once, mirrored),
    then one entry of ``V`` at a time into ``U'`` and into ``V'U``'s lower triangle."""
    kj = np.ascontiguousarray(kk[j, :k, :k])
    w = kj.T @ kj
    first, p = pair_off[j], pair_off[j + 1] - pair_off[j]
    gram = np.zeros((p, p))
    for q in range(p):
        a, c = pair_row[first + q], pair_col[first + q]
        hq = 0.5 if a == c else 1.0
        for r in range(q, p):
            b, d = pair_row[first + r], pair_col[first + r]
            hr = 0.5 if b == d else 1.0
            gram[q, r] = gram[r, q] = 2.0 * hq * hr * (w[c, b] * w[a, d] + w[c, d] * w[a, b])
    ut = np.zeros((nj, p))
    for e in range(sp_off[j], sp_off[j + 1]):
        ut[sp_loc[e]] += sp_val[e] * gram[sp_pair[e] - first]
    u = np.ascontiguousarray(ut.T)
    hj = np.zeros((nj, nj))
    for e in range(sp_off[j], sp_off[j + 1]):
        i = sp_loc[e]
        hj[i, : i + 1] += sp_val[e] * u[sp_pair[e] - first, : i + 1]
    return np.tril(hj), p


@pytest.mark.parametrize(("density", "k"), [(0.4, 6), (0.08, 9)])
def test_block_gram_is_the_entry_by_entry_formula_bit_for_bit(density, k):
    """Each block's ``P_j'P_j`` (``_block_gram``: the Gram matrix row by row with its lower triangle
    mirrored, a variable's entries added four at a time) equals the entry-by-entry formula bit
    for bit: blocks whose position pairs are the whole upper triangle (the contiguous runs) and
    blocks with some positions unused (the pair lists)."""
    from lmi.ipm.kernels.schur import _block_gram

    c, blocks = arrow_problem(7, private=9, k=k, density=density)
    solver = refreshed(c, blocks)
    rng = np.random.default_rng(8)
    orders = solver.block_orders
    s_chol = _padded([np.linalg.cholesky(_rand_pd(rng, kj)) for kj in orders])
    z = _padded([_rand_pd(rng, kj) for kj in orders])
    lay, sp = solver._layout, solver._sparse
    nb, kmax, n = len(orders), solver._kmax, solver.n
    kk, lam, pt = np.zeros((nb, kmax, kmax)), np.zeros((nb, kmax)), np.zeros((n, lay.size))
    assert kernels.scaling_and_schur_rows(s_chol, z, *lay.arrays, *sp, kk, lam, pt)
    sp_off, _, sp_pair, sp_val, pair_off, pair_row, pair_col = sp
    bv_off = solver._blockvars[0]
    sp_loc = arrow_local(solver._blockvars, sp_off, np.arange(n))[1]
    work = solver._workspace()
    complete = []
    for j in range(nb):
        nj = bv_off[j + 1] - bv_off[j]
        want, p = _block_gram_reference(kk, j, orders[j], pair_off, pair_row, pair_col, sp_off, sp_loc,
                                        sp_pair, sp_val, nj)
        hj = np.full((nj, nj), np.nan)
        _block_gram(kk, j, orders[j], pair_off, pair_row, pair_col, sp_off, sp_loc, sp_pair, sp_val, nj,
                    work[9], hj)
        assert np.array_equal(np.tril(hj), want), j
        complete.append(p == orders[j] * (orders[j] + 1) // 2)
    assert any(complete) if density > 0.2 else not all(complete)
