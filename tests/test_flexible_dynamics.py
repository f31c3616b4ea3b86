"""The nonlinear flexible satellite against physics (seed papers-S-V-flexible.md, checks 3-7).

Conservation laws, the power balance by finite differences, the rigid limit against
:class:`models.RigidSatellite`, the linear model against finite-difference Jacobians of the
nonlinear one, and bad input. Measured (this file's set-ups, DOP853): energy drift over 200 s
without damping 2.3e-13 relative at rtol = 1e-11 (asserted 1e-8), inertial momentum drift over
100 s with damping and PZT forces 3e-15 relative (asserted 1e-9), rigid limit 3e-13 rad and
rad/s over 30 s at rtol = 1e-12 (asserted 1e-9).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from models import FlexibleSatellite, RigidSatellite
from models.attitude.euler import kinematics_matrix
from models.attitude.quaternion import (
    euler321_to_quat,
    quat_error,
    quat_from_axis_angle,
    quat_kinematics_matrix,
    quat_multiply,
    quat_to_dcm,
    quat_to_euler321,
    rotation_angle,
)
from toolkit_common.errors import InvalidArgumentError


@pytest.fixture(scope="module")
def sat() -> FlexibleSatellite:
    return FlexibleSatellite.di_gennaro()


def _moving_state(sat: FlexibleSatellite) -> np.ndarray:
    q = quat_from_axis_angle([1.0, -2.0, 0.5], 0.7)
    return sat.state(q, rates=[0.02, -0.03, 0.05], modal=[0.05, -0.02, 0.01, 0.004],
                     modal_rates=[-0.01, 0.03, 0.02, -0.01])


def _integrate(model: FlexibleSatellite, x0: np.ndarray, t_end: float, u=None, rtol: float = 1e-11):
    sol = solve_ivp(lambda t, y: model.dynamics(y, u), (0.0, t_end), x0, method="DOP853",
                    rtol=rtol, atol=1e-13, dense_output=True)
    assert sol.success
    return sol


def test_energy_is_conserved_without_damping_and_decays_with_it(sat: FlexibleSatellite) -> None:
    undamped = FlexibleSatellite(sat.inertia, sat.frequencies, np.zeros(4), sat.coupling)
    x0 = _moving_state(sat)
    sol = _integrate(undamped, x0, 200.0)
    energy = np.array([undamped.energy(y) for y in sol.sol(np.linspace(0.0, 200.0, 401)).T])
    assert np.max(np.abs(energy / energy[0] - 1.0)) < 1e-8
    damped = _integrate(sat, x0, 200.0)
    e_damped = np.array([sat.energy(y) for y in damped.sol(np.linspace(0.0, 200.0, 401)).T])
    assert np.all(np.diff(e_damped) <= 1e-12 * e_damped[0])
    # what is lost is the work of the modal damping, int eta'' C eta' dt (Simpson on a fine grid)
    from scipy.integrate import simpson

    t = np.linspace(0.0, 200.0, 20001)
    c = np.diag(sat.damping_matrix)
    eta_dot = damped.sol(t)[11:]
    dissipated = simpson(np.sum(c[:, None] * eta_dot**2, axis=0), x=t)
    assert dissipated > 1e-4 * e_damped[0]
    assert e_damped[0] - e_damped[-1] == pytest.approx(dissipated, rel=1e-6)


def test_power_balance_by_finite_differences(sat: FlexibleSatellite) -> None:
    rng = np.random.default_rng(7)
    forced = FlexibleSatellite.di_gennaro(panel_disturbance=True)
    for _ in range(5):
        x = _moving_state(sat) + np.concatenate((np.zeros(4), 0.01 * rng.standard_normal(11)))
        x = forced.normalize_state(x)
        u = rng.standard_normal(7)          # torques and PZT commands
        d = rng.standard_normal(7)          # hub torque and panel forces
        f = forced.dynamics(x, u, d)
        h = 1e-4
        fd = (forced.energy(x + h * f) - forced.energy(x - h * f)) / (2 * h)
        exact = forced.energy_rate(x, u, d)
        assert fd == pytest.approx(exact, rel=1e-7, abs=1e-12)
        torque, v, d_f = u[:3] + d[:3], u[3:], d[3:]
        c = np.diag(sat.damping_matrix)
        by_hand = x[4:7] @ torque + x[11:] @ (v + d_f) - x[11:] @ (c * x[11:])
        assert exact == pytest.approx(by_hand, rel=1e-12)


def test_inertial_momentum_is_conserved_with_damping_and_pzt_forces(sat: FlexibleSatellite) -> None:
    x0 = _moving_state(sat)
    u = np.array([0.0, 0.0, 0.0, 0.3, -0.2, 0.1, 0.05])  # PZT forces only: internal
    sol = _integrate(sat, x0, 100.0, u=u)
    h0 = sat.angular_momentum_inertial(x0)
    for y in sol.sol(np.linspace(0.0, 100.0, 201)).T:
        drift = np.linalg.norm(sat.angular_momentum_inertial(y) - h0)
        assert drift < 1e-9 * np.linalg.norm(h0)
    # a hub torque changes it at the rate R(q) u
    x = x0
    rate = quat_to_dcm(x[:4]) @ np.array([0.1, 0.0, 0.0])
    f = sat.dynamics(x, [0.1, 0.0, 0.0])
    hh = 1e-5
    fd = (sat.angular_momentum_inertial(x + hh * f) - sat.angular_momentum_inertial(x - hh * f)) / (2 * hh)
    np.testing.assert_allclose(fd, rate, atol=1e-9)


@pytest.mark.parametrize("rigid_like", ["zero_coupling", "no_modes"])
def test_rigid_limit_equals_rigid_satellite(sat: FlexibleSatellite, rigid_like: str) -> None:
    model = (FlexibleSatellite(sat.inertia, sat.frequencies, sat.damping, np.zeros((4, 3)))
             if rigid_like == "zero_coupling" else sat.with_modes(0))
    np.testing.assert_array_equal(model.hub_inertia, sat.inertia)
    rigid = RigidSatellite(sat.inertia)
    euler0 = np.array([0.2, -0.3, 0.4])
    w0 = np.array([0.01, 0.02, -0.015])

    def torque(t: float) -> np.ndarray:
        return np.array([0.5 * np.sin(0.3 * t), -0.2, 0.1 * np.cos(0.7 * t)])

    x_f = np.concatenate((euler321_to_quat(euler0), w0, np.zeros(2 * model.n_modes)))
    if model.n_modes:
        x_f[7:] = 0.01  # the modes move but do not couple
    sol_f = solve_ivp(lambda t, y: model.dynamics(y, torque(t)), (0, 30), x_f, method="DOP853",
                      rtol=1e-12, atol=1e-14, dense_output=True)
    sol_r = solve_ivp(lambda t, y: rigid.dynamics(y, torque(t)), (0, 30), np.concatenate((euler0, w0)),
                      method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True)
    for t in np.linspace(0.0, 30.0, 31):
        y_f, y_r = sol_f.sol(t), sol_r.sol(t)
        np.testing.assert_allclose(quat_to_euler321(y_f[:4] / np.linalg.norm(y_f[:4])), y_r[:3], atol=1e-9)
        np.testing.assert_allclose(y_f[4:7], y_r[3:], atol=1e-9)


def _jacobian(fun, x: np.ndarray, n_out: int, h: float = 1e-6) -> np.ndarray:
    jac = np.zeros((n_out, x.size))
    for j in range(x.size):
        e = np.zeros(x.size)
        e[j] = h
        jac[:, j] = (fun(x + e) - fun(x - e)) / (2 * h)
    return jac


def test_linearisation_equals_finite_differences(sat: FlexibleSatellite) -> None:
    n = sat.n_linear_states

    def quaternion_form(z: np.ndarray, u: np.ndarray) -> np.ndarray:
        qv = z[:3]
        x = np.concatenate(([np.sqrt(1.0 - qv @ qv)], z))
        return np.delete(sat.dynamics(x, u), 0)   # q0 follows from q_v

    def euler_form(z: np.ndarray, u: np.ndarray) -> np.ndarray:
        x = np.concatenate((euler321_to_quat(z[:3]), z[3:]))
        f = sat.dynamics(x, u)
        return np.concatenate((kinematics_matrix(z[0], z[1]) @ z[3:6], f[4:]))

    u0 = np.zeros(7)
    for attitude, form, att in (("quaternion", quaternion_form, [0.1, -0.2, 0.15]),
                                ("euler", euler_form, [0.3, -0.4, 0.2]),
                                ("quaternion", quaternion_form, [0.0, 0.0, 0.0])):
        z0 = np.concatenate((att, np.zeros(n - 3)))
        a, b = sat.linearize(z0, attitude=attitude, pzt=True)
        a_fd = _jacobian(lambda z, form=form: form(z, u0), z0, n)
        b_fd = _jacobian(lambda u, form=form, z0=z0: form(z0, u), u0, n)
        np.testing.assert_allclose(a, a_fd, atol=1e-6)
        np.testing.assert_allclose(b, b_fd, atol=1e-6)
    # the default is unchanged: Euler angles, torques only, Kin = I at zero attitude
    a, b = sat.linearize()
    np.testing.assert_array_equal(a[:3, 3:6], np.eye(3))
    np.testing.assert_array_equal(sat.linearize(attitude="quaternion")[0][:3, 3:6], 0.5 * np.eye(3))
    assert b.shape == (14, 3)


def test_linear_state_maps_the_error_quaternion(sat: FlexibleSatellite) -> None:
    q_ref = quat_from_axis_angle([0.0, 0.0, 1.0], 0.4)
    q = quat_multiply(q_ref, quat_from_axis_angle([1.0, 0.0, 0.0], 0.1))
    x = sat.state(-q, rates=[0.1, 0.2, 0.3])  # -q is the same attitude
    z = sat.linear_state(x, q_ref=q_ref)
    np.testing.assert_allclose(z[:3], [np.sin(0.05), 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(sat.linear_state(x, q_ref=q_ref, attitude="euler")[:3], [0.1, 0.0, 0.0],
                               atol=1e-15)
    np.testing.assert_array_equal(z[3:6], [0.1, 0.2, 0.3])


def test_quaternion_helpers_agree_with_the_euler_kinematics() -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        att = rng.uniform([-3, -1.5, -3], [3, 1.5, 3])
        q = euler321_to_quat(att)
        np.testing.assert_allclose(quat_to_euler321(q), att, atol=1e-12)
        w = rng.standard_normal(3)
        # q' = E(q) w maps to the Euler rates K(phi, theta) w
        h = 1e-6
        att_dot = (quat_to_euler321(q + h * quat_kinematics_matrix(q) @ w)
                   - quat_to_euler321(q - h * quat_kinematics_matrix(q) @ w)) / (2 * h)
        np.testing.assert_allclose(att_dot, kinematics_matrix(att[0], att[1]) @ w, rtol=1e-6, atol=1e-7)
    # at gimbal lock the conversion returns a valid representation, not NaN
    q = euler321_to_quat([0.3, np.pi / 2, 0.5])
    att = quat_to_euler321(q)
    assert np.all(np.isfinite(att))
    np.testing.assert_allclose(quat_to_dcm(euler321_to_quat(att)), quat_to_dcm(q), atol=1e-12)
    assert rotation_angle(quat_from_axis_angle([1, 1, 1], np.radians(160.0))) == pytest.approx(
        np.radians(160.0), rel=1e-14)
    assert quat_error(-quat_from_axis_angle([1, 0, 0], 0.3))[0] > 0.0


def test_bad_input_names_the_argument(sat: FlexibleSatellite) -> None:
    with pytest.raises(InvalidArgumentError, match="coupling"):   # 3 delta: J_mb indefinite
        FlexibleSatellite(sat.inertia, sat.frequencies, sat.damping, 3.0 * sat.coupling)
    with pytest.raises(InvalidArgumentError, match="pzt_matrix"):
        FlexibleSatellite(sat.inertia, sat.frequencies, sat.damping, sat.coupling, pzt_matrix=np.eye(3))
    with pytest.raises(InvalidArgumentError, match="frequencies"):
        FlexibleSatellite(sat.inertia, [-0.7, 1.0, 2.0, 3.0], sat.damping, sat.coupling)
    with pytest.raises(InvalidArgumentError, match="u"):
        sat.dynamics(sat.state(), np.zeros(5))
    with pytest.raises(InvalidArgumentError, match="d"):
        sat.dynamics(sat.state(), None, np.zeros(4))
    with pytest.raises(InvalidArgumentError, match="x"):
        sat.dynamics(np.zeros(14))
    with pytest.raises(InvalidArgumentError, match="attitude"):
        sat.state([1.0, 0.1, 0.0, 0.0])
    with pytest.raises(InvalidArgumentError, match="attitude"):
        sat.linearize(attitude="mrp")
    with pytest.raises(InvalidArgumentError, match="x_op"):
        sat.linearize(np.concatenate(([0.9, 0.9, 0.0], np.zeros(11))), attitude="quaternion")
