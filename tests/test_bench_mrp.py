"""The mrp family of the harness and ``rmpc bench mrp`` (issue 14, parts 3 and 4)."""

from __future__ import annotations

import json

import pytest
from figure_checks import capture, curves, visible_axes
from regression import check

import benchmarks.reports.mrp_figures as mrp_figures
from benchmarks.cli import main
from benchmarks.core.runner import run_scenario
from benchmarks.core.scenario import Scenario
from benchmarks.core.sweep import expand, load_sweep
from benchmarks.suites.mrp import mrp_cases
from toolkit_common.errors import ConfigError


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"scenario": "M4"}, "scenario"),
        ({"plant_step": 0.1, "dt": 0.05}, "plant_step"),
        ({"controller": "BS", "saturation": "constraint"}, "saturation"),
        ({"spread": 1.0}, "spread"),
        ({"u_max": 0.0}, "u_max"),
        ({"fault_kind": "stuck"}, "fault_kind"),  # a wheel-family field
    ],
)
def test_bad_mrp_fields_name_the_field(data, field):
    with pytest.raises(ConfigError, match=field):
        Scenario.from_dict({"family": "mrp", "controller": "RMPC", **data})


def test_suite_cases_use_one_period_and_the_m3_limits():
    cases = mrp_cases()
    assert len(cases) == 20
    assert {c.scenario.dt for c in cases} == {0.05}
    m3 = [c.scenario for c in cases if c.experiment == "M3"]
    assert {(s.controller, s.saturation) for s in m3} >= {("RMPC", "constraint"), ("MAB", "limiter")}
    assert {s.inertia_scale for s in m3} == {1.3, 0.7}


def test_rmpc_on_the_mrp_plant_covers_the_initial_error_and_keeps_its_bound():
    sc = Scenario.from_dict(
        {"family": "mrp", "controller": "RMPC", "scenario": "M3", "saturation": "constraint",
         "duration": 3.0, "dt": 0.05}
    )
    rec = run_scenario(sc)
    m = rec["metrics"]
    assert rec["plant"] == "mrp"
    assert rec["settings"]["n_vertices"] == 18  # 2 inertia corners x 9 kinematics matrices
    assert m["max_abs_u"] <= 1.0 + 1e-6
    assert m["status_counts"].get("optimal", 0) == 60
    assert m["err_angle_final_deg"] < m["err_angle_initial_deg"]


def test_mab_reports_its_disturbance_estimate_error():
    rec = run_scenario(Scenario.from_dict({"family": "mrp", "controller": "MAB", "scenario": "M2",
                                           "duration": 4.0, "dt": 0.05}))
    assert rec["metrics"]["td_est_err_max"] is not None
    check("bench_mrp", "mab_m2_torque_estimate_error_max", rec["metrics"]["td_est_err_max"])


def test_shipped_gain_sweep_expands():
    cases = expand(load_sweep("mrp_gains"))
    assert len(cases) == 19
    bandwidths = {c.settings["observer_bandwidth"] for c in cases if c.controller == "MAB"}
    assert bandwidths == {5.0, 10.0, 20.0, 40.0}


def test_shipped_reference_sweep_expands_to_the_docs_table():
    """mrp_reference: BS, MAB, TF-AB x M1-M3 x {none, limiter} at the 0.01 s step (the docs' table)."""
    cases = expand(load_sweep("mrp_reference"))
    assert len(cases) == 18
    assert {(c.controller, c.scenario, c.saturation) for c in cases} >= {("MAB", "M3", "limiter")}
    assert {(c.dt, c.plant_step) for c in cases} == {(0.01, 0.01)}


def test_bench_mrp_short_writes_every_file(tmp_path, capsys, monkeypatch):
    built = capture(monkeypatch, mrp_figures, "mrp_group_figure")
    out = tmp_path / "mrp"
    status = main(["bench", "mrp", "--out", str(out), "--short", "--workers", "0", "--experiments", "M1",
                   "--no-progress"])
    stdout = capsys.readouterr().out
    assert status == 0, stdout
    assert "5 cases done, 0 failed" in stdout
    records = json.loads((out / "results.json").read_text())
    assert {r["controller"] for r in records} == {"BS", "MAB", "TFAB", "RMPC", "CRMPC"}
    for rec in records:
        for key in ("final_abs_err", "max_abs_u", "solve_time_p50", "err_angle_ss_max_deg"):
            assert key in rec["metrics"], key
    md = (out / "results.md").read_text()
    for section in ("## M1", "## Paper M's reported results", "## Settings", "(a) paper M's disk"):
        assert section in md
    assert (out / "figures" / "M1.png").stat().st_size > 0
    # the figure: one error-angle curve (log axis) and one torque curve per controller; M1 has
    # no disturbance torque, so the third panel holds only the estimates of MAB and TF-AB
    ((items, title), fig) = built[0]
    assert len(built) == 1 and title.startswith("M1: ")
    err, tor, dist = visible_axes(fig)
    names = [rec["controller"] for rec, _ in items]
    assert sorted(names) == sorted(r["controller"] for r in records)
    assert err.get_yscale() == "log" and [line.get_label() for line in curves(err)] == names
    assert tor.get_ylabel() == "max_i |u_i| (N m)" and [line.get_label() for line in curves(tor)] == names
    estimating = [name for name, (_, trace) in zip(names, items, strict=True) if "torque_estimate" in trace]
    assert {"MAB", "TFAB"} <= set(estimating)
    assert [line.get_label() for line in curves(dist)][: len(estimating)] == [
        f"{name} estimate (x)" for name in estimating]
