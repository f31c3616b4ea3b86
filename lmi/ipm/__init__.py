"""A structure-exploiting primal-dual interior-point solver for small block LMI problems.

Solves ``min c'x`` subject to ``S_j = C_j - sum_i x_i A_ij >= 0`` for a few small symmetric
blocks (:class:`BlockLMISolver`; the algorithm is described in :mod:`lmi.ipm.solver`). The
package follows the solver's seams:

- :mod:`lmi.ipm.solver`: the method (starting points, iterations, stopping rules, warm starts)
  and the factorisation of the Newton system;
- :mod:`lmi.ipm.blocks`: the data as the kernels read it (checked, packed, equilibrated, sparse
  and factored coefficients);
- :mod:`lmi.ipm.phase_one`: phase one, a feasible point or a checked proof of infeasibility;
- :mod:`lmi.ipm.kernels`: the compiled kernels of an iteration (numba).
"""

from lmi.ipm.blocks import DIRECT_MIN_VARIABLES, BlockFactor
from lmi.ipm.phase_one import (
    PHASE_ONE_MARGIN,
    PHASE_ONE_MAX_ITER,
    PHASE_ONE_RESIDUAL,
    PHASE_ONE_TOL,
    PhaseOneResult,
)
from lmi.ipm.solver import QR_SWITCH, REDUCED_TOL, STALL_WINDOW, BlockLMISolver, IPMResult

__all__ = [
    "DIRECT_MIN_VARIABLES", "PHASE_ONE_MARGIN", "PHASE_ONE_MAX_ITER", "PHASE_ONE_RESIDUAL", "PHASE_ONE_TOL",
    "QR_SWITCH", "REDUCED_TOL", "STALL_WINDOW", "BlockFactor", "BlockLMISolver", "IPMResult",
    "PhaseOneResult",
]
