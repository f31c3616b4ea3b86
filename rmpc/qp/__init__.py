"""A small QP layer: one problem description, back-ends for OSQP, ProxQP and Clarabel.

Every back-end follows ``setup(qp) -> update(g=, l=, u=, lb=, ub=) -> solve()``, is
warm-started where its solver allows, uses explicit (tightened) tolerances, and maps its
solver's statuses into the toolkit's one status vocabulary
(:class:`toolkit_common.status.Status`; :data:`STATUSES` lists the words a back-end
reports). ``"cvxpy"`` is a reference back-end for tests and timing comparisons, and
:func:`reference_solution` a certified high-accuracy answer (interior point refined on its
active set).

Examples
--------
>>> import numpy as np
>>> from rmpc.qp import QP, make_backend, kkt_residuals
>>> qp = QP(H=[[2.0, 0.5], [0.5, 1.0]], g=[1.0, 1.0], C=[[1.0, 1.0]], l=[1.0], u=[1.0],
...         lb=[0.0, 0.0], ub=[0.7, 0.7])
>>> be = make_backend("proxqp")
>>> be.setup(qp)
>>> res = be.solve()
>>> res.status, np.round(res.x, 6).tolist()
('optimal', [0.3, 0.7])
>>> kkt_residuals(qp, res).max() < 1e-8
True
>>> be.update(g=[0.0, 2.0])          # only vectors change between solves
>>> be.solve().status
'optimal'
"""

from rmpc.qp.base import BackendSettings, QPBackend
from rmpc.qp.clarabel_backend import ClarabelBackend, ClarabelSettings
from rmpc.qp.cvxpy_backend import CvxpyBackend, CvxpySettings
from rmpc.qp.factory import BACKENDS, make_backend
from rmpc.qp.osqp_backend import OSQPBackend, OSQPSettings
from rmpc.qp.problem import QP, STATUSES, KKTResiduals, QPResult, SolverResiduals, kkt_residuals
from rmpc.qp.proxqp_backend import ProxQPBackend, ProxQPSettings
from rmpc.qp.reference import reference_solution, refine_active_set

__all__ = [
    "BACKENDS",
    "QP",
    "STATUSES",
    "BackendSettings",
    "ClarabelBackend",
    "ClarabelSettings",
    "CvxpyBackend",
    "CvxpySettings",
    "KKTResiduals",
    "OSQPBackend",
    "OSQPSettings",
    "ProxQPBackend",
    "ProxQPSettings",
    "QPBackend",
    "QPResult",
    "SolverResiduals",
    "kkt_residuals",
    "make_backend",
    "reference_solution",
    "refine_active_set",
]
