"""Metrics on hand-made trajectories, scenario validation and ids, and the table formats."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from benchmarks.core.metrics import (
    compute_metrics,
    iae,
    ise,
    last_time_above,
    overshoot,
    recovery_time,
    settle_index,
    settling_time,
)
from benchmarks.core.scenario import Scenario
from benchmarks.reports.tables import metric_table, to_csv, to_json, to_latex, to_markdown
from rmpc import StepInfo, Trajectory
from toolkit_common.errors import ConfigError

# -- the metric functions on signals whose values are known exactly ---------------------------


def test_iae_and_ise_are_exact_on_piecewise_linear_signals():
    t = [0.0, 1.0, 2.0, 4.0]
    e = [2.0, 0.0, -1.0, -1.0]
    # trapezoids of |e|: (2 + 0)/2 * 1 + (0 + 1)/2 * 1 + (1 + 1)/2 * 2 = 1 + 0.5 + 2
    assert iae(t, e) == pytest.approx(3.5, abs=1e-15)
    # trapezoids of e^2: (4 + 0)/2 + (0 + 1)/2 + (1 + 1)/2 * 2 = 2 + 0.5 + 2
    assert ise(t, e) == pytest.approx(4.5, abs=1e-15)


def test_settling_time_is_the_first_sample_after_the_last_exit_from_the_2_percent_band():
    t = np.arange(6) * 0.5
    e = [1.0, 0.5, 0.01, 0.03, 0.019, 0.0]  # leaves the band (0.02) at t = 1.5 for the last time
    assert settling_time(t, e) == 2.0
    assert settling_time(t, [1.0, 0.01, 0.0, 0.0, 0.0, 0.0]) == 0.5
    assert settling_time(t, [1.0, 0.5, 0.4, 0.3, 0.2, 0.1]) is None  # not settled within the run
    assert settling_time(t, np.zeros(6)) == 0.0
    # e(0) = 0 (an axis hit by a disturbance later): the band is 2 % of the largest error
    assert settling_time(t, [0.0, 1.0, 0.5, 0.01, 0.0, 0.0]) == 1.5
    # the band is closed: 0.05 lies inside a 5 % band
    assert settling_time(t, [1.0, 0.5, 0.1, 0.05, 0.04, 0.03], band=0.05) == 1.5


def test_the_two_readings_of_settling_on_one_signal():
    """Relative band, first sample inside vs absolute threshold, last sample outside."""
    t = np.arange(6) * 0.5
    e = [1.0, -0.5, 0.01, 0.03, 0.019, 0.0]
    assert settle_index(e, 0.02) == 4  # |e| <= 0.02 from index 4 (0.019) on; the sign does not count
    assert settling_time(t, e) == 2.0  # 2 % of |e(0)| = 1: the sample after the last exit
    assert last_time_above(t, e, 0.02) == 1.5  # the same limit, absolute: the last sample outside
    double = 2.0 * np.asarray(e)
    assert last_time_above(t, double, 0.02) == 2.0  # absolute: 2 x 0.019 is outside now
    assert settling_time(t, double) == 2.0  # relative: the band doubles with e(0)
    assert last_time_above(t, np.zeros(6), 0.02) == 0.0 and settle_index(np.zeros(6), 0.02) == 0
    assert last_time_above(t, [1.0, 0.0, 0.0, 0.0, 0.0, 0.5], 0.02) == math.inf
    assert settle_index(np.column_stack([e, np.zeros(6)]), 0.02) == 4  # the largest column counts


def test_recovery_time_counts_from_the_event():
    rec = recovery_time([2.0, 2.5, 3.0, 3.5], [0.2, 0.1, 0.0, 0.0], t_on=1.9, band=0.05)
    assert rec == pytest.approx(1.1)
    assert recovery_time([2.0, 2.5], [0.01, 0.0], t_on=2.0, band=0.05) == 0.0
    assert recovery_time([2.0, 2.5], [0.0, 0.1], t_on=2.0, band=0.05) is None


def test_overshoot_is_the_excursion_past_zero_in_percent_of_the_initial_error():
    assert overshoot([2.0, 0.5, -0.2, -0.3, 0.0]) == pytest.approx(15.0)
    assert overshoot([-0.5, 0.0, 0.1, 0.0]) == pytest.approx(20.0)
    assert overshoot([1.0, 0.5, 0.1]) == 0.0
    assert overshoot([0.0, 1.0]) is None


def _trajectory() -> Trajectory:
    """Four steps of dt = 0.1 s with known errors, torques, statuses and gammas."""
    t = np.arange(5) * 0.1
    x = np.zeros((5, 6))
    x[:, 0] = [0.4, 0.2, 0.0, -0.1, 0.0]
    x[:, 1] = [-0.2, -0.1, 0.0, 0.0, 0.0]
    x[:, 2] = [0.0, 0.1, 0.1, 0.05, 0.02]
    u_cmd = np.array([[3.0, 0, 0], [0.5, -1.0, 0], [0.1, 0.2, 0.3], [0, 0, 0]])
    u_app = np.clip(u_cmd, -1.0, 1.0)
    u_app[2, 2] = 1.25  # a violation of 0.25 N m
    status = ["optimal", "reused", "infeasible", "inaccurate"]
    info = [StepInfo("optimal", 0.04, gamma=10.0), StepInfo("reused"),
            StepInfo("infeasible", 0.08, fallback=True), StepInfo("inaccurate", 0.02, gamma=2.0)]
    return Trajectory(
        t=t, x=x, u_cmd=u_cmd, u_applied=u_app, d=np.zeros((4, 3)), status=status,
        solve_time=np.array([0.04, 0.0, 0.08, 0.02]), step_time=np.array([0.05, 0.001, 0.09, 0.03]),
        gamma=np.array([10.0, np.nan, np.nan, 2.0]), info=info, plant="linear", dt=0.1,
        attitude_euler=x[:, :3],  # a satellite's run: its metrics are per attitude axis
    )


def test_compute_metrics_on_a_hand_made_trajectory():
    m = compute_metrics(_trajectory(), u_max=1.0)
    assert m["sum_abs_err"] == pytest.approx({"roll": 0.7, "pitch": 0.3, "yaw": 0.27})
    assert m["final_abs_err"] == pytest.approx({"roll": 0.0, "pitch": 0.0, "yaw": 0.02})
    # roll |e| = 0.4, 0.2, 0, 0.1, 0 -> trapezoids 0.03 + 0.01 + 0.005 + 0.005
    assert m["iae"]["roll"] == pytest.approx(0.05, abs=1e-15)
    assert m["ise"]["roll"] == pytest.approx(0.1 * (0.16 + 0.04) / 2 + 0.1 * 0.04 / 2 + 0.1 * 0.01, abs=1e-15)
    assert m["overshoot"]["roll"] == pytest.approx(25.0)
    assert m["overshoot"]["yaw"] is None
    assert m["settling_time"]["pitch"] == pytest.approx(0.2)
    assert m["settling_time"]["yaw"] is None  # 0.02 > 2 % of 0.1 at the end
    assert m["max_abs_u"] == 1.25
    assert m["max_abs_u_cmd"] == 3.0
    assert m["saturated_fraction"] == 0.5  # steps 0 and 1 reach the limit
    assert m["constraint_violation"] == pytest.approx(0.25)
    assert m["violation_steps"] == 1
    assert m["n_steps"] == 4 and m["n_solves"] == 3
    assert m["failure_count"] == 1 and m["fallback_count"] == 1
    assert m["status_counts"] == {"optimal": 1, "reused": 1, "infeasible": 1, "inaccurate": 1}
    assert m["solve_time_p50"] == pytest.approx(0.03)
    assert m["solve_time_max"] == pytest.approx(0.08)
    assert m["solve_time_solves_p50"] == pytest.approx(0.04)
    assert m["gamma"] == {
        "first": 10.0, "last": 2.0, "min": 2.0, "max": 10.0, "count": 2,
        "t": [0.0, pytest.approx(0.3)], "values": [10.0, 2.0],
    }
    json.dumps(m, allow_nan=False)  # JSON-ready


# -- scenarios ---------------------------------------------------------------------------------


def test_scenario_ids_are_stable_and_round_trip():
    a = Scenario.from_dict({"controller": "GIPC", "u_max": 1, "settings": {"Np": 100}})
    b = Scenario.from_dict({"settings": {"Np": 100}, "u_max": 1.0, "controller": "GIPC"})
    assert a.case_id == b.case_id
    assert Scenario.from_dict(a.to_dict()).case_id == a.case_id
    assert Scenario.from_dict({**a.to_dict(), "spread": 0.31}).case_id != a.case_id
    assert a.settings["Np"] == 100 and a.settings["Nc"] == 4  # defaults filled in


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"spredd": 0.1}, "base.spredd"),
        ({"spread": -0.1}, "base.spread"),
        ({"spread": 1.0}, "base.spread"),
        ({"u_max": 0}, "base.u_max"),
        ({"u_max": "1"}, "base.u_max"),
        ({"controller": "PID"}, "base.controller"),
        ({"plant": "flexible"}, "base.plant"),
        ({"saturation": "clip"}, "base.saturation"),
        ({"controller": "LQR", "saturation": "constraint"}, "base.saturation"),
        ({"true_inertia": [1.0, -1.0, 2.0]}, "base.true_inertia"),
        ({"disturbance_axes": ["roll", "roll"]}, "base.disturbance_axes"),
        ({"disturbance_axes": [[]]}, "base.disturbance_axes"),  # unhashable: was a TypeError
        ({"ic_scale": 3.0}, "base.ic_scale"),
        ({"duration": 0.001}, "base.duration"),
        ({"settings": {"Npp": 3}}, "base.settings.Npp"),
        ({"controller": "GIPC", "settings": {"Np": 0}}, "base.settings.Np"),
        ({"settings": {"resolve_threshold": 1.5}}, "base.settings.resolve_threshold"),
        ({"settings": {"input_constraint": "box"}}, "base.settings.input_constraint"),
    ],
)
def test_scenario_rejects_impossible_values_naming_the_field(data, field):
    with pytest.raises(ConfigError) as info:
        Scenario.from_dict(data, where="base")
    assert info.value.argument == field
    assert str(info.value).startswith(f"{field}: expected ")


# -- tables ------------------------------------------------------------------------------------


def _record() -> dict:
    m = compute_metrics(_trajectory(), u_max=1.0)
    return {"experiment": "E2", "controller": "RMPC", "plant": "linear", "saturation": "limiter",
            "settings": {"spread": 0.3}, "metrics": m}


def test_tables_in_every_format_hold_the_same_values():
    header, rows = metric_table([_record()])
    md = to_markdown(header, rows)
    assert md.splitlines()[0].startswith("| experiment | controller | plant | saturation | sum\\|e\\| roll")
    assert "| E2 | RMPC | linear | limiter | 0.7 |" in md
    csv_text = to_csv(header, rows)
    assert csv_text.splitlines()[1].startswith("E2,RMPC,linear,limiter,0.7")
    tex = to_latex(header, rows, caption="x_y 50%")
    assert r"\begin{tabular}" in tex and r"x\_y 50\%" in tex and r"sum$|$e$|$ roll" in tex
    obj = to_json(header, rows)[0]
    assert obj["experiment"] == "E2" and math.isclose(obj["sum|e| roll (rad)"], 0.7)
    assert obj["max settling (s)"] is None  # yaw did not settle


def test_a_table_of_records_without_the_rigid_metrics_shows_dashes():
    """The mrp family measures no per-axis IAE, settling time or overshoot: a sweep of it used to
    stop at the table with KeyError 'iae'."""
    rec = _record()
    for key in ("iae", "settling_time", "overshoot"):
        del rec["metrics"][key]
    header, rows = metric_table([rec])
    obj = dict(zip(header, rows[0], strict=True))
    assert obj["max IAE (rad s)"] is None and obj["max overshoot (%)"] is None
    assert obj["max|u| (N m)"] == rec["metrics"]["max_abs_u"]


@pytest.mark.parametrize(
    "module",
    [
        "core.metrics",
        "reports.tables",
        "reports.sections",
        "core.scenario",
        "core.store",
        "core.suite",
        "core.registry",
        "suites.paper",
        "core.sweep_spec",
    ],
)
def test_docstring_examples_run(module):
    import doctest
    import importlib

    mod = importlib.import_module(f"benchmarks.{module}")
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0 and result.attempted > 0


def test_recovery_after_an_event():
    from benchmarks.core.metrics import recovery

    t = np.linspace(0.0, 10.0, 101)
    e = np.where(t < 2.0, 0.0, np.exp(-(t - 2.0)))  # jumps to 1 at t = 2, decays
    out = recovery(t, np.column_stack([e, 0.5 * e]), t_on=2.0, band=1e-2)
    assert out["peak_error"] == 1.0
    # exp(-s) <= 1e-2 from s = ln(100) = 4.605..., the first sample after it is 4.7
    assert out["recovery_time"] == pytest.approx(4.7)
    assert recovery(t, e, t_on=2.0, band=1e-6)["recovery_time"] is None
    assert recovery(t, e, t_on=20.0, band=1e-2)["peak_error"] is None
