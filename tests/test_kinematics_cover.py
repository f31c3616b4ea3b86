"""The covering polytope of the nonlinear kinematics (issue 11, part 4).

Checked against independent computations: containment by a linear program (scipy's HiGHS),
the ZOH by the matrix exponential, and the frozen-attitude model by the nonlinear dynamics.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import linprog

from models import RigidSatellite
from models.attitude.euler import kinematics_cover, kinematics_matrix
from toolkit_common.errors import InvalidArgumentError, SingularityError


def _in_hull(point: np.ndarray, vertices: list[np.ndarray]) -> bool:
    """Is ``point`` a convex combination of ``vertices``? (an LP feasibility problem)."""
    v = np.array([m.ravel() for m in vertices]).T
    a_eq = np.vstack([v, np.ones((1, v.shape[1]))])
    b_eq = np.concatenate([point.ravel(), [1.0]])
    res = linprog(np.zeros(v.shape[1]), A_eq=a_eq, b_eq=b_eq, bounds=(0, None), method="highs")
    return res.status == 0


BOXES = [((-0.2, 0.5), (-0.3, 0.4)), ((0.0, 1.0), (0.2, 1.1)), ((-1.2, -0.4), (-1.0, 0.0))]


@pytest.mark.parametrize(("phi_b", "theta_b"), BOXES)
def test_cover_contains_every_attitude_of_the_box(phi_b, theta_b):
    mats = kinematics_cover(phi_b, theta_b)
    assert len(mats) == 9
    rng = np.random.default_rng(11)
    grid = [(p, t) for p in np.linspace(*phi_b, 7) for t in np.linspace(*theta_b, 7)]
    grid += [tuple(rng.uniform(*b) for b in (phi_b, theta_b)) for _ in range(30)]
    for phi, theta in grid:
        assert _in_hull(kinematics_matrix(phi, theta), mats), (phi, theta)


def test_box_corners_alone_do_not_cover_the_interior():
    phi_b, theta_b = (0.0, 1.0), (0.2, 1.1)
    corners = [kinematics_matrix(p, t) for p in phi_b for t in theta_b]
    mid = kinematics_matrix(0.5, 0.65)
    assert not _in_hull(mid, corners)
    assert _in_hull(mid, kinematics_cover(phi_b, theta_b))


def test_degenerate_ranges_reduce_the_vertex_count():
    assert len(kinematics_cover((0.3, 0.3), (0.1, 0.4))) == 3
    single = kinematics_cover((0.3, 0.3), (0.2, 0.2))
    assert len(single) == 1
    np.testing.assert_allclose(single[0], kinematics_matrix(0.3, 0.2), atol=1e-15)


def test_cover_rejects_bad_bounds():
    with pytest.raises(InvalidArgumentError, match="phi_bounds"):
        kinematics_cover((0.5, 0.1), (0.0, 0.1))
    with pytest.raises(InvalidArgumentError, match="theta_bounds"):
        kinematics_cover((0.0, 0.1), (0.4, 0.1))
    with pytest.raises(SingularityError):
        kinematics_cover((0.0, 0.1), (-0.2, 1.6))


def test_covering_polytope_vertices_are_the_zoh_of_the_frozen_attitude_model():
    sat = RigidSatellite.paper_p()
    x_op = np.array([0.3, -0.2, 0.1, 0.0, 0.0, 0.0])
    poly = sat.polytope(x_op, dt=0.01, spread=0.3, attitude_range=np.zeros(3))
    assert poly.n_vertices == 2  # one kinematics matrix, two inertia corners
    k_mat = kinematics_matrix(0.3, -0.2)
    for (a_d, b_d), inertia in zip(poly.vertices, sat.inertia_vertices(0.3, "scalar"), strict=True):
        a_c = np.zeros((6, 6))
        a_c[:3, 3:] = k_mat
        b_c = np.vstack([np.zeros((3, 3)), np.linalg.inv(inertia)])
        big = np.zeros((9, 9))
        big[:6, :6], big[:6, 6:] = a_c, b_c
        e = expm(big * 0.01)
        np.testing.assert_allclose(a_d, e[:6, :6], atol=1e-14)
        np.testing.assert_allclose(b_d, e[:6, 6:], atol=1e-14)


def test_covering_polytope_contains_the_frozen_models_of_the_box():
    sat = RigidSatellite.paper_p()
    x_op = np.array([0.4, 0.3, 0.0, 0.0, 0.0, 0.0])
    half = np.radians([20.0, 25.0, 0.0])
    poly = sat.polytope(x_op, dt=0.05, spread=0.3, attitude_range=half)
    assert poly.n_vertices == 18
    verts = [np.hstack([a, b]) for a, b in poly.vertices]
    rng = np.random.default_rng(3)
    for _ in range(15):
        phi = x_op[0] + rng.uniform(-1, 1) * half[0]
        theta = x_op[1] + rng.uniform(-1, 1) * half[1]
        scale = rng.uniform(0.7, 1.3)
        inertia = scale * sat.inertia
        a, b = RigidSatellite(inertia).polytope(
            np.array([phi, theta, 0.0, 0, 0, 0]), dt=0.05, spread=0.0, attitude_range=np.zeros(3)
        ).vertices[0]
        assert _in_hull(np.hstack([a, b]), verts), (phi, theta, scale)


def test_covering_polytope_errors_name_the_argument():
    sat = RigidSatellite.paper_p()
    x_op = np.zeros(6)
    with pytest.raises(InvalidArgumentError, match="attitude_range"):
        sat.polytope(x_op, 0.01, 0.3, attitude_range=[-0.1, 0.0, 0.0])
    with pytest.raises(InvalidArgumentError, match="attitude_range"):
        sat.polytope(x_op, 0.01, 0.3, attitude_range=[0.1, np.radians(91), 0.0])
    with pytest.raises(InvalidArgumentError, match="attitude_range"):
        sat.polytope(x_op, 0.01, 0.3, attitude_range=[np.radians(95), 0.0, 0.0])
    with pytest.raises(InvalidArgumentError, match="attitude_range"):
        sat.polytope(x_op, 0.01, 0.3, attitude_range=[np.nan, 0.0, 0.0])
    with pytest.raises(InvalidArgumentError, match="x_op"):
        sat.polytope(np.array([0, 0, 0, 0.1, 0, 0]), 0.01, 0.3, attitude_range=[0.1, 0.1, 0.0])
