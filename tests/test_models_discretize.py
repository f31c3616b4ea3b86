"""Zero-order-hold discretisation against python-control, and PolytopicModel <-> StateSpace."""

from __future__ import annotations

import control
import numpy as np
import pytest

from models import PAPER_P_INITIAL_STATE, PolytopicModel, RigidSatellite, zoh

RTOL = 1e-12


def _c2d(a: np.ndarray, b: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    n, m = b.shape
    sysd = control.c2d(control.ss(a, b, np.eye(n), np.zeros((n, m))), dt, "zoh")
    assert sysd.dt == dt
    return np.asarray(sysd.A), np.asarray(sysd.B)


def _assert_close(actual: np.ndarray, desired: np.ndarray) -> None:
    scale = max(1.0, float(np.max(np.abs(desired))))
    np.testing.assert_allclose(actual, desired, rtol=RTOL, atol=RTOL * scale)


def _cases() -> list[tuple[str, np.ndarray, np.ndarray, float]]:
    rng = np.random.default_rng(7)
    cases = [
        # singular A: double integrator (A nilpotent), Bd = [dt^2/2, dt]
        ("double-integrator", np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]]), 0.1),
        # singular A with a zero column and a stable mode
        ("singular-mixed", np.array([[0.0, 1.0, 0.0], [0.0, -2.0, 1.0], [0.0, 0.0, 0.0]]),
         np.array([[0.0, 1.0], [1.0, 0.0], [0.5, 1.0]]), 0.05),
        # A = 0 exactly
        ("zero-A", np.zeros((3, 3)), rng.normal(size=(3, 2)), 0.3),
    ]
    for i in range(4):
        n, m = rng.integers(2, 7), rng.integers(1, 4)
        cases.append((f"random-{i}", rng.normal(size=(n, n)), rng.normal(size=(n, m)),
                      float(rng.uniform(0.005, 0.5))))
    return cases


@pytest.mark.parametrize(("name", "a", "b", "dt"), _cases(), ids=[c[0] for c in _cases()])
def test_zoh_equals_control_c2d(name, a, b, dt):
    ad, bd = zoh(a, b, dt)
    ad_ref, bd_ref = _c2d(a, b, dt)
    _assert_close(ad, ad_ref)
    _assert_close(bd, bd_ref)


def test_zoh_double_integrator_closed_form():
    """Independent of both codes: Ad = [[1, dt], [0, 1]], Bd = [dt^2 / 2, dt]."""
    dt = 0.37
    ad, bd = zoh([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], dt)
    np.testing.assert_allclose(ad, [[1.0, dt], [0.0, 1.0]], rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(bd, [[dt**2 / 2], [dt]], rtol=1e-14, atol=1e-15)


@pytest.mark.parametrize("dt", [0.01, 0.1])
@pytest.mark.parametrize(
    "x_op",
    [np.asarray(PAPER_P_INITIAL_STATE), np.array([0.2, -0.5, 1.0, 0.3, -0.2, 0.6])],
    ids=["paper-p-point", "spinning"],
)
@pytest.mark.parametrize(
    "inertia",
    [[1.2928, 1.2928, 4.2953], [[2.0, -0.3, 0.1], [-0.3, 3.0, 0.4], [0.1, 0.4, 4.0]]],
    ids=["diag", "full"],
)
def test_satellite_discretize_equals_c2d(inertia, x_op, dt):
    sat = RigidSatellite(inertia)
    a, b = sat.linearize(x_op)
    if not np.any(x_op[3:]):
        # paper P's point: A is singular (nilpotent), the case the block exponential handles
        assert np.linalg.matrix_rank(a) < 6
    ad, bd = sat.discretize(x_op, dt)
    ad_ref, bd_ref = _c2d(a, b, dt)
    _assert_close(ad, ad_ref)
    _assert_close(bd, bd_ref)
    model = sat.linear_model(x_op, dt)
    assert model.n_vertices == 1 and model.dt == dt
    _assert_close(model.A[0], ad_ref)
    _assert_close(model.B[0], bd_ref)


def _random_polytope(rng: np.random.Generator, n: int = 4, m: int = 2, k: int = 3) -> PolytopicModel:
    verts = [(rng.normal(size=(n, n)), rng.normal(size=(n, m))) for _ in range(k)]
    return PolytopicModel(verts, dt=0.05)


def test_nominal_defaults_to_vertex_mean():
    rng = np.random.default_rng(3)
    plant = _random_polytope(rng)
    a_mean = sum(a for a, _ in plant.vertices) / plant.n_vertices
    b_mean = sum(b for _, b in plant.vertices) / plant.n_vertices
    np.testing.assert_allclose(plant.nominal[0], a_mean, rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(plant.nominal[1], b_mean, rtol=1e-15, atol=1e-15)
    # an explicit nominal is kept as given
    a_nom, b_nom = plant.vertex(0)
    explicit = PolytopicModel(plant.vertices, plant.dt, nominal=(a_nom, b_nom))
    np.testing.assert_array_equal(explicit.nominal[0], a_nom)
    np.testing.assert_array_equal(explicit.nominal[1], b_nom)


def test_to_statespace_and_back_round_trip():
    rng = np.random.default_rng(11)
    plant = _random_polytope(rng, n=5, m=3, k=4)
    systems = plant.to_statespace_list()
    assert len(systems) == plant.n_vertices
    for j, sys in enumerate(systems):
        assert isinstance(sys, control.StateSpace)
        assert sys.dt == plant.dt
        np.testing.assert_array_equal(sys.A, plant.A[j])
        np.testing.assert_array_equal(sys.B, plant.B[j])
        np.testing.assert_array_equal(sys.C, np.eye(5))
        np.testing.assert_array_equal(sys.D, np.zeros((5, 3)))
    back = PolytopicModel.from_statespace(systems)
    assert (back.n_states, back.n_inputs, back.n_vertices, back.dt) == (5, 3, 4, plant.dt)
    np.testing.assert_array_equal(back.A, plant.A)
    np.testing.assert_array_equal(back.B, plant.B)
    np.testing.assert_allclose(back.nominal[0], plant.nominal[0], rtol=1e-15, atol=1e-15)
    # the nominal system converts too, and can be handed back explicitly
    nominal_sys = plant.to_statespace()
    np.testing.assert_array_equal(nominal_sys.A, plant.nominal[0])
    again = PolytopicModel.from_statespace(systems, nominal=plant.to_statespace(2))
    np.testing.assert_array_equal(again.nominal[1], plant.B[2])


def test_from_single_statespace_and_names():
    sat = RigidSatellite.paper_p()
    plant = sat.polytope(sat.initial_state(), dt=0.01, spread=0.3, mode="scalar")
    sys = plant.to_statespace(1)
    assert list(sys.state_labels) == ["phi", "theta", "psi", "p", "q", "r"]
    assert list(sys.input_labels) == ["Mx", "My", "Mz"]
    one = PolytopicModel.from_statespace(sys)
    assert one.n_vertices == 1
    np.testing.assert_array_equal(one.B[0], plant.B[1])
    # the two vertices are the c2d of the continuous models at 1.3 J and 0.7 J (in some order)
    refs = [_c2d(*RigidSatellite(c * sat.inertia).linearize(sat.initial_state()), 0.01) for c in (1.3, 0.7)]
    got = [plant.to_statespace(j) for j in range(2)]
    if not np.allclose(got[0].B, refs[0][1], rtol=RTOL, atol=0.0):
        refs.reverse()
    for sys_j, (ad_ref, bd_ref) in zip(got, refs, strict=True):
        _assert_close(sys_j.A, ad_ref)
        _assert_close(sys_j.B, bd_ref)


def test_from_statespace_rejects_continuous_and_mixed_dt():
    cont = control.ss(np.eye(2), np.ones((2, 1)), np.eye(2), np.zeros((2, 1)))
    with pytest.raises(ValueError, match="dt"):
        PolytopicModel.from_statespace([cont])
    d1 = control.ss(np.eye(2), np.ones((2, 1)), np.eye(2), np.zeros((2, 1)), 0.1)
    d2 = control.ss(np.eye(2), np.ones((2, 1)), np.eye(2), np.zeros((2, 1)), 0.2)
    with pytest.raises(ValueError, match="dt"):
        PolytopicModel.from_statespace([d1, d2])
