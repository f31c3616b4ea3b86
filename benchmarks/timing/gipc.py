"""Per-step time of GIPC with each QP back-end, against the same QP through cvxpy, in one run.

**The section of** ``rmpc timing`` (:func:`time_gipc`, called by :mod:`benchmarks.timing.suite`):
the QPs of one GIPC closed loop (with E4's step disturbance half-way), solved by every back-end
of :data:`GIPC_BACKENDS`, interleaved, against cvxpy + Clarabel at 1e-10, with the KKT residual.

**The stand-alone script**: run as
``python -m benchmarks.timing.gipc [--steps N] [--plant linear|nonlinear] [--json FILE]``.
Each back-end drives its own closed loop of paper P's problem: the satellite from paper P's
initial attitude, ``Ts = 0.01`` s, GIPC with its defaults (``Np = 400``, ``Nc = 4``,
``|u| <= 1``, ``|du| <= 0.01``) and experiment E4's 0.5 N m step disturbance from t = 10 s,
so the loop has a constrained transient, a disturbance and a quiet end. The ``cvxpy`` row
solves the same QP modelled in cvxpy (parameters, DPP; Clarabel at 1e-10) through the same
controller. Reported per back-end, over all steps but the first (the first builds the
solver; its time is ``setup_s``):

- ``step``: wall time of ``GIPC.step`` (vectors, update, solve, checks) - the controller's
  cost per sample;
- ``solve``: wall time of the back-end's solve call alone;
- median, p95 and max of each, the ratio of the median step time to cvxpy's, the status
  counts, and the largest error of the applied ``du`` against a certified high-accuracy
  solution of the same QP (:func:`rmpc.qp.reference_solution`) on every
  ``--check-every``-th step, as a fraction of the ``du`` bound.

The machine (platform, CPU count, load average) and package versions are printed with the
figures: the timings depend on them.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from benchmarks.core.machine import machine_info, package_versions, percentiles
from benchmarks.timing.common import finite, median_int, rel_err, sample_key, tally
from models import PAPER_P_SAMPLE_TIME, RigidSatellite
from rmpc import GIPC, StepDisturbance, simulate
from rmpc.qp import QP, kkt_residuals, make_backend, reference_solution

if TYPE_CHECKING:
    from benchmarks.core.progress import CaseProgress
    from benchmarks.timing.config import TimingConfig

__all__ = ["GIPC_BACKENDS", "main", "run", "time_gipc"]

BACKENDS = ("proxqp", "osqp", "clarabel", "cvxpy")
#: The bound on the input increments ``|du| <= DU_MAX`` (N m per step), in both parts.
DU_MAX = 0.01
#: The reference of the section: cvxpy + Clarabel at this tolerance.
TIGHT = 1e-10
#: The section's back-ends: (label in the report, back-end name, its settings).
GIPC_BACKENDS: tuple[tuple[str, str, dict[str, Any]], ...] = (
    ("proxqp", "proxqp", {}),
    ("osqp", "osqp", {}),
    ("clarabel", "clarabel", {}),
    ("cvxpy:CLARABEL", "cvxpy", {"tol": 1e-8}),
)


# -- the section of rmpc timing -------------------------------------------------------------------
def time_gipc(cfg: TimingConfig, bar: CaseProgress | None = None) -> dict[str, Any]:
    """Time ``update + solve`` of every QP back-end on the QPs of one GIPC closed loop."""
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    model = sat.linear_model(x0, PAPER_P_SAMPLE_TIME)
    ctrl = GIPC(model, du_max=DU_MAX)
    n = cfg.cheap_steps
    t_dist = min(10.0, 0.5 * n * PAPER_P_SAMPLE_TIME)
    traj = simulate(ctrl, model, x0, n_steps=n, disturbance=StepDisturbance([0.5, 0.5, 0.5], t_dist))
    qps: list[QP] = []
    for k in range(traj.n_steps):
        prev = (None, None) if k == 0 else (traj.x[k - 1], traj.u_cmd[k - 1])
        qps.append(ctrl.qp_at(traj.x[k], *prev))
    vectors = [{"g": qp.g, "l": qp.l, "u": qp.u, "lb": qp.lb, "ub": qp.ub} for qp in qps]
    ref = make_backend("cvxpy", solver="CLARABEL", tol=TIGHT)
    ref.setup(qps[0])
    ref_obj, ref_status = [], {}
    for vec in vectors:
        ref.update(**vec)
        res = ref.solve()
        ref_obj.append(res.objective if res.status == "optimal" else float("nan"))
        tally(ref_status, res.status)
    warm = ctrl.qp_at(1.3 * x0)  # warm-up QP (not timed), unlike the first one: no free warm start
    backends = []
    for label, name, settings in GIPC_BACKENDS:
        be = make_backend(name, **settings)
        start = time.perf_counter()
        be.setup(warm)
        be.solve()
        backends.append({"label": label, "be": be, "setup_s": time.perf_counter() - start, "times": [],
                         "solver": [], "iters": [], "obj": [], "kkt": [], "status": {}})
    for k, vec in enumerate(vectors):
        shift = k % len(backends)
        for b in backends[shift:] + backends[:shift]:
            t0 = time.perf_counter()
            b["be"].update(**vec)
            res = b["be"].solve()
            b["times"].append(time.perf_counter() - t0)
            b["solver"].append(res.solve_time)
            b["iters"].append(res.iterations)
            b["obj"].append(res.objective)
            tally(b["status"], res.status)
            if res.status in ("optimal", "inaccurate"):
                b["kkt"].append(kkt_residuals(qps[k], res).max())
    if bar is not None:
        bar.advance("GIPC")
    records, samples = [], {}
    for b in backends:
        rec = {
            "problem": "GIPC", "formulation": f"velocity-form QP (Np={ctrl.Np}, Nc={ctrl.Nc})",
            "backend": b["label"], "vertices": 1, "polytope": "nominal", "steps": len(b["times"]),
            **percentiles(b["times"]),
            "solver_p50_s": percentiles(b["solver"])["p50_s"],
            "iterations_p50": median_int(b["iters"]),
            "status_counts": b["status"],
            "max_rel_err": rel_err(b["obj"], ref_obj, floor=1e-12),
            "max_kkt_residual": finite(max(b["kkt"])) if b["kkt"] else None,
            "setup_s": b["setup_s"],
            "settings": repr(b["be"].settings),
        }
        records.append(rec)
        samples[sample_key(rec)] = np.asarray(b["times"])
    reference = {"backend": "cvxpy:CLARABEL", "tol": TIGHT, "status_counts": ref_status,
                 "disturbance_start_s": t_dist, "controller": ctrl.settings()}
    return {"records": records, "samples": samples, "reference": reference}


# -- the stand-alone script -----------------------------------------------------------------------


def _one(backend: str, steps: int, plant: str, check_every: int) -> dict[str, Any]:
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    model = sat.linear_model(x0, PAPER_P_SAMPLE_TIME)
    ctrl = GIPC(model, backend=backend, du_max=DU_MAX)
    sim_plant = sat if plant == "nonlinear" else model
    start = time.perf_counter()
    traj = simulate(
        ctrl, sim_plant, x0, n_steps=steps, dt=PAPER_P_SAMPLE_TIME if plant == "nonlinear" else None,
        disturbance=StepDisturbance([0.5, 0.5, 0.5], 10.0),
    )
    wall = time.perf_counter() - start
    errs = []
    for k in range(1, traj.n_steps, check_every):
        res = reference_solution(ctrl.qp_at(traj.x[k], traj.x[k - 1], traj.u_cmd[k - 1]))
        du = traj.u_cmd[k] - traj.u_cmd[k - 1]
        errs.append(float(np.abs(du - res.x[:3]).max()) / DU_MAX)
    step_times = traj.step_time[1:]
    solve_times = traj.solve_time[1:]
    return {
        "backend": backend,
        "settings": repr(ctrl.backend.settings),
        "steps": traj.n_steps,
        "setup_s": float(traj.step_time[0]),
        "step": percentiles(step_times),
        "solve": percentiles(solve_times),
        "status_counts": traj.status_counts(),
        "fallbacks": int(sum(bool(getattr(i, "fallback", False)) for i in traj.info)),
        "max_du_err_frac": max(errs) if errs else float("nan"),
        "checked_steps": len(errs),
        "final_attitude_err_rad": float(np.abs(traj.x[-1, :3]).max()),
        "loop_wall_s": wall,
    }


def run(steps: int = 2000, plant: str = "linear", check_every: int = 20,
        backends: Sequence[str] = BACKENDS) -> dict[str, Any]:
    """Time every back-end; return ``{"machine", "versions", "controller", "records"}``."""
    if steps < 2:
        raise ValueError(f"steps: expected an integer >= 2, but found {steps}")
    records = [_one(name, steps, plant, check_every) for name in backends]
    base = next((r for r in records if r["backend"] == "cvxpy"), None)
    for rec in records:
        rec["ratio_to_cvxpy"] = (
            rec["step"]["p50_s"] / base["step"]["p50_s"] if base is not None else float("nan")
        )
    return {
        "problem": "GIPC",
        "machine": machine_info(),
        "versions": package_versions(),
        "controller": {"Np": 400, "Nc": 4, "Qy": 1.0, "R_du": 1.0, "u_max": 1.0, "du_max": DU_MAX,
                       "plant": plant, "disturbance": "0.5 N m per axis from t = 10 s",
                       "dt": PAPER_P_SAMPLE_TIME},
        "records": records,
    }


def _print(report: dict[str, Any]) -> None:
    m = report["machine"]
    print(f"GIPC per-step time, paper P's satellite ({report['controller']['plant']} plant, E4 disturbance)")
    print(f"machine: {m['platform']}, {m['processor']}, cpu_count={m['cpu_count']}, "
          f"load={m['load_average']}, python {m['python']}")
    print("versions: " + ", ".join(f"{k} {v}" for k, v in report["versions"].items()))
    head = (f"{'backend':9s} {'step p50':>9s} {'p95':>8s} {'max':>8s}  {'solve p50':>9s} {'p95':>8s} "
            f"{'max':>8s}  {'vs cvxpy':>8s}  {'du err/bound':>12s}  statuses")
    print(head)
    print("-" * len(head))
    for r in report["records"]:
        s, v = r["step"], r["solve"]
        print(f"{r['backend']:9s} {s['p50_s'] * 1e3:7.3f}ms {s['p95_s'] * 1e3:6.3f}ms "
              f"{s['max_s'] * 1e3:6.2f}ms  "
              f"{v['p50_s'] * 1e3:7.3f}ms {v['p95_s'] * 1e3:6.3f}ms {v['max_s'] * 1e3:6.2f}ms  "
              f"{r['ratio_to_cvxpy']:8.4f}  {r['max_du_err_frac']:12.1e}  {r['status_counts']}")
    print(f"steps per back-end: {report['records'][0]['steps']} (the first, solver set-up, excluded)")


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.timing.gipc", description=(__doc__ or "").split("\n")[0]
    )
    parser.add_argument(
        "--steps", type=int, default=2000, help="closed-loop steps per back-end (default 2000)"
    )
    parser.add_argument("--plant", choices=("linear", "nonlinear"), default="linear",
                        help="plant of the closed loop (the controller's time does not depend on it)")
    parser.add_argument("--check-every", type=int, default=20,
                        help="compare the applied du with a high-accuracy solution every N steps")
    parser.add_argument("--backends", default=",".join(BACKENDS), help="comma-separated back-end names")
    parser.add_argument("--json", default=None, help="also write the report to this JSON file")
    args = parser.parse_args(argv)
    if args.steps < 2 or args.check_every < 1:
        print("gipc_timing: error: --steps must be >= 2 and --check-every >= 1", file=sys.stderr)
        return 2
    names = [b.strip() for b in args.backends.split(",") if b.strip()]
    unknown = [b for b in names if b not in BACKENDS]
    if unknown:
        print(
            f"gipc_timing: error: unknown back-end(s) {unknown}; choose from {list(BACKENDS)}",
            file=sys.stderr,
        )
        return 2
    report = run(args.steps, args.plant, args.check_every, names)
    _print(report)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(report, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
