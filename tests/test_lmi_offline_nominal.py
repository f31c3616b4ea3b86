"""The off-line nested design with the nominal cost (Wan & Kothare 2003, Systems & Control Letters)
on Kothare's example 1, and the Lyapunov forms the nesting argument refuses."""

from __future__ import annotations

import numpy as np
import pytest

from lmi.forms import FormProblem
from lmi.offline import NestedKothareProblem
from models import PolytopicModel
from rmpc import OfflineRMPC
from toolkit_common.errors import InvalidArgumentError

A = [np.array([[1, 0.1], [0, 1 - 0.1 * a]]) for a in (0.1, 10.0)]
B = [np.array([[0.0], [0.1 * 0.787]])] * 2
NOMINAL = (np.mean(A, axis=0), B[0])
KW = dict(Q=np.diag([1.0, 0.0]), R=[[2e-5]], dt=0.1, input_constraint="peak", u_max=2.0)
X1 = np.array([0.05, 0.0])


def test_the_nesting_block_binds_where_the_free_optimum_is_not_nested():
    """At 0.95 of the first ellipsoid's boundary along the angle 1.96 rad (found by a sweep of
    nine angles, the only one where it binds) the nominal optimum without the nesting block leaves
    the first ellipsoid (``Q_1 - Q`` has eigenvalue -5e-4); with it the answer is nested, its
    margin is zero to 1e-10 and its bound larger (7.0316e-3 against 7.0145e-3)."""
    prob = NestedKothareProblem(A, B, **KW, cost="nominal", nominal=NOMINAL)
    first = prob.solve(X1)
    assert first.status == "optimal"
    v = np.array([np.cos(1.96), np.sin(1.96)])
    x2 = 0.95 * v / np.sqrt(v @ np.linalg.solve(first.Q, v))
    nested = prob.solve(x2, outer=first)
    free = FormProblem(A, B, **KW, cost="nominal", nominal=NOMINAL).solve(x2)
    assert free.status == nested.status == "optimal"
    assert np.linalg.eigvalsh(first.Q - free.Q)[0] < -1e-4 * np.linalg.norm(first.Q, 2)
    assert -1e-7 <= nested.nesting_margin <= 1e-8
    assert "nesting" in nested.certificate.margins
    assert nested.gamma > free.gamma * (1 + 1e-4)


def test_the_nominal_design_bounds_the_nominal_cost_below_the_worst_case():
    worst = NestedKothareProblem(A, B, **KW).design_ray(X1, n_ellipsoids=4, shrink=0.5)
    nominal = NestedKothareProblem(A, B, **KW, cost="nominal", nominal=NOMINAL).design_ray(
        X1, n_ellipsoids=4, shrink=0.5)
    assert nominal.stop_reason == worst.stop_reason == "complete"
    assert all(e.status == "optimal" for e in nominal.ellipsoids)
    assert np.all(nominal.gammas < worst.gammas)


def test_the_vertex_forms_and_a_missing_nominal_model_are_refused():
    with pytest.raises(InvalidArgumentError, match="lyapunov"):
        NestedKothareProblem(A, B, **KW, lyapunov="vertex")
    with pytest.raises(InvalidArgumentError, match="nominal"):
        NestedKothareProblem(A, B, **KW, cost="nominal")
    with pytest.raises(InvalidArgumentError, match="cost"):
        NestedKothareProblem(A, B, **KW, cost="best_case")


def test_offline_rmpc_with_the_nominal_cost_steps_with_a_certified_table():
    plant = PolytopicModel(list(zip(A, B, strict=True)), dt=0.1, nominal=NOMINAL)
    ctrl = OfflineRMPC(plant, KW["Q"], KW["R"], u_max=2.0, input_constraint="peak", cost="nominal",
                       n_ellipsoids=5)
    u = ctrl.step(X1)
    assert ctrl.table is not None and ctrl.table.n_ellipsoids == 5
    assert all(e.status == "optimal" for e in ctrl.table.ellipsoids)
    assert abs(float(u[0])) <= 2.0 + 1e-9
