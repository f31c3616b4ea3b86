"""Public LMI benchmarks: SDPLIB problems solved by :class:`lmi.ipm.BlockLMISolver` and by cvxpy + Clarabel.

The cases are SDPLIB 1.2's control2, control3 and control4 (B. Borchers, "SDPLIB 1.2, a library of
semidefinite programming test problems", Optimization Methods and Software 11(1-4), 1999):
Lyapunov-type LMIs from control with 66, 136 and 231 variables and two blocks each (orders 20
and 10, 30 and 15, 40 and 20). Their files ship with the tests (``tests/data/sdplib``, with
their provenance) and are read by :func:`lmi.sdpa.read_sdpa`. Each case is solved

- by :class:`lmi.ipm.BlockLMISolver` with its defaults, cold, on a freshly built solver, and
- by cvxpy + Clarabel with their defaults, on the same LMIs (``C_j - sum_i x_i A_ij >> 0``), a
  fresh cvxpy problem each time,

``repeats`` times, all inside one BLAS thread (:class:`lmi.threads.SingleThreadBlas`). A record
holds the status, the objective ``c'x``, its relative error against SDPLIB's published optimum,
the iterations and the median times: ``solve`` (the IPM's :meth:`~lmi.ipm.BlockLMISolver.solve`;
Clarabel's own solve time as cvxpy reports it) and ``total`` (with building the solver; with
building the cvxpy problem and its compilation).

``python -m dev.public_lmi [--cases control2 ...] [--repeats 3] [--out DIR]`` prints a
Markdown table; with ``--out`` it also writes ``DIR/results.md`` and ``DIR/results.json``.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from benchmarks.core.jsonable import write_json
from toolkit_common.errors import InvalidArgumentError

__all__ = ["DATA_DIR", "PUBLISHED_OPTIMA", "format_public", "load_case", "run_public"]

#: Where the shipped cases are (the repository's test data).
DATA_DIR = Path(__file__).resolve().parents[1] / "tests" / "data" / "sdplib"
#: SDPLIB 1.2's published optima (SDPA's sign convention: the minimum of ``c'x``).
PUBLISHED_OPTIMA = {"control2": 8.300000, "control3": 13.63327, "control4": 19.79423}


def load_case(name: str, data_dir: Path = DATA_DIR) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """``(c, blocks)`` of a shipped case (``DATA_DIR/<name>.dat-s.gz``)."""
    from lmi.sdpa import read_sdpa

    if name not in PUBLISHED_OPTIMA:
        raise InvalidArgumentError("case", f"one of {sorted(PUBLISHED_OPTIMA)}", repr(name))
    return read_sdpa(Path(data_dir) / f"{name}.dat-s.gz")


def _solve_ipm(c: np.ndarray, blocks: list) -> tuple[dict, float, float]:
    from lmi.ipm import BlockLMISolver

    start = time.perf_counter()
    solver = BlockLMISolver(c, blocks)
    built = time.perf_counter()
    res = solver.solve()
    done = time.perf_counter()
    out = {"status": res.status, "objective": float(c @ res.x), "iterations": res.iterations}
    return out, done - built, done - start


def _solve_cvxpy(c: np.ndarray, blocks: list) -> tuple[dict, float, float]:
    import cvxpy as cp

    start = time.perf_counter()
    n = c.shape[0]
    x = cp.Variable(n)
    constraints = []
    for const, coef in blocks:
        k = const.shape[0]
        expr = const - cp.reshape(coef.reshape(n, k * k).T @ x, (k, k), order="C")
        constraints.append(expr >= 0 if k == 1 else 0.5 * (expr + expr.T) >> 0)
    problem = cp.Problem(cp.Minimize(c @ x), constraints)
    problem.solve(solver=cp.CLARABEL)
    done = time.perf_counter()
    stats = problem.solver_stats
    objective = float(c @ x.value) if x.value is not None else float("nan")
    out = {"status": str(problem.status), "objective": objective, "iterations": stats.num_iters}
    return out, float(stats.solve_time), done - start


def run_public(cases: Sequence[str] = tuple(PUBLISHED_OPTIMA), repeats: int = 3,
               data_dir: Path = DATA_DIR) -> list[dict]:
    """One record per case and solver (``"BlockLMISolver"``, ``"cvxpy + Clarabel"``); see the
    module docstring. The answers of the repeats must agree (the solves are deterministic)."""
    from lmi.ipm import BlockLMISolver
    from lmi.threads import SingleThreadBlas

    if isinstance(repeats, bool) or not (isinstance(repeats, int) and repeats >= 1):
        raise InvalidArgumentError("repeats", "an integer >= 1", repr(repeats))
    records = []
    with SingleThreadBlas().limit():
        BlockLMISolver([1.0], [(-np.eye(1), -np.eye(1)[None])])  # loads the kernels before any timing
        for name in cases:
            c, blocks = load_case(name, data_dir)
            optimum = PUBLISHED_OPTIMA[name]
            for label, run in (("BlockLMISolver", _solve_ipm), ("cvxpy + Clarabel", _solve_cvxpy)):
                answers, solve_times, total_times = [], [], []
                for _ in range(repeats):
                    answer, t_solve, t_total = run(c, blocks)
                    answers.append(answer)
                    solve_times.append(t_solve)
                    total_times.append(t_total)
                answer = answers[0]
                records.append({
                    "case": name, "solver": label, "variables": int(c.shape[0]),
                    "block_orders": [int(b[0].shape[0]) for b in blocks], "published_optimum": optimum,
                    **answer, "rel_error": abs(answer["objective"] - optimum) / abs(optimum),
                    "repeats_agree": all(a == answer for a in answers[1:]),
                    "solve_time_s": statistics.median(solve_times),
                    "total_time_s": statistics.median(total_times), "repeats": repeats,
                })
    return records


def format_public(records: Sequence[dict]) -> str:
    """A Markdown table, one row per case and solver."""
    lines = ["| case | n | blocks | solver | status | c'x | rel. error | iterations | solve ms | total ms |",
             "| --- | ---: | --- | --- | --- | ---: | ---: | ---: | ---: | ---: |"]
    for r in records:
        lines.append(
            f"| {r['case']} | {r['variables']} | {', '.join(map(str, r['block_orders']))} | {r['solver']} "
            f"| {r['status']}{'' if r['repeats_agree'] else ' (repeats differ)'} | {r['objective']:.9g} "
            f"| {r['rel_error']:.1e} | {r['iterations']} | {1e3 * r['solve_time_s']:.1f} "
            f"| {1e3 * r['total_time_s']:.1f} |")
    lines += ["", "rel. error: against SDPLIB's published optimum (7 significant digits). solve: the "
              "IPM's solve() / Clarabel's own solve time; total: with building the solver / the cvxpy "
              f"problem. Medians of {records[0]['repeats'] if records else 0} repeats, one BLAS thread."]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m dev.public_lmi [--cases control2 control3 control4] [--repeats 3] [--out DIR]``."""
    import argparse
    import os
    import platform

    parser = argparse.ArgumentParser(
        description="public LMI benchmarks (SDPLIB control2-4): BlockLMISolver against cvxpy + Clarabel")
    parser.add_argument("--cases", nargs="+", default=list(PUBLISHED_OPTIMA), choices=list(PUBLISHED_OPTIMA))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", help="write results.md and results.json to this directory")
    args = parser.parse_args(argv)
    load_before = os.getloadavg()
    records = run_public(args.cases, args.repeats)
    import clarabel
    import cvxpy

    env = (f"{os.cpu_count()} CPUs, load average {load_before[0]:.2f} before and {os.getloadavg()[0]:.2f} "
           f"after; Python {platform.python_version()}, numpy {np.__version__}, cvxpy {cvxpy.__version__}, "
           f"clarabel {clarabel.__version__}")
    text = format_public(records) + "\n\n" + env + "\n"
    print(text, end="")
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "results.md").write_text(text, encoding="utf-8")
        write_json(out / "results.json", records)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
