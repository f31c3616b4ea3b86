"""``rmpc timing --problems C``: the exported C controllers against the anchors.

A quick run produces the rows (the export, the Python ipm and Clarabel at the same states, the
off-line lookups, object code and static memory, the targets); no timing is asserted (speed is
measured in benchmarks, not in tests), only what the rows must hold whatever the speed: the
export's answers agree with the Python ipm's at the same states, the statuses, the sizes.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

import benchmarks.timing.c_exports as c_exports
from benchmarks.cli import main
from benchmarks.compare import compare_runs, is_run_dependent
from benchmarks.timing.c_exports import TARGETS, judge_targets
from benchmarks.timing.cpg_attempt import error_lines

needs_cc = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("ctiming")
    argv = ["timing", "--out", str(out), "--quick", "--problems", "C", "--vertices", "2", "--steps", "3",
            "--no-progress"]
    assert main(argv) == 0
    return out, json.loads((out / "timing.json").read_text(encoding="utf-8"))


@needs_cc
def test_a_quick_run_produces_the_rows(quick_run):
    out, report = quick_run
    records = report["records"]
    assert {(r["backend"], r["formulation"]) for r in records} == {
        ("c-export", "delta_shared"), ("ipm", "delta_shared"), ("ipm-numba", "delta_shared"),
        ("clarabel", "delta_shared"),
        ("c-export", "lookup+interpolation"), ("c-export", "lookup")}
    for rec in records:
        assert rec["problem"] == "C" and rec["vertices"] == 2
        assert 0 < rec["p50_s"] <= rec["p95_s"] <= rec["max_s"]
        assert sum(rec["status_counts"].values()) == rec["steps"] > 0
    online = {r["backend"]: r for r in records if r["formulation"] == "delta_shared"}
    for rec in online.values():
        assert rec["steps"] == 3 and rec["status_counts"] == {"optimal": 3}
        assert 0 < rec["cpu_p50_s"] <= rec["cpu_p95_s"] <= rec["cpu_max_s"]
    c = online["c-export"]
    # the export answers as the Python ipm at the same states (the export tests' tolerances)
    assert c["compared_steps"] == 3 and c["max_rel_err"] < 1e-6 and c["max_abs_err_u"] < 1e-6
    assert c["text_bytes"] > 0 and c["bss_bytes"] >= c["solver_workspace_bytes"] > 0
    assert c["static_memory_bytes"] == c["export_static_bytes"] + c["solver_workspace_bytes"]
    assert c["object_bytes"] == c["text_bytes"] + c["data_bytes"]
    for rec in records:
        if rec["formulation"].startswith("lookup"):
            assert rec["same_statuses"] and rec["max_abs_err_u"] < 1e-12 and rec["n_ellipsoids"] == 5
            assert rec["steps"] == rec["lookup_states"] and rec["python_p50_s"] > 0
    summary = report["c"]
    assert summary["compiler"] and summary["note"] == ""
    assert [a["outcome"] for a in summary["cvxpygen"]] == ["not tried"]
    rows = summary["targets"]
    assert [(t["target"], t["vertices"]) for t in rows] == [(t[0], t[1]) for t in TARGETS]
    by_what = {t[2] + str(t[1]): row for t, row in zip(TARGETS, rows, strict=True)}
    assert by_what["c_cpu_p50_s2"]["measured"] == c["cpu_p50_s"]
    assert by_what["c_cpu_p50_s8"]["met"] is None  # 8 vertices were not in the run
    assert by_what["lookup_p50_s2"]["met"] is None  # 5 ellipsoids, not the target's 15
    assert by_what["cvxpygen_over_c2"]["met"] is None
    assert by_what["object_bytes2"]["met"] == (c["object_bytes"] < 200e3)
    text = (out / "timing.md").read_text(encoding="utf-8")
    assert "## C: the exported controllers against the anchors" in text and "### Targets" in text
    assert compare_runs(out, out) == []
    # every field that measures time is one benchmarks.compare leaves out (two runs compare equal)
    timed = {k for r in records for k in r if k.endswith("_s") or "over" in k}
    assert timed >= {"cpu_p50_s", "python_p50_s", "python_over_c_p50"}
    assert all(is_run_dependent(k) for k in timed)


def _records(c_cpu: float, ipm_cpu: float, ellipsoids: int = 15) -> list[dict]:
    base = {"problem": "C", "formulation": "delta_shared", "vertices": 2}
    return [
        {**base, "backend": "c-export", "cpu_p50_s": c_cpu, "p50_s": c_cpu, "object_bytes": 150_000,
         "static_memory_bytes": 10, "export_static_bytes": 4, "solver_workspace_bytes": 6},
        {**base, "backend": "ipm-numba", "cpu_p50_s": ipm_cpu, "p50_s": ipm_cpu},
        {**base, "backend": "c-export", "formulation": "lookup+interpolation", "p50_s": 1.5e-6,
         "n_ellipsoids": ellipsoids},
    ]


def test_the_targets_are_judged_by_their_limits():
    attempt = {2: {"outcome": "failed", "errors": ["error: no crates"]}}
    fast = {(r["target"], r["vertices"]): r["met"] for r in judge_targets(_records(0.5e-3, 2.5e-3), attempt)}
    slow = {(r["target"], r["vertices"]): r["met"] for r in judge_targets(_records(1.5e-3, 2.5e-3), attempt)}
    assert fast[("on-line export p50 warm per solve", 2)] is True
    assert slow[("on-line export p50 warm per solve", 2)] is False
    assert fast[("on-line export faster than the Python ipm (numba kernels, p50)", 2)] is True  # 5x
    assert slow[("on-line export faster than the Python ipm (numba kernels, p50)", 2)] is False  # 1.7x
    assert fast[("off-line lookup of 15 ellipsoids per step (p50)", 2)] is True
    assert fast[("object code of the on-line export (text + data)", 2)] is True
    assert fast[("on-line export p50 warm per solve", 8)] is None
    rows = judge_targets(_records(0.5e-3, 2.5e-3, ellipsoids=14), attempt)
    lookup = next(r for r in rows if r["target"].startswith("off-line"))
    assert lookup["met"] is None and "14 ellipsoids" in lookup["note"]
    cpg = next(r for r in rows if "CVXPYgen" in r["target"])
    assert cpg["met"] is None and "error: no crates" in cpg["note"]


def test_without_a_compiler_the_section_says_so_and_the_run_goes_on(tmp_path, monkeypatch):
    monkeypatch.setattr(c_exports.shutil, "which", lambda name: None)
    argv = ["timing", "--out", str(tmp_path), "--quick", "--problems", "C", "OfflineRMPC", "--vertices", "2",
            "--steps", "2", "--no-progress"]
    assert main(argv) == 0
    report = json.loads((tmp_path / "timing.json").read_text(encoding="utf-8"))
    assert report["c"]["note"] == "no C compiler" and report["c"]["targets"] == []
    assert {r["problem"] for r in report["records"]} == {"OfflineRMPC"}
    assert "no C compiler" in (tmp_path / "timing.md").read_text(encoding="utf-8")


@pytest.mark.filterwarnings("ignore:Solution may be inaccurate")
def test_the_section_follows_the_rmpc_sections_closed_loop():
    from benchmarks.timing.common import polytope
    from benchmarks.timing.config import TimingConfig
    from benchmarks.timing.rmpc import section_states, time_rmpc

    poly = polytope(2)
    cfg = TimingConfig(out=None, steps=3, rebuild_steps=1, scs_steps=0, quick=True)
    alone = section_states(poly, 3)
    interleaved = time_rmpc(poly, cfg)["states"]
    assert len(alone) == len(interleaved) == 3
    np.testing.assert_array_equal(np.array(alone), np.array(interleaved))
    assert not np.allclose(alone[1], alone[2])  # the loop moves


def test_error_lines_keep_the_errors_in_order():
    log = ("Updating index\nwarning: spurious network error (3 tries remaining): [6] Could not resolve host\n"
           "  error: failed to get `amd`\n  [6] Could not resolve host: index\n"
           "  error: failed to get `amd`\n")
    assert error_lines(log + "ImportError: cannot import name 'cpg_module'") == [
        "error: failed to get `amd`", "[6] Could not resolve host: index",
        "ImportError: cannot import name 'cpg_module'"]


def test_the_exports_codes_read_as_the_python_controllers_words():
    from rmpc.export.c_writer import STATUS_CODES

    words = {s.name: c_exports._c_word(s.value) for s in STATUS_CODES}
    assert words["RMPC_OK"] == "optimal" and words["RMPC_STATUS_INFEASIBLE"] == "infeasible"
    assert words["RMPC_STATUS_HELD"] == "reused" and words["RMPC_STATUS_BAD_STATE"] == "bad_state"
    assert len(set(words.values())) == len(words)


@needs_cc
@pytest.mark.filterwarnings("ignore:Solution may be inaccurate")
def test_with_the_rmpc_section_the_section_times_at_its_states(tmp_path, monkeypatch):
    from benchmarks.timing.common import polytope
    from benchmarks.timing.rmpc import section_states

    seen = []
    original = c_exports.time_c

    def spy(poly, cfg, states=None, bar=None):
        seen.append(states)
        return original(poly, cfg, states, bar)

    monkeypatch.setattr(c_exports, "time_c", spy)
    argv = ["timing", "--out", str(tmp_path), "--quick", "--problems", "RMPC", "C", "--vertices", "2",
            "--steps", "2", "--no-progress"]
    assert main(argv) == 0
    (states,) = seen
    np.testing.assert_array_equal(np.array(states), np.array(section_states(polytope(2), 2)))
    report = json.loads((tmp_path / "timing.json").read_text(encoding="utf-8"))
    assert {r["problem"] for r in report["records"]} == {"RMPC", "C"}
