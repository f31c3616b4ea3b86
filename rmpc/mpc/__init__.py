"""Predictive controllers: LQR (the reference), online robust MPC (Kothare et al. 1996), its
scheduled variant, off-line robust MPC (Wan & Kothare 2003), GIPC and CRMPC with its adaptation
rules.
"""

from rmpc.mpc.crmpc import CRMPC
from rmpc.mpc.gipc import GIPC
from rmpc.mpc.lqr import LQR
from rmpc.mpc.offline import OfflineRMPC
from rmpc.mpc.robust_mpc import RMPC
from rmpc.mpc.scheduled import ScheduledRMPC

__all__ = ["CRMPC", "GIPC", "LQR", "RMPC", "OfflineRMPC", "ScheduledRMPC"]
