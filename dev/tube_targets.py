"""Measure tube MPC's targets (python -m dev.tube_targets [--runs N] [--problem NAME]).

Zero constraint violations over 1,000 seeded 50-step disturbance sequences and a QP solve p50 of
at most 1 ms on the double integrator, for both kinds and each QP back-end asked for; prints the
measured figures, the machine's load and the share of the state box the tube's QP is feasible
from. ``--problem paper_p_hold``: the tightening on paper P's satellite holding attitude under a
gravity-gradient torque through B (the methods bench's problem; the box is paper P's start
attitude and 0.05 rad/s, the rigid tube refuses the flat disturbance).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from rmpc.mpc.tube import TubeMPC
from rmpc.mpc.tube_runs import disturbance_runs, double_integrator, feasible_initial_states


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--steps", type=int, default=50)
    parser.add_argument("--seed", type=int, default=2005)
    parser.add_argument("--kinds", nargs="+", default=["rigid", "tightening"])
    parser.add_argument("--backends", nargs="+", default=["clarabel"])
    parser.add_argument("--problem", choices=["double_integrator", "paper_p_hold"],
                        default="double_integrator")
    args = parser.parse_args(argv)
    if args.problem == "paper_p_hold":
        from benchmarks.suites.methods_problems import HOLD_FRACTION, build_problem

        p = build_problem("paper_p_hold")
        plant = p.true_plant
        options = {"Q": p.Q, "R": p.R, "horizon": 9, "u_max": p.u_max, "w_max": p.w_box, "E": p.w_matrix}
        box = np.concatenate([np.abs(p.x0[:3]) / HOLD_FRACTION, [0.05] * 3])    # paper P's start
        kinds = [k for k in args.kinds if k == "tightening"]
    else:
        problem = double_integrator()
        plant, options, box = (problem["A"], problem["B"]), problem["controller"], np.array([10.0, 10.0])
        kinds = args.kinds
    for kind in kinds:
        for backend in args.backends:
            start = time.perf_counter()
            tube = TubeMPC(plant, **options, kind=kind, backend=backend)
            design = time.perf_counter() - start
            rng = np.random.default_rng(args.seed)
            x0s, share = feasible_initial_states(tube, box, args.runs, rng)
            load = os.getloadavg()[0]
            runs = disturbance_runs(tube, x0s, steps=args.steps, rng=rng)
            p50, p95 = np.percentile(runs.solve_times, [50, 95]) * 1e3
            s50, s95 = np.percentile(runs.step_times, [50, 95]) * 1e3
            print(f"{kind:10s} {backend:8s} design {design:.3f} s | feasible share of the box {share:.3f} | "
                  f"{runs.runs} runs x {runs.steps} steps: violations {runs.violations}, "
                  f"max excess {runs.max_excess:.3g}, failed steps {runs.failed_steps} | "
                  f"solve p50 {p50:.3f} ms p95 {p95:.3f} ms | step p50 {s50:.3f} ms p95 {s95:.3f} ms | "
                  f"mean cost {np.mean(runs.cost):.2f} | load {load:.2f} -> {os.getloadavg()[0]:.2f}",
                  flush=True)


if __name__ == "__main__":
    main()
