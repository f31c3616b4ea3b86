"""SCS through cvxpy with Ctrl-C handed back to the process.

SCS installs its own SIGINT handler while it solves: Ctrl-C during a solve stops the solve (its
status ``-5``, "interrupted"), never reaches Python, and cvxpy reports it as a failed solve
(``SolverError``), which the Kothare problem records as ``"solver_error"`` and applies its
fallback input: the run went on as if nothing had been pressed. :class:`InterruptibleSCS` is
cvxpy's SCS interface that raises the signal again in the process after such a solve, where
Python's handler acts on it (``KeyboardInterrupt`` by default, or the benchmark runner's
handler); when the process goes on (SIGINT ignored, as in the benchmark's worker processes, or a
handler that only takes note), the solve is run again, so an interrupt never becomes a solver
failure. A failure remains only after :data:`SIGINT_RETRIES` interrupted solves in a row.

(:mod:`rmpc.qp.osqp_backend` does the same for OSQP, which catches SIGINT too.)
"""

from __future__ import annotations

import signal
from typing import Any

from cvxpy.reductions.solvers.conic_solvers.scs_conif import SCS

__all__ = ["SCS_SIGINT", "SIGINT_RETRIES", "InterruptibleSCS"]

SCS_SIGINT = -5
"""SCS's status value of a solve its SIGINT handler stopped."""
SIGINT_RETRIES = 3
"""Interrupted solves handed back and run again, in a row, before the last one is reported."""


class InterruptibleSCS(SCS):
    """cvxpy's SCS interface whose interrupted solves hand the SIGINT to the process.

    Passed to ``Problem.solve(solver=InterruptibleSCS())``; cvxpy wants a custom solver to have a
    name of its own (:meth:`name`), the rest is SCS's interface unchanged.
    """

    def name(self) -> str:
        """The solver's name for cvxpy (not ``"SCS"``: cvxpy refuses a custom solver of that name)."""
        return "SCS_SIGINT_AWARE"

    def solve_via_data(self, data: Any, warm_start: bool, verbose: bool, solver_opts: dict[str, Any],
                       solver_cache: Any = None) -> Any:
        """SCS's solve; an interrupted one raises SIGINT in the process, then (if that returns) runs again."""
        results = super().solve_via_data(data, warm_start, verbose, solver_opts, solver_cache)
        for _ in range(SIGINT_RETRIES):
            if int(results["info"]["status_val"]) != SCS_SIGINT:
                break
            signal.raise_signal(signal.SIGINT)  # the default handler raises KeyboardInterrupt here
            results = super().solve_via_data(data, warm_start, verbose, solver_opts, solver_cache)
        return results
