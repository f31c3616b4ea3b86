"""``python -m benchmarks.compare`` on inputs that are not runs, on shared identities, on true and 1.

Families: a folder whose results.json is not the records of a run (no records, items that are
not records, records without identifying fields, deep nesting, not JSON, a folder in its place)
is refused with exit 2 and one line naming the file, never a traceback; records that share their
identity are all compared and named; a boolean and a number never compare equal.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmarks.compare import compare_records, duplicate_identities, main

GOOD = [{"experiment": "E1", "label": "RMPC", "metrics": {"iae": 1.0}}]


def _folder(root: Path, name: str, content: str | None) -> Path:
    folder = root / name
    folder.mkdir()
    if content is not None:
        (folder / "results.json").write_text(content, encoding="utf-8")
    return folder


def _deep_record(depth: int) -> str:
    return json.dumps([{"experiment": "E1", "label": "RMPC", "deep": 0}]).replace(
        "0}", "[" * depth + "]" * depth + "}"
    )


NOT_RUNS = {
    "no records": ("[]", "no records"),
    "empty records": ('{"records": []}', "no records"),
    "an object without records": ('{"runs": 3}', "an object without it"),
    "a list of strings": ('["a", "b"]', "item 0: str 'a'"),
    "a list of numbers": ("[1, 2]", "item 0: int"),
    "a string": ('"E1"', "str"),
    "records without identity": ('[{"x": 1}]', "record 0 with none of them"),
    "deep (the parser's limit)": ("[" * 100000 + "]" * 100000, "nested too deeply to read"),
    "deep (a record)": (_deep_record(300), "record 0 nested deeper"),
    "not JSON": ("{not json", "Expecting property name"),
    "truncated": ('[{"experiment": "E1", "lab', "Unterminated string"),
}


@pytest.mark.parametrize("name", list(NOT_RUNS))
def test_an_input_that_is_not_a_run_exits_2_naming_the_file(tmp_path, capsys, name) -> None:
    content, found = NOT_RUNS[name]
    good = _folder(tmp_path, "good", json.dumps(GOOD))
    bad = _folder(tmp_path, "bad", content)
    for argv in ([str(good), str(bad)], [str(bad), str(good)]):
        assert main(argv) == 2
        captured = capsys.readouterr()
        (line,) = captured.err.strip().splitlines()
        assert str(bad / "results.json") in line and found in line
        assert "Traceback" not in captured.err and captured.out == ""


def test_a_folder_without_a_run_or_a_file_given_as_a_folder_exits_2(tmp_path, capsys) -> None:
    good = _folder(tmp_path, "good", json.dumps(GOOD))
    empty = _folder(tmp_path, "empty", None)
    (tmp_path / "folder_json").mkdir()
    (tmp_path / "folder_json" / "results.json").mkdir()
    cases = {
        empty: "neither",
        tmp_path / "missing": "nothing there",
        good / "results.json": "a file",
        tmp_path / "folder_json": "Is a directory",
    }
    for bad, found in cases.items():
        assert main([str(good), str(bad)]) == 2
        (line,) = capsys.readouterr().err.strip().splitlines()
        assert str(bad) in line and found in line


def test_true_and_1_differ_but_1_and_1_0_do_not() -> None:
    a = [{"experiment": "E1", "label": "RMPC", "ok": True, "n": 1}]
    b = [{"experiment": "E1", "label": "RMPC", "ok": 1, "n": 1.0}]
    assert compare_records(a, b) == ["E1 | RMPC: ok: true -> 1"]
    assert compare_records(b, a) == ["E1 | RMPC: ok: 1 -> true"]
    assert compare_records([dict(a[0], ok=False)], [dict(a[0], ok=0)]) == ["E1 | RMPC: ok: false -> 0"]


def test_records_sharing_an_identity_are_all_compared_never_merged() -> None:
    rec = {"experiment": "E1", "label": "RMPC"}
    # the third record's own key reads like the second's numbered repeat ("E1 | RMPC #2")
    before = [dict(rec, x=1), dict(rec, x=2), dict(rec, label="RMPC #2", x=3)]
    after = [dict(rec, x=1), dict(rec, x=5), dict(rec, label="RMPC #2", x=3)]
    assert compare_records(before, after) == ["E1 | RMPC #2: x: 2 -> 5"]
    after[2]["x"] = 4
    assert len(compare_records(before, after)) == 2
    assert duplicate_identities(before) == {"E1 | RMPC": 2}


def test_the_command_names_shared_identities_and_keeps_the_output_of_good_runs(tmp_path, capsys) -> None:
    twice = [dict(GOOD[0]), dict(GOOD[0])]
    a = _folder(tmp_path, "a", json.dumps(twice))
    b = _folder(tmp_path, "b", json.dumps(twice))
    assert main([str(a), str(b)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out == [
        f"note: 2 records of {a} share the identity 'E1 | RMPC'; all are compared, in order",
        f"note: 2 records of {b} share the identity 'E1 | RMPC'; all are compared, in order",
        "0 differences",
    ]
    c = _folder(tmp_path, "c", json.dumps(GOOD))
    d = _folder(tmp_path, "d", json.dumps([{**GOOD[0], "metrics": {"iae": 2.0}}]))
    assert main([str(c), str(c)]) == 0
    assert capsys.readouterr().out == "0 differences\n"
    assert main([str(c), str(d)]) == 1
    assert capsys.readouterr().out == "E1 | RMPC: metrics.iae: 1.0 -> 2.0\n1 difference\n"


def test_compare_records_refuses_items_that_are_not_records() -> None:
    with pytest.raises(ValueError, match=r"after: expected a list of records \(objects\), but found item 0"):
        compare_records(GOOD, ["E1"])
    with pytest.raises(ValueError, match="before: expected a list of records"):
        compare_records("E1", GOOD)  # type: ignore[arg-type]
