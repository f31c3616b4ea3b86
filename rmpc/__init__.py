"""Controllers and the closed loop: robust MPC, baselines and the simulator.

Every controller follows the ``step(x)`` protocol (:class:`rmpc.controller.Controller`): ``reset()``,
``step(x, inputs=None) -> u``, ``last`` (a :class:`StepInfo` whose ``status`` is a word of the one
status vocabulary, :class:`Status`), ``name`` and ``accepts`` (the :class:`StepInputs` fields it
uses).
"""

from rmpc.controller import Controller, Status, StepInfo, StepInputs
from rmpc.laws.flexible.adaptive_pd import AdaptivePD
from rmpc.laws.flexible.adaptive_smc import AdaptiveSMC
from rmpc.laws.flexible.attitude_pd import AttitudePD
from rmpc.laws.flexible.csmc import CSMC
from rmpc.laws.flexible.hybrid import FlexibleHybrid
from rmpc.laws.flexible.input_shaping import ShapedPD
from rmpc.laws.flexible.lqr import flexible_lqr
from rmpc.laws.flexible.mtsmc import MTSMC
from rmpc.laws.flexible.nonlinear_pd import NonlinearPD
from rmpc.laws.flexible.robust_avc import RobustAVC
from rmpc.laws.mrp.cf_backstepping import CFBackstepping
from rmpc.laws.mrp.command_filter import CommandFilter
from rmpc.laws.mrp.mab import MAB
from rmpc.laws.mrp.neso import NESO
from rmpc.laws.mrp.tuning_function_ab import TuningFunctionAB
from rmpc.laws.wheel.adaptive_backstepping import AdaptiveBacksteppingFTC
from rmpc.mpc.crmpc import CRMPC
from rmpc.mpc.gipc import GIPC
from rmpc.mpc.lqr import LQR
from rmpc.mpc.offline import OfflineRMPC
from rmpc.mpc.robust_mpc import RMPC
from rmpc.mpc.scheduled import ScheduledRMPC
from rmpc.sim.disturbances import ConstantDisturbance, SineDisturbance, StepDisturbance
from rmpc.sim.simulate import simulate
from rmpc.sim.trajectory import Trajectory
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
    "AdaptivePD",
    "AdaptiveSMC",
    "AttitudePD",
    "CFBackstepping",
    "CommandFilter",
    "ConstantDisturbance",
    "Controller",
    "FlexibleHybrid",
    "MappedController",
    "NonlinearPD",
    "OfflineRMPC",
    "RobustAVC",
    "ScheduledRMPC",
    "ShapedPD",
    "SineDisturbance",
    "Status",
    "StepDisturbance",
    "StepInfo",
    "StepInputs",
    "Trajectory",
    "TuningFunctionAB",
    "flexible_lqr",
    "simulate",
]
