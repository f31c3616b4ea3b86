"""Papers S and V's laws for the flexible satellite: attitude laws, vibration control, the hybrid."""

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

__all__ = [
    "CSMC",
    "MTSMC",
    "AdaptivePD",
    "AdaptiveSMC",
    "AttitudePD",
    "FlexibleHybrid",
    "NonlinearPD",
    "RobustAVC",
    "ShapedPD",
    "flexible_lqr",
]
