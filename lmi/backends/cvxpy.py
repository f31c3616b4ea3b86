"""cvxpy back-end: the Kothare LMIs written with cvxpy variables, any installed conic solver.

Independent of :mod:`lmi.backends.conic` (a second implementation of the same problem, used
to cross-check it). The problem is built once with parameters for the state and the bounds
(DPP), so a re-solve skips cvxpy's canonicalisation. SCS runs through
:class:`lmi.backends.scs_signal.InterruptibleSCS`, so Ctrl-C during an SCS solve reaches Python
instead of ending the solve as a failure.
"""

from __future__ import annotations

import time
from typing import Any

import cvxpy as cp
import numpy as np

from lmi.backends.base import KothareBackend, RawResult
from lmi.backends.clarabel import DEFAULT_CLARABEL_OPTIONS, clarabel_settings
from lmi.data import KothareData
from lmi.status import CVXPY_STATUS_MAP, SOLVER_ERROR
from toolkit_common.errors import InvalidArgumentError

__all__ = ["SCS_OPTIONS", "CvxpyKothare"]

#: Settings accepted for SCS (scs 3.x).
SCS_OPTIONS = frozenset(
    {
        "max_iters", "eps_abs", "eps_rel", "eps_infeas", "alpha", "scale", "adaptive_scale",
        "normalize", "rho_x", "acceleration_lookback", "acceleration_interval",
        "time_limit_secs", "verbose", "warm_start", "use_indirect",
    }
)
DEFAULT_SCS_OPTIONS: dict[str, Any] = {"eps_abs": 1e-9, "eps_rel": 1e-9, "max_iters": 100_000}


def _solver_options(solver: str, options: dict[str, Any] | None) -> dict[str, Any]:
    options = dict(options or {})
    if solver == "CLARABEL":
        clarabel_settings(options)  # validates names and values
        return {**DEFAULT_CLARABEL_OPTIONS, **options}
    if solver == "SCS":
        unknown = sorted(set(options) - SCS_OPTIONS)
        if unknown:
            raise InvalidArgumentError(
                "solver_options", f"SCS settings ({', '.join(sorted(SCS_OPTIONS))})",
                f"unknown setting(s) {unknown}",
            )
        return {**DEFAULT_SCS_OPTIONS, **options}
    if options:
        raise InvalidArgumentError(
            "solver_options",
            f"no options for solver {solver!r} (only CLARABEL and SCS options are validated)",
            f"{sorted(options)}",
        )
    return {}


class CvxpyKothare(KothareBackend):
    """The Kothare problem through cvxpy, built once and re-solved with new parameters."""

    def __init__(self, data: KothareData, solver: str = "CLARABEL", options: dict[str, Any] | None = None):
        installed = cp.installed_solvers()
        solver = str(solver).upper()
        if solver not in installed:
            raise InvalidArgumentError("solver", f"one of the installed solvers {installed}", repr(solver))
        self.name = f"cvxpy:{solver}"
        self.solver = solver
        # SCS catches SIGINT while it solves: its interface that hands it back (a solver object)
        self.solver_arg: Any = solver
        """What ``Problem.solve(solver=...)`` is given: the name, or SCS's interruptible interface."""
        if solver == "SCS":
            from lmi.backends.scs_signal import InterruptibleSCS

            self.solver_arg = InterruptibleSCS()
        self.options = _solver_options(solver, options)
        self.data = data
        n, m = data.n, data.m
        p = data.Q1h.shape[0]
        self.x = cp.Parameter(n)
        self.Qv = cp.Variable((n, n), symmetric=True)
        self.Yv = cp.Variable((m, n))
        self.gs = cp.Variable()
        q, y, gs = self.Qv, self.Yv, self.gs
        cons = [cp.bmat([[np.ones((1, 1)), cp.reshape(self.x, (1, n), order="C")],
                         [cp.reshape(self.x, (n, 1), order="C"), q]]) >> 0]
        cost_q = q @ data.Q1h.T
        cost_u = y.T @ data.Rh.T
        zn_p, zn_m = np.zeros((n, p)), np.zeros((n, m))
        if data.formulation == "delta_shared":
            w = cp.Variable((n, n), symmetric=True)
            mat = cp.bmat([[w, cost_q, cost_u], [cost_q.T, gs * np.eye(p), np.zeros((p, m))],
                           [cost_u.T, np.zeros((m, p)), gs * np.eye(m)]])
            cons.append(0.5 * (mat + mat.T) >> 0)
            for j in range(data.n_vertices):
                h = ((data.A[j] - np.eye(n)) / data.dt) @ q + (data.B[j] / data.dt) @ y
                mat = cp.bmat([[-(h + h.T) - w, np.sqrt(data.dt) * h.T], [np.sqrt(data.dt) * h, q]])
                cons.append(0.5 * (mat + mat.T) >> 0)
        for j in range(data.n_vertices if data.formulation != "delta_shared" else 0):
            if data.formulation == "standard":
                g = data.A[j] @ q + data.B[j] @ y
                top = [q, g.T, cost_q, cost_u]
                second = [g, q, zn_p, zn_m]
            else:
                h = ((data.A[j] - np.eye(n)) / data.dt) @ q + (data.B[j] / data.dt) @ y
                top = [-(h + h.T), np.sqrt(data.dt) * h.T, cost_q, cost_u]
                second = [np.sqrt(data.dt) * h, q, zn_p, zn_m]
            mat = cp.bmat([top, second, [cost_q.T, zn_p.T, gs * np.eye(p), np.zeros((p, m))],
                           [cost_u.T, zn_m.T, np.zeros((m, p)), gs * np.eye(m)]])
            cons.append(0.5 * (mat + mat.T) >> 0)
        # Bounds as scalings of the off-diagonal blocks (1/u, 1/y_max), as in the Clarabel back-end:
        # [[I, Y/u], [Y'/u, Q]] >= 0 rather than [[u^2 I, Y], [Y', Q]] >= 0.
        self.inv_u = None
        if data.input_constraint == "ellipsoid":
            self.inv_u = cp.Parameter(nonneg=True)
            yu = self.inv_u * y
            cons.append(cp.bmat([[np.eye(m), yu], [yu.T, q]]) >> 0)
        elif data.input_constraint == "peak":
            self.inv_u = cp.Parameter(m, nonneg=True)
            xv = cp.Variable((m, m), symmetric=True)
            yu = cp.multiply(cp.reshape(self.inv_u, (m, 1), order="C"), y)
            cons += [cp.bmat([[xv, yu], [yu.T, q]]) >> 0, cp.diag(xv) <= 1.0]
        self.inv_y = None
        if data.C_out is not None:
            p_out = data.C_out.shape[0]
            self.inv_y = cp.Parameter(p_out, nonneg=True)
            zv = cp.Variable((p_out, p_out), symmetric=True)
            for j in range(data.n_vertices):
                cg = data.C_out @ (data.A[j] @ q + data.B[j] @ y)
                cg = cp.multiply(cp.reshape(self.inv_y, (p_out, 1), order="C"), cg)
                cons.append(cp.bmat([[zv, cg], [cg.T, q]]) >> 0)
            cons.append(cp.diag(zv) <= 1.0)
        self.problem = cp.Problem(cp.Minimize(gs), cons)

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles hold the same problem without the solvers cvxpy cached in it
        (Clarabel's solver does not pickle); the next solve builds them again."""
        state = dict(self.__dict__)
        state["problem"] = cp.Problem(self.problem.objective, self.problem.constraints)
        return state

    def solve(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray) -> RawResult:
        self.x.value = x
        if self.inv_u is not None:
            ellipsoid = self.data.input_constraint == "ellipsoid"
            self.inv_u.value = 1.0 / float(u_max[0]) if ellipsoid else 1.0 / u_max
        if self.inv_y is not None:
            self.inv_y.value = 1.0 / y_max
        start = time.perf_counter()
        try:
            self.problem.solve(solver=self.solver_arg, **self.options)
        except cp.error.SolverError as err:
            return RawResult(SOLVER_ERROR, str(err), np.nan, None, None, None, time.perf_counter() - start)
        elapsed = time.perf_counter() - start
        raw = str(self.problem.status)
        status = CVXPY_STATUS_MAP.get(raw, SOLVER_ERROR)
        if self.Qv.value is None:
            return RawResult(status, raw, np.nan, None, None, None, elapsed)
        gamma = self.gamma(self.gs.value)
        stats = self.problem.solver_stats
        iters = None if stats is None or stats.num_iters is None else int(stats.num_iters)
        q_val, y_val = np.asarray(self.Qv.value), np.asarray(self.Yv.value)
        return RawResult(status, raw, gamma, q_val, y_val, iters, elapsed)
