"""Where an interior-point solve of paper P's LMIs spends its time, and the floor of its arithmetic.

``python -m benchmarks.timing.breakdown [--vertices 2 8] [--states N] [--out DIR] [--compile]``

For each polytope (paper P's satellite, 2 or 8 vertices, the ``ipm`` path of
:class:`lmi.KothareProblem` on its numba kernels (``solver_options={"core": "numba"}``; the C core
that runs these problems by default is timed by ``python -m benchmarks.timing.ccore --phases``),
warm-started along the closed loop of
:func:`benchmarks.timing.rmpc.closed_loop_states`) every compiled kernel the solver calls (the
residuals and the iteration itself, :mod:`lmi.ipm.kernels.iteration`) is timed by wrapping it,
in CPU time of this thread (``time.thread_time``: a shared machine's other processes inflate
wall time, much less the CPU time of this one). The table gives, per solve and per iteration,
the time of each call, of the solver (:meth:`lmi.BlockLMISolver.solve`) and of the whole
``KothareProblem.solve`` (scaling, solver, certificate, gain); what the kernels leave of the
solver's time is the Python around them. Inside the iteration, the parts (the NT scaling with
``P``, ``H = P'P``, its Cholesky factor, the QR factorisation in the QR phase, the Newton step)
are replayed one by one, each timed alone, on the iterates of the first solves of the loop.

The floor, two ways, for the dense linear algebra one iteration of this method cannot avoid at the
problem's dimensions (``n`` variables, packed size ``m``, blocks of order ``k_j``): the Schur
complement ``H = P P'`` (``n x m`` times its transpose, ``n^2 m`` flops), its Cholesky
factorisation (``n^3 / 3``), the two Newton solves' products with ``P`` and ``P'`` and their
triangular solves (``2 (4 n m + 2 n^2)``) and the Nesterov-Todd scaling of each block (an
eigen-decomposition with vectors and two products, about ``13 k^3``). *Calls*: each operation
timed alone as a LAPACK/BLAS call on this machine (scipy's ``dsyevd`` for the scaling), which
includes each call's fixed cost. *Arithmetic*: the flop count at the rate this machine reaches on
``P P'`` (the best-vectorised operation of the iteration), a floor no implementation of this
method beats. Both times the iterations per solve.

With ``--compile``, the first-call cost of the kernels (numba): a fresh process builds a solver
with an empty kernel cache (compilation) and then again with the cache filled (loading).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.machine import machine_info
from lmi.threads import SingleThreadBlas

__all__ = [
    "breakdown", "breakdown_sections", "compile_cost", "floor_per_iteration", "format_breakdown", "main",
    "replay_iteration",
]

#: The compiled kernels the solver calls (module ``lmi.ipm.kernels``), timed by wrapping them.
KERNELS = ("residuals", "rows_iteration", "grouped_iteration", "cholesky_blocks", "pack")
#: The iterations of this many solves (the first of the loop) are replayed part by part, each
#: part ``REPEATS`` times (the median counts).
REPLAYED_SOLVES = 3
REPEATS = 5


def _median_time(fn: Callable[[], Any], repeats: int = 400) -> float:
    """Median CPU time of ``fn()`` in seconds (after one call)."""
    fn()
    times = []
    for _ in range(repeats):
        start = time.thread_time()
        fn()
        times.append(time.thread_time() - start)
    return float(np.median(times))


def floor_per_iteration(n: int, size: int, orders: Sequence[int], seed: int = 0) -> dict[str, float]:
    """CPU seconds of the unavoidable dense linear algebra of one iteration (see the module notes).

    Returns the timed calls (their ``"total"``), the flop count (``"flops"``), the rate of
    ``P P'`` (``"flops_per_s"``) and the arithmetic floor (``"arithmetic"``, flops / rate).
    """
    from scipy.linalg import solve_triangular
    from scipy.linalg.lapack import dpotrf, dsyevd

    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, size))
    h = p @ p.T + n * np.eye(n)
    r = dpotrf(h, lower=0)[0]
    v, w = rng.normal(size=size), rng.normal(size=n)
    blocks = [(lambda a: a @ a.T)(rng.normal(size=(k, k))) for k in orders]
    parts = {
        "H = P P'": _median_time(lambda: p @ p.T),
        "Cholesky of H": _median_time(lambda: dpotrf(h, lower=0, clean=1)),
        "2 Newton solves": 2 * (_median_time(lambda: p @ v) + _median_time(lambda: p.T @ w)
                                + 2 * _median_time(lambda: solve_triangular(r, w, check_finite=False))),
        "NT scaling (dsyevd per block)": sum(_median_time(lambda b=b: dsyevd(b)) for b in blocks),
    }
    parts["total"] = sum(parts.values())
    flops = n * n * size + n**3 / 3 + 2 * (4 * n * size + 2 * n * n) + sum(13 * k**3 for k in orders)
    parts["flops"] = flops
    parts["flops_per_s"] = n * n * size / parts["H = P P'"]
    parts["arithmetic"] = flops / parts["flops_per_s"]
    return parts


def replay_iteration(args: tuple) -> dict[str, float]:
    """The parts of one :func:`lmi.ipm.kernels.rows_iteration` call (its arguments ``args``, copied
    when it was made), each timed alone: seconds per part, the parts this iterate's phase runs."""
    from lmi.ipm.kernels import newton_step, scaling_and_schur_rows
    from lmi.ipm.kernels.iteration import _factor_ok
    from lmi.ipm.kernels.lapack import cholesky_upper, householder_qr, schur_complement

    (s_chol, z, orders, offsets, ent_row, ent_col, ent_w, sp_off, sp_var, sp_pair, sp_val, pair_off,
     pair_row, pair_col, kk, lam, pt, h, work, r_fac, qr_h, qr_tau, no_qr_h, no_qr_tau, use_qr, x, theta,
     r0, rd, rp, g_mat, h_vec, mu, ref_scale, qr_switch, s_out, z_out, chol_out, err_limit) = args
    layout = (orders, offsets, ent_row, ent_col, ent_w)
    sparse = (sp_off, sp_var, sp_pair, sp_val, pair_off, pair_row, pair_col)
    parts = {"NT scaling and P": _median_time(
        lambda: scaling_and_schur_rows(s_chol, z, *layout, *sparse, kk, lam, pt))}
    householder = (no_qr_h, no_qr_tau)
    if not use_qr:
        parts["H = P'P (dsyrk)"] = _median_time(lambda: schur_complement(pt, h), REPEATS)
        parts["Cholesky of H (dpotrf)"] = _median_time(lambda: cholesky_upper(h, work, r_fac), REPEATS)
        use_qr = not _factor_ok(h, r_fac, qr_switch)
    if use_qr:
        parts["QR of P (dgeqrf), QR phase"] = _median_time(lambda: householder_qr(pt, qr_h, qr_tau, r_fac),
                                                                   REPEATS)
        householder = (qr_h, qr_tau)
    parts["Newton step (2 solves, step lengths, update)"] = _median_time(lambda: newton_step(
        pt, r_fac, np.zeros(0, dtype=np.int64), *householder, kk, lam, x, z, theta, r0, rd, rp, g_mat, h_vec,
        mu, ref_scale, *layout, *sparse, s_out, z_out, chol_out, err_limit if not use_qr else np.inf),
        REPEATS)
    return parts


def breakdown(n_vertices: int, n_states: int = 40) -> dict[str, Any]:
    """Time the parts of the warm solves along the closed loop; see the module notes."""
    import lmi.ipm.solver as solver_module
    from benchmarks.timing.common import Q1, U_MAX, R, polytope
    from benchmarks.timing.rmpc import closed_loop_states
    from lmi import KothareProblem

    poly = polytope(n_vertices)
    states = closed_loop_states(n_states, "scalar" if n_vertices == 2 else "box")
    # the numba kernels' path (the default "auto" runs these problems in the C core, whose phases
    # python -m benchmarks.timing.ccore --phases times)
    prob = KothareProblem(poly.A, poly.B, Q1, R, dt=poly.dt, u_max=U_MAX, solver_options={"core": "numba"})
    for x in states[:3]:  # kernels loaded, warm point set
        prob.solve(x)
    solver = prob._backend._solver
    spent: dict[str, float] = defaultdict(float)
    calls: dict[str, int] = defaultdict(int)
    captured: list[tuple] = []
    capture = [True]
    copying = [0.0]  # CPU time spent copying the captured arguments, taken out of the totals

    def timed(name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            if name == "rows_iteration" and capture[0]:
                start = time.thread_time()
                captured.append(tuple(a.copy() if isinstance(a, np.ndarray) else a for a in args))
                copying[0] += time.thread_time() - start
            start = time.thread_time()
            out = fn(*args, **kwargs)
            spent[name] += time.thread_time() - start
            calls[name] += 1
            return out
        return wrapper

    originals = {name: getattr(solver_module._kernels, name) for name in KERNELS}
    solve = solver.solve
    iterations = 0
    totals = []
    try:
        for name, fn in originals.items():
            setattr(solver_module._kernels, name, timed(name, fn))
        solver.solve = timed("BlockLMISolver.solve", solve)
        for count, x in enumerate(states):
            capture[0] = count < REPLAYED_SOLVES
            start, copied = time.thread_time(), copying[0]
            sol = prob.solve(x)
            totals.append(time.thread_time() - start - (copying[0] - copied))
            iterations += sol.iterations or 0
    finally:
        for name, fn in originals.items():
            setattr(solver_module._kernels, name, fn)
        del solver.solve
    count = len(states)
    per_iteration = iterations / count
    solver_time = spent.pop("BlockLMISolver.solve") - copying[0]
    calls.pop("BlockLMISolver.solve")
    parts = {name: {"per_solve_us": 1e6 * t / count, "per_iteration_us": 1e6 * t / iterations,
                    "calls_per_solve": calls[name] / count} for name, t in spent.items()}
    kernels = sum(spent.values())
    replayed: dict[str, list[float]] = defaultdict(list)
    with SingleThreadBlas().limit():  # as inside a solve
        for args in captured:
            for name, seconds in replay_iteration(args).items():
                replayed[name].append(seconds)
        floor = floor_per_iteration(solver.n, solver._layout.size, solver.block_orders)
    inside = {name: {"per_iteration_us": 1e6 * float(np.sum(t)) / max(len(captured), 1),
                     "share_of_iterations": len(t) / max(len(captured), 1)} for name, t in replayed.items()}
    rate, flops = floor.pop("flops_per_s"), floor.pop("flops")
    arithmetic = floor.pop("arithmetic")
    return {
        "vertices": n_vertices, "states": count, "variables": solver.n, "packed_size": solver._layout.size,
        "block_orders": list(solver.block_orders), "iterations_per_solve": per_iteration,
        "kothare_solve_us": 1e6 * float(np.sum(totals)) / count,
        "kothare_solve_p50_us": 1e6 * float(np.median(totals)),
        "solver_us": 1e6 * solver_time / count,
        "python_around_kernels_us": 1e6 * (solver_time - kernels) / count,
        "outside_solver_us": 1e6 * (float(np.sum(totals)) - solver_time) / count,
        "parts": parts,
        "iteration_parts": inside, "replayed_iterations": len(captured),
        "floor_per_iteration_us": {k: 1e6 * v for k, v in floor.items()},
        "floor_per_solve_us": 1e6 * floor["total"] * per_iteration,
        "flops_per_iteration": flops, "gflops_per_s": 1e-9 * rate,
        "arithmetic_floor_per_iteration_us": 1e6 * arithmetic,
        "arithmetic_floor_per_solve_us": 1e6 * arithmetic * per_iteration,
    }


def compile_cost() -> dict[str, float]:
    """Seconds to build the first solver of a fresh process: empty kernel cache, then filled."""
    code = ("import time; t = time.perf_counter(); from lmi import BlockLMISolver; import numpy as np; "
            "BlockLMISolver([1.0], [(-np.eye(2), -np.eye(2)[None])]).solve(); "
            "print(time.perf_counter() - t)")
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        runs = [float(subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True,
                                     text=True).stdout.split()[-1]) for _ in range(2)]
    return {"empty_cache_s": runs[0], "filled_cache_s": runs[1]}


def format_breakdown(results: Sequence[dict[str, Any]], compile_s: dict[str, float] | None = None) -> str:
    """The Markdown report."""
    lines = ["# Interior-point breakdown", ""]
    machine = machine_info()
    lines.append(f"Machine: {machine.get('platform')}, {machine.get('cpu_count')} CPUs, load average "
                 f"{machine.get('load_average')}.")
    lines += breakdown_sections(results, level="##")
    if compile_s is not None:
        lines += ["", "## First call", "",
                  f"A fresh process building its first solver: {compile_s['empty_cache_s']:.1f} s with an "
                  f"empty kernel cache (numba compiles), {compile_s['filled_cache_s']:.2f} s with the cache "
                  "filled (the kernels are cached next to their files after an install's first use)."]
    return "\n".join(lines) + "\n"


def breakdown_sections(results: Sequence[dict[str, Any]], level: str = "##") -> list[str]:
    """The Markdown lines of one section per polytope (``level`` is the heading's ``#``)."""
    lines = ["", f"{level} Where an interior-point solve spends its time (ipm, paper P)", "",
             "CPU time of this thread (time.thread_time), means over the warm solves of the closed loop; "
             "see benchmarks.timing.breakdown."]
    for res in results:
        lines += ["", f"{level}# {res['vertices']} vertices", "",
                  f"{res['states']} states; {res['variables']} variables, packed size {res['packed_size']}, "
                  f"blocks of order {res['block_orders']}; {res['iterations_per_solve']:.2f} iterations per "
                  "solve.", "",
                  "| part | us per solve | us per iteration | calls per solve |",
                  "| --- | ---: | ---: | ---: |"]
        for name, part in sorted(res["parts"].items(), key=lambda kv: -kv[1]["per_solve_us"]):
            lines.append(f"| {name} | {part['per_solve_us']:.0f} | {part['per_iteration_us']:.1f} | "
                         f"{part['calls_per_solve']:.2f} |")
        it = res["iterations_per_solve"]
        lines.append(f"| Python around the kernels | {res['python_around_kernels_us']:.0f} | "
                     f"{res['python_around_kernels_us'] / it:.1f} | |")
        lines.append(f"| **solver** (BlockLMISolver.solve) | {res['solver_us']:.0f} | "
                     f"{res['solver_us'] / it:.1f} | |")
        lines.append(f"| outside the solver (scaling, certificate, gain) | {res['outside_solver_us']:.0f} "
                     "| | |")
        lines.append(f"| **KothareProblem.solve** (mean; p50 {res['kothare_solve_p50_us']:.0f}) | "
                     f"{res['kothare_solve_us']:.0f} | | |")
        if res.get("iteration_parts"):
            replayed = res["replayed_iterations"]
            lines += ["", f"Inside the iteration (each part replayed alone on the {replayed} "
                      "iterates of the first solves; a part that runs in one phase only is averaged over "
                      "all iterations):", "", "| part | us per iteration | share of iterations |",
                      "| --- | ---: | ---: |"]
            for name, part in res["iteration_parts"].items():
                lines.append(f"| {name} | {part['per_iteration_us']:.1f} | "
                             f"{part['share_of_iterations']:.2f} |")
        lines += ["", "Floor, calls (the dense linear algebra of one iteration, each call timed alone):", "",
                  "| part | us per iteration |", "| --- | ---: |"]
        for name, value in res["floor_per_iteration_us"].items():
            lines.append(f"| {name} | {value:.1f} |")
        lines.append(f"| x {it:.2f} iterations = floor per solve | {res['floor_per_solve_us']:.0f} |")
        lines += ["", f"Floor, arithmetic: {res['flops_per_iteration'] / 1e6:.2f} Mflop per iteration at "
                  f"{res['gflops_per_s']:.1f} Gflop/s (the rate of P P') = "
                  f"{res['arithmetic_floor_per_iteration_us']:.0f} us per iteration, "
                  f"{res['arithmetic_floor_per_solve_us']:.0f} us per solve."]
    return [*lines, ""]


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: print the report, and write ``breakdown.md`` and ``breakdown.json`` with ``--out``."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.timing.breakdown",
                                     description=(__doc__ or "").split("\n")[0])
    parser.add_argument("--vertices", type=int, nargs="+", default=[2, 8], choices=[2, 4, 8])
    parser.add_argument("--states", type=int, default=40,
                        help="closed-loop states per polytope (default 40)")
    parser.add_argument("--out", type=Path, default=None,
                        help="directory for breakdown.md and breakdown.json")
    parser.add_argument("--compile", action="store_true", help="also measure the kernels' first-call cost")
    args = parser.parse_args(argv)
    if not 1 <= args.states <= 10000:
        parser.error(f"--states: expected an integer in [1, 10000], but found {args.states}")
    results = [breakdown(v, args.states) for v in args.vertices]
    compile_s = compile_cost() if args.compile else None
    text = format_breakdown(results, compile_s)
    print(text)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "breakdown.md").write_text(text, encoding="utf-8")
        (args.out / "breakdown.json").write_text(
            json.dumps({"machine": machine_info(), "results": results, "compile": compile_s}, indent=2),
            encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
