"""benchmarks.compare: the field-by-field comparison of two runs of a suite."""

from __future__ import annotations

import json

import pytest

from benchmarks.compare import compare_records, compare_runs, is_run_dependent, main


def _record(iae: float, status: dict, solve_time: float) -> dict:
    return {"experiment": "E1", "label": "RMPC linear", "settings": {"duration": 30.0, "dt": 0.01},
            "metrics": {"iae": {"roll": iae}, "status_counts": status, "solve_time_p50": solve_time,
                        "n_steps": 3000}}


def test_same_records_apart_from_times_compare_equal() -> None:
    before = [_record(0.25, {"optimal": 10}, 0.004)]
    after = [_record(0.25, {"optimal": 10}, 0.009)]
    assert compare_records(before, after) == []


def test_every_changed_added_and_removed_field_is_listed() -> None:
    before = [_record(0.25, {"optimal": 10}, 0.004), {"experiment": "E2", "label": "GIPC"}]
    after = [_record(0.25 + 1e-12, {"ok": 10}, 0.004), {"experiment": "E3", "label": "GIPC"}]
    lines = compare_records(before, after)
    assert "E1 | RMPC linear: metrics.iae.roll: 0.25 -> 0.250000000001" in lines
    assert "E1 | RMPC linear: metrics.status_counts.ok: added 10" in lines
    assert "E1 | RMPC linear: metrics.status_counts.optimal: removed" in lines
    assert "E2 | GIPC: record removed" in lines and "E3 | GIPC: record added" in lines
    assert len(lines) == 5
    # a relative tolerance lets the 4e-12 change through, nothing else
    assert len(compare_records(before, after, rtol=1e-9)) == 4


def test_settings_named_like_times_are_compared() -> None:
    assert not is_run_dependent("duration") and not is_run_dependent("disturbance_start")
    assert is_run_dependent("solve_time_p50") and is_run_dependent("p95_s") and is_run_dependent("machine")
    before, after = [_record(0.25, {}, 0.0)], [_record(0.25, {}, 0.0)]
    after[0]["settings"]["duration"] = 20.0
    assert compare_records(before, after) == ["E1 | RMPC linear: settings.duration: 30.0 -> 20.0"]


def test_the_command_reads_two_folders_and_exits_by_the_answer(tmp_path, capsys) -> None:
    for name, iae in (("a", 0.25), ("b", 0.25), ("c", 0.5)):
        (tmp_path / name).mkdir()
        (tmp_path / name / "results.json").write_text(json.dumps([_record(iae, {"ok": 1}, 0.0)]))
    assert main([str(tmp_path / "a"), str(tmp_path / "b")]) == 0
    assert main([str(tmp_path / "a"), str(tmp_path / "c")]) == 1
    assert "metrics.iae.roll: 0.25 -> 0.5" in capsys.readouterr().out
    (tmp_path / "d").mkdir()
    assert main([str(tmp_path / "a"), str(tmp_path / "d")]) == 2
    assert "results.json or timing.json" in capsys.readouterr().err


def test_timing_records_pair_by_problem_and_a_mixed_pair_is_an_error(tmp_path) -> None:
    rec = {"problem": "RMPC", "formulation": "delta_shared", "backend": "ipm", "vertices": 2,
           "p50_s": 0.004, "status_counts": {"optimal": 40}, "max_rel_err": 1e-8}
    for name, err in (("t1", 1e-8), ("t2", 2e-8)):
        (tmp_path / name).mkdir()
        timing = {"machine": {}, "records": [dict(rec, max_rel_err=err)]}
        (tmp_path / name / "timing.json").write_text(json.dumps(timing))
    assert compare_runs(tmp_path / "t1", tmp_path / "t2") == [
        "RMPC | delta_shared | ipm | 2 | #0: max_rel_err: 1e-08 -> 2e-08"]
    (tmp_path / "s").mkdir()
    (tmp_path / "s" / "results.json").write_text('[{"experiment": "E1", "label": "RMPC"}]')
    with pytest.raises(ValueError, match="after"):
        compare_runs(tmp_path / "t1", tmp_path / "s")


def test_methods_records_pair_by_problem_and_method_and_repeated_keys_keep_every_record() -> None:
    """The methods suite's records have no experiment or label: each (problem, method) is its own
    record, and a change in any of them is found (before, all collapsed onto one key)."""
    before = [{"problem": p, "method": m, "gamma": 1.0, "cvxpy_ratio": 3.0}
              for p in ("ex1", "ex2") for m in ("kothare", "vertex")]
    after = [dict(r) for r in before]
    after[0]["gamma"] = 2.0
    after[3]["cvxpy_ratio"] = 5.0  # a ratio of two solve times: a measurement of the run
    assert compare_records(before, after) == ["ex1 | kothare: gamma: 1.0 -> 2.0"]
    twice = [{"experiment": "E1", "label": "RMPC", "x": 1}, {"experiment": "E1", "label": "RMPC", "x": 2}]
    changed = [{"experiment": "E1", "label": "RMPC", "x": 1}, {"experiment": "E1", "label": "RMPC", "x": 3}]
    assert compare_records(twice, changed) == ["E1 | RMPC #2: x: 2 -> 3"]
