"""Controllers and the closed loop: robust MPC, baselines and the simulator.

Every controller follows the ``step(x)`` protocol (:class:`rmpc.controller.Controller`): ``reset()``,
``step(x, inputs=None) -> u``, ``last`` (a :class:`StepInfo` whose ``status`` is a word of the one
status vocabulary, :class:`Status`), ``name`` and ``accepts`` (the :class:`StepInputs` fields it
uses).
"""

from typing import TYPE_CHECKING

from toolkit_common.lazy import lazy_exports

if TYPE_CHECKING:
    from rmpc.controller import Controller, Status, StepInfo, StepInputs
    from rmpc.export import export_c
    from rmpc.io.registry import load
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
    from rmpc.mpc.multistage import MultiStageMPC
    from rmpc.mpc.offline import OfflineRMPC
    from rmpc.mpc.robust_mpc import RMPC
    from rmpc.mpc.scheduled import ScheduledRMPC
    from rmpc.mpc.tube import TubeMPC
    from rmpc.sim.disturbances import ConstantDisturbance, SineDisturbance, StepDisturbance
    from rmpc.sim.simulate import simulate
    from rmpc.sim.trajectory import Trajectory
    from rmpc.wrappers import MappedController


# the module defining each public name, imported when the name is first looked up
_EXPORTS = {
    "rmpc.controller": ("Controller", "Status", "StepInfo", "StepInputs"),
    "rmpc.export": ("export_c",),
    "rmpc.io.registry": ("load",),
    "rmpc.laws.flexible.adaptive_pd": ("AdaptivePD",),
    "rmpc.laws.flexible.adaptive_smc": ("AdaptiveSMC",),
    "rmpc.laws.flexible.attitude_pd": ("AttitudePD",),
    "rmpc.laws.flexible.csmc": ("CSMC",),
    "rmpc.laws.flexible.hybrid": ("FlexibleHybrid",),
    "rmpc.laws.flexible.input_shaping": ("ShapedPD",),
    "rmpc.laws.flexible.lqr": ("flexible_lqr",),
    "rmpc.laws.flexible.mtsmc": ("MTSMC",),
    "rmpc.laws.flexible.nonlinear_pd": ("NonlinearPD",),
    "rmpc.laws.flexible.robust_avc": ("RobustAVC",),
    "rmpc.laws.mrp.cf_backstepping": ("CFBackstepping",),
    "rmpc.laws.mrp.command_filter": ("CommandFilter",),
    "rmpc.laws.mrp.mab": ("MAB",),
    "rmpc.laws.mrp.neso": ("NESO",),
    "rmpc.laws.mrp.tuning_function_ab": ("TuningFunctionAB",),
    "rmpc.laws.wheel.adaptive_backstepping": ("AdaptiveBacksteppingFTC",),
    "rmpc.mpc.crmpc": ("CRMPC",),
    "rmpc.mpc.gipc": ("GIPC",),
    "rmpc.mpc.lqr": ("LQR",),
    "rmpc.mpc.multistage": ("MultiStageMPC",),
    "rmpc.mpc.offline": ("OfflineRMPC",),
    "rmpc.mpc.robust_mpc": ("RMPC",),
    "rmpc.mpc.scheduled": ("ScheduledRMPC",),
    "rmpc.mpc.tube": ("TubeMPC",),
    "rmpc.sim.disturbances": ("ConstantDisturbance", "SineDisturbance", "StepDisturbance"),
    "rmpc.sim.simulate": ("simulate",),
    "rmpc.sim.trajectory": ("Trajectory",),
    "rmpc.wrappers": ("MappedController",),
}

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
    "MultiStageMPC",
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
    "TubeMPC",
    "TuningFunctionAB",
    "export_c",
    "flexible_lqr",
    "load",
    "simulate",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
