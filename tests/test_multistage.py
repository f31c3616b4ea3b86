"""Multi-stage (scenario-tree) MPC: the tree, the QP against an independent scenario-form
construction (cvxpy, explicit non-anticipativity rows), the Riccati limit, the one-step state
guarantee, paper P's switching-vertex target, failures as statuses, save/load and bad input."""

from __future__ import annotations

import pickle
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import scipy.linalg as sla

import rmpc
from models import PolytopicModel, RigidSatellite
from rmpc import MultiStageMPC
from rmpc.controller import Controller
from rmpc.mpc.multistage import MAX_DENSE_VARIABLES, STATE_MARGIN
from rmpc.mpc.scenario_tree import ScenarioTree, tree_size
from rmpc.mpc.switching_runs import switching_runs
from rmpc.qp import QPResult, SolverResiduals
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

A_DI = np.array([[1.0, 1.0], [0.0, 1.0]])
BOX2 = (np.vstack((np.eye(2), -np.eye(2))), np.full(4, 10.0))


def _di(n_vertices: int = 2) -> PolytopicModel:
    """The double integrator with an uncertain input gain (0.8 to 1.2, or three gains)."""
    gains = (0.8, 1.2) if n_vertices == 2 else (0.8, 1.0, 1.2)
    return PolytopicModel([(A_DI, np.array([[0.5], [1.0]]) * g) for g in gains], dt=1.0)


def _di_coupled() -> PolytopicModel:
    """Two vertices differing in A and B, so that the branches really differ."""
    a2 = np.array([[1.0, 1.1], [0.0, 0.95]])
    return PolytopicModel([(A_DI, [[0.5], [1.0]]), (a2, [[0.3], [0.7]])], dt=1.0)


# -- the tree -------------------------------------------------------------------------------
@pytest.mark.parametrize(("v", "n", "nr"), [(2, 3, 1), (3, 4, 2), (2, 4, 4), (4, 5, 3)])
def test_tree_counts_and_edges(v: int, n: int, nr: int) -> None:
    tree = ScenarioTree(v, n, nr)
    counts = tree.nodes_per_stage
    assert counts == tuple(v ** min(k, nr) for k in range(n + 1))
    assert tree.scenarios == v**nr
    for k in range(n):
        parent, child, vertex = tree.transitions(k)
        assert sorted(child.tolist()) == list(range(counts[k + 1]))  # every node has one parent
        if k < nr:
            assert np.array_equal(np.bincount(parent), np.full(counts[k], v))
            assert np.array_equal(child % v, vertex)
        else:  # each branch keeps the vertex of its last branching
            assert np.array_equal(parent, child)
            assert np.array_equal(vertex, child % v)
    assert tree.probabilities()[-1] == pytest.approx(1.0 / tree.scenarios)


def test_tree_size_matches_the_built_qp() -> None:
    for v, n, nr, rows in [(2, 5, 1, 4), (3, 4, 2, 0), (2, 3, 3, 4)]:
        plant = _di(v)
        ctrl = MultiStageMPC(plant, np.eye(2), np.eye(1), horizon=n, robust_horizon=nr, u_max=1.0,
                             state_constraints=BOX2 if rows else None)
        qp = ctrl.qp_at([1.0, 0.0])
        size = tree_size(v, n, nr, n_states=2, n_inputs=1, state_rows=rows)
        assert ctrl.size == size
        assert qp.n_vars == size["variables"]
        assert qp.n_cons == size["equality_rows"] + size["inequality_rows"]
        assert qp.is_sparse


# -- against an independent construction ------------------------------------------------------
def _scenario_form(plant: PolytopicModel, q: np.ndarray, r: np.ndarray, n: int, nr: int, u_max: float,
                   box: tuple[np.ndarray, np.ndarray], terminal: list[np.ndarray], x0: np.ndarray) -> Any:
    """Multi-stage MPC written per scenario: every scenario its own input and state sequences,
    equal inputs imposed where two scenarios share their vertex history (cvxpy + Clarabel)."""
    import cvxpy as cp

    v = plant.n_vertices
    scen = [np.unravel_index(s, (v,) * nr) for s in range(v**nr)]  # the vertex of each branching
    mm = plant.n_inputs
    us = [cp.Variable((n, mm)) for _ in scen]
    cost, cons = 0, []
    for s, path in enumerate(scen):
        x = x0
        for k in range(n):
            j = int(path[min(k, nr - 1)])
            a, b = plant.vertex(j)
            cost += (cp.quad_form(us[s][k], r) + (cp.quad_form(x, q) if k else 0)) / len(scen)
            cons.append(cp.abs(us[s][k]) <= u_max)
            x = a @ x + b @ us[s][k]
            cons.append(box[0] @ x <= box[1])
        cost += cp.quad_form(x, terminal[int(path[nr - 1])]) / len(scen)
    for s, p1 in enumerate(scen):  # non-anticipativity: same history up to stage k -> same u_k
        for t in range(s + 1, len(scen)):
            p2 = scen[t]
            for k in range(n):
                if all(p1[i] == p2[i] for i in range(min(k, nr))):
                    cons.append(us[s][k] == us[t][k])
    prob = cp.Problem(cp.Minimize(cost), cons)
    prob.solve(solver=cp.CLARABEL, tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10)
    return prob, us[0].value[0]


@pytest.mark.parametrize(("nr", "x0"), [(1, [4.0, -1.0]), (2, [4.0, -1.0]), (3, [-6.0, 2.5])])
def test_qp_equals_the_scenario_form_with_explicit_non_anticipativity(nr: int, x0: list[float]) -> None:
    plant = _di_coupled()
    q, r = np.diag([1.0, 0.5]), np.array([[0.3]])
    box = (np.vstack((np.eye(2), -np.eye(2))), np.array([10.0, 3.0, 10.0, 3.0]))
    ctrl = MultiStageMPC(plant, q, r, horizon=4, robust_horizon=nr, u_max=1.0, state_constraints=box)
    u = ctrl.step(x0)
    assert ctrl.last.status == "optimal"
    terminal = [sla.solve_discrete_are(*plant.vertex(j), q, r) for j in range(2)]
    tight = (box[0], box[1] - STATE_MARGIN * np.maximum(1.0, box[1]))
    prob, u_ref = _scenario_form(plant, q, r, 4, nr, 1.0, tight, terminal, np.array(x0))
    assert prob.status == "optimal"
    # the QP's objective leaves out x0'Qx0 (a constant), as the scenario form above does
    assert ctrl.last.extra["objective"] == pytest.approx(prob.value, rel=1e-6, abs=1e-8)
    np.testing.assert_allclose(u, u_ref, atol=1e-5)


def test_one_vertex_and_no_active_bound_is_the_lqr_of_that_vertex() -> None:
    """With the Riccati terminal cost, the finite-horizon answer is the infinite-horizon LQR."""
    a, b = A_DI, np.array([[0.5], [1.0]])
    plant = PolytopicModel([(a, b)], dt=1.0)
    q, r = np.eye(2), np.array([[2.0]])
    p = sla.solve_discrete_are(a, b, q, r)
    k = np.linalg.solve(r + b.T @ p @ b, b.T @ p @ a)
    ctrl = MultiStageMPC(plant, q, r, horizon=6, robust_horizon=1, u_max=100.0)
    for x in ([1.0, 0.0], [-2.0, 0.5], [0.3, -0.7]):
        np.testing.assert_allclose(ctrl.step(x), -k @ np.array(x), atol=1e-7)


@pytest.mark.parametrize("backend", ["clarabel", "proxqp", "osqp"])
def test_backends_agree_on_the_double_integrator(backend: str) -> None:
    ref = MultiStageMPC(_di(3), np.eye(2), np.eye(1), horizon=8, robust_horizon=2, u_max=1.0,
                        state_constraints=BOX2)
    ctrl = MultiStageMPC(_di(3), np.eye(2), np.eye(1), horizon=8, robust_horizon=2, u_max=1.0,
                         state_constraints=BOX2, backend=backend)
    for x in ([5.0, -2.0], [-8.0, 3.0], [0.5, 0.5]):
        u_ref, u = ref.step(x), ctrl.step(x)
        assert ctrl.last.status == "optimal"
        np.testing.assert_allclose(u, u_ref, atol=1e-5)


# -- guarantees -----------------------------------------------------------------------------------
def test_every_plant_of_the_polytope_keeps_the_next_state_inside() -> None:
    """Solved at x, every vertex successor (so every convex combination) satisfies H x <= h."""
    # the vertices' A differ by 0.5 x2 in the position: a successor predicted with the wrong A
    # leaves the position bound
    plant = PolytopicModel([(A_DI, [[0.5], [1.0]]), ([[1.0, 1.5], [0.0, 1.0]], [[0.3], [0.7]])], dt=1.0)
    box = (np.vstack((np.eye(2), -np.eye(2))), np.array([10.0, 2.0, 10.0, 2.0]))
    ctrl = MultiStageMPC(plant, np.eye(2), np.eye(1), horizon=6, robust_horizon=1, u_max=1.0,
                         state_constraints=box)
    rng, states = np.random.default_rng(3), np.random.default_rng(4)
    solved = 0
    for _ in range(200):
        x = states.uniform([-10.0, -2.0], [10.0, 2.0])
        u = ctrl.step(x)
        if ctrl.last.status != "optimal":
            continue
        solved += 1
        assert ctrl.last.extra["next_state_margin"] <= 0.0
        for lam in rng.dirichlet(np.ones(2), size=5):
            a = sum(w * plant.vertex(j)[0] for j, w in enumerate(lam))
            b = sum(w * plant.vertex(j)[1] for j, w in enumerate(lam))
            assert np.all(box[0] @ (a @ x + b @ u) <= box[1])
    assert solved >= 150


def _paper_p() -> tuple[PolytopicModel, np.ndarray]:
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    return sat.polytope(x0, dt=0.01, spread=0.3, mode="scalar"), x0


RATE_BOUND = (np.vstack((np.eye(6)[3:], -np.eye(6)[3:])), np.full(6, 0.2))
Q_P, R_P = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1]), 0.01 * np.eye(3)


def test_paper_p_two_vertices_robust_horizon_one_has_no_bound_violation() -> None:
    """The target on seeded switching-vertex runs: |u_i| <= 1 and |w_i| <= 0.2 rad/s held (the
    unconstrained loop reaches 0.42 rad/s, so the rate bound is active), every QP solved."""
    plant, x0 = _paper_p()
    ctrl = MultiStageMPC(plant, Q_P, R_P, horizon=10, robust_horizon=1, u_max=1.0,
                         state_constraints=RATE_BOUND)
    out = switching_runs(ctrl, plant, x0, steps=400, runs=2, seed=11, u_max=1.0, state_constraints=RATE_BOUND,
                         Q=Q_P, R=R_P)
    assert out["violations"] == 0
    assert out["status_counts"] == {"optimal": 800}
    # the rate bound is reached (up to the QP's margin), and so is the torque bound
    # (the QP holds the states 1e-6 inside the bound, against the solvers' 1e-8 accuracy)
    assert -1.1e-6 < out["max_state_excess"] < -0.9e-6
    assert out["max_input_excess"] == pytest.approx(0.0, abs=1e-12)  # and the torque bound
    assert out["final_norm"] < 0.02 * np.linalg.norm(x0)  # and it regulates (4 s)


def test_switching_runs_counts_state_violations() -> None:
    """The counter of the target above sees a broken state bound (an LQR that ignores it)."""
    plant, x0 = _paper_p()
    out = switching_runs(rmpc.LQR(plant, Q_P, R_P), plant, x0, steps=100, runs=1, seed=11,
                         state_constraints=RATE_BOUND)
    assert out["state_violations"] > 0 and out["max_state_excess"] > 0.1


# -- failures are statuses ------------------------------------------------------------------------
def test_an_infeasible_tree_is_a_status_and_the_input_stays_in_its_bounds() -> None:
    box = (np.vstack((np.eye(2), -np.eye(2))), np.array([10.0, 1.0, 10.0, 1.0]))
    ctrl = MultiStageMPC(_di(), np.eye(2), np.eye(1), horizon=5, u_max=0.5, state_constraints=box)
    u = ctrl.step([9.5, 3.0])  # speed 3 toward the wall at 10: no bounded input stops it
    assert ctrl.last.status == "infeasible"
    assert ctrl.last.fallback and ctrl.last.extra["fallback_kind"] == "lqr"
    assert abs(u[0]) <= 0.5


def test_status_at_solves_without_a_step() -> None:
    """The region of attraction's test: the status at a state, ``last`` and the plan untouched."""
    box = (np.vstack((np.eye(2), -np.eye(2))), np.array([10.0, 1.0, 10.0, 1.0]))
    ctrl = MultiStageMPC(_di(), np.eye(2), np.eye(1), horizon=5, u_max=0.5, state_constraints=box)
    u = ctrl.step([2.0, 0.5])
    last, plan = ctrl.last, ctrl._plan.copy()
    assert ctrl.status_at([9.5, 3.0]) == "infeasible"
    assert ctrl.status_at([-2.0, 0.0]) == "optimal"
    assert ctrl.last is last and np.array_equal(ctrl._plan, plan)
    np.testing.assert_allclose(ctrl.step([2.0, 0.5]), u, atol=1e-8)


def _failing_once(ctrl: MultiStageMPC, monkeypatch: pytest.MonkeyPatch) -> None:
    real = ctrl.backend.solve
    calls = {"n": 0}

    def solve() -> QPResult:
        calls["n"] += 1
        res = real()
        if calls["n"] != 2:
            return res
        nan = np.full_like(res.x, np.nan)
        return QPResult(x=nan, objective=float("nan"), status="max_iterations", iterations=99, solve_time=0.0,
                        residuals=SolverResiduals(), y_C=res.y_C, y_box=res.y_box, raw_status="forced",
                        backend=res.backend)

    monkeypatch.setattr(ctrl.backend, "solve", solve)


def test_a_failed_solve_applies_the_previous_plan_for_the_realised_vertex(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    plant = _di_coupled()
    ctrl = MultiStageMPC(plant, np.eye(2), np.eye(1), horizon=6, robust_horizon=2, u_max=1.0,
                         state_constraints=BOX2)
    _failing_once(ctrl, monkeypatch)
    x = np.array([6.0, -1.0])
    u0 = ctrl.step(x)
    plan = ctrl._plan.copy()
    a, b = plant.vertex(1)
    x1 = a @ x + b @ u0
    u1 = ctrl.step(x1)
    assert ctrl.last.status == "max_iterations" and ctrl.last.fallback
    assert ctrl.last.extra["fallback_kind"] == "previous_plan"
    # stage 1 node 1 (vertex 1)'s input in the plan: the inputs are ordered by stage, then node
    np.testing.assert_allclose(u1, plan[1 + 1:1 + 2], atol=1e-9)
    assert ctrl.last.extra["next_state_margin"] <= 1e-9


def test_a_state_off_the_plan_falls_back_to_the_clipped_lqr(monkeypatch: pytest.MonkeyPatch) -> None:
    ctrl = MultiStageMPC(_di_coupled(), np.eye(2), np.eye(1), horizon=6, robust_horizon=2, u_max=0.2)
    _failing_once(ctrl, monkeypatch)
    ctrl.step([6.0, -1.0])
    u = ctrl.step([-3.0, 2.0])  # no plant of the polytope goes there in one sample
    assert ctrl.last.extra["fallback_kind"] == "lqr"
    np.testing.assert_allclose(u, np.clip(-ctrl.K_nominal @ [-3.0, 2.0], -0.2, 0.2))


# -- protocol, save and load ------------------------------------------------------------------------
def test_protocol_save_load_and_pickle(tmp_path: Path) -> None:
    ctrl = MultiStageMPC(_di(3), np.eye(2), np.eye(1), horizon=5, robust_horizon=2, u_max=1.0,
                         state_constraints=BOX2, output_matrix=[[1.0, 1.0]], y_max=12.0, terminal="nominal")
    assert isinstance(ctrl, Controller) and ctrl.name == "MultiStageMPC" and ctrl.accepts == frozenset()
    loaded = rmpc.load(ctrl.save(tmp_path / "ms.rmpc"))
    copied = pickle.loads(pickle.dumps(ctrl))
    for x in ([3.0, -1.0], [-5.0, 2.0]):
        u = ctrl.step(x)
        np.testing.assert_allclose(loaded.step(x), u, atol=1e-9)
        np.testing.assert_allclose(copied.step(x), u, atol=1e-9)
    assert loaded.settings() == ctrl.settings()
    p = np.diag([3.0, 2.0])
    with_matrix = MultiStageMPC(_di(), np.eye(2), np.eye(1), horizon=3, terminal=p, backend="osqp")
    again = rmpc.load(with_matrix.save(tmp_path / "ms2.rmpc"))
    assert np.array_equal(again.terminal, p) and again.backend.name == "osqp"


# -- bad input --------------------------------------------------------------------------------------
def test_the_euclidean_input_bound_is_refused_naming_the_reason() -> None:
    with pytest.raises(InvalidArgumentError, match=r"input_constraint: .*second-order cone.*'ellipsoid'"):
        MultiStageMPC(_di(), np.eye(2), np.eye(1), u_max=1.0, input_constraint="ellipsoid")


def test_a_tree_over_the_size_limit_is_refused_with_its_estimate() -> None:
    plant, _ = (RigidSatellite.paper_p().polytope(None, dt=0.01, spread=0.3, mode="box"), None)
    with pytest.raises(InvalidArgumentError, match=r"robust_horizon: .*max_variables = 50000.*"
                       r"robust_horizon = 5 with 8 vertices and horizon 10: 32768 scenarios, "
                       r"1713291 variables"):
        MultiStageMPC(plant, Q_P, R_P, horizon=10, robust_horizon=5)
    with pytest.raises(InvalidArgumentError, match="max_variables = 100"):
        MultiStageMPC(_di(), np.eye(2), np.eye(1), horizon=50, max_variables=100)


def test_a_dense_backend_is_refused_for_a_large_tree() -> None:
    plant = RigidSatellite.paper_p().polytope(None, dt=0.01, spread=0.3, mode="box")
    assert tree_size(8, 10, 2, n_states=6, n_inputs=3)["variables"] > MAX_DENSE_VARIABLES
    with pytest.raises(InvalidArgumentError,
                       match=r"backend: .*'osqp' or 'clarabel'.*'proxqp' with 5067 variables"):
        MultiStageMPC(plant, Q_P, R_P, horizon=10, robust_horizon=2, backend="proxqp")


@pytest.mark.parametrize(
    ("kwargs", "error", "pattern"),
    [
        ({"robust_horizon": 6}, InvalidArgumentError,
         r"robust_horizon: expected an integer in \[1, horizon = 5\]"),
        ({"robust_horizon": 0}, InvalidArgumentError, "robust_horizon: expected a positive integer"),
        ({"max_variables": 2.5}, InvalidArgumentError, "max_variables: expected a positive integer"),
        ({"state_constraints": (np.eye(2), [1.0, -1.0])}, InvalidArgumentError,
         r"state_constraints h: expected h >= 0 .*h\[1\] = -1"),
        ({"state_constraints": np.eye(2)}, ArgumentTypeError, r"state_constraints: expected a pair \(H, h\)"),
        ({"output_matrix": [[1.0, 0.0]]}, InvalidArgumentError,
         "output_matrix, y_max: expected both or neither"),
        ({"terminal": "kothare"}, InvalidArgumentError, "terminal"),
        ({"terminal": -np.eye(2)}, InvalidArgumentError, "terminal"),
        ({"u_max": 0.0}, InvalidArgumentError, "u_max: expected None or limits > 0"),
        ({"backend": "gurobi"}, InvalidArgumentError, "backend"),
        ({"backend": "osqp", "solver_options": {"tolerance": 1}}, InvalidArgumentError, "tolerance"),
    ],
)
def test_bad_arguments_name_themselves(kwargs: dict[str, Any], error: type, pattern: str) -> None:
    with pytest.raises(error, match=pattern):
        MultiStageMPC(_di(), np.eye(2), np.eye(1), horizon=5, **kwargs)


def test_a_plant_that_is_not_a_polytope_and_an_unstabilisable_vertex_are_refused() -> None:
    with pytest.raises(ArgumentTypeError, match=r"plant: expected a models\.PolytopicModel"):
        MultiStageMPC((A_DI, np.ones((2, 1))), np.eye(2), np.eye(1))
    bad = PolytopicModel([(A_DI, [[0.5], [1.0]]), (np.diag([2.0, 1.0]), [[0.0], [1.0]])], dt=1.0)
    with pytest.raises(InvalidArgumentError, match=r"plant \(vertex 1\): expected a stabilisable"):
        MultiStageMPC(bad, np.eye(2), np.eye(1))
