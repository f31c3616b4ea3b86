"""Stored cases are read through one validating schema; reports are written together or not at all.

Families: a ``rmpc bench methods`` case file damaged (wrong types, missing keys, not JSON,
truncated) or foreign (another case's record) is measured again and the run says so; a folder in
a case file's place leaves no temporary file and drops no case; a sweep row that is damaged or
another case's is measured again; a crash in a report writer leaves every report of the previous
run as it was.
"""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import pytest

from benchmarks.core.publish import staged_reports
from benchmarks.core.schema import first_problem
from benchmarks.core.store import STORE_NAME
from benchmarks.core.sweep import run_sweep
from benchmarks.suites.methods import run_methods
from benchmarks.suites.methods_store import CASE_SCHEMA, case_path
from toolkit_common.errors import InvalidArgumentError

PROBLEM, METHOD = "kothare_ex1", "kothare"
REPORTS = ("results.json", "results.md", "results.csv", "run.json")


def _run(out: Path, methods: tuple[str, ...] = (METHOD,)):
    return run_methods(out, short=True, problems=[PROBLEM], methods=list(methods), progress=False)


@pytest.fixture(scope="module")
def stored_case(tmp_path_factory) -> dict:
    """The case file a real short run stores for kothare_ex1 x kothare."""
    out = tmp_path_factory.mktemp("methods_good")
    _run(out)
    return json.loads(case_path(out, PROBLEM, METHOD).read_text(encoding="utf-8"))


def _damaged(case: dict, kind: str) -> str:
    case = json.loads(json.dumps(case))
    rec = case["record"]
    if kind == "settings = 5":
        case["settings"] = 5
    elif kind == "record.settings = 5":
        rec["settings"] = 5
    elif kind == "gamma = 'abc'":
        rec["gamma"] = "abc"
    elif kind == "notes = 5":
        rec["notes"] = 5
    elif kind == "status_counts = str":
        rec["status_counts"] = "optimal"
    elif kind == "extra = list":
        case["extra"] = [1]
    elif kind == "missing record.problem":
        del rec["problem"]
    elif kind == "missing record.region":
        del rec["region"]
    elif kind == "another problem's record":
        rec["problem"] = "kothare_ex2"
    elif kind == "another method's record":
        rec["method"] = "vertex"
    elif kind == "not JSON":
        return "{not json"
    elif kind == "truncated":
        return json.dumps(case)[:400]
    elif kind == "NaN":
        return json.dumps(case).replace(json.dumps(rec["gamma"]), "NaN", 1)
    return json.dumps(case)


def test_a_real_stored_case_fits_the_schema(stored_case) -> None:
    assert first_problem(stored_case, CASE_SCHEMA) is None
    stored_case = json.loads(json.dumps(stored_case))
    stored_case["record"]["region"]["capped"] = 1  # 1 is not true
    problem = first_problem(stored_case, CASE_SCHEMA)
    assert problem == "record.region.capped: expected true or false, found int 1"


@pytest.mark.parametrize(
    "kind",
    [
        "settings = 5",
        "record.settings = 5",
        "gamma = 'abc'",
        "notes = 5",
        "status_counts = str",
        "extra = list",
        "missing record.problem",
        "missing record.region",
        "another problem's record",
        "another method's record",
        "not JSON",
        "truncated",
        "NaN",
    ],
)
def test_a_damaged_or_foreign_case_is_measured_again_and_said_so(tmp_path, stored_case, kind) -> None:
    path = case_path(tmp_path, PROBLEM, METHOD)
    path.parent.mkdir(parents=True)
    path.write_text(_damaged(stored_case, kind), encoding="utf-8")
    outcome = _run(tmp_path)
    (rec,) = outcome.records
    assert (rec["problem"], rec["method"]) == (PROBLEM, METHOD)
    assert isinstance(rec["gamma"], float) and rec["gamma"] == pytest.approx(stored_case["record"]["gamma"])
    assert outcome.execution.finished == [f"{PROBLEM}__{METHOD}"]  # measured, not taken from the file
    (note,) = outcome.notes
    assert note.startswith(f"cases/{path.name}: not used (") and note.endswith("measured again")
    assert note in (tmp_path / "results.md").read_text(encoding="utf-8")
    assert json.loads((tmp_path / "run.json").read_text())["notes"] == [note]
    # the file is whole again: the next run takes it as it is, and says nothing
    again = _run(tmp_path)
    assert again.execution.finished == [] and again.notes == []


def test_a_folder_in_a_case_files_place_drops_no_case_and_leaves_no_temporary_file(tmp_path) -> None:
    path = case_path(tmp_path, PROBLEM, METHOD)
    path.mkdir(parents=True)
    outcome = _run(tmp_path)
    assert [r["method"] for r in outcome.records] == [METHOD]
    assert not outcome.failures
    assert sorted(p.name for p in path.parent.iterdir()) == [path.name]  # no .tmp, hidden or not
    assert outcome.notes == [
        f"cases/{path.name}: not used (a folder, not a file); measured again",
        f"cases/{path.name}: not stored ({path} is a folder); a later run measures it again",
    ]


def test_a_crash_in_the_report_writer_leaves_the_previous_reports_whole(tmp_path, monkeypatch) -> None:
    _run(tmp_path)
    before = {name: (tmp_path / name).read_bytes() for name in REPORTS}

    def broken(*args, **kwargs):
        raise RuntimeError("the summary figure failed")

    monkeypatch.setattr("benchmarks.reports.methods_figures.plot_summary", broken)
    with pytest.raises(RuntimeError, match="summary figure"):
        _run(tmp_path, (METHOD, "nominal"))  # a second record: every report would change
    assert {name: (tmp_path / name).read_bytes() for name in REPORTS} == before
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no staging folder left
    monkeypatch.undo()
    outcome = _run(tmp_path, (METHOD, "nominal"))
    assert len(json.loads((tmp_path / "results.json").read_text())) == 2
    assert all(p.exists() and tmp_path in p.parents for p in outcome.files)


def test_reports_whose_place_holds_a_folder_are_all_refused_before_any_is_replaced(tmp_path) -> None:
    (tmp_path / "results.json").write_text("old json")
    (tmp_path / "results.md").mkdir()
    with pytest.raises(InvalidArgumentError, match=r"results\.md"):
        with staged_reports(tmp_path) as stage:
            (stage / "results.json").write_text("new json")
            (stage / "results.md").write_text("new md")
    assert (tmp_path / "results.json").read_text() == "old json"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json", "results.md"]


TINY_SWEEP = """name = "tiny"
[base]
plant = "linear"
controller = "LQR"
saturation = "limiter"
duration = 0.2
"""


@pytest.mark.parametrize(
    ("kind", "why"),
    [
        ("metrics.iae = 'abc'", "record.metrics.iae: expected an object, found str 'abc'"),
        ("missing label", "record: expected the key label, found none"),
        ("record of another case", "the record of another case"),
        ("scenario of another case", "the scenario stored under this id is another case's"),
        ("record not JSON", "a column that is not JSON"),
    ],
)
def test_a_damaged_or_foreign_sweep_row_is_measured_again_and_said_so(tmp_path, capsys, kind, why) -> None:
    config = tmp_path / "sweep.toml"
    config.write_text(TINY_SWEEP)
    out = tmp_path / "out"
    run_sweep(config, out, workers=0, progress=False)
    good = json.loads((out / "results.json").read_text())
    with sqlite3.connect(out / STORE_NAME) as db:
        (text,) = db.execute("SELECT record FROM cases").fetchone()
        rec = json.loads(text)
        if kind == "metrics.iae = 'abc'":
            rec["metrics"]["iae"] = "abc"
        elif kind == "missing label":
            del rec["label"]
        elif kind == "record of another case":
            rec["case_id"] = "0123456789abcdef"
        new = "{not json" if kind == "record not JSON" else json.dumps(rec)
        if kind == "scenario of another case":
            db.execute("UPDATE cases SET scenario = ?", (json.dumps({"plant": "nonlinear"}),))
        else:
            db.execute("UPDATE cases SET record = ?", (new,))
    capsys.readouterr()
    outcome = run_sweep(config, out, workers=0, progress=False)
    assert (outcome.skipped, outcome.ran, outcome.failed) == (0, 1, 0)
    assert why in capsys.readouterr().err
    (rec,) = json.loads((out / "results.json").read_text())
    assert rec["metrics"]["iae"] == good[0]["metrics"]["iae"]
    assert run_sweep(config, out, workers=0, progress=False).skipped == 1  # whole again
