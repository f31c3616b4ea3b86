"""``timing.md``: the timing report as Markdown, read from ``timing.json``'s content.

One section per problem the run measured (RMPC with the rebuild/fast ratio and the reference,
OfflineRMPC, GIPC, the scale section of :mod:`benchmarks.timing.scale`), after the machine and
the package versions.
"""

from __future__ import annotations

from typing import Any

from benchmarks.reports.sections import statuses
from benchmarks.timing.common import ms, sci, us

__all__ = ["format_markdown"]


def format_markdown(report: dict[str, Any], plot_name: str | None = "timing.png") -> str:
    """``timing.md``: the tables, the machine, the package versions and how to read them."""
    m, s = report["machine"], report["settings"]
    lines = [
        "# Solver timing report", "",
        f"Paper P's satellite: Ts = {s['dt']} s, inertia spread {s['spread']}, Q1 = diag({s['Q1']}), "
        f"R = diag({s['R']}), {s['input_constraint']} with u_max = {s['u_max']}, x0 = {s['x0']}. "
        f"Wall time of the run: {report['wall_time_s']:.1f} s"
        + (" (quick run: small sizes, for tests)." if s["quick"] else "."), "",
        "Times are wall-clock per step, reported as percentiles (p50 = median, p95, max), not means. "
        "The machines are shared: compare rows of one report, interleaved state by state, rather "
        "than reports of different runs.", "",
        "## Machine", "",
        f"- platform: {m['platform']}; processor: {m['processor']}; CPUs (os.cpu_count): {m['cpu_count']}; "
        f"Python {m['python']}",
        f"- load average (1, 5, 15 min): {m['load_average_start']} at the start, "
        f"{m['load_average_end']} at the end", "",
        "| package | version |", "| --- | --- |",
        *[f"| {k} | {v} |" for k, v in report["versions"].items()], "",
    ]
    recs = report["records"]
    rmpc = [r for r in recs if r["problem"] == "RMPC"]
    if rmpc:
        lines += [
            "## RMPC (one SDP per step)", "",
            f"{s['steps']} states per vertex count: the closed loop of the default path (ipm, "
            "delta_shared) from x0 on vertex 0, every path solved at the same states, interleaved. "
            "Time = `KothareProblem.solve` (scaling, solver, certificate, F); for cvxpy-rebuild also "
            "the construction of the cvxpy problem. Error = max |gamma / gamma_ref - 1| over the states "
            "compared (in brackets: those with a gamma and an optimal reference); margin = the "
            "smallest recomputed relative LMI margin (>= -1e-7 counts as certified). F is not "
            "compared: it is not unique at the optimum.", "",
            "| vertices | backend | formulation | steps | p50 (ms) | p95 (ms) | max (ms) | solver p50 (ms) "
            "| iterations p50 | statuses | max rel err gamma | min margin |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for r in rmpc:
            it = "n/a" if r["iterations_p50"] is None else f"{r['iterations_p50']:g}"
            lines.append(
                f"| {r['vertices']} | {r['backend']} | {r['formulation']} | {r['steps']} | {ms(r['p50_s'])} "
                f"| {ms(r['p95_s'])} | {ms(r['max_s'])} | {ms(r['solver_p50_s'])} | {it} "
                f"| {statuses(r['status_counts'])} | {sci(r['max_rel_err'])} ({r['compared_steps']}) "
                f"| {sci(r['min_margin'])} |"
            )
        lines += ["", "### Rebuilding the cvxpy problem every step vs the fast path", "",
                  "Medians over the same first states (the rebuild path is slow, so it runs on a few). "
                  "Fast path = the toolkit's interior-point method (lmi.ipm), delta_shared, data built once, "
                  "warm-started. Target: >= 20x.", "",
                  "| vertices | steps | rebuild p50 (ms) | fast p50 (ms) | rebuild / fast "
                  "| cvxpy param p50 (ms) | rebuild / cvxpy param |",
                  "| --- | --- | --- | --- | --- | --- | --- |"]
        for q in report["rebuild_over_fast"]:
            lines.append(
                f"| {q['vertices']} | {q['steps']} | {ms(q['rebuild_p50_s'])} | {ms(q['fast_p50_s'])} "
                f"| {q['rebuild_over_fast']:.1f}x | {ms(q['cvxpy_param_p50_s'])} "
                f"| {q['rebuild_over_cvxpy_param']:.1f}x |"
            )
        lines += ["", "### The reference", "",
                  "cvxpy + Clarabel, three candidates solved at every state; per state the first that is "
                  "optimal (converged to its tolerances and certified) is the reference. The spread is "
                  "the largest relative disagreement of the optimal candidates at one state: errors "
                  "below it cannot be read.", "",
                  "| vertices | candidate | statuses | used as reference |", "| --- | --- | --- | --- |"]
        for ref in report["reference"]["RMPC"]:
            for cand, counts in ref["status_counts"].items():
                used = ref["used"].get(cand, 0)
                lines.append(f"| {ref['vertices']} | {cand} | {statuses(counts)} | {used} |")
            other = {k: v for k, v in ref["used"].items() if k not in ref["status_counts"]}
            if other:
                lines.append(f"| {ref['vertices']} | (no optimal candidate) | | {statuses(other)} |")
        lines += ["", "| vertices | spread between optimal references | states with several optimal |",
                  "| --- | --- | --- |"]
        for ref in report["reference"]["RMPC"]:
            lines.append(f"| {ref['vertices']} | {sci(ref['spread_between_optimal_references'])} "
                         f"| {ref['states_with_several_optimal']} |")
        lines.append("")
    off = [r for r in recs if r["problem"] == "OfflineRMPC"]
    if off:
        lines += [
            "## OfflineRMPC (Wan & Kothare 2003: lookup per step)", "",
            "Lookups at the states of its own closed loop (nominal linear model), several passes. "
            "Error = |gamma_1 / gamma_ref(x0) - 1| (the outermost ellipsoid is designed at x0, where it "
            "is the online problem); u err = the lookup against a direct evaluation of the table.", "",
            "| vertices | lookup | ellipsoids | design (s) | calls | p50 (us) | p95 (us) | max (us) "
            "| statuses | max rel err gamma_1 | max rel err u |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for r in off:
            lines.append(
                f"| {r['vertices']} | {r['formulation']} | {r['n_ellipsoids']} | {r['design_time_s']:.2f} "
                f"| {r['steps']} | {us(r['p50_s'])} | {us(r['p95_s'])} | {us(r['max_s'])} "
                f"| {statuses(r['status_counts'])} | {sci(r['max_rel_err'])} "
                f"| {sci(r['max_rel_err_u_lookup'])} |"
            )
        lines.append("")
    gipc = [r for r in recs if r["problem"] == "GIPC"]
    if gipc:
        ref = report["reference"]["GIPC"] or {}
        lines += [
            "## GIPC (velocity-form MPC: one QP per step)", "",
            f"The QPs of one closed loop (nominal linear model, {s['cheap_steps']} steps, 0.5 N m step "
            f"disturbance from t = {ref.get('disturbance_start_s', float('nan')):g} s); every back-end "
            "solves the same QPs, interleaved, warm-started from its previous solve. Time = `update` + "
            "`solve`. Error = max |objective / objective_ref - 1| against cvxpy + Clarabel at 1e-10 "
            f"(reference statuses: {statuses(ref.get('status_counts', {}))}); KKT = the largest "
            "recomputed KKT residual. The QP uses the nominal model: the vertex count does not enter.", "",
            "| backend | steps | p50 (us) | p95 (us) | max (us) | solver p50 (us) | iterations p50 "
            "| statuses | max rel err objective | max KKT residual |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for r in gipc:
            it = "n/a" if r["iterations_p50"] is None else f"{r['iterations_p50']:g}"
            lines.append(
                f"| {r['backend']} | {r['steps']} | {us(r['p50_s'])} | {us(r['p95_s'])} "
                f"| {us(r['max_s'])} | {us(r['solver_p50_s'])} | {it} | {statuses(r['status_counts'])} "
                f"| {sci(r['max_rel_err'])} | {sci(r['max_kkt_residual'])} |"
            )
        lines.append("")
    scale = [r for r in recs if r["problem"] == "Scale"]
    if scale:
        from benchmarks.timing.scale import format_scale_markdown

        lines += format_scale_markdown(scale, "timing_scale.png" if plot_name else None)
    if report.get("breakdown"):
        from benchmarks.timing.breakdown import breakdown_sections

        lines += breakdown_sections(report["breakdown"])
    if report.get("c") is not None:
        from benchmarks.timing.c_exports import c_markdown

        lines += c_markdown(report)
    if report.get("baseline") is not None:
        from benchmarks.timing.versus import baseline_markdown

        lines += baseline_markdown(report["baseline"])
    if plot_name:
        lines += ["## Distributions", "", f"![per-step time distributions]({plot_name})", ""]
    return "\n".join(lines)
