"""The IPM back-end's iteration count after phase one: a solve that ends in phase one reports the
iterations of the failed solve plus those of phase one (the closed-form infeasible problem of
``test_lmi_infeasibility``: ``x1(k+1) = 1.5 x1(k) + u``, ``|u| <= 0.01``, ``x1 = 10``)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from lmi import KothareProblem

A = np.diag([1.5, 0.9])
B = np.array([[1.0], [1.0]])


def _spy(monkeypatch: pytest.MonkeyPatch, prob: KothareProblem) -> dict[str, Any]:
    """Record the iterations of the failed solve handed to phase one and of phase one itself."""
    backend = prob._backend
    seen: dict[str, Any] = {}
    decide, phase_one = backend._decide, backend._solver.phase_one

    def spy_decide(raw: Any, *args: Any) -> Any:
        seen["before"] = raw.iterations
        return decide(raw, *args)

    def spy_phase_one(*args: Any, **kwargs: Any) -> Any:
        res = phase_one(*args, **kwargs)
        seen["phase_one"] = res.iterations
        return res

    monkeypatch.setattr(backend, "_decide", spy_decide)
    monkeypatch.setattr(backend._solver, "phase_one", spy_phase_one)
    return seen


def test_phase_one_iterations_are_added_to_the_count(monkeypatch: pytest.MonkeyPatch) -> None:
    # the ray test off, so that the failed main run goes to phase one
    prob = KothareProblem(A, B, np.eye(2), np.eye(1), dt=0.1, input_constraint="peak", u_max=0.01,
                          solver_options={"infeasibility_radius": np.inf})
    seen = _spy(monkeypatch, prob)
    sol = prob.solve(np.array([10.0, 1.0]))
    assert sol.status == "infeasible", sol.solver_status
    assert seen["before"] > 0 and seen["phase_one"] > 0
    assert sol.iterations == seen["before"] + seen["phase_one"]
