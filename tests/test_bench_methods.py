"""``rmpc bench methods``: the short path on one small problem, the records, resuming, the region search."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

from benchmarks.suites import methods as suite
from benchmarks.suites.methods import (
    MethodsSettings,
    method_options,
    region_along,
    run_methods,
)
from benchmarks.suites.methods_problems import build_problem
from benchmarks.suites.methods_report import least_conservative
from toolkit_common.errors import InvalidArgumentError

API_FIELDS = (
    "problem",
    "method",
    "status",
    "gamma",
    "solve_time_p50",
    "solve_time_p95",
    "cvxpy_time_p50",
    "region",
    "closed_loop_cost",
)


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("methods")
    outcome = run_methods(
        out, short=True, problems=["kothare_ex1"], methods=["kothare", "vertex"], progress=False
    )
    return out, outcome


def test_short_run_writes_records_report_and_figures(short_run):
    out, outcome = short_run
    assert not outcome.failures and not outcome.execution.interrupted
    records = json.loads((out / "results.json").read_text())
    assert [(r["problem"], r["method"]) for r in records] == [
        ("kothare_ex1", "kothare"),
        ("kothare_ex1", "vertex"),
    ]
    for rec in records:
        missing = [f for f in API_FIELDS if f not in rec]
        assert not missing, missing
        assert rec["status"] == "optimal" and rec["gamma"] > 0
        assert rec["solve_time_p50"] <= rec["solve_time_p95"]
        assert rec["cvxpy_time_p50"] > 0 and rec["closed_loop_cost"] > 0
        assert len(rec["region"]["t"]) == MethodsSettings.short().directions_2d
    report = (out / "results.md").read_text()
    assert "## kothare_ex1" in report and "least conservative" in report
    assert (out / "figures" / "region_kothare_ex1.png").stat().st_size > 0
    assert len(list((out / "cases").glob("*.json"))) == 2


def test_an_interrupted_run_resumes_where_it_stopped(tmp_path, monkeypatch):
    real = suite.evaluate
    calls: list[str] = []

    def interrupt_second(problem, method, settings):
        calls.append(method)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(problem, method, settings)

    monkeypatch.setattr(suite, "evaluate", interrupt_second)
    args = dict(short=True, problems=["kothare_ex1"], methods=["kothare", "nominal"], progress=False)
    first = run_methods(tmp_path, **args)
    assert first.execution.interrupted and first.execution.unfinished == ["kothare_ex1__nominal"]
    assert [r["method"] for r in json.loads((tmp_path / "results.json").read_text())] == ["kothare"]

    calls.clear()
    monkeypatch.setattr(suite, "evaluate", lambda p, m, s: (calls.append(m), real(p, m, s))[1])
    second = run_methods(tmp_path, **args)
    assert calls == ["nominal"]  # the stored case is not measured again
    assert [r["method"] for r in second.records] == ["kothare", "nominal"]
    assert second.records[0] == first.records[0]
    assert "1 cases were taken from an earlier run" in (tmp_path / "results.md").read_text()


def test_a_stored_case_of_other_settings_is_measured_again(tmp_path, monkeypatch):
    args = dict(problems=["kothare_ex1"], methods=["kothare"], progress=False)
    run_methods(tmp_path, short=True, **args)
    calls: list[str] = []
    real = suite.evaluate
    monkeypatch.setattr(suite, "evaluate", lambda p, m, s: (calls.append(m), real(p, m, s))[1])
    monkeypatch.setattr(
        MethodsSettings,
        "short",
        classmethod(lambda cls: cls(directions_2d=4, t_max=8.0, steps_factor=0.1, cvxpy_states=1)),
    )
    run_methods(tmp_path, short=True, **args)
    assert calls == ["kothare"]


class _Threshold:
    """A controller stub feasible exactly for ``|x| <= limit`` (failure word above)."""

    def __init__(self, limit: float, word: str = "infeasible") -> None:
        self.limit, self.word, self.solves = limit, word, 0

    def solve(self, x):
        self.solves += 1
        ok = np.linalg.norm(x) <= self.limit
        return SimpleNamespace(status="optimal" if ok else self.word,
                               certificate=SimpleNamespace(ok=True) if ok else None)


@pytest.mark.parametrize("limit", [0.3, 1.0, 3.3, 40.0])
def test_region_search_brackets_the_boundary(limit):
    settings = MethodsSettings(rel_tol=0.02, t_max=64.0)
    counts: dict[str, int] = {}
    t, why = region_along(_Threshold(limit, "numerical_error"), np.array([1.0, 0.0]), settings, counts)
    assert limit / (1 + settings.rel_tol) <= t <= limit
    assert why == "numerical_error" and counts["optimal"] >= 1


def test_region_search_stops_at_the_cap_and_at_zero():
    settings = MethodsSettings(t_max=16.0)
    assert region_along(_Threshold(1e9), np.array([1.0]), settings, {}) == (16.0, "cap")
    assert region_along(_Threshold(1e-9), np.array([1.0]), settings, {}) == (0.0, "infeasible")


def test_method_options_follow_the_problem():
    p = build_problem("paper_p_2v")  # ||u||_2 bound, three inputs
    options, _reason, comparable = method_options(p, "auxiliary_saturation")
    assert options == {"saturation": "auxiliary", "input_constraint": "peak"} and not comparable
    mup = build_problem("mup_demo")  # output bounds: the soft form softens them too
    assert method_options(mup, "soft")[0] == {"soft": {"u": suite.SOFT_WEIGHT, "y": suite.SOFT_WEIGHT}}
    assert method_options(build_problem("kothare_ex1"), "soft")[0] == {"soft": {"u": suite.SOFT_WEIGHT}}
    e, w_max = method_options(mup, "disturbance")[0]["disturbance"]
    assert e.shape == (2, 1) and w_max == pytest.approx(0.05 * 10.0)


def test_the_ranking_is_read_from_the_records():
    def rec(method, gamma, t, cost, status="optimal"):
        return {
            "problem": "p",
            "method": method,
            "status": status,
            "gamma": gamma,
            "comparable": True,
            "region": {"t": t},
            "closed_loop_cost": cost,
        }

    records = [
        rec("kothare", 10.0, [1.0, 2.0], 5.0),
        rec("vertex", 8.0, [2.0, 4.0], 6.0),
        rec("nominal", 1.0, [1.0, 1.0], 4.0),
        rec("vertex_pairs", 7.0, [1.0, 2.0], 5.5, "inaccurate"),
        rec("soft", 10.0, [64.0, 64.0], 5.0),  # relaxes the bounds: not in the region ranking
        rec("free_move", 9.0, [2.0, 4.0], 6.0),
    ]
    (line,) = least_conservative(records)
    assert "smallest worst-case gamma: vertex 8" in line  # nominal bounds another cost, pairs not optimal
    assert "largest region (hard bounds): vertex (2.000 x kothare's, geometric mean) (tied" in line
    assert "(tied within 0.1%: free_move)" in line
    assert "lowest closed-loop cost: nominal 4" in line


def test_mup_keys_take_the_demo_parameters_and_the_peak_bound():
    """The bench runs MUP's keys with the options of :data:`rmpc.mpc.methods.METHODS` and MUP's demo's
    parameters (beta = 1e3, N = 3); a saturation method on an ``||u||_2`` problem is not comparable."""
    p = build_problem("paper_p_2v")  # bounds ||u||_2
    options, reason, comparable = method_options(p, "huang")
    assert reason is None and not comparable
    assert options == {"saturation": "auxiliary", "unsaturated_weight": 1e3, "input_constraint": "peak"}
    options, _, comparable = method_options(p, "shi")
    assert comparable is False and options["horizon"] == 3 and options["lyapunov"] == "vertex_pairs"
    options, _, comparable = method_options(p, "ding")
    assert comparable and options == {"cost": "nominal", "lyapunov": "vertex_pairs"}


def test_new_methods_run_beside_the_forms(tmp_path):
    outcome = run_methods(tmp_path, short=True, problems=["kothare_ex1"], methods=["ding", "multistage"],
                          progress=False)
    assert not outcome.failures
    recs = {r["method"]: r for r in outcome.records}
    assert recs["ding"]["status"] == "optimal" and recs["ding"]["gamma"] > 0
    assert recs["multistage"]["status"] == "optimal" and recs["multistage"]["gamma"] is None
    assert recs["multistage"]["cvxpy_time_p50"] is None and "QP family" in recs["multistage"]["cvxpy_error"]
    for rec in recs.values():
        assert rec["violation_samples"] == rec["violation_runs"] * rec["closed_loop_steps"] > 0
        assert rec["violations"] == 0, rec  # both keep |u| <= 2 on every vertex sequence


def test_violations_count_the_samples_that_break_a_bound():
    p = build_problem("mup_demo")  # |u| <= 10 and |x_i| <= 10

    class TooStrong:
        last = None

        def reset(self):
            pass

        def step(self, x):
            return np.array([2.0 * p.u_max])  # every input beyond the bound

    settings = MethodsSettings.short()
    out = suite._violations(TooStrong(), p, 5, settings)
    assert out["violation_runs"] == settings.violation_runs
    assert out["violations_input"] == out["violation_samples"] == 5 * settings.violation_runs
    assert out["violations_state"] > 0  # u = 20 drives the states out of |x_i| <= 10


def test_tube_runs_on_the_double_integrator_and_is_skipped_on_a_polytope(tmp_path):
    outcome = run_methods(tmp_path, short=True, problems=["double_integrator", "kothare_ex1"],
                          methods=["tube", "tube_tightening"], progress=False)
    assert not outcome.failures
    recs = {(r["problem"], r["method"]): r for r in outcome.records}
    for kind in ("tube", "tube_tightening"):
        rec = recs[("double_integrator", kind)]
        assert rec["status"] == "optimal" and rec["violations"] == 0 and rec["violation_samples"] > 0
        assert rec["settings"]["options"]["kind"] == ("rigid" if kind == "tube" else "tightening")
        skipped = recs[("kothare_ex1", kind)]
        assert skipped["status"] == "skipped" and "additive disturbance set W" in skipped["skip_reason"]


def test_the_satellite_holding_attitude_runs_the_tightening_and_says_why_not_the_rigid_tube(tmp_path):
    """paper_p_hold: one plant, a gravity-gradient torque through B (flat in the state space)."""
    outcome = run_methods(tmp_path, short=True, problems=["paper_p_hold"],
                          methods=["tube", "tube_tightening"], progress=False)
    assert not outcome.failures
    recs = {r["method"]: r for r in outcome.records}
    tight = recs["tube_tightening"]
    assert tight["status"] == "optimal" and tight["violations"] == 0 and tight["violation_samples"] > 0
    assert tight["settings"]["options"]["E"].startswith("the nominal B")
    assert recs["tube"]["status"] == "skipped" and "3 of 6 state directions" in recs["tube"]["skip_reason"]


def test_switching_runs_push_by_the_disturbance_box():
    from models import PolytopicModel
    from rmpc.mpc.switching_runs import switching_runs

    plant = PolytopicModel([(np.eye(2), np.ones((2, 1)))], dt=1.0)

    class Zero:
        last = None

        def reset(self):
            pass

        def step(self, x):
            return np.zeros(1)

    calm = switching_runs(Zero(), plant, [0.0, 0.0], steps=7, runs=1, seed=3)
    pushed = switching_runs(Zero(), plant, [0.0, 0.0], steps=7, runs=1, seed=3, w_max=[0.1, 0.2])
    assert calm["final_norm"] == 0.0
    assert 0.0 < pushed["final_norm"] <= 7 * np.hypot(0.1, 0.2) + 1e-12
    with pytest.raises(InvalidArgumentError, match="w_max"):
        switching_runs(Zero(), plant, [0.0, 0.0], steps=1, runs=1, seed=0, w_max=[-0.1, 0.1])


def test_the_satellites_are_pushed_by_a_gravity_gradient_sized_torque():
    """Paper M's orbit (650 km: n = 1.071540e-3 rad/s) and paper P's inertias spread by +-30 %:
    ``3 n^2 (J_max - J_min) / 2``, entering through the nominal input matrix."""
    from benchmarks.suites.methods_problems import gravity_gradient_bound

    n = 1.071540e-3
    assert gravity_gradient_bound(np.array([2.0, 3.0])) == pytest.approx(1.5 * n**2, rel=1e-6)
    p = build_problem("paper_p_2v")
    j = np.array([1.2928, 4.2953])
    assert p.w_box == pytest.approx(np.full(3, 1.5 * n**2 * (1.3 * j[1] - 0.7 * j[0])), rel=1e-4)
    assert p.w_matrix.shape == (6, 3)
    e, w_max = p.disturbance  # the disturbance form keeps its own design bound
    assert w_max == pytest.approx(0.05) and e.shape == (6, 3)


def test_switching_runs_push_through_the_disturbance_matrix():
    from models import PolytopicModel
    from rmpc.mpc.switching_runs import switching_runs

    plant = PolytopicModel([(np.eye(2), np.ones((2, 1)))], dt=1.0)

    class Zero:
        last = None

        def reset(self):
            pass

        def step(self, x):
            return np.zeros(1)

    out = switching_runs(Zero(), plant, [0.0, 0.0], steps=5, runs=1, seed=1, w_max=[0.3], E=[[0.0], [1.0]],
                         state_constraints=(np.array([[1.0, 0.0], [-1.0, 0.0]]), [0.0, 0.0]))
    assert out["state_violations"] == 0  # the first state is never pushed
    assert 0.0 < out["final_norm"] <= 1.5 + 1e-12
