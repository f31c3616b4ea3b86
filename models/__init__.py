"""Plants: the nonlinear rigid satellite, linearisation, discretisation, polytopes, actuators.

Examples
--------
>>> from models import RigidSatellite
>>> sat = RigidSatellite.paper_p()
>>> plant = sat.polytope(sat.initial_state(), dt=0.01, spread=0.3, mode="scalar")
>>> plant.n_vertices, plant.n_states, plant.n_inputs
(2, 6, 3)
"""

from typing import TYPE_CHECKING

from toolkit_common.lazy import lazy_exports

if TYPE_CHECKING:
    from models.actuators import ReactionWheelActuator, TorqueLimiter
    from models.attitude.euler import kinematics_matrix
    from models.flexible.satellite import FlexibleSatellite
    from models.linear import PolytopicModel, zoh
    from models.mrp.satellite import MRPSatellite
    from models.mrp.scenarios import PaperMScenario, paper_m_scenario
    from models.mrp.spinning_disk import SpinningDisk
    from models.rigid.satellite import (
        INPUT_NAMES,
        PAPER_P_INERTIA,
        PAPER_P_INITIAL_STATE,
        PAPER_P_SAMPLE_TIME,
        PAPER_P_TORQUE_LIMIT,
        STATE_NAMES,
        RigidSatellite,
    )
    from models.wheels.array import WheelArray
    from models.wheels.faults import FaultSchedule, RankWindow, WheelFault, rank_deficient_windows
    from models.wheels.noise import AttitudeNoiseSensor, WheelDisturbance
    from models.wheels.satellite import WheelSatellite
    from models.wheels.scenarios import WheelScenario, paper_w_scenario
    from models.wheels.stage import WheelInputStage


# the module defining each public name, imported when the name is first looked up
_EXPORTS = {
    "models.actuators": ("ReactionWheelActuator", "TorqueLimiter"),
    "models.attitude.euler": ("kinematics_matrix",),
    "models.flexible.satellite": ("FlexibleSatellite",),
    "models.linear": ("PolytopicModel", "zoh"),
    "models.mrp.satellite": ("MRPSatellite",),
    "models.mrp.scenarios": ("PaperMScenario", "paper_m_scenario"),
    "models.mrp.spinning_disk": ("SpinningDisk",),
    "models.rigid.satellite": (
        "INPUT_NAMES", "PAPER_P_INERTIA", "PAPER_P_INITIAL_STATE", "PAPER_P_SAMPLE_TIME",
        "PAPER_P_TORQUE_LIMIT", "STATE_NAMES", "RigidSatellite",
    ),
    "models.wheels.array": ("WheelArray",),
    "models.wheels.faults": ("FaultSchedule", "RankWindow", "WheelFault", "rank_deficient_windows"),
    "models.wheels.noise": ("AttitudeNoiseSensor", "WheelDisturbance"),
    "models.wheels.satellite": ("WheelSatellite",),
    "models.wheels.scenarios": ("WheelScenario", "paper_w_scenario"),
    "models.wheels.stage": ("WheelInputStage",),
}

__all__ = [
    "INPUT_NAMES",
    "PAPER_P_INERTIA",
    "PAPER_P_INITIAL_STATE",
    "PAPER_P_SAMPLE_TIME",
    "PAPER_P_TORQUE_LIMIT",
    "STATE_NAMES",
    "AttitudeNoiseSensor",
    "FaultSchedule",
    "FlexibleSatellite",
    "MRPSatellite",
    "PaperMScenario",
    "PolytopicModel",
    "RankWindow",
    "ReactionWheelActuator",
    "RigidSatellite",
    "SpinningDisk",
    "TorqueLimiter",
    "WheelArray",
    "WheelDisturbance",
    "WheelFault",
    "WheelInputStage",
    "WheelSatellite",
    "WheelScenario",
    "kinematics_matrix",
    "paper_m_scenario",
    "paper_w_scenario",
    "rank_deficient_windows",
    "zoh",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
