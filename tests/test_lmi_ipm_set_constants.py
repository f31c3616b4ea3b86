"""``BlockLMISolver.set_constants``: several blocks' constants at once, checked as ``set_block``
checks one (a warm-started form sets a dozen or more per state)."""

from __future__ import annotations

import numpy as np
import pytest

from lmi.ipm import BlockLMISolver
from toolkit_common.errors import InvalidArgumentError


def _sym(mat: np.ndarray) -> np.ndarray:
    return 0.5 * (mat + mat.T)


def _problem(seed: int = 0):
    """A feasible three-block LMI problem (orders 3, 4, 3) in 5 variables."""
    rng = np.random.default_rng(seed)
    n, orders = 5, (3, 4, 3)
    blocks = []
    for k in orders:
        coef = np.stack([_sym(rng.normal(size=(k, k))) for _ in range(n)])
        const = np.eye(k) * (2.0 + k)
        blocks.append((const, coef))
    c = rng.normal(size=n)
    # a bounded objective: minimise c'z over a set that the trace constraint bounds
    blocks.append((np.eye(1) * 10.0, np.stack([np.eye(1) * s for s in np.sign(c)])))
    return c, blocks


def _new_constants(seed: int = 1) -> dict[int, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {0: np.eye(3) * 4.0 + 0.1 * _sym(rng.normal(size=(3, 3))),
            2: np.eye(3) * 3.0 + 0.1 * _sym(rng.normal(size=(3, 3)))}


def test_set_constants_leaves_the_solver_as_set_block_does_block_by_block():
    """The packed right-hand side, the stored constants and the answer are those of one
    ``set_block`` per block."""
    c, blocks = _problem()
    batch, single = BlockLMISolver(c, blocks), BlockLMISolver(c, blocks)
    consts = _new_constants()
    batch.set_constants(consts)
    for j, const in consts.items():
        single.set_block(j, const)
    assert np.array_equal(batch._h_vec, single._h_vec)
    assert all(np.array_equal(a, b) for a, b in zip(batch._const, single._const, strict=True))
    got, want = batch.solve(), single.solve()
    assert got.status == want.status == "optimal"
    assert np.array_equal(got.x, want.x)


def test_set_constants_takes_effect():
    """The answer after the new constants is that of a solver built with them."""
    c, blocks = _problem()
    consts = _new_constants()
    warm = BlockLMISolver(c, blocks)
    warm.solve()
    warm.set_constants(consts)
    fresh = BlockLMISolver(c, [(consts.get(j, const), coef) for j, (const, coef) in enumerate(blocks)])
    got, want = warm.solve(), fresh.solve()
    assert got.status == want.status == "optimal"
    assert float(c @ got.x) == pytest.approx(float(c @ want.x), rel=1e-7)
    before = BlockLMISolver(c, blocks).solve()
    assert abs(float(c @ before.x) - float(c @ want.x)) > 1e-6  # the constants do change the answer


@pytest.mark.parametrize(("j", "const", "words"), [
    (2, np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), "symmetric"),
    (0, np.diag([1.0, np.nan, 1.0]), "finite"),
    (1, np.eye(3), "order 4"),
    (7, np.eye(3), "block index"),
])
def test_set_constants_names_the_block_that_fails_the_checks(j, const, words):
    """An asymmetric, non-finite or wrongly sized constant, or an index out of range, is an
    error naming that block, as ``set_block`` gives it; nothing is set before it."""
    c, blocks = _problem()
    solver = BlockLMISolver(c, blocks)
    h_before = solver._h_vec.copy()
    good = {0: np.eye(3) * 5.0} if j != 0 else {2: np.eye(3) * 5.0}  # checked first, not set
    with pytest.raises(InvalidArgumentError, match=words):
        solver.set_constants({**good, j: const})
    assert np.array_equal(solver._h_vec, h_before)
    with pytest.raises(InvalidArgumentError, match=words):
        solver.set_block(j, const)


def test_an_asymmetry_at_the_tolerance_passes_and_beyond_it_fails():
    """The symmetry test is relative to the block's largest entry (1e-12), as ``set_block``'s."""
    c, blocks = _problem()
    solver = BlockLMISolver(c, blocks)
    scale = 1e6
    ok = np.eye(3) * scale
    ok[0, 1] += 0.5e-12 * scale
    solver.set_constants({0: ok})
    bad = np.eye(3) * scale
    bad[0, 1] += 5e-12 * scale
    with pytest.raises(InvalidArgumentError, match="symmetric"):
        solver.set_constants({0: bad})
