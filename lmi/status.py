"""The words of the one status vocabulary an LMI back-end reports, and its solvers' maps into it.

The words are members of :class:`toolkit_common.status.Status` (the vocabulary of the whole
toolkit, which the QP back-ends and every controller use too); this module names the ones
:meth:`lmi.KothareProblem.solve` can return. ``"optimal"`` means the solver converged **and**
the certificate (every LMI recomputed in numpy from the returned ``Q``, ``Y``, ``gamma``) holds.
Every other word is a failure the caller has to handle; none is ever raised as an exception.

Examples
--------
>>> from lmi.status import CLARABEL_STATUS_MAP, OPTIMAL, STATUSES
>>> OPTIMAL == "optimal", CLARABEL_STATUS_MAP["AlmostSolved"], STATUSES[0]
(True, 'inaccurate', 'optimal')
"""

from __future__ import annotations

from toolkit_common.status import Status

__all__ = [
    "CLARABEL_STATUS_MAP",
    "CVXPY_STATUS_MAP",
    "FAILURE_STATUSES",
    "INACCURATE",
    "INFEASIBLE",
    "MAX_ITERATIONS",
    "NUMERICAL_ERROR",
    "OPTIMAL",
    "SOLVER_ERROR",
    "STATUSES",
    "TIME_LIMIT",
    "UNBOUNDED",
    "UNCERTIFIED",
]

OPTIMAL = Status.OPTIMAL
#: Converged, but a recomputed LMI margin is below the certificate tolerance.
UNCERTIFIED = Status.UNCERTIFIED
INFEASIBLE = Status.INFEASIBLE
UNBOUNDED = Status.UNBOUNDED
INACCURATE = Status.INACCURATE
MAX_ITERATIONS = Status.MAX_ITERATIONS
TIME_LIMIT = Status.TIME_LIMIT
NUMERICAL_ERROR = Status.NUMERICAL_ERROR
SOLVER_ERROR = Status.SOLVER_ERROR

#: Every word an LMI solve can end with, ``"optimal"`` first.
STATUSES: tuple[Status, ...] = (
    OPTIMAL,
    UNCERTIFIED,
    INFEASIBLE,
    UNBOUNDED,
    INACCURATE,
    MAX_ITERATIONS,
    TIME_LIMIT,
    NUMERICAL_ERROR,
    SOLVER_ERROR,
)
#: Every word of :data:`STATUSES` except ``"optimal"``.
FAILURE_STATUSES: frozenset[Status] = frozenset(STATUSES) - {OPTIMAL}

#: Clarabel's ``SolverStatus`` names mapped to the vocabulary.
CLARABEL_STATUS_MAP: dict[str, Status] = {
    "Solved": OPTIMAL,
    "AlmostSolved": INACCURATE,
    "PrimalInfeasible": INFEASIBLE,
    "AlmostPrimalInfeasible": INFEASIBLE,
    "DualInfeasible": UNBOUNDED,
    "AlmostDualInfeasible": UNBOUNDED,
    "MaxIterations": MAX_ITERATIONS,
    "MaxTime": TIME_LIMIT,
    "NumericalError": NUMERICAL_ERROR,
    "InsufficientProgress": NUMERICAL_ERROR,
    "CallbackTerminated": SOLVER_ERROR,
    "Unsolved": SOLVER_ERROR,
}

#: cvxpy's status strings mapped to the vocabulary.
CVXPY_STATUS_MAP: dict[str, Status] = {
    "optimal": OPTIMAL,
    "optimal_inaccurate": INACCURATE,
    "infeasible": INFEASIBLE,
    "infeasible_inaccurate": INFEASIBLE,
    "unbounded": UNBOUNDED,
    "unbounded_inaccurate": UNBOUNDED,
    "user_limit": MAX_ITERATIONS,
    "infeasible_or_unbounded": INFEASIBLE,
    "solver_error": SOLVER_ERROR,
}
