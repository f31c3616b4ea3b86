"""Newmark-beta (``integrator="Newmark"``) against DOP853 on the flexible satellite (check 13).

Seed papers-S-V-flexible.md, section 7 check 13. The V-slew's first 10 s under MTSMC and CSMC
(tanh), the disturbance of seed section 3 and the 2 N m clip: Newmark-beta (beta = 1/4,
gamma = 1/2) against DOP853 at rtol 1e-8. Measured over the first 20 s with a 5 ms Newmark
step: attitude 3e-7 / 2e-6 deg, eta 1e-6 / 2e-6 (MTSMC / CSMC), falling 4x per halving of the
step (second order); over the full 150 s: see the report.
"""

from __future__ import annotations

import numpy as np
import pytest

from models import FlexibleSatellite, RigidSatellite
from models.attitude.quaternion import quat_error, rotation_angle
from models.flexible.scenario import paper_v_scenario
from rmpc import CSMC, MTSMC, simulate
from rmpc.sim.integrators import Newmark
from rmpc.sim.plants import SampledPlant
from toolkit_common.errors import InvalidArgumentError


@pytest.fixture(scope="module")
def scenario():
    return paper_v_scenario(duration=10.0)


def _run(scenario, plant, make, duration=None):
    return simulate(make(scenario.satellite), plant, scenario.initial_state(), duration or scenario.duration,
                    limiter=scenario.limiter(), disturbance=scenario.disturbance)


def _newmark(sat, dt: float, substep: float) -> SampledPlant:
    return SampledPlant(sat, dt, integrator="Newmark", substep=substep)


def _differences(a, b) -> tuple[float, float]:
    att = max(rotation_angle(quat_error(xa[:4], xb[:4])) for xa, xb in zip(a.x, b.x, strict=True))
    return float(np.rad2deg(att)), float(np.abs(a.x[:, 7:] - b.x[:, 7:]).max())


@pytest.mark.parametrize("make", [MTSMC, lambda s: CSMC(s, switch="tanh")], ids=["MTSMC", "CSMC"])
def test_newmark_agrees_with_dop853_on_the_v_slew(scenario, make):
    sat = scenario.satellite
    ref = _run(scenario, SampledPlant(sat, scenario.dt, rtol=1e-8, atol=1e-10), make)
    newmark = _run(scenario, _newmark(sat, scenario.dt, 0.005), make)
    att_deg, modal = _differences(newmark, ref)
    assert att_deg < 1e-3
    n = sat.n_modes
    assert np.abs(newmark.x[:, 7:7 + n] - ref.x[:, 7:7 + n]).max() < 1e-5
    assert modal < 1e-4  # eta' too
    assert np.abs(np.linalg.norm(newmark.x[:, :4], axis=1) - 1.0).max() < 1e-12
    assert np.abs(np.linalg.norm(ref.x[:, :4], axis=1) - 1.0).max() < 1e-12


def test_newmark_is_second_order(scenario):
    """Halving the step divides the error by about 4 (against DOP853 at rtol 1e-11), 5 s of the slew."""
    sat = scenario.satellite
    ref = _run(scenario, SampledPlant(sat, scenario.dt, rtol=1e-11, atol=1e-13), MTSMC, 5.0)
    errors = [
        _differences(_run(scenario, _newmark(sat, scenario.dt, h), MTSMC, 5.0), ref)
        for h in (0.01, 0.005)
    ]
    for coarse, fine in zip(errors[0], errors[1], strict=True):
        assert 3.5 < coarse / fine < 4.5


def test_newmark_one_step_from_rest():
    """From rest with a constant hub torque, w after one sample is ``J_mb^-1 u dt`` (the modes
    start at rest too), and the quaternion stays at unit norm."""
    sat = FlexibleSatellite.di_gennaro()
    plant = SampledPlant(sat, 0.01, integrator="Newmark")
    assert repr(plant.integrator) == "Newmark(substep=0.005, beta=0.25, gamma=0.5)" and plant.n_substeps == 2
    x1 = plant.advance(sat.state(), np.array([1.0, 0, 0, 0, 0, 0, 0]), 0.0, None)
    assert round(float(x1[4]), 8) == 3.296e-05
    assert round(float(np.linalg.inv(sat.hub_inertia)[0, 0] * 0.01), 8) == 3.296e-05
    assert round(float(np.linalg.norm(x1[:4])), 12) == 1.0


def test_newmark_bad_arguments():
    sat = FlexibleSatellite.di_gennaro()
    with pytest.raises(InvalidArgumentError, match="integrator") as err:
        SampledPlant(RigidSatellite.paper_p(), 0.01, integrator="Newmark")
    assert "Newmark" in str(err.value) and "RigidSatellite" in str(err.value)
    with pytest.raises(InvalidArgumentError, match="beta"):
        SampledPlant(sat, 0.01, integrator=Newmark(beta=0.6))
    with pytest.raises(InvalidArgumentError, match="substep"):
        SampledPlant(sat, 0.01, integrator="Newmark", substep=-1.0)
    with pytest.raises(InvalidArgumentError, match="max_iterations"):
        Newmark(max_iterations=0)
    with pytest.raises(InvalidArgumentError, match="substep"):  # no convergence: a step far too long
        SampledPlant(sat, 10.0, integrator=Newmark(substep=10.0, max_iterations=3)).advance(
            sat.state(rates=[0.5, 0.0, 0.0]), np.ones(7), 0.0, None)


class _Scrambled:
    """The flexible satellite declaring a layout that does not cover its state."""

    def __init__(self, sat: FlexibleSatellite) -> None:
        self.sat, self.n_states, self.n_inputs = sat, sat.n_states, sat.n_inputs

    def dynamics(self, x, u=None, d=None):
        return self.sat.dynamics(x, u, d)

    @property
    def second_order_layout(self):
        return {**self.sat.second_order_layout, "rate": slice(3, 6)}


def test_newmark_checks_the_declared_layout():
    sat = FlexibleSatellite.di_gennaro()
    n = sat.n_modes
    assert sat.second_order_layout == {"quaternion": slice(0, 4), "rate": slice(4, 7),
                                       "position": slice(7, 7 + n), "velocity": slice(7 + n, 7 + 2 * n)}
    with pytest.raises(InvalidArgumentError, match="second_order_layout"):
        SampledPlant(_Scrambled(sat), 0.01, integrator="Newmark")
