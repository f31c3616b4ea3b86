"""States far outside the region: does the IPM say "infeasible", with a checked proof, and how fast?

The problems are the infeasible ones of :mod:`dev.stress` (open-loop unstable: a real
eigenvalue ``lam`` in ``[1.1, 1.5]`` with left eigenvector ``w``), with the state placed
``distance`` times beyond the slab ``|w'x| (lam - 1) <= max |w' B_0 u|`` that holds every state
the input bound can keep from escaping (``distance`` of 10, 1e3 and 1e6 by default): infeasible by
construction. For each problem the benchmark also finds, by bisection on the same direction, the
largest state the IPM solves ``"optimal"`` (``feasible_radius``; the state's length over it is
``beyond``) and times a cold solve there (half that radius) against the cold solve at the far
state, both on freshly built problems, interleaved, ``repeats`` times (medians).

Each record: the status, ``solver_status`` and iterations of the IPM (the default settings, its
Clarabel fallback on: the fallback must not be needed) and whether its certificate passed the
independent check (:func:`lmi.infeasibility.check_farkas`), the radius it proves, the feasible
solve's status and iterations, the median times and their ratio. ``python -m
dev.far_states`` prints a Markdown table and the machine's load.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Sequence

import numpy as np

from benchmarks.core.jsonable import write_json
from dev.stress import StressProblem, make_problem

__all__ = ["FAR_DISTANCES", "far_problems", "feasible_radius", "format_far", "run_far"]

#: How far beyond the slab the states are placed by default.
FAR_DISTANCES = (10.0, 1e3, 1e6)
#: Bisection on the feasible radius: stop when the bracket's ratio is below this.
BISECTION_RATIO = 1.01


def far_problems(sizes: Sequence[int] = (2, 3, 4, 5, 6), seeds: Sequence[int] = (0, 1, 2, 3),
                 distances: Sequence[float] = FAR_DISTANCES,
                 n_vertices: int = 2) -> list[tuple[float, StressProblem]]:
    """The set as ``(distance, problem)`` pairs: every size, seed and distance (peak bound for even
    seeds, ellipsoid for odd; one input at two states, two above)."""
    out = []
    for n in sizes:
        for seed in seeds:
            constraint = "peak" if seed % 2 == 0 else "ellipsoid"
            for distance in distances:
                out.append((distance, make_problem(n, 1 if n == 2 else 2, n_vertices, "infeasible", seed,
                                                   constraint, distance=distance)))
    return out


def _kothare(prob: StressProblem, **options: object):
    from lmi import KothareProblem

    return KothareProblem(**prob.kothare_kwargs(), backend="ipm", **options)


def feasible_radius(prob: StressProblem, low: float = 1e-8) -> float:
    """The largest length along ``prob.x``'s direction at which the IPM answers ``"optimal"``
    (bisection to :data:`BISECTION_RATIO`; the set of feasible states is star-shaped about the
    origin: a state's ellipsoid holds every shorter state on its ray)."""
    direction = prob.x / np.linalg.norm(prob.x)
    kothare = _kothare(prob)
    hi = float(np.linalg.norm(prob.x))
    if kothare.solve(low * direction).status != "optimal":
        return 0.0
    while hi / low > BISECTION_RATIO:
        mid = float(np.sqrt(low * hi))
        if kothare.solve(mid * direction).status == "optimal":
            low = mid
        else:
            hi = mid
    return low


def _timed_cold(prob: StressProblem, x: np.ndarray):
    """A cold solve on a freshly built problem (the Clarabel fallback off): the solution and the
    time of the solve alone."""
    kothare = _kothare(prob, solver_options={"fallback": False})
    start = time.perf_counter()
    sol = kothare.solve(x)
    return sol, time.perf_counter() - start


def run_far(problems: Sequence[tuple[float, StressProblem]], repeats: int = 5) -> list[dict]:
    """One record per ``(distance, problem)`` pair of :func:`far_problems` (see the module docstring)."""
    records = []
    for distance, prob in problems:
        sol = _kothare(prob).solve(prob.x)
        cert = sol.infeasibility
        radius = feasible_radius(prob)
        length = float(np.linalg.norm(prob.x))
        x_in = 0.5 * radius * prob.x / length
        far_times, in_times = [], []
        far = near = None
        for _ in range(repeats):
            far, t_far = _timed_cold(prob, prob.x)
            near, t_in = _timed_cold(prob, x_in)
            far_times.append(t_far)
            in_times.append(t_in)
        t_far, t_in = statistics.median(far_times), statistics.median(in_times)
        records.append({
            "label": f"{prob.label}-d{distance:g}", "distance": distance, "n_states": prob.n_states,
            "vertices": prob.n_vertices,
            "input_constraint": prob.input_constraint, "length": length,
            "feasible_radius": radius, "beyond": length / radius if radius > 0.0 else float("inf"),
            "status": str(sol.status), "solver_status": sol.solver_status, "iterations": sol.iterations,
            "certificate_ok": bool(cert is not None and cert.ok),
            "certificate_radius": None if cert is None else float(cert.radius),
            "far_alone_status": str(far.status), "far_iterations": far.iterations,
            "feasible_status": str(near.status), "feasible_iterations": near.iterations,
            "far_time_s": t_far, "feasible_time_s": t_in, "time_ratio": t_far / t_in,
        })
    return records


def format_far(records: Sequence[dict]) -> str:
    """A Markdown table, one row per problem, and a summary line."""
    lines = ["| problem | beyond the region | status | solver_status | proof radius | iterations "
             "(far / feasible) | ms (far / feasible) | ratio |",
             "| --- | ---: | --- | --- | ---: | ---: | ---: | ---: |"]
    for r in records:
        proof = "n/a" if r["certificate_radius"] is None else f"{r['certificate_radius']:.1e}"
        lines.append(
            f"| {r['label']} | {r['beyond']:.3g} | {r['status']}"
            f"{'' if r['certificate_ok'] else ' (unchecked)'} "
            f"| {r['solver_status']} | {proof} | {r['far_iterations']} / {r['feasible_iterations']} "
            f"| {1e3 * r['far_time_s']:.1f} / {1e3 * r['feasible_time_s']:.1f} | {r['time_ratio']:.2f} |")
    proved = sum(r["status"] == "infeasible" and r["certificate_ok"] for r in records)
    ratios = [r["time_ratio"] for r in records]
    lines += ["", f"{proved} of {len(records)} infeasible with a checked certificate; time ratio far / "
              f"feasible: median {statistics.median(ratios):.2f}, max {max(ratios):.2f}." if ratios else ""]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m dev.far_states [--sizes 2 3 4 5 6] [--seeds 0 1 2 3]
    [--distances 10 1e3 1e6] [--vertices 2] [--repeats 5] [--out FILE]``."""
    import argparse
    import os

    parser = argparse.ArgumentParser(
        description="states far outside the region: the IPM's infeasibility proofs")
    parser.add_argument("--sizes", nargs="+", type=int, default=[2, 3, 4, 5, 6])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2, 3])
    parser.add_argument("--distances", nargs="+", type=float, default=list(FAR_DISTANCES))
    parser.add_argument("--vertices", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", help="write the records as JSON to this file")
    args = parser.parse_args(argv)
    records = run_far(far_problems(args.sizes, args.seeds, args.distances, args.vertices), args.repeats)
    print(format_far(records))
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()}")
    if args.out:
        write_json(args.out, records)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
