"""Paper W's verdicts and the studies W5-W7 of ``rmpc bench faults``.

The verdicts (:mod:`benchmarks.suites.faults_claims`) are checked on synthetic records that flip
each one, and on records of short runs of the suite's own cases (the ``--short`` length), where
each verdict must agree with the numbers it rests on.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.core.runner import simulate_scenario
from benchmarks.core.scenario import Scenario
from benchmarks.core.sweep import expand, load_sweep
from benchmarks.families.wheel import defaults
from benchmarks.families.wheel.family import misaligned_axes
from benchmarks.suites import faults_claims
from benchmarks.suites.faults import SHORT_TIME_SCALE, fault_cases, null_drift_section, w5_section
from benchmarks.suites.faults_claims import (
    assess_d_error,
    assess_hardware,
    assess_null_drift,
    assess_r1,
    onset_recovery,
    w5_table,
)
from models import WheelArray


def _rec(
    exp,
    ctrl="ABFTC",
    rt=None,
    *,
    gamma=0.1,
    limits=True,
    freeze=False,
    tv=0.1,
    h=(0.1, 0.0, 0.0, 0.0),
    drift=0.0,
    final=0.0,
    fields=None,
):
    return {
        "experiment": exp,
        "controller": ctrl,
        "label": f"{ctrl} S1",
        "settings": {
            "settings": {"gamma_g": gamma, "gamma_theta": gamma, "freeze": freeze},
            "limits_in_plant": limits,
            **(fields or {}),
        },
        "metrics": {
            "faults": {
                "recovery_time": [
                    {"event": "onset", "recovery_time": rt},
                    {"event": "end", "recovery_time": 1.0},
                ],
                "status_counts": {"ok": 10},
                "torque_tv_rate": tv,
                "final_h": list(h),
                "max_abs_u": 0.123,
                "final_abs_err": {"roll": final, "pitch": 0.0, "yaw": 0.0},
                "null_momentum": {"drift": drift, "final": drift, "at_t_from": 0.0, "t_from": 0.0},
            }
        },
    }


def _w5(lim_times, free_times):
    recs = [_rec("W5", rt=t, gamma=g, limits=True) for g, t in lim_times.items()]
    return recs + [_rec("W5", rt=t, gamma=g, limits=False) for g, t in free_times.items()]


def test_r1_verdict_and_cause_follow_the_numbers():
    w1 = [_rec("W1", rt=22.3)]
    # the pattern: no gain with limits within 15 s, without limits only a larger gain is
    r1 = assess_r1(w1 + _w5({0.1: 22.3, 1.0: None}, {0.1: 20.6, 1.0: 11.5}))
    assert r1.verdict == "not reproduced" and "cause: limits and gain" in r1.evidence
    assert "Gamma = 1 I3, 11.5 s" in r1.evidence and "20.6 s" in r1.why
    assert "cause: assumed gain" in assess_r1(w1 + _w5({0.1: 22.3, 3.0: 9.0}, {0.1: 20.6})).evidence
    assert "cause: limits" in assess_r1(w1 + _w5({0.1: 22.3}, {0.1: 9.0})).evidence
    assert "cause: neither" in assess_r1(w1 + _w5({0.1: 22.3}, {0.1: 30.0})).evidence
    assert assess_r1([_rec("W1", rt=9.0)]).verdict == "reproduced"
    assert assess_r1([_rec("W1", rt=faults_claims.ABOUT_FACTOR * 10.0 + 0.1)]).verdict == "not reproduced"
    assert assess_r1(_w5({0.1: 22.3}, {})).verdict == "not run"  # W5 alone: no verdict, the numbers


def _w6(nominal_tv=0.1, both_tv=1.0, nominal_h=0.5, both_h=0.01):
    f = {"viscous_friction": 5e-4, "coulomb_friction": 2e-3}
    return [
        _rec("W6", tv=nominal_tv, h=(nominal_h, 0, 0, 0)),
        _rec("W6", tv=0.2, h=(both_h, 0, 0, 0), fields=f),
        _rec("W6", tv=both_tv, h=(0.5, 0, 0, 0), fields={"angle_noise": 0.2}),
        _rec("W6", tv=both_tv, h=(both_h, 0, 0, 0), fields={**f, "angle_noise": 0.2}),
    ]


def test_hardware_verdicts_follow_the_numbers():
    r2, r3 = assess_hardware(_w6())
    assert r2.verdict == "reproduced (approximate)" and r3.verdict == "reproduced (approximate)"
    r2, r3 = assess_hardware(_w6(both_tv=0.19, both_h=0.3))
    assert r2.verdict == "not reproduced (approximate)" and r3.verdict == "partly reproduced (approximate)"
    assert assess_hardware(_w6(both_h=0.6))[1].verdict == "not reproduced (approximate)"


def test_d_error_verdict_is_abftc_recovering_within_the_threshold():
    thr = math.radians(defaults.RECOVERY_DEG)
    ok = [
        _rec("W7", rt=20.0, final=0.5 * thr),
        _rec("W7", "RMPC", rt=None, final=2 * thr),
        _rec("W1", rt=22.0),
    ]
    claim = assess_d_error(ok)
    assert claim.verdict == "reproduced" and "nominal D 22.0 s" in claim.evidence
    assert assess_d_error([_rec("W7", rt=20.0, final=2 * thr)]).verdict == "not reproduced"
    assert assess_d_error([_rec("W7", rt=None, final=0.0)]).verdict == "not reproduced"


def test_null_drift_is_flagged_above_the_limit_only():
    recs = [_rec("W1", "CRMPC", drift=faults_claims.DRIFT_LIMIT + 0.01), _rec("W1", drift=0.01)]
    flags = [row[3] for row in assess_null_drift(recs)]
    assert flags == [True, False]
    text = "\n".join(null_drift_section(recs))
    assert "Flagged: W1 CRMPC S1: drift +0.072" in text and "W1 ABFTC" not in text.split("Largest")[0]


def test_misaligned_axes_tilt_every_column_by_the_angle_and_depend_on_the_seed():
    d = WheelArray.paper_w().D
    a, b = misaligned_axes(d, 5.0, 0), misaligned_axes(d, 5.0, 1)
    angles = np.degrees(np.arccos(np.clip(np.sum(d * a, axis=0), -1, 1)))
    np.testing.assert_allclose(angles, 5.0, atol=1e-9)  # measured agreement: 1e-13
    np.testing.assert_allclose(np.linalg.norm(a, axis=0), 1.0, atol=1e-12)
    assert not np.allclose(a, b)
    np.testing.assert_array_equal(misaligned_axes(d, 0.0, 3), d)


def test_new_fields_keep_the_records_of_cases_that_leave_them_alone():
    plain = Scenario.from_dict({"family": "wheel", "controller": "ABFTC"})
    assert "wheel_limits" not in plain.to_dict() and "angle_noise" not in plain.to_dict()
    off = Scenario.from_dict({"family": "wheel", "controller": "ABFTC", "wheel_limits": False})
    assert off.to_dict()["wheel_limits"] is False and off.case_id != plain.case_id
    assert Scenario.from_dict(off.to_dict()) == off
    assert Scenario.from_dict({"family": "wheel", "controller": "ABFTC", "wheel_limits": True}) == plain


def test_w5_is_the_shipped_gamma_sweep_on_the_diagonal():
    sweep = {c.case_id for c in expand(load_sweep("faults_gamma"))}
    w5 = [c.scenario for c in fault_cases(1.0, ["W5"])]
    assert len(w5) == 2 * 2 * len(defaults.W5_GAMMAS)
    assert {sc.case_id for sc in w5} <= sweep
    assert len(fault_cases(SHORT_TIME_SCALE, ["W5"])) == 2 * len(defaults.W5_GAMMAS_SHORT)


@pytest.fixture(scope="module")
def short_records():
    """W5, W6 and ABFTC's W1 and W7 at the ``--short`` length, with traces."""
    out = []
    cases = fault_cases(SHORT_TIME_SCALE, ["W1", "W5", "W6", "W7"])
    for case in cases:
        if case.scenario.controller == "ABFTC":
            rec, trace = simulate_scenario(case.scenario, case.experiment, keep_trace=True)
            out.append({**rec, "trace": trace})
    return out


def test_short_runs_apply_the_new_fields(short_records):
    w6 = {
        (bool(r["settings"].get("viscous_friction")), bool(r["settings"].get("angle_noise"))): r
        for r in short_records
        if r["experiment"] == "W6"
    }
    assert len(w6) == 4
    # the plant without limits lets ABFTC's commands through; with them it clips
    nolim = next(r for r in short_records if r["experiment"] == "W5" and not r["settings"]["limits_in_plant"])
    lim = next(r for r in short_records if r["experiment"] == "W5" and r["settings"]["limits_in_plant"])
    assert (
        nolim["metrics"]["faults"]["max_abs_u"]
        > defaults.U_MAX
        >= lim["metrics"]["faults"]["max_abs_u"] - 1e-12
    )
    w7 = next(r for r in short_records if r["experiment"] == "W7")
    tilted = np.array(w7["settings"]["plant_D"])
    np.testing.assert_allclose(tilted, misaligned_axes(WheelArray.paper_w().D, defaults.D_TILT_DEG, 0))


def test_short_run_metrics_are_what_the_traces_say(short_records):
    d = WheelArray.paper_w().D
    proj = np.eye(4) - np.linalg.pinv(d) @ d
    for rec in short_records:
        f, trace = rec["metrics"]["faults"], rec["trace"]
        t = trace["t"]
        h = trace["x"][:, 6:]
        np.testing.assert_array_equal(f["final_h"], h[-1])
        assert f["null_momentum"]["final"] == pytest.approx(np.linalg.norm(proj @ h[-1]), rel=1e-12)
        k = int(np.searchsorted(t, f["null_momentum"]["t_from"] - 1e-12))
        assert f["null_momentum"]["at_t_from"] == pytest.approx(
            np.linalg.norm(proj @ h[k]), rel=1e-12, abs=1e-15
        )
        late = t[:-1] >= 0.5 * t[-1] - 1e-12
        tv = np.abs(np.diff(trace["u_applied"][late], axis=0)).sum() / (t[-1] - 0.5 * t[-1])
        assert f["torque_tv_rate"] == pytest.approx(tv, rel=1e-12)


def test_verdicts_follow_the_short_runs_numbers(short_records):
    recs = [{k: v for k, v in r.items() if k != "trace"} for r in short_records]
    about = faults_claims.ABOUT_FACTOR * faults_claims.R1_SECONDS
    w1 = next(r for r in recs if r["experiment"] == "W1")
    r1 = assess_r1(recs)
    base = onset_recovery(w1)
    assert (r1.verdict == "reproduced") == (base is not None and base <= about)
    table = w5_table(recs)
    assert set(table) == {(True, False), (False, False)}
    assert sorted(table[(True, False)]) == list(defaults.W5_GAMMAS_SHORT)
    lim_ok = any(t is not None and t <= about for t in table[(True, False)].values())
    assert ("cause: assumed gain" in r1.evidence) == lim_ok
    r2, r3 = assess_hardware(recs)
    w6 = [r for r in recs if r["experiment"] == "W6"]
    nominal = next(
        r for r in w6 if not r["settings"].get("angle_noise") and not r["settings"].get("viscous_friction")
    )
    both = next(r for r in w6 if r["settings"].get("angle_noise") and r["settings"].get("viscous_friction"))
    ratio = both["metrics"]["faults"]["torque_tv_rate"] / nominal["metrics"]["faults"]["torque_tv_rate"]
    assert r2.verdict.startswith("reproduced") == (ratio >= faults_claims.CHATTER_FACTOR)
    h_both = max(abs(v) for v in both["metrics"]["faults"]["final_h"])
    h_nom = max(abs(v) for v in nominal["metrics"]["faults"]["final_h"])
    assert r3.verdict.startswith("reproduced") == (h_both <= faults_claims.NEAR_ZERO_H and h_both < h_nom)
    w7 = next(r for r in recs if r["experiment"] == "W7")
    ok = onset_recovery(w7) is not None and max(
        w7["metrics"]["faults"]["final_abs_err"].values()
    ) <= math.radians(defaults.RECOVERY_DEG)
    assert (assess_d_error(recs).verdict == "reproduced") == ok
    for name, drift, _, flagged in assess_null_drift(recs):
        assert flagged == (drift > faults_claims.DRIFT_LIMIT), name
    text = "\n".join(w5_section(recs))
    assert "Gamma is assumed" in text and "appendix" in text and "0.1 I3" in text
