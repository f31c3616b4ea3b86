"""SampledPlant: any model with ``dynamics(x, u, d)``, sampled; integrators, input stages, normalisation."""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from models import RigidSatellite
from models.protocols import InputStage
from rmpc import LQR, StepDisturbance, simulate
from rmpc.sim.plants import SampledPlant
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

Q = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])


@pytest.fixture(scope="module")
def sat() -> RigidSatellite:
    return RigidSatellite.paper_p()


@pytest.fixture(scope="module")
def lqr(sat: RigidSatellite) -> LQR:
    return LQR(sat.linear_model(sat.initial_state(), 0.05), Q=Q, R=np.eye(3))


def _satellite_loop(sat: RigidSatellite, x: np.ndarray, u: np.ndarray, t: float, dt: float,
                    d: StepDisturbance) -> np.ndarray:
    """Paper P's sample as the satellite-only DOP853 loop did it: pieces at d's breakpoints, d's
    left limit at each piece's end, the torque ``u + d`` into the rigid-body right-hand side."""
    cuts = [t, *[tb for tb in d.breakpoints() if t < tb < t + dt], t + dt]
    for t0, t1 in pairwise(cuts):
        t_last = float(np.nextafter(t1, t0))
        sol = solve_ivp(lambda tau, y, t_last=t_last: sat.dynamics(y, u + d(min(tau, t_last))), (t0, t1), x,
                        method="DOP853", rtol=1e-10, atol=1e-12)
        x = sol.y[:, -1]
    return x


def test_dop853_on_the_rigid_satellite_is_the_satellite_loop_bit_for_bit(sat: RigidSatellite) -> None:
    """The one wrapper gives paper P's records unchanged: the same floats as the loop it replaced."""
    x0 = sat.initial_state()
    u = np.array([0.3, -0.2, 0.1])
    d = StepDisturbance([0.1, 0.0, -0.1], t_start=0.123)
    plant = SampledPlant(sat, 0.25)
    assert repr(plant.integrator) == "DOP853(rtol=1e-10, atol=1e-12)"
    x_w, x_l = x0.copy(), x0.copy()
    for k in range(8):
        x_w = plant.advance(x_w, u, 0.25 * k, d)
        x_l = _satellite_loop(sat, x_l, u, 0.25 * k, 0.25, d)
        np.testing.assert_array_equal(x_w, x_l)
    assert np.max(np.abs(x_w - x0)) > 0.1  # the plant moved


def test_rk4_converges_to_dop853_at_fourth_order(sat: RigidSatellite, lqr: LQR) -> None:
    x0 = sat.initial_state()
    ref = simulate(lqr, sat, x0, duration=5.0, dt=0.05)
    errors = []
    for substep in (0.025, 0.0125):
        plant = SampledPlant(sat, 0.05, integrator="RK4", substep=substep)
        run = simulate(lqr, plant, x0, duration=5.0)
        errors.append(float(np.max(np.abs(run.x - ref.x))))
    assert errors[1] < 1e-6
    # halving the step divides the error by about 2^4 = 16
    assert 10.0 < errors[0] / errors[1] < 24.0


class ClipStage:
    """Clips each torque to +-limit and records how often it did (a pure function per sample)."""

    def __init__(self, limit: float) -> None:
        self.limit = limit
        self.resets = 0

    def reset(self) -> None:
        self.resets += 1

    def begin_sample(self, t: float, x: np.ndarray, u: np.ndarray) -> dict[str, np.ndarray]:
        return {"clipped": np.abs(u) > self.limit, "t": t}

    def __call__(self, t: float, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        return np.clip(u, -self.limit, self.limit)


def test_input_stage_acts_inside_the_integration_and_is_logged(sat: RigidSatellite, lqr: LQR) -> None:
    x0 = sat.initial_state()
    stage = ClipStage(0.2)
    assert isinstance(stage, InputStage)
    plant = SampledPlant(sat, 0.05, input_stage=stage)
    run = simulate(lqr, plant, x0, duration=4.0)
    assert stage.resets == 1
    assert np.max(np.abs(run.u_applied)) <= 0.2 + 1e-15
    assert np.max(np.abs(run.u_cmd)) > 0.2  # the stage did work
    np.testing.assert_array_equal(run.stage_log["clipped"], np.abs(run.u_cmd) > 0.2)
    np.testing.assert_allclose(run.stage_log["t"], run.t[:-1])
    # a clip of the held command is the same as a limiter before the plant
    from models import TorqueLimiter

    same = simulate(lqr, sat, x0, duration=4.0, dt=0.05, limiter=TorqueLimiter(0.2))
    np.testing.assert_allclose(run.x, same.x, atol=1e-12)


class MomentumStage:
    """A state-dependent stage: no torque about x once the roll rate exceeds a bound."""

    def __call__(self, t: float, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        out = u.copy()
        if x[3] >= 0.01:
            out[0] = 0.0
        return out


def test_state_dependent_stage_switches_inside_a_sample(sat: RigidSatellite) -> None:
    # a constant roll torque from rest: p grows until it reaches the bound, then stops growing
    x0 = np.zeros(6)
    plant = SampledPlant(sat, 1.0, integrator="RK4", substep=0.001, input_stage=MomentumStage())
    x1 = plant.advance(x0, np.array([0.1, 0.0, 0.0]), 0.0, None)
    assert 0.01 <= x1[3] <= 0.01 + 0.1 / sat.inertia[0, 0] * 0.001 + 1e-12
    # without the stage the rate would be 0.1 / Ixx after 1 s
    assert x1[3] < 0.5 * 0.1 / sat.inertia[0, 0]


class UnitCircle:
    """x' = [-x2, x1] w: a point on the unit circle; normalize_state removes the drift."""

    n_states = 2
    n_inputs = 1
    n_disturbances = 1

    def dynamics(self, x: np.ndarray, u: np.ndarray, d: np.ndarray | None = None) -> np.ndarray:
        w = float(u[0]) + (0.0 if d is None else float(d[0]))
        return np.array([-x[1], x[0]]) * w

    def normalize_state(self, x: np.ndarray) -> np.ndarray:
        return x / np.linalg.norm(x)


class HoldOne:
    last = None

    def reset(self) -> None:
        pass

    def step(self, x: np.ndarray) -> np.ndarray:
        return np.array([1.0])


def test_normalize_state_after_every_step() -> None:
    model = UnitCircle()
    run = simulate(HoldOne(), SampledPlant(model, 0.5, integrator="RK4"), [1.0, 0.0], duration=50.0)
    np.testing.assert_allclose(np.linalg.norm(run.x, axis=1), 1.0, atol=1e-15)
    # a bare model is wrapped with DOP853; the angle after 50 s of unit rate is 50 rad
    run2 = simulate(HoldOne(), model, [1.0, 0.0], duration=50.0, dt=0.5)
    np.testing.assert_allclose(run2.x[-1], [np.cos(50.0), np.sin(50.0)], atol=1e-9)


class FourWheels:
    """4 inputs, 3 disturbance axes: d has its own size."""

    n_states = 3
    n_inputs = 4
    n_disturbances = 3

    def dynamics(self, x: np.ndarray, u: np.ndarray, d: np.ndarray | None = None) -> np.ndarray:
        d = np.zeros(3) if d is None else d
        return u[:3] + u[3] + d


class Zero4:
    last = None

    def step(self, x: np.ndarray) -> np.ndarray:
        return np.zeros(4)


def test_disturbance_has_the_models_own_size() -> None:
    run = simulate(Zero4(), FourWheels(), np.zeros(3), duration=1.0, dt=0.1,
                   disturbance=StepDisturbance([1.0, 0.0, 0.0]))
    assert run.d.shape == (10, 3)
    np.testing.assert_allclose(run.x[-1], [1.0, 0.0, 0.0], atol=1e-12)
    with pytest.raises(InvalidArgumentError, match="disturbance"):
        simulate(Zero4(), FourWheels(), np.zeros(3), duration=1.0, dt=0.1,
                 disturbance=StepDisturbance([1.0, 0.0, 0.0, 0.0]))


def test_bad_plants_and_options_name_the_argument(sat: RigidSatellite) -> None:
    with pytest.raises(ArgumentTypeError, match="plant"):
        simulate(HoldOne(), object(), [1.0], duration=1.0, dt=0.1)
    with pytest.raises(InvalidArgumentError, match="integrator"):
        SampledPlant(sat, 0.1, integrator="Euler")
    with pytest.raises(InvalidArgumentError, match="substep"):
        SampledPlant(sat, 0.1, integrator="RK4", substep=-1.0)
    with pytest.raises(ArgumentTypeError, match="input_stage"):
        SampledPlant(sat, 0.1, input_stage=3.0)
    with pytest.raises(InvalidArgumentError, match="dt"):
        simulate(HoldOne(), UnitCircle(), [1.0, 0.0], duration=1.0)
    with pytest.raises(InvalidArgumentError, match="dt"):
        simulate(HoldOne(), SampledPlant(UnitCircle(), 0.5), [1.0, 0.0], duration=1.0, dt=0.1)
    with pytest.raises(InvalidArgumentError, match="true_plant"):
        simulate(HoldOne(), SampledPlant(UnitCircle(), 0.5), [1.0, 0.0], duration=1.0, true_plant=0)
    with pytest.raises(InvalidArgumentError, match="true_plant"):
        simulate(HoldOne(), UnitCircle(), [1.0, 0.0], duration=1.0, dt=0.5, true_plant=0)

    class AdvanceOnly:  # has advance, but not what a sampled plant needs besides
        def advance(self, x, u, t, d):
            return x

    with pytest.raises(ArgumentTypeError, match="plant") as err:
        simulate(HoldOne(), AdvanceOnly(), [1.0, 0.0], duration=1.0, dt=0.5)
    assert "dt, n_states, n_inputs, kind" in str(err.value)
    with pytest.raises(ArgumentTypeError, match="plant"):
        SampledPlant(object(), 0.1)
    with pytest.raises(ArgumentTypeError, match="plant"):
        SampledPlant(type("NoSizes", (), {"dynamics": lambda self, x, u=None, d=None: x})(), 0.1)


class RateDrag:
    """A state-dependent disturbance d(t, x) = -c w (a drag on the rates)."""

    state_dependent = True

    def __init__(self, c: float) -> None:
        self.c = c

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        return -self.c * np.asarray(x)[3:6]


def test_state_dependent_disturbance_is_called_with_the_state(sat: RigidSatellite) -> None:
    x0 = np.array([0.0, 0.0, 0.0, 0.1, 0.0, 0.0])
    run = simulate(Zero3(), sat, x0, duration=10.0, dt=0.1, disturbance=RateDrag(0.5))
    # p' = -c p / Ixx about a principal axis: exponential decay
    np.testing.assert_allclose(run.x[-1, 3], 0.1 * np.exp(-0.5 * 10.0 / sat.inertia[0, 0]), rtol=1e-9)
    np.testing.assert_allclose(run.d[:, 0], -0.5 * run.x[:-1, 3], rtol=1e-12)
    rk4 = simulate(Zero3(), SampledPlant(sat, 0.1, integrator="RK4", substep=0.01), x0, duration=10.0,
                   disturbance=RateDrag(0.5))
    np.testing.assert_allclose(rk4.x[-1], run.x[-1], atol=1e-9)


class Zero3:
    last = None

    def step(self, x: np.ndarray) -> np.ndarray:
        return np.zeros(3)
