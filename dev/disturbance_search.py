"""Solves and time per state of the disturbance form's search for its contraction factor ``lam``.

Run as ``python -m dev.disturbance_search [STEPS] [PROBLEM,PROBLEM,...]`` (default 40 steps on
``paper_p_2v``, ``kothare_ex2`` and ``double_integrator`` of
:func:`benchmarks.suites.methods_problems.build_problem`, with the "disturbance" method's options of
:func:`benchmarks.suites.methods.method_options`). Per problem: the closed loop of the RMPC with
the disturbance form on the problem's true plant from ``x0`` (the law of the default search); then
the same states solved in order by three problems: the default search, the full search at every
state (``solver_options={"lambda_search": "grid"}``, when the toolkit has it) and Kothare's form
(no disturbance). Printed per problem: the solves per state (the ``_solve_at`` calls, counted by a
spy), p50/p95 wall time per state, the ratio of the p50 to Kothare's, the statuses, and the
largest relative difference of gamma between the two searches.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from benchmarks.suites.methods import _controller, method_options
from benchmarks.suites.methods_problems import build_problem
from lmi.forms import FormProblem

DEFAULT_PROBLEMS = ("double_integrator", "mup_demo", "kothare_ex1", "paper_p_2v", "kothare_ex2")


def _spy(problem: FormProblem) -> list[int]:
    """Count ``problem._solve_at`` calls (one list entry, incremented)."""
    count = [0]
    inner = problem._solve_at

    def counted(*args, **kwargs):
        count[0] += 1
        return inner(*args, **kwargs)

    problem._solve_at = counted  # type: ignore[method-assign]
    return count


def _run(problem, states, count) -> dict:
    solves, times, gammas, lams, statuses, hows = [], [], [], [], [], []
    for x in states:
        before = count[0] if count is not None else 0
        start = time.perf_counter()
        sol = problem.solve(x)
        times.append(time.perf_counter() - start)
        solves.append((count[0] - before) if count is not None else 1)
        gammas.append(sol.gamma if sol.ok else np.nan)
        lams.append(sol.lam if sol.lam is not None else np.nan)
        statuses.append(sol.status)
        rec = getattr(problem, "last_lambda_search", None)
        hows.append("none" if rec is None else rec.how if rec.fallback is None else f"grid ({rec.fallback})")
    return {"solves": np.array(solves), "times": np.array(times), "gamma": np.array(gammas),
            "lam": np.array(lams), "status": statuses, "how": hows}


def main(steps: int, names: list[str], verbose: bool = False) -> None:
    for name in names:
        p = build_problem(name)
        opts, _, _ = method_options(p, "disturbance")
        ctrl = _controller(p, opts)
        a, b = p.true_plant
        x = p.x0.copy()
        states = []
        for _ in range(steps):
            states.append(x.copy())
            u = np.asarray(ctrl.step(x), dtype=float)
            x = a @ x + b @ u
        runs = {}
        for label, extra in (("default", {}), ("grid", {"lambda_search": "grid"}), ("kothare", None)):
            kw = dict(opts) if extra is not None else {}
            if extra:
                kw["solver_options"] = extra
            try:
                c = _controller(p, kw)
            except Exception as err:  # the toolkit without the option
                print(f"{name} {label}: {err}")
                continue
            prob = c.problem
            count = _spy(prob) if isinstance(prob, FormProblem) else None
            runs[label] = _run(prob, states, count)
        k50 = float(np.median(runs["kothare"]["times"][1:]))
        print(f"== {name}: {len(states)} states, Kothare's form p50 {1e3 * k50:.1f} ms")
        for label, r in runs.items():
            t = r["times"][1:]  # the first (cold) left out
            st = {s: r["status"].count(s) for s in sorted(set(r["status"]))}
            print(f"  {label:8s} solves/state mean {r['solves'].mean():.2f} (first {r['solves'][0]}, "
                  f"later max {r['solves'][1:].max()}), p50 {1e3 * np.median(t):.1f} ms, "
                  f"p95 {1e3 * np.percentile(t, 95):.1f} ms, p50/Kothare {np.median(t) / k50:.1f}x, {st}")
            ok = np.isfinite(r["gamma"])
            ok[0] = False  # the first state: the grid in both
            if ok.any() and label != "kothare":
                t_ok = r["times"][ok]
                k_ok = runs["kothare"]["times"][ok]
                sv = r["solves"][ok]
                print(f"    at the {ok.sum()} later certified states: solves/state mean {sv.mean():.2f}"
                      f" (min {sv.min()}, max {sv.max()}), p50 {1e3 * np.median(t_ok):.1f} ms,"
                      f" p95 {1e3 * np.percentile(t_ok, 95):.1f} ms, p50/Kothare's p50 there "
                      f"{np.median(t_ok) / np.median(k_ok):.1f}x")
                if verbose:
                    print("    lam:", " ".join(f"{v:.4f}" for v in r["lam"]))
            if label == "default":
                hows = {h: r["how"].count(h) for h in sorted(set(r["how"]))}
                print(f"    searches: {hows}")
        if "grid" in runs and "default" in runs and np.any(np.isfinite(runs["grid"]["gamma"])):
            g0, g1 = runs["grid"]["gamma"], runs["default"]["gamma"]
            both = np.isfinite(g0) & np.isfinite(g1)
            if not both.any():
                print("  no state certified by both searches")
                continue
            rel = (g1[both] - g0[both]) / g0[both]
            if verbose:
                d = runs["default"]
                for i in np.flatnonzero(both):
                    print(f"    state {i}: rel {(g1[i] - g0[i]) / g0[i]:+.2e}, lam {d['lam'][i]:.5f} vs"
                          f" {runs['grid']['lam'][i]:.5f}, {d['solves'][i]} solves, {d['how'][i]}")
            print(f"  gamma default vs grid over {both.sum()} states: max |rel| {np.max(np.abs(rel)):.2e}, "
                  f"max rel (default higher) {np.max(rel):.2e}, min {np.min(rel):.2e}; "
                  f"lam grid {np.nanmin(runs['grid']['lam']):.3f}-{np.nanmax(runs['grid']['lam']):.3f}")


if __name__ == "__main__":
    n_steps = int(sys.argv[1]) if len(sys.argv) > 1 else 40
    problems = sys.argv[2].split(",") if len(sys.argv) > 2 else list(DEFAULT_PROBLEMS)
    main(n_steps, problems, verbose="-v" in sys.argv)
