"""Paper M's satellite in modified Rodrigues parameters on its orbit.

The family: :class:`~models.MRPSatellite` (:mod:`models.mrp.satellite`), the spinning disk that
disturbs it (:mod:`models.mrp.spinning_disk`), the tracking errors its controllers measure
(:mod:`models.mrp.tracking`) and paper M's scenarios (:mod:`models.mrp.scenarios`). The MRP
maths of :mod:`models.attitude.mrp` (Schaub & Junkins conventions) are importable from here
too, e.g. ``from models.mrp import mrp_to_dcm, mrp_error, mrp_shadow``.
"""

from models.attitude.mrp import (
    dcm_from_euler321,
    euler321_from_dcm,
    mrp_angle,
    mrp_error,
    mrp_error_angle,
    mrp_from_dcm,
    mrp_from_euler321,
    mrp_from_quaternion,
    mrp_kinematics_inverse,
    mrp_kinematics_matrix,
    mrp_shadow,
    mrp_switch,
    mrp_to_dcm,
    mrp_to_quaternion,
)
from models.mrp.satellite import MRPSatellite
from models.mrp.scenarios import PaperMScenario, paper_m_scenario
from models.mrp.spinning_disk import SpinningDisk
from models.mrp.tracking import MRPTrackingError, RMPCStateMap, rmpc_state, tracking_error

__all__ = [
    "MRPSatellite",
    "MRPTrackingError",
    "PaperMScenario",
    "RMPCStateMap",
    "SpinningDisk",
    "dcm_from_euler321",
    "euler321_from_dcm",
    "mrp_angle",
    "mrp_error",
    "mrp_error_angle",
    "mrp_from_dcm",
    "mrp_from_euler321",
    "mrp_from_quaternion",
    "mrp_kinematics_inverse",
    "mrp_kinematics_matrix",
    "mrp_shadow",
    "mrp_switch",
    "mrp_to_dcm",
    "mrp_to_quaternion",
    "paper_m_scenario",
    "rmpc_state",
    "tracking_error",
]
