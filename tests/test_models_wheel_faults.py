"""Wheel faults, the redundancy checker, the wheel input stage, seeded noise and paper W's scenarios.

Expected values come from paper W's fault models and scenario table and from the seed's
derived checks (``seeds/paper-W-wheel-faults.md`` sections 3, 5, 6.3 and 6.8).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from models import (
    AttitudeNoiseSensor,
    FaultSchedule,
    WheelArray,
    WheelDisturbance,
    WheelFault,
    WheelInputStage,
    WheelSatellite,
    paper_w_scenario,
    rank_deficient_windows,
)
from models.protocols import InputStage
from rmpc import StepInfo, simulate
from rmpc.sim.plants import SampledPlant
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

WHEELS = WheelArray.paper_w()


def test_each_kind_in_the_per_wheel_form() -> None:  # seed 3.1-3.2
    nu = 0.07
    cases = {
        WheelFault(2, "stuck", 8.0, 37.0, value=0.05): lambda t: 0.05,
        WheelFault(1, "sinusoidal", 30.0, 80.0, value=0.03): lambda t: 0.03 * math.sin(0.2 * t),
        WheelFault(4, "outage", 0.0): lambda t: 0.0,
        WheelFault(3, "effectiveness", 5.0, 9.0, effectiveness=0.25): lambda t: 0.25 * nu,
        WheelFault(3, "bias", 5.0, 9.0, value=-0.01): lambda t: nu - 0.01,
    }
    for fault, inside in cases.items():
        for t in np.linspace(fault.t_on, min(fault.t_off, 100.0), 7)[:-1]:
            assert fault.torque(t, nu) == pytest.approx(inside(t), abs=1e-15), (fault, t)
        if fault.t_on > 0.0:
            assert fault.torque(fault.t_on - 1e-9, nu) == nu
        if math.isfinite(fault.t_off):
            assert fault.torque(fault.t_off, nu) == nu  # the window is [t_on, t_off): healthy again
    assert WheelFault(1, "sinusoidal", 0.0, value=1.0, frequency=2.0, phase=0.5).torque(1.0, 0.0) == math.sin(
        2.5
    )
    assert [f.disobeys for f in cases] == [True, True, True, False, False]


def test_exponential_onset() -> None:  # seed 3.2, Remark 2
    fault = WheelFault(1, "effectiveness", 10.0, effectiveness=0.4, onset="exponential", onset_rate=0.5)
    for t in (10.0, 11.0, 14.0, 30.0):
        mu = 1.0 - math.exp(-0.5 * (t - 10.0))
        assert fault.onset_profile(t) == pytest.approx(mu, abs=1e-15)
        assert fault.effectiveness_at(t) == pytest.approx(1.0 - 0.6 * mu, abs=1e-15)
    stuck = WheelFault(2, "stuck", 1.0, value=0.05, onset="exponential")  # rho = 1 1/s by default
    assert stuck.torque(2.0, 0.1) == pytest.approx(
        math.exp(-1.0) * 0.1 + (1 - math.exp(-1.0)) * 0.05, abs=1e-15
    )
    assert stuck.torque(0.5, 0.1) == 0.1


def test_schedule_combines_the_wheels() -> None:
    schedule = paper_w_scenario("S3").schedule()
    t = 95.0  # wheel 4 out, wheel 2 stuck at 0.03
    np.testing.assert_array_equal(schedule.effectiveness(t), [1.0, 0.0, 1.0, 0.0])
    np.testing.assert_array_equal(schedule.additive(t), [0.0, 0.03, 0.0, 0.0])
    np.testing.assert_array_equal(schedule.apply(t, [0.1, 0.2, 0.3, 0.4]), [0.1, 0.03, 0.3, 0.0])
    np.testing.assert_array_equal(schedule.active(t), [False, True, False, True])
    assert schedule.events() == [0.0, 30.0, 80.0, 90.0, 120.0]


def test_redundancy_checker_flags_exactly_s3_and_s4() -> None:  # seed 6.3
    windows = {
        name: paper_w_scenario(name).schedule().rank_deficient_windows(WHEELS)
        for name in ("S1", "S2", "S3", "S4")
    }
    assert windows["S1"] == [] and windows["S2"] == []
    assert [(w.t_start, w.t_end, w.rank) for w in windows["S3"]] == [(30.0, 80.0, 2), (90.0, 120.0, 2)]
    assert [(w.t_start, w.t_end, w.rank) for w in windows["S4"]] == [(30.0, 60.0, 2), (70.0, 100.0, 2)]
    assert [w.wheels for w in windows["S3"]] == [(1, 4), (2, 4)]
    # a partial loss of effectiveness keeps rank 3; a total one does not; adjacent windows merge
    partial = [
        WheelFault(1, "effectiveness", 0.0, 10.0, effectiveness=0.5),
        WheelFault(2, "outage", 0.0, 10.0),
    ]
    assert rank_deficient_windows(partial, WHEELS) == []
    total = [
        WheelFault(1, "effectiveness", 0.0, 10.0, effectiveness=0.0),
        WheelFault(2, "outage", 0.0, 10.0),
        WheelFault(1, "outage", 10.0, 20.0),
        WheelFault(3, "stuck", 10.0, 20.0, value=0.01),
    ]
    merged = rank_deficient_windows(total, WHEELS.D, duration=15.0)
    assert [(w.t_start, w.t_end, w.rank, w.wheels) for w in merged] == [(0.0, 15.0, 2, (1, 2, 3))]


class ZeroCommand:
    last = None

    def reset(self) -> None:
        pass

    def step(self, x: np.ndarray) -> np.ndarray:
        self.last = StepInfo(status="ok")
        return np.zeros(4)


def test_stuck_wheel_reaches_its_momentum_limit_and_is_flagged() -> None:  # seed 6.8
    sat = WheelSatellite.paper_w()
    stage = WheelInputStage(sat.wheels, [WheelFault(2, "stuck", 0.0, value=0.05)])
    assert isinstance(stage, InputStage)
    plant = SampledPlant(sat, 0.04, integrator="RK4", substep=0.005, input_stage=stage)
    run = simulate(ZeroCommand(), plant, np.zeros(10), duration=14.0)
    h2 = run.x[:, 7]
    # h' = -0.05 N m from h = 0: the limit 0.625 N m s is reached at 12.5 s
    before = run.t <= 12.5 + 1e-9
    np.testing.assert_allclose(h2[before], -0.05 * run.t[before], atol=1e-12)
    assert np.all(np.abs(h2) <= 0.625 + 0.05 * 0.005 + 1e-12)  # overshoot below one RK4 substep
    np.testing.assert_allclose(h2[-1], -0.625, atol=0.05 * 0.005)
    limited = run.stage_log["momentum_limited"][:, 1]
    first = float(run.t[np.argmax(limited)])
    assert 12.5 <= first <= 12.5 + 0.04 + 1e-9
    assert np.all(limited[run.t[:-1] > first]) and not np.any(limited[run.t[:-1] < 12.5])
    np.testing.assert_array_equal(run.stage_log["fault_altered"][:, 1], limited)
    np.testing.assert_allclose(run.stage_log["u_fault"][:, 1], 0.05)
    np.testing.assert_allclose(run.u_applied[limited, 1], 0.0)
    assert not np.any(run.stage_log["torque_clipped"])
    # at 0.03 N m it would take 20.8 s
    assert 0.625 / 0.03 == pytest.approx(20.83, abs=0.01)


def test_limits_apply_after_the_faults() -> None:
    stage = WheelInputStage(WHEELS, [WheelFault(1, "bias", 0.0, value=0.1)])
    x = np.zeros(10)
    np.testing.assert_allclose(stage(0.0, x, np.array([0.05, 0.2, -0.2, 0.0])), [0.123, 0.123, -0.123, 0.0])
    log = stage.begin_sample(0.0, x, np.array([0.05, 0.2, -0.2, 0.0]))
    np.testing.assert_array_equal(log["torque_clipped"], [True, True, True, False])
    np.testing.assert_array_equal(log["fault_altered"], [True, False, False, False])
    x[6:] = [0.625, -0.7, 0.3, -0.625]
    # at the limit a wheel gives no torque outward (u h < 0) and any torque inward
    np.testing.assert_allclose(stage(0.0, x, np.array([-0.2, -0.1, -0.1, 0.1])), [0.0, -0.1, -0.1, 0.0])
    np.testing.assert_allclose(stage(0.0, x, np.array([0.01, 0.1, 0.0, -0.1])), [0.11, 0.0, 0.0, -0.1])
    free = WheelInputStage(
        WHEELS, [WheelFault(1, "bias", 0.0, value=0.1)], torque_limit=False, momentum_limit=False
    )
    np.testing.assert_allclose(free(0.0, x, np.array([0.5, 0.2, 0.0, 0.1])), [0.6, 0.2, 0.0, 0.1])


def test_wheel_disturbance_is_seeded_and_held_per_sample() -> None:  # seed 5, S4
    stage = WheelInputStage(WHEELS, wheel_disturbance=WheelDisturbance(4, seed=7))
    x = np.zeros(10)
    draws = []
    for _ in range(2):
        stage.reset()
        run = [stage.begin_sample(0.04 * k, x, np.zeros(4))["wheel_disturbance"] for k in range(3000)]
        draws.append(np.array(run))
    np.testing.assert_array_equal(draws[0], draws[1])
    t = 0.04 * np.arange(3000)
    noise = draws[0] - (0.001 + 0.05 * np.sin(2 * np.pi * t / 800.0))[:, None]
    assert np.all(np.abs(np.diff(noise, axis=0)) > 0)  # redrawn every sample
    np.testing.assert_allclose(noise.var(axis=0), 0.0052, rtol=0.1)
    np.testing.assert_allclose(noise.mean(axis=0), 0.0, atol=4 * math.sqrt(0.0052 / 3000))
    # held within a sample: the stage is a pure function of (t, x, u) between begin_sample calls
    u1 = stage(1.00, x, np.zeros(4))
    np.testing.assert_array_equal(stage(1.00, x, np.zeros(4)), u1)
    other = WheelDisturbance(4, seed=8)
    other.reset()
    assert not np.array_equal(other.draw(), WheelDisturbance(4, seed=7).draw())


def test_angle_noise_sensor() -> None:  # seed 2.5
    sensor = AttitudeNoiseSensor(seed=11)
    x = np.arange(10.0)
    ys = []
    for _ in range(2):
        sensor.reset()
        ys.append(np.array([sensor(0.04 * k, x) for k in range(4000)]))
    np.testing.assert_array_equal(ys[0], ys[1])
    np.testing.assert_array_equal(ys[0][:, 3:], np.tile(x[3:], (4000, 1)))
    np.testing.assert_allclose((ys[0][:, :3] - x[:3]).std(axis=0), math.radians(0.2), rtol=0.05)


def test_scenarios_against_the_seed_table() -> None:  # seed section 5
    s1, s2, s3, s4 = (paper_w_scenario(n) for n in ("S1", "S2", "S3", "S4"))
    assert [s.attitude_deg for s in (s1, s2, s3, s4)] == [
        (40.0, -21.0, -80.0),
        (23.0, 24.0, 73.0),
        (23.0, 23.0, 67.0),
        (-20.0, 26.0, 79.0),
    ]
    assert [s.duration for s in (s1, s2, s3, s4)] == [60.0, 150.0, 150.0, 150.0]

    def table(s):
        return [
            (f.wheel, f.kind, f.t_on, f.t_off, f.value, f.frequency if f.kind == "sinusoidal" else None)
            for f in s.faults
        ]

    inf = math.inf
    assert table(s1) == [(2, "stuck", 8.0, 37.0, 0.05, None)]
    assert table(s2) == [(1, "sinusoidal", 30.0, 80.0, 0.03, 0.2), (4, "stuck", 90.0, 120.0, 0.03, None)]
    assert table(s3) == [
        (4, "outage", 0.0, inf, 0.0, None),
        (1, "sinusoidal", 30.0, 80.0, 0.03, 0.2),
        (2, "stuck", 90.0, 120.0, 0.03, None),
    ]
    assert table(s4) == [
        (4, "outage", 0.0, inf, 0.0, None),
        (1, "stuck", 30.0, 60.0, 0.03, None),
        (2, "sinusoidal", 70.0, 100.0, 0.03, 0.2),
    ]
    assert table(paper_w_scenario("S1", stuck_torque=0.03))[0][4] == 0.03
    assert s4.inertia_scales == (1.2, 0.8) and s1.inertia_scales == (1.0,)
    assert s4.wheel_disturbance and s4.disturbance(seed=3).seed == 3 and s1.disturbance() is None
    assert paper_w_scenario("S4", disturbance_variance=2.5e-5).disturbance().variance == 2.5e-5
    assert s2.paper_basis == ((0.2,), (), (), ()) and s4.paper_basis is None
    np.testing.assert_allclose(s1.initial_state(), np.r_[np.radians([40.0, -21.0, -80.0]), np.zeros(7)])


def test_bad_faults_name_the_argument() -> None:
    with pytest.raises(
        InvalidArgumentError, match=r"faults\[1\]\.wheel: expected a wheel that exists \(1 \.\. 4\)"
    ):
        FaultSchedule([WheelFault(1, "outage", 0.0), WheelFault(5, "outage", 0.0)], WHEELS)
    with pytest.raises(InvalidArgumentError, match=r"wheel: expected a wheel number >= 1"):
        WheelFault(0, "outage", 0.0)
    with pytest.raises(ArgumentTypeError, match="wheel"):
        WheelFault(1.0, "outage", 0.0)
    with pytest.raises(InvalidArgumentError, match=r"faults\[0\]\.t_on: expected an onset before the end"):
        FaultSchedule([WheelFault(2, "stuck", 70.0, value=0.05)], WHEELS, duration=60.0)
    with pytest.raises(InvalidArgumentError, match=r"effectiveness: expected a value in \[0, 1\]"):
        WheelFault(1, "effectiveness", 0.0, effectiveness=1.2)
    with pytest.raises(InvalidArgumentError, match="effectiveness"):
        WheelFault(1, "effectiveness", 0.0, effectiveness=-0.1)
    with pytest.raises(InvalidArgumentError, match="t_off"):
        WheelFault(1, "outage", 5.0, 5.0)
    with pytest.raises(InvalidArgumentError, match="t_on"):
        WheelFault(1, "outage", -1.0)
    with pytest.raises(InvalidArgumentError, match="value"):
        WheelFault(1, "stuck", 0.0)
    with pytest.raises(InvalidArgumentError, match="value"):
        WheelFault(1, "outage", 0.0, value=0.1)
    with pytest.raises(InvalidArgumentError, match="frequency"):
        WheelFault(1, "stuck", 0.0, value=0.1, frequency=0.3)
    with pytest.raises(InvalidArgumentError, match="kind"):
        WheelFault(1, "jammed", 0.0)
    with pytest.raises(InvalidArgumentError, match=r"faults\[1\]: expected no overlap"):
        FaultSchedule([WheelFault(1, "outage", 0.0, 10.0), WheelFault(1, "stuck", 5.0, value=0.1)], 4)
    with pytest.raises(InvalidArgumentError, match="wheel_disturbance"):
        WheelInputStage(WHEELS, wheel_disturbance=WheelDisturbance(3))
    with pytest.raises(ArgumentTypeError, match="seed"):
        AttitudeNoiseSensor(seed=-1)
    with pytest.raises(InvalidArgumentError, match="name"):
        paper_w_scenario("S5")
    with pytest.raises(InvalidArgumentError, match="stuck_torque"):
        paper_w_scenario("S2", stuck_torque=0.03)
