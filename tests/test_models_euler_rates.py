"""The 3-2-1 Euler-angle rates against finite differences of the rotation (SciPy's ``Rotation``).

The attitude ``R = Rz(psi) Ry(theta) Rx(phi)`` (body to inertial) moves with the body rates
``w`` as ``R(t + h) = R(t) exp(h [w]x)``. SciPy composes the two rotations and returns the
angles of ``R(t +- h)`` (``as_euler("ZYX")``); their central difference is
``[phi', theta', psi']`` to ``O(h^2)``, independent of the toolkit's kinematics matrix.
Measured over 200 random attitudes (pitch within +-1.2 rad) and rates, ``h = 1e-5``: the
largest difference is 2.2e-9 of ``||eta'||`` (rounding over ``2 h``); asserted 1e-7.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from models.attitude.euler import euler_rates
from toolkit_common.errors import SingularityError

H = 1e-5


def _finite_difference(eta: np.ndarray, w: np.ndarray) -> np.ndarray:
    rot = Rotation.from_euler("ZYX", eta[::-1])
    plus = (rot * Rotation.from_rotvec(w * H)).as_euler("ZYX")[::-1]
    minus = (rot * Rotation.from_rotvec(-w * H)).as_euler("ZYX")[::-1]
    step = (plus - minus + np.pi) % (2.0 * np.pi) - np.pi  # across the +-pi cut of phi and psi
    return step / (2.0 * H)


def test_euler_rates_are_the_derivative_of_the_rotating_attitude():
    rng = np.random.default_rng(21)
    for _ in range(200):
        eta = rng.uniform([-3.0, -1.2, -3.0], [3.0, 1.2, 3.0])
        w = rng.normal(size=3)
        rates = euler_rates(eta, w)
        np.testing.assert_allclose(rates, _finite_difference(eta, w), rtol=0,
                                   atol=1e-7 * np.linalg.norm(rates))


def test_euler_rates_by_hand():
    """At zero roll and pitch the rates are the body rates; at roll 90 deg q drives yaw, r pitch."""
    w = np.array([0.1, -0.2, 0.3])
    np.testing.assert_allclose(euler_rates(np.array([0.0, 0.0, 1.0]), w), w, atol=1e-17)
    # phi = 90 deg: theta' = cos(phi) q - sin(phi) r = -r, psi' = (sin(phi) q + cos(phi) r)/cos(theta) = q
    np.testing.assert_allclose(euler_rates(np.array([np.pi / 2, 0.0, 0.0]), w), [0.1, -0.3, -0.2], atol=1e-16)


def test_euler_rates_refuse_gimbal_lock():
    with pytest.raises(SingularityError, match="theta"):
        euler_rates(np.array([0.0, np.pi / 2, 0.0]), np.ones(3))
