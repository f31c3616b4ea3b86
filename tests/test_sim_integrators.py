"""The integrators by name (DOP853, RK4, Newmark), their options, and the finite checks of a sample."""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import pytest

from models import FlexibleSatellite, RigidSatellite, WheelSatellite
from rmpc import StepDisturbance, simulate
from rmpc.sim.integrators import DOP853, INTEGRATORS, RK4, Newmark, make_integrator
from rmpc.sim.plants import SampledPlant
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError


@pytest.fixture(scope="module")
def sat() -> RigidSatellite:
    return RigidSatellite.paper_p()


def test_integrators_by_name(sat: RigidSatellite) -> None:
    assert INTEGRATORS == ("DOP853", "RK4", "Newmark")
    default = SampledPlant(sat, 0.1)
    assert type(default.integrator) is DOP853 and default.integrator.name == "DOP853"
    assert (default.integrator.rtol, default.integrator.atol, default.n_substeps) == (1e-10, 1e-12, None)
    tight = SampledPlant(sat, 0.1, rtol=1e-8, atol=1e-9, substep=0.01)  # substep: ignored by DOP853
    assert (tight.integrator.rtol, tight.integrator.atol) == (1e-8, 1e-9)
    rk4 = SampledPlant(sat, 0.1, integrator="RK4", substep=0.03)
    assert type(rk4.integrator) is RK4 and rk4.n_substeps == 4  # ceil(0.1 / 0.03)
    assert SampledPlant(sat, 0.1, integrator="RK4").n_substeps == 1  # one step per sample
    assert SampledPlant(sat, 0.1, integrator="RK4", substep=0.025).n_substeps == 4  # exact: no extra step
    flex = FlexibleSatellite.di_gennaro()
    newmark = SampledPlant(flex, 0.1, integrator="Newmark")
    assert type(newmark.integrator) is Newmark and newmark.n_substeps == 20  # default 5 ms
    ready = Newmark(substep=0.01, beta=0.3, gamma=0.6)
    assert SampledPlant(flex, 0.1, integrator=ready).integrator is ready
    assert make_integrator("RK4", substep=0.5).substep == 0.5


def test_unknown_integrator_names_the_argument(sat: RigidSatellite) -> None:
    with pytest.raises(InvalidArgumentError, match="integrator") as err:
        SampledPlant(sat, 0.1, integrator="Euler")
    assert "'DOP853', 'RK4', 'Newmark'" in str(err.value) and "'Euler'" in str(err.value)
    with pytest.raises(InvalidArgumentError, match="integrator"):
        SampledPlant(sat, 0.1, integrator="rk4")  # names are exact
    with pytest.raises(ArgumentTypeError, match="integrator"):
        SampledPlant(sat, 0.1, integrator=4)
    with pytest.raises(InvalidArgumentError, match="substep"):  # a ready integrator has its own step
        SampledPlant(sat, 0.1, integrator=RK4(0.01), substep=0.02)
    with pytest.raises(InvalidArgumentError, match="rtol"):
        SampledPlant(sat, 0.1, integrator=DOP853(), rtol=1e-6)
    with pytest.raises(InvalidArgumentError, match="rtol"):
        SampledPlant(sat, 0.1, rtol=-1.0)
    with pytest.raises(InvalidArgumentError, match="integrator"):  # Newmark needs a second-order layout
        SampledPlant(WheelSatellite.paper_w(), 0.04, integrator="Newmark")


def test_the_named_integrators_agree_on_a_sample_with_a_step_inside(sat: RigidSatellite) -> None:
    """DOP853 stops at the step's time; RK4 with a substep that puts the step on a grid point agrees."""
    x0 = sat.initial_state()
    u = np.array([0.2, -0.1, 0.05])
    d = StepDisturbance([0.3, 0.0, 0.0], t_start=0.05)
    x_dop = SampledPlant(sat, 0.1).advance(x0, u, 0.0, d)
    x_rk4 = SampledPlant(sat, 0.1, integrator="RK4", substep=0.001).advance(x0, u, 0.0, d)
    np.testing.assert_allclose(x_rk4, x_dop, rtol=0, atol=1e-12)
    # and the step matters: without it the state differs
    x_clean = SampledPlant(sat, 0.1).advance(x0, u, 0.0, None)
    assert np.max(np.abs(x_clean - x_dop)) > 1e-4


class _NaNAfter:
    """The rigid satellite whose right-hand side turns NaN from ``t_bad`` on (via the disturbance)."""

    state_dependent = False

    def __init__(self, t_bad: float) -> None:
        self.t_bad = t_bad

    def __call__(self, t: float) -> np.ndarray:
        return np.full(3, np.nan) if t >= self.t_bad else np.zeros(3)

    def breakpoints(self) -> tuple[float, ...]:
        return (self.t_bad,)


class _Zero:
    last = None

    def step(self, x: np.ndarray) -> np.ndarray:
        return np.zeros(3)


@contextmanager
def _deadline(seconds: int) -> Iterator[None]:
    """Fail instead of hanging (SIGALRM interrupts the Python loop of ``solve_ivp``)."""

    def expire(signum: int, frame: Any) -> None:
        raise TimeoutError(f"still integrating after {seconds} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def test_a_nan_disturbance_stops_dop853_with_the_time(sat: RigidSatellite) -> None:
    """A NaN in a DOP853 piece would make ``solve_ivp`` shrink its step forever; the disturbance is named."""
    x0 = np.array([0.1, 0.0, 0.0, 0.1, 0.2, 0.0])
    with _deadline(60), pytest.raises(InvalidArgumentError, match=r"^disturbance: ") as err:
        simulate(_Zero(), sat, x0, duration=1.0, dt=0.1, disturbance=_NaNAfter(0.3))
    assert "t = 0.3 s" in str(err.value)


def test_a_nan_disturbance_stops_rk4_with_the_time(sat: RigidSatellite) -> None:
    """RK4 evaluates the disturbance at its substeps: the first one at or after 0.35 s is named."""
    x0 = np.array([0.1, 0.0, 0.0, 0.1, 0.2, 0.0])
    plant = SampledPlant(sat, 0.1, integrator="RK4", substep=0.01)
    with pytest.raises(InvalidArgumentError, match=r"^disturbance: ") as err:
        simulate(_Zero(), plant, x0, duration=1.0, disturbance=_NaNAfter(0.35))
    assert "t = 0.35 s" in str(err.value)


class _NaNStage:
    def __call__(self, t: float, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        return np.full_like(u, np.nan) if t >= 0.2 else u


def test_a_nan_input_stage_is_named_with_the_time(sat: RigidSatellite) -> None:
    plant = SampledPlant(sat, 0.1, input_stage=_NaNStage())
    with pytest.raises(InvalidArgumentError, match="input_stage") as err:
        simulate(_Zero(), plant, np.zeros(6), duration=1.0)
    assert "t = 0.2 s" in str(err.value)


class _NaNBeyond:
    """A user's plant: the rigid satellite whose own right-hand side turns NaN once roll passes 0.25 rad."""

    def __init__(self, sat: RigidSatellite) -> None:
        self.sat = sat
        self.n_states, self.n_inputs = sat.n_states, sat.n_inputs

    def dynamics(self, x: np.ndarray, u: np.ndarray, d: np.ndarray | None = None) -> np.ndarray:
        out = self.sat.dynamics(x, u, d)
        return np.full_like(out, np.nan) if x[0] > 0.25 else out


@pytest.mark.parametrize("integrator", ["DOP853", "RK4"])
def test_a_nan_plant_right_hand_side_stops_with_the_time(sat: RigidSatellite, integrator: str) -> None:
    """The plant's own NaN (no callback to blame) stops the integrator with the plant named and the time."""
    x0 = np.array([0.1, 0.0, 0.0, 0.1, 0.0, 0.0])  # roll rate 0.1 rad/s: roll passes 0.25 rad near 1.5 s
    plant = SampledPlant(_NaNBeyond(sat), 0.1, integrator=integrator, substep=0.01)
    with _deadline(60), pytest.raises(InvalidArgumentError, match=r"^plant: ") as err:
        simulate(_Zero(), plant, x0, duration=3.0)
    message = str(err.value)
    assert "x'" in message and "nan" in message
    t_reported = float(message.split("at t = ")[1].split(" s")[0])
    assert 1.3 <= t_reported <= 1.7, message
