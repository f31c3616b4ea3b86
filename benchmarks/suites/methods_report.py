"""The report of ``rmpc bench methods``: ``results.md``, ``results.csv``, ``run.json`` and the figures.

Everything it says is read from the records of the run (:mod:`benchmarks.suites.methods` measures
them). Two kinds of record are kept apart from the comparisons:

- a form that never had a certified gain (no solve at ``x0`` or at any closed-loop step came back
  ``"optimal"``, so the controller applied ``u = 0`` or a fallback throughout) is shown as
  "no certified gain": no closed-loop cost, and no place in the cost ratios or the ranking;
- a region that reached the search cap ``t_max`` in some direction is a lower bound: written
  "at least ...", kept off the colour scale of the summary and off the extent of the region
  plots; where every form reaches the cap in every direction the plot says so instead of
  drawing the cap's polygon as if it were a region.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.baseline import (
    Baseline,
    TimeField,
    baseline_summary_lines,
    baseline_table,
    compare_times,
    rows_of,
)
from benchmarks.core.suite import SuiteOutcome, write_records, write_rows_csv, write_run_info

__all__ = [
    "FAMILIES",
    "GAMMA_COMPARABLE",
    "METHODS_TIME_FIELDS",
    "NO_GAIN",
    "SUMMARY_COLUMNS",
    "TIE_TOLERANCE",
    "certified",
    "families_head_to_head",
    "family_of",
    "least_conservative",
    "methods_comparison",
    "region_ratio",
    "summary_ratios",
    "table_row",
    "write_methods_report",
]

#: Methods whose ``gamma`` bounds the worst-case cost under the problem's own bounds and is what
#: they minimise (the nominal forms bound the nominal cost, the soft form's bound holds with the
#: bounds its slacks relaxed, Huang et al.'s keys minimise ``gamma + beta gamma_s``, so their
#: ``gamma`` grows with ``beta``): the ones ranked by gamma.
GAMMA_COMPARABLE: tuple[str, ...] = (
    "kothare", "vertex", "vertex_pairs", "free_move", "auxiliary_saturation", "li", "shi", "zhang",
)

#: Relative difference below which two methods tie in the report's ranking.
TIE_TOLERANCE: float = 0.001

#: What the report shows in place of a cost for a form that never had a certified gain.
NO_GAIN = "no certified gain"

#: The columns of the compact table each problem's section shows first (all columns follow).
SUMMARY_COLUMNS: tuple[str, ...] = (
    "method",
    "status at x0",
    "gamma",
    "region vs kothare",
    "cost (nominal plant)",
    "solve p50 / p95 (ms)",
    "violations / samples",
)

#: Step statuses that mean the controller applied a certified gain.
_CERTIFIED_STEPS = ("optimal", "reused")


def certified(rec: dict[str, Any]) -> bool:
    """Whether the form had a certified gain at some point: the solve at ``x0`` or a closed-loop
    step ``"optimal"`` (or ``"reused"``, a kept certified gain). A skipped record counts as
    certified-unknown and returns ``True`` (it has no cost to hide)."""
    if rec.get("status") == "skipped":
        return True
    if rec.get("status") == "optimal":
        return True
    counts = rec.get("status_counts") or {}
    return any(counts.get(s, 0) > 0 for s in _CERTIFIED_STEPS)


def _cost(rec: dict[str, Any], key: str = "closed_loop_cost") -> float | None:
    """The record's closed-loop cost, ``None`` when it has none or never had a certified gain."""
    value = rec.get(key)
    if value is None or not certified(rec):
        return None
    return float(value)


def _capped(rec: dict[str, Any] | None) -> bool:
    return bool(rec is not None and rec.get("region") and rec["region"].get("capped"))


def _fmt(value: float | None, spec: str = ".4g") -> str:
    return "-" if value is None else format(value, spec)


def _ms(value: float | None) -> str:
    return "-" if value is None else f"{1e3 * value:.1f}"


def summary_ratios(
    records: list[dict[str, Any]],
) -> tuple[list[str], list[str], np.ndarray, np.ndarray, np.ndarray]:
    """Problems, methods and the matrices (problem x method) of the region and of the closed-loop
    cost on the nominal plant, each over Kothare's (NaN where a record or a value is missing, and
    for the cost where either form never had a certified gain), and where the region ratio rests
    on a capped region (a bound, not a measurement: ``True``)."""
    problems = list(dict.fromkeys(r["problem"] for r in records))
    methods = list(dict.fromkeys(r["method"] for r in records))
    region = np.full((len(problems), len(methods)), np.nan)
    capped = np.zeros(region.shape, dtype=bool)
    cost = np.full_like(region, np.nan)
    for i, p in enumerate(problems):
        base = next((r for r in records if r["problem"] == p and r["method"] == "kothare"), None)
        for j, m in enumerate(methods):
            rec = next((r for r in records if r["problem"] == p and r["method"] == m), None)
            if rec is None or base is None:
                continue
            ratio = region_ratio(rec, base)
            if ratio is not None:
                region[i, j] = ratio
                capped[i, j] = _capped(rec) or _capped(base)
            c, c0 = _cost(rec), _cost(base)
            if c is not None and c0 and np.isfinite(c):
                cost[i, j] = c / c0
    return problems, methods, region, cost, capped


def region_ratio(rec: dict[str, Any], base: dict[str, Any] | None) -> float | None:
    """Geometric mean over the directions of ``t(method) / t(kothare)`` (directions where both > 0)."""
    if base is None or rec.get("region") is None or base.get("region") is None:
        return None
    a, b = np.asarray(rec["region"]["t"]), np.asarray(base["region"]["t"])
    ok = (a > 0) & (b > 0)
    if a.shape != b.shape or not ok.any():
        return None
    return float(np.exp(np.mean(np.log(a[ok] / b[ok]))))


def table_row(rec: dict[str, Any], base: dict[str, Any] | None) -> dict[str, str]:
    """The report's row of one record (``base``: the same problem's Kothare record)."""
    region = rec.get("region")
    counts = rec.get("status_counts") or {}
    ratio = region_ratio(rec, base)
    if region is None:
        reach = "-"
    else:
        cap = "at least " if region["capped"] else ""
        reach = f"{region['min_t']:.3g} / {cap}{region['geo_mean_t']:.3g}"
    if ratio is not None and (_capped(rec) or _capped(base)):
        ratio_text = f"{ratio:.3f} (a region at the cap: a bound)"
    else:
        ratio_text = _fmt(ratio, ".3f")
    gain = certified(rec)
    cv = rec.get("cvxpy_time_p50")
    return {
        "method": rec["method"] + ("" if rec.get("comparable", True) else " (peak bound)"),
        "status at x0": str(rec["status"]),
        "gamma": _fmt(rec.get("gamma")),
        "iter": _fmt(rec.get("iterations"), "d") if rec.get("iterations") is not None else "-",
        "region min / geo-mean t": reach,
        "region vs kothare": ratio_text,
        "region ended by": "-"
        if region is None
        else ", ".join(f"{k} {v}" for k, v in sorted(region.get("ended_by", {}).items())),
        "cost (nominal plant)": _fmt(rec.get("closed_loop_cost")) if gain else NO_GAIN,
        "cost (switching)": _fmt(rec.get("closed_loop_cost_switching")) if gain else NO_GAIN,
        "solve p50 / p95 (ms)": f"{_ms(rec.get('solve_time_p50'))} / {_ms(rec.get('solve_time_p95'))}",
        "cvxpy p50 (ms)": _ms(cv),
        "cvxpy / ipm": _fmt(rec.get("cvxpy_ratio"), ".1f"),
        "violations / samples": "-" if rec.get("violation_samples") is None
        else f"{rec.get('violations')} / {rec.get('violation_samples')}",
        "step statuses": ", ".join(f"{k} {v}" for k, v in sorted(counts.items())) or "-",
    }


def _best(recs: list[dict[str, Any]], key: Any, largest: bool) -> dict[str, Any] | None:
    cands = [r for r in recs if key(r) is not None and np.isfinite(key(r))]
    if not cands:
        return None
    return (max if largest else min)(cands, key=key)


def _ties(recs: list[dict[str, Any]], key: Any, best: dict[str, Any], rel: float = TIE_TOLERANCE) -> str:
    """`` (tied: a, b)`` for the other methods within ``rel`` of the best value, else ``""``."""
    v = key(best)
    tied = [
        r["method"]
        for r in recs
        if r is not best and key(r) is not None and abs(key(r) - v) <= rel * max(abs(v), 1e-300)
    ]
    return f" (tied within {rel:.1%}: {', '.join(tied)})" if tied else ""


def least_conservative(records: list[dict[str, Any]]) -> list[str]:
    """Per problem: the smallest worst-case gamma, the largest region and the lowest closed-loop cost."""
    lines = []
    for p in dict.fromkeys(r["problem"] for r in records):
        recs = [r for r in records if r["problem"] == p and r.get("comparable", True)]
        base = next((r for r in recs if r["method"] == "kothare"), None)
        parts = []
        gam = _best(
            [r for r in recs if r["method"] in GAMMA_COMPARABLE and r["status"] == "optimal"],
            lambda r: r.get("gamma"),
            largest=False,
        )
        if gam is not None:
            ref = (
                f" (kothare {base['gamma']:.4g}, {base['status']})"
                if base and base.get("gamma") is not None
                else ""
            )
            ranked = [r for r in recs if r["method"] in GAMMA_COMPARABLE and r["status"] == "optimal"]
            parts.append(
                f"smallest worst-case gamma: {gam['method']} {gam['gamma']:.4g}{ref}"
                + _ties(ranked, lambda r: r.get("gamma"), gam)
            )
        hard = [r for r in recs if r["method"] != "soft"]  # soft bounds enlarge the region by relaxing them

        def ratio(r: dict[str, Any], b: dict[str, Any] | None = base) -> float | None:
            return region_ratio(r, b)

        measured = [] if _capped(base) else [r for r in hard if not _capped(r)]
        at_cap = [r["method"] for r in hard if _capped(r)]
        reg = _best(measured, ratio, largest=True)
        if reg is not None:
            parts.append(
                f"largest region (hard bounds): {reg['method']} ({ratio(reg):.3f} x kothare's, "
                "geometric mean)"
                + _ties(measured, ratio, reg)
                + (f" (at the search cap, not ranked: {', '.join(at_cap)})" if at_cap else "")
            )
        elif at_cap:
            parts.append(
                "largest region (hard bounds): not ranked, the search cap bounds "
                + ("Kothare's region" if _capped(base) else "the regions")
                + f" (at the cap: {', '.join(at_cap)})"
            )
        gained = [r for r in recs if certified(r)]
        cost = _best(gained, _cost, largest=False)
        if cost is not None:
            c0 = _cost(base) if base else None
            ref = f" (kothare {c0:.4g})" if c0 is not None else ""
            parts.append(
                f"lowest closed-loop cost: {cost['method']} {cost['closed_loop_cost']:.4g}{ref}"
                + _ties(gained, _cost, cost)
            )
        lost = [r["method"] for r in recs if not certified(r)]
        if lost:
            parts.append(f"{NO_GAIN}: " + ", ".join(lost))
        if parts:
            lines.append(f"- **{p}**: " + "; ".join(parts) + ".")
    return lines


#: The families of the methods bench: a method not named here is an LMI form (or MUP's key).
FAMILIES: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("tube", ("tube", "tube_tightening")),
    ("multi-stage", ("multistage",)),
)


def family_of(method: str) -> str:
    """``"LMI"`` for the forms and MUP's keys, else the QP family's name (:data:`FAMILIES`)."""
    return next((name for name, members in FAMILIES if method in members), "LMI")


def families_head_to_head(records: list[dict[str, Any]]) -> list[str]:
    """Per problem where more than one family ran: for each family its lowest closed-loop cost
    (certified methods, the problem's own bounds), its fastest solve p50 and its violations over
    the seeded runs, and which family wins on cost and on time."""
    lines = []
    for p in dict.fromkeys(r["problem"] for r in records):
        ran = [r for r in records if r["problem"] == p and r["status"] != "skipped"]
        by_family: dict[str, list[dict[str, Any]]] = {}
        for r in ran:
            by_family.setdefault(family_of(r["method"]), []).append(r)
        if len(by_family) < 2:
            continue
        parts, best_cost, best_time = [], None, None
        for fam, recs in by_family.items():
            own = [r for r in recs if r.get("comparable", True) and certified(r)]
            cost = _best(own, _cost, largest=False)
            fast = _best(recs, lambda r: r.get("solve_time_p50"), largest=False)
            viol = sum(int(r.get("violations") or 0) for r in recs)
            samples = sum(int(r.get("violation_samples") or 0) for r in recs)
            text = f"{fam}: "
            text += (f"cost {cost['closed_loop_cost']:.4g} ({cost['method']})" if cost
                     else "no comparable cost")
            text += f", p50 {_ms(fast['solve_time_p50'])} ms ({fast['method']})" if fast else ""
            text += f", violations {viol} / {samples}"
            parts.append(text)
            if cost and (best_cost is None or _cost(cost) < _cost(best_cost)):
                best_cost = cost
            if fast and (best_time is None or fast["solve_time_p50"] < best_time["solve_time_p50"]):
                best_time = fast
        wins = []
        if best_cost is not None:
            wins.append(f"lowest cost: {family_of(best_cost['method'])}")
        if best_time is not None:
            wins.append(f"fastest: {family_of(best_time['method'])}")
        lines.append(f"- **{p}**: " + "; ".join(parts) + (" (" + ", ".join(wins) + ")" if wins else "") + ".")
    return lines


#: The timing figures ``--baseline`` puts next to the earlier run's (``p50_vs_kothare``: the
#: solve p50 over Kothare's form's on the same problem, in the same run).
METHODS_TIME_FIELDS: tuple[TimeField, ...] = (
    TimeField("solve_time_p50", "solve p50", "ms"),
    TimeField("solve_time_p95", "solve p95", "ms"),
    TimeField("iterations", "iter", "count"),
    TimeField("p50_vs_kothare", "p50 / kothare's", "x"),
    TimeField("cvxpy_time_p50", "cvxpy p50", "ms"),
    TimeField("cvxpy_ratio", "cvxpy / ipm", "x"),
)


def _time_figures(records: list[dict[str, Any]]) -> Any:
    """The figures of :data:`METHODS_TIME_FIELDS` of a record of ``records``."""

    def figures(rec: dict[str, Any]) -> dict[str, Any]:
        out = {f.key: rec.get(f.key) for f in METHODS_TIME_FIELDS}
        base = _kothare(records, rec["problem"])
        p50, k50 = rec.get("solve_time_p50"), None if base is None else base.get("solve_time_p50")
        out["p50_vs_kothare"] = p50 / k50 if p50 is not None and k50 else None
        return out

    return figures


def methods_comparison(
    records: list[dict[str, Any]], baseline: Baseline, machine: dict[str, Any] | None,
    versions: dict[str, Any] | None,
) -> dict[str, Any]:
    """This run's timing figures next to the baseline's, per problem and method
    (:func:`benchmarks.baseline.compare_times`; ``machine``, ``versions``: this run's)."""

    def side(recs: list[dict[str, Any]]) -> list[tuple[str, str, str, dict[str, Any]]]:
        return rows_of(recs, False, lambda r: r["problem"], lambda r: r["method"], _time_figures(recs))

    return compare_times(
        side(records), side(baseline.records), METHODS_TIME_FIELDS, baseline.folder,
        {"new": machine, "old": baseline.machine}, {"new": versions, "old": baseline.versions},
    )


def write_methods_report(
    out: Path,
    outcome: SuiteOutcome,
    extras: dict[tuple[str, str], dict[str, Any]],
    settings: Any,
    n_cases: int,
    resumed: int,
    short: bool,
    baseline: Baseline | None = None,
) -> list[Path]:
    """Write ``results.json``, ``results.csv``, ``run.json``, ``results.md`` and the figures.

    ``settings`` is the run's :class:`benchmarks.suites.methods.MethodsSettings` (not named in
    the signature: the runner imports this module). With ``baseline`` (an earlier run,
    :func:`benchmarks.baseline.load_baseline`) each problem's section gains a table of the
    timing figures next to the baseline's, ``results.md`` a section on what it is compared
    with, ``run.json`` the comparison under ``baseline`` and each record of ``results.json``
    its row under ``baseline`` (:mod:`benchmarks.baseline`).
    """
    from benchmarks.reports.methods_figures import plot_regions, plot_summary
    from benchmarks.reports.sections import failed_cases, run_lines, settings_section
    from benchmarks.reports.tables import to_markdown
    from benchmarks.suites.methods_problems import SUITE_CHOICES

    records = outcome.records
    info = write_run_info(out, "rmpc bench methods", outcome, n_cases, None, None, ("short", float(short)))
    comparison = None
    if baseline is not None:
        comparison = methods_comparison(records, baseline, info.get("machine"), info.get("versions"))
        info["baseline"] = comparison
        (out / "run.json").write_text(json.dumps(info, indent=1) + "\n", encoding="utf-8")
        by_key = {(r["group"], r["label"]): r for r in comparison["rows"]}
        written = [{**r, "baseline": by_key.get((r["problem"], r["method"]))} for r in records]
    files: list[Path] = [write_records(out, records if comparison is None else written)]
    rows = [{"problem": r["problem"], **table_row(r, _kothare(records, r["problem"]))} for r in records]
    csv_path = write_rows_csv(out / "results.csv", rows)
    if csv_path is not None:
        files.append(csv_path)
    (out / "figures").mkdir(exist_ok=True)
    figures: dict[str, Path] = {}
    for p in dict.fromkeys(r["problem"] for r in records):
        recs = [r for r in records if r["problem"] == p]
        if recs[0]["settings"]["n_states"] == 2:
            pts = {r["method"]: extras.get((p, r["method"]), {}).get("region_points") for r in recs}
            trajs = {r["method"]: extras.get((p, r["method"]), {}).get("trajectory") for r in recs}
            caps = {r["method"]: _capped(r) for r in recs}
            path = plot_regions(
                p, pts, trajs, recs[0]["settings"]["x0"], out / "figures" / f"region_{p}.png",
                capped=caps, t_max=settings.t_max,
            )
            if path is not None:
                figures[p] = path
                files.append(path)
    problems, methods, region, cost, capped = summary_ratios(records)
    summary = plot_summary(problems, methods, region, cost, out / "figures" / "summary.png", capped=capped)
    if summary is not None:
        files.append(summary)
    scale = (
        "short run (a smoke run: few directions, short horizons; no measurement: its regions and costs "
        "check the set-up, they do not rank the forms)"
        if short
        else "full run"
    )
    lines = [
        "# Benchmark suite `methods`: the robust MPC forms head to head",
        "",
        *run_lines(info, scale),
        *(
            [f"{resumed} cases were taken from an earlier run of the same command (`cases/`)."]
            if resumed
            else []
        ),
        *(
            ["", "Stored cases the run did not take as they were:", "", *(f"- {n}" for n in outcome.notes)]
            if outcome.notes
            else []
        ),
        "",
        "Per problem and method: the status and `gamma` of the solve at the start state `x0`; the "
        "feasible region as the largest certified multiple `t` of fixed directions (scaled to the "
        "size of `x0`, so `t = 1` reaches as far as `x0`; smallest and geometric mean over the "
        f"directions, `at least` where a direction reached the search cap {settings.t_max:g}: a bound, "
        "kept out of the ranking and off the summary's colour scale) and its ratio to "
        "Kothare's direction by direction, and what ended each direction (`infeasible`: the solver's "
        "certificate; a solver failure word: the form gave up there; `cap`); the closed-loop cost "
        "`sum x'Q x + u'R u` on the nominal "
        "plant and on a seeded switching sequence of vertices; the wall time of the closed-loop steps "
        "that solved (p50 / p95, certification included) and of cvxpy + Clarabel on the same LMIs "
        f"at the first {settings.cvxpy_states} closed-loop states (ratio to the toolkit's ipm on "
        "those states, both warm: the first solve, cvxpy's compilation and the ipm's cold start, "
        "is left out of both medians). `gamma` of the nominal form bounds the nominal cost, that of "
        "the soft form holds with the bounds its slacks relaxed (`slack` in the records; their price is "
        "not in `gamma`); the ranking by gamma leaves both out. A form that never had a certified gain "
        f"(no `optimal` solve at x0 or at any step: it applied u = 0 or a fallback) shows `{NO_GAIN}` "
        "in place of a cost and has no place in the cost ratios.",
        "",
        "What the families assume: the LMI forms take the polytope of plants (one vertex for the "
        "whole prediction with `lyapunov=\"common\"`/`\"vertex\"`, any vertex at every sample with "
        "`\"vertex_pairs\"`) and bound the worst-case cost (`gamma`); `multistage` (a scenario tree "
        "over the vertices, robust horizon 1) takes the same polytope, with no cost bound and no "
        "terminal set; `tube` and `tube_tightening` take one plant with an additive disturbance box W "
        "and run only where a problem gives one. `violations` counts the samples of the seeded "
        "switching-vertex runs (pushed by W where a problem has one) whose input or next state broke "
        "a bound.",
        "",
        "## Which form is least conservative where",
        "",
        *(
            [
                "No measurement: a smoke run's few directions and short horizons check the set-up; the "
                "lines below are what it measured, not a ranking of the forms.",
                "",
            ]
            if short
            else []
        ),
        *least_conservative(records),
        "",
        "## The families head to head",
        "",
        "Where more than one family ran (the LMI forms with MUP's keys, the tube, multi-stage): each "
        "family's lowest closed-loop cost on the nominal plant (certified, under the problem's own "
        "bounds), its fastest solve p50 and its bound violations over the seeded runs. The families "
        "assume different uncertainty (see above), so a win is on this problem's terms only.",
        "",
        *(
            [
                "No measurement: a smoke run's short horizons and few runs check the set-up; the lines "
                "below are what it measured, not a comparison of the families.",
                "",
            ]
            if short
            else []
        ),
        *(families_head_to_head(records) or ["(one family ran on every problem)"]),
        "",
    ]
    if comparison is not None:
        lines += [
            "## Times against the baseline",
            "",
            "Each problem's section ends with its timing figures next to those of the baseline run "
            "(paired by problem and method) and the ratio new/old; `p50 / kothare's` is the solve p50 "
            "over Kothare's form's on the same problem, in the same run.",
            "",
            *baseline_summary_lines(comparison, [r["problem"] for r in records]),
        ]
    for p in dict.fromkeys(r["problem"] for r in records):
        recs = [r for r in records if r["problem"] == p]
        s = recs[0]["settings"]
        lines += [
            f"## {p}",
            "",
            f"{s['n_states']} states, {s['n_inputs']} inputs, {s['n_vertices']} vertices, dt {s['dt']:g} s, "
            f"{s['input_constraint']} bound {s['u_max']:g}; x0 = {np.round(s['x0'], 4).tolist()}.",
            "",
        ]
        prows = [table_row(r, _kothare(records, p)) for r in recs]
        short_cols = [c for c in SUMMARY_COLUMNS if c in prows[0]]
        lines += [
            to_markdown(short_cols, [[row[c] for c in short_cols] for row in prows]),
            "",
            "All columns:",
            "",
            to_markdown(list(prows[0]), [list(row.values()) for row in prows]),
            "",
        ]
        notes = [f"- {r['method']}: {r['skip_reason']}" for r in recs if r.get("skip_reason")] + [
            f"- {r['method']}: {n}" for r in recs for n in r.get("notes", [])
        ]
        notes += [
            f"- {r['method']}: {NO_GAIN} (status at x0 {r['status']}; step statuses "
            + (", ".join(f"{k} {v}" for k, v in sorted((r.get("status_counts") or {}).items())) or "none")
            + ")"
            for r in recs
            if not certified(r)
        ]
        lines += notes + ([""] if notes else [])
        if comparison is not None:
            lines += ["Times against the baseline:", "", *baseline_table(comparison, p), ""]
        if p in figures:
            lines += [f"![{p}]({figures[p].relative_to(out).as_posix()})", ""]
    if summary is not None:
        lines += [
            "## Regions and costs against Kothare's",
            "",
            f"![summary]({summary.relative_to(out).as_posix()})",
            "",
        ]
    lines += failed_cases(outcome.failures)
    lost = {r["problem"] for r in records if r["method"] == "disturbance" and not certified(r)}
    rows_s = []
    for k, v, why in SUITE_CHOICES:
        if k == "disturbance method" and lost:
            why += f"; in this run no certified gain carries it on {', '.join(sorted(lost))}"
        rows_s.append((k, v, why))
    rows_s.append(
        (
            "region",
            f"{settings.directions_2d} angles (2 states) / {settings.directions} directions, "
            f"bisection to {settings.rel_tol:g} relative",
            "suite settings",
        )
    )
    rows_s.append(("seed", str(settings.seed), "directions and switching sequence"))
    lines += settings_section(
        "The problems' data and the suite's own choices (`benchmarks/suites/methods_problems.py`).",
        rows_s,
        "Every method sees the same problem, start state, directions and plants; a method that does not "
        "apply, or that this build does not offer, is recorded with its reason.",
    )
    (out / "results.md").write_text("\n".join(lines), encoding="utf-8")
    files += [out / "run.json", out / "results.md"]
    return files


def _kothare(records: list[dict[str, Any]], problem: str) -> dict[str, Any] | None:
    return next((r for r in records if r["problem"] == problem and r["method"] == "kothare"), None)
