"""Every satellite follows models.protocols.Plant; attitude_euler agrees with scipy's rotations.

Also the linearisation family's common signature (``x_op`` first, ``dt`` next, in every family),
the renamed arguments, and :attr:`models.PolytopicModel.attitude`.
"""

from __future__ import annotations

import control
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from models import FlexibleSatellite, MRPSatellite, PolytopicModel, RigidSatellite, WheelSatellite
from models.attitude.vectors import cross3, skew
from models.protocols import Plant
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

RIGID = RigidSatellite.paper_p()
WHEEL = WheelSatellite.paper_w()
MRP = MRPSatellite.paper_m()
FLEX = FlexibleSatellite.di_gennaro()
PLANTS = {"rigid": RIGID, "wheel": WHEEL, "mrp": MRP, "flexible": FLEX}


def _scipy_euler(rotation: Rotation) -> np.ndarray:
    """Roll, pitch, yaw of the body-to-reference rotation (intrinsic z-y'-x'', i.e. 3-2-1)."""
    return rotation.as_euler("ZYX")[::-1]


def _random_rotations(rng: np.random.Generator, count: int) -> list[Rotation]:
    """Random attitudes away from gimbal lock (|pitch| < 80 deg), where the angles are unique."""
    out = []
    while len(out) < count:
        rot = Rotation.random(random_state=rng)
        if abs(_scipy_euler(rot)[1]) < np.radians(80.0):
            out.append(rot)
    return out


def _state(name: str, rot: Rotation, rng: np.random.Generator) -> np.ndarray:
    """A plant state holding the attitude ``rot`` in the plant's own representation."""
    plant = PLANTS[name]
    rest = rng.normal(size=plant.n_states)
    if name in ("rigid", "wheel"):
        return np.concatenate((_scipy_euler(rot), rest[3:]))
    if name == "mrp":
        return np.concatenate((rot.as_mrp(), rest[3:]))  # scipy: sigma = tan(angle/4) axis
    q = rot.as_quat()  # scalar last
    return np.concatenate(([q[3]], q[:3], rest[4:]))


@pytest.mark.parametrize("name", list(PLANTS))
def test_every_satellite_is_a_plant(name: str) -> None:
    plant = PLANTS[name]
    assert isinstance(plant, Plant)
    assert len(plant.state_names) == plant.n_states and len(plant.input_names) == plant.n_inputs
    assert len(set(plant.state_names)) == plant.n_states
    x = plant.normalize_state(np.r_[1.0, np.zeros(plant.n_states - 1)]) if name == "flexible" else np.zeros(
        plant.n_states
    )
    assert plant.dynamics(x).shape == (plant.n_states,)
    assert plant.dynamics(x, np.zeros(plant.n_inputs), None).shape == (plant.n_states,)


@pytest.mark.parametrize("name", list(PLANTS))
def test_attitude_euler_matches_scipy(name: str) -> None:
    rng = np.random.default_rng(7)
    plant = PLANTS[name]
    rotations = _random_rotations(rng, 20)
    states = np.array([_state(name, rot, rng) for rot in rotations])
    expected = np.array([_scipy_euler(rot) for rot in rotations])
    for x, want in zip(states, expected, strict=True):
        got = plant.attitude_euler(x)
        assert got.shape == (3,)
        np.testing.assert_allclose(got, want, atol=1e-10)
    rows = plant.attitude_euler(states)  # a trajectory, one state per row
    assert rows.shape == (20, 3)
    np.testing.assert_allclose(rows, expected, atol=1e-10)
    assert plant.attitude_euler(states[:1]).shape == (1, 3)


def test_mrp_angles_are_relative_to_the_orbital_frame_and_ignore_the_shadow_set() -> None:
    rng = np.random.default_rng(3)
    for rot in _random_rotations(rng, 10):
        sigma = rot.as_mrp()
        x = MRP.state_at_rest(sigma)
        # C(sigma) maps orbital-frame components to body components: its transpose is scipy's matrix
        from models.mrp import mrp_shadow, mrp_to_dcm

        np.testing.assert_allclose(mrp_to_dcm(sigma).T, rot.as_matrix(), atol=1e-12)
        shadow = np.concatenate((mrp_shadow(sigma), x[3:]))
        np.testing.assert_allclose(MRP.attitude_euler(shadow), MRP.attitude_euler(x), atol=1e-12)
    # not the first three states read as angles (the bug of a report that took x[:3] in degrees)
    x = np.array([0.3, -0.2, 0.25, 0.0, 0.0, 0.0])
    assert np.abs(MRP.attitude_euler(x) - x[:3]).max() > 0.5


def test_flexible_angles_do_not_depend_on_the_quaternion_sign_or_scale() -> None:
    q = Rotation.from_euler("ZYX", [0.4, -0.3, 0.2]).as_quat()
    x = FLEX.state(np.r_[q[3], q[:3]])
    np.testing.assert_allclose(FLEX.attitude_euler(x), [0.2, -0.3, 0.4], atol=1e-12)
    flipped = x.copy()
    flipped[:4] *= -1.0000001
    np.testing.assert_allclose(FLEX.attitude_euler(flipped), [0.2, -0.3, 0.4], atol=1e-12)


def test_attitude_euler_checks_its_argument() -> None:
    with pytest.raises(InvalidArgumentError, match="x"):
        RIGID.attitude_euler(np.zeros(5))
    with pytest.raises(InvalidArgumentError, match="x"):
        WHEEL.attitude_euler(np.zeros((2, 6)))
    with pytest.raises(InvalidArgumentError, match="x"):
        MRP.attitude_euler(np.zeros((2, 2, 6)))
    with pytest.raises(InvalidArgumentError, match="x"):
        FLEX.attitude_euler(np.full(FLEX.n_states, np.nan))


# -- PolytopicModel.attitude ------------------------------------------------------------------
def test_polytopic_model_reads_its_attitude() -> None:
    a, b = np.eye(6), np.zeros((6, 3))
    rng = np.random.default_rng(5)
    euler = PolytopicModel([(a, b)], 0.1, attitude="euler321")
    x = rng.normal(size=(4, 6))
    np.testing.assert_array_equal(euler.attitude_euler(x), x[:, :3])
    quat = PolytopicModel([(a, b)], 0.1, attitude="quaternion_vector")
    for rot in _random_rotations(rng, 10):
        q = rot.as_quat()
        qv = q[:3] if q[3] >= 0.0 else -q[:3]  # the vector part with a non-negative scalar part
        np.testing.assert_allclose(quat.attitude_euler(np.r_[qv, np.zeros(3)]), _scipy_euler(rot), atol=1e-10)
    with pytest.raises(InvalidArgumentError, match="x"):
        quat.attitude_euler(np.r_[0.8, 0.8, 0.0, np.zeros(3)])
    plain = PolytopicModel([(a, b)], 0.1)
    assert plain.attitude is None
    with pytest.raises(InvalidArgumentError, match=r"^attitude: "):
        plain.attitude_euler(np.zeros(6))
    with pytest.raises(InvalidArgumentError, match="attitude"):
        PolytopicModel([(a, b)], 0.1, attitude="mrp")
    with pytest.raises(InvalidArgumentError, match="attitude"):
        PolytopicModel([(np.eye(2), np.zeros((2, 1)))], 0.1, attitude="euler321")


def test_from_statespace_keeps_the_attitude() -> None:
    poly = RIGID.polytope(dt=0.01, spread=0.3)
    back = PolytopicModel.from_statespace(poly.to_statespace_list(), attitude=poly.attitude)
    assert back.attitude == "euler321"
    assert PolytopicModel.from_statespace(control.ss(*poly.vertex(0), np.eye(6), 0, 0.01)).attitude is None


def test_every_satellite_builder_sets_the_attitude() -> None:
    assert RIGID.linear_model(dt=0.01).attitude == "euler321"
    assert RIGID.polytope(dt=0.01, spread=0.3).attitude == "euler321"
    assert RIGID.polytope(dt=0.01, spread=0.3, attitude_range=[0.1, 0.1, 0.0]).attitude == "euler321"
    assert WHEEL.polytope(dt=0.04).attitude == "euler321"
    assert WHEEL.linear_model(dt=0.04).attitude == "euler321"
    assert FLEX.polytope(dt=0.5).attitude == "euler321"
    assert FLEX.polytope(dt=0.5, attitude="quaternion").attitude == "quaternion_vector"
    assert FLEX.linear_model(dt=0.5, attitude="quaternion").attitude == "quaternion_vector"
    # the quaternion linear model reads back the plant's attitude about the identity
    q = Rotation.from_euler("ZYX", [0.1, 0.2, -0.3]).as_quat()
    x = FLEX.state(np.r_[q[3], q[:3]])
    model = FLEX.linear_model(dt=0.5, attitude="quaternion")
    np.testing.assert_allclose(model.attitude_euler(FLEX.linear_state(x)), FLEX.attitude_euler(x), atol=1e-12)


# -- one signature for the linearisation family -----------------------------------------------
def test_x_op_first_dt_next_in_every_family() -> None:
    for sat, n in ((RIGID, 6), (WHEEL, 6), (FLEX, FLEX.n_linear_states)):
        a0, b0 = sat.linearize()
        a1, b1 = sat.linearize(np.zeros(n))
        np.testing.assert_array_equal(a0, a1)
        np.testing.assert_array_equal(b0, b1)
        ad, _ = sat.discretize(None, 0.05)
        np.testing.assert_array_equal(ad, sat.discretize(dt=0.05)[0])
        np.testing.assert_array_equal(sat.linear_model(dt=0.05).A[0], ad)
        with pytest.raises(ArgumentTypeError, match=r"^dt: .*dt is required"):
            sat.discretize()
        with pytest.raises(ArgumentTypeError, match=r"^dt: "):
            sat.linear_model(np.zeros(n))
        with pytest.raises(InvalidArgumentError, match=r"^x_op: .*dt=\.\.\..*0\.05"):
            sat.discretize(0.05)  # the old argument order of the wheel and flexible families
    with pytest.raises(ArgumentTypeError, match=r"^dt: "):
        RIGID.polytope(spread=0.3)
    with pytest.raises(ArgumentTypeError, match=r"^spread: .*required"):
        RIGID.polytope(dt=0.01)
    with pytest.raises(ArgumentTypeError, match=r"^dt: "):
        WHEEL.polytope()
    with pytest.raises(ArgumentTypeError, match=r"^dt: "):
        FLEX.polytope()
    with pytest.raises(InvalidArgumentError, match=r"^x_op: "):
        FLEX.polytope(0.5)


def test_default_operating_points() -> None:
    np.testing.assert_array_equal(RIGID.linearize()[0][:3, 3:], np.eye(3))  # zero attitude: K = I
    yawed = np.array([0.0, 0.0, 1.2, 0.0, 0.0, 0.0])  # yaw enters neither K nor gravity
    np.testing.assert_array_equal(WHEEL.linearize(yawed)[0], WHEEL.linearize()[0])
    for bad in ([0.1, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 0.01, 0.0]):
        with pytest.raises(InvalidArgumentError, match=r"^x_op: .*level attitude at rest"):
            WHEEL.polytope(bad, dt=0.04)
    with pytest.raises(InvalidArgumentError, match=r"^x_op: "):
        FLEX.linearize(np.r_[0.1, 0.0, 0.0, 0.1, np.zeros(FLEX.n_linear_states - 4)])


def test_spread_is_the_relative_half_width_in_both_inertia_polytopes() -> None:
    rigid = RIGID.polytope(dt=0.04, spread=0.2, mode="scalar")
    np.testing.assert_allclose(rigid.B[0], RigidSatellite(1.2 * RIGID.inertia).discretize(dt=0.04)[1])
    wheel = WHEEL.polytope(dt=0.04, spread=0.2)
    heavy = WHEEL.replace(inertia=1.2 * WHEEL.inertia).discretize(dt=0.04)
    np.testing.assert_allclose(wheel.B[0], heavy[1], atol=1e-15)
    np.testing.assert_allclose(wheel.B[0], WHEEL.discretize(dt=0.04, inertia_scale=1.2)[1], atol=1e-15)
    for sat in (RIGID, WHEEL):
        with pytest.raises(InvalidArgumentError, match=r"^spread: .*\[0, 1\)"):
            sat.polytope(dt=0.04, spread=1.0)


def test_old_argument_names_give_a_clear_error() -> None:
    renamed_spread = r"^inertia_spread: expected the argument 'spread' \(renamed\)"
    with pytest.raises(ArgumentTypeError, match=renamed_spread):
        WHEEL.polytope(dt=0.04, inertia_spread=0.2)
    renamed = {
        "inertia_scale": "inverse_inertia_range",
        "frequency_scale": "frequency_range",
        "damping_scale": "damping_range",
        "effectiveness": "effectiveness_range",
    }
    for old, new in renamed.items():
        with pytest.raises(ArgumentTypeError, match=f"^{old}: expected the argument '{new}'"):
            FLEX.polytope(dt=0.5, **{old: (0.9, 1.1)})
    narrow = FLEX.polytope(dt=0.5, mode="effectiveness", effectiveness_range=(0.9, 1.1))
    np.testing.assert_allclose(narrow.B[1][:, :3], 1.1 * FLEX.discretize(dt=0.5)[1][:, :3], rtol=1e-12)


def test_one_skew_and_one_cross_product() -> None:
    rng = np.random.default_rng(2)
    for _ in range(10):
        a, b = rng.normal(size=3), rng.normal(size=3)
        np.testing.assert_allclose(cross3(a, b), np.cross(a, b), atol=1e-15)
        np.testing.assert_allclose(skew(a) @ b, np.cross(a, b), atol=1e-15)
        np.testing.assert_array_equal(skew(a), -skew(a).T)
