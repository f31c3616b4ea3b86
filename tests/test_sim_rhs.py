"""The one right-hand side helper: the sampled plants and the continuous-time closed loop share it."""

from __future__ import annotations

import numpy as np
import pytest

from models import MRPSatellite, RigidSatellite, paper_m_scenario
from rmpc import CFBackstepping, ConstantDisturbance, StepDisturbance
from rmpc.sim.rhs import model_dynamics, plant_derivative
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError


def test_the_unchecked_member_is_used_when_offered_and_agrees_with_dynamics() -> None:
    rigid, mrp = RigidSatellite.paper_p(), MRPSatellite.paper_m()
    assert model_dynamics(rigid) == rigid.dynamics_unchecked
    assert model_dynamics(mrp) == mrp.dynamics  # no unchecked member: the checked one
    x, u, d = rigid.initial_state(), np.array([0.3, -0.2, 0.1]), np.array([0.01, 0.02, -0.03])
    np.testing.assert_array_equal(rigid.dynamics_unchecked(x, u, d), rigid.dynamics(x, u, d))
    np.testing.assert_array_equal(rigid.dynamics_unchecked(x, u), rigid.dynamics(x, u))
    dist = StepDisturbance(d, t_start=1.0)
    f = model_dynamics(rigid)
    np.testing.assert_array_equal(plant_derivative(f, 0.5, x, u, dist), rigid.dynamics(x, u))
    np.testing.assert_array_equal(plant_derivative(f, 1.0, x, u, dist), rigid.dynamics(x, u, d))
    with pytest.raises(ArgumentTypeError, match="plant"):
        model_dynamics(object())
    # the checked member keeps its checks
    with pytest.raises(InvalidArgumentError, match="u"):
        rigid.dynamics(x, [np.nan, 0.0, 0.0])


@pytest.mark.parametrize("plant_kind", ["mrp", "rigid"])
def test_closed_loop_rhs_is_the_plant_derivative_and_the_internal_one(plant_kind: str) -> None:
    m1 = paper_m_scenario("M1")
    inertia = np.diag(m1.model().inertia).tolist()
    plant = m1.true_satellite() if plant_kind == "mrp" else RigidSatellite(inertia)
    bs = CFBackstepping(m1.model(), target=m1.sigma_ref, u_max=1.0)
    disturbance = ConstantDisturbance([0.01, -0.02, 0.005])
    rhs = bs.closed_loop_rhs(plant, disturbance)
    x = m1.initial_state()
    z = bs.initial_internal(x) + 0.01
    y_dot = rhs(2.0, np.concatenate((x, z)))
    u = bs.law(x, z)
    np.testing.assert_array_equal(y_dot[:6], plant.dynamics(x, u, disturbance(2.0)))
    np.testing.assert_array_equal(y_dot[6:], bs.internal_derivative(x, z, u))
    with pytest.raises(ArgumentTypeError, match="plant"):
        bs.closed_loop_rhs(object())
