"""Infeasibility as a status: the IPM's Farkas ray, its phase one and the independently checked
certificate.

* The closed-form infeasible problem of ``test_lmi_failures`` (``x1(k+1) = 1.5 x1(k) + u``,
  ``|u| <= 0.01``, ``x1 = 10``: ``|x1|`` grows for every admissible input) comes back
  ``"infeasible"`` from the IPM's main run itself (no phase one, no Clarabel fallback) with a
  certificate that :func:`lmi.infeasibility.check_farkas` accepts; with the ray test off
  (``infeasibility_radius = inf``) phase one proves it; cvxpy + Clarabel at 1e-9 says
  infeasible too.
* A certificate tampered with (sign flipped, a block made indefinite, checked against another
  state inside the region) fails the check.
* Infeasible stress problems (infeasible by construction, :mod:`dev.stress`) are proved
  infeasible; on feasible ones phase one finds a strictly feasible point, and a solve forced to
  fail (``max_iter = 2``) is never called infeasible.
* Bad settings still raise naming the argument.
"""

from __future__ import annotations

import numpy as np
import pytest

from dev.stress import make_problem
from lmi import KothareProblem
from lmi.infeasibility import MIN_RADIUS, check_farkas
from toolkit_common.errors import InvalidArgumentError

A = np.diag([1.5, 0.9])
B = np.array([[1.0], [1.0]])
FAR = np.array([10.0, 1.0])
NEAR = np.array([0.01, 0.0])


def _problem(constraint: str, **kw) -> KothareProblem:
    return KothareProblem(A, B, np.eye(2), np.eye(1), dt=0.1, input_constraint=constraint, u_max=0.01, **kw)


@pytest.mark.parametrize("constraint", ["ellipsoid", "peak"])
def test_closed_form_infeasible_state_is_proved_by_the_ipm(constraint):
    sol = _problem(constraint).solve(FAR)
    assert sol.status == "infeasible", sol.solver_status
    assert sol.solver_status == "ipm infeasible"  # the main run's ray: no phase one, no fallback
    cert = sol.infeasibility
    assert cert is not None and cert.ok
    assert cert.objective < 0.0 and cert.radius >= MIN_RADIUS and cert.min_eigenvalue >= 0.0
    assert np.isnan(sol.gamma) and sol.Q is None
    # the ray test off: phase one proves it
    slow = _problem(constraint, solver_options={"infeasibility_radius": np.inf}).solve(FAR)
    assert slow.status == "infeasible" and slow.infeasibility.ok
    assert slow.solver_status.endswith("phase one infeasible") and "clarabel" not in slow.solver_status
    assert slow.iterations > sol.iterations
    ref = _problem(constraint, backend="cvxpy", solver="CLARABEL",
                   solver_options={"tol_feas": 1e-9, "tol_gap_abs": 1e-9, "tol_gap_rel": 1e-9}).solve(FAR)
    assert ref.status == "infeasible"


def _certificate_parts():
    prob = _problem("peak")
    sol = prob.solve(FAR)
    backend = prob._backend
    xs = FAR / np.linalg.norm(FAR)
    u = prob.data.u_max / np.linalg.norm(FAR)
    y_max = prob.data.y_max
    return backend, sol, backend.conic.a_matrix(u, y_max), backend.conic.b_vector(xs), u, y_max


def prob_bound(x):
    return np.array([0.01]) / np.linalg.norm(x)


def _cones(backend):
    import clarabel

    out = []
    for cone, rows in zip(backend.conic.cones, backend._block_rows, strict=True):
        size = rows.stop - rows.start
        if isinstance(cone, clarabel.PSDTriangleConeT):
            out.append(("psd", round((np.sqrt(8 * size + 1) - 1) / 2)))
        else:
            out.append(("nonneg", size))
    return out


def test_tampered_certificate_fails_the_independent_check():
    backend, sol, a_mat, b, u, y_max = _certificate_parts()
    cones = _cones(backend)
    y = sol.infeasibility.y
    assert check_farkas(a_mat, b, cones, y).ok
    assert not check_farkas(a_mat, b, cones, -y).ok  # sign flipped: no longer in the cone
    # the state block (first cone) made indefinite
    k = cones[0][1]
    bad = y.copy()
    rows, cols = np.triu_indices(k)
    order = np.lexsort((rows, cols))  # svec order: column by column
    diag = np.flatnonzero(rows[order] == cols[order])
    bad[diag[0]] -= 10.0 * float(np.max(np.abs(y)))
    got = check_farkas(a_mat, b, cones, bad)
    assert got.min_eigenvalue < 0.0 and not got.ok
    # the wrong data: a state inside the region (normalised, with its own normalised bound;
    # the problem there is feasible, so no multipliers can pass)
    assert _problem("peak").solve(NEAR).status == "optimal"
    b_near = backend.conic.b_vector(NEAR / np.linalg.norm(NEAR))
    near = check_farkas(backend.conic.a_matrix(prob_bound(NEAR), y_max), b_near, cones, y)
    assert not near.ok
    # the wrong data: the bound ten times larger
    other = check_farkas(backend.conic.a_matrix(10.0 * u, y_max), b, cones, y)
    assert not other.ok
    with pytest.raises(InvalidArgumentError, match="y"):
        check_farkas(a_mat, b, cones, y[:-1])
    with pytest.raises(InvalidArgumentError, match="cones"):
        check_farkas(a_mat, b, [("box", 3)], y)


@pytest.mark.parametrize(("n", "vertices", "seed"), [(4, 2, 0), (4, 4, 1), (6, 2, 2)])
def test_stress_problems_are_classified_as_known(n, vertices, seed):
    constraint = "peak" if seed % 2 == 0 else "ellipsoid"
    bad = make_problem(n, 2, vertices, "infeasible", seed, constraint)
    sol = KothareProblem(**bad.kothare_kwargs()).solve(bad.x)
    assert sol.status == "infeasible" and sol.infeasibility.ok, sol.solver_status
    good = make_problem(n, 2, vertices, "feasible", seed, constraint)
    prob = KothareProblem(**good.kothare_kwargs(), solver_options={"max_iter": 2, "fallback": False})
    forced = prob.solve(good.x)  # the main run fails; phase one must not call it infeasible
    # ... it finds a strictly feasible point, which (mixed into the stopped run's last iterate)
    # gives a certified answer without the fallback, its gamma an upper bound on the optimum
    assert forced.status == "inaccurate" and forced.certificate.ok, forced.solver_status
    assert "; phase one feasible; " in forced.solver_status
    assert "phase one's point" in forced.solver_status
    assert forced.solver_status.endswith("(gamma an upper bound)")
    best = KothareProblem(**good.kothare_kwargs()).solve(good.x)
    assert best.status == "optimal" and forced.gamma >= best.gamma * (1.0 - 1e-7)


def test_phase_one_setting_is_checked():
    with pytest.raises(InvalidArgumentError, match="phase_one"):
        _problem("peak", solver_options={"phase_one": 1})
    off = _problem("peak", solver_options={"phase_one": False, "infeasibility_radius": np.inf}).solve(FAR)
    assert off.status == "infeasible" and "clarabel" in off.solver_status and off.infeasibility is None
    # phase one off, the ray on: the main run proves it by itself
    ray = _problem("peak", solver_options={"phase_one": False}).solve(FAR)
    assert ray.solver_status == "ipm infeasible" and ray.infeasibility.ok


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, True, "1e8"])
def test_infeasibility_radius_setting_is_checked(bad):
    with pytest.raises(InvalidArgumentError, match="infeasibility_radius"):
        _problem("peak", solver_options={"infeasibility_radius": bad})


def test_a_radius_beyond_reach_leaves_the_proof_to_phase_one():
    """A ray must prove the radius asked for: at 1e300 the main run cannot, phase one does (its
    check asks :data:`~lmi.infeasibility.MIN_RADIUS`)."""
    sol = _problem("peak", solver_options={"infeasibility_radius": 1e300}).solve(FAR)
    assert sol.status == "infeasible" and sol.solver_status.endswith("phase one infeasible")


def test_a_ray_that_fails_the_independent_check_is_not_called_infeasible(monkeypatch):
    """The main run's proof is checked on the conic data; a check that fails (here: made against
    a bound ten times larger, on which the multipliers prove nothing) leaves the solve failed."""
    prob = _problem("peak", solver_options={"phase_one": False})
    backend = prob._backend
    check = backend.farkas_check

    def wrong_data(z_blocks, xs, u_max, y_max):
        return check(z_blocks, xs, 10.0 * u_max, y_max)

    monkeypatch.setattr(backend, "farkas_check", wrong_data)
    sol = prob.solve(FAR)
    assert sol.solver_status.startswith("ipm infeasible (unchecked); clarabel"), sol.solver_status
    assert sol.infeasibility is None


def test_a_weak_ray_is_refused_with_its_radius() -> None:
    """``b'y = -1`` and ``||A'y|| = 1e-3``: no solution of norm below ``1 / 1e-3 = 1e3`` only,
    far below :data:`MIN_RADIUS`; the certificate says so and is refused (a residual below 1 is
    no exemption; the mutation test found that gap)."""
    got = check_farkas(np.array([[1e-3]]), np.array([-1.0]), [("nonneg", 1)], np.array([1.0]))
    assert got.radius == pytest.approx(1e3)
    assert not got.ok
    strong = check_farkas(np.array([[1e-12]]), np.array([-1.0]), [("nonneg", 1)], np.array([1.0]))
    assert strong.radius == pytest.approx(1e12) and strong.ok
