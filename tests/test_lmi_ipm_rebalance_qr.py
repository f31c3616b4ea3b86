"""Rebalancing after an optimal solve spent in the QR phase
(:data:`lmi.backends.ipm.REBALANCE_QR_SHARE`).

The generic stress set's 12-state plant over 2 vertices (:mod:`dev.generic_stress`, seed 0, no
input bound; open-loop unstable, its optimal ``Q`` spanning about four decades) is solved along a
shrinking state. Its first warm solve takes every step from the QR factorisation of ``P``: the
Cholesky factor of the Schur complement loses the step's accuracy in the construction's
coordinates. The back-end then rebuilds the problem in coordinates balanced on that answer's
``Q~``; the later solves take fewer QR steps, and every answer is certified and equal to the one
the back-end gives without rebalancing (within what both certify). Counts of QR steps are
compared, never times.
"""

from __future__ import annotations

import numpy as np
import pytest

from dev.generic_stress import generic_problem
from lmi import KothareProblem
from lmi.backends.ipm import REBALANCE_QR_SHARE
from lmi.ipm import BlockLMISolver

STATES = 5


def _closed_states() -> tuple[dict, list[np.ndarray]]:
    prob = generic_problem(12, 2, None, 0)
    return prob.kothare_kwargs(), [prob.x * 0.93**k for k in range(STATES)]


@pytest.fixture(scope="module")
def runs():
    """Per setting of ``rebalance``: each state's answer, QR share and coordinates' rank."""
    kw, states = _closed_states()
    out = {}
    for rebalance in (True, False):
        kp = KothareProblem(**kw, backend="ipm", solver_options={"fallback": False, "rebalance": rebalance})
        rows = []
        for x in states:
            sol = kp.solve(x)
            backend = kp._backend
            rows.append((sol, backend._last_qr_share, backend._t.ndim))
        out[rebalance] = (kp, rows)
    return out


def test_a_solve_spent_in_the_qr_phase_rebalances_the_next_ones(runs):
    _, rows = runs[True]
    shares = [share for _, share, _ in rows]
    # the first warm solve is spent in the QR phase; from then on the coordinates are full matrices
    assert shares[1] >= REBALANCE_QR_SHARE
    assert rows[0][2] == 1 and all(ndim == 2 for _, _, ndim in rows[1:])
    # the warm solves in the balanced coordinates take fewer QR steps than that one
    assert max(shares[3:]) < shares[1]
    # without the setting the coordinates stay, and so does the share
    _, plain = runs[False]
    assert all(ndim == 1 for _, _, ndim in plain)
    assert min(share for _, share, _ in plain[1:]) >= REBALANCE_QR_SHARE


def test_rebalanced_answers_are_certified_and_equal_the_plain_ones(runs):
    for (sol, _, _), (ref, _, _) in zip(runs[True][1], runs[False][1], strict=True):
        assert sol.status == ref.status == "optimal"
        assert sol.certificate is not None and sol.certificate.ok
        assert ref.certificate is not None and ref.certificate.ok
        assert sol.gamma == pytest.approx(ref.gamma, rel=1e-7)


def test_reset_returns_to_the_constructions_coordinates(runs):
    kp, _ = runs[True]
    kw, states = _closed_states()
    kp.reset()
    assert kp._backend._t.ndim == 1
    fresh = KothareProblem(**kw, backend="ipm", solver_options={"fallback": False})
    assert kp.solve(states[0]).gamma == fresh.solve(states[0]).gamma


def test_the_solver_counts_its_qr_steps():
    """A centred, well-conditioned problem takes no QR step (the generic plant's warm solves take
    them: the shares above come from these counts)."""
    easy = BlockLMISolver([1.0], [(-np.diag([1.0, 2.0]), -np.eye(2)[None])]).solve()
    assert easy.status == "optimal" and easy.iterations > 0 and easy.qr_iterations == 0
