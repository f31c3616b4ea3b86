"""The wheel family of the harness and ``rmpc bench faults`` (issue 13, parts 5 and 6)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from figure_checks import assert_readable, capture, curves, hatched_spans, hline_values, spans, visible_axes

import benchmarks.reports.fault_figures as fault_figures
import benchmarks.suites.faults as faults_suite
from benchmarks.cli import main
from benchmarks.core.runner import run_scenario
from benchmarks.core.scenario import Scenario
from benchmarks.core.sweep import expand, load_sweep
from benchmarks.families.wheel import defaults
from benchmarks.families.wheel.family import case_faults
from benchmarks.suites.faults import fault_cases
from models import WheelArray
from toolkit_common.errors import ConfigError


def test_wheel_scenarios_take_the_paper_scenario_and_controller_defaults():
    sc = Scenario.from_dict({"family": "wheel", "controller": "ABFTC", "scenario": "S3"})
    assert sc.saturation == "limiter"  # ABFTC has no constraint
    assert Scenario.from_dict({"family": "wheel", "controller": "RMPC"}).saturation == "constraint"
    kinds = [(f.wheel, f.kind) for f in case_faults(sc)]
    assert kinds == [(4, "outage"), (1, "sinusoidal"), (2, "stuck")]
    assert sc.to_dict()["family"] == "wheel"
    assert len(fault_cases(experiments=["W1", "W2", "W3", "W4"])) == 20 and len(fault_cases()) == 52


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"fault_kind": "stuck", "fault_wheel": 5}, "fault_wheel"),
        ({"fault_kind": "stuck", "fault_onset": 61.0}, "fault_onset"),
        ({"fault_kind": "effectiveness", "fault_value": 1.5}, "fault_value"),
        ({"fault_kind": "melted"}, "fault_kind"),
        ({"u_max": -0.1}, "u_max"),
        ({"controller": "ABFTC", "saturation": "constraint"}, "saturation"),
        ({"spread": 0.3}, "spread"),  # a rigid-family field
    ],
)
def test_bad_wheel_fields_name_the_field(data, field):
    with pytest.raises(ConfigError, match=field):
        Scenario.from_dict({"family": "wheel", "controller": "RMPC", **data})


def test_unknown_family_is_named():
    with pytest.raises(ConfigError, match="family"):
        Scenario.from_dict({"family": "spacecraft"})


def test_a_single_fault_case_runs_and_logs_the_clipped_wheels():
    sc = Scenario.from_dict(
        {
            "family": "wheel", "controller": "ABFTC", "scenario": "S1", "duration": 4.0,
            "fault_kind": "stuck", "fault_wheel": 3, "fault_onset": 1.0, "fault_value": 0.05,
        }
    )
    rec = run_scenario(sc)
    faults = rec["metrics"]["faults"]
    assert rec["plant"] == "wheel" and rec["saturation"] == "limiter"  # API.md: plant names the family
    assert faults["max_abs_u"] <= 0.123 + 1e-12 < faults["max_abs_u_cmd"]  # the plant clips
    assert faults["sat_fraction"]["any"] > 0.0
    assert [e["wheel"] for e in faults["recovery_time"]] == [3]
    assert math.isfinite(rec["metrics"]["sum_abs_err"]["roll"])


def test_shipped_faults_sweep_expands_over_kind_wheel_onset_and_controller():
    spec = load_sweep("faults")
    cases = expand(spec)
    assert {c.family for c in cases} == {"wheel"}
    assert {c.controller for c in cases} == {"ABFTC", "RMPC", "CRMPC", "GIPC"}
    assert {c.fault_kind for c in cases} >= {"stuck", "outage", "sinusoidal"}
    assert {c.saturation for c in cases if c.controller == "ABFTC"} == {"limiter"}
    assert len({c.case_id for c in cases}) == len(cases)


def test_bench_faults_short_writes_every_file(tmp_path, capsys, monkeypatch):
    built = capture(monkeypatch, fault_figures, "fault_case_group_figure")
    out = tmp_path / "faults"
    status = main(["bench", "faults", "--out", str(out), "--short", "--workers", "0",
                   "--experiments", "W1", "--no-progress"])
    stdout = capsys.readouterr().out
    assert status == 0, stdout
    assert "4 cases done, 0 failed" in stdout
    for name in ("results.json", "results.md", "results.csv", "run.json", "figures/W1.png"):
        assert (out / name).stat().st_size > 0, name
    records = json.loads((out / "results.json").read_text())
    assert {r["controller"] for r in records} == {"ABFTC", "RMPC", "CRMPC", "GIPC"}
    for rec in records:
        for key in ("sum_abs_err", "final_abs_err", "max_abs_u", "solve_time_p50"):
            assert key in rec["metrics"]
        assert rec["metrics"]["faults"]["max_abs_u"] <= 0.123 + 1e-12
    md = (out / "results.md").read_text()
    for section in ("## W1", "## Paper W's reported results", "## Inconsistencies in paper W", "## Settings"):
        assert section in md
    assert "13x" in md and "smoke run" in md
    # the figure: per controller attitude (3 curves), applied and commanded torque per wheel with
    # the torque limits, the wheel momenta with the momentum limits, the fault window shaded
    ((items, windows, title, torque_max, momentum_max), fig) = built[0]
    assert len(built) == 1 and title.startswith("W1: ")
    wheels = WheelArray.paper_w()  # S1's plant keeps paper W's wheels: the case's limits are theirs
    for rec, _ in items:
        assert rec["settings"]["wheel_torque_max"] == wheels.torque_max.tolist()
        assert rec["settings"]["wheel_momentum_max"] == wheels.momentum_max.tolist()
    assert torque_max == np.max(wheels.torque_max) and momentum_max == np.max(wheels.momentum_max)
    assert [rec["controller"] for rec, _ in items] == [r["controller"] for r in records]
    grid = np.array(visible_axes(fig)).reshape(3, len(items))
    for col in range(len(items)):
        att, tor, mom = grid[:, col]
        assert len(curves(att)) == 3 and len(curves(tor)) == 2 * 4 and len(curves(mom)) == 4
        assert hline_values(tor) == [-torque_max, torque_max]
        assert hline_values(mom) == [-momentum_max, momentum_max]
        t_end = float(items[col][1]["t"][-1])
        assert spans(att) == [(t0, min(t1, t_end)) for t0, t1 in windows] and len(windows) == 1
    assert grid[1, 0].get_ylabel().startswith("wheel torque (N m)")
    assert grid[2, 0].get_ylabel() == "wheel momentum (N m s)"
    assert_readable(fig, [])
    for col in range(len(items)):  # the recovery band; one wheel lost: no rank-deficient window
        assert hline_values(grid[0, col]) == [-defaults.RECOVERY_DEG, defaults.RECOVERY_DEG]
        assert items[col][0]["metrics"]["faults"]["rank_deficient_windows"] == []
        assert hatched_spans(grid[0, col]) == []


def test_bench_faults_short_w3_hatches_the_rank_deficient_windows(tmp_path, capsys, monkeypatch):
    """W3 (two wheels lost at once) with ABFTC and GIPC, the cheap controllers."""
    monkeypatch.setattr(faults_suite, "CONTROLLERS", ("ABFTC", "GIPC"))
    built = capture(monkeypatch, fault_figures, "fault_case_group_figure")
    out = tmp_path / "faults"
    status = main(["bench", "faults", "--out", str(out), "--short", "--workers", "0", "--experiments", "W3",
                   "--no-progress"])
    assert status == 0, capsys.readouterr().out
    ((items, _, title, _, _), fig) = built[0]
    assert len(built) == 1 and title.startswith("W3: ")
    assert_readable(fig, [])
    grid = np.array(visible_axes(fig)).reshape(3, len(items))
    for col, (rec, trace) in enumerate(items):
        rank = rec["metrics"]["faults"]["rank_deficient_windows"]
        t_end = float(trace["t"][-1])
        expected = [(w[0], min(w[1], t_end)) for w in rank if w[0] < t_end]
        assert len(expected) == 2  # wheel 4 out with wheel 1, then with wheel 2 (the short run's times)
        for ax in grid[:, col]:
            assert hatched_spans(ax) == expected
        assert hline_values(grid[0, col]) == [-defaults.RECOVERY_DEG, defaults.RECOVERY_DEG]


def test_a_run_shorter_than_the_scenario_faults_is_refused():
    with pytest.raises(ConfigError, match="duration"):
        Scenario.from_dict({"family": "wheel", "scenario": "S2", "duration": 10.0})


def test_fault_figures_draw_the_limits_of_the_case_not_the_defaults():
    """The limits a figure draws are those the records' plants applied (here other than paper W's),
    the largest over the group; a plant without limits adds none."""
    from benchmarks.suites.faults import _case_limits

    def rec(torque, momentum):
        return {"settings": {"wheel_torque_max": torque, "wheel_momentum_max": momentum}}

    records = [rec([0.05, 0.05, 0.06, 0.05], [0.3] * 4), rec(None, None), rec([0.04] * 4, [0.5] * 4)]
    assert _case_limits(records) == (0.06, 0.5)
    assert all(np.isnan(_case_limits([rec(None, None)])))
