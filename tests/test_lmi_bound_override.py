"""A per-solve input bound (KothareProblem.solve(x, u_max=...)) equals a problem built with it, and
RMPC takes one per step through the typed channel (RMPC.step(x, StepInputs(u_max=...)))."""

from __future__ import annotations

import numpy as np
import pytest

from lmi import KothareProblem
from models import RigidSatellite
from rmpc import RMPC
from rmpc.controller import StepInputs
from toolkit_common.errors import InvalidArgumentError

Q1 = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])
R = 0.01 * np.eye(3)


@pytest.fixture(scope="module")
def poly():
    sat = RigidSatellite.paper_p()
    return sat.polytope(sat.initial_state(), 0.01, 0.7)


@pytest.mark.parametrize("backend", ["ipm", "clarabel", "cvxpy"])
@pytest.mark.parametrize(("kind", "bound"), [("ellipsoid", 0.4), ("peak", [0.3, 0.4, 0.5])])
def test_override_equals_a_problem_built_with_the_bound(poly, backend, kind, bound) -> None:
    x0 = RigidSatellite.initial_state()
    built = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=bound, input_constraint=kind,
                           backend=backend).solve(x0)
    prob = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=1.0, input_constraint=kind,
                          backend=backend)
    prob.solve(x0)  # a warm start from the other bound must not matter
    over = prob.solve(x0, u_max=bound)
    assert over.status == built.status == "optimal"
    assert over.gamma == pytest.approx(built.gamma, rel=1e-7)
    # the certificate checks the bound that was used: u = F x0 honours it, not only the built one
    u = over.F @ x0
    if kind == "ellipsoid":
        assert np.linalg.norm(u) <= bound * (1 + 1e-6)
    else:
        assert np.all(np.abs(u) <= np.asarray(bound) * (1 + 1e-6))
    # and the next solve without an override is back to the built bound
    again = prob.solve(x0)
    assert again.gamma < over.gamma


def test_rmpc_step_with_a_tighter_bound_resolves_a_kept_gain(poly) -> None:
    ctrl = RMPC(poly, Q1, R, u_max=1.0, resolve_threshold=0.5)
    x = RigidSatellite.initial_state(0.5)
    ctrl.step(x)
    assert ctrl.last.status == "optimal"
    ctrl.step(0.99 * x)
    assert ctrl.last.status == "reused"  # inside the ellipsoid, level above 0.5
    u = ctrl.step(0.98 * x, StepInputs(u_max=0.1))
    assert ctrl.last.status == "optimal"  # a tighter bound forces a solve
    assert np.linalg.norm(u) <= 0.1 * (1 + 1e-6)
    ctrl.step(0.97 * x, StepInputs(u_max=0.2))
    assert ctrl.last.status == "reused"  # a looser bound keeps the gain certified for 0.1


def test_bad_overrides_name_u_max(poly) -> None:
    prob = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=1.0)
    x0 = RigidSatellite.initial_state()
    for bad in (-1.0, 0.0, [0.5, 0.5, 0.5], np.nan):
        with pytest.raises(InvalidArgumentError, match=r"^u_max"):
            prob.solve(x0, u_max=bad)
    free = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, input_constraint=None)
    with pytest.raises(InvalidArgumentError, match=r"^u_max"):
        free.solve(x0, u_max=1.0)
    peak = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=1.0, input_constraint="peak")
    with pytest.raises(InvalidArgumentError, match=r"^u_max"):
        peak.solve(x0, u_max=[1.0, -1.0, 1.0])


def test_rmpc_step_inputs_channel(poly) -> None:
    """RMPC accepts only u_max on the channel; the bound is checked by KothareProblem.input_bound."""
    ctrl = RMPC(poly, Q1, R, u_max=1.0)
    assert RMPC.accepts == frozenset({"u_max"}) and ctrl.name == "RMPC"
    x = RigidSatellite.initial_state(0.5)
    u = ctrl.step(x, StepInputs(u_max=0.05))
    assert ctrl.last.status == "optimal" and np.linalg.norm(u) <= 0.05 * (1 + 1e-6)
    assert ctrl.certified.bound.tolist() == [0.05]  # the bound the kept gain was certified for
    ctrl.step(x, StepInputs())  # an empty channel: the constructed bound
    assert ctrl.certified.bound.tolist() == [1.0]
    with pytest.raises(InvalidArgumentError, match=r"^inputs\.pzt"):
        ctrl.step(x, StepInputs(pzt=[0.1]))
    with pytest.raises(InvalidArgumentError, match=r"^u_max"):
        ctrl.step(x, StepInputs(u_max=[0.1, 0.1, 0.1]))  # the ellipsoid takes a scalar
    with pytest.raises(TypeError, match=r"^inputs"):
        ctrl.step(x, 0.1)  # a bare bound is not the channel
    prob = ctrl.problem
    assert prob.input_bound(0.3).tolist() == [0.3]
    peak = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=1.0, input_constraint="peak")
    assert peak.input_bound(0.3).tolist() == [0.3, 0.3, 0.3]
