"""The methods report keeps forms without a certified gain and regions at the search cap out of
its comparisons (records built here, no solver run)."""

from __future__ import annotations

import numpy as np

from benchmarks.suites.methods_report import (
    NO_GAIN,
    certified,
    least_conservative,
    summary_ratios,
    table_row,
)


def _rec(method: str, *, status: str = "optimal", counts: dict | None = None, cost: float = 10.0,
         t: list[float] | None = None, capped: bool = False, gamma: float = 5.0) -> dict:
    ts = t or [1.0, 2.0]
    return {
        "problem": "p",
        "method": method,
        "status": status,
        "gamma": gamma,
        "comparable": True,
        "status_counts": counts if counts is not None else {"optimal": 10},
        "closed_loop_cost": cost,
        "closed_loop_cost_switching": cost,
        "region": {"t": ts, "min_t": min(ts), "geo_mean_t": float(np.exp(np.mean(np.log(ts)))),
                   "capped": capped, "ended_by": {"cap" if capped else "infeasible": len(ts)}},
    }


def test_a_form_that_never_had_a_certified_gain_shows_no_cost_and_no_ratio():
    base = _rec("kothare", cost=20.0)
    lost = _rec("disturbance", status="infeasible", counts={"infeasible": 16}, cost=19.0)
    assert certified(base) and not certified(lost)
    row = table_row(lost, base)
    assert row["cost (nominal plant)"] == NO_GAIN and row["cost (switching)"] == NO_GAIN
    _, methods, _, cost, _ = summary_ratios([base, lost])
    assert np.isnan(cost[0, methods.index("disturbance")]) and cost[0, methods.index("kothare")] == 1.0
    (line,) = least_conservative([base, lost])
    # its lower (u = 0) cost does not win the ranking; it is named as having no gain
    assert "lowest closed-loop cost: kothare 20" in line and f"{NO_GAIN}: disturbance" in line


def test_a_kept_gain_counts_as_certified():
    assert certified(_rec("x", status="infeasible", counts={"reused": 3, "infeasible": 2}))


def test_regions_at_the_cap_are_bounds_out_of_the_ranking_and_the_colour_scale():
    base = _rec("kothare", t=[1.0, 2.0])
    soft = _rec("soft", t=[16.0, 64.0], capped=True)
    vertex = _rec("vertex", t=[1.5, 2.0])
    nominal = _rec("nominal", t=[2.0, 64.0], capped=True)
    records = [base, vertex, nominal, soft]
    row = table_row(nominal, base)
    assert row["region min / geo-mean t"].endswith(f"at least {nominal['region']['geo_mean_t']:.3g}")
    assert "a bound" in row["region vs kothare"]
    _, methods, region, _, capped = summary_ratios(records)
    assert capped[0].tolist() == [m in ("nominal", "soft") for m in methods]
    assert np.isfinite(region[0]).all()  # the value is kept (written in the cell), only marked
    (line,) = least_conservative(records)
    assert "largest region (hard bounds): vertex" in line and "at the search cap, not ranked: nominal" in line


def test_when_kothare_is_at_the_cap_no_region_is_ranked():
    records = [_rec("kothare", t=[64.0, 64.0], capped=True), _rec("vertex", t=[64.0, 64.0], capped=True)]
    (line,) = least_conservative(records)
    assert "largest region (hard bounds): not ranked, the search cap bounds Kothare's region" in line


def test_the_families_head_to_head_name_the_winner_by_cost_and_by_time():
    from benchmarks.suites.methods_report import families_head_to_head

    def rec(problem, method, cost, p50, violations=0):
        return {"problem": problem, "method": method, "status": "optimal", "closed_loop_cost": cost,
                "solve_time_p50": p50, "violations": violations, "violation_samples": 10,
                "comparable": True, "status_counts": {"optimal": 3}}

    lines = families_head_to_head([
        rec("p", "kothare", 5.0, 2e-3), rec("p", "vertex", 4.0, 3e-3),
        rec("p", "tube", 4.5, 1e-3, violations=2), rec("p", "multistage", 6.0, 5e-4),
        rec("q", "kothare", 1.0, 1e-3),  # one family only: no line
    ])
    assert len(lines) == 1 and lines[0].startswith("- **p**")
    assert "LMI: cost 4 (vertex)" in lines[0] and "tube: cost 4.5 (tube)" in lines[0]
    assert "violations 2 / 10" in lines[0]
    assert lines[0].endswith("(lowest cost: LMI, fastest: multi-stage).")
