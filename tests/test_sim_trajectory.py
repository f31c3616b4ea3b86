"""Trajectory knows its attitude: roll, pitch and yaw from the plant, whatever its states are.

The references are SciPy's rotations, independent of the toolkit's conversions: an MRP
``sigma`` of the body with respect to the orbit frame is ``Rotation.from_mrp(sigma)`` (whose
matrix is ``mrp_to_dcm(sigma)'``), a unit quaternion ``q = [q0, q_v]`` of the flexible satellite is
``Rotation.from_quat([q_v, q0])``; both are body-to-frame rotations ``Rz(yaw) Ry(pitch) Rx(roll)``,
so roll, pitch and yaw are ``as_euler("ZYX")`` reversed.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from models import FlexibleSatellite, MRPSatellite, RigidSatellite
from rmpc import LQR, simulate
from rmpc.sim.plants import LinearPlant, SampledPlant
from toolkit_common.errors import InvalidArgumentError


class _Zero:
    """No torque at all: the satellite tumbles freely."""

    last = None

    def __init__(self, m: int) -> None:
        self.m = m

    def step(self, x: np.ndarray) -> np.ndarray:
        return np.zeros(self.m)


def _wrapped(angles: np.ndarray) -> np.ndarray:
    """Angles (rad) wrapped into [-pi, pi), so roll and yaw near +-180 deg compare."""
    return (angles + np.pi) % (2.0 * np.pi) - np.pi


def test_attitude_of_a_tumbling_mrp_satellite_is_its_roll_pitch_yaw() -> None:
    sat = MRPSatellite.paper_m()
    x0 = np.array([0.0, 0.0, 0.0, 0.3, 0.1, 1.0])  # 1.05 rad/s, mostly about z
    run = simulate(_Zero(3), sat, x0, duration=10.0, dt=0.05)
    # the shadow set switched (sigma -> -sigma / |sigma|^2 at |sigma| = 1: a jump of about 2)
    assert np.abs(np.diff(run.x[:, :3], axis=0)).max() > 1.0
    expected = np.array([Rotation.from_mrp(s).as_euler("ZYX")[::-1] for s in run.x[:, :3]])
    assert np.abs(expected[:, 1]).max() < np.radians(60.0)  # far from gimbal lock
    assert run.attitude_euler.shape == (run.n_steps + 1, 3)
    np.testing.assert_allclose(_wrapped(run.attitude_euler - expected), 0.0, atol=1e-12)
    np.testing.assert_allclose(_wrapped(np.radians(run.attitude_deg) - expected), 0.0, atol=1e-12)
    # the MRPs themselves, read as angles, are far off after one second of the tumble
    k = round(1.0 / run.dt)
    assert np.max(np.abs(run.attitude_deg[k] - np.degrees(run.x[k, :3]))) > 20.0


def test_attitude_of_the_quaternion_plant_is_its_roll_pitch_yaw() -> None:
    sat = FlexibleSatellite.di_gennaro()
    x0 = sat.state(rates=[0.2, -0.3, 0.4])
    run = simulate(_Zero(sat.n_inputs), SampledPlant(sat, 0.05, integrator="RK4", substep=0.01), x0,
                   duration=6.0)
    q = run.x[:, :4]
    expected = np.array([Rotation.from_quat(np.r_[qk[1:], qk[0]]).as_euler("ZYX")[::-1] for qk in q])
    assert np.abs(expected).max() > 1.0  # a real rotation
    np.testing.assert_allclose(_wrapped(run.attitude_euler - expected), 0.0, atol=1e-12)
    np.testing.assert_allclose(_wrapped(np.radians(run.attitude_deg) - expected), 0.0, atol=1e-12)


def test_attitude_of_a_linear_run_from_the_rigid_satellites_model() -> None:
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    poly = sat.polytope(x0, 0.1, 0.3, "scalar")
    run = simulate(LQR(poly, Q=np.eye(6), R=np.eye(3)), poly, x0, duration=2.0)
    assert run.plant == "linear"
    np.testing.assert_array_equal(run.attitude_deg, np.degrees(run.x[:, :3]))


class _UnitCircle:
    """A model without attitude."""

    n_states, n_inputs = 2, 1

    def dynamics(self, x: np.ndarray, u: np.ndarray, d: np.ndarray | None = None) -> np.ndarray:
        return np.array([-x[1], x[0]]) * float(u[0])


def test_a_plant_without_attitude_has_none_and_says_so(tmp_path) -> None:
    run = simulate(_Zero(1), _UnitCircle(), [1.0, 0.0], duration=1.0, dt=0.1)
    assert run.attitude_euler is None
    with pytest.raises(InvalidArgumentError, match="plant") as err:
        _ = run.attitude_deg
    assert "attitude_euler" in str(err.value)
    path = tmp_path / "run.npz"
    run.save_npz(str(path))
    with np.load(path) as data:
        assert "attitude_deg" not in data.files and data["x"].shape == (11, 2)
    # a bare polytope member (no attitude given) likewise
    linear = LinearPlant(np.eye(2), np.ones((2, 1)), 0.1)
    assert not linear.has_attitude
    assert simulate(_Zero(1), linear, [1.0, 0.0], n_steps=3).attitude_euler is None
    with pytest.raises(InvalidArgumentError, match="plant"):
        linear.attitude_euler(np.zeros(2))
