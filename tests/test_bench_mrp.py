"""The mrp family of the harness and ``rmpc bench mrp`` (issue 14, parts 3 and 4)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from figure_checks import assert_readable, capture, curves, hline_values, hlines, spans, visible_axes
from regression import check

import benchmarks.reports.mrp_figures as mrp_figures
import benchmarks.suites.mrp as mrp_suite
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
    # the figure: one error-angle curve (log axis) and one torque curve per controller, the
    # torque again on the steady window; M1 has no disturbance torque (zero), the three panels
    # of the disturbance's axes hold the estimates of MAB and TF-AB next to it
    ((items, title), fig) = built[0]
    assert len(built) == 1 and title == f"M1: {mrp_suite.EXPERIMENTS['M1']}"  # the whole title
    err, tor, zoom, *dist = visible_axes(fig)
    names = [rec["controller"] for rec, _ in items]
    assert sorted(names) == sorted(r["controller"] for r in records)
    assert_readable(fig, names)
    assert err.get_yscale() == "log" and [line.get_label() for line in curves(err)] == names
    assert tor.get_ylabel() == "max_i |u_i| (N m)" and [line.get_label() for line in curves(tor)] == names
    estimating = [name for name, (_, trace) in zip(names, items, strict=True) if "torque_estimate" in trace]
    assert {"MAB", "TFAB"} <= set(estimating) and len(dist) == 3
    for ax in dist:
        labels = [line.get_label() for line in curves(ax)]
        assert labels == [*(f"{name} estimate" for name in estimating), "true"]
        assert not np.any(curves(ax)[-1].get_ydata())
    # M1 runs without a torque limit; its steady window (the records') shaded and zoomed on
    assert hlines(tor) == []
    steady = tuple(records[0]["settings"]["steady_window"])
    assert spans(err) == [steady] and zoom.get_xlim() == steady


def test_bench_mrp_short_figures_draw_the_torque_limit(tmp_path, capsys, monkeypatch):
    """M2 and M3 with the backstepping laws only (the robust MPC's figure lines are M1's)."""
    monkeypatch.setattr(mrp_suite, "CONTROLLERS", ("BS", "MAB", "TFAB"))
    built = capture(monkeypatch, mrp_figures, "mrp_group_figure")
    out = tmp_path / "mrp"
    status = main(["bench", "mrp", "--out", str(out), "--short", "--workers", "0", "--experiments", "M2,M3",
                   "--no-progress"])
    assert status == 0, capsys.readouterr().out
    records = json.loads((out / "results.json").read_text())
    assert len(records) == 9 and len(built) == 3  # M2, M3 at 1.3 J0 and at 0.7 J0
    for (items, title), fig in built:
        names = [rec["controller"] for rec, _ in items]
        assert_readable(fig, names)
        _, tor, _, *dist = visible_axes(fig)
        limits = sorted({rec["settings"]["u_max"] for rec, _ in items if rec["saturation"] != "none"})
        assert hline_values(tor) == limits  # M3: the records' 1 N m; M2: no limit
        assert limits == ([1.0] if title.startswith("M3") else [])
        for i, ax in enumerate(dist):  # the disk's torque per axis (black) and each estimate of it
            true = [line for line in curves(ax) if line.get_label() == "true"]
            assert len(true) == 1 and true[0].get_color() == "k"
            disk = next(trace["d"] for _, trace in items)
            np.testing.assert_allclose(true[0].get_ydata(), disk[:, i])
