"""Seed 6.7: S3 and S4 leave paper W's own condition (17), and the compensator is still tested.

In S3's window [30, 80) s wheels 1 (sinusoid) and 4 (out) do not obey, and wheels 2 and 3 have
no x component: nothing the controller commands reaches roll, which swings under the fault
torque and gravity alone. The seed asks to assert only that the platform stays inside its
+-40 deg range of roll and pitch, and to report the peak per window (the run's metrics do:
measured with the defaults, S3 peaks at 14.3 deg roll in [30, 80) and 11.9 deg pitch in
[90, 120); S4 at 1.2 J, 9.9 deg roll and 15.3 deg yaw in [30, 60), 11.3 deg pitch in [70, 100)).

Without roll authority in S3's [30, 80) the 0.03 N m sinusoid at 0.2 rad/s drives the pendulous
roll axis (stiffness 0.326 N m/rad, natural frequency about 0.42 rad/s): the forced amplitude
alone is about 0.03 / 0.326 / (1 - (0.2 / 0.42)^2) rad = 6.8 deg, beyond the 2 deg recovery
band, and roll, not pitch, must carry it.

Both runs are cut at the end of their second rank-deficient window (S3 at 120 s, S4 at 100 s;
150 s each in the scenarios) to keep the test time modest (about 8 s each on a loaded
2-core machine).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.families.wheel.metrics import fault_metrics
from benchmarks.families.wheel.plant import scenario_plant
from models import WheelSatellite, paper_w_scenario, rank_deficient_windows
from rmpc import AdaptiveBacksteppingFTC, simulate

PLATFORM_RANGE = math.radians(40.0)


@pytest.mark.parametrize(("name", "duration"), [("S3", 120.0), ("S4", 100.0)])
def test_platform_stays_in_range_through_two_wheel_losses(name: str, duration: float) -> None:
    sat = WheelSatellite.paper_w()
    scenario = paper_w_scenario(name)
    run = simulate(
        AdaptiveBacksteppingFTC(sat), scenario_plant(scenario), scenario.initial_state(), duration=duration
    )
    assert run.status_counts() == {"ok": run.n_steps}
    assert np.max(np.abs(run.x[:, :2])) < PLATFORM_RANGE
    wheels = sat.wheels
    assert np.max(np.abs(run.u_applied)) <= wheels.torque_max[0]
    metrics = fault_metrics(run, scenario.schedule(), wheels)
    expected = rank_deficient_windows(scenario.schedule(), wheels, duration)
    assert len(expected) == 2
    recorded = [[w.t_start, w.t_end, w.rank, list(w.wheels)] for w in expected]
    assert metrics["rank_deficient_windows"] == recorded
    peaks = metrics["peak_abs_err"]["rank_deficient_windows"]
    assert [(p["t_start"], p["t_end"]) for p in peaks] == [(w.t_start, w.t_end) for w in expected]
    if name == "S3":
        roll_window = peaks[0]["peak"]
        assert roll_window["roll"] > math.radians(2.0)
        assert roll_window["roll"] > 3.0 * roll_window["pitch"]
