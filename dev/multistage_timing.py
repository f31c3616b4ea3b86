"""Multi-stage MPC on paper P's satellite: the target run and the growth of the tree.

Run as ``python -m dev.multistage_timing --out DIR [--part target|growth|both] [--runs R]
[--steps S] [--backends ...] [--growth-steps S] [--budget SECONDS]``.

``target``
    Paper P's 2-vertex satellite (inertia +-30 %, ``mode="scalar"``, Ts = 0.01 s, the start
    attitude of paper P), ``Q1 = diag(1, 1, 1, 0.1, 0.1, 0.1)``, ``R = 0.01 I`` (the rigid
    family's weights), horizon 10, robust horizon 1, ``|u_i| <= 1`` N m and the rate bound
    ``|w_i| <= 0.2`` rad/s (the closed loop without it reaches 0.42 rad/s), ``R`` runs of ``S``
    samples on seeded switching vertices (:func:`rmpc.mpc.switching_runs.switching_runs`):
    violations, statuses, fallbacks, solve time p50/p95, per back-end.
``growth``
    The same problem over 2, 4 and 8 vertices (4: roll and pitch inertia together and the yaw
    inertia, each +-30 %; 8: ``mode="box"``) and robust horizons 1, 2 and 3: the tree's and the
    QP's size (variables, rows, non-zeros of ``H`` and ``C``), the construction time, the first
    solve and the p50/p95 of one seeded switching run of ``--growth-steps`` samples (cut by
    ``--budget`` seconds per case), per back-end (the dense ProxQP only up to
    :data:`rmpc.mpc.multistage.MAX_DENSE_VARIABLES` variables).

Writes ``multistage_timing.json`` and ``multistage_timing.md`` into ``DIR``, with the machine's
load average before and after (the machine is shared; times are wall times).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path
from typing import Any

import numpy as np

Q_DIAG = (1.0, 1.0, 1.0, 0.1, 0.1, 0.1)
R_DIAG = (0.01, 0.01, 0.01)
RATE_MAX = 0.2
SPREAD = 0.3
DT = 0.01
HORIZON = 10


def _plant(n_vertices: int) -> Any:
    from models import PolytopicModel, RigidSatellite

    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    if n_vertices in (2, 8):
        return sat.polytope(x0, dt=DT, spread=SPREAD, mode="scalar" if n_vertices == 2 else "box"), x0
    if n_vertices != 4:
        raise ValueError(f"n_vertices: expected 2, 4 or 8, but found {n_vertices}")
    inertia = np.asarray(sat.inertia, dtype=float)
    verts = []
    for s_xy in (1.0 + SPREAD, 1.0 - SPREAD):
        for s_z in (1.0 + SPREAD, 1.0 - SPREAD):
            verts.append(RigidSatellite(inertia * np.array([s_xy, s_xy, s_z])).discretize(x0, DT))
    return PolytopicModel(verts, DT, nominal=sat.discretize(x0, DT), attitude="euler321"), x0


def _rate_bound() -> tuple[np.ndarray, np.ndarray]:
    rows = np.vstack((np.eye(6)[3:], -np.eye(6)[3:]))
    return rows, np.full(6, RATE_MAX)


def _controller(plant: Any, robust_horizon: int, backend: str) -> Any:
    from rmpc import MultiStageMPC

    return MultiStageMPC(plant, Q=np.diag(Q_DIAG), R=np.diag(R_DIAG), horizon=HORIZON,
                         robust_horizon=robust_horizon, u_max=1.0, state_constraints=_rate_bound(),
                         backend=backend)


def target(runs: int, steps: int, backends: list[str]) -> list[dict[str, Any]]:
    """The paper-P 2-vertex, robust-horizon-1 target per back-end."""
    from rmpc.mpc.switching_runs import switching_runs

    plant, x0 = _plant(2)
    out = []
    for backend in backends:
        ctrl = _controller(plant, 1, backend)
        start = time.perf_counter()
        res = switching_runs(ctrl, plant, x0, steps=steps, runs=runs, seed=2026, u_max=1.0,
                             state_constraints=_rate_bound(), Q=np.diag(Q_DIAG), R=np.diag(R_DIAG))
        res.update(backend=backend, wall_s=time.perf_counter() - start, runs=runs, steps=steps)
        out.append(res)
        print(f"target {backend}: violations {res['violations']} of {res['samples']}, "
              f"p50 {1e3 * res['solve_time_p50']:.3f} ms, p95 {1e3 * res['solve_time_p95']:.3f} ms, "
              f"statuses {res['status_counts']}", flush=True)
    return out


def growth(steps: int, budget: float, backends: list[str]) -> list[dict[str, Any]]:
    """Size and solve times over vertices 2, 4, 8 and robust horizons 1, 2, 3."""
    from rmpc.mpc.multistage import MAX_DENSE_VARIABLES
    from rmpc.mpc.scenario_tree import tree_size

    out = []
    for n_v in (2, 4, 8):
        plant, x0 = _plant(n_v)
        vertices = [plant.vertex(j) for j in range(n_v)]
        for nr in (1, 2, 3):
            size = tree_size(n_v, HORIZON, nr, n_states=6, n_inputs=3, state_rows=6)
            for backend in backends:
                rec: dict[str, Any] = {"vertices": n_v, "robust_horizon": nr, "backend": backend, **size}
                if backend == "proxqp" and size["variables"] > MAX_DENSE_VARIABLES:
                    rec["skipped"] = f"dense back-end, {size['variables']} > {MAX_DENSE_VARIABLES} variables"
                    out.append(rec)
                    continue
                start = time.perf_counter()
                ctrl = _controller(plant, nr, backend)
                rec["build_s"] = time.perf_counter() - start
                qp = ctrl.qp_at(x0)
                rec["nnz_H"], rec["nnz_C"] = int(qp.H.nnz), int(qp.C.nnz)
                rng = np.random.default_rng(7)
                x, times, statuses = np.array(x0, dtype=float), [], {}
                deadline = time.perf_counter() + budget
                for k in range(steps):
                    start = time.perf_counter()
                    u = ctrl.step(x)
                    if k == 0:
                        rec["first_step_s"] = time.perf_counter() - start
                    else:
                        times.append(ctrl.last.solve_time)
                    key = str(ctrl.last.status)
                    statuses[key] = statuses.get(key, 0) + 1
                    a, b = vertices[int(rng.integers(n_v))]
                    x = a @ x + b @ u
                    if time.perf_counter() > deadline:
                        break
                rec["steps"] = len(times) + 1
                rec["status_counts"] = statuses
                rec["p50_s"] = float(np.percentile(times, 50)) if times else None
                rec["p95_s"] = float(np.percentile(times, 95)) if times else None
                out.append(rec)
                p50 = "-" if rec["p50_s"] is None else f"{1e3 * rec['p50_s']:.2f}"
                print(f"growth V={n_v} Nr={nr} {backend}: {size['variables']} vars, build "
                      f"{rec['build_s']:.2f} s, p50 {p50} ms over {rec['steps']} steps, {statuses}",
                      flush=True)
    return out


def _markdown(data: dict[str, Any]) -> str:
    lines = ["# Multi-stage MPC on paper P's satellite", "",
             f"Machine: {data['machine']}; load average before {data['load_before']}, "
             f"after {data['load_after']}.",
             ""]
    if data.get("target"):
        lines += ["## Target: 2 vertices, robust horizon 1, horizon 10, |u_i| <= 1, |w_i| <= 0.2", "",
                  "| back-end | runs x steps | violations | input / state | max state excess | statuses | "
                  "fallbacks | p50 (ms) | p95 (ms) |", "|---|---|---|---|---|---|---|---|---|"]
        for r in data["target"]:
            lines.append(
                f"| {r['backend']} | {r['runs']} x {r['steps']} | {r['violations']} | "
                f"{r['input_violations']} / "
                f"{r['state_violations']} | {r['max_state_excess']:.3g} | {r['status_counts']} | "
                f"{r['fallbacks']} | "
                f"{1e3 * r['solve_time_p50']:.3f} | {1e3 * r['solve_time_p95']:.3f} |")
        lines.append("")
    if data.get("growth"):
        lines += ["## Growth (horizon 10)", "",
                  "| V | Nr | scenarios | variables | eq. rows | ineq. rows | back-end | nnz C | build (s) | "
                  "first step (s) | steps | p50 (ms) | p95 (ms) | statuses |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for r in data["growth"]:
            if "skipped" in r:
                lines.append(f"| {r['vertices']} | {r['robust_horizon']} | {r['scenarios']} | "
                             f"{r['variables']} | "
                             f"{r['equality_rows']} | {r['inequality_rows']} | {r['backend']} | "
                             f"{r['skipped']} | | | | | | |")
                continue
            p50 = "-" if r["p50_s"] is None else f"{1e3 * r['p50_s']:.2f}"
            p95 = "-" if r["p95_s"] is None else f"{1e3 * r['p95_s']:.2f}"
            lines.append(
                f"| {r['vertices']} | {r['robust_horizon']} | {r['scenarios']} | {r['variables']} | "
                f"{r['equality_rows']} | {r['inequality_rows']} | {r['backend']} | {r['nnz_C']} | "
                f"{r['build_s']:.2f} | {r['first_step_s']:.3f} | {r['steps']} | {p50} | {p95} | "
                f"{r['status_counts']} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    """Run the parts asked for and write the JSON and Markdown reports."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--part", choices=("target", "growth", "both"), default="both")
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--growth-steps", type=int, default=60)
    parser.add_argument("--budget", type=float, default=60.0)
    parser.add_argument("--backends", nargs="+", default=["proxqp", "clarabel", "osqp"])
    args = parser.parse_args(argv)
    machine = f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    data: dict[str, Any] = {"machine": machine,
                            "load_before": [round(v, 2) for v in os.getloadavg()]}
    if args.part in ("target", "both"):
        data["target"] = target(args.runs, args.steps, args.backends)
    if args.part in ("growth", "both"):
        data["growth"] = growth(args.growth_steps, args.budget, args.backends)
    data["load_after"] = [round(v, 2) for v in os.getloadavg()]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "multistage_timing.json").write_text(json.dumps(data, indent=1, default=str))
    (out / "multistage_timing.md").write_text(_markdown(data))
    print(f"wrote {out / 'multistage_timing.md'}")


if __name__ == "__main__":
    main()
