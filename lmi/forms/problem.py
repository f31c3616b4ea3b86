"""A robust MPC form built once over a polytope and solved per state, certified like Kothare's.

:class:`FormProblem` takes the options of :mod:`lmi.forms.options`, lays out the variables and
writes the LMIs of :mod:`lmi.forms.lmis`, and solves them at each state with the toolkit's
interior-point method (:class:`lmi.BlockLMISolver`, warm-started from the previous solve, only the
blocks' constants rewritten per state), with Clarabel as fallback; ``backend="clarabel"`` and
``backend="cvxpy"`` solve the same LMIs with Clarabel's own API or through cvxpy. As in
:class:`lmi.KothareProblem` the problem is solved at ``x / ||x||`` (every LMI is homogeneous of
degree two in the state once the bounds are divided by ``||x||``) and in the diagonal state
coordinates of :func:`lmi.scaling.state_scaling`; the answer is mapped back and certified in the
original coordinates: every block recomputed in numpy at the returned matrices.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy import sparse

from lmi.affine import svec_matrix
from lmi.certificate import Certificate
from lmi.data import InputConstraint, KothareData, build_kothare_data
from lmi.forms.lmis import FormData, lyapunov_count, objective
from lmi.forms.options import FormOptions, form_options
from lmi.forms.program import Layout, Program
from lmi.forms.soft import soft_slacks

# every form's variables and blocks: lmi.forms.lmis's, or with steps (horizon > 1) lmi.forms.steps's
from lmi.forms.steps import declare_form as declare
from lmi.forms.steps import write_form as write
from lmi.infeasibility import InfeasibilityCertificate, check_farkas
from lmi.ipm import BlockLMISolver
from lmi.kothare import MIX_WEIGHTS, KothareProblem, LMISolution
from lmi.scaling import MIN_SPREAD, state_scaling
from lmi.status import (
    CLARABEL_STATUS_MAP,
    CVXPY_STATUS_MAP,
    INACCURATE,
    INFEASIBLE,
    NUMERICAL_ERROR,
    OPTIMAL,
    SOLVER_ERROR,
    UNBOUNDED,
    UNCERTIFIED,
)
from lmi.threads import SingleThreadBlas
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.interrupts import reraise_interrupt
from toolkit_common.validation import as_matrix, as_vector, check_positive

__all__ = ["LAMBDA_GRID", "LAMBDA_STEP", "MAX_COEFFICIENT_BYTES", "FormProblem", "LambdaSearch"]

#: The largest memory the dense block coefficients of a form may take (bytes); a larger form is
#: refused at construction with an error that says its size. The 14-state flexible satellite over 8
#: vertices (3 inputs, peak bound) is estimated at 0.4 GB with ``"vertex"`` (41 blocks, 1184
#: variables), 1.7 GB with ``"vertex_pairs"`` (97 blocks) and 1.5 GB with the auxiliary saturation
#: (76 blocks, 1030 variables).
MAX_COEFFICIENT_BYTES = 4e9

_GOLDEN_RATIO = (1.0 + math.sqrt(5.0)) / 2.0

#: The contraction factors tried first when the disturbance form searches ``lam``; the best is
#: then refined by :data:`LAMBDA_REFINE` golden-section steps inside its neighbours' interval.
#: The last three serve slowly contracting loops (fast sampling): with the grid ending at 0.98,
#: Kothare's example 2 (certified from 0.99), paper P's satellite at ``dt = 0.01`` s (from 0.995;
#: gamma 75.6 at 0.9995) and its attitude hold were reported infeasible at every ``lam`` tried.
LAMBDA_GRID: tuple[float, ...] = (0.05, 0.15, 0.3, 0.45, 0.6, 0.75, 0.85, 0.93, 0.98, 0.995, 0.999, 0.9997)
LAMBDA_REFINE = 8

#: The warm search's step (``solver_options={"lambda_search": "warm"}``, the default; at a state
#: after one with a certified answer) in the log-odds ``t = log(lam / (1 - lam))``: the longest
#: first step downhill from the previous ``lam`` with slopes, the bracket's half-width without
#: (0.3: ``lam`` 0.6 +- 0.07, 0.98 +- 0.005); also the scale of the flat-slope test
#: (``|slope| LAMBDA_STEP <= LAMBDA_FLAT |objective|``).
LAMBDA_STEP = 0.3
#: While the minimum is not bracketed: at most this many steps beyond the first, each
#: :data:`LAMBDA_GROW` times the one before (the golden ratio, the classic expansion); then the
#: full search.
LAMBDA_EXPAND = 3
LAMBDA_GROW = _GOLDEN_RATIO
#: The most secant (with slopes) or parabolic (without) steps inside the bracket.
LAMBDA_WARM_REFINE = 4
#: No step shorter than this (in ``t``): the shortest Newton step; a parabolic step shorter than
#: this is not taken, nor one where the best solve's neighbours are within :data:`LAMBDA_FLAT`
#: (relative) of its objective, nor another after a step that landed within it of the best: the
#: search has converged (or lies on a plateau of the objective); nor a Newton step whose model
#: (the previous search's curvature) gains less than :data:`LAMBDA_FLAT`: on paper W's disturbance
#: form that model predicted gains of 5.4e-7 to 6.2e-7 relative at each state of its closed loop,
#: the step then taken gained 5.4e-7 to 6.2e-7, a second solve per state for each.
LAMBDA_TOL = 1e-3
LAMBDA_FLAT = 1e-6
_LAMBDA_SEARCHES = ("warm", "grid")

_BACKENDS = ("ipm", "clarabel", "cvxpy")
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


@dataclasses.dataclass(frozen=True)
class LambdaSearch:
    """What the last search for the disturbance form's contraction factor did.

    ``lams``: the values solved, in order (each one solve); ``how``: ``"warm"`` (the search from
    the previous state's ``lam`` sufficed) or ``"grid"`` (the full search); ``fallback``: why the
    warm search did not suffice, when it was tried.
    """

    lams: tuple[float, ...]
    how: str
    fallback: str | None = None

    @property
    def solves(self) -> int:
        """The number of solves (one per ``lam``)."""
        return len(self.lams)


class _LambdaSearch:
    """The solves of one search for ``lam``: each value solved once, its objective ``inf`` unless
    certified, the time and iterations summed."""

    def __init__(self, solve: Any, objective: Any, slots: bool) -> None:
        self._solve, self._objective, self._slots = solve, objective, slots
        self.tried: dict[float, LMISolution] = {}
        self.values: dict[float, float] = {}
        #: d objective / d t (``t = log(lam / (1 - lam))``) of each certified solve that has one
        self.slopes: dict[float, float | None] = {}
        self.time, self.iterations = 0.0, 0
        #: where the next state's warm search starts, when not at this search's answer
        self.next_start: float | None = None

    def value(self, lam: float, keep: bool = False, slot: str | None = None) -> float:
        """The objective at ``lam`` (a solve unless done); ``keep`` the solver of this ``lam``, or
        the ipm's ``slot`` retuned from the lam it last solved."""
        if lam not in self.values:
            slot = slot if self._slots else None
            sol, slope = self._solve(lam, keep or slot is not None, slot)
            self.tried[lam] = sol
            self.time += sol.solve_time
            self.iterations += sol.iterations or 0
            self.values[lam] = self._objective(sol) if sol.ok else math.inf
            self.slopes[lam] = None if slope is None or not sol.ok else slope * lam * (1.0 - lam)
        return self.values[lam]


class _Solved:
    """One solver's answer in the solver's coordinates (``z``), or none."""

    def __init__(self, status: str, solver_status: str, z: np.ndarray | None, iterations: int | None,
                 solve_time: float, infeasibility: InfeasibilityCertificate | None = None,
                 point: np.ndarray | None = None) -> None:
        self.status, self.solver_status, self.z = status, solver_status, z
        self.iterations, self.solve_time = iterations, solve_time
        self.infeasibility = infeasibility
        #: phase one's strictly feasible point (solver's coordinates), when it found one
        self.point = point
        #: that point's variables in the original coordinates (kept across a rebalanced retry)
        self.interior: dict[str, np.ndarray] | None = None
        #: the answer's variables in the original coordinates, when they are given rather than ``z``
        self.values: dict[str, np.ndarray] | None = None
        #: d(c'z)/d lam at the ipm's own optimum (its dual), with a disturbance; ``None`` otherwise
        self.slope: float | None = None


class FormProblem:
    """One robust MPC form over a polytope ``Co{[A_j B_j]}``: ``min`` its cost bound at a state.

    Parameters
    ----------
    A, B, Q, R, dt, input_constraint, u_max, output_matrix, y_max
        As for :class:`lmi.KothareProblem` (checked the same way).
    nominal : (A0, B0), optional
        The nominal model, needed by ``cost="nominal"``.
    lyapunov, cost, free_moves, saturation, soft, disturbance, unsaturated_weight
        The form (:func:`lmi.forms.options.form_options`; the LMIs: the page "The field's robust
        MPC forms" of the docs).
    backend : {"ipm", "clarabel", "cvxpy"}
        The toolkit's interior-point method (default; Clarabel when it fails, option
        ``fallback``), Clarabel's own API, or cvxpy with Clarabel (the same LMIs, the reference).
    solver_options : dict, optional
        For ``"ipm"``: ``fallback`` (bool, default true), ``warm_start`` (bool, default true),
        ``state_scaling`` (bool, default true), ``phase_one`` (bool, default true: a failed solve
        runs :meth:`lmi.BlockLMISolver.phase_one`, whose checked Farkas certificate makes it
        ``"infeasible"``, before the fallback), ``rebalance`` (bool, default true: a failed solve
        is retried cold in coordinates balanced on its last Lyapunov matrix, kept for the next
        solves) and :class:`lmi.BlockLMISolver`'s settings
        (``tol_feas``, ``max_iter``, ...). For ``"clarabel"``/``"cvxpy"``: Clarabel's settings.
        Every back-end: ``lambda_search`` (``"warm"``, the default, or ``"grid"``), how the
        disturbance form searches its contraction factor (the page "The field's robust MPC forms").
    certificate_tol : float
        A solve is ``"optimal"`` only if every recomputed block's relative margin is ``>= -tol``.
    horizon, step_gains
        The forms with steps (:mod:`lmi.forms.steps`): ``horizon`` steps with gains of their own
        (Shi, Su & Chu 2013), or ``horizon=2, step_gains="vertex"`` (Li, Shi, Sun & Wang 2008);
        the answer's ``F``, ``Q``, ``Y`` are the first step's.

    Examples
    --------
    Kothare's example 2 (two masses and a spring whose constant lies in [0.5, 10]) with one
    Lyapunov matrix per vertex:

    >>> import numpy as np
    >>> from lmi.forms import FormProblem
    >>> def plant(k):
    ...     return [[1, 0, .1, 0], [0, 1, 0, .1], [-.1 * k, .1 * k, 1, 0], [.1 * k, -.1 * k, 0, 1]]
    >>> prob = FormProblem([plant(0.5), plant(10.0)], [[[0], [0], [.1], [0]]] * 2, Q=np.eye(4),
    ...                    R=[[1.0]], u_max=1.0, lyapunov="vertex")
    >>> sol = prob.solve([1.0, 1.0, 0.0, 0.0])
    >>> sol.status, round(sol.gamma, 2), len(sol.Q_vertices)
    ('optimal', 200.36, 2)
    """

    def __init__(
        self,
        A: ArrayLike,
        B: ArrayLike,
        Q: ArrayLike,
        R: ArrayLike,
        *,
        dt: float = 1.0,
        input_constraint: InputConstraint = "ellipsoid",
        u_max: ArrayLike | None = None,
        output_matrix: ArrayLike | None = None,
        y_max: ArrayLike | None = None,
        nominal: tuple[ArrayLike, ArrayLike] | None = None,
        lyapunov: str = "common",
        cost: str = "worst_case",
        free_moves: int = 0,
        saturation: str | None = None,
        soft: dict[str, float] | None = None,
        disturbance: Any = None,
        unsaturated_weight: float | None = None,
        backend: str = "ipm",
        solver_options: dict[str, Any] | None = None,
        certificate_tol: float = 1e-7,
        horizon: int = 1,
        step_gains: str = "common",
    ) -> None:
        self.data: KothareData = build_kothare_data(
            A, B, Q, R, dt=dt, input_constraint=input_constraint, u_max=u_max,
            output_matrix=output_matrix, y_max=y_max, formulation="standard",
        )
        data = self.data
        self.options: FormOptions = form_options(
            n_states=data.n, input_constraint=data.input_constraint, has_output=data.C_out is not None,
            lyapunov=lyapunov, cost=cost, free_moves=free_moves, saturation=saturation, soft=soft,
            disturbance=disturbance, horizon=horizon, step_gains=step_gains,
            unsaturated_weight=unsaturated_weight, n_inputs=data.m,
            n_outputs=None if data.C_out is None else data.C_out.shape[0],
        )
        if backend not in _BACKENDS:
            raise InvalidArgumentError("backend", "'ipm', 'clarabel' or 'cvxpy'", repr(backend))
        self.backend = backend
        self.certificate_tol = check_positive(certificate_tol, "certificate_tol")
        self._nominal = self._check_nominal(nominal)
        self._settings = self._check_settings(solver_options)
        dist = self.options.disturbance
        self._E = None if dist is None else dist.E
        if self._E is not None and data.C_out is not None:
            tight = data.y_max - np.linalg.norm(data.C_out @ self._E, axis=1) * dist.w_max
            if np.any(tight <= 0.0):
                raise InvalidArgumentError(
                    "disturbance, y_max",
                    "output bounds larger than the disturbance's own reach ||c_r E|| w_max",
                    f"y_max - ||C E|| w_max = {tight.tolist()}",
                )
        # the nesting block's Q_outer / ||x||^2 of the solve under way (set by every solve)
        self._q_outer: np.ndarray | None = None
        # ||x|| of the solve under way: the soft limits (soft["u_limit"], "y_limit") are divided by it
        self._scale = 1.0
        self._check_limits()
        use_scaling = self._settings.pop("state_scaling", True) if backend == "ipm" else False
        self._t = state_scaling(data) if use_scaling else np.ones(data.n)
        self._t0 = self._t  # a rebalanced retry replaces _t; reset() restores this
        template = self._form_data(np.ones(data.n), data.u_max, data.y_max, 0.0, 1.0)
        self.layout: Layout = declare(self.options, template)
        self._c = objective(self.options, self.layout)
        self._check_size(template)
        self._solvers: dict[tuple, Any] = {}
        self._blas = SingleThreadBlas()
        # the disturbance form's search: the last answer's lam (the next warm search's start), the
        # derivative in lam of the blocks it enters (per coordinates) and what the last search did
        self._lam_prev: float | None = None
        self._lam_derivative: tuple[bytes, dict[str, np.ndarray], dict[str, np.ndarray]] | None = None
        # d objective / d lam at the last _solve_at's answer (None unless the ipm's own optimum)
        self._last_slope: float | None = None
        # the last warm search's curvature of the objective in t, relative to it (a Newton step)
        self._lam_curvature: float | None = None
        self.last_lambda_search: LambdaSearch | None = None

    # -- checks ----------------------------------------------------------------------------
    def _check_size(self, template: FormData) -> None:
        """Refuse a form whose dense block coefficients would not fit in :data:`MAX_COEFFICIENT_BYTES`
        (the blocks are held as dense ``(n_vars + 1, k, k)`` arrays, about three copies of each)."""
        orders = [b.shape[0] for b in write(Program(self.layout, {}), self.options, template).blocks.values()]
        need = 3.0 * 8.0 * (self.layout.size + 1) * sum(k * k for k in orders)
        if need > MAX_COEFFICIENT_BYTES:
            # name what was given (the plant's vertices, the options set), never an option at its default
            given = {} if self.options.lyapunov == "common" else {"lyapunov": self.options.lyapunov}
            given.update({} if self.options.saturation is None else {"saturation": self.options.saturation})
            given.update({"horizon": self.options.horizon} if self.options.has_steps else {})
            remedies = ["fewer vertices"] + ["lyapunov='common'"] * ("lyapunov" in given)
            remedies += ["no auxiliary saturation"] * ("saturation" in given)
            remedies += ["a shorter horizon"] * ("horizon" in given)
            options = "".join(f", {key}={value!r}" for key, value in given.items())
            raise InvalidArgumentError(
                ", ".join(["plant", *given]),
                f"a form whose LMIs fit in {MAX_COEFFICIENT_BYTES / 1e9:g} GB as dense coefficients "
                f"({', '.join(remedies)})",
                f"{template.n_vertices} vertices{options}: {len(orders)} blocks of orders up to "
                f"{max(orders)} in {self.layout.size} variables, about {need / 1e9:.1f} GB",
            )

    def _check_limits(self) -> None:
        """Output soft limits larger than the disturbance's own reach (they are tightened by it as
        the hard output bounds are)."""
        soft = self.options.soft or {}
        if self._E is None or self.data.C_out is None or "y_limit" not in soft:
            return
        reach = np.linalg.norm(self.data.C_out @ self._E, axis=1) * self.options.disturbance.w_max
        tight = np.asarray(soft["y_limit"]) - reach
        if np.any(tight <= 0.0):
            raise InvalidArgumentError(
                "disturbance, soft['y_limit']",
                "output soft limits larger than the disturbance's own reach ||c_r E|| w_max",
                f"y_limit - ||C E|| w_max = {tight.tolist()}",
            )

    def _check_nominal(self, nominal: Any) -> tuple[np.ndarray, np.ndarray] | None:
        n, m = self.data.n, self.data.m
        if nominal is None:
            if self.options.cost == "nominal":
                expected = "the nominal model (A0, B0) with cost='nominal'"
                raise InvalidArgumentError("nominal", expected, "None")
            return None
        if not isinstance(nominal, tuple | list) or len(nominal) != 2:
            raise InvalidArgumentError("nominal", "an (A0, B0) pair", type(nominal).__name__)
        return as_matrix(nominal[0], "nominal A", (n, n)), as_matrix(nominal[1], "nominal B", (n, m))

    def _check_settings(self, options: dict[str, Any] | None) -> dict[str, Any]:
        if options is not None and not isinstance(options, dict):
            raise InvalidArgumentError("solver_options", "a dict of solver settings", type(options).__name__)
        opts = dict(options or {})
        search = opts.pop("lambda_search", "warm")  # the disturbance form's search, every back-end
        if not isinstance(search, str) or search not in _LAMBDA_SEARCHES:
            raise InvalidArgumentError("solver_options['lambda_search']", "'warm' or 'grid'", repr(search))
        self._lambda_search: str = search
        if self.backend == "ipm":
            known = {"fallback", "warm_start", "state_scaling", "phase_one", "rebalance", "lambda_search",
                     "tol_feas", "tol_gap_abs", "tol_gap_rel", "max_iter", "warm_max_iter", "warm_gap",
                     "warm_feas", "infeasibility_radius"}
            unknown = sorted(set(opts) - known)
            if unknown:
                raise InvalidArgumentError("solver_options", f"settings among {sorted(known)}",
                                           f"unknown setting(s) {unknown}")
            merged: dict[str, Any] = {"fallback": True, "warm_start": True, "state_scaling": True,
                                      "phase_one": True, "rebalance": True, "tol_gap_abs": 1e-12,
                                      "max_iter": 100}
            merged.update(opts)
            from lmi.backends.ipm import check_ipm_values

            return check_ipm_values(merged)  # the values: the one check Kothare's problem uses too
        from lmi.backends.clarabel import clarabel_settings

        clarabel_settings(opts)  # unknown names raise here
        return opts

    # -- the data of one solve ----------------------------------------------------------------
    def _form_data(self, x: np.ndarray, u_max: np.ndarray, y_max: np.ndarray, w_max: float, lam: float,
                   t: np.ndarray | None = None) -> FormData:
        """The LMIs' numbers in the coordinates ``x = T x~`` (``T = diag(t)``)."""
        data = self.data
        t = _as_matrix(self._t if t is None else t)
        ti = np.linalg.inv(t)
        a = ti @ data.A @ t
        b = ti @ data.B
        a0 = b0 = None
        if self._nominal is not None:
            a0 = ti @ self._nominal[0] @ t
            b0 = ti @ self._nominal[1]
        y_tight = y_max
        if self._E is not None and data.C_out is not None:
            y_tight = y_max - np.linalg.norm(data.C_out @ self._E, axis=1) * w_max
        q_outer = self._q_outer
        soft = self.options.soft or {}
        u_limit = y_limit = None
        if "u_limit" in soft:
            u_limit = np.asarray(soft["u_limit"], dtype=float) / self._scale
        if "y_limit" in soft and data.C_out is not None:
            y_limit = np.asarray(soft["y_limit"], dtype=float) / self._scale
            if self._E is not None:
                y_limit = y_limit - np.linalg.norm(data.C_out @ self._E, axis=1) * w_max
        return FormData(
            u_limit=u_limit, y_limit=y_limit,
            q_outer=None if q_outer is None else ti @ q_outer @ ti.T,
            A=a, B=b, A0=a0, B0=b0, Q1h=data.Q1h @ t, Rh=data.Rh,
            input_constraint=data.input_constraint,
            C_out=None if data.C_out is None else data.C_out @ t,
            E=None if self._E is None else ti @ self._E,
            x=ti @ x, u_max=u_max, y_max=y_tight, w_max=w_max, lam=lam, dt=data.dt,
        )

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles leave the solvers built so far behind (cvxpy's and Clarabel's do not
        pickle); the next solve builds them again, as after :meth:`reset` but in the same
        coordinates."""
        state = dict(self.__dict__)
        state["_solvers"] = {}
        state["_lam_prev"] = state["_lam_curvature"] = None
        return state

    # -- solve ---------------------------------------------------------------------------------
    def reset(self) -> None:
        """Forget the solvers built so far (their warm starts) and any rebalanced coordinates: the
        next solve gives what a freshly built problem gives."""
        self._solvers.clear()
        self._t = self._t0
        self._lam_prev = None
        self._lam_curvature = None

    def solve(self, x: ArrayLike, u_max: ArrayLike | None = None, q_outer: ArrayLike | None = None
              ) -> LMISolution:
        """Solve at the state ``x`` (non-zero); failures come back as a status, never raised.

        ``q_outer``: with the common Lyapunov function, also ``Q_outer - Q >= 0`` (the off-line
        design's nesting, :class:`lmi.offline.NestedKothareProblem`; certified as the block
        ``"nesting"``).
        """
        x = as_vector(x, "x", self.data.n)
        if q_outer is not None:
            if self.options.lyapunov != "common":
                raise InvalidArgumentError("q_outer", "None unless lyapunov='common'", "a matrix")
            q_outer = as_matrix(q_outer, "q_outer", (self.data.n, self.data.n))
        scale = float(np.linalg.norm(x))
        if scale == 0.0:
            expected = "a non-zero state (the problem is degenerate at the origin)"
            raise InvalidArgumentError("x", expected, "x = 0")
        bound = self.data.u_max if u_max is None else self.input_bound(u_max)
        xs, us, ys = x / scale, bound / scale, self.data.y_max / scale
        self._q_outer = None if q_outer is None else 0.5 * (q_outer + q_outer.T) / scale**2
        self._scale = scale
        dist = self.options.disturbance
        w_max = 0.0 if dist is None else dist.w_max / scale
        if w_max > 0.0 and dist is not None and dist.lam is None:
            return self._search_lambda(x, scale, xs, us, ys, w_max)
        lam = 1.0 if w_max == 0.0 or dist is None or dist.lam is None else dist.lam
        return self._solve_at(x, scale, xs, us, ys, w_max, lam)

    def input_bound(self, u_max: ArrayLike) -> np.ndarray:
        """``u_max`` checked as an input bound of this problem's kind (as
        :meth:`lmi.KothareProblem.input_bound`)."""
        return KothareProblem.input_bound(self, u_max)  # type: ignore[arg-type]

    def _search_lambda(self, x: np.ndarray, scale: float, xs: np.ndarray, us: np.ndarray, ys: np.ndarray,
                       w_max: float) -> LMISolution:
        """The contraction factor with the smallest certified bound: the warm search from the
        previous state's ``lam`` (:meth:`_warm_bracket`), else the full search (the grid, then
        golden section); :attr:`last_lambda_search` records the ``lam`` solved and why."""
        def solve(lam: float, keep: bool, slot: str | None) -> tuple[LMISolution, float | None]:
            sol = self._solve_at(x, scale, xs, us, ys, w_max, lam, keep=keep, slot=slot)
            return sol, self._last_slope  # the objective's d/d lam at that answer, when known

        search = _LambdaSearch(solve, self._objective, self.backend == "ipm")
        fallback = None
        if self._lambda_search == "warm" and self._lam_prev is not None:
            fallback = self._warm_bracket(search, self._lam_prev)
            if fallback is None:
                return self._searched(search, "warm", None)
        grid = [search.value(lam, keep=True) for lam in LAMBDA_GRID]
        best = int(np.argmin(grid))
        if np.isfinite(grid[best]):
            lo = LAMBDA_GRID[best - 1] if best > 0 else 0.5 * LAMBDA_GRID[0]
            hi = LAMBDA_GRID[best + 1] if best + 1 < len(LAMBDA_GRID) else 0.5 * (1.0 + LAMBDA_GRID[-1])
            c = hi - _GOLDEN * (hi - lo)
            d = lo + _GOLDEN * (hi - lo)
            # the grid's solvers are kept (warm starts at the next state); the refinement's are not
            fc, fd = search.value(c), search.value(d)
            for _ in range(LAMBDA_REFINE - 2):
                if fc < fd:
                    hi, d, fd = d, c, fc
                    c = hi - _GOLDEN * (hi - lo)
                    fc = search.value(c)
                else:
                    lo, c, fc = c, d, fd
                    d = lo + _GOLDEN * (hi - lo)
                    fd = search.value(d)
        return self._searched(search, "grid", fallback, LAMBDA_GRID[best])

    def _warm_bracket(self, search: _LambdaSearch, prev: float) -> str | None:
        """The warm search from the previous state's ``lam``, in the log-odds ``t = log(lam / (1 -
        lam))`` and inside the full search's range of ``lam``: with the slope of the solve at
        ``prev`` (:meth:`_warm_slopes`), else by values alone (:meth:`_warm_values`). ``None``
        when it found the minimum, otherwise why not (the full search follows). All its solves
        run in one kept ipm solver retuned to each ``lam`` and warm-started from the solve before
        (the first from the previous state's last)."""
        t_min, t_max = _logit(0.5 * LAMBDA_GRID[0]), _logit(0.5 * (1.0 + LAMBDA_GRID[-1]))
        t0 = min(max(_logit(prev), t_min), t_max)
        lam0 = _expit(t0)
        if not np.isfinite(search.value(lam0, slot="warm")):
            return f"no certified answer at the previous lam {prev:.6g}"
        if search.slopes[lam0] is not None:
            return self._warm_slopes(search, t0, t_min, t_max)
        return self._warm_values(search, t0, t_min, t_max)

    def _warm_slopes(self, search: _LambdaSearch, t0: float, t_min: float, t_max: float) -> str | None:
        """With slopes (the dual's ``d objective / d t``). A solve whose slope is flat (``|slope|
        LAMBDA_STEP <= LAMBDA_FLAT |objective|``, :data:`LAMBDA_STEP`, :data:`LAMBDA_FLAT`) ends
        the search, and so does one whose Newton step on the previous search's curvature would
        gain less than :data:`LAMBDA_FLAT` (relative; ``g0^2 / (2 c |f0|) <= LAMBDA_FLAT |f0|``,
        ``c`` that curvature relative to the objective; the next state then starts at that step's
        end). Otherwise steps downhill: the first a Newton step on the previous search's
        curvature (between :data:`LAMBDA_TOL` and :data:`LAMBDA_STEP`; the latter without one), each next
        :data:`LAMBDA_GROW` times longer (at most :data:`LAMBDA_EXPAND` more), until the slope
        turns or the objective rises; then up to :data:`LAMBDA_WARM_REFINE` secant steps on the
        slope inside that bracket, until the best solve's slope times the bracket's width is
        flat. Keeps the curvature (relative to the objective) for the next state."""
        f0, g0 = search.values[_expit(t0)], search.slopes[_expit(t0)]
        assert g0 is not None
        curvature = self._lam_curvature

        def flat(lam: float) -> bool:
            slope = search.slopes.get(lam)
            return slope is not None and abs(slope) * LAMBDA_STEP <= LAMBDA_FLAT * abs(search.values[lam])

        if flat(_expit(t0)):
            return None
        if curvature is not None and g0 * g0 <= 2.0 * LAMBDA_FLAT * curvature * f0 * f0:
            # the previous search's quadratic model ``f0 + g0 dt + curvature |f0| dt^2 / 2`` puts the
            # minimum less than LAMBDA_FLAT (relative) below f0: no step would gain more than that.
            # The next state starts at the model's minimum (the minimum drifts with the state: from
            # the same lam again, the gain the next model predicts grows)
            search.next_start = _expit(min(max(t0 - g0 / (curvature * abs(f0)), t_min), t_max))
            return None
        way = -1.0 if g0 > 0.0 else 1.0
        step = LAMBDA_STEP
        if curvature is not None:
            step = min(max(abs(g0) / (curvature * abs(f0)), LAMBDA_TOL), LAMBDA_STEP)
        t_a, f_a, g_a = t0, f0, g0
        for _ in range(LAMBDA_EXPAND + 1):
            t_b = min(max(t_a + way * step, t_min), t_max)
            if t_b == t_a:
                return "the minimum at an end of the range of lam"
            f_b = search.value(_expit(t_b), slot="warm")
            g_b = search.slopes.get(_expit(t_b))
            if not np.isfinite(f_b) or g_b is None:
                return "no certified answer (with its slope) on the way down from the previous lam"
            if flat(_expit(t_b)) and f_b <= f_a:
                return None
            if g_b * way >= 0.0 or f_b > f_a:
                break  # the slope turned, or the objective rose: a minimum between t_a and t_b
            t_a, f_a, g_a, step = t_b, f_b, g_b, step * LAMBDA_GROW
        else:
            return f"no interior minimum after {LAMBDA_EXPAND} steps beyond the bracket"
        (t_lo, g_lo), (t_hi, g_hi) = sorted([(t_a, g_a), (t_b, g_b)])
        for _ in range(LAMBDA_WARM_REFINE):
            lam_best = min(search.values, key=search.values.__getitem__)
            f_best, g_best = search.values[lam_best], search.slopes[lam_best]
            if g_best is not None and abs(g_best) * (t_hi - t_lo) <= LAMBDA_FLAT * abs(f_best):
                break
            t_new = t_lo - g_lo * (t_hi - t_lo) / (g_hi - g_lo) if g_lo < 0.0 < g_hi else 0.5 * (t_lo + t_hi)
            if not t_lo < t_new < t_hi:
                t_new = 0.5 * (t_lo + t_hi)
            search.value(_expit(t_new), slot="warm")
            g_new = search.slopes.get(_expit(t_new))
            if g_new is None:
                break  # not certified inside a bracket of certified ends: keep the best found
            if g_new < 0.0:
                t_lo, g_lo = t_new, g_new
            else:
                t_hi, g_hi = t_new, g_new
        f_best = min(search.values.values())
        if g_hi > g_lo and f_best != 0.0:
            self._lam_curvature = (g_hi - g_lo) / ((t_hi - t_lo) * abs(f_best))
        return None

    @staticmethod
    def _warm_values(search: _LambdaSearch, t0: float, t_min: float, t_max: float) -> str | None:
        """By values alone: :data:`LAMBDA_STEP` either side of ``t0``; while the best is at an end,
        up to :data:`LAMBDA_EXPAND` steps beyond it, each :data:`LAMBDA_GROW` times the last
        interval; then up to :data:`LAMBDA_WARM_REFINE` parabolic steps in ``t`` through the best
        solve and its neighbours (fewer once converged, :data:`LAMBDA_TOL`, :data:`LAMBDA_FLAT`)."""
        for side, t_side in (("lo", max(t0 - LAMBDA_STEP, t_min)), ("hi", min(t0 + LAMBDA_STEP, t_max))):
            if t_side != t0 and not np.isfinite(search.value(_expit(t_side), slot="warm")):
                return f"no certified answer at the {side} side of the bracket"
        for step in range(LAMBDA_EXPAND + 1):
            points = sorted((_logit(lam), f) for lam, f in search.values.items())
            k = min(range(len(points)), key=lambda i: points[i][1])
            if 0 < k < len(points) - 1:
                break
            if step == LAMBDA_EXPAND:
                return f"no interior minimum after {LAMBDA_EXPAND} steps beyond the bracket"
            inner = points[1 if k == 0 else -2][0]
            t_new = min(max(points[k][0] + LAMBDA_GROW * (points[k][0] - inner), t_min), t_max)
            if t_new == points[k][0]:
                return "the minimum at an end of the range of lam"
            if not np.isfinite(search.value(_expit(t_new), slot="warm")):
                return "no certified answer beyond the bracket"
        for _ in range(LAMBDA_WARM_REFINE):
            points = sorted((_logit(lam), f) for lam, f in search.values.items())
            k = min(range(len(points)), key=lambda i: points[i][1])
            best = points[k][1]
            if max(points[k - 1][1], points[k + 1][1]) - best <= LAMBDA_FLAT * abs(best):
                break  # flat around the best: a parabola's vertex would gain less than that
            t_new = _parabola_vertex(points[k - 1], points[k], points[k + 1])
            if abs(t_new - points[k][0]) < LAMBDA_TOL:
                break
            if abs(search.value(_expit(t_new), slot="warm") - best) <= LAMBDA_FLAT * abs(best):
                break  # as good as the best and no better: converged, or on a plateau
        return None

    def _searched(self, search: _LambdaSearch, how: str, fallback: str | None,
                  grid_best: float | None = None) -> LMISolution:
        """The search's answer: the certified solve with the smallest objective, with the whole
        search's time and iterations; keeps its ``lam`` (or the search's ``next_start``) for the
        next state's warm search."""
        tried = search.tried
        self.last_lambda_search = LambdaSearch(tuple(tried), how, fallback)
        certified = [s for s in tried.values() if s.ok]
        if certified:
            pick = min(certified, key=self._objective)
            self._lam_prev = pick.lam if search.next_start is None else search.next_start
            return dataclasses.replace(pick, solve_time=search.time, iterations=search.iterations)
        self._lam_prev = None
        assert grid_best is not None  # the warm search falls back to the grid when nothing certifies
        pick = tried[grid_best]
        if all(s.status == INFEASIBLE for s in tried.values()):
            # each proof holds for its own lam: the LMIs are bilinear in lam, so the grid's proofs
            # say nothing of the lam between them (give lam to decide one value)
            word = (f"{pick.solver_status} (proved infeasible at each of the {len(tried)} lam tried, "
                    "not for the lam between them)")
        else:
            word = f"{pick.solver_status} (no certified answer at any of the {len(tried)} lam tried)"
        return dataclasses.replace(pick, solve_time=search.time, iterations=search.iterations,
                                   solver_status=word, lam=grid_best)

    def _objective(self, sol: LMISolution) -> float:
        """The minimised objective: the cost bound plus the soft constraints' penalties."""
        slack = sol.slack or {}
        return sol.gamma + sum(s.weight * slack.get(s.key, 0.0) for s in soft_slacks(self.options.soft))

    def _solve_at(self, x: np.ndarray, scale: float, xs: np.ndarray, us: np.ndarray, ys: np.ndarray,
                  w_max: float, lam: float, keep: bool = True, slot: str | None = None) -> LMISolution:
        """One solve at the contraction factor ``lam``; ``slot`` names a kept ipm solver that the
        warm search retunes from ``lam`` to ``lam`` (``None``: the solver kept for this ``lam``)."""
        self._last_slope = None
        fd = self._form_data(xs, us, ys, w_max, lam)
        if self.backend == "ipm":
            solved = self._solve_ipm(fd, keep, phase_one=False, slot=slot)
            t_new = self._rebalanced(solved, xs) if solved.status not in (OPTIMAL, INFEASIBLE) else None
            if t_new is None and solved.status not in (OPTIMAL, INFEASIBLE):
                solved = self._phase_one(fd, solved, slot)
            elif t_new is not None:
                # retry cold in coordinates balanced on the failed run's Q; kept for the next solves
                first, self._t = solved, t_new
                self._solvers.clear()
                fd = self._form_data(xs, us, ys, w_max, lam)
                solved = self._solve_ipm(fd, keep, slot=slot)
                solved.solve_time += first.solve_time
                solved.iterations = (solved.iterations or 0) + (first.iterations or 0)
                solved.solver_status = f"{first.solver_status}; rebalanced {solved.solver_status}"
            proved = solved.infeasibility is not None and solved.infeasibility.ok
            if solved.status not in (OPTIMAL, INFEASIBLE) and self._settings["phase_one"]:
                solved, fd = self._settle(solved, fd, xs, us, ys, w_max, lam, slot)
                proved = solved.infeasibility is not None and solved.infeasibility.ok
            if solved.status != OPTIMAL and not proved and self._settings["fallback"]:
                first = solved
                solved = self._solve_clarabel(fd)
                solved.solve_time += first.solve_time
                solved.solver_status = f"ipm:{first.solver_status}; clarabel:{solved.solver_status}"
                solved.interior = first.interior
            if solved.interior is not None and (solved.z is None or not np.all(np.isfinite(solved.z))):
                solved = self._point_answer(solved)
        elif self.backend == "clarabel":
            solved = self._solve_clarabel(fd)
        else:
            solved = self._solve_cvxpy(fd, keep)
        if solved.slope is not None and solved.values is None:
            self._last_slope = scale**2 * solved.slope  # the objective is ||x||^2 c'z
        return self._finish(solved, x, scale, xs, us, ys, w_max, lam)

    def _settle(self, solved: _Solved, fd: FormData, xs: np.ndarray, us: np.ndarray, ys: np.ndarray,
                w_max: float, lam: float, slot: str | None = None) -> tuple[_Solved, FormData]:
        """A failed ipm solve (phase one done) settled as :meth:`lmi.KothareProblem.solve` settles
        Kothare's problem: if phase one was inconclusive, once more in coordinates balanced on the
        last failed run, with phase one again; if phase one found a strictly
        feasible point, a cold retry in coordinates balanced on that point, which is kept
        (``interior``) for :meth:`_finish` to mix into an optimum whose certificate fails or to
        give as the answer. Returns the answer and the form data of the coordinates it is in."""
        if solved.point is None:
            t_new = self._rebalanced(solved, xs)
            if t_new is not None:
                first, self._t = solved, t_new
                self._solvers.clear()
                fd = self._form_data(xs, us, ys, w_max, lam)
                solved = self._solve_ipm(fd, slot=slot)
                solved.solve_time += first.solve_time
                solved.iterations = (solved.iterations or 0) + (first.iterations or 0)
                solved.solver_status = f"{first.solver_status}; rebalanced {solved.solver_status}"
                if solved.status in (OPTIMAL, INFEASIBLE):
                    return solved, fd
        if solved.point is None:
            return solved, fd
        interior = self._original(self.layout.values(solved.point))
        solved.interior = interior
        t_new = self._rebalanced(_Solved(solved.status, "", solved.point, None, 0.0), xs)
        if t_new is None or not self._settings["rebalance"]:
            return solved, fd
        first, self._t = solved, t_new
        self._solvers.clear()
        fd = self._form_data(xs, us, ys, w_max, lam)
        retry = self._solve_ipm(fd, phase_one=False, slot=slot)
        retry.solve_time += first.solve_time
        retry.iterations = (retry.iterations or 0) + (first.iterations or 0)
        retry.solver_status = f"{first.solver_status}; rebalanced on it {retry.solver_status}"
        retry.interior = interior
        if retry.status == INFEASIBLE:  # a ray against phase one's point: not believed
            retry.status, retry.infeasibility, retry.z = NUMERICAL_ERROR, None, None
        return retry, fd

    @staticmethod
    def _point_answer(solved: _Solved) -> _Solved:
        """Phase one's strictly feasible point as the answer of a solve that gave none,
        ``"inaccurate"`` (``gamma`` an upper bound on the optimum; :meth:`_finish` certifies it
        as any answer)."""
        out = _Solved(INACCURATE, f"{solved.solver_status}; phase one's point (gamma an upper bound)", None,
                      solved.iterations, solved.solve_time)
        out.values = out.interior = solved.interior
        return out

    def _rebalanced(self, solved: _Solved, xs: np.ndarray) -> np.ndarray | None:
        """Coordinates balanced on a failed run's Lyapunov matrix (the mean of the ``Q_j`` in the
        vertex forms), as :meth:`lmi.backends.ipm.IPMKothare._rebalanced_scaling` does for
        Kothare's problem: ``T L ||L^-1 x||`` with ``L`` its Cholesky factor; ``None`` when the run
        gave nothing to balance on (no iterate, not positive definite, or already balanced)."""
        if not self._settings["rebalance"] or solved.z is None or not np.all(np.isfinite(solved.z)):
            return None
        values = self.layout.values(solved.z)
        names = [name for name in values if name[0] == "Q"]
        q_mat = sum(values[name] for name in names) / len(names)
        q_mat = 0.5 * (q_mat + q_mat.T)
        lam = np.linalg.eigvalsh(q_mat)
        if not (lam[0] > 0.0 and lam[-1] > MIN_SPREAD * lam[0]):
            return None
        low = np.linalg.cholesky(q_mat)
        xt = np.linalg.solve(_as_matrix(self._t), xs)
        return _as_matrix(self._t) @ (low * float(np.linalg.norm(np.linalg.solve(low, xt))))

    def _symbolic(self, fd: FormData) -> Program:
        return write(Program(self.layout), self.options, fd)

    def _solve_ipm(self, fd: FormData, keep: bool = True, phase_one: bool = True,
                   slot: str | None = None) -> _Solved:
        own = ("fallback", "warm_start", "phase_one", "rebalance")  # FormProblem's settings
        settings = {k: v for k, v in self._settings.items() if k not in own}
        key = _solver_key("ipm", fd, slot)
        solver = self._solvers.get(key)
        start = time.perf_counter()
        try:
            if solver is None:
                prog = self._symbolic(fd)
                solver = BlockLMISolver(self._c, prog.solver_blocks(), **settings)
                solver.form_blocks = {name: j for j, name in enumerate(prog.blocks)}
                solver.form_static = _static_blocks(prog, fd)
                solver.form_lam = fd.lam
                if keep:
                    self._solvers[key] = solver
                warm = False
            else:
                if solver.form_lam != fd.lam:  # a warm search's slot: the blocks lam enters retuned
                    self._retune(solver, fd)
                # only the blocks whose constant changes with the state and the bounds
                changing = Program(self.layout, {}, skip=solver.form_static)
                consts = write(changing, self.options, fd).constants()
                solver.set_constants({solver.form_blocks[name]: const for name, const in consts.items()})
                warm = bool(self._settings["warm_start"])
            res = solver.solve(warm_start=warm)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError) as err:
            return _Solved(SOLVER_ERROR, repr(err), None, None, time.perf_counter() - start)
        word = res.solver_status or res.status
        if res.status == UNBOUNDED:
            return _not_unbounded(_Solved(res.status, word, res.x, res.iterations, res.solve_time))
        if res.status == INFEASIBLE:  # the run's own Farkas ray
            proof = self._check_ray(fd, res.Z)
            status = INFEASIBLE if proof.ok else NUMERICAL_ERROR
            return _Solved(status, word, None, res.iterations, res.solve_time, proof)
        solved = _Solved(res.status, word, res.x, res.iterations, res.solve_time)
        if res.status == OPTIMAL and fd.E is not None and fd.w_max > 0.0:
            solved.slope = self._slope(solver, fd, res.x, res.Z)
        return self._phase_one(fd, solved, slot) if phase_one and res.status != OPTIMAL else solved

    def _slope(self, solver: BlockLMISolver, fd: FormData, z: np.ndarray, dual: list[np.ndarray]) -> float:
        """``d(c'z*)/d lam`` at an optimum ``z*`` with dual blocks ``Z_j`` (the envelope theorem):
        ``-sum_j <Z_j, dM_j/d lam (z*)>`` over the blocks ``lam`` enters (each affine in ``lam``).
        Measured against central differences (``h = 1e-4``) on Kothare's example 1 and the double
        integrator: the same to 1e-5 relative or better."""
        lifted = np.concatenate([[1.0], z])
        return -sum(float(np.sum(dual[solver.form_blocks[name]] * np.tensordot(lifted, d_coef, axes=1)))
                    for name, d_coef in self._lam_coefficients(fd).items())

    def _lam_coefficients(self, fd: FormData) -> dict[str, np.ndarray]:
        """``d/d lam`` of the solver's coefficients ``(n_vars + 1, k, k)`` of each block ``lam``
        enters, in the present coordinates (the blocks are affine in ``lam``: the difference of
        the programs at ``lam = 1`` and ``lam = 0``)."""
        return self._lam_affine(fd)[0]

    def _lam_affine(self, fd: FormData) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        """Of each block ``lam`` enters: ``d/d lam`` of its solver coefficients and its
        coefficients of the variables at ``lam = 0`` (``(n_vars, k, k)``, which neither the state
        nor the bounds enter), made once per coordinates."""
        key = np.asarray(self._t).tobytes() + bytes([fd.q_outer is not None])
        if self._lam_derivative is None or self._lam_derivative[0] != key:
            one = self._symbolic(dataclasses.replace(fd, lam=1.0))
            zero = self._symbolic(dataclasses.replace(fd, lam=0.0))
            diff = {name: one.solver_coef(name) - zero.solver_coef(name) for name in one.blocks}
            slopes = {name: d for name, d in diff.items() if np.any(d != 0.0)}
            self._lam_derivative = (key, slopes, {name: zero.solver_coef(name)[1:] for name in slopes})
        return self._lam_derivative[1], self._lam_derivative[2]

    def _retune(self, solver: BlockLMISolver, fd: FormData) -> None:
        """Rewrite the coefficients of the blocks ``lam`` enters (the invariance blocks'
        ``lam T_i`` and ``(1 - lam) I``) for ``fd.lam``; the solver keeps its warm-start point.

        The coefficients of the variables are those at ``lam = 0`` plus ``lam`` times their slope
        (:meth:`_lam_affine`; the same numbers as the symbolic program written at ``lam``: ``lam``
        enters as ``lam T_i``, ``T_i``'s coefficients symmetric, and ``(1 - lam) I``, constant),
        the constants from the numeric program of those blocks alone: no symbolic program per
        retuning (measured on paper W's disturbance form: 9.6 ms of writing per state)."""
        slopes, base = self._lam_affine(fd)
        others = frozenset(solver.form_blocks) - frozenset(slopes)
        consts = write(Program(self.layout, {}, skip=others), self.options, fd).constants()
        for name, slope in slopes.items():
            solver.set_block(solver.form_blocks[name], consts[name], -(base[name] + fd.lam * slope[1:]))
        solver.form_lam = fd.lam

    def _phase_one(self, fd: FormData, failed: _Solved, slot: str | None = None) -> _Solved:
        """After a failed solve near the edge of the feasible region: phase one looks for a proof
        of infeasibility (as :mod:`lmi.backends.ipm` does for Kothare's problem) before the
        fallback is asked; ``failed`` with phase one's word added otherwise."""
        solver = self._solvers.get(_solver_key("ipm", fd, slot))
        if not self._settings["phase_one"] or solver is None:
            return failed
        start = time.perf_counter()
        try:
            one = solver.phase_one()
        except (np.linalg.LinAlgError, ValueError, FloatingPointError) as err:
            failed.solver_status += f"; phase one {err!r}"
            return failed
        its = (failed.iterations or 0) + one.iterations
        elapsed = failed.solve_time + time.perf_counter() - start
        word = f"{failed.solver_status}; phase one {one.status}"
        if one.status == INFEASIBLE and one.Z is not None:
            proof = self._check_ray(fd, one.Z)
            if proof.ok:
                return _Solved(INFEASIBLE, word, None, its, elapsed, proof)
        point = one.x if one.status == "feasible" else None
        return _Solved(failed.status, word, failed.z, its, elapsed, point=point)

    def _check_ray(self, fd: FormData, z_blocks: list[np.ndarray]) -> InfeasibilityCertificate:
        """A Farkas ray of the ipm, checked on the conic data of the problem as solved."""
        a_rows, b, orders = self._symbolic(fd).conic_rows()
        y = np.concatenate([svec_matrix(z_block) for z_block in z_blocks])
        return check_farkas(a_rows, b, [("psd", k) for k in orders], y)

    def _clarabel_data(self, fd: FormData) -> tuple[np.ndarray, np.ndarray, list[int]]:
        return self._symbolic(fd).conic_rows()

    def _solve_clarabel(self, fd: FormData) -> _Solved:
        import clarabel

        from lmi.backends.clarabel import clarabel_settings

        a_rows, b, orders = self._clarabel_data(fd)
        n = self.layout.size
        settings = clarabel_settings(self._settings if self.backend != "ipm" else None)
        start = time.perf_counter()
        try:
            with self._blas.limit():
                solver = clarabel.DefaultSolver(
                    sparse.csc_matrix((n, n)), self._c, sparse.csc_matrix(a_rows), b,
                    [clarabel.PSDTriangleConeT(k) for k in orders], settings,
                )
                sol = solver.solve()
        except BaseException as err:  # Clarabel raises its own panics as BaseException
            reraise_interrupt(err)  # Ctrl-C, bare or wrapped by the binding: not a failed solve
            return _Solved(SOLVER_ERROR, repr(err), None, None, time.perf_counter() - start)
        raw = str(sol.status)
        status = CLARABEL_STATUS_MAP.get(raw, SOLVER_ERROR)
        z = None if status == INFEASIBLE else np.asarray(sol.x)
        return _not_unbounded(_Solved(status, raw, z, int(sol.iterations), time.perf_counter() - start))

    def _solve_cvxpy(self, fd: FormData, keep: bool = True) -> _Solved:
        import cvxpy as cp

        key = _solver_key("cvxpy", fd)
        built = self._solvers.get(key)
        if built is None:
            prog = self._symbolic(fd)
            z = cp.Variable(self.layout.size)
            params, cons = [], []
            for name in prog.blocks:
                coef = prog.solver_coef(name)  # the data the other back-ends get
                k = coef.shape[1]
                const = cp.Parameter((k, k), symmetric=True)
                lin = coef[1:].reshape(self.layout.size, k * k).T @ z
                expr = const + cp.reshape(lin, (k, k), order="C")
                cons.append(0.5 * (expr + expr.T) >> 0)
                params.append(const)
            built = (cp.Problem(cp.Minimize(self._c @ z), cons), z, params)
            if keep:
                self._solvers[key] = built
        problem, z, params = built
        consts = write(Program(self.layout, {}), self.options, fd).constants()
        for param, const in zip(params, consts.values(), strict=True):
            param.value = const
        start = time.perf_counter()
        try:
            with self._blas.limit():
                problem.solve(solver="CLARABEL", **self._settings)
        except BaseException as err:  # cvxpy.error.SolverError, the solver's own errors and panics
            if isinstance(err, SystemExit):
                raise
            reraise_interrupt(err)  # Ctrl-C, bare or wrapped by the binding: not a failed solve
            return _Solved(SOLVER_ERROR, repr(err), None, None, time.perf_counter() - start)
        elapsed = time.perf_counter() - start
        status = CVXPY_STATUS_MAP.get(str(problem.status), SOLVER_ERROR)
        zval = None if z.value is None else np.asarray(z.value, dtype=float)
        stats = problem.solver_stats
        its = None if stats is None or stats.num_iters is None else int(stats.num_iters)
        return _not_unbounded(_Solved(status, str(problem.status), zval, its, elapsed))

    # -- the answer ------------------------------------------------------------------------------
    def _finish(self, solved: _Solved, x: np.ndarray, scale: float, xs: np.ndarray, us: np.ndarray,
                ys: np.ndarray, w_max: float, lam: float) -> LMISolution:
        backend = self.backend if self.backend != "cvxpy" else "cvxpy:CLARABEL"
        if solved.values is None and (solved.z is None or not np.all(np.isfinite(solved.z))):
            return LMISolution(solved.status, np.nan, None, None, None, solved.solve_time, solved.iterations,
                               solved.solver_status, None, backend, x,
                               solved.infeasibility if solved.status == INFEASIBLE else None)
        values = solved.values if solved.values is not None else self._original(self.layout.values(solved.z))
        sol = self._answer(values, solved.status, solved, x, scale, xs, us, ys, w_max, lam)
        certified = sol.certificate is not None and sol.certificate.ok and sol.F is not None
        if solved.interior is not None and not (certified and sol.status in (OPTIMAL, INACCURATE)):
            # not certified (an optimum on the boundary of a thin feasible set, its recomputed
            # margins just below the tolerance; a failure word's last iterate): mixed with phase
            # one's strictly feasible point (every block is affine in the variables, so the mix is
            # feasible wherever both are), the smallest weight first, the point itself last
            for w in MIX_WEIGHTS:
                mixed = {name: (1.0 - w) * val + w * solved.interior[name] for name, val in values.items()}
                trial = self._answer(mixed, INACCURATE, solved, x, scale, xs, us, ys, w_max, lam)
                if trial.certificate is not None and trial.certificate.ok and trial.F is not None:
                    how = "phase one's point" if w == 1.0 else f"mixed with phase one's point at w={w:g}"
                    return dataclasses.replace(trial, solver_status=f"{solved.solver_status}; {how} "
                                                                    "(gamma an upper bound)")
        return sol

    def _answer(self, values: dict[str, np.ndarray], status: str, solved: _Solved, x: np.ndarray,
                scale: float, xs: np.ndarray, us: np.ndarray, ys: np.ndarray, w_max: float,
                lam: float) -> LMISolution:
        """The solution at ``values`` (original coordinates, normalised state), certified: ``status``
        becomes ``"uncertified"`` if it is ``"optimal"`` and the certificate fails."""
        backend = self.backend if self.backend != "cvxpy" else "cvxpy:CLARABEL"
        # the certificate: every block recomputed at the answer, original coordinates, x / ||x||
        check = write(Program(self.layout, values), self.options,
                      self._form_data(xs, us, ys, w_max, lam, t=np.ones(self.data.n)))
        margins = check.margins()
        opts = self.options
        for soft in soft_slacks(opts.soft):
            # a slack is >= 0 (its diagonal entry of the state block is certified with that
            # block, relative to the block's size); here also against the squared bound it
            # softens: a negative slack tightens that bound, and lowers the objective by w |s|
            slack_n = float(values[soft.name][0, 0])
            if soft.limit is not None:
                bound = soft.limit / scale
            else:
                bounds = np.asarray(us if soft.family == "u" else ys)
                bound = float(np.min(bounds) if soft.component is None else bounds[soft.component])
            square = bound**2
            margins[f"slack_{soft.key}"] = slack_n / max(square, abs(slack_n), np.finfo(float).tiny)
        g_mat = values["G"] if opts.vertex_lyapunov else values["Q"]
        try:
            g_inv = np.linalg.inv(g_mat)
        except np.linalg.LinAlgError:
            g_inv = None
            margins["G_invertible"] = -np.inf
        cert = Certificate(margins, self.certificate_tol)
        s2 = scale**2
        f_mat = None if g_inv is None else values["Y"] @ g_inv
        h_mat = None if g_inv is None or "Z" not in values else values["Z"] @ g_inv
        q_vertices = None
        if opts.vertex_lyapunov:
            count = lyapunov_count(opts, self.data.n_vertices, self.data.m)
            q_vertices = tuple(s2 * values[f"Q{j}"] for j in range(count))
            q_mat = _inner_ellipsoid(q_vertices)
        else:
            q_mat = s2 * values["Q"]
        gamma = float(values["gamma"][0, 0]) + (float(values["s0"][0, 0]) if "s0" in values else 0.0)
        slack = None
        if opts.soft is not None:
            slack = {s.key: s2 * float(values[s.name][0, 0]) for s in soft_slacks(opts.soft)}
        finite = f_mat is not None and np.all(np.isfinite(f_mat)) and q_mat is not None
        if status == OPTIMAL and not (cert.ok and finite):
            status = UNCERTIFIED
        dist = opts.disturbance
        return LMISolution(
            status, s2 * gamma, q_mat, s2 * values["Y"], f_mat, solved.solve_time, solved.iterations,
            solved.solver_status, cert, backend, x,
            G=s2 * g_mat if opts.vertex_lyapunov else None, Q_vertices=q_vertices,
            u0=scale * values["u0"][:, 0] if "u0" in values else None,
            H=h_mat, slack=slack, lam=lam if dist is not None and w_max > 0.0 else None,
            steps={name: s2 * val for name, val in values.items() if "@" in name} if opts.has_steps else None,
            gamma_s=s2 * float(values["gamma_s"][0, 0]) if "gamma_s" in values else None,
        )

    def _original(self, values: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Variables of the scaled coordinates ``x = T x~`` mapped back (``Q = T Q~ T``, ...)."""
        t = _as_matrix(self._t)
        out = {}
        for name, val in values.items():
            base = name.split("@")[0]  # a later step's variable (lmi.forms.steps), as the first's
            if base == "G" or name[0] in "QW":  # G, Q, Q_j and the shared W
                out[name] = t @ val @ t.T
            elif base in ("Y", "Z"):
                out[name] = val @ t.T
            else:
                out[name] = val
        return out


def _not_unbounded(solved: _Solved) -> _Solved:
    """A solver's ``"unbounded"`` made a ``"numerical_error"``: no form is unbounded. Its objective,
    ``gamma`` (+ ``s0``) + ``w_u s_u + w_y s_y`` (:func:`lmi.forms.lmis.objective`), is ``>= 0``
    at every feasible point: ``gamma`` is a diagonal entry of the cost blocks (``gamma I``), ``s0``
    of the free move's stage block exceeds the stage cost ``>= 0``, each slack ``s_u, s_y`` is a
    diagonal entry of the state block (:func:`lmi.forms.lmis._with_slacks`) and the weights are
    ``> 0``. A solver that says otherwise has lost the problem to rounding: measured with Clarabel
    at soft weights of 1e15 (``"DualInfeasible"``, gamma 1.9e-12 and a slack of -7.7e-14)."""
    if solved.status != UNBOUNDED:
        return solved
    word = f"{solved.solver_status} (not believed: the form's objective is >= 0 on its feasible set)"
    return _Solved(NUMERICAL_ERROR, word, solved.z, solved.iterations, solved.solve_time)


def _solver_key(backend: str, fd: FormData, slot: str | None = None) -> tuple:
    """What a kept solver is built for: its back-end, the contraction factor (or the warm search's
    slot, whose solver is retuned to each new ``lam``) and the nesting block."""
    return (backend, fd.lam if slot is None else slot, fd.q_outer is not None)


def _logit(lam: float) -> float:
    """``log(lam / (1 - lam))``: the warm search's coordinate of ``lam`` in ``(0, 1)``."""
    return math.log(lam / (1.0 - lam))


def _expit(t: float) -> float:
    """The inverse of :func:`_logit`."""
    return 1.0 / (1.0 + math.exp(-t)) if t >= 0.0 else math.exp(t) / (1.0 + math.exp(t))


def _parabola_vertex(a: tuple[float, float], b: tuple[float, float], c: tuple[float, float]) -> float:
    """The abscissa of the vertex of the parabola through three points ``(t, f)``, ``t_a < t_b <
    t_c`` with ``f_b <= f_a, f_c`` (then it lies in ``[t_a, t_c]``); ``t_b`` when they are on a line."""
    (ta, fa), (tb, fb), (tc, fc) = a, b, c
    num = (tb - ta) ** 2 * (fb - fc) - (tb - tc) ** 2 * (fb - fa)
    den = (tb - ta) * (fb - fc) - (tb - tc) * (fb - fa)
    if den == 0.0 or not np.isfinite(num / den):
        return tb
    return min(max(tb - 0.5 * num / den, ta), tc)


def _as_matrix(t: np.ndarray) -> np.ndarray:
    """The coordinates ``x = T x~``: a diagonal given as a vector, or the full matrix."""
    return np.diag(t) if t.ndim == 1 else t


def _static_blocks(prog: Program, fd: FormData) -> frozenset[str]:
    """The blocks whose constant part is zero whatever the state and the bounds: the cost blocks,
    and the invariance blocks without a disturbance (their ``w_max E`` scales with the state)."""
    disturbed = fd.E is not None and fd.w_max > 0.0
    names = [name for name in prog.blocks
             if name.startswith("cost") or (name.startswith("invariance") and not disturbed)]
    return frozenset(name for name in names if not np.any(prog.blocks[name].coef[0]))


def _inner_ellipsoid(q_vertices: tuple[np.ndarray, ...]) -> np.ndarray | None:
    """``c Q_1`` with the largest ``c`` such that ``c Q_1 <= Q_j`` for every ``j``: an ellipsoid
    inside every ``{x' Q_j^-1 x <= 1}``."""
    try:
        chol = np.linalg.cholesky(q_vertices[0])
    except np.linalg.LinAlgError:
        return None
    c_inv = np.linalg.inv(chol)
    c = min(float(np.linalg.eigvalsh(c_inv @ q @ c_inv.T)[0]) for q in q_vertices)
    return c * q_vertices[0] if c > 0.0 else None


