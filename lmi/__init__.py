"""LMI problem builders, solver back-ends and certificates for robust MPC.

The main object is :class:`KothareProblem` (Kothare, Balakrishnan & Morari 1996): built once
over a polytope of discrete-time models, solved for each measured state, every answer checked
by :func:`certify`. Under it, and usable on its own, is :class:`BlockLMISolver`, the toolkit's
interior-point method for ``min c'x`` subject to ``C_j - sum_i x_i A_ij >= 0`` (its result:
:class:`IPMResult`).
"""

from typing import TYPE_CHECKING

from toolkit_common.lazy import lazy_exports

if TYPE_CHECKING:
    from lmi.certificate import Certificate, certify
    from lmi.data import KothareData, build_kothare_data
    from lmi.ipm import BlockLMISolver, IPMResult
    from lmi.kothare import KothareProblem, LMISolution
    from lmi.status import FAILURE_STATUSES, OPTIMAL, STATUSES


# the module defining each public name, imported when the name is first looked up
_EXPORTS = {
    "lmi.certificate": ("Certificate", "certify"),
    "lmi.data": ("KothareData", "build_kothare_data"),
    "lmi.ipm": ("BlockLMISolver", "IPMResult"),
    "lmi.kothare": ("KothareProblem", "LMISolution"),
    "lmi.status": ("FAILURE_STATUSES", "OPTIMAL", "STATUSES"),
}

__all__ = [
    "FAILURE_STATUSES",
    "OPTIMAL",
    "STATUSES",
    "BlockLMISolver",
    "Certificate",
    "IPMResult",
    "KothareData",
    "KothareProblem",
    "LMISolution",
    "build_kothare_data",
    "certify",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
