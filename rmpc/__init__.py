"""Controllers and the closed loop: robust MPC, baselines and the simulator.

Every controller follows the ``step(x)`` protocol (:class:`rmpc.controller.Controller`).
"""

from rmpc.adaptive_backstepping import AdaptiveBacksteppingFTC
from rmpc.adaptive_smc import AdaptiveSMC
from rmpc.attitude_pd import AttitudePD
from rmpc.cf_backstepping import CFBackstepping
from rmpc.command_filter import CommandFilter
from rmpc.controller import Controller, StepInfo
from rmpc.crmpc import CRMPC
from rmpc.csmc import CSMC
from rmpc.disturbances import ConstantDisturbance, SineDisturbance, StepDisturbance
from rmpc.flexible_hybrid import FlexibleHybrid
from rmpc.gipc import GIPC
from rmpc.lqr import LQR
from rmpc.lqr_flexible import flexible_lqr
from rmpc.mab import MAB
from rmpc.mtsmc import MTSMC
from rmpc.neso import NESO
from rmpc.offline_rmpc import OfflineRMPC
from rmpc.robust_avc import RobustAVC
from rmpc.robust_mpc import RMPC
from rmpc.scheduled_rmpc import ScheduledRMPC
from rmpc.simulate import Trajectory, simulate
from rmpc.tuning_function_ab import TuningFunctionAB
from rmpc.wrappers import MappedController

__all__ = [
    "CRMPC",
    "CSMC",
    "GIPC",
    "LQR",
    "MAB",
    "MTSMC",
    "NESO",
    "RMPC",
    "AdaptiveBacksteppingFTC",
    "AdaptiveSMC",
    "AttitudePD",
    "CFBackstepping",
    "CommandFilter",
    "ConstantDisturbance",
    "Controller",
    "FlexibleHybrid",
    "MappedController",
    "OfflineRMPC",
    "RobustAVC",
    "ScheduledRMPC",
    "SineDisturbance",
    "StepDisturbance",
    "StepInfo",
    "Trajectory",
    "TuningFunctionAB",
    "flexible_lqr",
    "simulate",
]
