"""Public LMI benchmarks: SDPLIB's control2-4 solved by :class:`lmi.ipm.BlockLMISolver`.

The references come from outside the toolkit: the optima SDPLIB publishes (B. Borchers,
"SDPLIB 1.2", 1999; ``tests/data/sdplib/README.md``), and the LMIs themselves, recomputed here from
the returned ``x`` on the data as read. The file also checks the two changes that made these
problems solvable: the block weights (:func:`lmi.ipm.blocks.block_weights`; the outputs stay in
the units of the data as given, also for an infeasible problem and phase one) and the stall rule
(:data:`lmi.ipm.solver.STALL_WINDOW`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from lmi.affine import svec_matrix
from lmi.infeasibility import check_farkas
from lmi.ipm import BlockLMISolver
from lmi.ipm import blocks as ipm_blocks
from lmi.ipm.blocks import BLOCK_WEIGHT_SPREAD, block_weights
from lmi.ipm.solver import INFEASIBILITY_RADIUS
from lmi.sdpa import read_sdpa
from lmi.threads import SingleThreadBlas

DATA = Path(__file__).resolve().parent / "data" / "sdplib"
#: SDPLIB 1.2's published optima (SDPA's ``c'x``), given to 7 significant digits.
PUBLISHED = {"control2": 8.300000, "control3": 13.63327, "control4": 19.79423}


@pytest.fixture(scope="module", autouse=True)
def one_blas_thread():
    """Solve on one BLAS thread: OpenBLAS's threads on a loaded 2-core machine made this file take
    53 s instead of 3 s (measured)."""
    with SingleThreadBlas().limit():
        yield


@pytest.fixture(scope="module")
def problems():
    return {name: read_sdpa(DATA / f"{name}.dat-s.gz") for name in PUBLISHED}


@pytest.fixture(scope="module")
def solved(problems):
    out = {}
    for name, (c, blocks) in problems.items():
        slv = BlockLMISolver(c, blocks)
        out[name] = (slv, slv.solve())
    return out


def _rel_min_eig(mat: np.ndarray) -> float:
    lam = np.linalg.eigvalsh(0.5 * (mat + mat.T))
    return float(lam[0] / max(float(np.max(np.abs(lam))), np.finfo(float).tiny))


def _slacks(blocks, x):
    return [const - np.einsum("i,ikl->kl", x, coef) for const, coef in blocks]


# -- the public problems --------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_control_problem_is_solved_to_its_published_optimum(name, problems, solved):
    """"optimal", ``c'x`` within 1e-6 relative of SDPLIB's value, and every LMI holds at the returned
    ``x`` (recomputed from the data as read).

    Measured: relative errors of 8.9e-10, 2.8e-7 and 2.0e-8; the published values carry 7
    digits, a rounding of up to 3.7e-7 relative (control3), and 1e-6 leaves a factor 2.7 above
    that. The smallest relative eigenvalues of the recomputed slacks were +8e-16..+2e-15 (the
    iterate is interior), far above the -1e-7 asked."""
    c, blocks = problems[name]
    _, res = solved[name]
    assert res.status == "optimal"
    objective = float(c @ res.x)
    assert abs(objective - PUBLISHED[name]) <= 1e-6 * PUBLISHED[name]
    assert objective == pytest.approx(res.primal_objective, rel=1e-12)
    assert min(_rel_min_eig(s) for s in _slacks(blocks, res.x)) >= -1e-7


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_control_problem_returns_a_dual_point_of_the_data_as_given(name, problems, solved):
    """``Z`` is a dual point of the original blocks (not of the weighted ones the kernels see):
    positive semidefinite, ``c_i + sum_j <A_ij, Z_j> = 0`` and the duality gap closes. Measured:
    dual residuals of 1.3e-10..3.8e-10 relative to ``||c||`` (the test asks 1e-8), gaps of
    2.2e-9..3.3e-9 relative (the solver's own tolerance, 1e-8, asked)."""
    c, blocks = problems[name]
    _, res = solved[name]
    for z in res.Z:
        assert _rel_min_eig(z) >= -1e-12
    a_z = sum(np.einsum("ikl,kl->i", coef, z) for (_, coef), z in zip(blocks, res.Z, strict=True))
    assert np.linalg.norm(c + a_z) <= 1e-8 * np.linalg.norm(c)
    dual = -sum(float(np.sum(const * z)) for (const, _), z in zip(blocks, res.Z, strict=True))
    assert dual == pytest.approx(res.dual_objective, rel=1e-9)
    assert abs(float(c @ res.x) - dual) <= 1e-8 * abs(dual)


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_control_problem_slacks_are_returned_in_the_units_of_the_data(name, problems, solved):
    """The returned ``S_j`` equal ``C_j - sum_i x_i A_ij`` recomputed from ``x`` (the blocks are
    weighted inside the solver: control2-4's weights span 256-512). Measured: differences of at
    most 1.2e-15 relative to each block's largest entry; the test asks 1e-12."""
    _, blocks = problems[name]
    slv, res = solved[name]
    assert float(np.max(slv.block_weights)) / float(np.min(slv.block_weights)) >= BLOCK_WEIGHT_SPREAD
    for got, want in zip(res.S, _slacks(blocks, res.x), strict=True):
        assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want))


# -- block weights --------------------------------------------------------------------------------
def test_block_weights_balance_badly_scaled_blocks(problems):
    """control2's Lyapunov block has coefficients ~100 times those of ``P >= I``: it gets the
    smaller weight, a power of two, and the largest weight is 1."""
    _, blocks = problems["control2"]
    w = block_weights([coef for _, coef in blocks])
    assert w[1] == 1.0 and w[0] < 1.0 / BLOCK_WEIGHT_SPREAD
    assert np.array_equal(w, np.exp2(np.round(np.log2(w))))


def test_block_weights_leave_balanced_blocks_alone():
    """Below :data:`BLOCK_WEIGHT_SPREAD` nothing is weighted (paper P's blocks span about 2)."""
    rng = np.random.default_rng(0)
    coefs = [rng.normal(size=(4, 3, 3)), 10.0 * rng.normal(size=(4, 5, 5))]
    coefs = [0.5 * (a + np.swapaxes(a, 1, 2)) for a in coefs]
    assert np.array_equal(block_weights(coefs), np.ones(2))
    coefs[1] *= 1e3
    assert not np.array_equal(block_weights(coefs), np.ones(2))


def test_weights_make_control_problems_take_fewer_iterations(problems, solved, monkeypatch):
    """The reason for the weights: unweighted, control2-4 take 40/45/44 iterations, weighted
    29/32/34 (measured); both end optimal at the same objective (1e-7 relative)."""
    monkeypatch.setattr(ipm_blocks, "BLOCK_WEIGHT_SPREAD", np.inf)
    for name, (c, blocks) in problems.items():
        plain_slv = BlockLMISolver(c, blocks)
        plain = plain_slv.solve()
        assert np.array_equal(plain_slv.block_weights, np.ones(len(blocks)))
        weighted = solved[name][1]
        assert plain.status == weighted.status == "optimal"
        assert weighted.iterations < plain.iterations
        assert weighted.primal_objective == pytest.approx(plain.primal_objective, rel=1e-7)


def test_vertex_copies_get_equal_weights_and_stay_one_group():
    """Blocks given in factored form with equal entries (a Kothare problem's vertex blocks) but
    different dictionaries have coefficients of different size; they must get one weight, or
    the kernels could no longer sum them as one group (:func:`lmi.ipm.blocks.factor_groups`)."""
    rng = np.random.default_rng(3)
    n, k = 6, 4
    var = np.repeat(np.arange(n), 3)
    p = rng.integers(0, k, size=var.size)
    q = np.maximum(p, rng.integers(0, k, size=var.size))
    val = rng.normal(size=var.size)
    blocks, factors = [], []
    for scale in (1.0, 8.0, 64.0):  # three vertex copies, dictionaries scaled apart
        dmat = scale * (np.eye(k) + 0.1 * rng.normal(size=(k, k)))
        nmat = np.zeros((n, k, k))
        np.add.at(nmat, (var, p, q), val)
        np.add.at(nmat, (var[p != q], q[p != q], p[p != q]), val[p != q])
        coef = dmat @ nmat @ dmat.T
        blocks.append((100.0 * np.eye(k) * scale**2, coef))
        factors.append((dmat, var, p, q, val))
    blocks.append((np.eye(n), np.stack([np.diag(e) for e in np.eye(n)])))  # x_i <= 1
    factors.append(None)
    slv = BlockLMISolver(np.ones(n), blocks, factors=factors)
    res = slv.solve()
    w = slv.block_weights
    assert len(set(w.tolist())) > 1  # weighted at all
    assert w[0] == w[1] == w[2]
    assert sorted(np.diff(slv._groups[0]).tolist()) == [1, 3]
    assert res.status == "optimal"


def _weighted_infeasible_blocks():
    """``P >= I`` and ``P - A'PA >= I`` with ``A`` unstable (no ``P``), the second LMI scaled by
    1e4 so that the blocks are weighted."""
    a = np.array([[1.2, 0.3], [0.0, 0.5]])
    basis = [np.array([[1.0, 0.0], [0.0, 0.0]]), np.array([[0.0, 1.0], [1.0, 0.0]]),
             np.array([[0.0, 0.0], [0.0, 1.0]])]
    return [(-np.eye(2), -np.array(basis)),
            (-1e4 * np.eye(2), -1e4 * np.array([e - a.T @ e @ a for e in basis]))]


def _conic_check(blocks, z_blocks):
    """:func:`lmi.infeasibility.check_farkas` on the data as given (``b = svec C``, columns
    ``svec A_i``)."""
    b = np.concatenate([svec_matrix(const) for const, _ in blocks])
    a_mat = np.concatenate([np.stack([svec_matrix(a) for a in coef], axis=1) for _, coef in blocks])
    y = np.concatenate([svec_matrix(0.5 * (z + z.T)) for z in z_blocks])
    return check_farkas(a_mat, b, [("psd", const.shape[0]) for const, _ in blocks], y)


def test_an_infeasible_weighted_problem_returns_a_ray_of_the_data_as_given():
    """The Farkas ray of an ``"infeasible"`` result is in the original units: it passes the
    independent conic check on the data as given, and the radius it proves there is the one
    reported (agreement measured: 2e-9 relative)."""
    blocks = _weighted_infeasible_blocks()
    slv = BlockLMISolver(np.ones(3), blocks)
    res = slv.solve()
    assert not np.array_equal(slv.block_weights, np.ones(2))
    assert res.status == "infeasible"
    assert np.sqrt(sum(float(np.sum(z * z)) for z in res.Z)) == pytest.approx(1.0, rel=1e-12)
    cert = _conic_check(blocks, res.Z)
    assert cert.ok and cert.min_eigenvalue >= 0.0
    objective = sum(float(np.sum(c * z)) for (c, _), z in zip(blocks, res.Z, strict=True))
    a_z = sum(np.einsum("ikl,kl->i", a, z) for (_, a), z in zip(blocks, res.Z, strict=True))
    radius = -objective / float(np.linalg.norm(a_z))
    assert radius >= INFEASIBILITY_RADIUS
    assert res.infeasibility_radius == pytest.approx(radius, rel=1e-6)


def test_phase_one_certificate_of_a_weighted_problem_is_in_the_units_of_the_data():
    """Phase one's certificate (``Z``, its objective and residual) refers to the data as given.
    Phase one runs in the solver's weighted units: its auxiliary solver carries the solver's
    weights (with a block of constant data added, that solver's own balancing would give
    different ones, measured: 0.25, 3.1e-5 and 1 instead of 1, 1.2e-4 and 1)."""
    blocks = [*_weighted_infeasible_blocks(), (np.eye(2), np.zeros((3, 2, 2)))]
    slv = BlockLMISolver(np.ones(3), blocks)
    res = slv.phase_one()
    assert not np.array_equal(slv.block_weights, np.ones(3))
    assert np.array_equal(slv._phase_one_solver.block_weights, slv.block_weights)
    assert res.status == "infeasible"
    assert _conic_check(blocks, res.Z).ok
    objective = sum(float(np.sum(c * z)) for (c, _), z in zip(blocks, res.Z, strict=True))
    assert res.objective == pytest.approx(objective, rel=1e-9)
    a_z = sum(np.einsum("ikl,kl->i", a, z) for (_, a), z in zip(blocks, res.Z, strict=True))
    a_norm = np.sqrt(sum(np.einsum("ikl,ikl->i", a, a) for _, a in blocks))
    z_norm = np.sqrt(sum(float(np.sum(z * z)) for z in res.Z))
    want = float(np.max(np.abs(a_z) / a_norm)) / z_norm
    assert res.residual == pytest.approx(want, rel=1e-6, abs=0.0)


def test_phase_one_of_a_weighted_feasible_problem_finds_a_point_of_the_data_as_given(problems):
    """Phase one on control2-4 (weighted) returns an ``x`` strictly inside every original LMI,
    within 3 iterations (measured: 3, 3 and 2; with phase one's ``t`` given the coefficient
    ``-I`` of the original blocks instead of ``-I`` in the weighted ones, 3, 5 and 6)."""
    for c, blocks in problems.values():
        res = BlockLMISolver(c, blocks).phase_one()
        assert res.status == "feasible" and res.iterations <= 3
        for s in _slacks(blocks, res.x):
            np.linalg.cholesky(s)


# -- the stall rule -------------------------------------------------------------------------------
def test_a_run_that_converges_again_after_a_stall_is_not_cut(problems, monkeypatch):
    """control3 without weights: its merit (worst of the relative residuals and gap) stalls from
    iteration 16 to 33 while the objective falls from 220 to 17 (the relative gap stays near 0.5
    as gap and objective fall together); the dual iterate grows meanwhile, so the run goes on for
    an infeasibility proof. Before the fix it ended there, "insufficient_progress" at c'x = 220.5,
    when that growth stopped (iteration 44), although the merit was halving again; now the
    run is back under the ordinary rules and ends optimal."""
    monkeypatch.setattr(ipm_blocks, "BLOCK_WEIGHT_SPREAD", np.inf)
    c, blocks = problems["control3"]
    res = BlockLMISolver(c, blocks).solve()
    assert res.status == "optimal"
    assert abs(res.primal_objective - PUBLISHED["control3"]) <= 1e-6 * PUBLISHED["control3"]


# -- blocks of very different scale ---------------------------------------------------------------
def _scaled_control2(problems, exponent: int):
    """control2 with its second block (constant and coefficients) multiplied by ``10**exponent``:
    the same feasible set and optimum, 8.3."""
    c, blocks = problems["control2"]
    scale = 10.0**exponent
    return c, [blocks[0], (blocks[1][0] * scale, blocks[1][1] * scale)]


def _right(blocks, c, res) -> bool:
    """The published optimum (to its 7 digits) and every recomputed LMI to -1e-7 relative."""
    margins = [_rel_min_eig(s) for s in _slacks(blocks, res.x)]
    optimum = PUBLISHED["control2"]
    return abs(float(c @ res.x) - optimum) <= 1e-6 * optimum and min(margins) >= -1e-7


@pytest.mark.parametrize("exponent", [-200, -170, -50, 20, 50, 150])
def test_a_block_far_out_of_scale_never_gives_a_wrong_optimal(problems, exponent):
    """Measured before the per-block and objective tests: "optimal" at c'x = 7.1e12 for 1e50 (the
    residuals and gap relative to norms over all blocks, a dual objective of 2.5e23) and at
    c'x = 1.3e-9 with the small block violated entirely (relative eigenvalue -1) from 1e-170
    down. Now each ends with a failure status or at the optimum."""
    c, blocks = _scaled_control2(problems, exponent)
    res = BlockLMISolver(c, blocks).solve()
    assert res.status != "optimal" or _right(blocks, c, res)


@pytest.mark.parametrize("exponent", [-20, 20])
def test_without_block_weights_a_block_out_of_scale_never_gives_a_wrong_optimal(problems, monkeypatch,
                                                                                 exponent):
    """Unweighted, "optimal" came wrong from 1e-12 down and at 1e20 and above (measured)."""
    monkeypatch.setattr(ipm_blocks, "BLOCK_WEIGHT_SPREAD", np.inf)
    c, blocks = _scaled_control2(problems, exponent)
    res = BlockLMISolver(c, blocks).solve()
    assert res.status != "optimal" or _right(blocks, c, res)


@pytest.mark.parametrize("exponent", [-12, 0, 8])
def test_the_block_tests_keep_the_optimum_where_it_was_found(problems, exponent):
    """The same data within the weights' reach still end "optimal" at the optimum (measured
    25-47 iterations for 1e-12 to 1e8)."""
    c, blocks = _scaled_control2(problems, exponent)
    res = BlockLMISolver(c, blocks).solve()
    assert res.status == "optimal" and _right(blocks, c, res)
