"""Failures are statuses, never crashes or silent numbers; RMPC falls back or raises; certificates bite.

The infeasible problem: ``A = diag(1.5, 0.9)``, ``B = [1, 1]'``, ``|u| <= 0.01`` (ellipsoid or
peak), state ``x = [10, 1]``. It is infeasible for *any* controller, not only for the LMIs:
``x1(k+1) = 1.5 x1(k) + u(k)`` with ``|u| <= 0.01`` gives ``|x1(k+1)| >= |x1(k)| + (0.5 |x1(k)| -
0.01)``, so from ``|x1| = 10`` the first state grows without bound and no finite cost bound
exists. Without the input bound the same problem is feasible (the pair is controllable), which
the tests check too. Measured: the direct Clarabel back-end stops with ``PrimalInfeasible`` and
returns its last iterate (gamma 1168.7, certificate failing); the cvxpy back-ends (Clarabel, SCS)
return status "infeasible" with gamma NaN; the default ``ipm`` back-end runs out of iterations and
hands the state to Clarabel, which reports it infeasible.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from lmi import FAILURE_STATUSES, KothareProblem, certify
from models import PolytopicModel
from rmpc import RMPC
from toolkit_common.errors import NoCertifiedGainWarning, SolverError, ToolkitError

A = np.diag([1.5, 0.9])
B = np.array([[1.0], [1.0]])
FAR = np.array([10.0, 1.0])
NEAR = np.array([0.01, 0.0])  # feasible with |u| <= 0.01 (measured)
PLANT = PolytopicModel([(A, B)], dt=0.1)


@pytest.mark.parametrize(("constraint", "u_max"), [("ellipsoid", 0.01), ("peak", 0.01)])
@pytest.mark.parametrize(
    ("backend", "solver"), [("ipm", None), ("clarabel", None), ("cvxpy", "CLARABEL"), ("cvxpy", "SCS")]
)
def test_infeasible_problem_is_a_failure_status(backend, solver, constraint, u_max):
    prob = KothareProblem(
        A, B, np.eye(2), np.eye(1), dt=0.1, input_constraint=constraint, u_max=u_max,
        backend=backend, solver=solver,
    )
    sol = prob.solve(FAR)  # must not raise
    assert sol.status in FAILURE_STATUSES
    assert sol.status == "infeasible", (sol.status, sol.solver_status)
    assert not sol.ok
    assert np.isnan(sol.gamma) or not sol.certificate.ok
    # the same plant without the input bound is feasible: the failure is the bound's
    free = KothareProblem(
        A, B, np.eye(2), np.eye(1), dt=0.1, input_constraint=None, backend=backend, solver=solver
    ).solve(FAR)
    assert free.status == "optimal" and np.isfinite(free.gamma)


def _controller(**kw) -> RMPC:
    return RMPC(PLANT, Q=np.eye(2), R=np.eye(1), u_max=0.01, **kw)


def test_step_keeps_the_last_certified_gain_on_failure():
    ctrl = _controller()
    u_near = ctrl.step(NEAR)
    assert ctrl.last.status == "optimal" and not ctrl.last.fallback
    gain = ctrl.gain
    np.testing.assert_allclose(u_near, gain @ NEAR, rtol=1e-12)
    assert np.linalg.norm(u_near) <= 0.01 + 1e-9

    u_far = ctrl.step(FAR)
    info = ctrl.last
    assert info.fallback is True
    assert info.status == "infeasible"
    assert info.gamma is None
    assert info.extra["had_gain"] is True
    assert info.extra["inside_ellipsoid"] is False
    assert info.extra["solution"].status == "infeasible"
    np.testing.assert_array_equal(ctrl.gain, gain)  # unchanged
    np.testing.assert_allclose(u_far, gain @ FAR, rtol=1e-12)

    # back in the feasible region the controller solves again
    ctrl.step(NEAR / 2)
    assert ctrl.last.status == "optimal" and not ctrl.last.fallback


def test_failure_without_a_previous_gain_applies_zero():
    ctrl = _controller()
    with pytest.warns(NoCertifiedGainWarning, match="'infeasible'.*input bound"):
        u = ctrl.step(FAR)
    assert ctrl.last.fallback and ctrl.last.extra["had_gain"] is False
    np.testing.assert_array_equal(u, np.zeros(1))
    assert ctrl.gain is None


def test_on_failure_raise():
    ctrl = _controller(on_failure="raise")
    ctrl.step(NEAR)
    with pytest.raises(SolverError) as err:
        ctrl.step(FAR)
    assert isinstance(err.value, ToolkitError) and isinstance(err.value, RuntimeError)
    assert "infeasible" in str(err.value) and "on_failure" in str(err.value)


def test_solver_stopped_early_is_a_fallback():
    """``max_iter = 2`` (no Clarabel fallback, no phase one): the IPM stops early; RMPC records it
    and falls back."""
    options = {"max_iter": 2, "fallback": False, "phase_one": False}
    ctrl = _controller(solver_options=options)
    with pytest.warns(NoCertifiedGainWarning, match="'max_iterations'.*max_iter"):
        u = ctrl.step(NEAR)
    assert ctrl.last.status == "max_iterations" and ctrl.last.fallback
    np.testing.assert_array_equal(u, np.zeros(1))
    with pytest.raises(SolverError):
        _controller(solver_options=options, on_failure="raise").step(NEAR)


def test_solver_stopped_early_with_phase_one_applies_its_certified_point():
    """The same early stop with phase one (the default): phase one's strictly feasible point is
    the answer, ``"inaccurate"`` with its certificate, and it is applied (no fallback)."""
    ctrl = _controller(solver_options={"max_iter": 2, "fallback": False})
    u = ctrl.step(NEAR)
    sol = ctrl.last.extra["solution"]
    assert ctrl.last.status == "inaccurate" and not ctrl.last.fallback, sol.solver_status
    assert sol.solver_status.startswith("ipm max_iterations; phase one feasible")
    assert sol.solver_status.endswith("phase one's point (gamma an upper bound)")
    assert sol.certificate.ok and min(sol.certificate.margins.values()) > 0.0
    np.testing.assert_allclose(u, sol.F @ NEAR, rtol=1e-12)


# -- certificates ----------------------------------------------------------------------------


def _kothare_solution(input_constraint="peak"):
    a = [[[1.0, 0.1], [0.0, 1.0 - 0.1 * al]] for al in (0.1, 10.0)]
    b = [[[0.0], [0.1 * 0.787]]] * 2
    prob = KothareProblem(
        a, b, np.diag([1.0, 0.0]), [[2e-5]], dt=0.1, input_constraint=input_constraint, u_max=2.0,
        output_matrix=[[0.0, 1.0]], y_max=0.2,
    )
    x = np.array([0.05, 0.0])
    sol = prob.solve(x)
    assert sol.status == "optimal"
    return prob, x, sol


@pytest.mark.parametrize("input_constraint", ["peak", "ellipsoid"])
def test_certificate_of_a_solution_passes(input_constraint):
    prob, x, sol = _kothare_solution(input_constraint)
    cert = certify(prob.data, x, sol.gamma, sol.Q, sol.Y)
    assert cert.ok and cert.worst >= -1e-7
    names = set(cert.margins)
    assert {"state", "vertex_0", "vertex_1", "output_0"} <= names
    assert ("input_0" in names) if input_constraint == "peak" else ("input" in names)


@pytest.mark.parametrize(
    ("corrupt", "failing"),
    [
        (lambda g, q, y: (g, 0.5 * q, y), "state"),  # x leaves the ellipsoid
        (lambda g, q, y: (0.5 * g, q, y), "vertex_0"),  # the cost bound is too small
        (lambda g, q, y: (g, q, 3.0 * y), "input_0"),  # |u| exceeds u_max
        (lambda g, q, y: (g, q, -y), "vertex_1"),  # a destabilising gain
        (lambda g, q, y: (g, q + np.diag([0.0, -2.0 * q[1, 1]]), y), "state"),  # indefinite Q
        (lambda g, q, y: (g, q, np.full_like(y, np.nan)), "finite"),
    ],
)
def test_corrupted_solution_fails_the_certificate(corrupt, failing):
    prob, x, sol = _kothare_solution("peak")
    gamma, q, y = corrupt(sol.gamma, sol.Q, sol.Y)
    cert = certify(prob.data, x, gamma, q, y)
    assert not cert.ok
    assert cert.margins[failing] < -1e-7, cert.margins


@pytest.mark.parametrize("factor", [1e-6, 1.0, 1e3])
def test_certificate_margins_do_not_depend_on_the_scale_of_the_state(factor):
    """At ``c x`` the answer is ``c^2 (gamma, Q, Y)`` and every margin is the same, so a state
    1e-4 outside its ellipsoid is caught at every scale (formed from the raw ``[[1, x'], [x, Q]]``,
    the state margin shrank like ``c^2``: at ``c = 1e-6`` the violation read as about -1e-16)."""
    prob, x, sol = _kothare_solution("peak")
    base = certify(prob.data, x, sol.gamma, sol.Q, sol.Y)
    c2 = factor**2
    scaled = certify(prob.data, factor * x, c2 * sol.gamma, c2 * sol.Q, c2 * sol.Y)
    for name, margin in base.margins.items():
        if not name.startswith(("input", "output")):  # bounds do not scale with the state
            assert scaled.margins[name] == pytest.approx(margin, rel=1e-6, abs=1e-12), name
    shrunk = (1.0 - 1e-4) * c2 * sol.Q  # x' Q^-1 x = 1 / (1 - 1e-4) > 1
    cert = certify(prob.data, factor * x, c2 * sol.gamma, shrunk, c2 * sol.Y)
    assert cert.margins["state"] < -1e-7, cert.margins


def test_tighter_output_bound_fails_the_certificate():
    """The solution at y_max = 0.2 does not certify a bound of 0.05 (the constraint is active)."""
    prob, x, sol = _kothare_solution("peak")
    tight = dataclasses.replace(prob.data, y_max=np.array([0.05]))
    cert = certify(tight, x, sol.gamma, sol.Q, sol.Y)
    assert not cert.ok and cert.margins["output_0"] < -1e-7


def test_uncertified_answer_is_never_applied(monkeypatch):
    """A back-end that returns 'Solved' with a wrong Y: status 'uncertified', RMPC falls back."""
    ctrl = _controller()
    ctrl.step(NEAR)
    gain = ctrl.gain
    backend = ctrl.problem._backend
    honest = backend.solve

    def lying(*args, **kwargs):
        raw = honest(*args, **kwargs)
        return dataclasses.replace(raw, Y=10.0 * raw.Y)

    monkeypatch.setattr(backend, "solve", lying)
    sol = ctrl.solve(NEAR / 2)
    assert sol.solver_status == "optimal"  # the default back-end's (lmi.ipm) own word
    assert sol.status == "uncertified" and not sol.certificate.ok
    u = ctrl.step(NEAR / 2)
    assert ctrl.last.fallback and ctrl.last.status == "uncertified"
    np.testing.assert_allclose(u, gain @ (NEAR / 2), rtol=1e-12)


def test_a_singular_q_is_never_certified() -> None:
    """At ``x = 0`` with ``Q = 0, Y = 0`` every LMI holds with margin 0 (within the tolerance):
    only the invertibility of ``Q`` (the gain is ``Y Q^-1``) refuses it (mutmut's survivor
    x_certify__mutmut_114 flipped that margin's sign)."""
    from lmi import build_kothare_data

    data = build_kothare_data([[[1.1]]], [[[1.0]]], [[1.0]], [[1.0]], input_constraint="peak", u_max=1.0)
    cert = certify(data, np.zeros(1), 1.0, np.zeros((1, 1)), np.zeros((1, 1)))
    assert cert.margins["Q_invertible"] == -np.inf and not cert.ok
    assert all(v >= -cert.tol for k, v in cert.margins.items() if k != "Q_invertible")
