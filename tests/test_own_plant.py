"""A user's own plant from python-control: names carried through, errors that point the way."""

from __future__ import annotations

import control
import numpy as np
import pytest

from models import PolytopicModel
from rmpc import RMPC
from toolkit_common.errors import ArgumentTypeError


def motor(dt: float = 0.1, gain: float = 1.0, **names: object) -> control.StateSpace:
    """A DC motor's angle and speed, ZOH at ``dt`` (python-control's ``c2d``)."""
    sys = control.ss([[0.0, 1.0], [0.0, -2.0]], [[0.0], [gain]], np.eye(2), 0.0, **names)
    return control.c2d(sys, dt)


def test_from_statespace_keeps_python_control_signal_names() -> None:
    named = PolytopicModel.from_statespace(
        [motor(states=["angle", "speed"], inputs=["voltage"]), motor(gain=1.5)]
    )
    assert named.state_names == ("angle", "speed") and named.input_names == ("voltage",)
    default = PolytopicModel.from_statespace(motor())
    assert default.state_names == ("x[0]", "x[1]") and default.input_names == ("u[0]",)


def test_rmpc_of_a_statespace_points_at_from_statespace() -> None:
    with pytest.raises(ArgumentTypeError, match=r"plant: .*from_statespace.*found StateSpace"):
        RMPC(motor(), Q=np.eye(2), R=np.eye(1))
