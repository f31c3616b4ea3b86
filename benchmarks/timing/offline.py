"""Per-step lookup time and design time of off-line robust MPC on paper P's satellite.

**The section of** ``rmpc timing`` (:func:`time_offline`, called by :mod:`benchmarks.timing.suite`):
the table designed at ``x0`` on the report's polytope, its lookups timed at the states of its own
closed loop with and without interpolation, and ``gamma_1`` against the online ``gamma(x0)``.

**The stand-alone script**: run as
``python -m benchmarks.timing.offline [--steps N] [--repeats R] [--out FILE]``. For 2 and 8
vertices (inertia spread 0.3, ``||u|| <= 1``, Ts = 0.01 s, ``Q1 = diag(1, 1, 1, 0.1, 0.1,
0.1)``, ``R = I``) it designs :class:`rmpc.OfflineRMPC` from paper P's initial state (15
ellipsoids along its ray; the design time is the wall time of the construction), runs one closed
loop of the nominal linear model, and then times ``step(x)`` at the loop's states, ``R`` passes
over all of them, with and without interpolation. Reported per step: median, p95 and max of the
wall time of the call, and of the time the controller reports itself (``last.solve_time``), with
the machine and its load average (the machines are shared and noisy).

``max_rel_err`` compares each returned ``u`` with a direct evaluation (every level
``x' Q_i^-1 x`` by ``numpy.linalg.solve``, the interpolation weight from its formula).
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from benchmarks.core.machine import machine_info, package_versions, percentiles
from benchmarks.timing.common import (
    POLYTOPE_NAMES,
    Q1,
    U_MAX,
    R,
    finite,
    machine_line,
    sample_key,
    tally,
    write_result,
)
from benchmarks.timing.rmpc import reference_gamma_at
from models import PAPER_P_SAMPLE_TIME, RigidSatellite
from rmpc import OfflineRMPC, simulate

if TYPE_CHECKING:
    from benchmarks.timing.config import TimingConfig
    from models import PolytopicModel

__all__ = ["format_table", "lookup_times", "main", "reference_u", "run", "time_lookup", "time_offline"]

LEVEL_TOL = 1e-6


# -- lookups, timed and checked (both parts) ------------------------------------------------------
def reference_u(ctrl: OfflineRMPC, x: np.ndarray) -> np.ndarray:
    """``u`` computed the slow, obvious way from the stored table."""
    assert ctrl.table is not None
    ells = ctrl.table.ellipsoids
    levels = np.array([x @ np.linalg.solve(e.Q, x) for e in ells])
    inside = np.flatnonzero(levels <= 1.0 + LEVEL_TOL)
    if inside.size == 0:
        return ells[0].F @ x
    i = int(inside.max())
    if i == len(ells) - 1 or not (ctrl.interpolate and ctrl.table.interpolable[i]):
        return ells[i].F @ x
    alpha = min((levels[i + 1] - 1.0) / (levels[i + 1] - levels[i]), 1.0)
    return (alpha * ells[i].F + (1.0 - alpha) * ells[i + 1].F) @ x


def lookup_times(
    ctrl: OfflineRMPC, states: np.ndarray, repeats: int, check_u: bool = True
) -> tuple[list[float], list[float], dict[str, int], float | None]:
    """Time ``step`` at ``states``, ``repeats`` passes; then check ``u`` against :func:`reference_u`.

    Returns the wall time of each call, the controller's own ``solve_time`` of each, the status
    counts and the largest relative error of ``u`` (``None`` without ``check_u``).
    """
    ctrl.step(states[0])  # the first step of a run (reset by simulate) is not a plain lookup
    wall, reported, statuses = [], [], {}
    for _ in range(repeats):
        for x in states:
            start = time.perf_counter()
            ctrl.step(x)
            wall.append(time.perf_counter() - start)
            reported.append(ctrl.last.solve_time)
            tally(statuses, ctrl.last.status)
    if not check_u:
        return wall, reported, statuses, None
    err = 0.0
    for x in states:
        u, ref = ctrl.step(x), reference_u(ctrl, x)
        err = max(err, float(np.linalg.norm(u - ref) / max(np.linalg.norm(ref), 1e-300)))
    return wall, reported, statuses, err


def time_lookup(ctrl: OfflineRMPC, states: np.ndarray, repeats: int) -> dict[str, Any]:
    """Wall time of each ``step`` call and the controller's own ``solve_time``."""
    wall, reported, statuses, err = lookup_times(ctrl, states, repeats)
    rep = percentiles(reported)
    return {**percentiles(wall), "reported_p50_s": rep["p50_s"], "reported_p95_s": rep["p95_s"],
            "status_counts": statuses, "max_rel_err": err, "calls": len(wall)}


# -- the section of rmpc timing -------------------------------------------------------------------
def time_offline(poly: PolytopicModel, cfg: TimingConfig, gamma_x0: float | None) -> dict[str, Any]:
    """Design OfflineRMPC at ``x0``, then time its lookups at the states of its own closed loop."""
    x0 = RigidSatellite.initial_state()
    start = time.perf_counter()
    ctrl = OfflineRMPC(poly, Q1, R, u_max=U_MAX, x_design=x0, n_ellipsoids=cfg.n_ellipsoids)
    design_time = time.perf_counter() - start
    if gamma_x0 is None or not math.isfinite(gamma_x0):
        gamma_x0 = reference_gamma_at(poly, x0)
    table = ctrl.table
    gamma_1 = float(table.gammas[0]) if table is not None and table.n_ellipsoids else float("nan")
    err = abs(gamma_1 / gamma_x0 - 1.0) if math.isfinite(gamma_1) and math.isfinite(gamma_x0) else None
    states = simulate(ctrl, poly, x0, n_steps=cfg.cheap_steps).x[:-1]
    records, samples = [], {}
    for interpolate in (True, False):
        ctrl.interpolate = interpolate
        wall, reported, statuses, err_u = lookup_times(ctrl, states, cfg.lookup_repeats, table is not None)
        rec = {
            "problem": "OfflineRMPC", "formulation": "lookup" + ("+interpolation" if interpolate else ""),
            "backend": "numpy", "vertices": poly.n_vertices, "polytope": POLYTOPE_NAMES[poly.n_vertices],
            "steps": len(wall), **percentiles(wall),
            "solver_p50_s": percentiles(reported)["p50_s"], "iterations_p50": None,
            "status_counts": statuses, "max_rel_err": finite(err),
            "max_rel_err_u_lookup": finite(err_u),
            "design_time_s": design_time,
            "n_ellipsoids": table.n_ellipsoids if table is not None else 0,
            "gamma_1": finite(gamma_1), "gamma_ref_x0": finite(gamma_x0),
            "settings": f"{cfg.n_ellipsoids} ellipsoids along the ray of x0 (shrink 0.5), design by "
                        "cvxpy + Clarabel (delta_shared); lookups at the states of its closed loop, "
                        f"{cfg.lookup_repeats} passes",
        }
        records.append(rec)
        samples[sample_key(rec)] = np.asarray(wall)
    return {"records": records, "samples": samples}


# -- the stand-alone script -----------------------------------------------------------------------
def run(steps: int = 1000, repeats: int = 5, n_ellipsoids: int = 15,
        modes: Sequence[str] = ("scalar", "box")) -> dict[str, Any]:
    """Run the benchmark and return ``{"machine", "versions", "records"}``."""
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    records = []
    for mode in modes:
        poly = sat.polytope(x0, PAPER_P_SAMPLE_TIME, 0.3, mode)
        start = time.perf_counter()
        ctrl = OfflineRMPC(poly, Q1, R, u_max=U_MAX, x_design=x0, n_ellipsoids=n_ellipsoids)
        design_time = time.perf_counter() - start
        assert ctrl.table is not None
        states = simulate(ctrl, poly, x0, n_steps=steps).x[:-1]
        for interpolate in (True, False):
            ctrl.interpolate = interpolate  # the same table, looked up with or without interpolation
            rec = time_lookup(ctrl, states, repeats)
            records.append({
                "problem": "OfflineRMPC", "formulation": "lookup" + ("+interpolation" if interpolate else ""),
                "backend": "numpy", "vertices": poly.n_vertices, "n_ellipsoids": ctrl.table.n_ellipsoids,
                "design_time_s": design_time, "design_solver_time_s":
                    float(sum(e.solve_time for e in ctrl.table.ellipsoids)), **rec,
            })
    return {"machine": machine_info(), "versions": package_versions(), "records": records}


def format_table(result: dict[str, Any]) -> str:
    """A Markdown table of the records, then the machine."""
    lines = [
        "| vertices | ellipsoids | lookup | design (s) | p50 (us) | p95 (us) | max (us) "
        "| reported p50 (us) | statuses | max rel err u |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in result["records"]:
        lines.append(
            f"| {r['vertices']} | {r['n_ellipsoids']} | {r['formulation']} | {r['design_time_s']:.2f} | "
            f"{1e6 * r['p50_s']:.1f} | {1e6 * r['p95_s']:.1f} | {1e6 * r['max_s']:.1f} | "
            f"{1e6 * r['reported_p50_s']:.1f} | {r['status_counts']} | {r['max_rel_err']:.1e} |"
        )
    lines.append("")
    lines.append(machine_line(result["machine"]))
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1000, help="closed-loop states to look up")
    parser.add_argument("--repeats", type=int, default=5, help="passes over the states")
    parser.add_argument("--n-ellipsoids", type=int, default=15, help="ellipsoids in the table")
    parser.add_argument("--modes", nargs="+", default=["scalar", "box"], choices=["scalar", "box"],
                        help="inertia polytopes: scalar (2 vertices), box (8 vertices)")
    parser.add_argument("--out", help="write the result as JSON to this file")
    args = parser.parse_args(argv)
    if args.steps < 1 or args.repeats < 1 or args.n_ellipsoids < 1:
        parser.error("--steps, --repeats and --n-ellipsoids must be >= 1")
    result = run(args.steps, args.repeats, args.n_ellipsoids, args.modes)
    write_result(result, format_table(result), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
