"""Tables of records as Markdown, CSV, LaTeX and JSON.

A table is a header and rows of plain values (``str``, ``int``, ``float`` or ``None``);
:func:`metric_table` builds one from ``results.json`` records, with the columns of paper P's
tables (``sum |e(k)|`` per axis) and the toolkit's extra metrics. Numbers are written with
four significant digits in Markdown and LaTeX and in full in CSV and JSON.

Examples
--------
>>> from benchmarks.reports.tables import to_markdown
>>> print(to_markdown(["a", "b"], [[1, 0.123456], ["x", None]]))
| a | b |
| --- | --- |
| 1 | 0.1235 |
| x | - |
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from benchmarks.core.metrics import AXES

__all__ = [
    "METRIC_COLUMNS",
    "SUMMARY_COLUMNS",
    "drop_empty_columns",
    "format_value",
    "metric_table",
    "select_columns",
    "to_csv",
    "to_json",
    "to_latex",
    "to_markdown",
    "varying_fields",
    "write_tables",
]

Row = list[Any]


def _worst(values: Mapping[str, Any] | None) -> float | None:
    """The largest per-axis value, ``None`` if any axis has none (not settled, say)."""
    if not values:
        return None
    vals = list(values.values())
    if any(v is None for v in vals):
        return None
    return max(vals)


def _ms(value: Any) -> float | None:
    return None if value is None else 1e3 * float(value)


#: (header, getter) of the metric columns, in table order.
METRIC_COLUMNS: tuple[tuple[str, Any], ...] = (
    *((f"sum|e| {ax} (rad)", lambda m, ax=ax: m["sum_abs_err"][ax]) for ax in AXES),
    ("max final |e| (rad)", lambda m: _worst(m["final_abs_err"])),
    ("max IAE (rad s)", lambda m: _worst(m["iae"])),
    ("max settling (s)", lambda m: _worst(m["settling_time"])),
    ("max overshoot (%)", lambda m: _worst(m["overshoot"])),
    ("max|u| (N m)", lambda m: m["max_abs_u"]),
    ("saturated", lambda m: m["saturated_fraction"]),
    ("violation (N m)", lambda m: m["constraint_violation"]),
    ("per-solve p50 (ms)", lambda m: _ms(m["solve_time_solves_p50"])),
    ("per-solve p95 (ms)", lambda m: _ms(m["solve_time_solves_p95"])),
    ("per-solve max (ms)", lambda m: _ms(m["solve_time_solves_max"])),
    ("solves", lambda m: m["n_solves"]),
    ("step p95 (ms)", lambda m: _ms(m["step_time_p95"])),
    ("fallbacks", lambda m: m["fallback_count"]),
    ("failures", lambda m: m["failure_count"]),
)


def varying_fields(scenarios: Sequence[Mapping[str, Any]]) -> list[str]:
    """Scenario fields (``settings.<name>`` for controller settings) whose value differs between cases.

    Examples
    --------
    >>> varying_fields([{"spread": 0.1, "settings": {"Np": 4}}, {"spread": 0.3, "settings": {}}])
    ['spread']
    """
    flat = [_flatten(s) for s in scenarios]
    keys: list[str] = []
    for f in flat:
        keys.extend(k for k in f if k not in keys)
    # a controller setting counts only among the cases whose controller has it
    return [k for k in keys if len({json.dumps(f[k], sort_keys=True) for f in flat if k in f}) > 1]


def _flatten(scenario: Mapping[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in scenario.items():
        if key == "settings" and isinstance(value, Mapping):
            out.update({f"settings.{k}": v for k, v in value.items()})
        else:
            out[key] = value
    return out


def _cell(get: Any, metrics: Mapping[str, Any]) -> Any:
    """One metric cell; ``None`` when the record's family does not measure it (the mrp and
    flexible families have no per-axis IAE, settling time or overshoot)."""
    try:
        return get(metrics)
    except KeyError:
        return None


def metric_table(
    records: Sequence[Mapping[str, Any]],
    lead: Sequence[str] = ("experiment", "controller", "plant", "saturation"),
    scenario_fields: Sequence[str] = (),
) -> tuple[list[str], list[Row]]:
    """One row per record: the ``lead`` keys, chosen scenario fields, then :data:`METRIC_COLUMNS`
    (``None`` where the record lacks the metric)."""
    header = [*lead, *scenario_fields, *(name for name, _ in METRIC_COLUMNS)]
    rows = []
    for rec in records:
        flat = _flatten(rec.get("settings", {}))
        row: Row = [rec.get(k) for k in lead]
        row += [flat.get(k) for k in scenario_fields]
        row += [_cell(get, rec["metrics"]) for _, get in METRIC_COLUMNS]
        rows.append(row)
    return header, rows


#: The metric columns of the compact summary table a report shows first (the full table follows).
SUMMARY_COLUMNS: tuple[str, ...] = (
    *(f"sum|e| {ax} (rad)" for ax in AXES),
    "max final |e| (rad)",
    "max|u| (N m)",
    "saturated",
    "failures",
)


def select_columns(
    header: Sequence[str], rows: Sequence[Row], names: Sequence[str]
) -> tuple[list[str], list[Row]]:
    """The columns of ``header`` named in ``names`` (in the table's order), with their cells."""
    keep = [i for i, h in enumerate(header) if h in names]
    return [header[i] for i in keep], [[row[i] for i in keep] for row in rows]


def drop_empty_columns(
    header: Sequence[str], rows: Sequence[Row]
) -> tuple[list[str], list[Row], list[str]]:
    """The table without the columns that are empty (``None``) in every row, and their names.

    Examples
    --------
    >>> drop_empty_columns(["a", "b"], [[1, None], [2, None]])
    (['a'], [[1], [2]], ['b'])
    """
    if not rows:
        return list(header), [list(r) for r in rows], []
    keep = [i for i in range(len(header)) if any(row[i] is not None for row in rows)]
    dropped = [header[i] for i in range(len(header)) if i not in keep]
    return [header[i] for i in keep], [[row[i] for i in keep] for row in rows], dropped


def format_value(value: Any) -> str:
    """Four significant digits for floats, ``-`` for ``None``, compact lists."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(format_value(v) for v in value) + "]"
    return str(value)


def to_markdown(header: Sequence[str], rows: Sequence[Row]) -> str:
    """A GitHub-flavoured Markdown table."""

    def cell(v: Any) -> str:
        return format_value(v).replace("|", "\\|")

    lines = [
        "| " + " | ".join(cell(h) for h in header) + " |",
        "| " + " | ".join("---" for _ in header) + " |",
    ]
    lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def to_csv(header: Sequence[str], rows: Sequence[Row]) -> str:
    """CSV with full-precision numbers and empty cells for ``None``."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(header)
    for row in rows:
        writer.writerow(
            ["" if v is None else json.dumps(v) if isinstance(v, list | tuple) else v for v in row]
        )
    return buf.getvalue()


_LATEX_ESCAPES = {
    "\\": r"\textbackslash{}",
    "&": r"\&",
    "%": r"\%",
    "$": r"\$",
    "#": r"\#",
    "_": r"\_",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde{}",
    "^": r"\textasciicircum{}",
    "|": r"$|$",
}


def _latex_escape(text: str) -> str:
    return "".join(_LATEX_ESCAPES.get(ch, ch) for ch in text)


def to_latex(header: Sequence[str], rows: Sequence[Row], caption: str | None = None) -> str:
    """A ``tabular`` (booktabs rules) inside a ``table`` float; numbers right-aligned."""
    align = "".join(
        "r" if any(isinstance(r[i], int | float) for r in rows) else "l" for i in range(len(header))
    )
    lines = [r"\begin{table}[htbp]", r"\centering", r"\small"]
    if caption:
        lines.append(rf"\caption{{{_latex_escape(caption)}}}")
    lines += [
        rf"\begin{{tabular}}{{{align}}}",
        r"\toprule",
        " & ".join(_latex_escape(h) for h in header) + r" \\",
        r"\midrule",
    ]
    lines += [" & ".join(_latex_escape(format_value(v)) for v in row) + r" \\" for row in rows]
    lines += [r"\bottomrule", r"\end{tabular}", r"\end{table}"]
    return "\n".join(lines) + "\n"


def to_json(header: Sequence[str], rows: Sequence[Row]) -> list[dict[str, Any]]:
    """Rows as a list of ``{column: value}`` objects."""
    return [dict(zip(header, row, strict=True)) for row in rows]


def write_tables(out: Path, header: Sequence[str], rows: Sequence[Row], caption: str) -> list[Path]:
    """Write ``results.csv``, ``results.tex`` and ``results_table.json`` (rows as objects) into ``out``."""
    files = {
        "results.csv": to_csv(header, rows),
        "results.tex": to_latex(header, rows, caption),
        "results_table.json": json.dumps(to_json(header, rows), indent=1) + "\n",
    }
    for name, text in files.items():
        (out / name).write_text(text, encoding="utf-8")
    return [out / name for name in files]
