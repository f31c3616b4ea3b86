"""LMI problem builders, solver back-ends and certificates for robust MPC.

The main object is :class:`KothareProblem` (Kothare, Balakrishnan & Morari 1996): built once
over a polytope of discrete-time models, solved for each measured state, every answer checked
by :func:`certify`.
"""

from lmi.certificate import Certificate, certify
from lmi.data import KothareData, build_kothare_data
from lmi.kothare import KothareProblem, LMISolution
from lmi.status import FAILURE_STATUSES, OPTIMAL, STATUSES

__all__ = [
    "FAILURE_STATUSES",
    "OPTIMAL",
    "STATUSES",
    "Certificate",
    "KothareData",
    "KothareProblem",
    "LMISolution",
    "build_kothare_data",
    "certify",
]
