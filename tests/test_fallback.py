"""The certified-gain fallback (rmpc.mpc.fallback.CertifiedGain), one class for RMPC and ScheduledRMPC.

The unstable scalar plant ``x+ = 2 x + u``, ``|u| <= 1``: at ``x = 0.5`` the Kothare problem is
feasible, at ``x = 50`` no gain with ``|F x| <= 1`` stabilises it (``|2 + F| < 1`` needs
``|F| > 1``), so the solve fails ("infeasible").
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from lmi import KothareProblem
from models import PolytopicModel, RigidSatellite
from rmpc import RMPC, ScheduledRMPC
from rmpc.mpc import fallback
from rmpc.mpc.fallback import CertifiedGain, is_certified
from toolkit_common.errors import InvalidArgumentError, NoCertifiedGainWarning, SolverError
from toolkit_common.status import Status

PLANT = PolytopicModel([(np.array([[2.0]]), np.array([[1.0]]))], dt=1.0)
NEAR, FAR = np.array([0.5]), np.array([50.0])


def _problem() -> KothareProblem:
    return KothareProblem(PLANT.A, PLANT.B, Q=[[1.0]], R=[[1.0]], u_max=1.0)


def test_a_certified_solve_replaces_the_gain_and_a_failed_one_keeps_it() -> None:
    prob = _problem()
    kept = CertifiedGain("test")
    with pytest.warns(NoCertifiedGainWarning, match="no certified gain"):
        u0, info0 = kept.take(prob.solve(FAR), FAR, (1, 1))  # before any gain: zero
    assert info0.fallback and info0.status == Status.INFEASIBLE and info0.extra["had_gain"] is False
    assert u0.tolist() == [0.0] and kept.gain is None and not kept.contains(NEAR)
    good = prob.solve(NEAR)
    assert is_certified(good)
    u1, info1 = kept.take(good, NEAR, (1, 1), bound=np.array([1.0]), extra={"note": 1})
    assert not info1.fallback and info1.status == Status.OPTIMAL and info1.gamma == good.gamma
    assert list(info1.extra) == ["solution", "note"]
    np.testing.assert_array_equal(u1, good.F @ NEAR)
    assert kept.bound.tolist() == [1.0] and kept.contains(NEAR)
    np.testing.assert_allclose(kept.q_inv, np.linalg.inv(good.Q))
    bad = prob.solve(FAR)
    u2, info2 = kept.take(bad, FAR, (1, 1), failure_extra={"where": "far"})
    assert info2.fallback and info2.gamma is None and info2.status == Status.INFEASIBLE
    assert list(info2.extra) == ["solution", "where", "had_gain"] and info2.extra["had_gain"] is True
    np.testing.assert_array_equal(u2, good.F @ FAR)  # the last certified gain
    assert kept.solution is good
    kept.reset()
    assert kept.gain is None and kept.bound is None and kept.q_inv is None


def test_near_origin_is_reused_and_failure_raises_on_request() -> None:
    kept = CertifiedGain("Owner", on_failure="raise", hold_radius=1e-3)
    assert kept.near_origin(np.array([1e-4])) and not kept.near_origin(NEAR)
    u, info = kept.reuse(np.array([1e-4]), (1, 1), "near origin")
    assert info.status == Status.REUSED and info.extra == {"solution": None, "reason": "near origin"}
    assert u.tolist() == [0.0]
    with pytest.raises(SolverError, match=r"^Owner\.step: the LMI solve at x = \[50\.0\] returned status"):
        kept.take(_problem().solve(FAR), FAR, (1, 1))
    with pytest.raises(InvalidArgumentError, match=r"^on_failure"):
        CertifiedGain("x", on_failure="ignore")  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match=r"^hold_radius"):
        CertifiedGain("x", hold_radius=-1.0)


def test_rmpc_and_scheduled_rmpc_decide_through_the_same_class(monkeypatch: pytest.MonkeyPatch) -> None:
    """Both controllers hold a CertifiedGain and every solved step goes through its ``take``."""
    owners: list[str] = []
    original = fallback.CertifiedGain.take

    def recording(self: CertifiedGain, *args: Any, **kwargs: Any) -> Any:
        owners.append(self.owner)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(fallback.CertifiedGain, "take", recording)
    rmpc = RMPC(PLANT, Q=[[1.0]], R=[[1.0]], u_max=1.0)
    sched = ScheduledRMPC(lambda x: PLANT, Q=[[1.0]], R=[[1.0]], u_max=1.0)
    for ctrl in (rmpc, sched):
        assert isinstance(ctrl.certified, CertifiedGain)
        u_near = ctrl.step(NEAR)
        gain = ctrl.gain
        u_far = ctrl.step(FAR)  # infeasible: the gain of NEAR is kept
        assert ctrl.last.fallback and ctrl.last.extra["had_gain"] is True
        np.testing.assert_array_equal(u_far, gain @ FAR)
        np.testing.assert_array_equal(u_near, gain @ NEAR)
        u_hold = ctrl.step(np.array([1e-12]))
        assert ctrl.last.status == Status.REUSED and ctrl.last.extra["reason"] == "near origin"
        np.testing.assert_array_equal(u_hold, gain @ np.array([1e-12]))
    assert owners == ["RMPC", "RMPC", "ScheduledRMPC", "ScheduledRMPC"]
    rmpc.step(FAR)
    assert rmpc.last.extra["inside_ellipsoid"] is False
    sched.step(FAR)
    assert "build_time" in sched.last.extra and "inside_ellipsoid" not in sched.last.extra


def test_scheduled_rmpc_protocol_attributes() -> None:
    sat = RigidSatellite.paper_p()
    ctrl = ScheduledRMPC.for_satellite(sat, 0.01, 0.3, np.eye(6), np.eye(3), u_max=1.0)
    assert ctrl.name == "ScheduledRMPC" and ctrl.accepts == frozenset()
    assert ctrl.on_failure == "fallback" and ctrl.hold_radius == 1e-9
