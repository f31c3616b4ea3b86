"""The inertia polytope contains every plant of the uncertainty set (zero operating rates).

At zero rates ``A`` does not depend on ``J`` and the discrete ``B`` is linear in ``J^-1``, so an
inertia inside the box (or the scalar interval) must give a ``B`` in the convex hull of the
vertices' ``B``. Membership is checked with an LP: the smallest ``t`` such that some convex
weights reproduce ``B`` to within ``t`` in every entry (each entry scaled by its largest vertex
magnitude). Inside: measured ``t`` <= 1.3e-15; asserted ``t < 1e-9``. The negative controls
(an inertia 10 % beyond the box; a non-scalar inertia against the scalar polytope) give
``t`` = 0.035 to 0.65, so the check can fail.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

from models import PAPER_P_INITIAL_STATE, RigidSatellite

DT = 0.01
FULL_INERTIA = np.array([[2.0, -0.3, 0.15], [-0.3, 3.0, 0.4], [0.15, 0.4, 4.5]])
INERTIAS = {
    "paper-p-diag": np.diag([1.2928, 1.2928, 4.2953]),
    "diag": np.diag([1.0, 2.5, 4.0]),
    "full": FULL_INERTIA,
}
INSIDE_TOL = 1e-9


def hull_distance(point: np.ndarray, vertices: list[np.ndarray]) -> float:
    """Smallest scaled max-entry distance from ``point`` to the convex hull of ``vertices``."""
    pts = np.array([v.ravel() for v in vertices])  # (k, d)
    target = point.ravel()
    scale = np.max(np.abs(pts), axis=0)
    keep = scale > 0.0
    # entries that are zero at every vertex must be zero in the point too
    if np.any(np.abs(target[~keep]) > 0.0):
        return float("inf")
    pts, target, scale = pts[:, keep] / scale[keep], target[keep] / scale[keep], scale[keep]
    k, d = pts.shape
    # variables: weights (k), t; minimise t
    c = np.zeros(k + 1)
    c[-1] = 1.0
    a_ub = np.block([[pts.T, -np.ones((d, 1))], [-pts.T, -np.ones((d, 1))]])
    b_ub = np.concatenate((target, -target))
    a_eq = np.concatenate((np.ones(k), [0.0]))[None, :]
    res = linprog(c, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=[1.0], bounds=[(0, None)] * (k + 1),
                  method="highs")
    assert res.status == 0, res.message
    # recompute the residual from the returned weights rather than trusting the LP's t
    w = res.x[:k]
    assert np.all(w >= -1e-12) and abs(w.sum() - 1.0) < 1e-9
    return float(np.max(np.abs(w @ pts - target)))


def _operating_points(rng: np.random.Generator, count: int) -> list[np.ndarray]:
    points = [np.asarray(PAPER_P_INITIAL_STATE)]
    while len(points) < count:
        att = [rng.uniform(-np.pi, np.pi), rng.uniform(-1.2, 1.2), rng.uniform(-np.pi, np.pi)]
        points.append(np.concatenate((att, np.zeros(3))))
    return points


def _principal(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal inertias and axes; the body axes for a diagonal matrix."""
    if np.count_nonzero(inertia - np.diag(np.diag(inertia))) == 0:
        return np.diag(inertia).copy(), np.eye(3)
    return np.linalg.eigh(inertia)


def _box_draws(rng: np.random.Generator, inertia: np.ndarray, spread: float, count: int) -> list:
    """Inertias with each principal value scaled independently within [1 - s, 1 + s]."""
    lam, vec = _principal(inertia)
    draws = []
    for i in range(count):
        if i < 4:  # corners and faces of the box are part of the set too
            scales = rng.choice([1.0 - spread, 1.0 + spread], size=3)
            if i >= 2:
                scales[i - 2] = rng.uniform(1.0 - spread, 1.0 + spread)
        else:
            scales = rng.uniform(1.0 - spread, 1.0 + spread, 3)
        draws.append(vec @ np.diag(lam * scales) @ vec.T)
    return draws


@pytest.mark.parametrize("spread", [0.3, 0.7])
@pytest.mark.parametrize("name", list(INERTIAS))
def test_box_polytope_contains_every_inertia_in_the_box(name, spread):
    rng = np.random.default_rng([list(INERTIAS).index(name), round(100 * spread), 1])
    sat = RigidSatellite(INERTIAS[name])
    worst = 0.0
    for x_op in _operating_points(rng, 2):
        poly = sat.polytope(x_op, dt=DT, spread=spread, mode="box")
        assert poly.n_vertices == 8
        b_vertices = [b for _, b in poly.vertices]
        # A is the same at every vertex (zero rates: A does not depend on J)
        for a, _ in poly.vertices:
            np.testing.assert_allclose(a, poly.A[0], rtol=0, atol=1e-15)
        for inertia in _box_draws(rng, INERTIAS[name], spread, 8):
            _, b = RigidSatellite(inertia).discretize(x_op, DT)
            worst = max(worst, hull_distance(b, b_vertices))
        # the nominal satellite is inside as well
        worst = max(worst, hull_distance(poly.nominal[1], b_vertices))
    assert worst < INSIDE_TOL


@pytest.mark.parametrize("spread", [0.3, 0.7])
@pytest.mark.parametrize("name", list(INERTIAS))
def test_scalar_polytope_contains_every_scaled_inertia(name, spread):
    rng = np.random.default_rng([list(INERTIAS).index(name), round(100 * spread), 2])
    sat = RigidSatellite(INERTIAS[name])
    worst = 0.0
    for x_op in _operating_points(rng, 2):
        poly = sat.polytope(x_op, dt=DT, spread=spread, mode="scalar")
        assert poly.n_vertices == 2
        b_vertices = [b for _, b in poly.vertices]
        scalings = np.concatenate(([1.0 - spread, 1.0 + spread], rng.uniform(1 - spread, 1 + spread, 4)))
        for c in scalings:
            _, b = RigidSatellite(c * INERTIAS[name]).discretize(x_op, DT)
            worst = max(worst, hull_distance(b, b_vertices))
    assert worst < INSIDE_TOL


@pytest.mark.parametrize("name", ["diag", "full"])
def test_inertias_outside_the_set_are_outside_the_hull(name):
    """Negative controls: the LP check is able to say 'outside'."""
    spread = 0.3
    sat = RigidSatellite(INERTIAS[name])
    x_op = np.asarray(PAPER_P_INITIAL_STATE)
    lam, vec = _principal(INERTIAS[name])
    box = [b for _, b in sat.polytope(x_op, DT, spread, mode="box").vertices]
    scalar = [b for _, b in sat.polytope(x_op, DT, spread, mode="scalar").vertices]
    # one principal inertia 10 % beyond the box
    beyond = vec @ np.diag(lam * np.array([1.0, 1.0 + spread + 0.1, 1.0])) @ vec.T
    _, b = RigidSatellite(beyond).discretize(x_op, DT)
    assert hull_distance(b, box) > 1e-2
    # inside the box but not a scalar multiple of J0: outside the 2-vertex scalar polytope
    skewed = vec @ np.diag(lam * np.array([1.0 - spread, 1.0, 1.0 + spread])) @ vec.T
    _, b = RigidSatellite(skewed).discretize(x_op, DT)
    assert hull_distance(b, box) < INSIDE_TOL
    assert hull_distance(b, scalar) > 1e-2


@pytest.mark.parametrize("mode", ["scalar", "box"])
@pytest.mark.parametrize("name", list(INERTIAS))
def test_zero_spread_vertices_equal_nominal(name, mode):
    sat = RigidSatellite(INERTIAS[name])
    x_op = np.array([0.1, 0.4, -0.2, 0.0, 0.0, 0.0])
    poly = sat.polytope(x_op, dt=DT, spread=0.0, mode=mode)
    assert poly.n_vertices == (2 if mode == "scalar" else 8)
    ad, bd = sat.discretize(x_op, DT)
    np.testing.assert_allclose(poly.nominal[0], ad, rtol=0, atol=0)
    np.testing.assert_allclose(poly.nominal[1], bd, rtol=0, atol=0)
    for a, b in poly.vertices:
        np.testing.assert_allclose(a, ad, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(b, bd, rtol=1e-13, atol=1e-15)


def test_inertia_vertices_are_the_box_corners():
    """The 8 vertex inertias are exactly the corners (1 +- s) J_i, each corner once."""
    spread = 0.3
    base = np.array([1.0, 2.5, 4.0])
    sat = RigidSatellite(base)
    corners = sat.inertia_vertices(spread, mode="box")
    got = sorted(tuple(np.round(np.diag(c) / base, 12)) for c in corners)
    want = sorted(
        (sx, sy, sz) for sx in (0.7, 1.3) for sy in (0.7, 1.3) for sz in (0.7, 1.3)
    )
    assert got == want
    for c in corners:
        assert np.count_nonzero(c - np.diag(np.diag(c))) == 0
    scalar = sat.inertia_vertices(spread, mode="scalar")
    assert sorted(float(c[0, 0] / base[0]) for c in scalar) == pytest.approx([0.7, 1.3])


def test_full_inertia_box_corners_keep_principal_axes():
    """For a full J0 the box is in its principal axes: every corner commutes with J0."""
    sat = RigidSatellite(FULL_INERTIA)
    for corner in sat.inertia_vertices(0.4, mode="box"):
        np.testing.assert_allclose(corner, corner.T, atol=1e-14)
        np.testing.assert_allclose(corner @ FULL_INERTIA, FULL_INERTIA @ corner, atol=1e-12)
        lam = np.linalg.eigvalsh(corner)
        assert np.all(lam > 0)
