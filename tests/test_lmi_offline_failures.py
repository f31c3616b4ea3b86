""":meth:`lmi.offline.NestedKothareProblem.solve` returns a solver failure as a status, never
raises it: when cvxpy's solver raises ``SolverError`` (``backend="cvxpy"``, for the first
ellipsoid and for a nested one), the entry says ``"solver_error"``, carries the solver's message
and no solution. An entry that failed cannot be the outer ellipsoid of the next one: that is
refused, naming ``outer``."""

from __future__ import annotations

import cvxpy as cp
import numpy as np
import pytest

from lmi.offline import NestedKothareProblem
from lmi.status import SOLVER_ERROR
from toolkit_common.errors import InvalidArgumentError

# Kothare (1996), example 1 (as in NestedKothareProblem's docstring)
A = [[[1, 0.1], [0, 1 - 0.1 * a]] for a in (0.1, 10.0)]
B = [[[0.0], [0.1 * 0.787]]] * 2


def _problem() -> NestedKothareProblem:
    return NestedKothareProblem(A, B, Q=np.diag([1.0, 0.0]), R=[[2e-5]], dt=0.1,
                                input_constraint="peak", u_max=2.0, backend="cvxpy")


def _raise(*args: object, **kwargs: object) -> None:
    raise cp.error.SolverError("the solver gave up (injected)")


@pytest.mark.parametrize("nested", [False, True])
def test_a_solver_error_comes_back_as_a_status(nested: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    prob = _problem()
    outer = prob.solve([0.05, 0.0]) if nested else None
    if outer is not None:
        assert outer.ok  # the outer ellipsoid itself is solved normally
    monkeypatch.setattr(prob._nested if nested else prob._base.problem, "solve", _raise)
    entry = prob.solve([0.025, 0.0], outer=outer)
    assert entry.status == SOLVER_ERROR and not entry.ok
    assert entry.solver_status == "the solver gave up (injected)"
    assert entry.Q is None and entry.Y is None and entry.F is None and entry.certificate is None
    assert np.isnan(entry.gamma)
    np.testing.assert_array_equal(entry.x, [0.025, 0.0])


def test_a_failed_entry_is_refused_as_the_outer_ellipsoid(monkeypatch: pytest.MonkeyPatch) -> None:
    prob = _problem()
    with monkeypatch.context() as patch:
        patch.setattr(prob._base.problem, "solve", _raise)
        failed = prob.solve([0.05, 0.0])
    assert failed.status == SOLVER_ERROR
    with pytest.raises(InvalidArgumentError, match="outer"):
        prob.solve([0.025, 0.0], outer=failed)
    assert prob.solve([0.025, 0.0], outer=prob.solve([0.05, 0.0])).ok  # a certified outer is taken
