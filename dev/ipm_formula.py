"""Per-warm-solve time of the interior-point method with each Schur formula forced.

Run as ``python -m dev.ipm_formula [CASE ...] [--states N] [--kernels-only]``; a case is
``problem:method`` (a problem of :mod:`benchmarks.suites.methods_problems`, a method of
:data:`benchmarks.suites.methods.METHODS` or options of :class:`rmpc.RMPC` as
``key=value[,key=value]``, e.g. ``flexible_8v:horizon=2``), default :data:`CASES`.

:class:`lmi.ipm.BlockLMISolver` forms the Schur complement ``H`` either from the factored
coefficients (the "direct" formula, :func:`lmi.ipm.kernels.scaling_and_schur_grouped`) or from
``P'`` and one ``dsyrk`` (the "rows" formula, :func:`lmi.ipm.kernels.scaling_and_schur_rows`);
:meth:`lmi.ipm.blocks.BlockData._choose_formula` chooses. Per case, four controllers are built
(``backend="ipm"``): the choice as the package makes it (``auto``), and each formula forced
(``BlockData._choose_formula`` replaced for the run; the blockwise formula,
:func:`lmi.ipm.kernels.scaling_and_schur_blockwise`, too). They solve the same ``N`` states
alternately, state by state, so that they see the same machine load: the closed loop of the
``auto`` controller's first move (clipped to the bound) on the true plant from ``x0``, restarted
from ``0.9^k x0`` when ``||x|| < 0.05 ||x0||``. Printed per case and mode: the median and the
spread of the ``N - 1`` warm solves (the first, cold, solve left out), their median iterations,
how many ended ``"optimal"`` and certified, and the formula each solver took.

Per case also the formation of ``H`` alone, both formulas, on the solver's own data at ``S = Z =
I`` (their cost does not depend on the values): ``direct`` (the NT scaling and the pair sums),
``rows`` (the NT scaling, ``P'`` and the ``dsyrk``), and one pair of the Newton step's products
``P'v``, ``P dx`` from the sparse coefficients (direct path) and with ``P`` formed (rows path),
with the choice of the operation count used before (``old``) and of the cost model (``new``) and
the model's terms (:meth:`lmi.ipm.blocks.BlockData._schur_terms`). At the end :func:`fit` fits
the model's constants to those times and counts the cases where the package's constants pick
the slower formula by more than 1.3 times. ``--kernels-only`` builds and solves only the
``auto`` controller, once. The load average goes with the answer (the machine is shared).
"""

from __future__ import annotations

import argparse
import os
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
from scipy.optimize import nnls

from benchmarks.suites.methods import _controller, method_options
from benchmarks.suites.methods_problems import build_problem
from lmi.ipm import BlockLMISolver
from lmi.ipm import kernels as ker
from lmi.ipm.blocks import DIRECT_MIN_VARIABLES, BlockData, formula_costs
from lmi.ipm.kernels.lapack import schur_complement
from lmi.ipm.kernels.step import _p_times, _pt_times
from toolkit_common.errors import InvalidArgumentError

CASES = (
    "paper_p_2v:kothare", "paper_p_2v:vertex", "paper_p_2v:vertex_pairs", "paper_p_2v:shi",
    "paper_p_2v:horizon=3",
    "paper_p_8v:kothare", "paper_p_8v:vertex", "paper_p_8v:vertex_pairs", "paper_p_8v:horizon=2",
    "paper_p_8v:auxiliary_saturation", "paper_p_8v:free_move",
    "kothare_ex2:kothare", "kothare_ex2:shi", "kothare_ex2:horizon=3", "kothare_ex2:vertex",
    "kothare_ex2:auxiliary_saturation",
    "paper_w:kothare", "paper_w:vertex", "paper_w:horizon=2",
    "flexible_8v:kothare", "flexible_8v:horizon=2", "flexible_8v:vertex",
)
MODES = ("auto", "direct", "rows", "blockwise")
#: Pairs of products ``P'v``, ``P dx`` per iteration in the fit (each of the two Newton solves
#: makes one and a half, and one more per refinement step: one assumed).
PRODUCT_PAIRS = 5
#: The fewest cases :func:`fit` fits the four constants on.
MIN_FIT_CASES = 8


@contextmanager
def forced(mode: str) -> Iterator[None]:
    """``BlockData._choose_formula`` answering ``mode`` (``auto``: unchanged) inside."""
    original = BlockData._choose_formula
    if mode != "auto":
        BlockData._choose_formula = lambda self: mode  # type: ignore[method-assign]
    try:
        yield
    finally:
        BlockData._choose_formula = original  # type: ignore[method-assign]


def solvers_of(ctrl: Any) -> list[BlockLMISolver]:
    """The interior-point solvers a controller's problem holds."""
    prob = ctrl.problem
    if hasattr(prob, "_solvers"):
        return [s for s in prob._solvers.values() if isinstance(s, BlockLMISolver)]
    solver = getattr(getattr(prob, "_backend", None), "_solver", None)
    return [solver] if isinstance(solver, BlockLMISolver) else []


def old_rule(solver: BlockLMISolver) -> bool:
    """The choice before the cost model: the operation count (``2 e^2 + k^2 d + k d^2`` per block
    against ``e_rows m_j + m n^2``, ``e`` the factored and ``e_rows`` the sparse entries)."""
    direct, rows = 0.0, 0.0
    for j, k in enumerate(solver.block_orders):
        dmat, var = solver._fact_parts[j][0], solver._fact_parts[j][1]
        d = dmat.shape[1]
        size = k * (k + 1) // 2
        direct += 2.0 * var.shape[0] ** 2 + k * k * d + k * d * d
        rows += solver._sparse_parts[j][1].shape[0] * size + size * solver.n ** 2
    return solver.n > 64 and direct < rows


def uses_core(ctrl: Any) -> bool:
    return getattr(getattr(ctrl.problem, "_backend", None), "_core", None) is not None


def kernel_times(solver: BlockLMISolver, repeats: int = 5) -> tuple[float, float, float, float]:
    """Median seconds of forming ``H`` by the direct and by the rows formula (``S = Z = I``), and
    of one product ``P' v`` and one ``P dx`` of the Newton step (:mod:`lmi.ipm.kernels.step`)
    from the sparse coefficients (direct path, ``P`` not formed) and with ``P`` formed."""
    solver._refresh()
    lay = solver._layout
    nb, kmax, n, size = len(solver.block_orders), solver._kmax, solver.n, lay.size
    eye = np.zeros((nb, kmax, kmax))
    for j, k in enumerate(solver.block_orders):
        eye[j, :k, :k] = np.eye(k)
    kk, lam = np.zeros((nb, kmax, kmax)), np.zeros((nb, kmax))
    h = np.zeros((n, n))
    pt = np.zeros((n, size))
    v, dx = np.ones(size), np.ones(n)

    def run(what: int) -> None:
        if what == 0:
            ker.scaling_and_schur_grouped(eye, eye, lay.orders, *solver._fact, *solver._groups, kk, lam, h)
        elif what == 1:
            ker.scaling_and_schur_rows(eye, eye, *lay.arrays, *solver._sparse, kk, lam, pt)
            schur_complement(pt, h)
        else:
            mat = np.zeros((n, 0)) if what == 2 else pt
            _pt_times(mat, v, kk, *lay.arrays, *solver._sparse, n)
            _p_times(mat, dx, kk, *lay.arrays, *solver._sparse)

    out = []
    with solver._blas.limit():
        for what in range(4):
            times = []
            for _ in range(repeats + 1):
                start = time.perf_counter()
                run(what)
                times.append(time.perf_counter() - start)
            out.append(float(np.median(times[1:])))
    return out[0], out[1], out[2], out[3]


def _options(problem: Any, method: str) -> tuple[dict[str, Any] | None, str | None]:
    """The options of ``method``: a method of the methods bench, or ``key=value[,key=value]``
    options of :class:`rmpc.RMPC` (integers, floats or words)."""
    if "=" not in method:
        options, skip, _ = method_options(problem, method)
        return options, skip
    options: dict[str, Any] = {}
    for item in method.split(","):
        key, value = item.split("=")
        for kind in (int, float, str):
            try:
                options[key] = kind(value)
                break
            except ValueError:
                continue
    return options, None


def _move(sol: Any, x: np.ndarray, u_max: float) -> np.ndarray:
    u = getattr(sol, "u0", None)
    if u is None:
        u = sol.F @ x
    return np.clip(np.asarray(u, dtype=float).ravel(), -u_max, u_max)


def time_case(case: str, states: int, kernels_only: bool, fits: list[Fit]) -> None:
    name, method = case.split(":")
    p = build_problem(name)
    options, skip = _options(p, method)
    if options is None:
        print(f"{case}: skipped ({skip})", flush=True)
        return
    a_true, b_true = p.true_plant
    ctrls = {}
    for mode in ("auto",) if kernels_only else MODES:
        with forced(mode):
            try:
                ctrls[mode] = _controller(p, options)
            except InvalidArgumentError as err:  # the size guard: too large for memory
                print(f"{case}: skipped ({err})", flush=True)
                return
    times: dict[str, list[float]] = {m: [] for m in ctrls}
    iters: dict[str, list[int]] = {m: [] for m in ctrls}
    ok = dict.fromkeys(ctrls, 0)
    x = p.x0.copy()
    count = 1 if kernels_only else states
    for step in range(count):
        sols = {}
        for mode, ctrl in ctrls.items():
            with forced(mode):
                start = time.perf_counter()
                sols[mode] = ctrl.problem.solve(x)
                elapsed = time.perf_counter() - start
            if step:
                times[mode].append(elapsed)
                iters[mode].append(int(sols[mode].iterations or 0))
            cert = sols[mode].certificate
            ok[mode] += sols[mode].status == "optimal" and cert is not None and cert.ok
        x = a_true @ x + b_true @ _move(sols["auto"], x, p.u_max)
        if np.linalg.norm(x) < 0.05 * np.linalg.norm(p.x0):
            x = p.x0 * 0.9 ** (step + 1)
    for solver in solvers_of(ctrls["auto"]):
        solver._refresh()
        t_dir, t_rows, t_sparse, t_formed = kernel_times(solver)
        terms = {**solver._schur_terms(), "variables": solver.n}
        grouped = bool(np.any(np.diff(solver._groups[0]) > 1))
        fits.append((case, terms, grouped, t_dir + PRODUCT_PAIRS * t_sparse,
                     t_rows + PRODUCT_PAIRS * t_formed))
        old = "direct" if old_rule(solver) else "rows"
        new = solver._formula
        print(f"{case:34s} n={solver.n:4d} blocks={len(solver.block_orders):3d} "
              f"size={solver._layout.size:6d} old={old:6s} new={new:6s} H: direct {1e3 * t_dir:8.3f} ms "
              f"rows {1e3 * t_rows:8.3f} ms  products: sparse {1e3 * t_sparse:8.3f} ms "
              f"formed {1e3 * t_formed:8.3f} ms  " + " ".join(f"{k}={v:.3g}" for k, v in terms.items()),
              flush=True)
    if kernels_only:
        return
    for mode in MODES:
        v = np.array(times[mode])
        took = ",".join(s._formula for s in solvers_of(ctrls[mode])) or "-"
        if uses_core(ctrls[mode]):
            took += "+ccore"
        print(f"{case:34s} {mode:6s} warm p50 {1e3 * np.median(v):9.2f} ms "
              f"[{1e3 * v.min():8.2f}, {1e3 * v.max():8.2f}] it {np.median(iters[mode]):4.1f} "
              f"{ok[mode]}/{count} optimal+certified  took {took}", flush=True)


#: One case's data for :func:`fit`: the name, the model's terms, whether the solver has a group of
#: several factored blocks (Kothare's vertex blocks, whose pair sums are vectorised over the group),
#: and the measured per-iteration seconds of the direct and of the rows formula.
Fit = tuple[str, dict[str, float], bool, float, float]


def fit(fits: list[Fit]) -> None:
    """Relative least squares (non-negative) of the per-iteration times on the model's terms
    (:meth:`lmi.ipm.blocks.BlockData._schur_terms`): rows ``c_1 syrk + c_2 stream + c_3 products``,
    direct ``c_0 pairs`` (fitted on the solvers without groups), printed as ratios to ``c_1`` (the
    units of :data:`lmi.ipm.blocks.SCHUR_PAIR_COST`); then the cases of more than
    :data:`lmi.ipm.blocks.DIRECT_MIN_VARIABLES` variables where the package's constants pick the
    formula more than 1.3 times slower than the other."""
    t_dir = np.array([f[3] for f in fits])
    t_rows = np.array([f[4] for f in fits])
    single = np.array([not f[2] for f in fits])
    if len(fits) >= MIN_FIT_CASES and int(single.sum()) >= 2:
        rows_x = np.array([[f[1]["syrk"], f[1]["stream"], f[1]["products"]] for f in fits])
        b, _ = nnls(rows_x / t_rows[:, None], np.ones(len(fits)))
        pairs = np.array([[f[1]["pairs"]] for f in fits])
        a, _ = nnls(pairs[single] / t_dir[single, None], np.ones(int(single.sum())))
        unit = b[0] if b[0] > 0.0 else 1.0
        print(f"fit ({len(fits)} cases): a dsyrk operation {1e9 * b[0]:.4f} ns; in those units: pair "
              f"{a[0] / unit:.0f}, stream {b[1] / unit:.0f}, product {b[2] / unit:.0f}", flush=True)
    else:
        print(f"fit: {len(fits)} cases, too few (at least {MIN_FIT_CASES})", flush=True)
    wrong = []
    for name, t, _, td, tr in fits:
        if t["variables"] <= DIRECT_MIN_VARIABLES:  # rows whatever the model says
            continue
        costs = formula_costs(t)
        direct, rows = costs["direct"], costs["rows"]
        if (direct < rows) != (td < tr) and max(td, tr) > 1.3 * min(td, tr):
            wrong.append(name)
    print(f"the package's constants pick the slower formula by more than 1.3x in {len(wrong)} of "
          f"{len(fits)} cases {wrong}", flush=True)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*", default=list(CASES))
    parser.add_argument("--states", type=int, default=8)
    parser.add_argument("--kernels-only", action="store_true")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    print(f"load average {os.getloadavg()}, {os.cpu_count()} cpus", flush=True)
    fits: list[Fit] = []
    for case in args.cases:
        time_case(case, args.states, args.kernels_only, fits)
    fit(fits)
    print(f"load average {os.getloadavg()}", flush=True)


if __name__ == "__main__":
    main()
