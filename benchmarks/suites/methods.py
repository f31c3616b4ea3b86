"""The benchmark suite "methods": the field's robust MPC forms head to head (``rmpc bench methods``).

Every problem of :mod:`benchmarks.suites.methods_problems` is solved by every method of
:data:`METHODS`: the forms of :class:`rmpc.RMPC`, MUP's method keys (:mod:`rmpc.mpc.methods`) and
the QP families of :mod:`benchmarks.suites.methods_qp` (tube and multi-stage MPC); one record per
problem and method holds

- ``status``, ``gamma``, ``iterations`` of the solve at the start state ``x0``;
- ``region``: the largest feasible multiple ``t`` of fixed directions (``t d`` certified
  ``"optimal"``; the directions have the scaled size of ``x0``, the first is ``x0`` itself, so
  ``t = 1`` reaches as far as the start state), found by bracketing and bisection;
- ``closed_loop_cost``: ``sum x'Q x + u'R u`` over the problem's horizon on its fixed plant (the
  nominal model), applying ``ctrl.step``; ``closed_loop_cost_switching`` on a seeded sequence
  of vertices;
- ``solve_time_p50`` / ``solve_time_p95``: wall time of the steps that solved (``time.perf_counter``
  around ``ctrl.step``, certification included), and ``cvxpy_time_p50``: wall time of
  ``ctrl.solve`` with ``backend="cvxpy"`` (the same LMIs through cvxpy + Clarabel) on the first
  states of the closed loop, next to the toolkit's ipm on the same states;
- ``violations``: samples of seeded switching-vertex runs whose input or next state broke a bound;
- ``status_counts`` of the closed-loop steps and ``skip_reason`` where a method does not apply.

Each finished record is stored in ``DIR/cases/`` at once; running the same command again skips
them (``fresh=True`` starts over), so an interrupted run resumes. A stored case is taken only when
it fits the schema of :mod:`benchmarks.suites.methods_store` and is the case asked for; any other
is measured again and named in the run's notes. :func:`run_methods` writes ``results.json``,
``results.md``, ``results.csv``, ``run.json`` and ``figures/*.png`` through
:mod:`benchmarks.suites.methods_report`, all of them or none (:mod:`benchmarks.core.publish`).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from benchmarks.baseline import Baseline, load_baseline
from benchmarks.core.execute import ExecOutcome
from benchmarks.core.interrupts import Interrupts
from benchmarks.core.jsonable import json_safe
from benchmarks.core.progress import CaseProgress
from benchmarks.core.publish import published_paths, staged_reports
from benchmarks.core.suite import SuiteOutcome
from benchmarks.suites.methods_problems import PROBLEMS, SHORT_PROBLEMS, MethodsProblem, build_problem
from benchmarks.suites.methods_qp import QP_METHODS, qp_method, state_box
from benchmarks.suites.methods_report import write_methods_report
from benchmarks.suites.methods_store import case_path, load_case, store_case
from rmpc.analysis import TimeBudgetExceeded, boundary_along
from toolkit_common.errors import ConfigError

__all__ = [
    "METHODS", "MUP_KEYS", "MUP_PARAMETERS", "MethodsSettings", "evaluate", "method_options", "run_methods",
]

#: Method -> what it is (the options of :class:`rmpc.RMPC` are in :func:`method_options`).
METHODS: dict[str, str] = {
    "kothare": "Kothare, Balakrishnan & Morari 1996: one Lyapunov matrix, worst-case cost (the defaults)",
    "vertex": "Cuzzola, Geromel & Morari 2002: one Q_j per vertex and a slack G (constant uncertainty)",
    "vertex_pairs": "Mao 2003: Q_j per vertex over every vertex pair (uncertainty may switch each sample)",
    "nominal": "Wan & Kothare 2003: cost bound on the nominal model, robust invariance on every vertex",
    "free_move": "one free first move u(k), the feedback law from k+1 on",
    "auxiliary_saturation": "Cao & Lin 2005: u = sat(F x) with an auxiliary gain H carrying the peak bound",
    "soft": "Oravec & Bakosova 2016: soft input (and output) bounds with linear slack penalties",
    "disturbance": "bounded disturbance E w, ||w|| <= w_max: an invariant ellipsoid under it",
    "ding": "Ding, Xi, Cychowski & O'Mahony 2007: nominal cost with vertex-pair Lyapunov matrices",
    "li": "Li, Shi, Sun & Wang 2008: two-step gains, a second-step gain per first-step vertex",
    "huang": "Huang, Li, Lin & Xi 2011: auxiliary saturation, the unsaturated blocks under gamma_s",
    "shi": "Shi, Su & Chu 2013: N steps with chained vertex Lyapunov matrices",
    "zhang": "Zhang, Wang & Li 2013: a saturation-dependent Lyapunov function",
    "wan_huang": "Wan & Kothare 2003 with Huang et al. 2011 (nominal cost)",
    "mao_huang": "Mao 2003 with Huang et al. 2011 (vertex-pair Lyapunov matrices)",
    "wan_zhang": "Wan & Kothare 2003 with Zhang et al. 2013 (nominal cost)",
    **QP_METHODS,
}

#: The methods of :data:`METHODS` that are MUP's method keys beyond the eight forms: their options
#: are :data:`rmpc.mpc.methods.METHODS`'s, with the tuning parameters of MUP's demo
#: (``mup_rmpc_demo.m``: ``beta = 1e3`` for Huang et al.'s weight, ``N = 3`` for Shi et al.'s
#: horizon).
MUP_KEYS: tuple[str, ...] = ("ding", "li", "huang", "shi", "zhang", "wan_huang", "mao_huang", "wan_zhang")
MUP_PARAMETERS: Mapping[str, Mapping[str, Any]] = MappingProxyType({
    "huang": MappingProxyType({"unsaturated_weight": 1e3}),
    "wan_huang": MappingProxyType({"unsaturated_weight": 1e3}),
    "mao_huang": MappingProxyType({"unsaturated_weight": 1e3}),
    "shi": MappingProxyType({"horizon": 3}),
})

#: The soft method's slack weights.
SOFT_WEIGHT: float = 1e3

#: Version of the record layout; a stored case of another version is run again.
RECORD_VERSION = 2


@dataclass(frozen=True)
class MethodsSettings:
    """How much the suite measures per case (full run or ``--short``).

    Attributes
    ----------
    directions_2d, directions : int
        Region directions for 2-state problems (evenly spaced angles, drawn as a picture) and for
        the others (``x0`` and seeded random directions).
    rel_tol : float
        Relative width at which the bisection of ``t`` stops.
    t_max : float
        The largest multiple tried (a region reaching it is reported as ``>= t_max``).
    steps_factor : float
        Fraction of each problem's closed-loop horizon.
    cvxpy_states : int
        How many closed-loop states are also solved by cvxpy + Clarabel (and again by the ipm, on a
        controller of its own); the first solve of each builds its problem (cvxpy compiles, the
        ipm starts cold) and is left out of the medians when there are more states.
    slow_solve_s : float
        A method whose solve at ``x0`` takes longer skips the region and the closed loop (recorded).
    violation_runs : int
        Seeded switching-vertex runs (each the closed loop's length) whose bound violations are
        counted (``violations``), within ``violation_budget_s``.
    region_budget_s, loop_budget_s, cvxpy_budget_s, violation_budget_s : float
        Wall-time budgets of the region, the two closed loops together and the cvxpy solves: a
        phase that runs past its budget stops, and the record says where (``notes``; a region or a
        cost that is not complete is ``None``).
    seed : int
        Seed of the random directions and the switching sequence.
    """

    directions_2d: int = 24
    directions: int = 6
    rel_tol: float = 0.02
    t_max: float = 1024.0
    steps_factor: float = 1.0
    cvxpy_states: int = 8
    slow_solve_s: float = 20.0
    region_budget_s: float = 240.0
    loop_budget_s: float = 240.0
    cvxpy_budget_s: float = 60.0
    violation_runs: int = 20
    violation_budget_s: float = 120.0
    seed: int = 0

    @classmethod
    def short(cls) -> MethodsSettings:
        """The settings of ``--short``: a smoke run that checks the set-up."""
        return cls(
            directions_2d=6,
            directions=2,
            rel_tol=0.1,
            t_max=64.0,
            steps_factor=0.25,
            cvxpy_states=3,
            slow_solve_s=5.0,
            region_budget_s=15.0,
            loop_budget_s=15.0,
            cvxpy_budget_s=10.0,
            violation_runs=2,
            violation_budget_s=10.0,
        )

    def as_dict(self) -> dict[str, Any]:
        """The settings as a plain dict (stored with every record)."""
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def method_options(problem: MethodsProblem, method: str) -> tuple[dict[str, Any] | None, str | None, bool]:
    """The options of :class:`rmpc.RMPC` for ``method`` on ``problem``.

    Returns
    -------
    options : dict or None
        Keyword arguments added to the problem's own (``None`` when the method is skipped).
    skip_reason : str or None
        Why the method does not apply to the problem.
    comparable : bool
        Whether the method solves the problem's own bounds (the auxiliary saturation needs a peak
        bound: on a problem that bounds ``||u||_2`` it runs with ``|u_l| <= u_max`` instead).
    """
    if method not in METHODS:
        raise ConfigError("method", "one of " + ", ".join(METHODS), repr(method))
    if method == "kothare":
        return {}, None, True
    if method in MUP_KEYS:
        return _mup_options(problem, method)
    if method in ("vertex", "vertex_pairs"):
        return {"lyapunov": method}, None, True
    if method == "nominal":
        return {"cost": "nominal"}, None, True
    if method == "free_move":
        return {"free_moves": 1}, None, True
    if method == "auxiliary_saturation":
        comparable = problem.input_constraint == "peak" or problem.plant.n_inputs == 1
        return {"saturation": "auxiliary", "input_constraint": "peak"}, None, comparable
    if method == "soft":
        weights = {"u": SOFT_WEIGHT}
        if problem.y_max is not None:
            weights["y"] = SOFT_WEIGHT
        return {"soft": weights}, None, True
    e, w_max = problem.disturbance
    if w_max <= 0.0:
        return None, "the problem has no input bound to size the disturbance by", True
    return {"disturbance": (e, w_max)}, None, True


def _mup_options(problem: MethodsProblem, key: str) -> tuple[dict[str, Any], None, bool]:
    """MUP's method ``key`` (:data:`rmpc.mpc.methods.METHODS`) with MUP's demo parameters; a method
    with the auxiliary saturation runs with the peak bound, as ``auxiliary_saturation``."""
    from rmpc.mpc.methods import METHODS as MUP

    options = {**dict(MUP[key].defaults), **dict(MUP[key].options), **MUP_PARAMETERS.get(key, {})}
    comparable = True
    if options.get("saturation") is not None:
        comparable = problem.input_constraint == "peak" or problem.plant.n_inputs == 1
        options["input_constraint"] = "peak"
    return options, None, comparable


def _controller(problem: MethodsProblem, options: dict[str, Any], backend: str = "ipm") -> Any:
    from rmpc import RMPC

    kwargs: dict[str, Any] = {"input_constraint": problem.input_constraint, "backend": backend}
    if problem.output_matrix is not None:
        kwargs.update(output_matrix=problem.output_matrix, y_max=problem.y_max)
    kwargs.update(options)
    return RMPC(problem.plant, problem.Q, problem.R, u_max=problem.u_max, **kwargs)


def _directions(problem: MethodsProblem, settings: MethodsSettings) -> np.ndarray:
    """Unit-size directions (rows): the scaled size of ``x0``; the first is ``x0`` (n > 2)."""
    scale = problem.region_scale
    size = float(np.linalg.norm(problem.x0 / scale))
    if problem.n_states == 2:
        angles = np.linspace(0.0, 2.0 * np.pi, settings.directions_2d, endpoint=False)
        base = np.arctan2(problem.x0[1] / scale[1], problem.x0[0] / scale[0])
        v = np.stack([np.cos(base + angles), np.sin(base + angles)], axis=1)
    else:
        rng = np.random.default_rng(settings.seed)
        v = rng.standard_normal((max(settings.directions - 1, 0), problem.n_states))
        v = np.vstack([problem.x0 / scale, v])
        v = v / np.linalg.norm(v, axis=1, keepdims=True)
    return size * v * scale


_OverBudget = TimeBudgetExceeded


def region_along(
    ctrl: Any, d: np.ndarray, settings: MethodsSettings, counts: dict[str, int], deadline: float = np.inf
) -> tuple[float, str]:
    """:func:`rmpc.analysis.boundary_along` with the settings' cap and tolerance: the largest
    certified multiple of ``d`` and what stopped it (``"cap"`` at ``t_max``). Raises
    ``_OverBudget`` (:class:`rmpc.analysis.TimeBudgetExceeded`) past ``deadline``."""
    return boundary_along(ctrl, d, t_max=settings.t_max, rel_tol=settings.rel_tol, counts=counts,
                          deadline=deadline)


def _closed_loop(
    ctrl: Any,
    problem: MethodsProblem,
    steps: int,
    plants: Sequence[tuple[np.ndarray, np.ndarray]],
    deadline: float = np.inf,
) -> dict[str, Any]:
    """Run ``ctrl.step`` on ``plants[k]`` for ``steps`` samples; cost, step times, statuses, states.

    Past ``deadline`` the run stops: ``done`` < ``steps`` and the cost covers the steps run.
    """
    ctrl.reset()
    x = problem.x0.copy()
    cost = 0.0
    times: list[float] = []
    counts: dict[str, int] = {}
    states = [x.copy()]
    max_u = 0.0
    done = 0
    for k in range(steps):
        if time.perf_counter() > deadline:
            break
        done = k + 1
        start = time.perf_counter()
        u = np.asarray(ctrl.step(x), dtype=float)
        elapsed = time.perf_counter() - start
        info = ctrl.last
        status = str(info.status) if info is not None else "none"
        counts[status] = counts.get(status, 0) + 1
        if status != "reused":
            times.append(elapsed)
        cost += float(x @ problem.Q @ x + u @ problem.R @ u)
        max_u = max(max_u, float(np.max(np.abs(u))))
        a, b = plants[k]
        x = a @ x + b @ u
        states.append(x.copy())
        if not np.all(np.isfinite(x)):
            counts["diverged"] = counts.get("diverged", 0) + 1
            cost = float("inf")
            break
    return {
        "cost": cost,
        "times": times,
        "counts": counts,
        "states": np.array(states),
        "max_abs_u": max_u,
        "final_norm": float(np.linalg.norm(states[-1])),
        "done": done,
    }


def _percentile(values: Sequence[float], q: float) -> float | None:
    return float(np.percentile(values, q)) if len(values) else None


def _cvxpy_times(
    problem: MethodsProblem, options: dict[str, Any], states: Sequence[np.ndarray], deadline: float = np.inf
) -> dict[str, Any]:
    """cvxpy + Clarabel on ``states`` next to the ipm on the same states (wall time of ``solve``)."""
    out: dict[str, Any] = {"cvxpy_statuses": {}, "cvxpy_gamma": None, "cvxpy_error": None}
    try:
        ref = _controller(problem, options, backend="cvxpy")
    except Exception as err:  # a form the cvxpy back-end does not build is a note, not a crash
        out["cvxpy_error"] = f"{type(err).__name__}: {err}"
        return out
    ipm = _controller(problem, options)
    cv_times, ipm_times = [], []
    for i, x in enumerate(states):
        if i and time.perf_counter() > deadline:
            break
        start = time.perf_counter()
        with warnings.catch_warnings():  # cvxpy's "may be inaccurate": the status says it
            warnings.simplefilter("ignore", UserWarning)
            sol = ref.solve(x)
        cv_times.append(time.perf_counter() - start)
        out["cvxpy_statuses"][sol.status] = out["cvxpy_statuses"].get(sol.status, 0) + 1
        if i == 0:
            out["cvxpy_gamma"] = sol.gamma
            out["cvxpy_status_x0"] = sol.status
        start = time.perf_counter()
        ipm.solve(x)
        ipm_times.append(time.perf_counter() - start)
    # the first solve builds the problem (cvxpy's compilation, the ipm's cold start): left out
    warm = slice(1, None) if len(cv_times) > 1 else slice(None)
    out["cvxpy_time_p50"] = _percentile(cv_times[warm], 50)
    out["ipm_time_same_states_p50"] = _percentile(ipm_times[warm], 50)
    out["cvxpy_first_time"] = cv_times[0] if cv_times else None
    out["cvxpy_states"] = len(cv_times)
    return out


def _switching(problem: MethodsProblem, steps: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, problem.plant.n_vertices, size=steps)
    return [
        problem.plant.vertex(int(j)) if hasattr(problem.plant, "vertex") else problem.plant.vertices[j]
        for j in idx
    ]


def _base_record(problem: MethodsProblem, method: str, settings: MethodsSettings) -> dict[str, Any]:
    return {
        "problem": problem.name,
        "method": method,
        "status": None,
        "gamma": None,
        "iterations": None,
        "solve_time_p50": None,
        "solve_time_p95": None,
        "cvxpy_time_p50": None,
        "region": None,
        "closed_loop_cost": None,
        "closed_loop_cost_switching": None,
        "status_counts": {},
        "skip_reason": None,
        "comparable": True,
        "notes": [],
        "settings": {
            "options": {},
            "n_states": problem.n_states,
            "n_inputs": int(problem.plant.n_inputs),
            "n_vertices": int(problem.plant.n_vertices),
            "dt": float(problem.plant.dt),
            "u_max": problem.u_max,
            "input_constraint": problem.input_constraint,
            "x0": problem.x0.tolist(),
            "suite": settings.as_dict(),
            "record_version": RECORD_VERSION,
        },
    }


def _options_json(options: dict[str, Any]) -> dict[str, Any]:
    out = dict(options)
    if "disturbance" in out:
        e, w_max = out["disturbance"]
        out["disturbance"] = {"E_shape": list(np.shape(e)), "w_max": w_max}
    return out


def evaluate(problem: MethodsProblem, method: str, settings: MethodsSettings) -> tuple[dict[str, Any], dict]:
    """Measure ``method`` on ``problem``: the record and the data of the figures.

    Never raises for a failing solver or an option this build does not have: the record says
    what happened (``status``, ``skip_reason``, ``notes``).
    """
    start_case = time.perf_counter()
    rec = _base_record(problem, method, settings)
    extra: dict[str, Any] = {}
    qp_family = method in QP_METHODS
    if qp_family:
        ctrl, reason, comparable, options = qp_method(problem, method)
    else:
        options, reason, comparable = method_options(problem, method)
    rec["comparable"] = comparable
    if options is None or reason is not None:
        rec["status"], rec["skip_reason"] = "skipped", reason
        return rec, extra
    rec["settings"]["options"] = _options_json(options)
    if not comparable:
        rec["notes"].append("runs with the peak bound |u_l| <= u_max: not the problem's ||u||_2 bound")
    if not qp_family:
        try:
            ctrl = _controller(problem, options)
        except (TypeError, ValueError) as err:
            rec["status"] = "skipped"
            rec["skip_reason"] = f"RMPC does not take these options: {type(err).__name__}: {err}"
            return rec, extra
    start = time.perf_counter()
    sol = ctrl.solve(problem.x0)
    x0_time = time.perf_counter() - start
    rec.update(status=sol.status, gamma=sol.gamma, iterations=sol.iterations)
    if sol.slack is not None:  # the soft form's slacks at x0 (squared units)
        rec["slack"] = dict(sol.slack)
    rec["x0_solve_time"] = x0_time
    if x0_time > settings.slow_solve_s:
        rec["skip_reason"] = (
            f"one solve at x0 took {x0_time:.1f} s (> {settings.slow_solve_s:g} s): no region, closed loop "
            "or cvxpy run"
        )
        rec["solve_time_p50"] = rec["solve_time_p95"] = x0_time
        rec["case_time_s"] = time.perf_counter() - start_case
        return rec, extra
    # the region
    dirs = _directions(problem, settings)
    region_counts: dict[str, int] = {}
    deadline = time.perf_counter() + settings.region_budget_s
    ts, limits = [], []
    try:
        for d in dirs:
            t, why = region_along(ctrl, d, settings, region_counts, deadline)
            ts.append(t)
            limits.append(why)
    except _OverBudget:
        rec["notes"].append(
            f"region: {len(ts)} of {len(dirs)} directions within its {settings.region_budget_s:g} s budget"
        )
        rec["region_partial"] = {"t": ts, "limits": limits, "status_counts": region_counts}
        ts = []
    if ts:
        _region(rec, ts, limits, region_counts, problem, settings)
        extra["region_points"] = (np.array(ts)[:, None] * dirs).tolist()
    # the closed loop: fixed plant, then switching vertices
    steps = max(2, round(problem.steps * settings.steps_factor))
    deadline = time.perf_counter() + settings.loop_budget_s
    fixed = _closed_loop(ctrl, problem, steps, [problem.true_plant] * steps, deadline)
    switching = _closed_loop(ctrl, problem, steps, _switching(problem, steps, settings.seed), deadline)
    for name, run in (("closed_loop_cost", fixed), ("closed_loop_cost_switching", switching)):
        if run["done"] == steps:
            rec[name] = run["cost"]
        else:
            rec["notes"].append(
                f"{name}: stopped after {run['done']} of {steps} steps ({settings.loop_budget_s:g} s budget)"
            )
    rec["closed_loop_steps"] = steps
    rec["closed_loop_max_abs_u"] = fixed["max_abs_u"]
    rec["closed_loop_final_norm"] = fixed["final_norm"]
    times = fixed["times"] + switching["times"]
    rec["solve_time_p50"] = _percentile(times, 50)
    rec["solve_time_p95"] = _percentile(times, 95)
    rec["solves"] = len(times)
    counts: dict[str, int] = {}
    for c in (fixed["counts"], switching["counts"]):
        for k, v in c.items():
            counts[k] = counts.get(k, 0) + v
    rec["status_counts"] = counts
    extra["trajectory"] = fixed["states"].tolist()
    rec.update(_violations(ctrl, problem, steps, settings))
    if qp_family:  # no LMIs: nothing for cvxpy to solve the same way
        rec["cvxpy_error"] = "a QP family: no LMIs to solve through cvxpy + Clarabel"
        rec["case_time_s"] = time.perf_counter() - start_case
        return rec, extra
    # cvxpy + Clarabel on the first states of the closed loop
    cv_states = list(fixed["states"][: max(1, settings.cvxpy_states)])
    cv = _cvxpy_times(problem, options, cv_states, time.perf_counter() + settings.cvxpy_budget_s)
    rec.update(cv)
    if rec["cvxpy_time_p50"] and rec.get("ipm_time_same_states_p50"):
        rec["cvxpy_ratio"] = rec["cvxpy_time_p50"] / rec["ipm_time_same_states_p50"]
    rec["case_time_s"] = time.perf_counter() - start_case
    return rec, extra


def _violations(ctrl: Any, problem: MethodsProblem, steps: int, settings: MethodsSettings) -> dict[str, Any]:
    """Bound violations over seeded switching-vertex runs (:func:`rmpc.mpc.switching_runs.switching_runs`):
    run ``r`` draws its vertices with seed ``settings.seed + r``; runs stop at the budget.

    The input bound is checked per component (``|u_l| <= u_max``; on a problem that bounds
    ``||u||_2`` that is a necessary condition only), the state bound where the problem has output
    bounds (``|C x| <= y_max``); a problem with an additive disturbance box pushes every sample by
    a vertex of it.
    """
    from rmpc.mpc.switching_runs import switching_runs

    state = state_box(problem)
    deadline = time.perf_counter() + settings.violation_budget_s
    out = {"violations": 0, "violation_runs": 0, "violation_samples": 0, "violations_input": 0,
           "violations_state": 0}
    for r in range(settings.violation_runs):
        if r and time.perf_counter() > deadline:
            break
        run = switching_runs(ctrl, problem.plant, problem.x0, steps=steps, runs=1, seed=settings.seed + r,
                             u_max=float(problem.u_max), state_constraints=state, Q=problem.Q, R=problem.R,
                             w_max=problem.w_box, E=problem.w_matrix)
        out["violations"] += run["violations"]
        out["violations_input"] += run["input_violations"]
        out["violations_state"] += run["state_violations"]
        out["violation_samples"] += run["samples"]
        out["violation_runs"] += 1
    return out


def _region(
    rec: dict[str, Any],
    ts: list[float],
    limits: list[str],
    counts: dict[str, int],
    problem: MethodsProblem,
    settings: MethodsSettings,
) -> None:
    ended: dict[str, int] = {}
    for why in limits:
        ended[why] = ended.get(why, 0) + 1
    rec["region"] = {
        "t": ts,
        "limits": limits,
        "ended_by": ended,
        "geo_mean_t": float(np.exp(np.mean(np.log(np.maximum(ts, 1.0 / settings.t_max))))),
        "min_t": float(min(ts)),
        "t_x0": float(ts[0]) if problem.n_states > 2 else None,
        "capped": bool(max(ts) >= settings.t_max),
        "directions": len(ts),
        "status_counts": counts,
    }


# -- running, storing, resuming ----------------------------------------------------------------


def _chosen(known: Sequence[str], asked: Sequence[str] | None, arg: str) -> list[str]:
    chosen = list(known) if asked is None else list(asked)
    for name in chosen:
        if name not in known:
            raise ConfigError(arg, "names among " + ", ".join(known), repr(name))
    if not chosen:
        raise ConfigError(arg, "one or more names among " + ", ".join(known), "none")
    return chosen


def run_methods(
    out: str | Path,
    short: bool = False,
    problems: Sequence[str] | None = None,
    methods: Sequence[str] | None = None,
    progress: bool | None = None,
    fresh: bool = False,
    baseline: str | Path | Baseline | None = None,
) -> SuiteOutcome:
    """Run every chosen problem x method and write the report into ``out`` (created if needed).

    Parameters
    ----------
    out : str or Path
        Output directory; ``out/cases/`` keeps each finished case, so the same command resumes.
    short : bool
        A smoke run: :data:`~benchmarks.suites.methods_problems.SHORT_PROBLEMS` by default and
        :meth:`MethodsSettings.short`.
    problems, methods : sequence of str, optional
        Run only these (default: all; with ``short`` the short problems).
    progress : bool, optional
        Force the progress bar on or off (default: on a terminal).
    fresh : bool
        Ignore the stored cases and measure everything again.
    baseline : str, Path or Baseline, optional
        An earlier run's output folder (or :func:`benchmarks.baseline.load_baseline` of it): the
        report puts its timing figures next to this run's (read before anything is measured; a
        folder without methods records raises
        :class:`~toolkit_common.errors.InvalidArgumentError` naming ``--baseline``).

    Returns
    -------
    SuiteOutcome
        Records in problem x method order; ``execution.interrupted`` after Ctrl-C (the files
        then hold the finished cases). Ctrl-C stops the running case at once, in the compiled
        solvers too (:class:`benchmarks.core.interrupts.Interrupts`); that case is neither
        stored nor counted as failed.
    """
    if baseline is not None and not isinstance(baseline, Baseline):
        baseline = load_baseline(baseline, "methods")
    settings = MethodsSettings.short() if short else MethodsSettings()
    default_problems = list(SHORT_PROBLEMS) if short else list(PROBLEMS)
    chosen_p = _chosen(list(PROBLEMS), default_problems if problems is None else problems, "--problems")
    chosen_m = _chosen(list(METHODS), methods, "--methods")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    execution = ExecOutcome()
    results: dict[tuple[str, str], dict[str, Any]] = {}
    failures: list[dict[str, Any]] = []
    keys = [(p, m) for p in chosen_p for m in chosen_m]
    resumed = 0
    notes: list[str] = []
    bar_context = CaseProgress(len(keys), "rmpc bench methods", progress)
    with bar_context as bar, Interrupts(first_raises=True) as stop:
        built: dict[str, MethodsProblem] = {}
        try:
            for p, m in keys:
                path = case_path(out, p, m)
                stored, why = (None, None) if fresh else load_case(
                    path, settings.as_dict(), p, m, RECORD_VERSION
                )
                if stored is not None:
                    results[(p, m)] = stored
                    resumed += 1
                    bar.advance(f"{p}/{m} (stored)")
                    continue
                if why is not None:
                    notes.append(f"cases/{path.name}: not used ({why}); measured again")
                try:
                    if p not in built:
                        built[p] = build_problem(p)
                    rec, extra = evaluate(built[p], m, settings)
                except Exception as err:  # a failing case is data, not a crash of the suite
                    if stop.interrupted(err):  # Ctrl-C, wrapped by compiled code on its way
                        raise KeyboardInterrupt from err
                    failures.append(
                        {"experiment": p, "key": f"{p}__{m}", "error": f"{type(err).__name__}: {err}"}
                    )
                    bar.advance(f"{p}/{m}", ok=False)
                    continue
                if stop.interrupted():  # swallowed inside the case: what it returned is not a result
                    raise KeyboardInterrupt
                unstored = store_case(path, settings.as_dict(), rec, extra)
                if unstored is not None:
                    notes.append(f"cases/{path.name}: not stored ({unstored}); a later run measures it again")
                results[(p, m)] = json_safe({"record": rec, "extra": extra})
                execution.finished.append(f"{p}__{m}")
                bar.advance(f"{p}/{m}" + (f" (stored case not used: {why}; measured again)" if why else ""))
        except KeyboardInterrupt:
            stop.settle()
            execution.interrupted = True
            execution.unfinished = [f"{p}__{m}" for p, m in keys if (p, m) not in results]
    outcome = SuiteOutcome(
        records=[results[k]["record"] for k in keys if k in results],
        failures=failures,
        wall_time_s=time.perf_counter() - start,
        execution=execution,
        executor="this process (one case at a time, for clean timings)",
        notes=notes,
    )
    extras = {k: results[k].get("extra", {}) for k in keys if k in results}
    with staged_reports(out) as stage:  # every report file, or none of them, is new
        files = write_methods_report(
            stage, outcome, extras, settings, len(keys), resumed, short, baseline=baseline
        )
    outcome.files = published_paths(files, stage, out)
    return outcome
