"""Design time of the off-line nested design (Wan & Kothare 2003) per back-end, and gamma agreement.

Run as ``python -m dev.offline_timing --out DIR [--repeats R] [--cases ...] [--backends ...]``.
For each case the table of :class:`lmi.offline.NestedKothareProblem` is designed ``R`` times per
back-end (``"ipm"``, the toolkit's interior-point method, and ``"cvxpy"``, cvxpy + Clarabel), a
fresh problem each time (its construction counted: that is what a user pays once); reported per
back-end: the median, minimum and maximum wall time, the number of ellipsoids and whether the
design is complete (every ellipsoid ``"optimal"``: converged, certified and nested), the stop
reason, and per ellipsoid the status, ``gamma``, the solver's own words, the iterations where the
back-end counts them and the nesting margin; and where the time went (medians): the problem's
construction, the solver's own time summed over the stored ellipsoids, and the rest
(certificates, nesting and interpolation checks, Python, and the solve that stopped an incomplete
design). When both back-ends ran, the relative difference of
their gammas per ellipsoid, and the speed-up (cvxpy's median over the ipm's) only when both
designs were complete in every repeat: a design that stopped early is timed to its failure,
which is no time to compare with (the flexible case in the ``"delta_shared"`` form, on which
cvxpy + Clarabel ends ``"solver_error"`` at the first design state after a few seconds). The
machine and its load average go with the answer (the machines are shared and noisy).

Cases:

``F4``
    The flexible suite's F4 table (:mod:`benchmarks.suites.flexible`): the 14-state linear model
    ``[q_v, w, eta, eta']`` of the flexible satellite over its 8-vertex 'groups' polytope at
    0.5 s, ``Q1 = diag(400 I6, 0.1 I8)``, ``R = I``, per-axis peak bound 2 N m, the ``"delta"``
    form, 6 ellipsoids along the ray of the 10 deg slew's initial state, shrink 0.5.
``flex8``
    The same model, polytope, weights, bound and design states in the default ``"delta_shared"``
    form (the default of :class:`rmpc.OfflineRMPC`).
``paperP2``, ``paperP8``
    Paper P's satellite as :mod:`benchmarks.timing.offline` designs it (2 and 8 vertices, inertia
    spread 0.3, ``||u|| <= 1``, Ts = 0.01 s, 15 ellipsoids along the ray of ``x0``).

Writes ``offline_timing.json`` and ``offline_timing.md`` into ``DIR``.
"""

from __future__ import annotations

import argparse
import inspect
import json
import os
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.machine import machine_info, package_versions

__all__ = ["CASES", "case_problem", "main", "run", "speedup"]

#: Case name -> a short description (the module docstring has the details).
CASES: dict[str, str] = {
    "F4": "flexible F4: 14 states, 8 vertices, 0.5 s, peak 2 N m, 'delta', 6 ellipsoids",
    "flex8": "flexible: 14 states, 8 vertices, 0.5 s, peak 2 N m, 'delta_shared', 6 ellipsoids",
    "paperP2": "paper P: 6 states, 2 vertices, 0.01 s, ||u|| <= 1, 'delta_shared', 15 ellipsoids",
    "paperP8": "paper P: 6 states, 8 vertices, 0.01 s, ||u|| <= 1, 'delta_shared', 15 ellipsoids",
}


def _flexible(formulation: str) -> tuple[dict[str, Any], np.ndarray, int, float]:
    from benchmarks.families.flexible import defaults
    from benchmarks.families.flexible.controllers import linear_weights
    from benchmarks.families.flexible.family import _design_state, _polytope, paper_scenario
    from benchmarks.suites.flexible import flexible_cases

    case = next(c for c in flexible_cases(experiments=["F4"]) if c.tag == "OfflineRMPC")
    sc = case.scenario
    settings = {**defaults.CONTROLLER_DEFAULTS["OfflineRMPC"], **sc.settings}
    pc = paper_scenario(sc)
    sat = pc.satellite
    poly = _polytope(sat, sc.dt, settings["polytope"])
    q1, r = linear_weights(settings, sat.n_modes)
    args = {"A": poly.A, "B": poly.B, "Q": q1, "R": r, "dt": poly.dt, "input_constraint": "peak",
            "u_max": sc.u_max, "formulation": formulation}
    return args, _design_state(sat, pc), int(settings["n_ellipsoids"]), float(settings["shrink"])


def _paper_p(vertices: int) -> tuple[dict[str, Any], np.ndarray, int, float]:
    from benchmarks.timing.common import Q1, U_MAX, R
    from models import PAPER_P_SAMPLE_TIME, RigidSatellite

    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    mode = "scalar" if vertices == 2 else "box"
    poly = sat.polytope(x0, dt=PAPER_P_SAMPLE_TIME, spread=0.3, mode=mode)
    assert poly.n_vertices == vertices
    args = {"A": poly.A, "B": poly.B, "Q": Q1, "R": R, "dt": poly.dt, "input_constraint": "ellipsoid",
            "u_max": U_MAX, "formulation": "delta_shared"}
    return args, x0, 15, 0.5


_BUILDERS: dict[str, Callable[[], tuple[dict[str, Any], np.ndarray, int, float]]] = {
    "F4": lambda: _flexible("delta"),
    "flex8": lambda: _flexible("delta_shared"),
    "paperP2": lambda: _paper_p(2),
    "paperP8": lambda: _paper_p(8),
}


def case_problem(name: str) -> tuple[dict[str, Any], np.ndarray, int, float]:
    """``(NestedKothareProblem keyword arguments, x_1, n_ellipsoids, shrink)`` of a case."""
    return _BUILDERS[name]()


def _has_backend_option() -> bool:
    from lmi.offline import NestedKothareProblem

    return "backend" in inspect.signature(NestedKothareProblem).parameters


def _design(args: dict[str, Any], x1: np.ndarray, count: int, shrink: float, backend: str) -> dict[str, Any]:
    from lmi.offline import NestedKothareProblem

    extra = {"backend": backend} if _has_backend_option() else {}
    start = time.perf_counter()
    prob = NestedKothareProblem(**args, **extra)
    built = time.perf_counter()
    table = prob.design_ray(x1, count, shrink)
    wall = time.perf_counter() - start
    ells = list(table.ellipsoids)
    solver_s = float(sum(e.solve_time for e in ells))
    iterations = [getattr(e, "iterations", None) for e in ells]
    return {
        "wall_s": wall,
        "construct_s": built - start,
        "solver_s": solver_s,
        "rest_s": wall - (built - start) - solver_s,
        "iterations_total": None if not ells or None in iterations else int(sum(iterations)),
        "n_ellipsoids": table.n_ellipsoids,
        "complete": table.stop_reason == "complete" and table.n_ellipsoids == count
        and all(e.ok for e in ells),
        "stop_reason": table.stop_reason,
        "status": [e.status for e in ells] + ([table.failed_status] if table.failed_status else []),
        "gamma": [float(e.gamma) for e in ells],
        "solver_status": [e.solver_status for e in ells],
        "iterations": iterations,
        "nesting_margin": [float(e.nesting_margin) for e in ells],
        "solve_s": [float(e.solve_time) for e in ells],
    }


def run(cases: Sequence[str], backends: Sequence[str], repeats: int) -> dict[str, Any]:
    """Design every case ``repeats`` times per back-end; see the module docstring."""
    if not _has_backend_option():
        backends = [b for b in backends if b == "cvxpy"]
    out: dict[str, Any] = {"machine": machine_info(), "packages": package_versions(), "repeats": repeats,
                           "load_before": os.getloadavg(), "cases": {}}
    for name in cases:
        args, x1, count, shrink = case_problem(name)
        entry: dict[str, Any] = {"description": CASES[name]}
        for backend in backends:
            runs = [_design(args, x1, count, shrink, backend) for _ in range(repeats)]
            walls = [r["wall_s"] for r in runs]
            entry[backend] = {"median_s": float(np.median(walls)), "min_s": min(walls), "max_s": max(walls),
                              "walls_s": walls, "last": runs[-1],
                              "complete_all": all(r["complete"] for r in runs),
                              **{f"{part}_median_s": float(np.median([r[f"{part}_s"] for r in runs]))
                                 for part in ("construct", "solver", "rest")}}
            print(f"{name:8s} {backend:6s} median {entry[backend]['median_s']:8.2f} s  "
                  f"{runs[-1]['n_ellipsoids']} ellipsoids  {runs[-1]['stop_reason']}", flush=True)
        if "ipm" in entry and "cvxpy" in entry:
            g_i, g_c = entry["ipm"]["last"]["gamma"], entry["cvxpy"]["last"]["gamma"]
            k = min(len(g_i), len(g_c))
            entry["gamma_rel_diff"] = [abs(a - b) / max(abs(b), 1e-300) for a, b in zip(g_i[:k], g_c[:k],
                                                                                         strict=True)]
            entry["speedup"], entry["speedup_note"] = speedup(entry)
        out["cases"][name] = entry
    out["load_after"] = os.getloadavg()
    return out


def speedup(entry: dict[str, Any]) -> tuple[float | None, str]:
    """cvxpy's median design time over the ipm's for one case of :func:`run`, and a note.

    ``None`` (the note says why) unless both back-ends designed the complete table in every
    repeat: an incomplete design is timed only up to the solve that stopped it.
    """
    if "ipm" not in entry or "cvxpy" not in entry:
        return None, "no speed-up: one back-end did not run"
    failed = [b for b in ("ipm", "cvxpy") if not entry[b]["complete_all"]]
    if failed:
        why = "; ".join(f"{b} incomplete ({entry[b]['last']['stop_reason']})" for b in failed)
        return None, f"no speed-up: {why}, timed to its failure"
    return entry["cvxpy"]["median_s"] / entry["ipm"]["median_s"], "cvxpy / ipm, both complete"


def _markdown(res: dict[str, Any]) -> str:
    lines = ["# Off-line nested design: design time per back-end", "",
             f"machine: {res['machine']}",
             f"load average before / after: {res['load_before']} / {res['load_after']}",
             f"repeats: {res['repeats']} (fresh problem each, construction counted)", "",
             "| case | back-end | median (s) | min / max (s) | construction / solver / rest (s) "
             "| iterations | ellipsoids | complete | stop reason |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for name, entry in res["cases"].items():
        for backend in ("ipm", "cvxpy"):
            if backend not in entry:
                continue
            e = entry[backend]
            median = f"{e['median_s']:.2f}" + ("" if e["complete_all"] else " (to failure)")
            parts = " / ".join(f"{e.get(f'{p}_median_s', float('nan')):.2f}"
                               for p in ("construct", "solver", "rest"))
            lines.append(f"| {name} | {backend} | {median} | {e['min_s']:.2f} / {e['max_s']:.2f} | "
                         f"{parts} | {e['last'].get('iterations_total')} | {e['last']['n_ellipsoids']} | "
                         f"{e['complete_all']} | {e['last']['stop_reason']} |")
    speedups = [(name, entry) for name, entry in res["cases"].items() if "speedup_note" in entry]
    if speedups:
        lines += ["", "Speed-up of the ipm design (median over median):", ""]
        lines += [f"- {name}: " + (f"{entry['speedup']:.1f}x ({entry['speedup_note']})"
                                   if entry["speedup"] is not None else entry["speedup_note"])
                  for name, entry in speedups]
    lines += ["", "Gamma per ellipsoid (last repeat) and |gamma_ipm - gamma_cvxpy| / gamma_cvxpy:", ""]
    for name, entry in res["cases"].items():
        lines.append(f"- {name}: " + "; ".join(
            f"{b} {[f'{g:.6g}' for g in entry[b]['last']['gamma']]}" for b in ("ipm", "cvxpy") if b in entry))
        if "gamma_rel_diff" in entry:
            lines.append(f"  rel. diff {[f'{d:.1e}' for d in entry['gamma_rel_diff']]}")
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: ``python -m dev.offline_timing --out DIR``."""
    parser = argparse.ArgumentParser(prog="python -m dev.offline_timing",
                                     description=(__doc__ or "").split("\n")[0])
    parser.add_argument("--out", required=True, help="output directory")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    parser.add_argument("--backends", nargs="+", default=["ipm", "cvxpy"], choices=["ipm", "cvxpy"])
    ns = parser.parse_args(argv)
    if ns.repeats < 1:
        parser.error("--repeats must be >= 1")
    res = run(ns.cases, ns.backends, ns.repeats)
    out = Path(ns.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "offline_timing.json").write_text(json.dumps(res, indent=1, default=str), encoding="utf-8")
    (out / "offline_timing.md").write_text(_markdown(res), encoding="utf-8")
    print(_markdown(res))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
