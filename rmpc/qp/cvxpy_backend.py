"""A reference back-end through cvxpy (for tests and the timing comparison).

The QP is modelled once with cvxpy parameters for the vectors (DPP, so cvxpy caches its
canonicalisation); ``update`` sets parameter values and ``solve`` calls
``Problem.solve``. Each finite bound is one constraint; if an update changes which bounds
are finite or equal, the cvxpy problem is rebuilt. ``solve_time`` includes cvxpy's own
overhead (parameter handling, re-stuffing the solver data), which is what a user who
writes the QP in cvxpy pays per step.

The default solver is Clarabel with tolerances 1e-10: the high-accuracy reference the tests
compare the fast back-ends with.
"""

from __future__ import annotations

import dataclasses
import time
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from rmpc.qp.base import DEFAULT_TIME_LIMIT, BackendSettings, QPBackend
from rmpc.qp.problem import QPResult, SolverResiduals
from toolkit_common.status import Status

if TYPE_CHECKING:  # cvxpy itself is imported on set-up: it costs ~0.5 s at start-up
    import cvxpy as cp

__all__ = ["CvxpyBackend", "CvxpySettings"]


@dataclasses.dataclass(frozen=True)
class CvxpySettings(BackendSettings):
    """Settings of :class:`CvxpyBackend`.

    Attributes
    ----------
    solver : {"CLARABEL", "OSQP"}
        The solver cvxpy calls.
    tol : float
        Tolerance passed to that solver (Clarabel: ``tol_gap_abs``, ``tol_gap_rel``,
        ``tol_feas``; OSQP: ``eps_abs``, ``eps_rel``, with polishing).
    max_iter : int
        Iteration limit passed to the solver.
    time_limit : float
        Bound in seconds on the solver's run, passed to it (Clarabel's and OSQP's
        ``time_limit``; :data:`~rmpc.qp.base.DEFAULT_TIME_LIMIT` by default, ``inf`` for none).
        cvxpy's own work around the solver (parameters, re-stuffing the data: about a
        millisecond per solve at GIPC's size) is not bounded by it. cvxpy reports both limits
        as ``"user_limit"``; the back-end tells them apart by the solver's own status (OSQP)
        or its iteration count (Clarabel: ``max_iter`` reached means the iteration limit).
    verbose : bool
        Let cvxpy and the solver print.
    """

    solver: str = "CLARABEL"
    tol: float = 1e-10
    max_iter: int = 500
    time_limit: float = DEFAULT_TIME_LIMIT
    verbose: bool = False

    _POSITIVE: ClassVar[tuple[str, ...]] = ("tol",)
    _COUNTS: ClassVar[tuple[str, ...]] = ("max_iter",)
    _SECONDS: ClassVar[tuple[str, ...]] = ("time_limit",)
    _FLAGS: ClassVar[tuple[str, ...]] = ("verbose",)
    _CHOICES: ClassVar[dict[str, tuple[str, ...]]] = {"solver": ("CLARABEL", "OSQP")}

    def solver_options(self) -> dict[str, Any]:
        """Keyword arguments for ``Problem.solve``."""
        if self.solver == "CLARABEL":
            return {"tol_gap_abs": self.tol, "tol_gap_rel": self.tol, "tol_feas": self.tol,
                    "max_iter": self.max_iter, "time_limit": float(self.time_limit)}
        return {"eps_abs": self.tol, "eps_rel": self.tol, "polishing": True, "max_iter": self.max_iter,
                "time_limit": min(float(self.time_limit), 1e10)}  # OSQP's "none" is 1e10 s


class CvxpyBackend(QPBackend):
    """The QP modelled and solved through cvxpy (reference and timing baseline).

    Examples
    --------
    >>> import numpy as np
    >>> from rmpc.qp import QP, CvxpyBackend
    >>> be = CvxpyBackend()
    >>> be.setup(QP(H=np.eye(2), g=[-1.0, -1.0], ub=[0.5, 2.0]))
    >>> res = be.solve()
    >>> res.status, np.round(res.x, 7).tolist()
    ('optimal', [0.5, 1.0])
    """

    name = "cvxpy"
    settings_class = CvxpySettings
    STATUS_MAP: ClassVar[dict[Any, Status]] = {
        "optimal": Status.OPTIMAL,
        "optimal_inaccurate": Status.INACCURATE,
        "infeasible": Status.INFEASIBLE,
        "infeasible_inaccurate": Status.INFEASIBLE,
        "unbounded": Status.UNBOUNDED,
        "unbounded_inaccurate": Status.UNBOUNDED,
        "user_limit": Status.MAX_ITERATIONS,  # or TIME_LIMIT: see _user_limit
        "solver_error": Status.NUMERICAL_ERROR,
    }

    def _structure(self) -> tuple[bytes, ...]:
        v = self._vec
        keys = []
        for lo, up in ((v["l"], v["u"]), (v["lb"], v["ub"])):
            eq = np.isfinite(up) & (lo == up)
            keys += [eq.tobytes(), (np.isfinite(up) & ~eq).tobytes(), (np.isfinite(lo) & ~eq).tobytes()]
        return tuple(keys)

    def _setup(self) -> None:
        import cvxpy as cp

        assert self._qp is not None
        qp, v = self._qp, self._vec
        n = qp.n_vars
        self._key = self._structure()
        z = cp.Variable(n)
        self._g = cp.Parameter(n, value=v["g"])
        objective = 0.5 * cp.quad_form(z, cp.psd_wrap(qp.H)) + self._g @ z
        self._groups: list[tuple[str, str, np.ndarray, float, cp.Parameter, cp.Constraint]] = []
        eye = np.eye(n)
        for part, mat, lo_key, up_key in (("C", qp.C, "l", "u"), ("box", eye, "lb", "ub")):
            lo, up = v[lo_key], v[up_key]
            eq = np.isfinite(up) & (lo == up)
            for kind, mask, key in (("eq", eq, up_key), ("up", np.isfinite(up) & ~eq, up_key),
                                    ("lo", np.isfinite(lo) & ~eq, lo_key)):
                idx = np.flatnonzero(mask)
                if idx.size == 0:
                    continue
                par = cp.Parameter(idx.size, value=v[key][idx])
                expr = mat[idx] @ z
                con = expr == par if kind == "eq" else (expr <= par if kind == "up" else expr >= par)
                sign = -1.0 if kind == "lo" else 1.0
                self._groups.append((part, key, idx, sign, par, con))
        self._z = z
        self._problem = cp.Problem(cp.Minimize(objective), [grp[5] for grp in self._groups])

    def _user_limit(self, stats: Any) -> Status:
        """``"time_limit"`` or ``"max_iterations"`` for cvxpy's ``"user_limit"`` (it merges both)."""
        info = getattr(getattr(stats, "extra_stats", None), "info", None)
        if info is not None and hasattr(info, "status_val"):  # OSQP: its own status is kept
            import osqp

            timed_out = int(info.status_val) == int(osqp.SolverStatus.OSQP_TIME_LIMIT_REACHED)
            return Status.TIME_LIMIT if timed_out else Status.MAX_ITERATIONS
        iters = None if stats is None else stats.num_iters
        if iters is not None and iters < self.settings.max_iter:  # Clarabel: stopped short of max_iter
            return Status.TIME_LIMIT
        return Status.MAX_ITERATIONS

    def _update(self, changed: dict[str, np.ndarray]) -> None:
        if {"l", "u", "lb", "ub"} & changed.keys() and self._structure() != self._key:
            self._build()
            return
        if "g" in changed:
            self._g.value = changed["g"]
        for _part, key, idx, _sign, par, _con in self._groups:
            if key in changed:
                par.value = changed[key][idx]

    def _solve(self) -> QPResult:
        import cvxpy as cp

        assert self._qp is not None
        start = time.perf_counter()
        try:
            self._problem.solve(
                solver=self.settings.solver, verbose=self.settings.verbose, **self.settings.solver_options()
            )
        except cp.error.SolverError as err:
            return self._result(
                Status.NUMERICAL_ERROR, f"SolverError: {err}", None, None, None, -1,
                time.perf_counter() - start, SolverResiduals(),
            )
        elapsed = time.perf_counter() - start
        raw = str(self._problem.status)
        status = self.map_status(raw)
        stats = self._problem.solver_stats
        if raw == "user_limit":
            status = self._user_limit(stats)
        n, m = self._qp.n_vars, self._qp.n_cons
        y_c, y_box = np.zeros(m), np.zeros(n)
        if status in (Status.OPTIMAL, Status.INACCURATE):
            for part, _key, idx, sign, _par, con in self._groups:
                target = y_c if part == "C" else y_box
                target[idx] += sign * np.asarray(con.dual_value, dtype=float).reshape(-1)
        iters = stats.num_iters if stats is not None and stats.num_iters is not None else -1
        return self._result(
            status, raw, self._z.value, y_c, y_box, int(iters), elapsed, SolverResiduals(),
            {"solver": self.settings.solver},
        )
