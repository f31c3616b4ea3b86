"""The uncertainty polytope of the flexible satellite (seed papers-S-V-flexible.md, section 9).

The continuous-time model at any parameter point of the box is *exactly* the combination of the
vertex models with the multilinear (tensor-product) weights of the point, because ``A`` is
multi-affine and ``B`` affine in the box parameters. After the zero-order hold this holds only
to second order in ``dt``: measured at ``(kappa, f, g) = (1.07, 0.95, 1.4)`` the residual of
``A_d`` is 1.3e-5, 2.7e-6, 6.8e-7, 1.7e-7 at dt = 0.04, 0.02, 0.01, 0.005 s (ratio 4 per
halving), that of ``B_d`` 2.4e-9 .. 3.3e-11 (``|B_d|`` ~ 2e-4 at 0.01 s).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from models import FlexibleSatellite, zoh
from models.flexible.linear import ParameterPoint
from models.flexible.polytope import (
    DEFAULT_DAMPING_RANGE,
    DEFAULT_FREQUENCY_RANGE,
    DEFAULT_INVERSE_INERTIA_RANGE,
    vertex_parameters,
)
from toolkit_common.errors import InvalidArgumentError


@pytest.fixture(scope="module")
def sat() -> FlexibleSatellite:
    return FlexibleSatellite.di_gennaro()


def _group_weights(kappa: float, f: float, g: float) -> np.ndarray:
    """Multilinear weights of a point in the (kappa, f^2, f g) box, in vertex order."""
    k_lo, k_hi = DEFAULT_INVERSE_INERTIA_RANGE
    f_lo, f_hi = DEFAULT_FREQUENCY_RANGE
    g_lo, g_hi = DEFAULT_DAMPING_RANGE
    coords = [
        (kappa - k_lo) / (k_hi - k_lo),
        (f**2 - f_lo**2) / (f_hi**2 - f_lo**2),
        (f * g - f_lo * g_lo) / (f_hi * g_hi - f_lo * g_lo),
    ]
    return np.array([np.prod([t if hi else 1.0 - t for t, hi in zip(coords, corner, strict=True)])
                     for corner in itertools.product((0, 1), repeat=3)])


def _true_point(sat: FlexibleSatellite, kappa: float, f: float, g: float) -> ParameterPoint:
    k0 = np.diag(sat.stiffness)
    c0 = np.diag(sat.damping_matrix)
    return ParameterPoint(kappa=kappa, stiffness=f**2 * k0, viscous_damping=f * g * c0)


@pytest.mark.parametrize("attitude", ["euler", "quaternion"])
def test_continuous_family_is_in_the_hull_of_the_vertices(sat: FlexibleSatellite, attitude: str) -> None:
    points = vertex_parameters(sat)
    assert len(points) == 8
    verts = [sat.linearize(pzt=True, attitude=attitude, parameters=p) for p in points]
    rng = np.random.default_rng(11)
    for _ in range(25):
        kappa = rng.uniform(*DEFAULT_INVERSE_INERTIA_RANGE)
        f = rng.uniform(*DEFAULT_FREQUENCY_RANGE)
        g = rng.uniform(*DEFAULT_DAMPING_RANGE)
        w = _group_weights(kappa, f, g)
        assert np.all(w >= 0.0) and w.sum() == pytest.approx(1.0, abs=1e-14)
        a, b = sat.linearize(pzt=True, attitude=attitude, parameters=_true_point(sat, kappa, f, g))
        a_hull = np.tensordot(w, np.stack([v[0] for v in verts]), axes=1)
        b_hull = np.tensordot(w, np.stack([v[1] for v in verts]), axes=1)
        np.testing.assert_allclose(a_hull, a, rtol=0, atol=1e-13 * np.abs(a).max())
        np.testing.assert_allclose(b_hull, b, rtol=0, atol=1e-13 * np.abs(b).max())


def test_box_mode_holds_every_corner(sat: FlexibleSatellite) -> None:
    small = sat.with_modes(2)
    poly = small.polytope(dt=0.01, mode="box")
    assert poly.n_vertices == 2 ** (1 + 2 * 2)
    points = vertex_parameters(small, "box")
    # the corner (kappa low, k_1 high, k_2 low, c_1 low, c_2 high) is there, in product order
    index = int("01001", 2)
    p = points[index]
    k0 = np.diag(small.stiffness)
    c0 = np.diag(small.damping_matrix)
    assert p.kappa == DEFAULT_INVERSE_INERTIA_RANGE[0]
    np.testing.assert_allclose(p.stiffness, [1.1**2 * k0[0], 0.9**2 * k0[1]])
    np.testing.assert_allclose(p.viscous_damping, [0.45 * c0[0], 2.2 * c0[1]])
    np.testing.assert_allclose(poly.vertex(index)[0], zoh(*small.linearize(parameters=p), 0.01)[0])
    assert sat.polytope(dt=0.01, mode="box").n_vertices == 512


def test_zoh_residual_is_second_order_in_dt(sat: FlexibleSatellite) -> None:
    w = _group_weights(1.07, 0.95, 1.4)
    residual = []
    for dt in (0.02, 0.01):
        poly = sat.polytope(dt=dt)
        a, b = zoh(*sat.linearize(parameters=_true_point(sat, 1.07, 0.95, 1.4)), dt)
        a_hull, b_hull = poly.combination(w)
        residual.append(np.abs(a_hull - a).max())
        assert np.abs(b_hull - b).max() < 1e-5 * np.abs(b).max()
    assert residual[1] > 0.0  # not exact after the hold ...
    assert 3.0 < residual[0] / residual[1] < 5.0  # ... but O(dt^2)


def test_effectiveness_mode_scales_the_torque_columns(sat: FlexibleSatellite) -> None:
    poly = sat.polytope(dt=0.01, mode="effectiveness", pzt=True)
    a0, b0 = sat.discretize(dt=0.01, pzt=True)
    assert poly.n_vertices == 2
    for (a, b), e in zip(poly.vertices, (0.8, 1.2), strict=True):
        np.testing.assert_allclose(a, a0, atol=1e-15)
        np.testing.assert_allclose(b[:, :3], e * b0[:, :3], rtol=1e-12, atol=1e-18)
        np.testing.assert_allclose(b[:, 3:], b0[:, 3:], rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(poly.nominal[1], b0)
    assert poly.input_names == ("Mx", "My", "Mz", "v_1", "v_2", "v_3", "v_4")
    assert sat.polytope(dt=0.01, attitude="quaternion").state_names[:3] == ("q1", "q2", "q3")


def test_bad_options_name_the_argument(sat: FlexibleSatellite) -> None:
    with pytest.raises(InvalidArgumentError, match="mode"):
        sat.polytope(dt=0.01, mode="corners")
    with pytest.raises(InvalidArgumentError, match="damping_range"):
        sat.polytope(dt=0.01, damping_range=(2.0, 0.5))
    with pytest.raises(InvalidArgumentError, match="inverse_inertia_range"):
        sat.polytope(dt=0.01, inverse_inertia_range=(-0.1, 1.2))
    with pytest.raises(InvalidArgumentError, match="dt"):
        sat.polytope(dt=0.0)
    with pytest.raises(InvalidArgumentError, match="stiffness"):
        sat.linearize(parameters=ParameterPoint(stiffness=[1.0, 1.0, -1.0, 1.0]))
