"""The public surface as the API contract writes it: names, import places, calls and protocols.

Users, the documentation and outside checks rely on these names and calls exactly as written
here; each test is a line of the contract run as code. A rename or a move that breaks one of
them fails here, whatever else the tests cover.
"""

from __future__ import annotations

import json

import control
import numpy as np
import pytest

from models import (
    FlexibleSatellite,
    MRPSatellite,
    PolytopicModel,
    RigidSatellite,
    WheelArray,
    WheelFault,
    WheelSatellite,
)
from models.mrp import mrp_error, mrp_shadow, mrp_to_dcm
from models.protocols import Plant
from rmpc import (
    CRMPC,
    CSMC,
    GIPC,
    MAB,
    MTSMC,
    NESO,
    RMPC,
    AdaptiveBacksteppingFTC,
    CFBackstepping,
    CommandFilter,
    Controller,
    OfflineRMPC,
    RobustAVC,
    Status,
    StepInfo,
    TuningFunctionAB,
    simulate,
)

Q1 = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])


@pytest.fixture(scope="module")
def sat() -> RigidSatellite:
    return RigidSatellite(inertia=[1.2928, 1.2928, 4.2953])


def test_polytope_from_explicit_vertices() -> None:
    a1, b1 = np.eye(2), np.array([[0.0], [0.1]])
    a2, b2 = np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.0], [0.2]])
    plant = PolytopicModel(vertices=[(a1, b1), (a2, b2)], dt=0.1)
    assert (plant.n_vertices, plant.n_states, plant.n_inputs, plant.dt) == (2, 2, 1, 0.1)


def test_the_satellite_its_polytopes_and_a_full_inertia(sat) -> None:
    x_op = sat.initial_state()
    scalar = sat.polytope(x_op, dt=0.01, spread=0.3, mode="scalar")
    box = sat.polytope(x_op, dt=0.01, spread=0.3, mode="box")
    cover = sat.polytope(x_op, dt=0.01, spread=0.3, attitude_range=np.radians([30, 30, 30]))
    assert isinstance(scalar, PolytopicModel) and scalar.n_vertices == 2 and box.n_vertices == 8
    assert cover.n_vertices > scalar.n_vertices
    full = RigidSatellite(inertia=np.diag([1.2928, 1.2928, 4.2953]))
    np.testing.assert_array_equal(full.inertia, sat.inertia)


def test_rmpc_solve_and_step_as_written(sat) -> None:
    x = sat.initial_state()
    plant = sat.polytope(x, dt=0.01, spread=0.3, mode="scalar")
    ctrl = RMPC(plant, Q=Q1, R=np.eye(3), u_max=2.0, input_constraint="peak")
    sol = ctrl.solve(x)
    assert isinstance(sol.gamma, float) and sol.F.shape == (3, 6) and sol.status == "optimal"
    assert sol.Q.shape == (6, 6) and sol.Y.shape == (3, 6) and sol.solve_time > 0.0
    u = ctrl.step(x)
    np.testing.assert_allclose(u, ctrl.last.extra["solution"].F @ x)
    for kind in ("ellipsoid", "peak", None):
        RMPC(plant, Q=Q1, R=np.eye(3), u_max=None if kind is None else 1.0, input_constraint=kind)


def test_every_controller_of_the_contract_follows_the_step_protocol(sat) -> None:
    x = sat.initial_state()
    plant = sat.polytope(x, dt=0.01, spread=0.3, mode="scalar")
    controllers = [
        RMPC(plant, Q=Q1, R=np.eye(3), u_max=1.0),
        OfflineRMPC(plant, Q=Q1, R=np.eye(3), u_max=1.0, input_constraint="ellipsoid"),
        GIPC(plant),
        CRMPC(plant, Q=Q1, R=np.eye(3), u_max=1.0),
    ]
    for ctrl in controllers:
        assert isinstance(ctrl, Controller), type(ctrl).__name__
        ctrl.reset()
        u = ctrl.step(x)
        assert u.shape == (3,) and np.all(np.isfinite(u))
        assert isinstance(ctrl.last, StepInfo) and isinstance(ctrl.last.status, Status)
        assert isinstance(ctrl.name, str) and ctrl.name


def test_simulate_returns_the_trajectory_with_its_attitude(sat) -> None:
    x0 = sat.initial_state()
    plant = sat.polytope(x0, dt=0.01, spread=0.3, mode="scalar")
    ctrl = RMPC(plant, Q=Q1, R=np.eye(3), u_max=1.0)
    traj = simulate(ctrl, sat, x0, duration=0.05, dt=0.01)
    for name in ("t", "x", "u_applied", "u_cmd", "solve_time", "status"):
        assert hasattr(traj, name)
    assert traj.x.shape == (6, 6) and traj.u_cmd.shape == (5, 3) and len(traj.status) == 5
    # the rigid satellite's state holds its 3-2-1 Euler angles: attitude_deg is their degrees
    np.testing.assert_allclose(traj.attitude_deg, np.degrees(traj.x[:, :3]), rtol=0, atol=1e-12)


def test_later_systems_as_written() -> None:
    wheels = WheelArray.paper_w()
    assert wheels.D.shape == (3, 4)
    np.testing.assert_allclose(np.linalg.norm(wheels.D, axis=0), 1.0)
    assert np.all(np.asarray(wheels.torque_max) > 0) and np.all(np.asarray(wheels.momentum_max) > 0)
    sat_w = WheelSatellite.paper_w()
    assert (sat_w.n_states, sat_w.n_inputs) == (10, 4)
    fault = WheelFault(wheel=2, kind="stuck", t_on=8.0, t_off=37.0, value=0.05)
    assert fault.wheel == 2
    for kind, extra in (("stuck", {"value": 0.05}), ("sinusoidal", {"value": 0.03}), ("outage", {}),
                        ("effectiveness", {"effectiveness": 0.5}), ("bias", {"value": 0.01})):
        assert WheelFault(wheel=1, kind=kind, t_on=1.0, t_off=2.0, **extra).kind == kind
    poly_w = sat_w.polytope(dt=0.04, effectiveness="single_outage")
    assert (poly_w.n_vertices, poly_w.n_states, poly_w.n_inputs) == (5, 6, 4)
    ftc = AdaptiveBacksteppingFTC(sat_w)
    assert ftc.step(sat_w.state(np.radians([5.0, -3.0, 10.0]))).shape == (4,)

    sat_m = MRPSatellite.paper_m()
    assert (sat_m.n_states, sat_m.n_inputs) == (6, 3)
    sigma, sigma_ref = np.array([0.1, -0.2, 0.05]), np.array([0.02, 0.03, -0.1])
    assert mrp_to_dcm(sigma).shape == (3, 3)
    np.testing.assert_allclose(mrp_to_dcm(mrp_error(sigma, sigma_ref)),
                               mrp_to_dcm(sigma) @ mrp_to_dcm(sigma_ref).T, atol=1e-12)
    np.testing.assert_allclose(mrp_to_dcm(mrp_shadow(sigma)), mrp_to_dcm(sigma), atol=1e-12)

    sat_f = FlexibleSatellite.di_gennaro()
    a, b = sat_f.linearize()
    assert a.shape == (14, 14) and b.shape == (14, 3)
    assert isinstance(sat_f.single_axis_tf(axis=0), control.TransferFunction)
    for cls in (CommandFilter, NESO, CFBackstepping, MAB, TuningFunctionAB, MTSMC, CSMC, RobustAVC):
        assert callable(cls)


def test_every_plant_follows_the_plant_protocol() -> None:
    plants = [RigidSatellite.paper_p(), WheelSatellite.paper_w(), MRPSatellite.paper_m(),
              FlexibleSatellite.di_gennaro()]
    for plant in plants:
        assert isinstance(plant, Plant), type(plant).__name__
        n, m = plant.n_states, plant.n_inputs
        assert len(plant.state_names) == n and len(plant.input_names) == m
        x = np.zeros(n)
        if isinstance(plant, FlexibleSatellite):
            x[0] = 1.0  # the unit quaternion at rest
        assert np.asarray(plant.dynamics(x, np.zeros(m))).shape == (n,)
        np.testing.assert_allclose(plant.attitude_euler(x), np.zeros(3), atol=1e-15)


def test_records_hold_status_words_as_plain_strings() -> None:
    info = StepInfo(status="reused")
    assert info.status is Status.REUSED
    assert json.loads(json.dumps({"status": info.status})) == {"status": "reused"}
