"""One status vocabulary for every LMI back-end.

``"optimal"`` means the solver converged **and** the certificate (every LMI recomputed in numpy
from the returned ``Q``, ``Y``, ``gamma``) holds. Every other word is a failure the caller has to
handle; none is ever raised as an exception by :meth:`lmi.KothareProblem.solve`.
"""

from __future__ import annotations

__all__ = [
    "FAILURE_STATUSES",
    "OPTIMAL",
    "STATUSES",
]

OPTIMAL = "optimal"
#: Converged, but a recomputed LMI margin is below the certificate tolerance.
UNCERTIFIED = "uncertified"
INFEASIBLE = "infeasible"
UNBOUNDED = "unbounded"
INACCURATE = "inaccurate"
MAX_ITERATIONS = "max_iterations"
TIME_LIMIT = "time_limit"
NUMERICAL_ERROR = "numerical_error"
SOLVER_ERROR = "solver_error"

STATUSES: tuple[str, ...] = (
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
FAILURE_STATUSES: frozenset[str] = frozenset(STATUSES) - {OPTIMAL}

#: Clarabel's ``SolverStatus`` names mapped to the vocabulary.
CLARABEL_STATUS_MAP: dict[str, str] = {
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
CVXPY_STATUS_MAP: dict[str, str] = {
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
