"""The closed loop: :func:`~rmpc.simulate`, the sampled plants it advances, their integrators,
disturbances and the :class:`~rmpc.Trajectory` it returns."""

from rmpc.sim.disturbances import ConstantDisturbance, SineDisturbance, StepDisturbance
from rmpc.sim.plants import SampledPlant
from rmpc.sim.simulate import simulate
from rmpc.sim.trajectory import Trajectory

__all__ = [
    "ConstantDisturbance",
    "SampledPlant",
    "SineDisturbance",
    "StepDisturbance",
    "Trajectory",
    "simulate",
]
