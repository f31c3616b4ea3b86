"""ScheduledRMPC: the polytope rebuilt at the measured attitude (issue 11, part 4)."""

from __future__ import annotations

import numpy as np
import pytest

from lmi import KothareProblem
from models import RigidSatellite
from rmpc import RMPC, ScheduledRMPC, simulate
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError, NoCertifiedGainWarning, SolverError

Q = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])
R = 0.01 * np.eye(3)


def _problem(sat: RigidSatellite, attitude: np.ndarray, dt: float) -> KothareProblem:
    """The Kothare problem on the polytope frozen at ``attitude`` (zero rates), built here."""
    poly = sat.polytope(np.concatenate([attitude, np.zeros(3)]), dt, 0.3)
    return KothareProblem(poly.A, poly.B, dt=dt, Q=Q, R=R, u_max=1.0, input_constraint="ellipsoid")


def test_each_step_solves_the_polytope_at_the_measured_attitude():
    """Two steps at attitudes far apart, each against the problem built at its own attitude.

    The second state's gamma on the first state's polytope is 31 % above its own (measured), so
    a controller that kept the first step's problem fails the second comparison. Measured
    agreement with the reference: gamma and ``u`` equal (the same computation); asserted to
    1e-8 relative, a margin for another CPU's rounding far below the 31 %.
    """
    sat = RigidSatellite.paper_p()
    ctrl = ScheduledRMPC.for_satellite(sat, 0.01, 0.3, Q, R, u_max=1.0)
    states = [np.array([0.3, -0.4, 0.2, 0.01, -0.02, 0.0]), np.array([-0.5, 0.6, -0.3, 0.0, 0.02, -0.01])]
    for x in states:
        u = ctrl.step(x)
        ref = _problem(sat, x[:3], 0.01).solve(x)
        assert ctrl.last.status == "optimal"
        assert ctrl.last.extra["build_time"] > 0.0
        np.testing.assert_allclose(ctrl.last.gamma, ref.gamma, rtol=1e-8)
        np.testing.assert_allclose(u, ref.F @ x, rtol=1e-8, atol=1e-8 * np.linalg.norm(u))
        assert np.linalg.norm(u) <= 1.0 + 1e-6
    stale = _problem(sat, states[0][:3], 0.01).solve(states[1])
    assert stale.gamma > 1.2 * ctrl.last.gamma  # the check above can tell the two problems apart


@pytest.fixture(scope="module")
def closed_loop():
    """10 s of the nonlinear satellite under scheduling, 200 steps of 0.05 s."""
    sat = RigidSatellite.paper_p()
    ctrl = ScheduledRMPC.for_satellite(sat, 0.05, 0.3, Q, R, u_max=1.0)
    x0 = sat.initial_state()
    return sat, x0, simulate(ctrl, sat, x0, duration=10.0, dt=0.05)


def test_scheduled_settles_the_nonlinear_satellite_inside_the_limit(closed_loop):
    _, x0, traj = closed_loop
    assert np.all(np.linalg.norm(traj.u_applied, axis=1) <= 1.0 + 1e-6)
    assert np.max(np.abs(traj.x[-1, :3])) < 0.1 * np.max(np.abs(x0[:3]))


@pytest.mark.parametrize("k", [20, 50])
def test_closed_loop_step_solves_at_its_own_attitude(closed_loop, k):
    """Step ``k`` of the loop used the polytope at ``x_k``'s attitude, not the first step's.

    Measured: the gamma the loop recorded equals a fresh solve on the polytope at ``x_k``
    exactly (the same computation); on the polytope at ``x_0`` the same state gives a gamma
    6.2 % (k = 20, attitude (14, 21, -14) deg against (21, 30, -15) deg at k = 0) and 13.5 %
    (k = 50, (2, 3, -6) deg) away.
    Asserted 1e-8 relative: a margin for the rounding of another CPU, far below 6 %.
    """
    sat, _, traj = closed_loop
    assert traj.status[k] == "optimal"
    x = traj.x[k]
    own = _problem(sat, x[:3], 0.05).solve(x)
    np.testing.assert_allclose(traj.gamma[k], own.gamma, rtol=1e-8)


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
    with pytest.warns(NoCertifiedGainWarning, match="input bound u_max = 1e-09"):
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
