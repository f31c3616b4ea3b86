"""The solve time that :meth:`lmi.KothareProblem.solve` reports is a duration spent inside the call:
positive and no longer than the call itself, for every back-end (no speed is asserted)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from lmi import KothareProblem

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
