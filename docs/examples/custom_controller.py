"""Simulation: a hand-written controller that follows the step(x) protocol."""

import numpy as np

from models import PAPER_P_TORQUE_LIMIT, ReactionWheelActuator, RigidSatellite, TorqueLimiter
from rmpc import Controller, Status, StepDisturbance, StepInfo, StepInputs, simulate
from rmpc.controller import check_step_inputs


class AttitudePD:
    """u = -kp * attitude - kd * rates, the same gains on every axis."""

    name = "PD"                 # the short name in reports
    accepts = frozenset()       # the StepInputs fields it uses: none

    def __init__(self, kp: float, kd: float) -> None:
        self.kp, self.kd = kp, kd
        self.last: StepInfo | None = None

    def reset(self) -> None:
        self.last = None

    def step(self, x: np.ndarray, inputs: StepInputs | None = None) -> np.ndarray:
        check_step_inputs(inputs, self.accepts, self.name)  # a field it does not use is an error
        u = -self.kp * x[:3] - self.kd * x[3:]
        self.last = StepInfo(status=Status.OK, solve_time=0.0, extra={"u_unclipped": u})  # closed form
        return u


assert isinstance(AttitudePD(2.0, 3.0), Controller)


sat = RigidSatellite.paper_p()
x0 = sat.initial_state()
traj = simulate(
    AttitudePD(kp=2.0, kd=3.0),
    sat,                                         # the nonlinear satellite
    x0,
    duration=30.0,
    dt=0.01,
    limiter=TorqueLimiter(PAPER_P_TORQUE_LIMIT),  # +-1 N m per axis
    actuator=ReactionWheelActuator(),             # paper P's reaction wheels
    disturbance=StepDisturbance([0.5, 0.0, 0.0], t_start=10.0),
)

print(traj.n_steps, "steps on the", traj.plant, "plant; statuses:", traj.status_counts())
print("largest commanded / applied torque (N m):",
      round(float(np.abs(traj.u_cmd).max()), 3), "/", round(float(np.abs(traj.u_applied).max()), 3))
print("final attitude (deg):", traj.attitude_deg[-1].round(3).tolist())
print("disturbance on at t = 10 s:", traj.d[999].tolist(), traj.d[1000].tolist())
