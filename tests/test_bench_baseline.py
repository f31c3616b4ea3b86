"""``--baseline``: the methods bench and the timing report put an earlier run's times next to theirs."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmarks.baseline import Baseline, baseline_summary_lines, baseline_table, load_baseline
from benchmarks.cli import build_parser, main
from benchmarks.compare import compare_records
from benchmarks.suites.methods_report import methods_comparison
from benchmarks.timing.config import config_from_args
from benchmarks.timing.versus import baseline_markdown, timing_comparison
from toolkit_common.errors import InvalidArgumentError

MACHINE = {"platform": "Linux-x", "processor": "x86_64", "python": "3.11.7", "cpu_count": 2,
           "load_average": [1.0, 1.0, 1.0]}


def _rec(problem: str, method: str, p50: float, p95: float, it: int, cvxpy: float) -> dict:
    return {"problem": problem, "method": method, "status": "optimal", "solve_time_p50": p50,
            "solve_time_p95": p95, "iterations": it, "cvxpy_time_p50": cvxpy, "cvxpy_ratio": cvxpy / p50}


#: The earlier run: P1 kothare, vertex, soft; P2 kothare (a problem the new run leaves out).
OLD = [_rec("P1", "kothare", 0.004, 0.008, 20, 0.04), _rec("P1", "vertex", 0.010, 0.020, 30, 0.05),
       _rec("P1", "soft", 0.006, 0.009, 25, 0.03), _rec("P2", "kothare", 0.001, 0.002, 10, 0.01)]
#: The new run: P1 kothare and vertex faster, soft gone, a new method.
NEW = [_rec("P1", "kothare", 0.002, 0.006, 20, 0.04), _rec("P1", "vertex", 0.005, 0.010, 24, 0.05),
       _rec("P1", "li", 0.008, 0.012, 28, 0.06)]


def _methods_dir(tmp_path: Path, records: list, machine: dict | None = MACHINE, name: str = "old") -> Path:
    out = tmp_path / name
    out.mkdir()
    (out / "results.json").write_text(json.dumps(records), encoding="utf-8")
    if machine is not None:
        versions = {"numpy": "2.0", "lmi_ccore": "a"}
        info = {"command": "rmpc bench methods", "machine": machine, "versions": versions}
        (out / "run.json").write_text(json.dumps(info), encoding="utf-8")
    return out


def _row(cmp: dict, group: str, label: str) -> dict:
    return next(r for r in cmp["rows"] if r["group"] == group and r["label"] == label)


def test_methods_rows_pair_by_problem_and_method_with_new_over_old(tmp_path):
    base = load_baseline(_methods_dir(tmp_path, OLD), "methods")
    cmp = methods_comparison(NEW, base, MACHINE, {"numpy": "2.0", "lmi_ccore": "b"})
    kothare, vertex = _row(cmp, "P1", "kothare"), _row(cmp, "P1", "vertex")
    assert kothare["presence"] == vertex["presence"] == "both"
    assert kothare["old"]["solve_time_p50"] == 0.004 and kothare["new"]["solve_time_p50"] == 0.002
    assert kothare["ratio"]["solve_time_p50"] == pytest.approx(0.5)
    assert kothare["ratio"]["solve_time_p95"] == pytest.approx(0.75)
    assert vertex["ratio"]["iterations"] == pytest.approx(24 / 30)
    # the ratio to Kothare's form, per run: new 0.005 / 0.002, old 0.010 / 0.004
    assert vertex["new"]["p50_vs_kothare"] == pytest.approx(2.5)
    assert vertex["old"]["p50_vs_kothare"] == pytest.approx(2.5)
    assert vertex["ratio"]["p50_vs_kothare"] == pytest.approx(1.0)
    assert vertex["ratio"]["cvxpy_ratio"] == pytest.approx((0.05 / 0.005) / (0.05 / 0.010))
    assert cmp["p50_ratio_geomean"] == pytest.approx(0.5)
    assert cmp["version_differences"] == ["lmi_ccore: a -> b"]
    table = "\n".join(baseline_table(cmp, "P1"))
    assert "| kothare | 2 | 4 | 0.50 | 6 | 8 | 0.75 |" in table


def test_rows_absent_from_either_side_say_so(tmp_path):
    cmp = methods_comparison(NEW, load_baseline(_methods_dir(tmp_path, OLD), "methods"), MACHINE, None)
    assert _row(cmp, "P1", "li")["presence"] == "this run only"
    assert _row(cmp, "P1", "li")["old"] is None and _row(cmp, "P1", "li")["ratio"]["solve_time_p50"] is None
    assert _row(cmp, "P1", "soft")["presence"] == "the baseline only"
    assert _row(cmp, "P2", "kothare")["presence"] == "the baseline only"
    assert cmp["counts"] == {"both": 2, "this run only": 1, "the baseline only": 2}
    table = baseline_table(cmp, "P1")
    assert any(line.startswith("| li (not in the baseline) | 8 | - | - |") for line in table)
    assert any(line.startswith("| soft (not in this run) | - | 6 | - |") for line in table)
    summary = "\n".join(baseline_summary_lines(cmp, ["P1"]))
    assert "in the baseline only, not run now: P2 (1 row)" in summary


def test_a_baseline_from_another_machine_is_flagged(tmp_path):
    other = {**MACHINE, "cpu_count": 16, "load_average": [0.0, 0.0, 0.0]}
    same = {**MACHINE, "load_average": [9.0, 9.0, 9.0]}  # the load is not the machine
    def against(machine: dict | None, name: str) -> dict:
        base = load_baseline(_methods_dir(tmp_path, OLD, machine, name), "methods")
        return methods_comparison(NEW, base, MACHINE, None)

    cmp_other, cmp_same, cmp_none = against(other, "o"), against(same, "s"), against(None, "n")
    assert cmp_other["same_machine"] is False
    assert cmp_other["machine_differences"] == ["cpu_count: 16 -> 2"]
    flagged = "\n".join(baseline_summary_lines(cmp_other))
    assert "**measured on another machine**: cpu_count: 16 -> 2" in flagged
    assert cmp_same["same_machine"] is True
    assert "another machine" not in "\n".join(baseline_summary_lines(cmp_same))
    assert cmp_none["same_machine"] is None
    assert "**machine unknown**" in "\n".join(baseline_summary_lines(cmp_none))


def _timing_report(records: list, machine: dict) -> dict:
    return {"machine": machine, "versions": {"numpy": "2.0"}, "records": records}


def _trec(backend: str, vertices: int, p50: float, it: float | None, problem: str = "RMPC") -> dict:
    return {"problem": problem, "backend": backend, "formulation": "delta_shared", "vertices": vertices,
            "p50_s": p50, "p95_s": 2 * p50, "solver_p50_s": 0.9 * p50, "iterations_p50": it}


def test_timing_cases_pair_by_problem_backend_formulation_and_vertices(tmp_path):
    old_recs = [_trec("ipm", 2, 0.010, 9.0), _trec("ipm", 8, 0.040, 12.0), _trec("clarabel", 2, 0.05, 17.0)]
    new_recs = [_trec("ipm", 2, 0.004, 9.0), _trec("ipm", 8, 0.010, 11.0),
                _trec("numpy", 2, 1e-5, None, "GIPC")]
    folder = tmp_path / "old_timing"
    folder.mkdir()
    other = {**MACHINE, "processor": "arm64"}
    (folder / "timing.json").write_text(json.dumps(_timing_report(old_recs, other)), encoding="utf-8")
    base = load_baseline(folder, "timing")
    assert base.machine == other
    cmp = timing_comparison(_timing_report(new_recs, MACHINE), base)
    ipm8 = _row(cmp, "RMPC", "ipm, delta_shared, 8 vertices")
    assert ipm8["ratio"]["p50_s"] == pytest.approx(0.25)
    assert ipm8["ratio"]["iterations_p50"] == pytest.approx(11 / 12)
    assert _row(cmp, "RMPC", "ipm, delta_shared, 2 vertices")["ratio"]["p50_s"] == pytest.approx(0.4)
    assert _row(cmp, "RMPC", "clarabel, delta_shared, 2 vertices")["presence"] == "the baseline only"
    assert _row(cmp, "GIPC", "numpy, delta_shared, 2 vertices")["presence"] == "this run only"
    assert cmp["same_machine"] is False
    text = "\n".join(baseline_markdown(cmp))
    assert "### RMPC" in text and "### GIPC" in text and "processor: arm64 -> x86_64" in text
    assert "| ipm, delta_shared, 8 vertices | 10 | 40 | 0.25 |" in text


@pytest.mark.parametrize(
    ("make", "kind", "found"),
    [
        (lambda d: d / "missing", "methods", "nothing there"),
        (lambda d: d, "methods", "a folder without results.json or timing.json"),
        (lambda d: (d / "results.json").write_text("[]") and d, "methods", "no records"),
        (lambda d: (d / "results.json").write_text(json.dumps([{"experiment": "E1", "label": "RMPC"}])) and d,
         "methods", "records without problem and method"),
        (lambda d: (d / "results.json").write_text(json.dumps(OLD)) and d, "timing", "the results.json of a"),
        (lambda d: (d / "timing.json").write_text(json.dumps({"records": [_trec("ipm", 2, 0.1, 9.0)]})) and d,
         "methods", "the timing.json of `rmpc timing`"),
    ],
)
def test_a_baseline_without_records_of_that_kind_is_a_clear_error(tmp_path, make, kind, found):
    with pytest.raises(InvalidArgumentError) as err:
        load_baseline(make(tmp_path), kind)
    assert err.value.argument == "--baseline"
    command = "bench methods" if kind == "methods" else "timing"
    assert f"earlier `rmpc {command}` output folder" in err.value.expected
    assert found in err.value.found


def test_the_cli_parses_baseline_and_refuses_a_bad_one_before_measuring(tmp_path, capsys):
    out = str(tmp_path / "new")
    args = build_parser(["bench", "methods", "--out", out, "--baseline", "OLD"]).parse_args(
        ["bench", "methods", "--out", out, "--baseline", "OLD"])
    assert args.baseline == "OLD"
    targv = ["timing", "--out", out, "--quick", "--baseline", "OLD_T"]
    assert config_from_args(build_parser(targv).parse_args(targv)).baseline == Path("OLD_T")
    assert config_from_args(build_parser(targv[:-2]).parse_args(targv[:-2])).baseline is None
    assert main(["bench", "methods", "--short", "--out", out, "--baseline", str(tmp_path / "nope")]) == 2
    assert "--baseline: expected an earlier `rmpc bench methods` output folder" in capsys.readouterr().err
    assert main([*targv[:-1], str(tmp_path / "nope")]) == 2
    assert "--baseline: expected an earlier `rmpc timing` output folder" in capsys.readouterr().err
    assert not Path(out).exists()  # refused before anything was measured or written


def test_compare_leaves_the_baseline_field_out():
    a = [{"problem": "P1", "method": "kothare", "gamma": 1.0}]
    b = [{"problem": "P1", "method": "kothare", "gamma": 1.0, "baseline": {"presence": "both"}}]
    assert compare_records(a, b) == []


def test_the_methods_run_writes_the_comparison_into_its_files(tmp_path):
    from benchmarks.suites.methods import run_methods

    old = [_rec("kothare_ex2", "kothare", 1e-9, 1e-9, 1, 1e-9), _rec("kothare_ex2", "soft", 1.0, 1.0, 1, 1.0)]
    folder = _methods_dir(tmp_path, old, {**MACHINE, "platform": "elsewhere"})
    out = tmp_path / "new"
    run_methods(out, short=True, problems=["kothare_ex2"], methods=["kothare"], progress=False,
                baseline=folder)
    rec = json.loads((out / "results.json").read_text())[0]
    assert rec["baseline"]["presence"] == "both" and rec["baseline"]["old"]["solve_time_p50"] == 1e-9
    assert rec["baseline"]["ratio"]["solve_time_p50"] == pytest.approx(rec["solve_time_p50"] / 1e-9)
    info = json.loads((out / "run.json").read_text())["baseline"]
    assert info["baseline"] == str(folder) and info["same_machine"] is False
    assert info["counts"] == {"both": 1, "this run only": 0, "the baseline only": 1}
    md = (out / "results.md").read_text()
    assert "## Times against the baseline" in md
    assert "**measured on another machine**: platform: elsewhere" in md
    assert "| soft (not in this run) | - | 1e+03 | - |" in md
    assert isinstance(load_baseline(out, "methods"), Baseline)  # a compared run is a baseline in turn
