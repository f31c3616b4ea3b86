"""The off-line nested design on the toolkit's interior-point method (``backend="ipm"``, default).

The nesting ``Q_outer - Q >= 0`` is one more block of the on-line problem's conic data
(:class:`lmi.backends.ipm.IPMKothare` with ``nesting=True``). The solver works at the normalised
state and in its own coordinates ``x~ = T^-1 x`` (the diagonal state scaling, or the full factor
of a rebalanced retry), so ``Q_outer`` must reach it as ``T^-1 (Q_outer / ||x||^2) T^-T /
||T^-1 x / ||x||| |^2``. Checked here on a nesting constraint that binds (Kothare's example 1,
as in ``test_lmi_offline_nesting``): the answer in every coordinate system is the same, agrees
with the independent cvxpy construction, and is certified with a non-negative recomputed nesting
margin. Also: the first ellipsoid is exactly the on-line problem's answer; whole designs agree
with cvxpy per ellipsoid; a solver answer outside the outer ellipsoid is caught by the recomputed
margin; a design state outside the outer ellipsoid is proved infeasible (the Farkas check sees
the nesting block); without the nesting block the conic data are those of the on-line problem.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from lmi import KothareProblem
from lmi.affine import svec_matrix
from lmi.backends.base import RawResult
from lmi.backends.conic import KothareConic
from lmi.backends.ipm import IPMKothare
from lmi.data import build_kothare_data
from lmi.offline import NestedEllipsoid, NestedKothareProblem, nesting_margin
from lmi.status import INFEASIBLE, NUMERICAL_ERROR, OPTIMAL, UNCERTIFIED
from models import RigidSatellite
from toolkit_common.errors import InvalidArgumentError

# Kothare (1996), example 1
A = [[[1, 0.1], [0, 1 - 0.1 * a]] for a in (0.1, 10.0)]
B = [[[0.0], [0.1 * 0.787]]] * 2
KW = {"Q": np.diag([1.0, 0.0]), "R": [[2e-5]], "dt": 0.1, "input_constraint": "peak", "u_max": 2.0}
X_OUTER = np.array([0.05, 0.0])
X_INNER = np.array([0.025, 0.0])
#: A full (non-diagonal) change of coordinates, as a rebalanced retry makes.
T_FULL = np.array([[0.5, 0.2], [-0.1, 1.3]])

#: ipm against cvxpy + Clarabel (both stopping at relative gaps of 1e-8): measured at most
#: 3.0e-7 relative over the 10 ellipsoids of Kothare's example 1 and 2.3e-8 over 6 of paper P's
#: (2 vertices); 1.2e-7 on the binding case below. Asserted 1e-6, as between the on-line
#: back-ends (test_lmi_backends_agree).
RTOL_CVXPY = 1e-6
#: ipm against itself in other coordinates: measured 1.4e-9 relative on the binding case
#: (identity, diagonal and full coordinates); asserted 1e-7, ten times the solver's relative gap.
RTOL_COORDINATES = 1e-7


def _problem(**extra) -> NestedKothareProblem:
    return NestedKothareProblem(A, B, **KW, **extra)


@pytest.fixture(scope="module")
def binding_outer() -> NestedEllipsoid:
    """The ellipsoid designed at ``X_OUTER`` shrunk to 0.3 of itself: it still holds ``X_INNER``,
    and the free ellipsoid at ``X_INNER`` is not inside it (the nesting binds)."""
    designed = _problem().solve(X_OUTER)
    assert designed.ok
    outer = dataclasses.replace(designed, Q=0.3 * designed.Q)
    assert X_INNER @ np.linalg.solve(outer.Q, X_INNER) < 1.0
    free = _problem().solve(X_INNER)
    assert free.ok and nesting_margin(outer.Q, free.Q) < -0.1
    return outer


@pytest.fixture(scope="module")
def cvxpy_nested(binding_outer) -> NestedEllipsoid:
    entry = _problem(backend="cvxpy").solve(X_INNER, binding_outer)
    assert entry.ok, entry.status
    return entry


def _ipm_in(coordinates: str) -> NestedKothareProblem:
    if coordinates == "identity":
        prob = _problem(solver_options={"state_scaling": False})
        assert np.array_equal(prob._nest._t, np.ones(2))
    else:
        prob = _problem()
        assert not np.allclose(prob._nest._t, 1.0)  # the diagonal scaling is in use
        if coordinates == "full":
            prob._nest._build(T_FULL)  # the coordinates a rebalanced retry leaves behind
    return prob


@pytest.mark.parametrize("coordinates", ["identity", "diagonal", "full"])
def test_the_outer_ellipsoid_reaches_the_solver_in_its_coordinates(coordinates, binding_outer,
                                                                   cvxpy_nested) -> None:
    prob = _ipm_in(coordinates)
    assert prob.backend == "ipm"
    entry = prob.solve(X_INNER, binding_outer)
    assert entry.status == OPTIMAL, entry.solver_status
    assert entry.solver_status == "optimal"  # the ipm's own answer (no fallback stage)
    assert entry.certificate is not None and entry.certificate.ok
    assert entry.nesting_margin == nesting_margin(binding_outer.Q, entry.Q)
    assert -prob.certificate_tol <= entry.nesting_margin < 1e-6  # inside, and the nesting binds
    assert entry.gamma == pytest.approx(cvxpy_nested.gamma, rel=RTOL_CVXPY)
    reference = _ipm_in("identity").solve(X_INNER, binding_outer)
    assert entry.gamma == pytest.approx(reference.gamma, rel=RTOL_COORDINATES)
    assert entry.iterations is not None and entry.iterations > 0


def test_the_first_ellipsoid_is_the_online_answer_bit_for_bit() -> None:
    online = KothareProblem(A, B, **KW).solve(X_OUTER)
    table = _problem().design_ray(X_OUTER, 3, 0.5)
    first = table.ellipsoids[0]
    assert first.gamma == online.gamma
    np.testing.assert_array_equal(first.Q, online.Q)
    np.testing.assert_array_equal(first.F, online.F)


def test_a_design_does_not_depend_on_the_designs_before_it() -> None:
    """Every design starts from a reset back-end (no warm start left over): designing twice gives
    the same table, bit for bit."""
    prob = _problem()
    first = prob.design_ray(X_OUTER, 4, 0.5)
    prob.design_ray(0.7 * X_OUTER, 4, 0.5)
    again = prob.design_ray(X_OUTER, 4, 0.5)
    np.testing.assert_array_equal(again.gammas, first.gammas)
    for a, b in zip(again.ellipsoids, first.ellipsoids, strict=True):
        np.testing.assert_array_equal(a.Q, b.Q)


@pytest.mark.parametrize("case", ["kothare", "paper_p"])
def test_whole_designs_agree_with_cvxpy_per_ellipsoid(case) -> None:
    if case == "kothare":
        args, x1, count = {"A": A, "B": B, **KW}, X_OUTER, 10
    else:
        sat = RigidSatellite.paper_p()
        x1 = sat.initial_state()
        poly = sat.polytope(x1, dt=0.01, spread=0.3, mode="scalar")
        args = {"A": poly.A, "B": poly.B, "Q": np.diag([1, 1, 1, 0.1, 0.1, 0.1]), "R": np.eye(3),
                "dt": poly.dt, "u_max": 1.0}
        count = 6
    ipm = NestedKothareProblem(**args).design_ray(x1, count, 0.5)
    ref = NestedKothareProblem(**args, backend="cvxpy").design_ray(x1, count, 0.5)
    assert ipm.stop_reason == ref.stop_reason == "complete"
    assert ipm.n_ellipsoids == ref.n_ellipsoids == count
    np.testing.assert_allclose(ipm.gammas, ref.gammas, rtol=RTOL_CVXPY)
    for e in ipm.ellipsoids[1:]:
        assert e.ok and e.nesting_margin >= -1e-7


def test_an_answer_outside_the_outer_ellipsoid_is_not_certified(monkeypatch) -> None:
    """The solver is not trusted: its answer scaled by 6 (``Q``, ``Y`` and ``gamma``; without an
    input bound the Kothare LMIs are homogeneous and still hold, the state LMI with room) lies
    outside ``Q_outer``, and only the recomputed nesting margin catches it. (Unconstrained, the
    optimum at ``X_INNER = X_OUTER / 2`` is the outer one divided by 4: scaled by 6 it is 1.5 times
    the outer ellipsoid.)"""
    prob = NestedKothareProblem(A, B, **{**KW, "input_constraint": None, "u_max": None})
    outer = prob.solve(X_OUTER)
    true = prob.solve(X_INNER, outer)
    assert outer.ok and true.ok
    s2 = float(X_INNER @ X_INNER)
    tampered = RawResult(OPTIMAL, "optimal", 6 * true.gamma / s2, 6 * true.Q / s2, 6 * true.Y / s2, 7,
                         0.0)
    monkeypatch.setattr(prob._nest, "solve", lambda *args, **kwargs: tampered)
    entry = prob.solve(X_INNER, outer)
    assert entry.certificate is not None and entry.certificate.ok  # the Kothare LMIs hold
    assert entry.nesting_margin < -0.1
    assert entry.status == UNCERTIFIED and not entry.ok


def test_a_failed_ipm_solve_comes_back_as_a_status(binding_outer, monkeypatch) -> None:
    prob = _problem()
    failed = RawResult(NUMERICAL_ERROR, "ipm insufficient_progress (injected)", np.nan, None, None, 40, 0.1)
    monkeypatch.setattr(prob._nest, "solve", lambda *args, **kwargs: failed)
    entry = prob.solve(X_INNER, binding_outer)
    assert entry.status == NUMERICAL_ERROR and entry.Q is None and np.isnan(entry.gamma)
    assert entry.solver_status == "ipm insufficient_progress (injected)" and entry.iterations == 40
    table = prob.design(np.array([X_OUTER, X_INNER]))
    assert table.n_ellipsoids == 1 and table.failed_status == NUMERICAL_ERROR


def test_a_design_state_outside_the_outer_ellipsoid_is_proved_infeasible(binding_outer) -> None:
    """No Q <= Q_outer holds a state with x' Q_outer^-1 x > 1: the ipm proves it, and its Farkas
    certificate is checked on conic data that include the nesting block's constant."""
    x_far = 1.5 * X_OUTER
    assert x_far @ np.linalg.solve(binding_outer.Q, x_far) > 1.0
    entry = _problem().solve(x_far, binding_outer)
    assert entry.status == INFEASIBLE, entry.solver_status
    assert entry.solver_status == "ipm infeasible"  # proved by the ipm's own run, not the fallback
    assert entry.Q is None


def test_without_the_nesting_block_the_conic_data_are_the_online_ones() -> None:
    data = build_kothare_data(A, B, **KW)
    plain, nested = KothareConic(data), KothareConic(data, nesting=True)
    assert len(nested.cones) == len(plain.cones) + 1
    np.testing.assert_array_equal(nested.offsets[:-1], plain.offsets)
    rows = plain.offsets[-1]
    assert (nested.A[:rows] != plain.A).nnz == 0
    np.testing.assert_array_equal(nested.b_static[:rows], plain.b_static)
    q_out = np.array([[2.0, 0.3], [0.3, 1.0]])
    x = np.array([0.6, 0.8])
    np.testing.assert_array_equal(nested.b_vector(x, q_out)[:rows], plain.b_vector(x))
    # the block reads Q_outer - Q: at z holding Q = Q_outer / 2 its slack is Q_outer / 2
    z = np.zeros(nested.n_vars)
    z[1:1 + nested.n_q] = [1.0, 0.15, 0.5]  # svec order of Q: (0,0), (0,1), (1,1)
    q_half = nested.q_affine.value(z)
    np.testing.assert_allclose(q_half, q_out / 2)
    slack = (nested.b_vector(x, q_out) - nested.A @ z)[rows:]
    np.testing.assert_allclose(slack, svec_matrix(q_out / 2))


def test_outer_is_required_with_the_nesting_block_and_refused_without() -> None:
    data = build_kothare_data(A, B, **KW)
    x, u, y = np.array([1.0, 0.0]), data.u_max / 0.05, data.y_max
    with pytest.raises(InvalidArgumentError, match="outer"):
        IPMKothare(data, nesting=True).solve(x, u, y)
    with pytest.raises(InvalidArgumentError, match="outer"):
        IPMKothare(data).solve(x, u, y, np.eye(2))
    with pytest.raises(InvalidArgumentError, match="outer"):
        KothareConic(data, nesting=True).b_vector(x)


@pytest.mark.parametrize(("kwargs", "name"), [({"backend": "nope"}, "backend"),
                                              ({"backend": "ipm", "solver": "SCS"}, "solver"),
                                              ({"backend": "clarabel", "solver": "SCS"}, "solver")])
def test_bad_backend_arguments_name_the_argument(kwargs, name) -> None:
    with pytest.raises(InvalidArgumentError, match=name):
        _problem(**kwargs)


def test_the_clarabel_backend_solves_the_same_nested_problem(binding_outer, cvxpy_nested) -> None:
    entry = _problem(backend="clarabel").solve(X_INNER, binding_outer)
    assert entry.ok and entry.nesting_margin >= -1e-7
    assert entry.gamma == pytest.approx(cvxpy_nested.gamma, rel=RTOL_CVXPY)
