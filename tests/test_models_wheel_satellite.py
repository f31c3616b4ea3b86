"""Paper W's wheel satellite: the checks of seed section 6.1-6.4 and physical invariants.

Expected numbers are the seed's derived values (``seeds/paper-W-wheel-faults.md``, sections
2, 4.6 and 6), computed independently of this toolkit.
"""

from __future__ import annotations

import itertools

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from models import WheelArray, WheelSatellite
from models.attitude.euler import kinematics_matrix
from models.attitude.euler_inverse import inverse_kinematics_matrix
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

ONES = np.ones((3, 3))


@pytest.fixture(scope="module")
def sat() -> WheelSatellite:
    return WheelSatellite.paper_w()


def test_distribution_matrix_geometry() -> None:  # seed 6.1
    d = WheelArray.paper_w().D
    for i in range(3):
        np.testing.assert_allclose(np.degrees(np.arccos(d[:, 3] @ np.eye(3)[i])), 54.7356, atol=1e-4)
    np.testing.assert_allclose(np.linalg.norm(d, axis=0), 1.0, atol=1e-15)
    np.testing.assert_allclose(d @ d.T, np.eye(3) + ONES / 3.0, atol=1e-12)
    # per-axis authority and momentum capacity (seed 2.3 and 6.6): 0.123 (1 + 1/sqrt 3), 0.625 (1 + 1/sqrt 3)
    wheels = WheelArray.paper_w()
    np.testing.assert_allclose(wheels.axis_authority(), 0.123 * (1 + 1 / np.sqrt(3)), rtol=1e-12)
    np.testing.assert_allclose(wheels.axis_authority(), 0.194, atol=5e-4)
    np.testing.assert_allclose(wheels.momentum_capacity(), 0.986, atol=5e-4)


def test_inertia_input_matrix_and_nominal_gain(sat: WheelSatellite) -> None:  # seed 6.2
    j = sat.inertia
    np.testing.assert_array_equal(j, j.T)
    np.testing.assert_allclose(np.linalg.eigvalsh(j), [1.6491, 1.8993, 3.4326], atol=1e-4)
    g2 = [
        [0.5538, 0.0379, -0.0046, 0.3389],
        [0.0379, 0.5790, -0.0032, 0.3543],
        [-0.0046, -0.0032, 0.2914, 0.1638],
    ]
    np.testing.assert_allclose(sat.input_matrix, g2, atol=1e-4)
    g_nom = sat.nominal_gain()
    np.testing.assert_allclose(
        g_nom, [[2.8106, -0.8892, -0.8561], [-0.8892, 2.5799, -0.8620], [-0.8561, -0.8620, 9.7654]], atol=1e-4
    )
    np.testing.assert_allclose(g_nom, j @ (np.eye(3) - ONES / 6.0) @ j, atol=1e-10)
    np.testing.assert_allclose(np.linalg.eigvalsh(g_nom), [1.6181, 3.5911, 9.9467], atol=1e-4)
    np.testing.assert_allclose(sat.nominal_gain([1, 1, 1, 0]), j @ j, atol=1e-10)  # wheel 4 out


def test_rank_of_every_single_and_double_outage(sat: WheelSatellite) -> None:  # seed 6.3
    expected_smallest = [0.2154, 0.2205, 0.1296, 0.2913]
    for j in range(4):
        sigma = np.ones(4)
        sigma[j] = 0.0
        assert sat.wheels.rank(sigma) == 3
        smallest = np.linalg.svd(sat.input_matrix * sigma, compute_uv=False)[-1]
        np.testing.assert_allclose(smallest, expected_smallest[j], atol=1e-4)
    for pair in itertools.combinations(range(4), 2):
        sigma = np.ones(4)
        sigma[list(pair)] = 0.0
        assert sat.wheels.rank(sigma) == 2, pair
        with pytest.raises(InvalidArgumentError, match="effectiveness"):
            sat.nominal_gain(sigma)


def test_kinematics_and_gravity(sat: WheelSatellite) -> None:  # seed 6.4
    rng = np.random.default_rng(5)
    for phi, theta in rng.uniform(-1.2, 1.2, size=(20, 2)):
        r_inv = inverse_kinematics_matrix(phi, theta)
        np.testing.assert_allclose(kinematics_matrix(phi, theta) @ r_inv, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(np.linalg.det(r_inv), np.cos(theta), atol=1e-12)
    level_40 = np.radians([40.0, 0.0, 0.0])
    np.testing.assert_allclose(sat.gravity_torque(level_40), [-0.2095, 0.0, 0.0], atol=1e-4)
    # the inverted reading topples with 0.210 N m, more than the 0.194 N m roll authority (seed 2.4)
    inverted = sat.replace(gravity="inverted")
    np.testing.assert_allclose(inverted.gravity_torque(level_40), [0.2095, 0.0, 0.0], atol=1e-4)
    assert inverted.gravity_torque(level_40)[0] > sat.wheels.axis_authority()[0]
    np.testing.assert_array_equal(sat.replace(gravity="off").gravity_torque(level_40), 0.0)
    # the general form m g (r x k) with k the body-frame image of the inertial "down"
    from models.attitude.euler import rotation_matrix

    att = np.array([0.3, -0.2, 1.1])
    k = rotation_matrix(att).T @ np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(sat.gravity_torque(att), np.cross([0.0, 0.0, 0.326], k), atol=1e-15)


def _integrate(model: WheelSatellite, x0: np.ndarray, u_fn, t_end: float) -> np.ndarray:
    sol = solve_ivp(
        lambda t, y: model.dynamics(y, u_fn(t)),
        (0.0, t_end),
        x0,
        method="DOP853",
        rtol=1e-11,
        atol=1e-12,
        dense_output=True,
    )
    assert sol.success
    return sol.sol(np.linspace(0.0, t_end, 200)).T


def test_total_angular_momentum_is_conserved_with_the_gyroscopic_term(sat: WheelSatellite) -> None:
    # wheel torques and bearing friction are internal: R (J w + D h) is constant without gravity,
    # and its vertical component is constant with gravity (the gravity torque is horizontal)
    model = sat.replace(gravity="off", wheel_gyroscopic=True, viscous_friction=1e-4, coulomb_friction=2e-3)
    x0 = model.state([0.2, -0.1, 0.4], rates=[0.05, -0.02, 0.03], momenta=[0.1, -0.2, 0.05, 0.3])

    def u_fn(t: float) -> np.ndarray:
        return 0.05 * np.array([np.sin(t), np.cos(2 * t), -0.5, np.sin(0.3 * t)])

    xs = _integrate(model, x0, u_fn, 8.0)
    h0 = model.angular_momentum_inertial(x0)
    drift = max(float(np.max(np.abs(model.angular_momentum_inertial(x) - h0))) for x in xs)
    assert drift < 1e-8
    assert np.max(np.abs(xs[:, 3:6])) > 0.1  # the platform did move
    pendulous = model.replace(gravity="pendulous")
    xs = _integrate(pendulous, x0, u_fn, 8.0)
    hz = [pendulous.angular_momentum_inertial(x)[2] for x in xs]
    assert max(abs(v - hz[0]) for v in hz) < 1e-8
    # without the gyroscopic term (paper W's model, the default) the total is not conserved
    xs = _integrate(sat.replace(gravity="off"), x0, u_fn, 8.0)
    drift = max(float(np.max(np.abs(model.angular_momentum_inertial(x) - h0))) for x in xs)
    assert drift > 1e-4


def test_pendulum_energy_is_conserved_without_wheel_torque(sat: WheelSatellite) -> None:
    # E = w' J w / 2 - s (m g r) . k(eta); the gyroscopic term does no work
    for model in (sat, sat.replace(wheel_gyroscopic=True), sat.replace(gravity="inverted")):
        x0 = model.state([0.3, -0.2, 0.5], rates=[0.02, 0.01, -0.03], momenta=[0.1, 0.0, -0.1, 0.2])
        xs = _integrate(model, x0, lambda t: np.zeros(4), 10.0)
        sign = {"pendulous": 1.0, "inverted": -1.0}[model.gravity]

        def energy(x: np.ndarray, model: WheelSatellite = model, sign: float = sign) -> float:
            w = x[3:6]
            k = np.array([-np.sin(x[1]), np.sin(x[0]) * np.cos(x[1]), np.cos(x[0]) * np.cos(x[1])])
            return 0.5 * w @ model.inertia @ w - sign * model.imbalance @ k

        energies = np.array([energy(x) for x in xs])
        assert np.max(np.abs(energies - energies[0])) < 1e-10
        np.testing.assert_allclose(
            xs[:, 6:], np.tile(x0[6:], (len(xs), 1)), atol=1e-14
        )  # no torque, no friction: h constant


def test_wheel_momentum_and_friction(sat: WheelSatellite) -> None:
    x = sat.state([0.1, 0.2, 0.3], rates=[0.01, 0.02, 0.03], momenta=[0.2, -0.3, 0.0, 0.1])
    u = np.array([0.01, -0.02, 0.03, 0.04])
    np.testing.assert_array_equal(sat.dynamics(x, u)[6:], -u)
    rubbing = sat.replace(viscous_friction=1e-3, coulomb_friction=5e-3)
    omega = x[6:] / 0.0123
    expected = -1e-3 * omega - 5e-3 * np.sign(omega)
    np.testing.assert_allclose(rubbing.dynamics(x, u)[6:], -u + expected, rtol=1e-13)


def test_linearisation_matches_finite_differences(sat: WheelSatellite) -> None:
    for model in (sat, sat.replace(gravity="inverted"), sat.replace(imbalance=[0.05, -0.1, 0.3])):
        a, b = model.linearize()
        h = 1e-6
        a_fd = np.zeros((6, 6))
        for i in range(6):
            dx = np.zeros(10)
            dx[i] = h
            a_fd[:, i] = (model.dynamics(dx, np.zeros(4)) - model.dynamics(-dx, np.zeros(4)))[:6] / (2 * h)
        b_fd = np.zeros((6, 4))
        for j in range(4):
            du = np.zeros(4)
            du[j] = h
            b_fd[:, j] = (model.dynamics(np.zeros(10), du) - model.dynamics(np.zeros(10), -du))[:6] / (2 * h)
        np.testing.assert_allclose(a, a_fd, atol=1e-8)
        np.testing.assert_allclose(b, b_fd, atol=1e-8)
    a, _ = sat.linearize()
    np.testing.assert_allclose(
        a[3:, :3], -np.linalg.inv(sat.inertia) @ np.diag([0.326, 0.326, 0.0]), atol=1e-15
    )


def test_effectiveness_polytope(sat: WheelSatellite) -> None:
    poly = sat.polytope(dt=0.04, effectiveness="single_outage")
    assert (poly.n_vertices, poly.n_states, poly.n_inputs) == (5, 6, 4)
    a_c, _ = sat.linearize()
    for v, lam in enumerate(sat.effectiveness_vertices("single_outage")):
        _, b_c = sat.linearize(effectiveness=lam)
        sys_d = control.c2d(control.ss(a_c, b_c, np.eye(6), np.zeros((6, 4))), 0.04, method="zoh")
        np.testing.assert_allclose(poly.A[v], sys_d.A, atol=1e-12)
        np.testing.assert_allclose(poly.B[v], sys_d.B, atol=1e-12)
        assert np.linalg.matrix_rank(poly.B[v][3:]) == 3
    # B is linear in Lambda: the polytope holds every member of the single-outage set exactly
    lam = np.array([0.6, 0.7, 1.0, 0.7])  # sum(1 - lambda) = 1
    weights = np.array([0.0, 0.4, 0.3, 0.0, 0.3])
    np.testing.assert_allclose(
        poly.combination(weights)[1], sat.discretize(dt=0.04, effectiveness=lam)[1], atol=1e-15
    )
    np.testing.assert_allclose(poly.nominal[1], poly.B[0], atol=0.0)
    assert sat.polytope(dt=0.04, effectiveness="box").n_vertices == 16
    both = sat.polytope(dt=0.04, spread=0.2)
    assert both.n_vertices == 10
    # vertex order: inertia scale 1.2 then 0.8, effectiveness inside; a scale on J is a heavier platform
    for v, scale, lam in ((0, 1.2, [1, 1, 1, 1]), (6, 0.8, [0, 1, 1, 1])):
        a_s, b_s = sat.replace(inertia=scale * sat.inertia).discretize(dt=0.04, effectiveness=lam)
        np.testing.assert_allclose(both.A[v], a_s, atol=1e-15)
        np.testing.assert_allclose(both.B[v], b_s, atol=1e-15)


def test_vertex_check_names_the_failing_vertex(sat: WheelSatellite) -> None:  # seed 8(c)
    with pytest.raises(InvalidArgumentError, match=r"effectiveness.*vertex 3 .*rank\(D Lambda\) = 2"):
        sat.polytope(dt=0.04, effectiveness="box", lambda_min=0.0)
    with pytest.raises(InvalidArgumentError, match=r"vertex 1 .*rank\(D Lambda\) = 0"):
        sat.polytope(dt=0.04, effectiveness=[[1, 1, 1, 1], [0, 0, 0, 0]])
    with pytest.raises(InvalidArgumentError, match=r"effectiveness\[0\]"):
        sat.polytope(dt=0.04, effectiveness=[[1.2, 1, 1, 1]])
    with pytest.raises(InvalidArgumentError, match="lambda_min"):
        sat.polytope(dt=0.04, effectiveness="box", lambda_min=1.0)


def test_bad_arrays_and_options_name_the_argument(sat: WheelSatellite) -> None:
    flat = np.array([[1.0, 0.0, 0.6, 0.8], [0.0, 1.0, 0.8, -0.6], [0.0, 0.0, 0.0, 0.0]])
    with pytest.raises(InvalidArgumentError, match=r"D: expected columns that span three axes.*rank 2"):
        WheelArray(flat)
    with pytest.raises(InvalidArgumentError, match=r"D: expected unit columns.*wheel 2"):
        WheelArray([[1, 0, 0], [0, 2, 0], [0, 0, 1]])
    with pytest.raises(InvalidArgumentError, match="D"):
        WheelArray(np.eye(2))
    with pytest.raises(InvalidArgumentError, match="torque_max"):
        WheelArray(np.eye(3), torque_max=-0.1)
    with pytest.raises(InvalidArgumentError, match="momentum_max"):
        WheelArray(np.eye(3), momentum_max=[0.6, 0.6])
    with pytest.raises(InvalidArgumentError, match="effectiveness"):
        sat.wheels.rank([1.0, 1.5, 1.0, 1.0])
    with pytest.raises(InvalidArgumentError, match="gravity"):
        WheelSatellite.paper_w(gravity="upside-down")
    with pytest.raises(ArgumentTypeError, match="wheels"):
        WheelSatellite(sat.inertia, sat.wheels.D)
    with pytest.raises(InvalidArgumentError, match="viscous_friction"):
        sat.replace(viscous_friction=-1.0)
    with pytest.raises(InvalidArgumentError, match="changes"):
        sat.replace(mass=40.0)
    with pytest.raises(InvalidArgumentError, match="u"):
        sat.dynamics(np.zeros(10), np.zeros(3))
    assert WheelArray(np.eye(3), torque_max=np.inf).torque_max.tolist() == [np.inf] * 3
    assert "WheelSatellite(n_wheels=4, gravity='pendulous'" in repr(sat)
