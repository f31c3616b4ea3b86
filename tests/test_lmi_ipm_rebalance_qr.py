"""Rebalancing after an optimal solve whose QR phase began far from the optimum
(:data:`lmi.backends.ipm.REBALANCE_QR_GAP`).

The generic stress set's 12-state plant over 2 vertices (:mod:`dev.generic_stress`, seed 0, no
input bound; open-loop unstable, its optimal ``Q`` spanning about four decades) is solved along a
shrinking state. Its cold solve goes to the QR factorisation of ``P`` at a relative gap of about
6e-3, its warm solves take every step from it (from 1e-3): the Cholesky factor of the Schur
complement loses the step's accuracy in the construction's coordinates. The back-end rebuilds
the problem in coordinates balanced on the first answer's ``Q~``; the later solves begin their QR
phase near the optimum (1e-5), and every answer is certified and equal to the one the back-end
gives without rebalancing (within what both certify). Paper P's closed loop on the numba path,
whose QR phases are the end game (from relative gaps below 5e-6), keeps its coordinates. Gaps
and counts are compared, never times.
"""

from __future__ import annotations

import numpy as np
import pytest

from dev.generic_stress import generic_problem
from lmi import KothareProblem
from lmi.backends.ipm import REBALANCE_QR_GAP
from lmi.ipm import BlockLMISolver

STATES = 5


def _closed_states() -> tuple[dict, list[np.ndarray]]:
    prob = generic_problem(12, 2, None, 0)
    return prob.kothare_kwargs(), [prob.x * 0.93**k for k in range(STATES)]


@pytest.fixture(scope="module")
def runs():
    """Per setting of ``rebalance``: each state's answer, the gap its QR phase began at and the
    coordinates' rank."""
    kw, states = _closed_states()
    out = {}
    for rebalance in (True, False):
        kp = KothareProblem(**kw, backend="ipm", solver_options={"fallback": False, "rebalance": rebalance})
        rows = []
        for x in states:
            sol = kp.solve(x)
            backend = kp._backend
            rows.append((sol, backend._last_qr_gap, backend._t.ndim))
        out[rebalance] = (kp, rows)
    return out


def test_a_qr_phase_far_from_the_optimum_rebalances_the_next_solves(runs):
    _, rows = runs[True]
    gaps = [gap for _, gap, _ in rows]
    # the first (cold) solve went to the QR phase far from the optimum; from then on the
    # coordinates are full matrices, and the QR phase comes only near the optimum
    assert gaps[0] >= REBALANCE_QR_GAP
    assert all(ndim == 2 for _, _, ndim in rows)
    assert all(gap < REBALANCE_QR_GAP for gap in gaps[1:])
    # without the setting the coordinates stay, and so does the early QR phase
    _, plain = runs[False]
    assert all(ndim == 1 for _, _, ndim in plain)
    assert all(gap >= REBALANCE_QR_GAP for _, gap, _ in plain[1:])


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


def test_paper_p_keeps_its_coordinates_on_the_numba_path():
    """Paper P's E1 robust MPC (its weights, no input bound) over 8 inertia vertices on the numba
    path, 20 samples of its closed loop: every solve's QR phase begins near the optimum (measured:
    relative gaps of at most 4.7e-6 over 40 samples), and the coordinates stay those of the
    construction."""
    from benchmarks.timing.common import polytope
    from models import RigidSatellite
    from rmpc import RMPC

    plant = polytope(8)
    ctrl = RMPC(plant, np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1]), np.diag([0.01] * 3),
                solver_options={"core": "numba"})
    backend = ctrl.problem._backend
    x = RigidSatellite.paper_p().initial_state()
    for _ in range(20):
        u = ctrl.step(x)
        assert str(ctrl.last.status) == "optimal"
        assert np.isnan(backend._last_qr_gap) or backend._last_qr_gap < REBALANCE_QR_GAP
        x = plant.A[0] @ x + plant.B[0] @ u
    assert backend._t is backend._initial_scaling


def test_the_solver_counts_its_qr_steps():
    """A centred, well-conditioned problem takes no QR step (the generic plant's warm solves take
    them: the gaps above come from the same record)."""
    easy = BlockLMISolver([1.0], [(-np.diag([1.0, 2.0]), -np.eye(2)[None])]).solve()
    assert easy.status == "optimal" and easy.iterations > 0 and easy.qr_iterations == 0
    assert np.isnan(easy.qr_start_gap)
