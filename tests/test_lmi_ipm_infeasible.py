"""The block LMI solver recognises infeasibility from its own dual iterates (a Farkas ray).

Each proof is recomputed here from the data as given (not the solver's packed, equilibrated
copy): ``Z`` positive definite, ``sum_j <C_j, Z_j> < 0`` and no ``x`` with ``||x|| < r`` for
``r = -sum_j <C_j, Z_j> / ||(sum_j <A_ij, Z_j>)_i||``, at least the radius asked for.
"""

from __future__ import annotations

import numpy as np
import pytest

from lmi.ipm import BlockLMISolver
from lmi.ipm.solver import INFEASIBILITY_RADIUS
from toolkit_common.errors import InvalidArgumentError


def _proved_radius(blocks, z_blocks) -> float:
    """The radius the multipliers prove, from the original data."""
    objective = sum(float(np.sum(c * z)) for (c, _), z in zip(blocks, z_blocks, strict=True))
    a_z = sum(np.einsum("ijk,jk->i", a, z) for (_, a), z in zip(blocks, z_blocks, strict=True))
    assert objective < 0.0
    size = float(np.linalg.norm(a_z))
    return -objective / size if size > 0.0 else np.inf


def _check_proof(res, blocks) -> None:
    assert res.status == "infeasible"
    total = np.sqrt(sum(float(np.sum(z * z)) for z in res.Z))
    assert total == pytest.approx(1.0, rel=1e-12)  # unit Frobenius norm over all blocks
    for z in res.Z:
        np.linalg.cholesky(z)  # positive definite: raises otherwise
    radius = _proved_radius(blocks, res.Z)
    assert radius >= INFEASIBILITY_RADIUS and res.infeasibility_radius >= INFEASIBILITY_RADIUS
    if np.isfinite(radius):
        # the solver's radius comes from G'z = rd - c (a cancellation): it agreed with the one
        # recomputed here to 4e-9..7e-6 relative on these problems (radii 1e8 and 1e12)
        assert res.infeasibility_radius == pytest.approx(radius, rel=1e-4)


def _interval_blocks():
    """``x >= 1`` and ``x <= -1``: no ``x`` at all."""
    return [(-np.eye(1), -np.eye(1)[None]), (-np.eye(1), np.eye(1)[None])]


def _unstable_lyapunov_blocks():
    """``P >= I`` and ``P - A'PA >= I`` for ``A`` with an eigenvalue 1.2: infeasible
    (``x'(P - A'PA)x = (1 - 1.2^2) x'Px < 0`` for the eigenvector). Variables: P's three entries."""
    a = np.array([[1.2, 0.3], [0.0, 0.5]])
    basis = [np.array([[1.0, 0.0], [0.0, 0.0]]), np.array([[0.0, 1.0], [1.0, 0.0]]),
             np.array([[0.0, 0.0], [0.0, 1.0]])]
    # C - sum_i x_i A_i >= 0 with C = -I, A_i = -E_i (P >= I) and A_i = -(E_i - A'E_i A)
    return [(-np.eye(2), -np.array(basis)),
            (-np.eye(2), -np.array([e - a.T @ e @ a for e in basis]))]


@pytest.mark.parametrize("make", [_interval_blocks, _unstable_lyapunov_blocks])
def test_an_infeasible_problem_ends_infeasible_with_a_ray_that_proves_it(make):
    blocks = make()
    n = blocks[0][1].shape[0]
    res = BlockLMISolver(np.ones(n), blocks).solve()
    _check_proof(res, blocks)


@pytest.mark.parametrize("make", [_interval_blocks, _unstable_lyapunov_blocks])
def test_with_the_test_off_the_run_does_not_claim_infeasibility(make):
    blocks = make()
    n = blocks[0][1].shape[0]
    res = BlockLMISolver(np.ones(n), blocks, infeasibility_radius=np.inf).solve()
    assert res.solver_status in ("insufficient_progress", "max_iterations", "numerical_error")
    assert res.status in ("max_iterations", "numerical_error")
    assert np.isnan(res.infeasibility_radius)


def test_a_larger_radius_asks_for_more_iterations():
    blocks = _unstable_lyapunov_blocks()
    near = BlockLMISolver(np.ones(3), blocks).solve()
    far = BlockLMISolver(np.ones(3), blocks, infeasibility_radius=1e12).solve()
    assert far.status == "infeasible" and far.iterations > near.iterations
    assert _proved_radius(blocks, far.Z) >= 1e12


def test_a_feasible_problem_with_a_large_optimum_is_solved_not_called_infeasible():
    """``min x`` s.t. ``x >= 1e10``: its dual optimum ``z = 1`` gives a radius of 1e10 too, but it
    is no ray (``A'z = -c``)."""
    res = BlockLMISolver([1.0], [(-1e10 * np.eye(1), -np.eye(1)[None])]).solve()
    assert res.status == "optimal"
    assert res.x[0] == pytest.approx(1e10, rel=1e-8)


def test_a_warm_start_on_infeasible_data_keeps_the_proof():
    blocks = _interval_blocks()
    slv = BlockLMISolver([1.0], [(np.eye(1), -np.eye(1)[None]), (np.eye(1), np.eye(1)[None])])
    assert slv.solve().status == "optimal"  # -1 <= x <= 1
    for j, (c, a) in enumerate(blocks):
        slv.set_block(j, c, a)
    res = slv.solve(warm_start=True)
    _check_proof(res, blocks)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, True, "1e8"])
def test_the_radius_setting_is_checked(bad):
    with pytest.raises(InvalidArgumentError, match="infeasibility_radius"):
        BlockLMISolver([1.0], _interval_blocks()[:1], infeasibility_radius=bad)
