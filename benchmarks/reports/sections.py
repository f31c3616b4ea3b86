"""The Markdown pieces the suites' ``results.md`` share: the run line, tables of rows, failures, settings.

Each suite (:mod:`benchmarks.suites.paper`, ``faults``, ``mrp``, ``flexible``) writes its own
report; what they write alike is here, once.

Examples
--------
>>> from benchmarks.reports.sections import dash, rows_table, statuses
>>> dash(None), dash(0.123456), dash(0.5, ".2%")
('-', '0.1235', '50.00%')
>>> statuses({"reused": 2, "optimal": 5})
'optimal 5, reused 2'
>>> print(rows_table([{"controller": "RMPC", "statuses": "optimal 5"}]))
| controller | statuses |
| --- | --- |
| RMPC | optimal 5 |
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from benchmarks.reports.tables import to_markdown

__all__ = ["dash", "failed_cases", "rows_table", "run_lines", "settings_section", "statuses"]


def dash(value: float | None, spec: str = ".4g") -> str:
    """``value`` formatted by ``spec``; ``-`` for ``None``."""
    return "-" if value is None else format(value, spec)


def statuses(counts: Mapping[str, int]) -> str:
    """Status counts as ``word n, word n``, in alphabetical order."""
    return ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))


def rows_table(rows: Sequence[Mapping[str, Any]]) -> str:
    """A Markdown table of rows that are dicts with the same keys (the keys are the header)."""
    header = list(rows[0])
    return to_markdown(header, [[row[h] for h in header] for row in rows])


def run_lines(info: Mapping[str, Any], scale: str, versions_in_run_json: bool = False) -> list[str]:
    """The run's wall time, executor, scale, counts and machine, from ``run.json``'s content.

    ``scale`` is the scale part as it reads in the report (``"time scale 0.1"``, with any remark).
    """
    m = info["machine"]
    return [
        f"Wall time {info['wall_time_s']:.1f} s on {info['executor']}; {scale}; "
        f"{info['done']} of {info['cases']} cases done, {info['failed']} failed"
        + (" (interrupted)" if info["interrupted"] else "")
        + ".",
        f"Machine: {m['platform']}, {m['cpu_count']} CPUs, load average {m['load_average']} at the end"
        + ("; package versions in `run.json`." if versions_in_run_json else "."),
    ]


def failed_cases(failures: Sequence[Mapping[str, Any]]) -> list[str]:
    """The section listing the cases that raised (nothing when none did)."""
    if not failures:
        return []
    return ["## Failed cases", "", *(f"- {f['key']}: {f['error']}" for f in failures), ""]


def settings_section(intro: str, rows: Sequence[Sequence[Any]], rationale: str | None) -> list[str]:
    """The settings the toolkit chose: ``intro``, the table of ``(setting, value, source)`` rows, why.

    ``rationale=None`` (a smoke run: the reasons speak of the full runs' lengths and results)
    leaves the reasons out and says where they are.
    """
    lines = [
        "## Settings",
        "",
        intro,
        "",
        to_markdown(["setting", "value", "source"], [list(r) for r in rows]),
        "",
    ]
    if rationale is None:
        return [
            *lines,
            "The reasons for these values speak of the full runs and are left out of a smoke run's "
            "report; they are in the defaults module named above.",
            "",
        ]
    return [*lines, "Why these values:", "", rationale, ""]
