"""Per-step solve time of online robust MPC on paper P's problem, fast path vs rebuild path.

Run as ``python -m benchmarks.timing.rmpc [--steps N] [--out FILE]``. For 2 and 8 vertices
(inertia spread 0.3, ``||u|| <= 1``, Ts = 0.01 s) it follows the states of one closed loop
from paper P's initial attitude (the linear model, the vertex of the larger inertia) and at
each state times, in the same run:

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
import json
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from benchmarks.core.machine import machine_info, package_versions, percentiles
from lmi import KothareProblem
from models import PAPER_P_SAMPLE_TIME, RigidSatellite

Q1 = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])
R = np.eye(3)
U_MAX = 1.0


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

        tight = {"tol_gap_abs": 1e-10, "tol_gap_rel": 1e-10, "tol_feas": 1e-10}
        reference = _time_path(maker("cvxpy", "delta", tight), states, rebuild=False)["gammas"]
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
    print(format_table(result))
    if args.out:
        with open(args.out, "w", encoding="utf-8") as fh:
            json.dump(result, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
