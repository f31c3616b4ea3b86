"""Paper M's laws for the satellite in modified Rodrigues parameters."""

from rmpc.laws.mrp.cf_backstepping import CFBackstepping
from rmpc.laws.mrp.command_filter import CommandFilter
from rmpc.laws.mrp.mab import MAB
from rmpc.laws.mrp.neso import NESO
from rmpc.laws.mrp.tuning_function_ab import TuningFunctionAB

__all__ = ["MAB", "NESO", "CFBackstepping", "CommandFilter", "TuningFunctionAB"]
