"""The analytic Jacobians of ``RigidSatellite.linearize`` against finite differences and python-control.

Measured over the 24 points below (seed 20240611), as max |error| / max |A|: central
differences (step 1e-5, see ``_central_jacobians``) 3e-10; python-control's forward differences
1.6e-6 with its default ``eps = 1e-6`` and 4e-8 with ``eps = 1e-8``. Asserted: 1e-6, 2e-5 and
1e-6 respectively.
"""

from __future__ import annotations

import control
import numpy as np
import pytest

from models import PAPER_P_INERTIA, PAPER_P_INITIAL_STATE, RigidSatellite

SEED = 20240611
N_POINTS = 12


def _random_inertia(rng: np.random.Generator, full: bool) -> np.ndarray:
    """A diagonal or a full symmetric positive definite inertia (principal values 0.5..5 kg m^2)."""
    principal = rng.uniform(0.5, 5.0, 3)
    if not full:
        return np.diag(principal)
    while True:
        rot, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        inertia = rot @ np.diag(principal) @ rot.T
        inertia = 0.5 * (inertia + inertia.T)
        # really full: every product of inertia is non-negligible
        if np.min(np.abs(inertia[np.triu_indices(3, 1)])) > 1e-2:
            return inertia


def _random_points(full: bool) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(inertia, x_op, u_op) with non-zero rates and |pitch| <= 1.2 rad (69 deg) from +-90 deg."""
    rng = np.random.default_rng(SEED + int(full))
    points = []
    while len(points) < N_POINTS:
        inertia = _random_inertia(rng, full)
        attitude = np.array(
            [rng.uniform(-np.pi, np.pi), rng.uniform(-1.2, 1.2), rng.uniform(-np.pi, np.pi)]
        )
        rates = rng.uniform(-1.0, 1.0, 3)
        rates += 0.1 * np.sign(rates)  # every rate at least 0.1 rad/s in magnitude
        points.append((inertia, np.concatenate((attitude, rates)), rng.uniform(-1.0, 1.0, 3)))
    return points


POINTS = [(False, *p) for p in _random_points(False)] + [(True, *p) for p in _random_points(True)]
IDS = [f"{'full' if full else 'diag'}-{i % N_POINTS}" for i, (full, *_) in enumerate(POINTS)]


def _central_jacobians(
    sat: RigidSatellite, x: np.ndarray, u: np.ndarray, h: float = 1e-5
) -> tuple[np.ndarray, np.ndarray]:
    """Central differences of ``sat.dynamics``.

    The truncation error is ``h^2 |f'''| / 6`` and the rounding error ``eps |f| / h``; both are
    about 1e-10 at ``h = 1e-5`` for these O(1) states, well inside the 1e-6 asserted below.
    """
    a = np.zeros((6, 6))
    b = np.zeros((6, 3))
    for i in range(6):
        e = np.zeros(6)
        e[i] = h
        a[:, i] = (sat.dynamics(x + e, u) - sat.dynamics(x - e, u)) / (2.0 * h)
    for i in range(3):
        e = np.zeros(3)
        e[i] = h
        b[:, i] = (sat.dynamics(x, u + e) - sat.dynamics(x, u - e)) / (2.0 * h)
    return a, b


def _assert_close(actual: np.ndarray, desired: np.ndarray, rel: float) -> None:
    """Element-wise within ``rel`` times the largest entry of ``desired``."""
    scale = float(np.max(np.abs(desired)))
    assert scale > 0.0
    np.testing.assert_allclose(actual, desired, rtol=rel, atol=rel * scale)


@pytest.mark.parametrize(("full", "inertia", "x_op", "u_op"), POINTS, ids=IDS)
def test_linearize_equals_central_differences(full, inertia, x_op, u_op):
    # a diagonal inertia is given as its three principal values, the other constructor form
    sat = RigidSatellite(np.diag(inertia) if not full else inertia)
    a, b = sat.linearize(x_op, u_op)
    a_fd, b_fd = _central_jacobians(sat, x_op, u_op)
    _assert_close(a, a_fd, 1e-6)
    _assert_close(b, b_fd, 1e-6)
    # the rate-dependent blocks are really exercised (non-zero rates)
    assert np.max(np.abs(a[3:, 3:])) > 1e-3
    assert np.max(np.abs(a[:3, :3])) > 1e-3


@pytest.mark.parametrize(("full", "inertia", "x_op", "u_op"), POINTS[::3], ids=IDS[::3])
def test_linearize_equals_python_control(full, inertia, x_op, u_op):
    sat = RigidSatellite(inertia)
    a, b = sat.linearize(x_op, u_op)
    nlsys = sat.to_nlsys()
    # python-control uses forward differences: truncation error eps |f''| / 2
    lin = control.linearize(nlsys, x_op, u_op)  # default eps = 1e-6
    _assert_close(lin.A, a, 2e-5)
    _assert_close(lin.B, b, 2e-5)
    lin_fine = control.linearize(nlsys, x_op, u_op, eps=1e-8)
    _assert_close(lin_fine.A, a, 1e-6)
    _assert_close(lin_fine.B, b, 1e-6)
    # full-state output
    np.testing.assert_allclose(lin.C, np.eye(6), atol=1e-6)
    np.testing.assert_allclose(lin.D, 0.0, atol=1e-6)


def test_nlsys_disturbance_inputs_enter_like_the_torque():
    inertia, x_op, u_op = POINTS[-1][1:]
    sat = RigidSatellite(inertia)
    nlsys = sat.to_nlsys(with_disturbance=True)
    assert nlsys.ninputs == 6
    lin = control.linearize(nlsys, x_op, np.concatenate((u_op, np.zeros(3))), eps=1e-8)
    _, b = sat.linearize(x_op, u_op)
    _assert_close(lin.B[:, :3], b, 1e-6)
    _assert_close(lin.B[:, 3:], b, 1e-6)


def test_u_op_does_not_change_the_jacobians():
    inertia, x_op, _ = POINTS[N_POINTS + 1][1:]
    sat = RigidSatellite(inertia)
    a0, b0 = sat.linearize(x_op)
    a1, b1 = sat.linearize(x_op, [0.7, -0.3, 2.0])
    np.testing.assert_array_equal(a0, a1)
    np.testing.assert_array_equal(b0, b1)


def test_paper_p_operating_point_structure():
    """At zero rates: A = [[0, K(phi0, theta0)], [0, 0]], B = [0; J^-1] (spec section 1)."""
    sat = RigidSatellite.paper_p()
    x_op = np.asarray(PAPER_P_INITIAL_STATE)
    phi, theta = x_op[0], x_op[1]
    # the kinematics matrix written out from the spec's equations (not from the code)
    k = np.array(
        [
            [1.0, np.sin(phi) * np.tan(theta), np.cos(phi) * np.tan(theta)],
            [0.0, np.cos(phi), -np.sin(phi)],
            [0.0, np.sin(phi) / np.cos(theta), np.cos(phi) / np.cos(theta)],
        ]
    )
    a, b = sat.linearize(x_op)
    expected_a = np.zeros((6, 6))
    expected_a[:3, 3:] = k
    expected_b = np.vstack((np.zeros((3, 3)), np.diag(1.0 / np.asarray(PAPER_P_INERTIA))))
    np.testing.assert_allclose(a, expected_a, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(b, expected_b, rtol=1e-14, atol=1e-14)
    # and it matches the spec's numbers: Mx / Ixx with Ixx = 1.2928
    assert b[3, 0] == pytest.approx(1.0 / 1.2928, rel=1e-14)
    assert b[5, 2] == pytest.approx(1.0 / 4.2953, rel=1e-14)


def test_zero_rate_structure_holds_for_a_full_inertia():
    """With a full J and zero rates the gyroscopic block still vanishes and B = [0; J^-1]."""
    inertia = POINTS[N_POINTS][1]
    x_op = np.array([0.3, -0.4, 1.0, 0.0, 0.0, 0.0])
    sat = RigidSatellite(inertia)
    a, b = sat.linearize(x_op)
    np.testing.assert_array_equal(a[3:, :], 0.0)
    np.testing.assert_array_equal(a[:3, :3], 0.0)
    np.testing.assert_allclose(b[3:, :] @ inertia, np.eye(3), atol=1e-12)
    np.testing.assert_array_equal(b[:3, :], 0.0)
