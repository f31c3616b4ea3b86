"""Paper V's metrics (benchmarks.families.flexible.metrics) and the scenario data (models.flexible.scenario).

Each metric is checked on a run whose value is known in closed form: a constant command
beyond the 2 N m clip (peak, saturated fraction, effort, chattering index), the satellite at
rest (no rotation error, settled at 0), a free modal oscillation (peak |eta|, modal energy).
"""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.core.metrics import last_time_above
from benchmarks.families.flexible.metrics import flexible_metrics
from models import FlexibleSatellite
from models.attitude.quaternion import rotation_angle
from models.flexible.scenario import (
    F2_EPSILONS,
    ConstantHubTorque,
    PaperVDisturbance,
    paper_v_scenario,
    steady_error_scenario,
)
from rmpc import StepInfo, simulate
from rmpc.sim.plants import SampledPlant
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError


class _Constant:
    def __init__(self, u):
        self.u = np.asarray(u, dtype=float)
        self.last = None

    def reset(self):
        self.last = None

    def step(self, x):
        self.last = StepInfo(status="ok")
        return self.u.copy()


@pytest.fixture(scope="module")
def sat() -> FlexibleSatellite:
    return FlexibleSatellite.di_gennaro()


def _run(sat, u, x0, horizon=2.0):
    return simulate(_Constant(u), SampledPlant(sat, 0.01, integrator="RK4"), x0, horizon,
                    limiter=sat.input_limiter(2.0))


def test_t_s_is_the_last_time_above_the_threshold_edges():
    t = np.arange(4.0)
    assert last_time_above(t, np.zeros(4), 1.0) == 0.0
    assert last_time_above(t, np.array([2.0, 0.0, 0.0, 2.0]), 1.0) == np.inf
    assert last_time_above(t, np.array([2.0, 2.0, 0.5, 0.5]), 1.0) == 1.0


def test_input_metrics_of_a_clipped_constant_command(sat):
    traj = _run(sat, [3.0, -1.0, 0.0, 0.5, 0.0, 0.0, 0.0], sat.state())
    m = flexible_metrics(traj, sat)
    assert m["peak_u"] == 2.0
    assert m["saturated_fraction"] == 1.0
    assert m["ci"] == 0.0
    assert m["effort"] == pytest.approx(3.0 * 2.0, rel=1e-12)  # (2 + 1) N m over 2 s
    assert m["v_peak"] == 0.5
    assert m["hf_power_fraction"] == 0.0  # no torque variation
    assert "regime" not in m


def test_modal_metrics_of_a_free_oscillation(sat):
    """A free, undamped modal oscillation: peak |eta| and the tail's modal energy by hand."""
    free = FlexibleSatellite(sat.inertia, sat.frequencies, np.zeros(4), sat.coupling)
    x0 = free.state(modal=[0.01, 0.0, 0.0, 0.0])
    traj = _run(free, np.zeros(7), x0, horizon=5.0)
    m = flexible_metrics(traj, free, tail=1.0, bandwidth=0.05)
    assert m["eta_peak"][0] == pytest.approx(0.01, rel=1e-12)  # the initial value is the peak
    tail = traj.x[traj.t >= traj.t[-1] - 1.0]
    eta, eta_dot = tail[:, 7:11], tail[:, 11:]
    by_hand = 0.5 * np.sum(eta_dot**2, axis=1) + 0.5 * np.sum(free.frequencies**2 * eta**2, axis=1)
    assert m["modal_energy_residual"] == pytest.approx(by_hand.max(), rel=1e-12)
    assert m["regime"] == "rigid-like"
    assert m["final_error"] == pytest.approx(rotation_angle(traj.x[-1, :4]))


def test_metrics_bad_input(sat):
    traj = _run(sat, np.zeros(7), sat.state(), horizon=0.1)
    with pytest.raises(ArgumentTypeError, match="traj"):
        flexible_metrics(traj.x, sat)
    with pytest.raises(InvalidArgumentError, match="traj"):
        flexible_metrics(traj, sat.with_modes(2))
    with pytest.raises(InvalidArgumentError, match="threshold"):
        flexible_metrics(traj, sat, threshold=0.0)


def test_scenario_data(sat):
    sc = paper_v_scenario()
    assert rotation_angle(sc.initial_state()[:4]) == pytest.approx(np.deg2rad(160.0), rel=1e-12)
    np.testing.assert_allclose(sc.initial_state()[1:4] / np.linalg.norm(sc.initial_state()[1:4]),
                               np.ones(3) / np.sqrt(3.0), rtol=1e-12)
    assert np.all(sc.initial_state()[4:] == 0.0)
    d = PaperVDisturbance()
    t = 3.7
    np.testing.assert_allclose(d(t), 0.05 * np.array([np.sin(0.1 * t), np.cos(0.1 * t),
                                                      np.sin(0.1 * t + np.pi / 4)]), rtol=1e-15)
    assert sc.limiter()(np.array([3.0, 0, 0, 50.0, 0, 0, 0])).tolist() == [2.0, 0, 0, 50.0, 0, 0, 0]
    steady = steady_error_scenario()
    assert steady.duration == 250.0 and rotation_angle(steady.initial_state()[:4]) == 0.0
    assert isinstance(steady.disturbance, ConstantHubTorque)
    assert 0.01 in F2_EPSILONS
    with pytest.raises(InvalidArgumentError, match="duration"):
        paper_v_scenario(duration=-1.0)
    with pytest.raises(ArgumentTypeError, match="satellite"):
        paper_v_scenario(satellite="sat")
    with pytest.raises(InvalidArgumentError, match="u_max"):
        sat.input_limiter(-2.0)
    with pytest.raises(InvalidArgumentError, match="v_max"):
        sat.input_limiter(2.0, v_max=[1.0, 2.0])
