"""GIPC: the velocity-form MPC against an independent unconstrained solution, its bounds in
closed loop, integral action on the nonlinear satellite, failures and argument checks."""

from __future__ import annotations

import numpy as np
import pytest
from regression import check

from models import PolytopicModel, RigidSatellite
from rmpc import GIPC, StepDisturbance, simulate
from rmpc.controller import Controller
from rmpc.mpc.gipc import prediction_matrices, velocity_form
from rmpc.qp import ProxQPBackend, QPBackend, QPResult, SolverResiduals
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

FAST = ("proxqp", "osqp", "clarabel")


@pytest.fixture(scope="module")
def sat() -> RigidSatellite:
    return RigidSatellite.paper_p()


@pytest.fixture(scope="module")
def lin(sat: RigidSatellite) -> PolytopicModel:
    return sat.linear_model(sat.initial_state(), 0.01)


def predicted_outputs(a, b, c, x, x_prev, du_seq, n_p, n_c):
    """Outputs over the horizon by simulating the velocity form step by step (no matrices)."""
    m = b.shape[1]
    dx, xk, ys = x - x_prev, x.copy(), []
    for i in range(n_p):
        du = du_seq[i * m:(i + 1) * m] if i < n_c else np.zeros(m)
        dx = a @ dx + b @ du
        xk = xk + dx
        ys.append(c @ xk)
    return np.concatenate(ys)


def unconstrained_du(a, b, c, qy, r_du, x, x_prev, y_ref, n_p, n_c):
    """argmin sum |y_ref - y|^2_Qy + |du|^2_Rdu by a linear solve (the analytic solution)."""
    m = b.shape[1]
    nz = n_c * m
    y0 = predicted_outputs(a, b, c, x, x_prev, np.zeros(nz), n_p, n_c)
    phi = np.column_stack([predicted_outputs(a, b, c, x, x_prev, e, n_p, n_c) - y0 for e in np.eye(nz)])
    qbar = np.kron(np.eye(n_p), qy)
    rbar = np.kron(np.eye(n_c), r_du)
    rs = np.tile(y_ref, n_p)
    return np.linalg.solve(phi.T @ qbar @ phi + rbar, phi.T @ qbar @ (rs - y0))


def test_prediction_matrices_match_a_simulation(lin: PolytopicModel) -> None:
    a, b = lin.nominal
    c = np.eye(6)[:3]
    rng = np.random.default_rng(0)
    x, x_prev = rng.normal(size=6), rng.normal(size=6)
    f, phi = prediction_matrices(*velocity_form(a, b, c), n_p=30, n_c=4)
    du = rng.normal(size=12)
    xa = np.concatenate((x - x_prev, c @ x))
    expected = predicted_outputs(a, b, c, x, x_prev, du, 30, 4)
    np.testing.assert_allclose(f @ xa + phi @ du, expected, atol=1e-12)


@pytest.mark.parametrize("backend", FAST)
def test_unconstrained_gipc_equals_the_linear_solve(lin: PolytopicModel, backend: str) -> None:
    a, b = lin.nominal
    qy = np.diag([2.0, 1.0, 0.5])
    r_du = np.array([[1.0, 0.2, 0.0], [0.2, 2.0, 0.0], [0.0, 0.0, 0.5]])
    x_ref = np.array([0.1, -0.05, 0.02, 0.0, 0.0, 0.0])
    ctrl = GIPC(lin, Np=80, Nc=5, Qy=qy, R_du=r_du, u_max=None, du_max=None, backend=backend, x_ref=x_ref)
    rng = np.random.default_rng(1)
    x1 = 0.3 * rng.normal(size=6)
    x2 = x1 + 0.01 * rng.normal(size=6)
    u1 = ctrl.step(x1)  # first step: dx = 0, u(k-1) = 0
    du1 = unconstrained_du(a, b, ctrl.C, qy, r_du, x1, x1, ctrl.C @ x_ref, 80, 5)
    np.testing.assert_allclose(u1, du1[:3], rtol=1e-6, atol=1e-9 * np.abs(du1).max())
    u2 = ctrl.step(x2)  # second step: dx = x2 - x1, u(k-1) = u1
    du2 = unconstrained_du(a, b, ctrl.C, qy, r_du, x2, x1, ctrl.C @ x_ref, 80, 5)
    np.testing.assert_allclose(u2, u1 + du2[:3], rtol=1e-6, atol=1e-9 * np.abs(du2).max())
    assert ctrl.last.status == "optimal" and not ctrl.last.fallback


@pytest.mark.parametrize("backend", FAST)
def test_bounds_hold_at_every_step(lin: PolytopicModel, sat: RigidSatellite, backend: str) -> None:
    """u and du inside their bounds at every step, with both bounds reached at some step."""
    u_max = np.array([0.08, 0.06, 0.2])
    du_max = np.array([0.01, 0.005, 0.01])
    ctrl = GIPC(lin, u_max=u_max, du_max=du_max, backend=backend)
    traj = simulate(ctrl, lin, sat.initial_state(), duration=20.0)
    assert traj.status_counts() == {"optimal": traj.n_steps}
    u = traj.u_cmd
    du = np.diff(np.vstack((np.zeros(3), u)), axis=0)
    assert np.all(np.abs(u) <= u_max + 1e-12)
    assert np.all(np.abs(du) <= du_max + 1e-12)
    np.testing.assert_allclose(np.abs(u).max(axis=0), u_max, rtol=1e-9)     # u bound active
    np.testing.assert_allclose(np.abs(du).max(axis=0), du_max, rtol=1e-9)   # du bound active
    assert np.abs(traj.x[-1, :3]).max() < 1e-2


def test_disturbance_rejection_on_the_nonlinear_satellite(sat: RigidSatellite, lin: PolytopicModel) -> None:
    """Experiment E4: a 0.5 N m step torque on every axis from t = 10 s.

    With the defaults (Np = 400, Nc = 4, Qy = 1, R_du = 1, |u| <= 1, |du| <= 0.01) the
    attitude error peaks at about 6.4 deg after the step and is back below 1e-3 rad at
    t = 20.2 s (measured), below 1e-5 rad by t = 30 s; the control settles at -0.5 N m,
    cancelling the disturbance: integral action. These four numbers are regression values in
    ``tests/regression/gipc.json`` (``python -m tests.regression.regenerate gipc``).
    """
    x0 = sat.initial_state()
    ctrl = GIPC(lin)
    traj = simulate(ctrl, sat, x0, duration=32.0, dt=0.01, disturbance=StepDisturbance([0.5, 0.5, 0.5], 10.0))
    assert traj.status_counts() == {"optimal": traj.n_steps}
    err = np.abs(traj.x[:, :3]).max(axis=1)
    check("gipc", "e4_peak_error_after_onset_deg", np.degrees(err[traj.t >= 10.5].max()))  # it did push
    settled = traj.t[np.flatnonzero(err >= 1e-3)[-1] + 1]
    check("gipc", "e4_settled_s", settled)
    check("gipc", "e4_attitude_32s", err[-1])
    check("gipc", "e4_torque_gap_32s", np.max(np.abs(traj.u_cmd[-1] + 0.5)))  # u cancels d
    assert np.abs(traj.u_cmd).max() <= 1.0 + 1e-12
    assert np.abs(np.diff(traj.u_cmd, axis=0)).max() <= 0.01 + 1e-12


def test_protocol_reset_and_memory(lin: PolytopicModel, sat: RigidSatellite) -> None:
    ctrl = GIPC(lin, Np=100, Nc=3)
    assert isinstance(ctrl, Controller)
    x0 = sat.initial_state()
    xs = [x0, x0 + 1e-3, x0 + 3e-3]
    first = [ctrl.step(x) for x in xs]
    np.testing.assert_allclose(ctrl.u_prev, first[-1])
    ctrl.reset()
    assert ctrl.last is None and np.all(ctrl.u_prev == 0.0)
    again = [ctrl.step(x) for x in xs]
    np.testing.assert_allclose(again, first, atol=1e-10)
    info = ctrl.last
    assert info.status == "optimal" and info.solve_time > 0 and info.iterations is not None
    assert set(ctrl.settings()) >= {"Np", "Nc", "Qy", "R_du", "u_max", "du_max", "backend"}


class CountingBackend(ProxQPBackend):
    """ProxQP that counts setups and updates."""

    def __init__(self) -> None:
        super().__init__()
        self.setups = 0
        self.updates = 0

    def setup(self, qp) -> None:
        self.setups += 1
        super().setup(qp)

    def update(self, **vectors) -> None:
        self.updates += 1
        assert set(vectors) <= {"g", "l", "u", "lb", "ub"}
        super().update(**vectors)


def test_qp_is_built_once_and_only_vectors_change(lin: PolytopicModel, sat: RigidSatellite) -> None:
    be = CountingBackend()
    ctrl = GIPC(lin, backend=be)
    simulate(ctrl, lin, sat.initial_state(), n_steps=50)
    assert be.setups == 1 and be.updates == 49
    simulate(ctrl, lin, sat.initial_state(), n_steps=5)  # reset() keeps the built QP
    assert be.setups == 1


class FailingBackend(ProxQPBackend):
    """Returns a chosen status (and x) after the first step."""

    def __init__(self, status: str, x_scale: float = 0.0) -> None:
        super().__init__()
        self.fail_status, self.x_scale, self.calls = status, x_scale, 0

    def solve(self) -> QPResult:
        self.calls += 1
        res = super().solve()
        if self.calls < 3:
            return res
        fill = self.x_scale if self.fail_status == "optimal" else np.nan
        x = np.full(res.x.shape, fill)
        return QPResult(
            x=x, objective=float("nan"), status=self.fail_status, iterations=7, solve_time=1e-4,
            residuals=SolverResiduals(), y_C=res.y_C, y_box=res.y_box, raw_status="fake", backend="proxqp",
        )


@pytest.mark.parametrize(
    ("status", "x_scale", "expected"),
    [("numerical_error", 0.0, "numerical_error"), ("max_iterations", 0.0, "max_iterations"),
     ("time_limit", 0.0, "time_limit"), ("optimal", 0.5, "bound_violation")],
)
def test_solver_failure_holds_the_previous_input(
    lin: PolytopicModel, sat: RigidSatellite, status: str, x_scale: float, expected: str
) -> None:
    ctrl = GIPC(lin, backend=FailingBackend(status, x_scale))
    x0 = sat.initial_state()
    ctrl.step(x0)
    u_before = ctrl.step(x0)
    u = ctrl.step(x0)
    np.testing.assert_array_equal(u, u_before)  # du = 0: inside both bounds
    assert ctrl.last.status == expected and ctrl.last.fallback
    assert ctrl.last.iterations == 7


@pytest.mark.parametrize("backend", ["osqp", "clarabel"])
def test_a_solve_stopped_by_its_time_limit_holds_the_previous_input(
    lin: PolytopicModel, sat: RigidSatellite, backend: str
) -> None:
    """A real ``time_limit`` from the back-end (not a faked status) is a fallback like any failure.

    OSQP and Clarabel read their clock before the first iteration, so 1e-9 s stops every solve.
    """
    x0 = sat.initial_state()
    ctrl = GIPC(lin, backend=backend, solver_options={"time_limit": 1e-9}, u0=[0.1, -0.1, 0.0])
    for _ in range(2):
        u = ctrl.step(x0)
        np.testing.assert_array_equal(u, [0.1, -0.1, 0.0])  # u0 held: du = 0
        assert ctrl.last.status == "time_limit" and ctrl.last.fallback
        np.testing.assert_array_equal(ctrl.last.extra["du"], np.zeros(3))
    free = GIPC(lin, backend=backend, u0=[0.1, -0.1, 0.0])  # the default limit: the same step solves
    free.step(x0)
    assert free.last.status == "optimal" and not free.last.fallback


# -- arguments ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "argument"),
    [
        ({"Np": 0}, "Np"),
        ({"Np": 2.5}, "Np"),
        ({"Np": 10, "Nc": 11}, "Nc"),
        ({"Nc": 0}, "Nc"),
        ({"Qy": [[1.0, 2.0], [2.0, 1.0]]}, "Qy"),                 # wrong size
        ({"Qy": np.diag([1.0, -1.0, 1.0])}, "Qy"),                # indefinite
        ({"R_du": 0.0}, "R_du"),                                  # not definite
        ({"R_du": [1.0, 1.0]}, "R_du"),
        ({"u_max": -1.0}, "u_max"),
        ({"du_max": [0.01, 0.0, 0.01]}, "du_max"),
        ({"C": np.eye(5)}, "C"),
        ({"x_ref": np.zeros(5)}, "x_ref"),
        ({"u0": [2.0, 0.0, 0.0]}, "u0"),                          # outside u_max
        ({"backend": "gurobi"}, "backend"),
        ({"solver_options": {"eps": 1.0}}, "settings 'eps'"),
        ({"backend": ProxQPBackend(), "solver_options": {"eps_abs": 1e-6}}, "solver_options"),
    ],
)
def test_bad_arguments_name_themselves(lin: PolytopicModel, kwargs: dict, argument: str) -> None:
    with pytest.raises(InvalidArgumentError) as err:
        GIPC(lin, **kwargs)
    assert str(err.value).startswith(f"{argument}:"), str(err.value)


def test_bad_types_and_states(lin: PolytopicModel) -> None:
    with pytest.raises(ArgumentTypeError, match=r"^plant:"):
        GIPC("satellite")  # type: ignore[arg-type]
    with pytest.raises(ArgumentTypeError, match=r"^backend:"):
        GIPC(lin, backend=3)  # type: ignore[arg-type]
    ctrl = GIPC(lin)
    with pytest.raises(InvalidArgumentError, match=r"^x:"):
        ctrl.step(np.zeros(5))
    with pytest.raises(InvalidArgumentError, match=r"^x:"):
        ctrl.step([0.0, 0.0, np.nan, 0.0, 0.0, 0.0])


def test_solver_options_reach_the_backend(lin: PolytopicModel) -> None:
    ctrl = GIPC(lin, backend="osqp", solver_options={"eps_abs": 1e-7})
    assert ctrl.backend.name == "osqp" and ctrl.backend.settings.eps_abs == 1e-7
    assert isinstance(ctrl.backend, QPBackend)
