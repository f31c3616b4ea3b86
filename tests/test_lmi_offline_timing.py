"""The design-time report of the off-line design (``python -m dev.offline_timing``): the speed-up
is given only where both back-ends designed the complete table, and the report says so."""

from __future__ import annotations

from typing import Any

import numpy as np

from dev.offline_timing import _markdown, speedup


def _backend(median: float, complete: bool, reason: str = "complete") -> dict[str, Any]:
    last = {"stop_reason": reason, "n_ellipsoids": 6 if complete else 0, "gamma": [],
            "iterations_total": 128 if complete else None}
    return {"median_s": median, "min_s": median, "max_s": median, "complete_all": complete, "last": last,
            "construct_median_s": 0.5, "solver_median_s": median - 1.0, "rest_median_s": 0.5}


def test_speedup_when_both_complete() -> None:
    value, note = speedup({"ipm": _backend(2.0, True), "cvxpy": _backend(161.0, True)})
    assert value == 161.0 / 2.0
    assert "both complete" in note


def test_no_speedup_against_a_design_that_failed() -> None:
    # flex8: cvxpy + Clarabel stopped at the first design state after about 4 s; that time is a
    # time to failure, not a design time to divide by
    reason = "design state 0: status 'solver_error'"
    value, note = speedup({"ipm": _backend(2.0, True), "cvxpy": _backend(4.1, False, reason)})
    assert value is None
    assert "cvxpy incomplete" in note and "solver_error" in note
    value, note = speedup({"ipm": _backend(2.0, False, "design state 3: status 'uncertified'"),
                           "cvxpy": _backend(4.1, True)})
    assert value is None and "ipm incomplete" in note
    assert speedup({"ipm": _backend(2.0, True)})[0] is None


def test_report_marks_a_failed_design_and_its_missing_speedup() -> None:
    entry: dict[str, Any] = {"ipm": _backend(2.0, True),
                             "cvxpy": _backend(4.1, False, "design state 0: status 'solver_error'")}
    entry["speedup"], entry["speedup_note"] = speedup(entry)
    done: dict[str, Any] = {"ipm": _backend(3.0, True), "cvxpy": _backend(150.0, True)}
    done["speedup"], done["speedup_note"] = speedup(done)
    res = {"machine": {}, "load_before": (1.0,), "load_after": (2.0,), "repeats": 3,
           "cases": {"flex8": entry, "F4": done}}
    text = _markdown(res)
    assert "| flex8 | cvxpy | 4.10 (to failure) |" in text
    assert "| flex8 | ipm | 2.00 |" in text
    assert "- F4: 50.0x (cvxpy / ipm, both complete)" in text
    assert "- flex8: no speed-up: cvxpy incomplete" in text
    assert "| 0.50 / 1.00 / 0.50 | 128 |" in text


def _scalar_unstable() -> dict[str, Any]:
    """``x+ = 1.5 x + u``, ``|u| <= 1``: no invariant ellipsoid holds a state beyond ``|x| = 2``."""
    return {"A": [[[1.5]]], "B": [[[1.0]]], "Q": [[1.0]], "R": [[1.0]], "dt": 1.0,
            "input_constraint": "peak", "u_max": 1.0, "formulation": "standard"}


def test_design_record_splits_the_time_and_counts_iterations() -> None:
    from dev.offline_timing import _design

    rec = _design(_scalar_unstable(), np.array([0.5]), 3, 0.5, "clarabel")
    assert rec["complete"] and rec["n_ellipsoids"] == 3
    assert rec["iterations_total"] == sum(rec["iterations"]) > 0
    parts = rec["construct_s"] + rec["solver_s"] + rec["rest_s"]
    assert abs(parts - rec["wall_s"]) < 1e-9 and rec["solver_s"] == sum(rec["solve_s"])
    assert min(rec["construct_s"], rec["solver_s"], rec["rest_s"]) >= 0.0


def test_design_record_of_a_design_that_failed_has_no_iteration_total() -> None:
    from dev.offline_timing import _design

    rec = _design(_scalar_unstable(), np.array([100.0]), 3, 0.5, "clarabel")
    assert not rec["complete"] and rec["n_ellipsoids"] == 0
    assert rec["status"] == ["infeasible"]
    assert rec["iterations_total"] is None and rec["solver_s"] == 0.0
