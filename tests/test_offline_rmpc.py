"""Off-line robust MPC (Wan & Kothare 2003): certificates, nesting, the lookup, closed-loop cost.

References checked: Kothare (1996) example 1 (SPEC section 4; Wan & Kothare use it too), where
the first ellipsoid is the on-line problem at ``x0`` (``gamma ~= 9.716e-3``,
``F ~= [-33.21, -6.11]``) and the realised cost of any plant of the polytope, fixed or
time-varying, must stay below ``gamma_1``; and paper P's satellite, where the closed-loop cost
is compared with on-line :class:`rmpc.RMPC` (re-solved at every step) over the same 300 steps.
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest
from printed_digits import assert_rounds_to
from solve_guard import forbid_solves

from lmi import certify
from lmi.offline import NestedKothareProblem, interpolation_margin
from models import PolytopicModel, RigidSatellite
from rmpc import RMPC, OfflineRMPC, simulate
from rmpc.controller import Controller
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

# -- Kothare (1996), example 1 ---------------------------------------------------------------
K_Q1 = np.diag([1.0, 0.0])
K_R = np.array([[2e-5]])
K_X0 = np.array([0.05, 0.0])
K_UMAX = 2.0


def kothare_ab(alpha: float) -> tuple[np.ndarray, np.ndarray]:
    return np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * alpha]]), np.array([[0.0], [0.1 * 0.787]])


@pytest.fixture(scope="module")
def kothare_plant() -> PolytopicModel:
    return PolytopicModel([kothare_ab(0.1), kothare_ab(10.0)], dt=0.1)


@pytest.fixture(scope="module")
def kothare_ctrl(kothare_plant) -> OfflineRMPC:
    return OfflineRMPC(kothare_plant, K_Q1, K_R, u_max=K_UMAX, input_constraint="peak", x_design=K_X0,
                       n_ellipsoids=10)


@pytest.fixture(scope="module")
def kothare_plain(kothare_plant) -> OfflineRMPC:
    """The same design, looked up without interpolation."""
    return OfflineRMPC(kothare_plant, K_Q1, K_R, u_max=K_UMAX, input_constraint="peak", x_design=K_X0,
                       n_ellipsoids=10, interpolate=False)


# -- paper P's satellite ---------------------------------------------------------------------
S_Q1 = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])
S_R = np.eye(3)


@pytest.fixture(scope="module")
def sat_x0() -> np.ndarray:
    return RigidSatellite.paper_p().initial_state()


@pytest.fixture(scope="module")
def sat_plant(sat_x0) -> PolytopicModel:
    return RigidSatellite.paper_p().polytope(sat_x0, 0.01, 0.3, "scalar")


@pytest.fixture(scope="module")
def sat_ctrl(sat_plant, sat_x0) -> OfflineRMPC:
    return OfflineRMPC(sat_plant, S_Q1, S_R, u_max=1.0, x_design=sat_x0)


def loop_cost(x: np.ndarray, u: np.ndarray, q1: np.ndarray, r: np.ndarray) -> float:
    """``sum_k x_k' Q1 x_k + u_k' R u_k`` over the applied steps (``x`` has one more row)."""
    return float(np.einsum("ki,ij,kj->", x[: len(u)], q1, x[: len(u)]) + np.einsum("ki,ij,kj->", u, r, u))


def run_varying(ctrl: OfflineRMPC, alphas: np.ndarray) -> tuple[np.ndarray, np.ndarray, list]:
    """Closed loop of Kothare's plant with ``alpha(k)`` (any sequence in [0.1, 10])."""
    ctrl.reset()
    x = K_X0.copy()
    xs, us, infos = [x], [], []
    for alpha in alphas:
        u = ctrl.step(x)
        a, b = kothare_ab(float(alpha))
        x = a @ x + b @ u
        xs.append(x)
        us.append(u)
        infos.append(ctrl.last)
    return np.array(xs), np.array(us), infos


# -- the table ---------------------------------------------------------------------------------
@pytest.mark.parametrize("which", ["kothare", "satellite"])
def test_ellipsoids_are_nested(which, kothare_ctrl, sat_ctrl) -> None:
    table = (kothare_ctrl if which == "kothare" else sat_ctrl).table
    assert table.stop_reason == "complete"
    assert table.n_ellipsoids == (10 if which == "kothare" else 15)
    ells = table.ellipsoids
    for outer, inner in pairwise(ells):
        diff = outer.Q - inner.Q
        lam = np.linalg.eigvalsh(0.5 * (diff + diff.T))
        assert lam[0] >= -1e-7 * np.linalg.norm(outer.Q, 2)
        # the design state of the inner ellipsoid is strictly inside the outer one
        assert inner.x @ np.linalg.solve(outer.Q, inner.x) < 1.0
    levels = [[x @ np.linalg.solve(e.Q, x) for e in ells] for x in table.states]
    assert np.all(np.diff(levels, axis=1) >= -1e-9 * np.abs(levels)[:, 1:])  # Q_i^-1 increases with i


@pytest.mark.parametrize("which", ["kothare", "satellite"])
def test_every_stored_gain_is_certified(which, kothare_ctrl, sat_ctrl) -> None:
    ctrl = kothare_ctrl if which == "kothare" else sat_ctrl
    data = ctrl.problem.data
    for e in ctrl.table.ellipsoids:
        assert e.status == "optimal"
        cert = certify(data, e.x, e.gamma, e.Q, e.Y, tol=1e-7)
        assert cert.ok, cert.margins
        assert min(cert.margins.values()) >= -1e-7
        np.testing.assert_allclose(e.F @ e.Q, e.Y, rtol=1e-9, atol=1e-12 * np.abs(e.Y).max())
        # the design state is on (or inside) its ellipsoid: gamma bounds x' P x there
        assert e.x @ np.linalg.solve(e.Q, e.x) <= 1.0 + 1e-6


def test_first_ellipsoid_is_the_online_problem(kothare_plant, kothare_ctrl) -> None:
    online = RMPC(kothare_plant, K_Q1, K_R, u_max=K_UMAX, input_constraint="peak").solve(K_X0)
    first = kothare_ctrl.table.ellipsoids[0]
    # measured 7.9e-8 apart (cvxpy + Clarabel against the IPM, both stopping at a relative gap of
    # 1e-8); asserted 1e-6, as between the back-ends in test_lmi_backends_agree
    assert first.gamma == pytest.approx(online.gamma, rel=1e-6)
    # Kothare's published values to their printed digits (measured 9.71634e-3 and
    # [-33.2121, -6.1102]: 3.4e-7 and 2.1e-3 from them, inside 5e-7 and 5e-3)
    assert_rounds_to(first.gamma, "9.716e-3")
    assert_rounds_to(first.F.ravel(), ("-33.21", "-6.11"))


def test_interpolation_condition_recomputed(kothare_ctrl) -> None:
    """Condition (18) of Wan & Kothare in its printed form, against the stored flags."""
    table, data = kothare_ctrl.table, kothare_ctrl.problem.data
    ells = table.ellipsoids
    for i, (outer, inner) in enumerate(pairwise(ells)):
        q_inv = np.linalg.inv(outer.Q)
        worst = min(
            np.linalg.eigvalsh(q_inv - (a + b @ inner.F).T @ q_inv @ (a + b @ inner.F))[0]
            / np.linalg.norm(q_inv, 2)
            for a, b in zip(data.A, data.B, strict=True)
        )
        assert (worst > 0) == bool(table.interpolable[i])
        assert table.interpolation_margins[i] == pytest.approx(interpolation_margin(data, outer.Q, inner.F))
    assert table.interpolable.all()


# -- the lookup --------------------------------------------------------------------------------
def test_lookup_matches_brute_force(sat_ctrl, sat_x0) -> None:
    ells = sat_ctrl.table.ellipsoids
    rng = np.random.default_rng(3)
    for _ in range(200):
        x = rng.standard_normal(6) * sat_x0.max() * 10.0 ** rng.uniform(-4, 0)
        u = sat_ctrl.step(x)
        lev = np.array([x @ np.linalg.solve(e.Q, x) for e in ells])
        inside = np.flatnonzero(lev <= 1.0 + 1e-6)
        info = sat_ctrl.last
        if inside.size == 0:
            assert info.status == "outside" and info.fallback and info.gamma is None
            np.testing.assert_allclose(u, ells[0].F @ x)
            continue
        i = int(inside.max())
        assert info.status == "optimal" and info.extra["index"] == i
        assert info.gamma == ells[i].gamma
        if i == len(ells) - 1:
            np.testing.assert_allclose(u, ells[i].F @ x, atol=1e-12)
            continue
        alpha = info.extra["alpha"]
        assert 0.0 <= alpha <= 1.0
        assert alpha * lev[i] + (1 - alpha) * lev[i + 1] == pytest.approx(1.0, abs=1e-6)
        np.testing.assert_allclose(u, (alpha * ells[i].F + (1 - alpha) * ells[i + 1].F) @ x, atol=1e-12)
        assert np.linalg.norm(u) <= 1.0 + 1e-6  # ||u|| <= u_max anywhere in E_1 (Jensen)


def test_lookup_without_interpolation(kothare_plain) -> None:
    kothare_plain.reset()
    for x in (0.3 * K_X0, np.array([0.01, -0.02])):
        u = kothare_plain.step(x)
        i = kothare_plain.last.extra["index"]
        assert kothare_plain.last.extra["alpha"] == 1.0
        np.testing.assert_allclose(u, kothare_plain.table.ellipsoids[i].F @ x)


def test_lookup_solves_no_sdp(sat_ctrl, sat_x0, monkeypatch) -> None:
    """300 steps along the design ray with every SDP solve forbidden: the table answers them all.

    What the step costs in time is measured by ``python -m benchmarks.timing.offline`` and quoted
    in ``docs/offline_rmpc.rst`` (a median of 7.7 us per step on a loaded two-core machine).
    """
    sat_ctrl.reset()
    table = sat_ctrl.table
    attempts = forbid_solves(monkeypatch)
    indices = []
    for s in np.geomspace(1.0, 1e-3, 300):
        x = s * sat_x0
        u = sat_ctrl.step(x)
        assert sat_ctrl.last.status == "optimal"
        i = sat_ctrl.last.extra["index"]
        indices.append(i)
        assert np.linalg.norm(u) <= 1.0 + 1e-6
    assert attempts == []
    assert sat_ctrl.table is table  # not redesigned
    # x = s x0 with s in [0.5^(i+1), 0.5^i) lies in E_i and not in E_(i+1) (shrink 0.5): E_0 .. E_9
    assert sorted(set(indices)) == list(range(10)) and np.all(np.diff(indices) >= 0)


# -- closed loops --------------------------------------------------------------------------------
@pytest.mark.parametrize("interpolate", [True, False])
@pytest.mark.parametrize("alpha", [9.0, 1.0, "random"])
def test_kothare_cost_below_bound(kothare_ctrl, kothare_plain, alpha, interpolate) -> None:
    ctrl = kothare_ctrl if interpolate else kothare_plain
    steps = 100
    rng = np.random.default_rng(7)
    alphas = rng.uniform(0.1, 10.0, steps) if alpha == "random" else np.full(steps, alpha)
    x, u, infos = run_varying(ctrl, alphas)
    gamma_1 = ctrl.table.ellipsoids[0].gamma
    cost = loop_cost(x, u, K_Q1, K_R)
    assert cost < gamma_1
    assert np.linalg.norm(x[-1]) < 1e-3 * np.linalg.norm(K_X0)  # converged: the tail is negligible
    assert np.all(np.abs(u) <= K_UMAX + 1e-9)
    assert all(info.status == "optimal" for info in infos)
    index = [info.extra["index"] for info in infos]
    assert np.all(np.diff(index) >= 0)  # the state never leaves an ellipsoid it has entered


def test_satellite_cost_within_10_percent_of_online(sat_plant, sat_ctrl, sat_x0) -> None:
    """300 steps (3 s) of the nominal linear model; both costs computed by ``loop_cost``.

    Measured: ratio 1.0000 (offline 93.42 vs online 93.42); over 1500 steps 102.08 for both.
    """
    steps = 300
    online = simulate(RMPC(sat_plant, S_Q1, S_R, u_max=1.0, resolve_threshold=1.0), sat_plant, sat_x0,
                      n_steps=steps)
    offline = simulate(sat_ctrl, sat_plant, sat_x0, n_steps=steps)
    c_on = loop_cost(online.x, online.u_cmd, S_Q1, S_R)
    c_off = loop_cost(offline.x, offline.u_cmd, S_Q1, S_R)
    assert c_off <= 1.10 * c_on, (c_off, c_on)
    assert offline.status_counts() == {"optimal": steps}
    assert np.all(np.linalg.norm(offline.u_cmd, axis=1) <= 1.0 + 1e-6)
    assert np.all(np.diff(offline.gamma) <= 0)


def test_simulate_designs_from_the_first_state(sat_plant, sat_x0) -> None:
    """``x_design=None``: designed at the first step, kept while runs start inside, renewed outside."""
    ctrl = OfflineRMPC(sat_plant, S_Q1, S_R, u_max=1.0, n_ellipsoids=4)
    assert isinstance(ctrl, Controller) and ctrl.table is None
    traj = simulate(ctrl, sat_plant, sat_x0, n_steps=20)
    assert traj.info[0].extra["design_time"] > 0 and traj.info[1].status == "optimal"
    assert traj.solve_time[0] >= traj.info[0].extra["design_time"]
    first = ctrl.table
    simulate(ctrl, sat_plant, 0.5 * sat_x0, n_steps=5)
    assert ctrl.table is first
    traj = simulate(ctrl, sat_plant, 1.3 * sat_x0, n_steps=5)  # E6: initial attitude +30 %
    assert ctrl.table is not first and traj.status[0] == "optimal"
    np.testing.assert_allclose(ctrl.table.states[0], 1.3 * sat_x0)


def test_nonlinear_satellite(sat_ctrl, sat_x0) -> None:
    traj = simulate(sat_ctrl, RigidSatellite.paper_p(), sat_x0, n_steps=100, dt=0.01)
    assert traj.plant == "nonlinear" and set(traj.status) <= {"optimal", "outside"}
    assert np.linalg.norm(traj.x[-1, :3]) < np.linalg.norm(sat_x0[:3])


def test_outside_the_largest_ellipsoid(sat_ctrl, sat_x0) -> None:
    sat_ctrl.reset()
    u = sat_ctrl.step(2.0 * sat_x0)
    assert sat_ctrl.last.status == "outside" and sat_ctrl.last.fallback
    np.testing.assert_allclose(u, sat_ctrl.table.ellipsoids[0].F @ (2.0 * sat_x0))
    assert sat_ctrl.last.extra["level"] > 1.0


def test_trajectory_and_explicit_design_states(kothare_plant) -> None:
    ctrl = OfflineRMPC(kothare_plant, K_Q1, K_R, u_max=K_UMAX, input_constraint="peak", x_design=K_X0,
                       n_ellipsoids=5, path="trajectory")
    table = ctrl.table
    assert table.n_ellipsoids == 5 and table.stop_reason == "complete"
    for outer, inner in pairwise(table.ellipsoids):
        assert inner.x @ np.linalg.solve(outer.Q, inner.x) <= 0.25 + 1e-12  # shrink^2
    # explicit states: the second is not inside the first ellipsoid and is skipped
    states = np.array([K_X0, [0.0, 0.5], 0.5 * K_X0])
    table = ctrl.design(states)
    assert table.n_ellipsoids == 2 and [k for k, _ in table.skipped] == [1]
    np.testing.assert_allclose(table.states, states[[0, 2]])


def test_infeasible_design_is_a_status() -> None:
    """An unstable plant with ``|u| <= 1`` cannot be held from ``x = 10``: no ellipsoid, u = 0."""
    plant = PolytopicModel([([[1.5]], [[1.0]])], dt=1.0)
    ctrl = OfflineRMPC(plant, [[1.0]], [[1.0]], u_max=1.0, x_design=[10.0], n_ellipsoids=3)
    assert ctrl.table.n_ellipsoids == 0 and ctrl.table.failed_status == "infeasible"
    u = ctrl.step([10.0])
    assert ctrl.last.status == "infeasible" and ctrl.last.fallback and np.all(u == 0)


def test_direct_problem_reports_bad_states() -> None:
    a, b = kothare_ab(1.0)
    prob = NestedKothareProblem(a, b, K_Q1, K_R, dt=0.1, input_constraint="peak", u_max=K_UMAX)
    with pytest.raises(InvalidArgumentError, match="states"):
        prob.design(np.zeros((2, 2)))
    with pytest.raises(InvalidArgumentError, match=r"^x:"):
        prob.solve([0.0, 0.0])
    with pytest.raises(InvalidArgumentError, match="n_ellipsoids"):
        prob.design_ray(K_X0, 0)
    with pytest.raises(InvalidArgumentError, match="shrink"):
        prob.design_trajectory(K_X0, 3, shrink=1.0)


# -- bad input ------------------------------------------------------------------------------------
BAD = [
    ({"plant": "not a plant"}, ArgumentTypeError, "plant"),
    ({"Q": -np.eye(2)}, InvalidArgumentError, "Q"),
    ({"R": [[0.0]]}, InvalidArgumentError, "R"),
    ({"u_max": None, "input_constraint": "peak"}, InvalidArgumentError, "u_max"),
    ({"input_constraint": "box"}, InvalidArgumentError, "input_constraint"),
    ({"n_ellipsoids": 0}, InvalidArgumentError, "n_ellipsoids"),
    ({"n_ellipsoids": 2.5}, InvalidArgumentError, "n_ellipsoids"),
    ({"shrink": 1.5}, InvalidArgumentError, "shrink"),
    ({"shrink": "half"}, ArgumentTypeError, "shrink"),
    ({"path": "spiral"}, InvalidArgumentError, "path"),
    ({"interpolate": "yes"}, ArgumentTypeError, "interpolate"),
    ({"x_design": [0.05, 0.0, 1.0]}, InvalidArgumentError, "x_design"),
    ({"x_design": [0.0, 0.0]}, InvalidArgumentError, "x_design"),
    ({"x_design": [[0.05, 0.0], [0.0, 0.0]]}, InvalidArgumentError, "x_design"),
    ({"x_design": [np.nan, 0.0]}, InvalidArgumentError, "x_design"),
    ({"solver_options": {"no_such_setting": 1}}, InvalidArgumentError, "solver_options"),
]


@pytest.mark.parametrize(("change", "error", "name"), BAD, ids=[b[2] + str(i) for i, b in enumerate(BAD)])
def test_bad_arguments_name_themselves(kothare_plant, change, error, name) -> None:
    args = {"plant": kothare_plant, "Q": K_Q1, "R": K_R, "u_max": K_UMAX, "input_constraint": "peak"}
    args.update(change)
    with pytest.raises(error) as info:
        OfflineRMPC(**args)
    assert str(info.value).startswith(f"{name}:") or str(info.value).startswith(f"{name}["), str(info.value)
    assert "expected" in str(info.value) and "found" in str(info.value)


@pytest.mark.parametrize("x", [[np.nan, 0.0], [0.1, 0.2, 0.3], "x"])
def test_bad_state_names_x(kothare_ctrl, x) -> None:
    with pytest.raises((InvalidArgumentError, ArgumentTypeError), match=r"^x:"):
        kothare_ctrl.step(x)


def test_column_state_is_accepted(kothare_ctrl) -> None:
    kothare_ctrl.reset()
    u_col = kothare_ctrl.step(K_X0.reshape(2, 1))
    u_vec = kothare_ctrl.step(K_X0)
    np.testing.assert_allclose(u_col, u_vec)
