"""The torque limiter's two kinds and its saturation test, against values worked out by hand; the
reaction-wheel actuator's admissible parameters and the bounds on axis and wheel counts.

``kind="box"`` clips each axis (paper P's limiter); ``kind="norm"`` scales the whole vector down
to ``||u||_2 = u_max`` and keeps its direction. The expected vectors below are computed by hand
(``[3, 4, 0]`` has norm 5, so it scales to ``[0.6, 0.8, 0]``); equality is asserted to 1e-15,
the rounding of one division and one product.
"""

from __future__ import annotations

import numpy as np
import pytest

from models import (
    FaultSchedule,
    ReactionWheelActuator,
    TorqueLimiter,
    WheelArray,
    WheelDisturbance,
    WheelInputStage,
)
from models.actuators import MAX_AXES
from models.wheels.array import MAX_WHEELS
from toolkit_common.errors import InvalidArgumentError


@pytest.mark.parametrize(
    ("u", "expected"),
    [
        ([3.0, 4.0, 0.0], [0.6, 0.8, 0.0]),  # norm 5 -> scaled by 1/5
        ([0.0, -2.0, 0.0], [0.0, -1.0, 0.0]),
        ([2.0, -0.5, -3.0], np.array([2.0, -0.5, -3.0]) / np.sqrt(13.25)),  # 4 + 0.25 + 9
        ([0.3, -0.4, 0.0], [0.3, -0.4, 0.0]),  # norm 0.5: inside, unchanged
        ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
    ],
)
def test_norm_limiter_scales_the_vector_to_the_bound(u, expected):
    np.testing.assert_allclose(TorqueLimiter(1.0, kind="norm")(u), expected, rtol=0, atol=1e-15)


def test_norm_and_box_limiters_differ_on_the_same_vector():
    """Box keeps [1, -0.5, -1] (each axis clipped); norm keeps the direction of [2, -0.5, -3]."""
    u = [2.0, -0.5, -3.0]
    np.testing.assert_array_equal(TorqueLimiter(1.0)(u), [1.0, -0.5, -1.0])
    scaled = TorqueLimiter(2.5, kind="norm")(u)
    assert np.linalg.norm(scaled) == pytest.approx(2.5, rel=1e-15)
    np.testing.assert_allclose(scaled / np.linalg.norm(scaled), np.array(u) / np.sqrt(13.25), atol=1e-15)


def test_norm_limiter_needs_a_scalar_bound():
    with pytest.raises(InvalidArgumentError, match="u_max"):
        TorqueLimiter([1.0, 2.0, 3.0], kind="norm")


@pytest.mark.parametrize(
    ("kind", "u_max", "u", "saturated"),
    [
        ("box", 1.0, [1.0, 0.0, 0.0], True),  # on the limit
        ("box", 1.0, [0.0, -1.2, 0.0], True),  # beyond it, negative side
        ("box", 1.0, [0.999, 0.5, -0.999], False),
        ("box", 1.0, [0.8, 0.8, 0.0], False),  # norm 1.13 but every axis inside
        ("box", 1.0, [1.0 - 1e-10, 0.0, 0.0], True),  # within the default tol 1e-9 of the limit
        ("box", 1.0, [1.0 - 1e-8, 0.0, 0.0], False),  # beyond that tol
        ("box", [1.0, 2.0, 3.0], [0.5, 1.9, 2.9], False),  # per-axis limits
        ("box", [1.0, 2.0, 3.0], [0.5, 2.0, 0.0], True),
        ("box", [1.0, 2.0, 3.0], [0.0, 0.0, -3.5], True),
        ("box", [1.0, 2.0, 3.0], [1.5, 0.0, 0.0], True),
        ("norm", 1.0, [0.8, 0.8, 0.0], True),  # norm 1.13
        ("norm", 1.0, [0.6, 0.8, 0.0], True),  # norm 1: on the limit
        ("norm", 1.0, [0.3, 0.4, 0.0], False),  # norm 0.5
        ("norm", 1.0, [0.99, 0.0, 0.0], False),
        ("norm", 2.0, [1.0, 1.0, 1.0], False),  # norm 1.73 < 2
        ("norm", 2.0, [1.2, 1.2, 1.2], True),  # norm 2.08 > 2
    ],
)
def test_is_saturated(kind, u_max, u, saturated):
    assert TorqueLimiter(u_max, kind=kind).is_saturated(u) is saturated


def test_is_saturated_uses_its_tolerance():
    lim = TorqueLimiter(1.0)
    assert not lim.is_saturated([0.99, 0.0, 0.0])
    assert lim.is_saturated([0.99, 0.0, 0.0], tol=0.02)  # 0.99 >= 1 * (1 - 0.02)
    assert not TorqueLimiter(1.0, kind="norm").is_saturated([0.6, 0.7, 0.0], tol=0.05)  # 0.922 < 0.95
    assert TorqueLimiter(1.0, kind="norm").is_saturated([0.6, 0.7, 0.0], tol=0.1)  # 0.922 >= 0.9


@pytest.mark.parametrize("kind", ["box", "norm"])
def test_clipped_output_is_saturated_exactly_when_the_input_exceeded_the_bound(kind):
    lim = TorqueLimiter(1.0, kind=kind)
    rng = np.random.default_rng(4)
    exceeded = 0
    for u in rng.normal(scale=0.8, size=(200, 3)):
        over = np.max(np.abs(u)) > 1.0 if kind == "box" else np.linalg.norm(u) > 1.0
        exceeded += over
        clipped = lim(u)
        if over:
            assert lim.is_saturated(clipped) and lim.is_saturated(u)
        else:
            np.testing.assert_array_equal(clipped, u)
    assert 20 <= exceeded <= 180  # both branches exercised (measured: 101 box, 134 norm of 200)


# --- paper P's reaction-wheel actuator: what is admissible --------------------------------------


def test_a_pole_at_zero_is_a_one_sample_delay_with_gain_c_b():
    """``a = 0`` (a lag much shorter than the sample) is admitted: the torque is ``c b u`` one sample late."""
    act = ReactionWheelActuator(n_axes=2, a=0.0, b=0.5, c=4.0)
    assert act.dc_gain == 2.0
    np.testing.assert_array_equal(act.step([1.0, -3.0]), [0.0, 0.0])
    np.testing.assert_array_equal(act.step([0.0, 0.0]), [2.0, -6.0])
    np.testing.assert_array_equal(act.step([0.0, 0.0]), [0.0, 0.0])


def test_max_axes_lifts_the_bound_on_n_axes():
    with pytest.raises(InvalidArgumentError, match="max_axes = 1000") as info:
        ReactionWheelActuator(n_axes=MAX_AXES + 1)
    assert info.value.argument == "n_axes" and "lift" in info.value.expected
    act = ReactionWheelActuator(n_axes=MAX_AXES + 1, max_axes=MAX_AXES + 1)
    assert act.n_axes == MAX_AXES + 1 and act.step(np.ones(MAX_AXES + 1)).shape == (MAX_AXES + 1,)


def test_max_wheels_lifts_the_bound_and_an_existing_array_is_never_refused():
    with pytest.raises(InvalidArgumentError, match="max_wheels = 1000"):
        WheelDisturbance(MAX_WHEELS + 1)
    more = MAX_WHEELS + 1
    assert WheelDisturbance(more, max_wheels=more).draw().shape == (more,)
    assert FaultSchedule([], more, max_wheels=more).effectiveness(0.0).shape == (more,)
    # an array of more wheels than the bound: its count is the array's, never refused
    axes = np.zeros((3, more))
    axes[np.arange(more) % 3, np.arange(more)] = 1.0
    wheels = WheelArray(axes)
    assert FaultSchedule([], wheels, max_wheels=4).n_wheels == more
    assert WheelInputStage(wheels).faults.n_wheels == more
