"""The closed-loop simulator with the LQR reference controller, disturbances, limiter, actuator.

With Q = diag(1, 1, 1, 0.1, 0.1, 0.1), R = I, dt = 0.01 s from paper P's initial attitude, the
times after which every |angle| stays below 1e-3 rad (nonlinear satellite, linear model), the
residual rates and offsets at the end of the runs and the aggressive LQR's peak command are the
toolkit's own earlier outputs: regression values, kept with their measurements, thresholds and
margins in ``tests/regression/sim_simulate.json`` (``python -m tests.regression.regenerate
sim_simulate`` regenerates them). The LQR gain, the closed-loop powers of the linear model and the
fixed points are outside references (python-control, SciPy, linear algebra) and stay here.
"""

from __future__ import annotations

import control
import numpy as np
import pytest
from regression import check
from scipy.integrate import solve_ivp
from scipy.linalg import solve_discrete_are

from models import PolytopicModel, ReactionWheelActuator, RigidSatellite, TorqueLimiter
from rmpc import LQR, ConstantDisturbance, StepDisturbance, StepInfo, Trajectory, simulate

DT = 0.01
Q = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])
R = np.eye(3)


@pytest.fixture(scope="module")
def sat() -> RigidSatellite:
    return RigidSatellite.paper_p()


@pytest.fixture(scope="module")
def x0(sat) -> np.ndarray:
    return sat.initial_state()


@pytest.fixture(scope="module")
def linear(sat, x0) -> PolytopicModel:
    return sat.linear_model(x0, DT)


@pytest.fixture(scope="module")
def lqr(linear) -> LQR:
    return LQR(linear, Q=Q, R=R)


@pytest.fixture(scope="module")
def nonlinear_run(sat, x0, lqr) -> Trajectory:
    return simulate(lqr, sat, x0, duration=25.0, dt=DT)


def _settled_from(traj: Trajectory, tol: float = 1e-3) -> float:
    """First time after which every |angle| stays below ``tol``."""
    above = np.nonzero(np.max(np.abs(traj.x[:, :3]), axis=1) >= tol)[0]
    return float(traj.t[above[-1] + 1]) if above.size else 0.0


# --- LQR -----------------------------------------------------------------------------


def test_lqr_gain_is_minus_dlqr_gain_and_riccati_solution(linear, lqr):
    a, b = linear.nominal
    k, _, _ = control.dlqr(a, b, Q, R)
    np.testing.assert_allclose(lqr.F, -np.asarray(k), rtol=1e-12, atol=1e-12)
    # independently of python-control: the DARE solution and K = (R + B'PB)^-1 B'PA
    p = solve_discrete_are(a, b, Q, R)
    np.testing.assert_allclose(lqr.P, p, rtol=1e-8)
    np.testing.assert_allclose(lqr.F, -np.linalg.solve(R + b.T @ p @ b, b.T @ p @ a), rtol=1e-8, atol=1e-10)
    # the closed loop is stable
    assert np.max(np.abs(np.linalg.eigvals(a + b @ lqr.F))) < 1.0


def test_lqr_on_a_vertex_and_with_a_reference(sat, x0):
    poly = sat.polytope(x0, DT, spread=0.3, mode="scalar")
    ctrl = LQR(poly, Q=Q, R=R, vertex=1)
    k, _, _ = control.dlqr(*poly.vertex(1), Q, R)
    np.testing.assert_allclose(ctrl.F, -np.asarray(k), rtol=1e-12, atol=1e-12)
    k0, _, _ = control.dlqr(*poly.vertex(0), Q, R)
    assert not np.allclose(ctrl.F, -np.asarray(k0))
    x_ref = np.array([0.1, 0.0, -0.1, 0.0, 0.0, 0.0])
    ref_ctrl = LQR(poly, Q=Q, R=R, x_ref=x_ref)
    x = np.array([0.2, 0.1, 0.0, 0.01, 0.0, 0.0])
    np.testing.assert_allclose(ref_ctrl.step(x), ref_ctrl.F @ (x - x_ref), rtol=1e-15)
    assert isinstance(ref_ctrl.last, StepInfo) and ref_ctrl.last.status == "ok"
    ref_ctrl.reset()
    assert ref_ctrl.last is None


# --- convergence -----------------------------------------------------------------------


def test_lqr_brings_the_nonlinear_satellite_to_zero_attitude(nonlinear_run):
    traj = nonlinear_run
    assert traj.plant == "nonlinear"
    assert np.max(np.abs(traj.x[0, :3])) > 0.5  # starts 0.524 rad away in pitch
    check("sim_simulate", "lqr_nonlinear_settled_s", _settled_from(traj))
    check("sim_simulate", "lqr_nonlinear_final_rate", np.max(np.abs(traj.x[-1, 3:])))
    assert np.max(np.abs(traj.u_applied)) < 1.0  # no limiter needed with these weights


def test_lqr_brings_the_linear_model_to_zero_attitude(x0, linear, lqr):
    traj = simulate(lqr, linear, x0, duration=25.0)
    assert traj.plant == "linear"
    check("sim_simulate", "lqr_linear_settled_s", _settled_from(traj))
    # independent: the linear closed loop is x(k) = (A + B F)^k x0
    a, b = linear.nominal
    acl = a + b @ lqr.F
    x = x0.copy()
    for _ in range(traj.n_steps):
        x = acl @ x
    np.testing.assert_allclose(traj.x[-1], x, rtol=1e-9, atol=1e-14)


def test_nonlinear_and_linear_loops_differ(nonlinear_run, x0, linear, lqr):
    """The nonlinear kinematics matter: same controller, visibly different transients."""
    lin = simulate(lqr, linear, x0, duration=25.0)
    gap = np.max(np.abs(lin.x[:, :3] - nonlinear_run.x[:, :3]))
    assert gap > 1e-2


# --- trajectory bookkeeping ------------------------------------------------------------


def test_trajectory_shapes_statuses_and_progress(sat, x0, lqr, tmp_path):
    calls = []
    traj = simulate(lqr, sat, x0, duration=0.5, dt=DT, progress=lambda k, n: calls.append((k, n)))
    n = 50
    assert traj.n_steps == n
    assert traj.t.shape == (n + 1,) and traj.x.shape == (n + 1, 6)
    for arr in (traj.u_cmd, traj.u_applied, traj.d):
        assert arr.shape == (n, 3)
    for arr in (traj.solve_time, traj.step_time, traj.gamma):
        assert arr.shape == (n,)
    assert len(traj.status) == len(traj.info) == n
    np.testing.assert_allclose(traj.t, DT * np.arange(n + 1), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(traj.x[0], x0)
    assert traj.status == ["ok"] * n and traj.status_counts() == {"ok": n}
    assert all(isinstance(i, StepInfo) for i in traj.info)
    assert np.all(np.isnan(traj.gamma))  # LQR has no cost bound
    assert np.all(traj.solve_time >= 0) and np.all(traj.step_time >= 0)
    np.testing.assert_array_equal(traj.d, 0.0)
    # no limiter, no actuator: what was commanded was applied, u = F x
    np.testing.assert_array_equal(traj.u_applied, traj.u_cmd)
    np.testing.assert_allclose(traj.u_cmd, traj.x[:-1] @ lqr.F.T, rtol=1e-12, atol=1e-15)
    # paper P's states are the roll, pitch and yaw themselves
    np.testing.assert_array_equal(traj.attitude_euler, traj.x[:, :3])
    np.testing.assert_array_equal(traj.attitude_deg, np.degrees(traj.x[:, :3]))
    assert calls == [(k, n) for k in range(1, n + 1)]
    assert traj.dt == DT
    # n_steps instead of duration gives the same run
    again = simulate(lqr, sat, x0, n_steps=n, dt=DT)
    np.testing.assert_array_equal(again.x, traj.x)
    # the arrays survive a round trip through .npz
    path = tmp_path / "traj.npz"
    traj.save_npz(str(path))
    with np.load(path) as data:
        np.testing.assert_array_equal(data["x"], traj.x)
        np.testing.assert_array_equal(data["attitude_deg"], traj.attitude_deg)
        assert list(data["status"]) == traj.status


def test_controller_without_info_gets_status_unknown(linear, x0):
    class Hold:
        last = None

        def step(self, x):
            return np.array([0.1, 0.0, -0.1])

    traj = simulate(Hold(), linear, x0, n_steps=3)
    assert traj.status == ["unknown"] * 3
    np.testing.assert_array_equal(traj.u_applied, np.tile([0.1, 0.0, -0.1], (3, 1)))


# --- disturbances ----------------------------------------------------------------------


def test_step_disturbance_on_the_linear_model_leaves_an_lqr_offset(x0, linear, lqr):
    mag = np.array([0.01, -0.02, 0.015])
    dist = StepDisturbance(mag, t_start=10.0)
    traj = simulate(lqr, linear, x0, duration=60.0, disturbance=dist)
    clean = simulate(lqr, linear, x0, duration=60.0)
    before, after = traj.t[:-1] < 10.0 - DT / 2, traj.t[:-1] > 10.0 + DT / 2
    np.testing.assert_array_equal(traj.d[before], 0.0)
    np.testing.assert_array_equal(traj.d[after], np.tile(mag, (after.sum(), 1)))
    # identical up to the step (the state at 10 s has not seen it yet), different after
    upto = traj.t <= 10.0 + 1e-9
    np.testing.assert_array_equal(traj.x[upto], clean.x[upto])
    assert np.max(np.abs(traj.x[-1] - clean.x[-1])) > 1e-3
    # plain LQR keeps a constant offset: the fixed point of x = (A + B F) x + B d
    a, b = linear.nominal
    x_ss = np.linalg.solve(np.eye(6) - a - b @ lqr.F, b @ mag)
    assert np.max(np.abs(x_ss[:3])) > 1e-3  # a real attitude offset (0.025 rad in pitch)
    np.testing.assert_allclose(x_ss[3:], 0.0, atol=1e-15)  # at rest
    check("sim_simulate", "step_offset_gap_60s", np.max(np.abs(traj.x[-1] - x_ss)))
    # at the offset the controller cancels the disturbance torque exactly
    np.testing.assert_allclose(lqr.F @ x_ss, -mag, rtol=1e-9, atol=1e-15)


def test_constant_disturbance_offset_on_the_nonlinear_satellite(sat, x0, lqr):
    """At rest (w = 0) the torque balances d: F[:, :3] eta = -d, a non-zero attitude offset.

    At 25 s the loop is still converging to it: the gaps are regression values.
    """
    mag = np.array([0.02, 0.0, -0.01])
    traj = simulate(lqr, sat, x0, duration=25.0, dt=DT, disturbance=ConstantDisturbance(mag))
    eta_ss = np.linalg.solve(lqr.F[:, :3], -mag)
    assert np.max(np.abs(eta_ss)) > 5e-3  # 0.019 rad of roll: the offset integral action removes
    check("sim_simulate", "constant_offset_attitude_gap_25s", np.max(np.abs(traj.x[-1, :3] - eta_ss)))
    check("sim_simulate", "constant_offset_torque_gap_25s", np.max(np.abs(traj.u_applied[-1] + mag)))
    np.testing.assert_array_equal(traj.d, np.tile(mag, (traj.n_steps, 1)))


def test_step_disturbance_at_a_sample_instant_on_the_nonlinear_satellite(sat, x0, lqr):
    """A step at t = 1 s (a sample time) does not leak into the sample before it."""
    mag = np.array([0.05, -0.05, 0.05])
    traj = simulate(lqr, sat, x0, duration=1.05, dt=DT, disturbance=StepDisturbance(mag, 1.0))
    clean = simulate(lqr, sat, x0, duration=1.05, dt=DT)
    k = 100
    assert traj.t[k] == pytest.approx(1.0)
    np.testing.assert_array_equal(traj.d[:k], 0.0)
    np.testing.assert_array_equal(traj.d[k:], np.tile(mag, (traj.n_steps - k, 1)))
    np.testing.assert_array_equal(traj.x[: k + 1], clean.x[: k + 1])
    assert np.max(np.abs(traj.x[k + 1] - clean.x[k + 1])) > 1e-7


def test_step_disturbance_inside_a_sample_on_the_nonlinear_satellite(sat, x0, lqr):
    """A step at 1.005 s: logged from the next sample on, but felt from 1.005 s on."""
    mag = np.array([0.05, -0.05, 0.05])
    traj = simulate(lqr, sat, x0, duration=1.02, dt=DT, disturbance=StepDisturbance(mag, 1.005))
    clean = simulate(lqr, sat, x0, duration=1.02, dt=DT)
    k = 100  # the sample [1.00, 1.01)
    assert traj.t[k] == pytest.approx(1.0)
    np.testing.assert_array_equal(traj.d[k], 0.0)
    np.testing.assert_array_equal(traj.d[k + 1], mag)
    np.testing.assert_array_equal(traj.x[: k + 1], clean.x[: k + 1])
    assert np.max(np.abs(traj.x[k + 1] - clean.x[k + 1])) > 1e-7
    # independent reference for that sample: integrate the two pieces by hand
    u = traj.u_applied[k]
    first = solve_ivp(lambda _t, y: sat.dynamics(y, u), (1.0, 1.005), traj.x[k],
                      method="DOP853", rtol=1e-12, atol=1e-14)
    second = solve_ivp(lambda _t, y: sat.dynamics(y, u, mag), (1.005, 1.01), first.y[:, -1],
                       method="DOP853", rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(traj.x[k + 1], second.y[:, -1], rtol=0, atol=1e-12)


# --- limiter and actuator --------------------------------------------------------------


def test_limiter_clips_applied_torque_to_one(sat, x0, linear):
    aggressive = LQR(linear, Q=np.diag([10.0, 10.0, 10.0, 1.0, 1.0, 1.0]), R=np.eye(3))
    traj = simulate(aggressive, sat, x0, duration=5.0, dt=DT, limiter=TorqueLimiter(1.0))
    check("sim_simulate", "aggressive_lqr_peak_command", np.max(np.abs(traj.u_cmd)))  # the limiter has work
    assert np.max(np.abs(traj.u_cmd)) > 1.0
    assert np.max(np.abs(traj.u_applied)) <= 1.0
    np.testing.assert_array_equal(traj.u_applied, np.clip(traj.u_cmd, -1.0, 1.0))
    assert np.any(np.abs(traj.u_applied) == 1.0)
    # the plant was driven by the clipped torque: rerun open loop with it
    clipped_run = simulate(_Replay(traj.u_applied), sat, x0, n_steps=traj.n_steps, dt=DT)
    np.testing.assert_allclose(clipped_run.x, traj.x, rtol=0, atol=1e-13)


class _Replay:
    """Plays back a recorded input sequence."""

    last = None

    def __init__(self, inputs: np.ndarray) -> None:
        self.inputs = inputs
        self.k = 0

    def reset(self) -> None:
        self.k = 0

    def step(self, x: np.ndarray) -> np.ndarray:
        u = self.inputs[self.k]
        self.k += 1
        return u


def test_reaction_wheel_dc_gain_and_step_response():
    a, b, c = 0.86, 0.0093, 14.28  # as printed in paper P
    wheel = ReactionWheelActuator()
    assert wheel.dc_gain == pytest.approx(c * b / (1 - a), rel=1e-14)
    assert wheel.dc_gain == pytest.approx(0.9486, abs=1e-4)
    outputs = np.array([wheel.step([1.0, -2.0, 0.5]) for _ in range(100)])
    k = np.arange(100)
    # y(k) = c b (1 - a^k) / (1 - a): one sample of delay, first-order rise to the DC gain
    expected = np.outer(wheel.dc_gain * (1.0 - a**k), [1.0, -2.0, 0.5])
    np.testing.assert_allclose(outputs, expected, rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(outputs[0], 0.0)
    assert outputs[-1, 0] == pytest.approx(wheel.dc_gain, rel=1e-6)
    wheel.reset()
    np.testing.assert_array_equal(wheel.state, 0.0)


def test_actuator_in_the_loop_is_reset_and_filters_the_command(x0, linear, lqr):
    wheel = ReactionWheelActuator()
    wheel.step([5.0, 5.0, 5.0])  # dirty state: simulate must reset it
    traj = simulate(lqr, linear, x0, duration=1.0, actuator=wheel)
    xa = np.zeros(3)
    for k in range(traj.n_steps):
        np.testing.assert_allclose(traj.u_applied[k], 14.28 * xa, rtol=1e-12, atol=1e-15)
        xa = 0.86 * xa + 0.0093 * traj.u_cmd[k]
    assert np.max(np.abs(traj.u_applied - traj.u_cmd)) > 1e-2


# --- true_plant --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def poly(sat, x0) -> PolytopicModel:
    return sat.polytope(x0, DT, spread=0.3, mode="scalar")


def _manual(a: np.ndarray, b: np.ndarray, f: np.ndarray, x0: np.ndarray, n: int) -> np.ndarray:
    xs = [x0]
    for _ in range(n):
        xs.append(a @ xs[-1] + b @ (f @ xs[-1]))
    return np.array(xs)


@pytest.mark.parametrize(
    "selector",
    [None, 0, 1, np.int64(1), [0.25, 0.75], np.array([1.0, 0.0]), "pair"],
    ids=["nominal", "vertex-0", "vertex-1", "np-int", "weights-list", "weights-array", "pair"],
)
def test_true_plant_selects_the_simulated_member(poly, x0, selector):
    ctrl = LQR(poly, Q=Q, R=R)
    (a0, b0), (a1, b1) = poly.vertices
    if selector is None:
        a, b = poly.nominal
        true_plant = None
    elif isinstance(selector, str):
        a, b = a1, 0.4 * b0 + 0.6 * b1
        true_plant = (a, b)
    elif np.ndim(selector) == 0:
        a, b = poly.vertices[int(selector)]
        true_plant = selector
    else:
        w = np.asarray(selector, dtype=float)
        a, b = w[0] * a0 + w[1] * a1, w[0] * b0 + w[1] * b1
        true_plant = selector
    traj = simulate(ctrl, poly, x0, n_steps=200, true_plant=true_plant)
    np.testing.assert_allclose(traj.x, _manual(a, b, ctrl.F, x0, 200), rtol=1e-12, atol=1e-14)


def test_true_plant_vertices_give_different_runs(poly, x0):
    ctrl = LQR(poly, Q=Q, R=R)
    run0 = simulate(ctrl, poly, x0, n_steps=200, true_plant=0)
    run1 = simulate(ctrl, poly, x0, n_steps=200, true_plant=1)
    assert np.max(np.abs(run0.x - run1.x)) > 1e-3
