"""Paper M's outcomes R1-R4 in the mrp report: the chattering metric, the late window, the verdicts.

The verdicts (:mod:`benchmarks.suites.mrp_claims`) are checked twice: on synthetic records that
flip each one, and on records of short runs of the suite's own cases (5 s, the ``--short`` length),
where each verdict must agree with the numbers it prints.
"""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.core.runner import simulate_scenario
from benchmarks.core.scenario import Scenario
from benchmarks.families.mrp.family import LATE_WINDOW_START, chattering, late_window_start
from benchmarks.suites import mrp_claims
from benchmarks.suites.mrp import SHORT_TIME_SCALE, mrp_cases, paper_m_comparison
from benchmarks.suites.mrp_claims import assess_paper_m


def test_chattering_is_total_variation_per_second_on_the_window():
    dt = 0.1
    t = np.arange(0.0, 10.0 + dt / 2, dt)
    k = np.arange(t.size - 1)
    u = np.zeros((k.size, 3))
    u[:, 0] = np.where(k % 2 == 0, 0.5, -0.5)  # a torque that switches every sample: 1 N m per step
    d = np.zeros((k.size, 3))
    d[:, 1] = 0.1 * t[:-1]  # a ramp: 0.01 N m per step
    out = chattering(t, u, d, 4.0)
    late = 60  # samples at t >= 4 s (4.0 .. 9.9), so 59 differences
    assert out["chatter_tv_rate"] == pytest.approx((late - 1) * 1.0 / 6.0, rel=1e-12)
    assert out["chatter_ratio"] == pytest.approx(1.0 / 0.01, rel=1e-9)
    assert chattering(t, u, np.zeros_like(d), 4.0)["chatter_ratio"] is None  # no disturbance
    assert chattering(t, u, d, 9.95) == {"chatter_tv_rate": None, "chatter_ratio": None}


def test_late_window_is_20_s_on_full_runs_and_the_steady_window_on_short_ones():
    assert late_window_start(50.0) == LATE_WINDOW_START == 20.0
    assert late_window_start(2.5) == 2.5


@pytest.fixture(scope="module")
def short_records():
    """The suite's BS, MAB and TF-AB cases of M1 and M2 at the ``--short`` length, with traces."""
    out = []
    for case in mrp_cases(SHORT_TIME_SCALE, ["M1", "M2"]):
        if case.scenario.controller in ("BS", "MAB", "TFAB"):
            rec, trace = simulate_scenario(case.scenario, case.experiment, keep_trace=True)
            out.append({**rec, "trace": trace})
    return out


def test_short_run_records_carry_the_late_window_metrics(short_records):
    for rec in short_records:
        m, s = rec["metrics"], rec["settings"]
        lo, hi = s["late_window"]
        assert (lo, hi) == tuple(s["steady_window"])  # 5 s: shorter than 40 s
        trace = rec["trace"]
        late = trace["t"][:-1] >= lo
        tv = np.abs(np.diff(trace["u_applied"][late], axis=0)).sum() / (trace["t"][-1] - lo)
        assert m["chatter_tv_rate"] == pytest.approx(tv, rel=1e-12)
        if rec["experiment"] == "M1":
            assert m["chatter_ratio"] is None
        else:
            tv_d = np.abs(np.diff(trace["d"][late], axis=0)).sum() / (trace["t"][-1] - lo)
            assert m["chatter_ratio"] == pytest.approx(tv / tv_d, rel=1e-12)
        if "torque_estimate" in trace:
            err = np.abs(trace["torque_estimate"][late] - trace["d"][late]).max()
            assert m["td_est_err_max"] == pytest.approx(err, rel=1e-12)


def _by_key(records):
    return {c.experiment: c for c in assess_paper_m(records)}


def test_verdicts_follow_the_short_runs_numbers(short_records):
    def metric(exp, ctrl, key):
        rec = next(r for r in short_records if (r["experiment"], r["controller"]) == (exp, ctrl))
        return rec["metrics"][key]

    claims = _by_key(short_records)
    r1 = all(metric("M1", c, "err_angle_ss_max_deg") < mrp_claims.SMALL_ERROR_DEG for c in ("BS", "MAB"))
    assert (claims["R1"].verdict == "reproduced") == r1
    r2 = all(metric("M1", c, "max_abs_u_time") < mrp_claims.FIRST_SECONDS for c in ("BS", "MAB", "TFAB"))
    assert (claims["R2"].verdict == "reproduced") == r2
    bs, mab = metric("M2", "BS", "err_angle_ss_max_deg"), metric("M2", "MAB", "err_angle_ss_max_deg")
    r3 = [bs >= mrp_claims.CLEAR_ERROR_DEG, mab <= mrp_claims.MINIMAL_ERROR_DEG and bs >= 10 * mab,
          metric("M2", "MAB", "td_est_err_max") <= mrp_claims.ESTIMATE_ERROR]
    assert claims["R3"].verdict == ("reproduced" if all(r3) else "partly reproduced" if any(r3)
                                    else "not reproduced")
    ratio = metric("M2", "MAB", "chatter_ratio")
    r4 = [mab < metric("M2", "TFAB", "err_angle_ss_max_deg"),
          metric("M2", "MAB", "err_angle_final_deg") < metric("M2", "MAB", "err_angle_initial_deg"),
          ratio <= mrp_claims.CHATTER_RATIO]
    assert claims["R4"].verdict == ("reproduced" if all(r4) else "partly reproduced" if any(r4)
                                    else "not reproduced")
    assert f"{ratio:.3g}" in claims["R4"].evidence
    text = "\n".join(paper_m_comparison(short_records))
    for c in claims.values():  # a smoke run's report judges none of them
        assert f"**{c.experiment}: no measurement.**" in text
    assert "reproduced" not in text


def _rec(exp, ctrl, err=1e-9, t_peak=0.0, est=None, ratio=None, final=1e-9, initial=57.8):
    metrics = {"err_angle_ss_max_deg": err, "max_abs_u": 1.9, "max_abs_u_time": t_peak,
               "td_est_err_max": est, "chatter_ratio": ratio, "err_angle_final_deg": final,
               "err_angle_initial_deg": initial}
    return {"experiment": exp, "controller": ctrl, "metrics": metrics,
            "settings": {"inertia_scale_used": 1.0, "late_window": [20.0, 100.0]}}


def test_each_verdict_flips_with_its_number():
    m1 = [_rec("M1", c) for c in ("BS", "MAB", "TFAB")]
    m2 = [_rec("M2", "BS", err=0.417), _rec("M2", "MAB", err=0.0194, est=8.3e-4, ratio=1.02),
          _rec("M2", "TFAB", err=0.138, est=6.3e-3, ratio=1.01)]
    claims = _by_key(m1 + m2)
    assert [c.verdict for c in claims.values()] == ["reproduced"] * 4
    assert "t >= 20 s" in claims["R3"].evidence
    m1[1] = _rec("M1", "MAB", err=2e-6)
    assert _by_key(m1 + m2)["R1"].verdict == "not reproduced"
    m1[2] = _rec("M1", "TFAB", t_peak=6.0)
    assert _by_key(m1 + m2)["R2"].verdict == "not reproduced"
    m2[1] = _rec("M2", "MAB", err=0.0194, est=3e-3, ratio=1.6)
    claims = _by_key(m1 + m2)
    assert claims["R3"].verdict == "partly reproduced" and "estimate error" in claims["R3"].why
    assert claims["R4"].verdict == "partly reproduced" and "chattering" in claims["R4"].why
    m2[1] = _rec("M2", "MAB", err=0.2, est=8.3e-4, ratio=1.0, final=60.0)
    claims = _by_key(m1 + m2)
    assert claims["R3"].verdict == "partly reproduced"
    assert claims["R4"].verdict == "partly reproduced" and "grew" in claims["R4"].why
    assert [c.verdict for c in assess_paper_m([])] == ["not run"] * 4


def test_the_estimate_error_is_measured_from_20_s_on_a_run_longer_than_40_s():
    """TF-AB on M2 for 60 s: the steady window is [30, 60] s, the late window [20, 60] s. TF-AB's
    estimate error peaks once per half period of the disk's speed; the peak near 27 s is the
    largest (6.2029e-3 N m against 6.2017e-3 after 30 s), so the two windows differ."""
    sc = Scenario.from_dict({"family": "mrp", "controller": "TFAB", "scenario": "M2", "duration": 60.0,
                             "dt": 0.05})
    rec, trace = simulate_scenario(sc, keep_trace=True)
    assert rec["settings"]["late_window"] == [20.0, 60.0] and rec["settings"]["steady_window"] == [30.0, 60.0]
    t, err = trace["t"][:-1], np.abs(trace["torque_estimate"] - trace["d"]).max(axis=1)
    from_20, from_30 = err[t >= 20.0].max(), err[t >= 30.0].max()
    assert from_20 > from_30 * (1 + 1e-5)  # the two windows give different numbers on this run
    assert rec["metrics"]["td_est_err_max"] == pytest.approx(from_20, rel=1e-12)
    late = t >= 20.0
    tv = chattering(trace["t"], trace["u_applied"], trace["d"], 20.0)
    assert rec["metrics"]["chatter_ratio"] == pytest.approx(tv["chatter_ratio"], rel=1e-12)
    assert late.sum() == 800
