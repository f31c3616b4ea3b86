"""The closed loop: :func:`~rmpc.simulate`, the sampled plants it advances, disturbances."""

from rmpc.sim.disturbances import ConstantDisturbance, SineDisturbance, StepDisturbance
from rmpc.sim.simulate import Trajectory, simulate

__all__ = ["ConstantDisturbance", "SineDisturbance", "StepDisturbance", "Trajectory", "simulate"]
