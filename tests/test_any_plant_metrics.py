"""Metrics and plots of any plant: the plant's own names, no satellite assumption."""

from __future__ import annotations

import control
import numpy as np
import pytest

from benchmarks.core.metrics import compute_metrics
from models import PolytopicModel, RigidSatellite
from rmpc import LQR, simulate
from toolkit_common.errors import InvalidArgumentError


def motor(dt: float = 0.1) -> PolytopicModel:
    sys = control.ss([[0.0, 1.0], [0.0, -2.0]], [[0.0], [1.0]], np.eye(2), 0.0,
                     states=["angle", "speed"], inputs=["voltage"])
    return PolytopicModel.from_statespace(control.c2d(sys, dt))


def test_a_two_state_plant_gets_metrics_by_its_state_names() -> None:
    """Before: ``zip() argument 2 is shorter`` (the satellite's roll, pitch, yaw on 2 states).
    The errors are the states; their sums are what the trajectory holds."""
    plant = motor()
    traj = simulate(LQR(plant, Q=np.eye(2), R=np.eye(1)), plant, [1.0, 0.0], n_steps=50)
    assert traj.state_names == ("angle", "speed") and traj.input_names == ("voltage",)
    m = compute_metrics(traj, u_max=10.0)
    assert set(m["sum_abs_err"]) == {"angle", "speed"}
    assert m["sum_abs_err"]["angle"] == pytest.approx(float(np.sum(np.abs(traj.x[:, 0]))))
    assert m["final_abs_err"]["speed"] == pytest.approx(abs(traj.x[-1, 1]))


def test_a_four_state_plant_without_attitude_is_not_called_roll_pitch_yaw() -> None:
    a = np.diag([0.9, 0.8, 0.7, 0.6])
    plant = PolytopicModel([(a, np.eye(4)[:, :1])], dt=0.1)
    traj = simulate(LQR(plant, Q=np.eye(4), R=np.eye(1)), plant, np.ones(4), n_steps=10)
    iae = compute_metrics(traj, u_max=1.0)["iae"]
    assert tuple(iae) == plant.state_names and len(iae) == 4 and "roll" not in iae


def test_the_satellite_keeps_roll_pitch_yaw() -> None:
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    plant = sat.linear_model(x0, 0.01)
    traj = simulate(LQR(plant, Q=np.eye(6), R=np.eye(3)), sat, x0, n_steps=5, dt=0.01)
    assert set(compute_metrics(traj, u_max=1.0)["sum_abs_err"]) == {"roll", "pitch", "yaw"}


def test_trajectory_plot_draws_the_named_states_inputs_bounds_and_status() -> None:
    import matplotlib

    matplotlib.use("Agg")
    plant = motor()
    traj = simulate(LQR(plant, Q=np.eye(2), R=np.eye(1)), plant, [1.0, 0.0], n_steps=30,
                    limiter=lambda u: np.clip(u, -0.3, 0.3))
    fig = traj.plot(u_max=0.3)
    states, inputs, solve, status = fig.axes[:4]
    assert [t.get_text() for t in states.get_legend().get_texts()] == ["angle", "speed"]
    labels = [t.get_text() for t in inputs.get_legend().get_texts()]
    assert labels == ["voltage applied", "voltage commanded"]  # the limiter acted
    assert sorted(line.get_ydata()[0] for line in inputs.lines if line.get_linestyle() == "--") == [-0.3, 0.3]
    assert [t.get_text() for t in status.get_yticklabels()] == sorted(set(traj.status))
    assert solve.get_yscale() == "log"
    with pytest.raises(InvalidArgumentError, match="states"):
        traj.plot(states=[5])
