"""Times of a run next to those of an earlier run (``--baseline DIR``): the figures, new/old, the machine.

``rmpc bench methods --baseline DIR`` and ``rmpc timing --baseline DIR`` read an earlier output
folder of the same command (:func:`load_baseline`), pair its records with this run's by their
identity (:func:`benchmarks.compare.record_identity`: ``problem | method`` for the methods
suite, ``problem | formulation | backend | vertices | n_states`` for the timing report) and put
each timing figure of both runs side by side with the ratio new / old (:func:`compare_times`).
A row present in one run only says so; a baseline measured on another machine (platform,
processor, CPU count or Python differ, as the runs recorded them) is flagged.

The comparison is a JSON object (:func:`compare_times`; written as ``baseline`` into the
methods suite's ``run.json`` and each of its ``results.json`` records, and into ``timing.json``):

``baseline``
    The baseline folder as given.
``same_machine``
    ``true``, ``false``, or ``null`` when either run did not record its machine.
``machine_differences``
    ``"field: baseline value -> this run's value"`` per differing field of :data:`MACHINE_FIELDS`.
``version_differences``
    The same for the package versions both runs recorded.
``fields``
    The figures compared, ``{"key": ..., "label": ..., "unit": ...}`` each.
``counts``
    How many rows are in ``both`` runs, in ``this run only``, in ``the baseline only``.
``p50_ratio_geomean``
    Geometric mean of the new/old ratio of the first field over the rows that have it (``null``
    when none has).
``rows``
    One per record identity: ``group`` (the problem), ``label`` (the method, or back-end,
    formulation, vertices...), ``key``, ``presence`` (one of :data:`PRESENCE`), ``new`` and
    ``old`` (the figures, ``null`` where a run has none) and ``ratio`` (new / old per field,
    ``null`` where either is missing or old is not positive).

Examples
--------
>>> from benchmarks.baseline import TimeField, compare_times
>>> fields = (TimeField("p50", "p50", "ms"),)
>>> new = [("P1", "kothare", "P1 | kothare", {"p50": 0.002})]
>>> old = [("P1", "kothare", "P1 | kothare", {"p50": 0.004}), ("P1", "vertex", "P1 | vertex", {"p50": 0.01})]
>>> cmp = compare_times(new, old, fields, "old_run", {}, {})
>>> [(r["label"], r["presence"], r["ratio"]["p50"]) for r in cmp["rows"]]
[('kothare', 'both', 0.5), ('vertex', 'the baseline only', None)]
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks.compare import load_run, paired_records, record_identity
from benchmarks.core.schema import read_json_file
from toolkit_common.errors import InvalidArgumentError

__all__ = [
    "MACHINE_FIELDS",
    "PRESENCE",
    "Baseline",
    "TimeField",
    "baseline_summary_lines",
    "baseline_table",
    "compare_times",
    "load_baseline",
    "machine_differences",
    "rows_of",
]

#: What identifies the machine a run was timed on (``run.json`` / ``timing.json`` ``machine``).
MACHINE_FIELDS: tuple[str, ...] = ("platform", "processor", "cpu_count", "python")

#: Where a row's record is: in both runs, in this run only, in the baseline only.
PRESENCE: tuple[str, str, str] = ("both", "this run only", "the baseline only")

#: The kinds of run a baseline can be: what each expects, in words.
_KINDS = {
    "methods": "an earlier `rmpc bench methods` output folder (results.json with problem/method records)",
    "timing": "an earlier `rmpc timing` output folder (timing.json)",
}


@dataclass(frozen=True)
class TimeField:
    """One figure compared: its key in the figures, its column label and its unit
    (``"ms"``, ``"us"``: a time in seconds shown so; ``"count"``; ``"x"``: a ratio)."""

    key: str
    label: str
    unit: str


@dataclass(frozen=True)
class Baseline:
    """An earlier run's records and what it was measured on."""

    folder: str
    records: list[dict[str, Any]]
    machine: dict[str, Any] | None
    versions: dict[str, Any] | None


def load_baseline(folder: str | Path, kind: str) -> Baseline:
    """Read the output folder of an earlier run of ``kind`` (``"methods"`` or ``"timing"``).

    Raises
    ------
    InvalidArgumentError
        Naming ``--baseline``: no such folder, no ``results.json`` / ``timing.json``, not JSON,
        no records, or the records of another kind of run.
    """
    if kind not in _KINDS:
        raise InvalidArgumentError("kind", "one of " + ", ".join(_KINDS), repr(kind))
    expected = _KINDS[kind]
    path = Path(folder)
    try:
        records, timing = load_run(path, argument="--baseline")
    except InvalidArgumentError as err:  # say which kind of run was expected
        found = err.found.replace("neither", "a folder without results.json or timing.json", 1)
        raise InvalidArgumentError("--baseline", expected, found) from None
    if timing != (kind == "timing"):
        found = "the timing.json of `rmpc timing`" if timing else "the results.json of a benchmark suite"
        raise InvalidArgumentError("--baseline", expected, f"{found} ({path})")
    meta_name = "timing.json" if timing else "run.json"
    meta, _ = read_json_file(path / meta_name)
    meta = meta if isinstance(meta, dict) else {}
    if kind == "methods":
        other = next((r for r in records if "problem" not in r or "method" not in r), None)
        command = meta.get("command")
        if other is not None or (command is not None and command != "rmpc bench methods"):
            what = f"run.json of {command!r}" if other is None else (
                "records without problem and method (keys: " + ", ".join(sorted(map(str, other))[:6]) + ")"
            )
            raise InvalidArgumentError("--baseline", expected, f"{what} ({path})")
    machine = meta.get("machine") if isinstance(meta.get("machine"), dict) else None
    versions = meta.get("versions") if isinstance(meta.get("versions"), dict) else None
    return Baseline(str(folder), list(records), machine, versions)


def machine_differences(
    new: dict[str, Any] | None, old: dict[str, Any] | None, fields: Sequence[str] = MACHINE_FIELDS
) -> list[str] | None:
    """``"field: old -> new"`` for each of ``fields`` that differs; ``None`` when either is unknown."""
    if not new or not old:
        return None
    return [f"{k}: {old.get(k)} -> {new.get(k)}" for k in fields if old.get(k) != new.get(k)]


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        return None
    return float(value)


def _ratio(new: Any, old: Any) -> float | None:
    a, b = _number(new), _number(old)
    return None if a is None or b is None or b <= 0.0 else a / b


#: One side's row: (group, label, key, figures by field key).
Row = tuple[str, str, str, dict[str, Any]]


def compare_times(
    new: Sequence[Row],
    old: Sequence[Row],
    fields: Sequence[TimeField],
    folder: str,
    machines: dict[str, dict[str, Any] | None],
    versions: dict[str, dict[str, Any] | None],
) -> dict[str, Any]:
    """The comparison (the JSON object of the module's docstring) of two runs' rows.

    Parameters
    ----------
    new, old : sequence of (group, label, key, figures)
        This run's rows and the baseline's; rows pair by ``key``, which must be unique per side.
    fields : sequence of TimeField
        The figures to compare (the first one's ratios give ``p50_ratio_geomean``).
    folder : str
        The baseline folder, as given.
    machines, versions : dict
        ``{"new": ..., "old": ...}``: what each run recorded (``None``: nothing).
    """
    by_old = {key: (group, label, figs) for group, label, key, figs in old}
    new_keys = {key for _, _, key, _ in new}
    rows: list[dict[str, Any]] = []

    def figures(figs: dict[str, Any] | None) -> dict[str, Any] | None:
        return None if figs is None else {f.key: _number(figs.get(f.key)) for f in fields}

    def row(group: str, label: str, key: str, a: dict[str, Any] | None, b: dict[str, Any] | None) -> None:
        presence = PRESENCE[0] if a is not None and b is not None else PRESENCE[1 if b is None else 2]
        fa, fb = figures(a), figures(b)
        ratio = {f.key: _ratio(fa[f.key], fb[f.key]) if fa and fb else None for f in fields}
        rows.append({"group": group, "label": label, "key": key, "presence": presence,
                     "new": fa, "old": fb, "ratio": ratio})

    for group, label, key, figs in new:
        row(group, label, key, figs, by_old[key][2] if key in by_old else None)
    for group, label, key, figs in old:  # the baseline's rows this run has not: after its group's rows
        if key not in new_keys:
            row(group, label, key, None, figs)
    order = {g: i for i, g in enumerate(dict.fromkeys(r["group"] for r in rows))}
    rows.sort(key=lambda r: order[r["group"]])  # stable: this run's order within a group
    first = [r["ratio"][fields[0].key] for r in rows if fields and r["ratio"][fields[0].key]]
    diff = machine_differences(machines.get("new"), machines.get("old"))
    vnew, vold = versions.get("new") or {}, versions.get("old") or {}
    return {
        "baseline": folder,
        "same_machine": None if diff is None else not diff,
        "machine_differences": diff or [],
        "version_differences": [
            f"{k}: {vold[k]} -> {vnew[k]}" for k in sorted(set(vnew) & set(vold)) if vnew[k] != vold[k]
        ],
        "fields": [{"key": f.key, "label": f.label, "unit": f.unit} for f in fields],
        "counts": {p: sum(r["presence"] == p for r in rows) for p in PRESENCE},
        "p50_ratio_geomean": math.exp(sum(map(math.log, first)) / len(first)) if first else None,
        "rows": rows,
    }


def _show(value: float | None, unit: str) -> str:
    if value is None:
        return "-"
    if unit == "ms":
        return f"{1e3 * value:.3g}"
    if unit == "us":
        return f"{1e6 * value:.3g}"
    if unit == "count":
        return f"{value:g}"
    return f"{value:.2f}"


def baseline_table(comparison: dict[str, Any], group: str, label_header: str = "method") -> list[str]:
    """The markdown table of ``group``'s rows: per field this run, the baseline and new/old."""
    fields = [TimeField(**f) for f in comparison["fields"]]
    rows = [r for r in comparison["rows"] if r["group"] == group]
    if not rows:
        return []
    head = [label_header]
    for f in fields:
        unit = f" ({f.unit})" if f.unit in ("ms", "us") else ""
        head += [f"{f.label}{unit} new", "old", "new/old"]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for r in rows:
        cells = [r["label"]]
        if r["presence"] != PRESENCE[0]:
            cells[0] += f" ({'not in the baseline' if r['old'] is None else 'not in this run'})"
        for f in fields:
            a = None if r["new"] is None else r["new"][f.key]
            b = None if r["old"] is None else r["old"][f.key]
            q = r["ratio"][f.key]
            cells += [_show(a, f.unit), _show(b, f.unit), "-" if q is None else f"{q:.2f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def baseline_summary_lines(comparison: dict[str, Any], shown_groups: Sequence[str] = ()) -> list[str]:
    """What the comparison is against: the folder, the machine flag, the versions, the counts,
    the geometric mean of the first ratio; and the groups of the baseline's rows that are not in
    ``shown_groups`` (a problem this run did not run), with their row counts."""
    c = comparison
    counts = c["counts"]
    first = c["fields"][0]["label"] if c["fields"] else "time"
    lines = [f"Baseline: `{c['baseline']}`; new/old < 1 means this run is faster.", ""]
    if c["same_machine"] is None:
        lines.append("- **machine unknown**: one of the runs did not record its machine; the ratios "
                     "may compare two machines.")
    elif not c["same_machine"]:
        lines.append("- **measured on another machine**: " + "; ".join(c["machine_differences"])
                     + ". The ratios mix the change with the machines' difference.")
    else:
        lines.append("- same machine (" + ", ".join(MACHINE_FIELDS) + " as recorded); the load may differ.")
    if c["version_differences"]:
        lines.append("- package versions that differ (baseline -> this run): "
                     + "; ".join(c["version_differences"]))
    lines.append(f"- rows: {counts[PRESENCE[0]]} in both runs, {counts[PRESENCE[1]]} in this run only, "
                 f"{counts[PRESENCE[2]]} in the baseline only")
    if c["p50_ratio_geomean"] is not None:
        lines.append(f"- {first}: new/old geometric mean {c['p50_ratio_geomean']:.3f} over the rows "
                     "both runs timed")
    absent: dict[str, int] = {}
    for r in c["rows"]:
        if r["presence"] == PRESENCE[2] and r["group"] not in shown_groups:
            absent[r["group"]] = absent.get(r["group"], 0) + 1
    if absent:
        lines.append("- in the baseline only, not run now: "
                     + ", ".join(f"{g} ({n} row{'s' if n != 1 else ''})" for g, n in absent.items()))
    return [*lines, ""]


def rows_of(
    records: Sequence[dict[str, Any]], timing: bool, group: Callable[[dict[str, Any]], str],
    label: Callable[[dict[str, Any]], str], figures: Callable[[dict[str, Any]], dict[str, Any]],
) -> list[Row]:
    """One side's rows: the records keyed by :func:`benchmarks.compare.record_identity` (with a
    count where one repeats, :func:`benchmarks.compare.paired_records`), each with its group,
    label (and that count) and figures."""
    out = []
    for key, rec in paired_records(records, timing, positional=False).items():
        repeat = key[len(record_identity(rec, timing)):]
        out.append((group(rec), label(rec) + repeat, key, figures(rec)))
    return out
