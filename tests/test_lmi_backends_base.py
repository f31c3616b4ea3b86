"""The back-ends of KothareProblem share one base (lmi.backends.base); the IPM owns its Clarabel fallback.

The infeasible problem of ``tests/test_lmi_failures.py``: ``A = diag(1.5, 0.9)``, ``B = [1, 1]'``,
``|u| <= 0.01`` at ``x = [10, 1]`` (no input that small can hold the first state).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from lmi import KothareProblem
from lmi.backends.base import KothareBackend, RawResult
from lmi.backends.clarabel import ClarabelKothare
from lmi.backends.conic import KothareConic
from lmi.backends.cvxpy import CvxpyKothare
from lmi.backends.ipm import IPMKothare

A = np.diag([1.5, 0.9])
B = np.array([[1.0], [1.0]])
FAR = np.array([10.0, 1.0])


def _problem(backend: str, **kwargs: Any) -> KothareProblem:
    return KothareProblem(A, B, np.eye(2), np.eye(1), dt=0.1, u_max=0.01, backend=backend, **kwargs)


def test_every_backend_is_a_kothare_backend_and_none_is_another_s_subclass() -> None:
    backends = {name: _problem(name)._backend for name in ("ipm", "clarabel", "cvxpy")}
    assert all(isinstance(b, KothareBackend) for b in backends.values())
    assert isinstance(backends["ipm"], IPMKothare) and not isinstance(backends["ipm"], ClarabelKothare)
    assert isinstance(backends["clarabel"], ClarabelKothare)
    assert not isinstance(backends["clarabel"], IPMKothare)
    assert isinstance(backends["cvxpy"], CvxpyKothare)
    assert not issubclass(IPMKothare, ClarabelKothare) and not issubclass(ClarabelKothare, IPMKothare)
    with pytest.raises(TypeError):
        KothareBackend()  # type: ignore[abstract]


def test_the_ipm_falls_back_to_the_clarabel_backend_it_owns(monkeypatch: pytest.MonkeyPatch) -> None:
    """A failed IPM solve goes to ``fallback_solver``, a Clarabel back-end on the IPM's own conic data."""
    # phase one and the main run's Farkas test off: the failed solve goes to Clarabel
    prob = _problem("ipm", solver_options={"phase_one": False, "infeasibility_radius": np.inf})
    ipm = prob._backend
    assert isinstance(ipm.conic, KothareConic) and isinstance(ipm.fallback_solver, ClarabelKothare)
    assert ipm.fallback_solver.conic is ipm.conic and ipm.fallback_solver.data is ipm.data
    calls: list[np.ndarray] = []
    honest = ipm.fallback_solver.solve

    def recording(x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray) -> RawResult:
        calls.append(x)
        return honest(x, u_max, y_max)

    monkeypatch.setattr(ipm.fallback_solver, "solve", recording)
    sol = prob.solve(FAR)
    assert sol.status == "infeasible" and "; clarabel " in sol.solver_status
    assert len(calls) == 1
    assert prob.solve(0.001 * FAR / np.linalg.norm(FAR)).status == "optimal" and len(calls) == 1


@pytest.mark.parametrize(
    ("formulation", "scale"), [("standard", 1.0), ("delta", 0.04), ("delta_shared", 0.04)]
)
def test_gamma_from_the_objective(formulation: str, scale: float) -> None:
    """gamma_s is gamma in the standard form and dt gamma in the delta forms (dt = 0.04 here)."""
    backend = KothareProblem(A, B, np.eye(2), np.eye(1), dt=0.04, u_max=0.01, backend="clarabel",
                             formulation=formulation)._backend
    assert backend.gamma(2.0) == pytest.approx(2.0 / scale, rel=1e-15)
