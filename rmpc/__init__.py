"""Controllers and the closed loop: robust MPC, baselines and the simulator.

Every controller follows the ``step(x)`` protocol (:class:`rmpc.controller.Controller`).
"""

from rmpc.controller import Controller, StepInfo
from rmpc.disturbances import ConstantDisturbance, SineDisturbance, StepDisturbance
from rmpc.lqr import LQR
from rmpc.robust_mpc import RMPC
from rmpc.simulate import Trajectory, simulate

__all__ = [
    "LQR",
    "RMPC",
    "ConstantDisturbance",
    "Controller",
    "SineDisturbance",
    "StepDisturbance",
    "StepInfo",
    "Trajectory",
    "simulate",
]
