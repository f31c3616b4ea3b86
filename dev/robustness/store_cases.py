"""Damaged stores and the compare tool: resumes over case files and sweep rows that cannot be
trusted, and ``benchmarks.compare`` on inputs that are not runs.

- ``cli:methods case ...``: ``rmpc bench methods`` resumes over a case file that an earlier run
  stored and that was then damaged (wrong types, missing keys, not JSON, truncated, another case's
  record, a folder in its place). A good answer measures the case again (exit 0); a traceback, or
  an exit status other than 0 and 2, is a crash. An exit 2 must name the ``folder`` or the case.
- ``cli:sweep row ...``: the same for a sweep's store whose row of the case was damaged.
- ``benchmarks.compare...``: the compare tool's function on two folders. Inputs that are not runs
  must be refused with an error naming the file; for two runs that differ only where the old tool
  was blind (``true`` against ``1``, a record merged with another), the probe's call returns the
  number of differences and NaN when there are none, so a tool that finds nothing is ``silent``.
  (``python -m benchmarks.compare`` is not a subcommand of ``rmpc``, the CLI door of the probe:
  these probes go through the API door; the command's exit statuses are in
  ``tests/test_compare_inputs.py``.)
"""

from __future__ import annotations

import json
import os
import sqlite3
import tempfile
from collections.abc import Callable
from typing import Any

from dev.robustness.cli_cases import SWEEP_ARGV, TINY_SWEEP
from dev.robustness.probe import Probe

__all__ = ["store_probes"]

_PROBLEM, _METHOD = "kothare_ex1", "kothare"
_CASE = f"out/cases/{_PROBLEM}__{_METHOD}.json"
_METHODS_ARGV = (
    "bench", "methods", "--short", "--problems", _PROBLEM, "--methods", _METHOD, "--out", "{tmp}/out",
)


def _stored_case(tmp: str) -> dict[str, Any]:
    """Run the one case for real (the case file a later run resumes from); its stored JSON."""
    from benchmarks.suites.methods import run_methods

    run_methods(os.path.join(tmp, "out"), short=True, problems=[_PROBLEM], methods=[_METHOD], progress=False)
    with open(os.path.join(tmp, _CASE), encoding="utf-8") as handle:
        return dict(json.load(handle))


def _damage(kind: str) -> Callable[[str], None]:
    """``setup(tmp)``: a finished run in ``tmp/out`` whose case file is then damaged by ``kind``."""

    def setup(tmp: str) -> None:
        case = _stored_case(tmp)
        path = os.path.join(tmp, _CASE)
        rec = case["record"]
        text: str | None = None
        if kind == "settings = 5":
            case["settings"] = 5
        elif kind == "record.settings = 5":
            rec["settings"] = 5
        elif kind == "gamma = 'abc'":
            rec["gamma"] = "abc"
        elif kind == "notes = 5":
            rec["notes"] = 5
        elif kind == "status_counts = list":
            rec["status_counts"] = ["optimal"]
        elif kind == "region.t = string":
            rec["region"] = dict(rec["region"] or {}, t="wide")
        elif kind == "missing record.problem":
            del rec["problem"]
        elif kind == "missing record.region":
            del rec["region"]
        elif kind == "missing record":
            del case["record"]
        elif kind == "extra = list":
            case["extra"] = [1, 2]
        elif kind == "another case's record":
            rec["problem"] = "kothare_ex2"
        elif kind == "another method's record":
            rec["method"] = "vertex"
        elif kind == "a list":
            text = json.dumps([case])
        elif kind == "not JSON":
            text = "{not json"
        elif kind == "NaN":
            text = json.dumps(case).replace(json.dumps(rec["gamma"]), "NaN", 1)
        elif kind == "truncated":
            text = json.dumps(case)[: len(json.dumps(case)) // 2]
        elif kind == "empty":
            text = ""
        elif kind == "a folder":
            os.remove(path)
            os.makedirs(path)
            return
        else:
            raise ValueError(kind)
        with open(path, "w", encoding="utf-8") as handle:
            handle.write(json.dumps(case) if text is None else text)

    return setup


_CASE_KINDS = (
    "settings = 5",
    "record.settings = 5",
    "gamma = 'abc'",
    "notes = 5",
    "status_counts = list",
    "region.t = string",
    "missing record.problem",
    "missing record.region",
    "missing record",
    "extra = list",
    "another case's record",
    "another method's record",
    "a list",
    "not JSON",
    "NaN",
    "truncated",
    "empty",
    "a folder",
)


def _sweep_row(kind: str) -> Callable[[str], None]:
    """``setup(tmp)``: the tiny sweep run for real into ``tmp/out``, then its row damaged by ``kind``."""

    def setup(tmp: str) -> None:
        from benchmarks.core.sweep import run_sweep

        config = os.path.join(tmp, "sweep.toml")
        with open(config, "w", encoding="utf-8") as handle:
            handle.write(TINY_SWEEP)
        run_sweep(config, os.path.join(tmp, "out"), workers=0, progress=False)
        with sqlite3.connect(os.path.join(tmp, "out", "sweep.sqlite")) as db:
            (record,) = db.execute("SELECT record FROM cases").fetchone()
            rec = json.loads(record)
            if kind == "metrics.iae = 'abc'":
                rec["metrics"]["iae"] = "abc"
            elif kind == "metrics = 5":
                rec["metrics"] = 5
            elif kind == "missing metrics":
                del rec["metrics"]
            elif kind == "record of another case":
                rec["case_id"] = "0123456789abcdef"
            new = json.dumps(rec)
            if kind == "record not JSON":
                new = "{not json"
            if kind == "scenario of another case":
                db.execute("UPDATE cases SET scenario = ?", (json.dumps({"plant": "nonlinear"}),))
            else:
                db.execute("UPDATE cases SET record = ?", (new,))

    return setup


_ROW_KINDS = (
    "metrics.iae = 'abc'",
    "metrics = 5",
    "missing metrics",
    "record of another case",
    "record not JSON",
    "scenario of another case",
)


def _run_folder(root: str, name: str, content: str | None) -> str:
    folder = os.path.join(root, name)
    os.makedirs(folder, exist_ok=True)
    if content is not None:
        with open(os.path.join(folder, "results.json"), "w", encoding="utf-8") as handle:
            handle.write(content)
    return folder


def _compare_refuses(content: str | None) -> Callable[[], Any]:
    """Compare a good run with a folder holding ``content`` as results.json (None: no file)."""

    def call() -> Any:
        from benchmarks.compare import compare_runs

        with tempfile.TemporaryDirectory() as root:
            good = _run_folder(root, "good", json.dumps([{"experiment": "E1", "label": "RMPC", "x": 1}]))
            bad = _run_folder(root, "bad", content)
            return compare_runs(good, bad)

    return call


def _compare_finds(before: list[dict[str, Any]], after: list[dict[str, Any]]) -> Callable[[], Any]:
    """Compare two runs that differ: the number of differences found, NaN for none (``silent``)."""

    def call() -> float:
        from benchmarks.compare import compare_runs

        with tempfile.TemporaryDirectory() as root:
            lines = compare_runs(
                _run_folder(root, "a", json.dumps(before)), _run_folder(root, "b", json.dumps(after))
            )
        return float(len(lines)) if lines else float("nan")

    return call


def _deep(depth: int) -> str:
    return json.dumps([{"experiment": "E1", "label": "RMPC", "x": 0}])[:-2] + ', "deep": ' + (
        "[" * depth + "]" * depth
    ) + "}]"


def store_probes() -> list[Probe]:
    """Every probe of this module: resumes over damaged stores (cli), compare on bad inputs (api)."""
    probes = [
        Probe(
            f"cli:methods case {kind}",
            "cli",
            ("folder", f"{_PROBLEM}__{_METHOD}"),
            argv=_METHODS_ARGV,
            setup=_damage(kind),
            expect="either",
            kind="store",
        )
        for kind in _CASE_KINDS
    ]
    probes += [
        Probe(
            f"cli:sweep row {kind}",
            "cli",
            ("sweep.sqlite", "store"),
            argv=SWEEP_ARGV,
            setup=_sweep_row(kind),
            expect="either",
            kind="store",
        )
        for kind in _ROW_KINDS
    ]
    refused = {
        "no records": "[]",
        "an object without records": '{"runs": 1}',
        "empty records": '{"records": []}',
        "a list of strings": '["a", "b"]',
        "a list of numbers": "[1, 2]",
        "records without identity": '[{"x": 1}]',
        "deeply nested (parser)": "[" * 100000 + "]" * 100000,
        "deeply nested (record)": _deep(500),
        "not JSON": "{not json",
        "truncated": '[{"experiment": "E1", "lab',
        "no results.json": None,
    }
    probes += [
        Probe(f"benchmarks.compare.after:{name}", "api", ("results.json", "bad"), call=_compare_refuses(text),
              kind="compare")
        for name, text in refused.items()
    ]
    rec = {"experiment": "E1", "label": "RMPC"}
    probes += [
        Probe(
            "benchmarks.compare.after:true against 1",
            "api",
            ("compare",),
            call=_compare_finds([dict(rec, ok=True)], [dict(rec, ok=1)]),
            expect="either",
            kind="compare",
        ),
        Probe(
            "benchmarks.compare.after:shared identity",
            "api",
            ("compare",),
            call=_compare_finds(
                [dict(rec, x=1), dict(rec, x=2), dict(rec, label="RMPC #2", x=3)],
                [dict(rec, x=1), dict(rec, x=5), dict(rec, label="RMPC #2", x=3)],
            ),
            expect="either",
            kind="compare",
        ),
    ]
    return probes
