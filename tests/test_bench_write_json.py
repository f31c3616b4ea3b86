"""The stand-alone benchmark scripts write their records through
:func:`benchmarks.core.jsonable.write_json`: the directory is made, the value reads back as
written (NaN included), and the file is replaced whole, never left half-written."""

from __future__ import annotations

import json
import math

import pytest

from benchmarks.core import jsonable
from benchmarks.core.jsonable import write_json


def test_the_records_read_back_in_a_new_directory(tmp_path):
    path = tmp_path / "new" / "records.json"
    records = [{"case": "a", "radius": float("nan"), "its": 3}]
    write_json(path, records)
    back = json.loads(path.read_text(encoding="utf-8"))
    assert back[0]["case"] == "a" and back[0]["its"] == 3 and math.isnan(back[0]["radius"])
    assert [p.name for p in path.parent.iterdir()] == ["records.json"]  # no partial file left


def test_a_write_interrupted_halfway_leaves_the_previous_file_whole(tmp_path, monkeypatch):
    path = tmp_path / "records.json"
    write_json(path, [1, 2])
    original = jsonable.Path.write_text

    def interrupted(self, text, *args, **kwargs):
        original(self, text[: len(text) // 2], *args, **kwargs)  # half the text, then the stop
        raise KeyboardInterrupt

    monkeypatch.setattr(jsonable.Path, "write_text", interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_json(path, list(range(100)))
    monkeypatch.undo()
    assert json.loads(path.read_text(encoding="utf-8")) == [1, 2]
