"""Paper W's run metrics and scenario plants (benchmarks.families.wheel.metrics and .plant).

The metric tests use hand-made trajectories whose answers follow from their definitions
(seed 6.10: recovery runs from the event until max |eta_i| stays <= 2 deg); one short S1 run
checks that commanded and applied torque, the clip log and the metrics agree.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.families.wheel.metrics import (
    attitude_error,
    fault_metrics,
    max_abs_momentum,
    momentum_limit_events,
    peak_abs_error,
    recovery_times,
    saturated_fraction,
)
from benchmarks.families.wheel.plant import scenario_plant, wheel_plant
from models import FaultSchedule, WheelFault, WheelSatellite, paper_w_scenario
from rmpc import AdaptiveBacksteppingFTC, Trajectory, simulate
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError


def _trajectory(roll_deg: np.ndarray, dt: float = 0.5, stage_log: dict | None = None) -> Trajectory:
    n = roll_deg.size - 1
    x = np.zeros((n + 1, 10))
    x[:, 0] = np.radians(roll_deg)
    x[:, 2] = np.radians(359.5)  # yaw error -0.5 deg once wrapped
    x[:, 6] = np.linspace(0.0, -0.7, n + 1)
    u = np.zeros((n, 4))
    return Trajectory(
        t=np.arange(n + 1) * dt,
        x=x,
        u_cmd=u,
        u_applied=u,
        d=np.zeros((n, 3)),
        status=["ok"] * n,
        solve_time=np.zeros(n),
        step_time=np.zeros(n),
        gamma=np.full(n, np.nan),
        info=[None] * n,
        plant="nonlinear",
        dt=dt,
        stage_log=stage_log or {},
    )


def test_recovery_time_per_event() -> None:
    # t = 0, 0.5, .., 10 s; roll 5 deg, a blip above 2 deg at t = 6 s, 1 deg after it, 3 deg at the end
    roll = np.full(21, 1.0)
    roll[:5] = 5.0
    roll[12] = 2.5
    roll[20] = 3.0
    traj = _trajectory(roll)
    faults = FaultSchedule([WheelFault(2, "stuck", 2.0, 8.0, value=0.05)], 4)
    onset, end = recovery_times(traj, faults)
    assert (onset["event"], onset["t_event"], onset["horizon"]) == ("onset", 2.0, 8.0)
    assert onset["recovery_time"] == pytest.approx(6.5 - 2.0)  # below 2 deg from t = 6.5 s to the horizon
    assert (end["event"], end["t_event"], end["horizon"]) == ("end", 8.0, 10.0)
    assert end["recovery_time"] is None  # above the threshold at the end of the run
    outage = FaultSchedule([WheelFault(1, "outage", 3.0)], 4)  # no end: the horizon is the run's end
    assert recovery_times(traj, outage)[0]["recovery_time"] is None
    roll[20] = 1.0
    assert recovery_times(_trajectory(roll), outage)[0]["recovery_time"] == pytest.approx(6.5 - 3.0)
    assert recovery_times(traj, faults, threshold=math.radians(4.0))[1]["recovery_time"] == 0.0
    np.testing.assert_allclose(np.degrees(attitude_error(traj)[0]), [5.0, 0.0, 0.5], atol=1e-12)


def test_peak_error_saturation_and_momentum_metrics() -> None:
    roll = np.linspace(0.0, 10.0, 21)
    clipped = np.zeros((20, 4), dtype=bool)
    clipped[[1, 2, 5], 0] = True
    clipped[5, 3] = True
    held = np.zeros((20, 4), dtype=bool)
    held[3:6, 0] = True
    held[9:12, 0] = True
    held[4:20, 2] = True
    log = {"torque_clipped": clipped, "momentum_limited": held, "fault_altered": held & False}
    traj = _trajectory(roll, stage_log=log)
    (window,) = peak_abs_error(traj, [(2.0, 4.0)])
    assert window["peak"]["roll"] == pytest.approx(math.radians(3.5))  # t = 3.5 s, the window is half-open
    assert window["peak"]["yaw"] == pytest.approx(math.radians(0.5))
    assert peak_abs_error(traj, [(20.0, 30.0)])[0]["peak"]["roll"] is None
    sat = saturated_fraction(traj)
    assert sat["any"] == pytest.approx(3 / 20) and sat["per_wheel"] == pytest.approx([3 / 20, 0, 0, 1 / 20])
    events = momentum_limit_events(traj)
    assert events["count"] == 3 and events["samples"] == 17  # samples 3 .. 19
    assert events["events"] == [{"t": 1.5, "wheel": 1}, {"t": 2.0, "wheel": 3}, {"t": 4.5, "wheel": 1}]
    assert max_abs_momentum(traj) == pytest.approx([0.7, 0.0, 0.0, 0.0])
    with pytest.raises(InvalidArgumentError, match="torque_max"):
        saturated_fraction(_trajectory(roll))
    with pytest.raises(InvalidArgumentError, match="windows"):
        peak_abs_error(traj, [(3.0, 1.0)])
    with pytest.raises(ArgumentTypeError, match="traj"):
        attitude_error(np.zeros((3, 10)))


def test_short_s1_run_logs_commanded_and_applied_torque() -> None:
    sat = WheelSatellite.paper_w()
    scenario = paper_w_scenario("S1")
    plant = scenario_plant(scenario)
    assert plant.input_stage.faults.faults == scenario.faults
    run = simulate(AdaptiveBacksteppingFTC(sat), plant, scenario.initial_state(), duration=10.0)
    log = run.stage_log
    # the applied torque is the stage's output at the start of each sample: clip after the fault
    expected = np.clip(log["u_fault"], -0.123, 0.123)
    expected[log["momentum_limited"]] = 0.0
    np.testing.assert_allclose(run.u_applied, expected, atol=1e-15)
    healthy = ~log["fault_active"]
    np.testing.assert_array_equal(log["u_fault"][healthy], run.u_cmd[healthy])
    np.testing.assert_allclose(log["u_fault"][run.t[:-1] >= 8.0, 1], 0.05)  # wheel 2 stuck from 8 s
    metrics = fault_metrics(run, scenario.schedule(), sat.wheels)
    assert metrics["max_abs_u"] <= 0.123 and metrics["max_abs_u_cmd"] > 1.6
    assert metrics["sat_fraction"]["any"] == pytest.approx(
        np.mean(np.any(np.abs(log["u_fault"]) > 0.123, axis=1))
    )
    assert metrics["rank_deficient_windows"] == []
    assert metrics["recovery_time"][0]["t_event"] == 8.0
    assert metrics["status_counts"] == {"ok": 250}
    assert metrics["max_abs_angle_deg"]["roll"] == pytest.approx(40.0)


def test_scenario_plant_and_wheel_plant() -> None:
    s4 = paper_w_scenario("S4")
    plant = scenario_plant(s4, seed=5)
    np.testing.assert_allclose(plant.model.inertia, 1.2 * WheelSatellite.paper_w().inertia, atol=1e-15)
    assert plant.input_stage.wheel_disturbance.seed == 5
    assert (plant.integrator.name, plant.n_substeps, plant.dt) == ("RK4", 8, 0.04)
    light = scenario_plant(s4, inertia_scale=0.8)
    np.testing.assert_allclose(light.model.inertia, 0.8 * WheelSatellite.paper_w().inertia, atol=1e-15)
    free = wheel_plant(WheelSatellite.paper_w(), torque_limit=False, momentum_limit=False)
    assert not free.input_stage.torque_limit and len(free.input_stage.faults) == 0
    with pytest.raises(ArgumentTypeError, match="satellite"):
        wheel_plant(WheelSatellite.paper_w().inertia)
    with pytest.raises(InvalidArgumentError, match=r"faults\[0\]\.wheel"):
        wheel_plant(WheelSatellite.paper_w(), [WheelFault(7, "outage", 0.0)])
