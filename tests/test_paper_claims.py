"""benchmarks.suites.paper_claims: each verdict follows the numbers (synthetic records)."""

from __future__ import annotations

from benchmarks.suites.paper_claims import CLOSE_RELATIVE, assess_claims


def _rec(exp, ctrl, plant, sat, sum_e=(10.0, 10.0, 10.0), final=1e-9, max_u=0.5, max_cmd=None,
         saturated=0.0, limiter=False, violation=0.0):
    axes = ("roll", "pitch", "yaw")
    return {
        "experiment": exp, "controller": ctrl, "plant": plant, "saturation": sat,
        "settings": {"u_max": 1.0, "limiter_in_loop": limiter, "settings": {"du_max": 0.01}},
        "metrics": {
            "sum_abs_err": dict(zip(axes, sum_e, strict=True)),
            "final_abs_err": dict.fromkeys(axes, final),
            "max_abs_u": max_u, "max_abs_u_cmd": max_u if max_cmd is None else max_cmd,
            "saturated_fraction": saturated, "constraint_violation": violation,
        },
    }


def _by_exp(records):
    return {c.experiment: c for c in assess_claims(records)}


def test_e1_needs_both_commands_far_past_the_limit():
    recs = [_rec("E1", "RMPC", "linear", "none", max_u=4.0), _rec("E1", "GIPC", "linear", "none", max_u=4.4)]
    assert _by_exp(recs)["E1"].verdict == "reproduced"
    recs[1] = _rec("E1", "GIPC", "linear", "none", max_u=1.5)
    assert _by_exp(recs)["E1"].verdict == "not reproduced"


def test_e2_close_with_limiter_and_rmpc_below_with_constraint():
    close = 1.0 - CLOSE_RELATIVE / 2
    recs = [
        _rec("E2", "RMPC", "linear", "limiter", sum_e=(10, 10, 10)),
        _rec("E2", "GIPC", "linear", "limiter", sum_e=(10 / close, 10, 10)),
        _rec("E2", "RMPC", "linear", "constraint", sum_e=(5, 5, 5)),
        _rec("E2", "GIPC", "linear", "constraint", sum_e=(6, 6, 6)),
    ]
    assert _by_exp(recs)["E2"].verdict == "reproduced"
    recs[3] = _rec("E2", "GIPC", "linear", "constraint", sum_e=(6, 4, 6))  # RMPC worse on pitch
    claim = _by_exp(recs)["E2"]
    assert claim.verdict == "partly reproduced"
    assert "not below" in claim.why


def test_e4_rmpc_must_drift_and_crmpc_settle():
    recs = [_rec("E4", "RMPC", "nonlinear", "constraint", final=0.4),
            _rec("E4", "CRMPC", "nonlinear", "constraint", final=1e-9)]
    assert _by_exp(recs)["E4"].verdict == "reproduced"
    recs[1] = _rec("E4", "CRMPC", "nonlinear", "constraint", final=0.02)
    assert _by_exp(recs)["E4"].verdict == "partly reproduced"


def test_e5_names_where_gipc_saturates():
    base = [_rec("E5", "GIPC", "nonlinear", "constraint", max_u=0.64),
            _rec("E5", "CRMPC", "nonlinear", "constraint", max_u=0.85)]
    claim = _by_exp(base)["E5"]
    assert claim.verdict == "partly reproduced"
    assert "does not saturate" in claim.why
    limited = _rec("E5", "GIPC", "nonlinear", "limiter", max_u=1.0, max_cmd=50.0, saturated=0.9, limiter=True)
    assert _by_exp([*base, limited])["E5"].verdict == "reproduced with GIPC behind the limiter"
    with_limiter = [base[0], _rec("E5", "CRMPC", "nonlinear", "constraint", max_u=1.0, limiter=True)]
    assert "limiter" in _by_exp(with_limiter)["E5"].why


def test_e6_fails_when_rmpc_leaves_the_limit():
    recs = [_rec("E6", c, p, "constraint") for c in ("RMPC", "GIPC") for p in ("linear", "nonlinear")]
    assert _by_exp(recs)["E6"].verdict == "reproduced"
    recs[0] = _rec("E6", "RMPC", "linear", "constraint", max_u=1.2, violation=0.2)
    assert _by_exp(recs)["E6"].verdict == "not reproduced"
