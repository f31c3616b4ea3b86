"""The Newton step's per-block kernels (:mod:`lmi.ipm.kernels.step`) against plain numpy.

* the products with ``P`` from the sparse coefficients (``P`` not formed: the blockwise and
  grouped formulas' path), ``P'v`` and ``P dx``, equal those with the ``P`` that
  :func:`lmi.ipm.kernels.scaling_and_schur_rows` forms, on blocks of different orders (the
  products share one work array between blocks, so a block of a smaller order after a larger
  one, and position pairs no coefficient uses, are covered), with the NT scalings padded with
  NaN outside each block's ``[:k, :k]`` so that a read outside it shows;
* the refinement's fused ``P dx + v`` and ``P'`` of it (:func:`~lmi.ipm.kernels.step._p_then_pt`)
  equal the separate products bit for bit;
* the Newton solve's iterative refinement (:func:`~lmi.ipm.kernels.step._newton`) stops at
  :data:`~lmi.ipm.kernels.step.REFINE_TARGET` of the reference scale: a solve whose dual equation
  already meets it is not refined, one that misses it is refined until it meets it; the C core
  uses the same target;
* the step length :func:`~lmi.ipm.kernels.step._max_step` (a Cholesky test of each shifted
  block first, the eigenvalue bisection only where it fails) equals the largest ``a <= 1/0.99``
  with ``diag(lambda) + a d >= 0`` computed from numpy's eigenvalues, when no block limits the
  step, when one does, and when several do.

Tolerances: the products add the same terms as ``P`` itself in another order (a few ``eps``
times the sum of magnitudes; the bound is 16 ``eps`` of it, measured worst 4.0 over 240 draws);
the step length is a lower bound found to ``rtol`` 1e-9 (the bound 4e-9 relative below, 64 ``eps``
above; measured 1.4e-9 below and never above over 400 draws).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import lmi.ccore
from lmi.ipm import BlockLMISolver, kernels
from lmi.ipm.kernels.step import _STEP_CAP, REFINE_TARGET, _max_step, _newton, _p_then_pt, _p_times, _pt_times

EPS = np.finfo(float).eps


def _sym(mat: np.ndarray) -> np.ndarray:
    return 0.5 * (mat + np.swapaxes(mat, -1, -2))


def _rand_pd(rng: np.random.Generator, k: int) -> np.ndarray:
    g = rng.normal(size=(k, k))
    return g @ g.T / k + 0.5 * np.eye(k)


def _padded(blocks: list[np.ndarray], fill: float = 0.0) -> np.ndarray:
    kmax = max(b.shape[0] for b in blocks)
    out = np.full((len(blocks), kmax, kmax), fill)
    for j, b in enumerate(blocks):
        out[j, :b.shape[0], :b.shape[0]] = b
    return out


def _problem(seed: int, orders: tuple[int, ...], n: int = 9, density: float = 0.3) -> BlockLMISolver:
    """A strictly feasible LMI problem with sparse coefficients on blocks of ``orders``; in the
    first block only the first row and column are used, so most position pairs are absent."""
    rng = np.random.default_rng(seed)
    x0 = rng.normal(size=n)
    blocks, c = [], np.zeros(n)
    for j, k in enumerate(orders):
        mask = np.triu(rng.random((n, k, k)) < density)
        coef = _sym(rng.normal(size=(n, k, k)) * (mask | np.swapaxes(mask, 1, 2)))
        if j == 0:
            coef[:, 1:, 1:] = 0.0
        coef[:, 0, 0] += 1.0
        blocks.append((np.einsum("i,ikl->kl", x0, coef) + _rand_pd(rng, k), coef))
        c += np.einsum("ikl,kl->i", coef, _rand_pd(rng, k))
    solver = BlockLMISolver(c, blocks)
    solver._refresh()
    return solver


def _nt_point(solver: BlockLMISolver, orders: tuple[int, ...],
              rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(K, lambda, P')`` by the rows formula at random ``S`` and ``Z`` of the blocks' orders,
    ``K`` padded with NaN outside each block's ``[:k, :k]``."""
    nb, kmax = len(orders), solver._kmax
    s_chol = _padded([np.linalg.cholesky(_rand_pd(rng, k)) for k in orders])
    z = _padded([_rand_pd(rng, k) for k in orders])
    kk, lam = np.full((nb, kmax, kmax), np.nan), np.zeros((nb, kmax))
    pt = np.zeros((solver.n, solver._layout.size))
    assert kernels.scaling_and_schur_rows(s_chol, z, *solver._layout.arrays, *solver._sparse, kk, lam, pt)
    return kk, lam, pt


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("orders", [(6, 9, 4, 9), (9, 3, 7, 2, 5)])
def test_products_with_p_from_the_sparse_coefficients_equal_the_formed_ones(seed, orders):
    """``P'v`` and ``P dx`` without ``P`` (``pt`` with no columns) against ``pt @ v`` and
    ``pt.T @ dx`` with ``P'`` formed by the rows formula at the same NT point: within 16 eps of
    the sums of magnitudes ``|P'| |v|`` and ``|P| |dx|`` (measured worst 1.1 and 4.0)."""
    solver = _problem(seed, orders)
    rng = np.random.default_rng(50 + seed)
    lay, sp, n = solver._layout, solver._sparse, solver.n
    kk, _, pt = _nt_point(solver, orders, rng)
    assert np.isnan(kk).any()  # the padding a product must not read
    none = np.zeros((n, 0))
    for _ in range(3):
        v, dx = rng.normal(size=lay.size), rng.normal(size=n)
        got = _pt_times(none, v, kk, *lay.arrays, *sp, n)
        assert np.all(np.abs(got - pt @ v) <= 16 * EPS * (np.abs(pt) @ np.abs(v)))
        got = _p_times(none, dx, kk, *lay.arrays, *sp)
        assert np.all(np.abs(got - pt.T @ dx) <= 16 * EPS * (np.abs(pt).T @ np.abs(dx)))
        # with P formed they are the products themselves
        assert np.array_equal(_pt_times(pt, v, kk, *lay.arrays, *sp, n), pt @ v)
        # the fused pass of the refinement: P dx + v and P' of it, bit for bit the separate calls
        dz, ptz = _p_then_pt(none, dx, v, kk, *lay.arrays, *sp, n)
        want = _p_times(none, dx, kk, *lay.arrays, *sp) + v
        assert np.array_equal(dz, want)
        assert np.array_equal(ptz, _pt_times(none, want, kk, *lay.arrays, *sp, n))


def _newton_case(seed: int):
    """``_newton``'s arguments at an NT point of :func:`_problem` with ``P`` formed, and a factor
    of ``H + 1e-6 diag(H)`` instead of ``H = P'P``: the first solve misses the dual equation by
    about 1e-6 relative, and each refinement step gains about six orders of magnitude."""
    orders = (6, 9, 4, 9)
    solver = _problem(seed, orders)
    rng = np.random.default_rng(70 + seed)
    lay, sp, n = solver._layout, solver._sparse, solver.n
    kk, _, pt = _nt_point(solver, orders, rng)
    h = pt @ pt.T
    r_fac = np.ascontiguousarray(np.linalg.cholesky(h + 1e-6 * np.diag(np.diag(h))).T)
    rd, rpt, u = rng.normal(size=n), rng.normal(size=lay.size), rng.normal(size=lay.size)

    def solve(ref_scale: float):
        return _newton(pt, r_fac, np.zeros(0, dtype=np.int64), rd, rpt, u, ref_scale, kk, *lay.arrays, sp)

    return solve, pt, rd


@pytest.mark.parametrize("seed", range(3))
def test_refinement_stops_at_the_target(seed):
    """With ``ref_scale = inf`` nothing is refined: the first solve and its residual ``e0``. A
    reference scale at which ``e0`` already meets ``REFINE_TARGET`` (twice the target: a margin
    for the product's rounding) returns that first solve bit for bit; one at which the target is
    ``e0 / 1000`` refines: the residual returned meets the target, and it is the exact equation's
    residual of the step returned (``P' dz~ + r_d`` recomputed from ``dx``: the step and its
    residual belong together)."""
    solve, pt, rd = _newton_case(seed)
    dx0, _, dz0, e0 = solve(np.inf)
    assert e0 > 1e-12  # the inexact factor leaves a residual to refine
    dx, _, dz, e = solve(2.0 * e0 / REFINE_TARGET)
    assert e == e0 and np.array_equal(dx, dx0) and np.array_equal(dz, dz0)
    ref_scale = 1e-3 * e0 / REFINE_TARGET
    dx, _, dz, e = solve(ref_scale)
    assert e <= REFINE_TARGET * ref_scale and e < 1e-3 * e0
    assert not np.array_equal(dx, dx0)
    assert abs(np.linalg.norm(pt @ dz + rd) - e) <= 1e-3 * e


def test_the_c_core_refines_to_the_same_target():
    """The C core (``lmi/ccore/ipm.c``) defines ``REFINE_TARGET`` as the numba kernels' value."""
    source = (Path(lmi.ccore.__file__).parent / "ipm.c").read_text()
    found = re.search(r"^#define REFINE_TARGET (\S+)", source, re.MULTILINE)
    assert found is not None, "ipm.c defines no REFINE_TARGET"
    assert float(found.group(1)) == REFINE_TARGET


def _reference_step(lam: np.ndarray, dirs: list[np.ndarray], orders: tuple[int, ...]) -> float:
    """The largest ``a <= _STEP_CAP`` with ``diag(lambda_j) + a d_j >= 0``, every block and
    direction, from numpy's eigenvalues of ``diag(lambda)^-1/2 d diag(lambda)^-1/2``."""
    alpha = _STEP_CAP
    for d in dirs:
        for j, k in enumerate(orders):
            isq = 1.0 / np.sqrt(lam[j, :k])
            low = np.linalg.eigvalsh(d[j] * np.outer(isq, isq))[0]
            if low < 0.0:
                alpha = min(alpha, -1.0 / low)
    return alpha


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("limiting", ["none", "one", "several"])
def test_step_length_equals_the_one_from_the_eigenvalues(seed, limiting):
    """:func:`_max_step` against :func:`_reference_step`: within 4e-9 relative below and never
    longer (to 64 eps). ``limiting``: no block limits the step below the cap (directions of norm
    0.1 in the scaled metric), one block does (its direction scaled up), or every block of the
    ``dz`` direction does, with steps from 0.05 to 0.9."""
    orders = (6, 9, 4, 9, 3)
    rng = np.random.default_rng(seed)
    solver = _problem(seed, orders)
    lay = solver._layout
    kmax = max(orders)
    lam = np.array([np.concatenate([np.sort(rng.uniform(0.5, 2.0, size=k)), np.full(kmax - k, np.nan)])
                    for k in orders])
    blocks = {"ds": [], "dz": []}
    for name in blocks:
        for j, k in enumerate(orders):
            d = _sym(rng.normal(size=(k, k)))
            d *= 0.1 / np.linalg.norm(d, 2)
            if limiting == "one" and name == "ds" and j == 2:
                d *= 30.0
            if limiting == "several" and name == "dz":
                d *= rng.uniform(1.5, 30.0)
            blocks[name].append(d * np.sqrt(np.outer(lam[j, :k], lam[j, :k])))
    ds = kernels.pack(_padded(blocks["ds"]), *lay.arrays)
    dz = kernels.pack(_padded(blocks["dz"]), *lay.arrays)
    want = _reference_step(lam, [blocks["ds"], blocks["dz"]], orders)
    got = _max_step(lam, ds, dz, *lay.arrays)
    if limiting == "none":
        assert got == _STEP_CAP
    else:
        assert want < 1.0
    assert want * (1.0 - 4e-9) <= got <= want * (1.0 + 64 * EPS)
