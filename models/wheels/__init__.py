"""Paper W's satellite on four reaction wheels: the array, faults, noise, input stage, scenarios."""

from models.wheels.array import WheelArray
from models.wheels.faults import FaultSchedule, RankWindow, WheelFault, rank_deficient_windows
from models.wheels.noise import AttitudeNoiseSensor, WheelDisturbance
from models.wheels.satellite import WheelSatellite
from models.wheels.scenarios import WheelScenario, paper_w_scenario
from models.wheels.stage import WheelInputStage

__all__ = [
    "AttitudeNoiseSensor",
    "FaultSchedule",
    "RankWindow",
    "WheelArray",
    "WheelDisturbance",
    "WheelFault",
    "WheelInputStage",
    "WheelSatellite",
    "WheelScenario",
    "paper_w_scenario",
    "rank_deficient_windows",
]
