"""The MRP satellite of paper M: MRP identities, shadow sets, errors, orbit, disk, scenarios.

Outside references: SciPy's ``Rotation`` (quaternions, 3-2-1 Euler angles and MRPs), the
quaternion direction cosine matrix of Schaub & Junkins, a quaternion integration of the same
motion, finite differences, and conservation of the inertial angular momentum. Expected
numbers are those of ``seeds/paper-M-mrp-backstepping.md`` (sections 2, 6, 7 and 9).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from models import MRPSatellite, SpinningDisk, paper_m_scenario
from models.attitude.euler import rotation_matrix
from models.attitude.mrp import (
    dcm_from_euler321,
    euler321_from_dcm,
    mrp_angle,
    mrp_error,
    mrp_error_angle,
    mrp_from_dcm,
    mrp_from_euler321,
    mrp_from_quaternion,
    mrp_kinematics_inverse,
    mrp_kinematics_matrix,
    mrp_shadow,
    mrp_switch,
    mrp_to_dcm,
    mrp_to_quaternion,
)
from models.mrp.tracking import RMPCStateMap, rmpc_state, tracking_error
from rmpc import simulate
from rmpc.sim.plants import SampledPlant
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError, SingularityError

SIGMA0 = [0.195676, -0.096964, 0.130312]
SIGMA_REF = [0.045466, 0.017929, -0.045466]


def quaternion_dcm(q: np.ndarray) -> np.ndarray:
    """Schaub & Junkins: C = (q4^2 - qv'qv) I + 2 qv qv' - 2 q4 [qv x] (scalar last)."""
    qv, q4 = q[:3], q[3]
    sk = np.array([[0.0, -qv[2], qv[1]], [qv[2], 0.0, -qv[0]], [-qv[1], qv[0], 0.0]])
    return (q4**2 - qv @ qv) * np.eye(3) + 2.0 * np.outer(qv, qv) - 2.0 * q4 * sk


@pytest.fixture(scope="module")
def rotations() -> Rotation:
    return Rotation.random(200, random_state=np.random.default_rng(14))


def test_dcm_is_the_quaternion_dcm_and_scipys(rotations: Rotation) -> None:
    for rot in rotations:
        q = rot.as_quat()  # scalar last
        sigma = mrp_from_quaternion(q)
        c = mrp_to_dcm(sigma)
        np.testing.assert_allclose(c @ c.T, np.eye(3), atol=1e-12)
        assert abs(np.linalg.det(c) - 1.0) < 1e-12
        np.testing.assert_allclose(c, quaternion_dcm(q), atol=1e-12)
        # SciPy's matrix maps body to frame components: C is its transpose
        np.testing.assert_allclose(c, rot.as_matrix().T, atol=1e-12)
        np.testing.assert_allclose(sigma, rot.as_mrp(), atol=1e-12)
        np.testing.assert_allclose(mrp_from_dcm(c), sigma, atol=1e-12)
        back = mrp_to_quaternion(sigma)
        np.testing.assert_allclose(np.abs(back @ q), 1.0, atol=1e-12)


def test_initial_attitude_and_euler_angles() -> None:
    angles = np.radians([40.0, -30.0, 20.0])  # roll, pitch, yaw
    reference = Rotation.from_euler("ZYX", angles[::-1]).as_matrix().T
    sigma0 = mrp_from_euler321(angles)
    np.testing.assert_allclose(mrp_to_dcm(sigma0), reference, atol=1e-12)
    np.testing.assert_allclose(dcm_from_euler321(angles), reference, atol=1e-12)
    np.testing.assert_allclose(rotation_matrix(angles).T, reference, atol=1e-12)  # models.attitude.euler
    np.testing.assert_allclose(sigma0, SIGMA0, atol=1e-6)
    np.testing.assert_allclose(euler321_from_dcm(reference), angles, atol=1e-12)
    with pytest.raises(SingularityError, match="pitch"):
        euler321_from_dcm(dcm_from_euler321([0.3, np.pi / 2, -0.2]))


def test_kinematics_matrix_identities(rotations: Rotation) -> None:
    for sigma in rotations.as_mrp()[:50]:
        for s in (sigma, mrp_shadow(sigma)):
            n_mat = mrp_kinematics_matrix(s)
            k = (1.0 + s @ s) / 4.0
            np.testing.assert_allclose(n_mat.T @ n_mat, k**2 * np.eye(3), atol=1e-12 * max(1.0, k**2))
            np.testing.assert_allclose(np.linalg.solve(n_mat, s), 4.0 * s / (1.0 + s @ s), atol=1e-12)
            np.testing.assert_allclose(mrp_kinematics_inverse(s) @ n_mat, np.eye(3), atol=1e-12)


def test_shadow_set_is_the_same_attitude(rotations: Rotation) -> None:
    for sigma in rotations.as_mrp()[:50]:
        shadow = mrp_shadow(sigma)
        np.testing.assert_allclose(mrp_to_dcm(shadow), mrp_to_dcm(sigma), atol=1e-12)
        assert np.linalg.norm(shadow) >= 1.0 - 1e-12
        np.testing.assert_array_equal(mrp_switch(shadow), mrp_shadow(shadow))
        np.testing.assert_array_equal(mrp_switch(sigma), sigma)
    assert mrp_angle([0.0, 0.0, 1.0]) == pytest.approx(np.pi)
    with pytest.raises(SingularityError, match="sigma"):
        mrp_shadow(np.zeros(3))
    with pytest.raises(InvalidArgumentError, match="threshold"):
        mrp_switch([0.1, 0.2, 0.3], threshold=0.5)


def test_mrp_error_composition(rotations: Rotation) -> None:
    mrps = rotations.as_mrp()
    for s, sr in zip(mrps[:60], mrps[60:120], strict=True):
        for s_any, sr_any in ((s, sr), (mrp_shadow(s), sr), (s, mrp_shadow(sr))):
            se = mrp_error(s_any, sr_any)
            np.testing.assert_allclose(mrp_to_dcm(se), mrp_to_dcm(s) @ mrp_to_dcm(sr).T, atol=1e-12)
            assert se @ se <= 1.0 + 1e-12
        np.testing.assert_allclose(mrp_error(s, s), 0.0, atol=1e-15)
        # the composition formula is 0/0 there: the identity written as a 360 deg rotation
        np.testing.assert_allclose(mrp_error(mrp_shadow(sr), sr), 0.0, atol=1e-12)
    angle = mrp_error_angle(SIGMA0, SIGMA_REF)
    assert np.degrees(angle) == pytest.approx(57.8316, abs=1e-4)


def test_error_rate_is_n_times_relative_rate() -> None:
    sat = MRPSatellite.paper_m()
    x = np.concatenate((SIGMA0, [0.1, -0.2, 0.3]))
    err = tracking_error(x, SIGMA_REF, sat.mean_motion)
    se_dot = err.kinematics @ err.relative_rate
    sigma_dot = sat.dynamics(x)[:3]
    h = 1e-5
    ahead, behind = (mrp_error(x[:3] + sign * h * sigma_dot, SIGMA_REF) for sign in (1.0, -1.0))
    diff = (ahead - behind) / (2 * h)
    np.testing.assert_allclose(diff, se_dot, rtol=1e-6)
    np.testing.assert_allclose(err.relative_rate, sat.relative_rate(x), atol=1e-15)


def test_orbit_rate_and_gravity_gradient() -> None:
    sat = MRPSatellite.paper_m()
    assert sat.mean_motion == pytest.approx(1.071540e-3, abs=1e-9)
    assert sat.orbit_period / 60.0 == pytest.approx(97.73, abs=0.01)
    j_full = np.array([[3.0, 0.1, -0.2], [0.1, 2.5, 0.05], [-0.2, 0.05, 2.0]])
    sat_full = MRPSatellite(j_full, gravity_gradient=True)
    rng = np.random.default_rng(7)
    for sigma in Rotation.random(20, random_state=rng).as_mrp():
        c3 = mrp_to_dcm(sigma)[:, 2]
        r = -sat_full.orbit_radius * c3  # position from the Earth's centre, body components
        expected = 3.0 * sat_full.mu / np.linalg.norm(r) ** 5 * np.cross(r, j_full @ r)
        tg = sat_full.gravity_gradient_torque(sigma)
        np.testing.assert_allclose(tg, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
        x = np.concatenate((sigma, rng.normal(size=3) * 0.01))
        without = MRPSatellite(j_full).dynamics(x)
        np.testing.assert_allclose(sat_full.dynamics(x)[3:] - without[3:], np.linalg.solve(j_full, tg),
                                   atol=1e-18)
    np.testing.assert_array_equal(sat.gravity_gradient_torque(np.zeros(3)), 0.0)
    assert not sat.gravity_gradient  # off by default, as in paper M


def test_at_rest_in_the_orbital_frame_stays_there() -> None:
    sat = MRPSatellite.paper_m()
    x = sat.state_at_rest(SIGMA0)
    np.testing.assert_allclose(sat.relative_rate(x), 0.0, atol=1e-18)
    np.testing.assert_allclose(sat.dynamics(x)[:3], 0.0, atol=1e-18)


class Zero:
    last = None

    def reset(self) -> None:
        pass

    def step(self, x: np.ndarray) -> np.ndarray:
        return np.zeros(3)


def test_tumbling_run_switches_twice_and_matches_a_quaternion_run() -> None:
    sat = MRPSatellite([3.0, 3.0, 2.0])
    n = sat.mean_motion
    x0 = np.array([0.0, 0.0, 0.0, 0.1, 0.05, 0.5])
    run = simulate(Zero(), SampledPlant(sat, 1e-3, integrator="RK4"), x0, duration=20.0)
    jumps = np.linalg.norm(np.diff(run.x[:, :3], axis=0), axis=1)
    assert int(np.sum(jumps > 0.5)) == 2
    assert np.all(np.sum(run.x[:, :3] ** 2, axis=1) <= 1.0)

    def quaternion_rhs(_t: float, y: np.ndarray) -> np.ndarray:
        q, w = y[:4], y[4:]
        w_bo = w + n * quaternion_dcm(q)[:, 1]
        qv, q4 = q[:3], q[3]
        q_dot = 0.5 * np.concatenate((q4 * w_bo + np.cross(qv, w_bo), [-qv @ w_bo]))
        jw = sat.inertia @ w
        return np.concatenate((q_dot, np.linalg.solve(sat.inertia, -np.cross(w, jw))))

    ref = solve_ivp(quaternion_rhs, (0.0, 20.0), np.concatenate(([0, 0, 0, 1.0], x0[3:])), method="DOP853",
                    t_eval=run.t, rtol=1e-13, atol=1e-14)
    err = max(
        np.abs(mrp_to_dcm(run.x[k, :3]) - quaternion_dcm(ref.y[:4, k] / np.linalg.norm(ref.y[:4, k]))).max()
        for k in range(0, run.t.size, 10)
    )
    assert err <= 1e-10
    # torque-free: kinetic energy and |J w| are conserved
    energy = 0.5 * np.einsum("ki,ij,kj->k", run.x[:, 3:], sat.inertia, run.x[:, 3:])
    momentum = np.linalg.norm(run.x[:, 3:] @ sat.inertia, axis=1)
    assert np.ptp(energy) / energy[0] < 1e-11
    assert np.ptp(momentum) / momentum[0] < 1e-11


def test_disk_torque_is_minus_the_rate_of_its_momentum() -> None:
    disk = SpinningDisk.paper_m()
    assert disk.spin_inertia == pytest.approx(6.25e-4)
    np.testing.assert_allclose(disk.axis, [0.6124, 0.3536, 0.7071], atol=5e-5)
    np.testing.assert_allclose(disk.inertia @ disk.axis, disk.spin_inertia * disk.axis, atol=1e-18)
    w = np.array([0.02, -0.05, 0.03])
    h = 1e-4
    for t in (0.0, 1.3, 7.7):
        h_dot = (disk.momentum(t + h) - disk.momentum(t - h)) / (2 * h)  # derivative in the body frame
        expected = -(h_dot + np.cross(w, disk.momentum(t)))  # minus the inertial rate of H_disk
        tol = 1e-8 * np.linalg.norm(expected)  # central difference: round-off ~1e-12 N m
        np.testing.assert_allclose(disk.torque_at_rate(t, w), expected, rtol=0, atol=tol)
        np.testing.assert_allclose(disk(t, np.concatenate((np.zeros(3), w))), expected, rtol=0, atol=tol)
    # at rest only the speed change acts: amplitude Is dW nu (seed: about 0.02 N m)
    amp = max(np.linalg.norm(disk.torque_at_rate(t, np.zeros(3))) for t in np.linspace(0, 21, 500))
    assert amp == pytest.approx(6.25e-4 * 1000 * 2 * np.pi / 60 * 0.3, rel=1e-3)
    assert 0.019 < amp < 0.021


def test_disk_and_bus_conserve_the_total_inertial_momentum() -> None:
    """No control, no gravity gradient: C_IB (J w + Jb wb a) is constant (paper M's dH/dt = 0).

    The orbital frame turns about its own o2 axis at -n, so C_OI(t) = R2(-n t).
    """
    sat = MRPSatellite.paper_m()
    disk = SpinningDisk.paper_m()
    x0 = sat.state_at_rest(SIGMA0, relative_rate=[0.01, -0.02, 0.015])
    run = simulate(Zero(), sat, x0, duration=10.0, dt=0.1, disturbance=disk)
    totals = []
    for t, x in zip(run.t, run.x, strict=True):
        a = -sat.mean_motion * t
        c_oi = np.array([[np.cos(a), 0.0, -np.sin(a)], [0.0, 1.0, 0.0], [np.sin(a), 0.0, np.cos(a)]])
        c_bi = mrp_to_dcm(x[:3]) @ c_oi
        totals.append(c_bi.T @ (sat.inertia @ x[3:] + disk.momentum(t)))
    totals = np.array(totals)
    assert np.abs(totals - totals[0]).max() < 1e-10 * np.linalg.norm(totals[0])
    # and the disk did act: the body rate changed
    assert np.linalg.norm(run.x[-1, 3:] - run.x[0, 3:]) > 1e-3


def test_rmpc_state_map() -> None:
    sat = MRPSatellite.paper_m()
    m1 = paper_m_scenario("M1")
    x0 = m1.initial_state()
    big_x = rmpc_state(x0, m1.sigma_ref, sat.mean_motion)
    np.testing.assert_allclose(np.degrees(big_x[:3]), [27.27, -28.67, 36.69], atol=5e-3)
    np.testing.assert_allclose(big_x[3:], 0.0, atol=1e-18)  # at rest in O
    se = mrp_error(x0[:3], m1.sigma_ref)
    np.testing.assert_allclose(dcm_from_euler321(big_x[:3]), mrp_to_dcm(se), atol=1e-12)
    c = dcm_from_euler321(big_x[:3])
    principal_angle = np.arccos((np.trace(c) - 1.0) / 2.0)
    assert principal_angle == pytest.approx(mrp_error_angle(x0[:3], m1.sigma_ref), abs=1e-12)
    # zero at the target, at rest in O; the rate part is w_BO
    np.testing.assert_allclose(rmpc_state(sat.state_at_rest(m1.sigma_ref), m1.sigma_ref, sat.mean_motion),
                               0.0, atol=1e-15)
    x = sat.state_at_rest(SIGMA0, relative_rate=[0.01, 0.02, -0.03])
    mapping = RMPCStateMap(m1.sigma_ref, sat.mean_motion)
    np.testing.assert_allclose(mapping(x)[3:], [0.01, 0.02, -0.03], atol=1e-15)
    np.testing.assert_array_equal(mapping(x), rmpc_state(x, m1.sigma_ref, sat.mean_motion))
    gimbal = np.concatenate((mrp_from_euler321([0.0, np.pi / 2, 0.0]), np.zeros(3)))
    with pytest.raises(SingularityError, match="pitch"):
        RMPCStateMap(np.zeros(3), sat.mean_motion)(gimbal)


def test_scenarios_are_the_seeds() -> None:
    m1, m2, m3 = (paper_m_scenario(name) for name in ("M1", "M2", "M3"))
    for sc in (m1, m2, m3):
        np.testing.assert_allclose(sc.sigma0, SIGMA0, atol=1e-6)
        np.testing.assert_allclose(sc.sigma_ref, SIGMA_REF, atol=1e-6)
        assert sc.initial_error_deg == pytest.approx(57.83, abs=5e-3)
        assert (sc.duration, sc.dt, sc.steady_window) == (100.0, 0.01, (50.0, 100.0))
        sat = sc.true_satellite()
        np.testing.assert_allclose(sat.relative_rate(sc.initial_state()), 0.0, atol=1e-18)
        np.testing.assert_array_equal(sc.model().inertia, np.diag([3.0, 3.0, 2.0]))
    assert (m1.disk, m2.disk, m3.disk) == (False, True, True)
    assert m1.disturbance() is None and isinstance(m2.disturbance(), SpinningDisk)
    assert (m1.u_max, m2.u_max, m3.u_max) == (None, None, 1.0)
    np.testing.assert_allclose(m3.true_satellite().inertia, 1.3 * np.diag([3.0, 3.0, 2.0]))
    light = paper_m_scenario("M3", inertia_scale=0.7)
    np.testing.assert_allclose(light.true_satellite().inertia, 0.7 * np.diag([3.0, 3.0, 2.0]))
    assert len(m2.settings()["notes"]) == 6
    with pytest.raises(InvalidArgumentError, match="name"):
        paper_m_scenario("M4")
    with pytest.raises(InvalidArgumentError, match="overrides"):
        paper_m_scenario("M1", altitude=1.0)
    with pytest.raises(InvalidArgumentError, match="steady_window"):
        paper_m_scenario("M1", duration=20.0, steady_window=(10.0, 30.0))


def test_bad_input_names_the_argument() -> None:
    with pytest.raises(InvalidArgumentError, match="inertia"):
        MRPSatellite([[3.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 2.0]])
    with pytest.raises(InvalidArgumentError, match="inertia"):
        MRPSatellite([3.0, 0.0, 2.0])
    with pytest.raises(InvalidArgumentError, match=r"altitude.*below the surface"):
        MRPSatellite([3.0, 3.0, 2.0], altitude=-1000.0)
    with pytest.raises(InvalidArgumentError, match="shadow_threshold"):
        MRPSatellite([3.0, 3.0, 2.0], shadow_threshold=0.9)
    with pytest.raises(InvalidArgumentError, match="gravity_gradient"):
        MRPSatellite([3.0, 3.0, 2.0], gravity_gradient="yes")
    with pytest.raises(InvalidArgumentError, match="mass"):
        SpinningDisk(mass=0.0)
    with pytest.raises(InvalidArgumentError, match="speed_frequency"):
        SpinningDisk(speed_frequency=-0.3)
    with pytest.raises(ArgumentTypeError, match="x"):
        MRPSatellite.paper_m().dynamics("state")
    with pytest.raises(InvalidArgumentError, match="q"):
        mrp_from_quaternion([1.0, 1.0, 0.0, 0.0])
    with pytest.raises(InvalidArgumentError, match="dcm"):
        mrp_from_dcm(2.0 * np.eye(3))
