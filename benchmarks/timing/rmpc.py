"""RMPC per-step solve times on paper P's problem: the RMPC section of ``rmpc timing``, and a script.

**The section** (:func:`time_rmpc`, called by :mod:`benchmarks.timing.suite`): every RMPC solve
path of the report (the toolkit's ipm warm and cold, Clarabel's own API with three formulations,
cvxpy built once, rebuilt at every step, and with SCS) at the states of one closed loop,
interleaved state by state, with ``gamma`` against the reference of :data:`REFERENCES`.

**The stand-alone script**: run as ``python -m benchmarks.timing.rmpc [--steps N] [--out FILE]``.
For 2 and 8 vertices (inertia spread 0.3, ``||u|| <= 1``, Ts = 0.01 s) it follows the states of
one closed loop from paper P's initial attitude (the linear model, the vertex of the larger
inertia) and at each state times, in the same run:

- ``ipm/delta_shared``: :class:`lmi.KothareProblem` built once, the default back-end (the
  toolkit's own interior-point method, warm-started from the previous solve): the fast path;
- ``clarabel/<formulation>``: :class:`lmi.KothareProblem` built once, Clarabel's own API;
- ``cvxpy-param/delta``: the cvxpy formulation built once with parameters (DPP);
- ``cvxpy-rebuild/delta``: a new cvxpy problem built and solved at every step (the slow path
  this toolkit avoids; measured only for the ratio).

Times are wall-clock per step (build or update + solve + certificate), reported as median,
p95 and max, with the machine and its load average: the machines are shared and noisy.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from benchmarks.core.machine import machine_info, package_versions, percentiles
from benchmarks.timing.common import (
    POLYTOPE_NAMES,
    Q1,
    SCS_OPTIONS,
    U_MAX,
    R,
    finite,
    median_int,
    rel_err,
    sample_key,
    tally,
    write_result,
)
from lmi import KothareProblem
from models import PAPER_P_SAMPLE_TIME, RigidSatellite

if TYPE_CHECKING:
    from benchmarks.core.progress import CaseProgress
    from benchmarks.timing.config import TimingConfig
    from lmi import LMISolution
    from models import PolytopicModel

__all__ = [
    "REFERENCES",
    "closed_loop_states",
    "format_table",
    "main",
    "reference_gamma_at",
    "run",
    "section_states",
    "time_rmpc",
]

REBUILD = "cvxpy-rebuild:CLARABEL"
NO_REFERENCE = "none optimal (state left out of the errors)"
#: The RMPC reference: cvxpy + Clarabel, candidates in order of preference. At 1e-10 Clarabel
#: often stops with AlmostSolved (reduced tolerances, ~1e-7 off) on the delta form; the
#: delta_shared form at 1e-9 converges on nearly every state here.
REFERENCES: tuple[tuple[str, float], ...] = (
    ("delta", 1e-10), ("delta_shared", 1e-10), ("delta_shared", 1e-9),
)


# -- the section of rmpc timing -------------------------------------------------------------------
@dataclass
class _Path:
    """One RMPC solve path and what it measured."""

    backend: str
    formulation: str
    make: Callable[[], KothareProblem]
    limit: int
    rebuild: bool = False
    settings: str = ""
    problem: KothareProblem | None = None
    setup_s: float = float("nan")
    times: list[float] = field(default_factory=list)
    solver_times: list[float] = field(default_factory=list)
    iterations: list[int | None] = field(default_factory=list)
    gammas: list[float] = field(default_factory=list)
    margins: list[float] = field(default_factory=list)
    statuses: dict[str, int] = field(default_factory=dict)
    ok: list[bool] = field(default_factory=list)

    def run(self, x: np.ndarray) -> LMISolution:
        start = time.perf_counter()
        prob = self.make() if self.rebuild else self.problem
        assert prob is not None
        sol = prob.solve(x)
        self.times.append(time.perf_counter() - start)
        self.solver_times.append(sol.solve_time)
        self.iterations.append(sol.iterations)
        self.gammas.append(sol.gamma)
        self.margins.append(sol.certificate.worst if sol.certificate is not None else float("nan"))
        tally(self.statuses, sol.status)
        self.ok.append(sol.ok)
        return sol


def _rmpc_paths(poly: PolytopicModel, cfg: TimingConfig) -> tuple[list[_Path], list[_Path]]:
    def maker(backend: str, formulation: str, solver: str | None = None,
              opts: dict[str, Any] | None = None) -> Callable[[], KothareProblem]:
        return lambda: KothareProblem(
            poly.A, poly.B, Q1, R, dt=poly.dt, u_max=U_MAX, backend=backend, solver=solver,
            formulation=formulation, solver_options=opts,
        )

    n = cfg.steps
    paths = [
        _Path("ipm", "delta_shared", maker("ipm", "delta_shared"), n,
              settings="defaults (residuals and relative gap 1e-8), warm-started from the previous solve"),
        _Path("ipm-cold", "delta_shared", maker("ipm", "delta_shared", opts={"warm_start": False}), n,
              settings="defaults (residuals and relative gap 1e-8), every solve from the default "
                       "initial point"),
        _Path("clarabel", "delta_shared", maker("clarabel", "delta_shared"), n, settings="defaults (1e-8)"),
        _Path("clarabel", "delta", maker("clarabel", "delta"), n, settings="defaults (1e-8)"),
        _Path("clarabel", "standard", maker("clarabel", "standard"), n, settings="defaults (1e-8)"),
        _Path("cvxpy:CLARABEL", "delta", maker("cvxpy", "delta", "CLARABEL"), n,
              settings="built once, parameters (DPP); Clarabel 1e-8"),
        _Path(REBUILD, "delta", maker("cvxpy", "delta", "CLARABEL"), cfg.rebuild_steps, rebuild=True,
              settings="new cvxpy problem built and solved every step; Clarabel 1e-8"),
    ]
    if cfg.scs_steps:
        paths.append(_Path("cvxpy:SCS", "delta", maker("cvxpy", "delta", "SCS", SCS_OPTIONS), cfg.scs_steps,
                           settings=f"built once, parameters; SCS {SCS_OPTIONS}"))
    refs = [
        _Path("cvxpy:CLARABEL", formulation, maker("cvxpy", formulation, "CLARABEL", _tol(tol)), n,
              settings=f"{formulation} tol {tol:g}")
        for formulation, tol in REFERENCES
    ]
    return paths, refs


def _tol(tol: float) -> dict[str, float]:
    return {"tol_gap_abs": tol, "tol_gap_rel": tol, "tol_feas": tol}


def _reference_gamma(refs: list[_Path], k: int) -> tuple[float, str, float | None]:
    """The reference at state ``k``, which candidate it is, and the spread of the optimal candidates.

    The first candidate of :data:`REFERENCES` that is optimal (converged to its tolerances and
    certified); if none is, NaN: an answer that met only reduced tolerances can be ~1e-7 off,
    as far as the paths under test, so that state is left out of the errors.
    """
    good = [(r.gammas[k], r.settings) for r in refs if r.ok[k] and math.isfinite(r.gammas[k])]
    spread = None
    if len(good) > 1:
        vals = np.array([g for g, _ in good])
        spread = float((vals.max() - vals.min()) / abs(vals.min()))
    if good:
        return good[0][0], good[0][1], spread
    return float("nan"), NO_REFERENCE, None


def time_rmpc(poly: PolytopicModel, cfg: TimingConfig, bar: CaseProgress | None = None) -> dict[str, Any]:
    """Time every RMPC path at the states of one closed loop; return records and samples."""
    paths, refs = _rmpc_paths(poly, cfg)
    x = RigidSatellite.initial_state()
    for path in paths + refs:
        if not path.rebuild:
            start = time.perf_counter()
            path.problem = path.make()
            # Warm-up, not timed: first-call set-up (cvxpy compiles here). At another state (E6's
            # 1.3 x0), so that a solver cvxpy warm-starts (SCS) does not start from the answer.
            path.problem.solve(1.3 * x)
            path.setup_s = time.perf_counter() - start
    fast = paths[0]
    a0, b0 = poly.vertex(0)
    gain = np.zeros((poly.n_inputs, poly.n_states))
    ref_gammas, ref_used, spreads, states = [], {}, [], []
    for k in range(cfg.steps):
        states.append(x.copy())
        shift = k % len(paths)
        fast_sol = None
        for path in paths[shift:] + paths[:shift] + refs:  # rotate the order: no path always first
            if k >= path.limit:
                continue
            sol = path.run(x)
            if path is fast:
                fast_sol = sol
        gamma_ref, used, spread = _reference_gamma(refs, k)
        ref_gammas.append(gamma_ref)
        tally(ref_used, used)
        if spread is not None:
            spreads.append(spread)
        gain = _next_gain(fast_sol, gain)
        x = a0 @ x + b0 @ (gain @ x)
        if bar is not None:
            bar.advance(f"RMPC {poly.n_vertices} vertices, state {k + 1}/{cfg.steps}")
    records, samples = [], {}
    for path in paths:
        n = len(path.times)
        rec = {
            "problem": "RMPC", "formulation": path.formulation, "backend": path.backend,
            "vertices": poly.n_vertices, "polytope": POLYTOPE_NAMES[poly.n_vertices], "steps": n,
            **percentiles(path.times),
            "solver_p50_s": percentiles(path.solver_times)["p50_s"],
            "iterations_p50": median_int(path.iterations),
            "status_counts": dict(path.statuses),
            "max_rel_err": rel_err(path.gammas, ref_gammas[:n]),
            "compared_steps": int(np.sum(np.isfinite(path.gammas) & np.isfinite(ref_gammas[:n]))),
            "min_margin": finite(np.nanmin(path.margins)) if np.any(np.isfinite(path.margins)) else None,
            "setup_s": finite(path.setup_s),
            "settings": path.settings,
        }
        records.append(rec)
        samples[sample_key(rec)] = np.asarray(path.times)
    rebuild = next(p for p in paths if p.rebuild)
    param = next(p for p in paths if p.backend == "cvxpy:CLARABEL")
    m = len(rebuild.times)
    ratio = {
        "vertices": poly.n_vertices, "steps": m,
        "rebuild_p50_s": float(np.median(rebuild.times)), "fast_p50_s": float(np.median(fast.times[:m])),
        "cvxpy_param_p50_s": float(np.median(param.times[:m])),
    }
    ratio["rebuild_over_fast"] = ratio["rebuild_p50_s"] / ratio["fast_p50_s"]
    ratio["rebuild_over_cvxpy_param"] = ratio["rebuild_p50_s"] / ratio["cvxpy_param_p50_s"]
    reference = {
        "vertices": poly.n_vertices, "steps": cfg.steps, "backend": "cvxpy:CLARABEL",
        "used": ref_used,
        "status_counts": {r.settings: dict(r.statuses) for r in refs},
        "p50_s": {r.settings: percentiles(r.times)["p50_s"] for r in refs},
        "min_margin": {r.settings: finite(np.nanmin(r.margins)) for r in refs},
        "spread_between_optimal_references": max(spreads) if spreads else None,
        "states_with_several_optimal": len(spreads),
    }
    return {"records": records, "samples": samples, "ratio": ratio, "reference": reference,
            "gamma_x0": ref_gammas[0] if ref_gammas else float("nan"), "states": states}


def _next_gain(sol: LMISolution | None, gain: np.ndarray) -> np.ndarray:
    """The gain the section's closed loop applies next: the fast path's when it is optimal, else the last."""
    return sol.F if sol is not None and sol.F is not None and sol.ok else gain


def section_states(poly: PolytopicModel, steps: int) -> list[np.ndarray]:
    """The states of :func:`time_rmpc`'s closed loop, from its fast path alone.

    The fast path (the toolkit's ipm, ``delta_shared``, warm-started) chains its warm starts over
    its own solves only, so solving it alone, with the same untimed first solve at ``1.3 x0``,
    visits the same states as the section does with every path interleaved. For a section that
    times other paths at those states when the RMPC section did not run.
    """
    x = RigidSatellite.initial_state()
    prob = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=U_MAX, backend="ipm",
                          formulation="delta_shared")
    prob.solve(1.3 * x)
    a0, b0 = poly.vertex(0)
    gain = np.zeros((poly.n_inputs, poly.n_states))
    states = []
    for _ in range(steps):
        states.append(x.copy())
        gain = _next_gain(prob.solve(x), gain)
        x = a0 @ x + b0 @ (gain @ x)
    return states


def reference_gamma_at(poly: PolytopicModel, x: np.ndarray) -> float:
    """``gamma(x)`` from the first optimal candidate of :data:`REFERENCES` (NaN if none is)."""
    for formulation, tol in REFERENCES:
        sol = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=U_MAX, backend="cvxpy",
                             solver="CLARABEL", formulation=formulation, solver_options=_tol(tol)).solve(x)
        if sol.ok:
            return sol.gamma
    return float("nan")


# -- the stand-alone script -----------------------------------------------------------------------
def closed_loop_states(n_steps: int, mode: str) -> list[np.ndarray]:
    """States visited by an RMPC closed loop (the fast path) on vertex 0 of the polytope."""
    sat = RigidSatellite.paper_p()
    x = sat.initial_state()
    poly = sat.polytope(x, PAPER_P_SAMPLE_TIME, 0.3, mode)
    prob = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=U_MAX)
    a, b = poly.vertex(0)
    states = []
    gain = np.zeros((3, 6))
    for _ in range(n_steps):
        states.append(x.copy())
        sol = prob.solve(x)
        if sol.F is not None and sol.certificate is not None and sol.certificate.ok:
            gain = sol.F
        x = a @ x + b @ (gain @ x)
    return states


def _time_path(make: Any, states: Sequence[np.ndarray], rebuild: bool) -> dict[str, Any]:
    times, statuses, gammas = [], {}, []
    prob = None if rebuild else make()
    for x in states:
        start = time.perf_counter()
        if rebuild:
            prob = make()
        sol = prob.solve(x)
        times.append(time.perf_counter() - start)
        statuses[sol.status] = statuses.get(sol.status, 0) + 1
        gammas.append(sol.gamma)
    return {"times": times, "status_counts": statuses, "gammas": np.asarray(gammas)}


def run(n_steps: int = 100, rebuild_steps: int = 20, modes: Sequence[str] = ("scalar", "box")) -> dict:
    """Run the benchmark and return the records (see the module docstring)."""
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    records = []
    for mode in modes:
        poly = sat.polytope(x0, PAPER_P_SAMPLE_TIME, 0.3, mode)
        states = closed_loop_states(n_steps, mode)

        def maker(backend: str, formulation: str, opts: dict | None = None, poly=poly) -> Any:
            return lambda: KothareProblem(
                poly.A, poly.B, Q1, R, dt=poly.dt, u_max=U_MAX, backend=backend,
                formulation=formulation, solver_options=opts,
            )

        reference = _time_path(maker("cvxpy", "delta", _tol(1e-10)), states, rebuild=False)["gammas"]
        paths = [
            ("ipm", "delta_shared", False, len(states)),
            ("clarabel", "delta_shared", False, len(states)),
            ("clarabel", "delta", False, len(states)),
            ("cvxpy-param", "delta", False, min(len(states), max(rebuild_steps, 20))),
            ("cvxpy-rebuild", "delta", True, min(len(states), rebuild_steps)),
        ]
        for name, formulation, rebuild, count in paths:
            backend = name if name in ("ipm", "clarabel") else "cvxpy"
            res = _time_path(maker(backend, formulation), states[:count], rebuild)
            rel = np.abs(res["gammas"] / reference[:count] - 1.0)
            records.append({
                "vertices": poly.n_vertices, "path": name, "formulation": formulation,
                "steps": count, **percentiles(res["times"]),
                "status_counts": res["status_counts"],
                "max_rel_err_gamma": float(np.nanmax(rel)) if np.any(np.isfinite(rel)) else None,
            })
    by_key = {(r["vertices"], r["path"], r["formulation"]): r for r in records}
    ratios = {}
    for vertices in sorted({r["vertices"] for r in records}):
        fast = by_key.get((vertices, "ipm", "delta_shared"))
        slow = by_key.get((vertices, "cvxpy-rebuild", "delta"))
        if fast and slow:
            ratios[str(vertices)] = slow["p50_s"] / fast["p50_s"]
    return {"machine": machine_info(), "versions": package_versions(), "records": records,
            "rebuild_over_fast_p50": ratios}


def format_table(result: dict) -> str:
    """A Markdown table of the records."""
    lines = [
        "| vertices | path | formulation | steps | p50 (ms) | p95 (ms) | max (ms) | statuses "
        "| max rel err gamma |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in result["records"]:
        err = "n/a" if r["max_rel_err_gamma"] is None else f"{r['max_rel_err_gamma']:.1e}"
        lines.append(
            f"| {r['vertices']} | {r['path']} | {r['formulation']} | {r['steps']} | "
            f"{1e3 * r['p50_s']:.1f} | {1e3 * r['p95_s']:.1f} | {1e3 * r['max_s']:.1f} | "
            f"{r['status_counts']} | {err} |"
        )
    lines.append("")
    lines.append("rebuild-per-step p50 / fast p50: " + ", ".join(
        f"{k} vertices: {v:.1f}x" for k, v in result["rebuild_over_fast_p50"].items()))
    m = result["machine"]
    lines.append(f"machine: {m['platform']}, {m['cpu_count']} CPUs, load average {m['load_average']}")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=100, help="closed-loop states per vertex count")
    parser.add_argument("--rebuild-steps", type=int, default=20, help="states for the rebuild path")
    parser.add_argument("--out", help="write the result as JSON to this file")
    args = parser.parse_args(argv)
    if args.steps < 1 or args.rebuild_steps < 1:
        parser.error("--steps and --rebuild-steps must be >= 1")
    result = run(args.steps, args.rebuild_steps)
    write_result(result, format_table(result), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
