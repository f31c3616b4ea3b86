"""Plants: the nonlinear rigid satellite, linearisation, discretisation, polytopes, actuators.

Examples
--------
>>> from models import RigidSatellite
>>> sat = RigidSatellite.paper_p()
>>> plant = sat.polytope(sat.initial_state(), dt=0.01, spread=0.3, mode="scalar")
>>> plant.n_vertices, plant.n_states, plant.n_inputs
(2, 6, 3)
"""

from models.actuators import ReactionWheelActuator, TorqueLimiter
from models.discretize import zoh
from models.flexible import FlexibleSatellite
from models.kinematics import kinematics_matrix
from models.mrp_satellite import MRPSatellite
from models.mrp_scenarios import PaperMScenario, paper_m_scenario
from models.polytope import PolytopicModel
from models.satellite import (
    INPUT_NAMES,
    PAPER_P_INERTIA,
    PAPER_P_INITIAL_STATE,
    PAPER_P_SAMPLE_TIME,
    PAPER_P_TORQUE_LIMIT,
    STATE_NAMES,
    RigidSatellite,
)
from models.spinning_disk import SpinningDisk
from models.wheel_faults import FaultSchedule, RankWindow, WheelFault, rank_deficient_windows
from models.wheel_noise import AttitudeNoiseSensor, WheelDisturbance
from models.wheel_satellite import WheelSatellite
from models.wheel_scenarios import WheelScenario, paper_w_scenario
from models.wheel_stage import WheelInputStage
from models.wheels import WheelArray

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
