"""Controllers and the closed loop: robust MPC, baselines and the simulator.

Every controller follows the ``step(x)`` protocol (:class:`rmpc.controller.Controller`).
"""

from rmpc.adaptive_backstepping import AdaptiveBacksteppingFTC
from rmpc.cf_backstepping import CFBackstepping
from rmpc.command_filter import CommandFilter
from rmpc.controller import Controller, StepInfo
from rmpc.crmpc import CRMPC
from rmpc.disturbances import ConstantDisturbance, SineDisturbance, StepDisturbance
from rmpc.gipc import GIPC
from rmpc.lqr import LQR
from rmpc.mab import MAB
from rmpc.neso import NESO
from rmpc.offline_rmpc import OfflineRMPC
from rmpc.robust_mpc import RMPC
from rmpc.scheduled_rmpc import ScheduledRMPC
from rmpc.simulate import Trajectory, simulate
from rmpc.tuning_function_ab import TuningFunctionAB
from rmpc.wrappers import MappedController

__all__ = [
    "CRMPC",
    "GIPC",
    "LQR",
    "MAB",
    "NESO",
    "RMPC",
    "AdaptiveBacksteppingFTC",
    "CFBackstepping",
    "CommandFilter",
    "ConstantDisturbance",
    "Controller",
    "MappedController",
    "OfflineRMPC",
    "ScheduledRMPC",
    "SineDisturbance",
    "StepDisturbance",
    "StepInfo",
    "Trajectory",
    "TuningFunctionAB",
    "simulate",
]
