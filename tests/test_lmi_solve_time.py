"""The solve time that :meth:`lmi.KothareProblem.solve` and :meth:`lmi.ipm.BlockLMISolver.solve`
report is a duration spent inside the call: positive and no longer than the call itself, for every
back-end (no speed is asserted)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from lmi import KothareProblem
from lmi.ipm import BlockLMISolver

A = [np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * a]]) for a in (0.1, 10.0)]
B = [np.array([[0.0], [0.1 * 0.787]])] * 2


@pytest.mark.parametrize("backend", ["ipm", "clarabel", "cvxpy"])
def test_the_reported_solve_time_lies_within_the_call(backend: str) -> None:
    prob = KothareProblem(A, B, np.diag([1.0, 0.0]), np.array([[2e-5]]), dt=0.1, input_constraint="peak",
                          u_max=2.0, backend=backend)
    for x in ([0.05, 0.0], [0.02, -0.01]):  # a cold solve and a warm one
        start = time.perf_counter()
        sol = prob.solve(np.array(x))
        elapsed = time.perf_counter() - start
        assert sol.status == "optimal", sol.solver_status
        assert 0.0 < sol.solve_time <= elapsed


def test_the_ipm_solver_reports_a_solve_time_within_the_call() -> None:
    # the example of BlockLMISolver's docstring: min t s.t. t I - [[2, 1], [1, 2]] >= 0 (t = 3)
    solver = BlockLMISolver([1.0], [(-np.array([[2.0, 1.0], [1.0, 2.0]]), -np.eye(2)[None])])
    for _ in range(2):  # a cold solve and a warm one
        start = time.perf_counter()
        res = solver.solve()
        elapsed = time.perf_counter() - start
        assert res.status == "optimal"
        assert 0.0 < res.solve_time <= elapsed
