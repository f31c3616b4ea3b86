"""``rmpc timing --baseline OLD_DIR``: this report's per-case solve times next to an earlier report's.

Every record with per-case solve times (``p50_s``: the RMPC, OfflineRMPC, GIPC, Scale and C
sections) is paired with the baseline's record of the same problem, formulation, back-end,
vertex count and size (:func:`benchmarks.compare.record_identity`); :func:`timing_comparison`
builds the comparison (:func:`benchmarks.baseline.compare_times`, stored as ``baseline`` in
``timing.json``) and :func:`baseline_markdown` its section of ``timing.md``: one table per
problem with p50, p95, the solver's own p50 and the iterations of both runs and new/old.

Examples
--------
>>> from benchmarks.timing.versus import case_label
>>> case_label({"problem": "RMPC", "backend": "ipm", "formulation": "delta_shared", "vertices": 2})
'ipm, delta_shared, 2 vertices'
"""

from __future__ import annotations

from typing import Any

from benchmarks.baseline import (
    Baseline,
    TimeField,
    baseline_summary_lines,
    baseline_table,
    compare_times,
    rows_of,
)

__all__ = ["TIMING_TIME_FIELDS", "baseline_markdown", "case_label", "timing_comparison"]

#: The figures compared, per record (seconds; ``iterations_p50``: a count).
TIMING_TIME_FIELDS: tuple[TimeField, ...] = (
    TimeField("p50_s", "p50", "ms"),
    TimeField("p95_s", "p95", "ms"),
    TimeField("solver_p50_s", "solver p50", "ms"),
    TimeField("iterations_p50", "iterations p50", "count"),
)


def case_label(rec: dict[str, Any]) -> str:
    """A timing record's row label: back-end, formulation, vertices and (Scale) states."""
    parts = [str(rec.get("backend")), str(rec.get("formulation")), f"{rec.get('vertices')} vertices"]
    if rec.get("n_states") is not None:
        parts.append(f"{rec['n_states']} states")
    return ", ".join(parts)


def _timed(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [r for r in records if "p50_s" in r]


def timing_comparison(report: dict[str, Any], baseline: Baseline) -> dict[str, Any]:
    """The comparison of ``report`` (a ``timing.json``) with ``baseline``'s records."""

    def side(records: list[dict[str, Any]]) -> list[tuple[str, str, str, dict[str, Any]]]:
        return rows_of(_timed(records), True, lambda r: str(r.get("problem")), case_label, lambda r: r)

    return compare_times(
        side(report["records"]), side(baseline.records), TIMING_TIME_FIELDS, baseline.folder,
        {"new": report.get("machine"), "old": baseline.machine},
        {"new": report.get("versions"), "old": baseline.versions},
    )


def baseline_markdown(comparison: dict[str, Any]) -> list[str]:
    """The section of ``timing.md`` on the baseline: what it is, then one table per problem."""
    lines = [
        "## Times against the baseline", "",
        "Every record with per-step times, paired with the baseline's of the same problem, back-end, "
        "formulation, vertices and size: both runs' figures and new/old.", "",
        *baseline_summary_lines(comparison, [r["group"] for r in comparison["rows"]]),
    ]
    for group in dict.fromkeys(r["group"] for r in comparison["rows"]):
        lines += [f"### {group}", "", *baseline_table(comparison, group, "case"), ""]
    return lines
