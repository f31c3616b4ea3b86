"""ScheduledRMPC: the polytope rebuilt at the measured attitude (issue 11, part 4)."""

from __future__ import annotations

import numpy as np
import pytest

from lmi import KothareProblem
from models import RigidSatellite
from rmpc import RMPC, ScheduledRMPC, simulate
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError, SolverError

Q = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])
R = 0.01 * np.eye(3)


def test_each_step_solves_the_polytope_at_the_measured_attitude():
    sat = RigidSatellite.paper_p()
    ctrl = ScheduledRMPC.for_satellite(sat, 0.01, 0.3, Q, R, u_max=1.0)
    x = np.array([0.3, -0.4, 0.2, 0.01, -0.02, 0.0])
    u = ctrl.step(x)
    poly = sat.polytope(np.concatenate([x[:3], np.zeros(3)]), 0.01, 0.3)
    ref = KothareProblem(poly.A, poly.B, Q=Q, R=R, u_max=1.0, input_constraint="ellipsoid").solve(x)
    assert ctrl.last.status == "optimal"
    assert ctrl.last.extra["build_time"] > 0.0
    np.testing.assert_allclose(ctrl.last.gamma, ref.gamma, rtol=1e-5)
    # F follows gamma's accuracy only to about its square root (a flat optimum).
    np.testing.assert_allclose(u, ref.F @ x, atol=1e-3 * np.linalg.norm(u))
    assert np.linalg.norm(u) <= 1.0 + 1e-6


def test_scheduled_settles_the_nonlinear_satellite_inside_the_limit():
    sat = RigidSatellite.paper_p()
    ctrl = ScheduledRMPC.for_satellite(sat, 0.05, 0.3, Q, R, u_max=1.0)
    x0 = sat.initial_state()
    traj = simulate(ctrl, sat, x0, duration=10.0, dt=0.05)
    assert np.all(np.linalg.norm(traj.u_applied, axis=1) <= 1.0 + 1e-6)
    assert np.max(np.abs(traj.x[-1, :3])) < 0.1 * np.max(np.abs(x0[:3]))


def test_near_origin_keeps_the_last_gain():
    sat = RigidSatellite.paper_p()
    ctrl = ScheduledRMPC.for_satellite(sat, 0.01, 0.3, Q, R, u_max=1.0, hold_radius=1e-3)
    ctrl.step(np.array([0.1, 0.0, 0.0, 0, 0, 0]))
    gain = ctrl.gain
    u = ctrl.step(np.full(6, 1e-5))
    assert ctrl.last.status == "reused"
    np.testing.assert_allclose(u, gain @ np.full(6, 1e-5))


def test_failure_is_a_status_or_raises_on_request():
    sat = RigidSatellite.paper_p()
    # An input bound far too small for this state: infeasible.
    ctrl = ScheduledRMPC.for_satellite(sat, 0.01, 0.3, Q, R, u_max=1e-9)
    u = ctrl.step(np.array([1.0, 1.0, 1.0, 0.5, 0.5, 0.5]))
    assert ctrl.last.fallback
    assert ctrl.last.status != "optimal"
    np.testing.assert_array_equal(u, np.zeros(3))
    strict = ScheduledRMPC.for_satellite(sat, 0.01, 0.3, Q, R, u_max=1e-9, on_failure="raise")
    with pytest.raises(SolverError, match="on_failure='raise'"):
        strict.step(np.array([1.0, 1.0, 1.0, 0.5, 0.5, 0.5]))


def test_bad_arguments_are_named():
    sat = RigidSatellite.paper_p()
    with pytest.raises(ArgumentTypeError, match="polytope_at"):
        ScheduledRMPC("not callable", Q, R)
    with pytest.raises(ArgumentTypeError, match="satellite"):
        ScheduledRMPC.for_satellite("sat", 0.01, 0.3, Q, R)
    with pytest.raises(InvalidArgumentError, match="spread"):
        ScheduledRMPC.for_satellite(sat, 0.01, -1.0, Q, R)
    bad = ScheduledRMPC(lambda x: "no polytope", Q, R)
    with pytest.raises(ArgumentTypeError, match="polytope_at"):
        bad.step(np.ones(6))


def test_covering_polytope_rmpc_certifies_every_frozen_model_of_the_box():
    """The covering polytope's solution is invariant for the frozen model at any attitude of the box."""
    sat = RigidSatellite.paper_p()
    x0 = np.array([np.radians(40), np.radians(-30), 0.0, 0, 0, 0])
    half = np.abs(x0[:3]) / 2 + np.radians(5)
    poly = sat.polytope(np.concatenate([x0[:3] / 2, np.zeros(3)]), 0.05, 0.3, attitude_range=half)
    ctrl = RMPC(poly, Q, R, u_max=1.0)
    sol = ctrl.solve(x0)
    assert sol.status == "optimal"
    q_inv = np.linalg.inv(sol.Q)
    rng = np.random.default_rng(5)
    for _ in range(10):
        att = x0[:3] / 2 + rng.uniform(-1, 1, 3) * half
        a, b = RigidSatellite(sat.inertia * rng.uniform(0.7, 1.3)).polytope(
            np.concatenate([att, np.zeros(3)]), 0.05, 0.0, attitude_range=np.zeros(3)
        ).vertices[0]
        acl = a + b @ sol.F
        # Lyapunov decrease of the ellipsoid's matrix: Acl' Q^-1 Acl - Q^-1 < 0.
        assert np.max(np.linalg.eigvalsh(acl.T @ q_inv @ acl - q_inv)) < 0.0
