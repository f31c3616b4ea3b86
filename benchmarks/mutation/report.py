"""The mutation check's outputs: ``results.json`` (every mutant's record) and ``report.md``."""

from __future__ import annotations

import json
import subprocess
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from benchmarks.mutation.operators import Mutant
    from benchmarks.mutation.runner import CheckConfig, MutantResult

__all__ = ["STATUSES", "project_commit", "render_markdown", "summarize", "write_report"]

#: The outcomes, in the order the report counts them.
STATUSES = ("caught", "survived", "timeout", "error", "not run")


def project_commit(root: Path) -> str:
    """The short commit of ``root``, with a note when tracked files have uncommitted changes."""
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + (" (with uncommitted changes)" if dirty else "")


def summarize(config: CheckConfig, every: Sequence[Mutant], results: Sequence[MutantResult],
              map_info: dict[str, Any], seconds: float, interrupted: bool, untouched: bool,
              commit: str | None = None) -> dict[str, Any]:
    """Everything ``results.json`` holds; ``commit`` is the project's commit when the run started
    (read now if not given)."""
    counts = Counter(r.status for r in results)
    settings = {k: (str(v) if isinstance(v, Path) else v) for k, v in asdict(config).items()}
    settings["operators"] = list(config.operators)
    return {
        "settings": settings,
        "commit": commit if commit is not None else project_commit(config.root),
        "mutants_in_modules": len(every),
        "mutants_by_module": dict(Counter(m.module for m in every)),
        "map": map_info,
        "counts": {status: counts.get(status, 0) for status in STATUSES},
        "no_test": sum(1 for r in results if r.detail == "no test runs it"),
        "tried": len(results),
        "wall_seconds": round(seconds, 1),
        "interrupted": interrupted,
        "working_files_untouched": untouched,
        "mutants": [r.to_json() for r in results],
    }


def _table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return lines


def _by(records: Sequence[dict[str, Any]], key: str) -> list[list[Any]]:
    groups: dict[str, Counter[str]] = {}
    for r in records:
        groups.setdefault(r[key], Counter())[r["status"]] += 1
    return [[name, sum(c.values()), *(c.get(s, 0) for s in STATUSES)] for name, c in sorted(groups.items())]


def _code(text: str) -> str:
    return "`" + text.replace("`", "'").replace("|", "\\|") + "`"


def _map_note(info: dict[str, Any]) -> str:
    if not info:
        return ""
    if info.get("reused"):
        return f"; the map was reused from an earlier run (which took {info['seconds']:.0f} s)"
    return f", of which the map run {info['seconds']:.0f} s"


def render_markdown(summary: dict[str, Any]) -> str:
    """``report.md``: the settings, the counts, and every mutant that was not caught."""
    s = summary["settings"]
    c = summary["counts"]
    records = summary["mutants"]
    out = [
        "# Mutation check",
        "",
        f"Commit {summary['commit']}; modules {', '.join(s['modules'])}; tests {', '.join(s['tests'])}.",
        f"Sample of {summary['tried']} of {summary['mutants_in_modules']} mutants (seed {s['seed']}, "
        f"operators {', '.join(s['operators'])}); wall time {summary['wall_seconds']:.0f} s"
        + _map_note(summary["map"]) + ".",
        "",
        f"**{c['caught']} caught, {c['survived']} survived ({summary['no_test']} run by no test), "
        f"{c['timeout']} timed out, {c['error']} errors, {c['not run']} not run.**",
        "",
    ]
    if summary["interrupted"]:
        out += ["The run was interrupted: the counts are of the mutants that finished.", ""]
    if not summary["working_files_untouched"]:
        out += ["WARNING: the modules' working files changed during the run (not by this check).", ""]
    header = ["", "mutants", *STATUSES]
    out += ["## By module", "", *_table(["module", *header[1:]], _by(records, "module")), ""]
    out += ["## By operator", "", *_table(["operator", *header[1:]], _by(records, "operator")), ""]
    for status, title in (("survived", "Survivors"), ("timeout", "Timed out"), ("error", "Errors")):
        rows = [[r["id"], f"{r['path']}:{r['line']}", _code(r["original"]), _code(r["replacement"]),
                 f"{r['tests_run']}/{r['tests_covering']}", r["detail"]]
                for r in records if r["status"] == status]
        columns = ["mutant", "where", "was", "became", "tests run/covering", "note"]
        if rows:
            out += [f"## {title}", "", *_table(columns, rows), ""]
    return "\n".join(out)


def write_report(out: Path, summary: dict[str, Any]) -> None:
    """Write ``results.json`` and ``report.md`` into ``out``."""
    (out / "results.json").write_text(json.dumps(summary, indent=1), encoding="utf-8")
    (out / "report.md").write_text(render_markdown(summary), encoding="utf-8")
