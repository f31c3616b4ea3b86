"""Back-ends and formulations agree; output constraints hold; bad input names the argument.

Independent paths to the same optimum: the toolkit's IPM (the default, ``ref`` below), the
direct Clarabel conic data (``backend="clarabel"``), and the cvxpy formulation solved by
Clarabel and by SCS. Measured (relative differences of gamma) on the four random polytopes
below (n = 3..4, 2-3 vertices, unit-norm states) x three input constraints, and on six more
seeds (20-25, 15 feasible problems) in brackets:

- cvxpy + Clarabel and direct Clarabel against the IPM: 5.2e-8 (1.2e-7); IPM and Clarabel both
  stop at a relative gap of 1e-8. Asserted 1e-6: 8 times the largest.
- cvxpy + Clarabel against direct Clarabel (the same solver on two encodings): 1.3e-10
  (3.2e-8). Asserted 3e-7: 9 times the largest.
- SCS (eps 1e-6) against the IPM: 6.8e-6 (6.2e-6). Asserted 1e-4: 15 times the largest (SCS,
  a first-order method, converges to its residual tolerance, not to a gap).
- The three formulations: 1.1e-9 (2.8e-7). Asserted 2e-6: 7 times the largest.
- Output-constrained example (cvxpy + Clarabel against the IPM): 6.2e-8. Asserted 1e-6.

SCS at eps 1e-6 leaves relative LMI margins down to -7e-5, below the default certificate
tolerance 1e-7: it then reports "uncertified", which is asserted to match the certificate.

Output constraint on Kothare's example 1 (velocity ``|x2(k+i)| <= 0.1``, i >= 1): without it the
closed loop reaches ``|x2| = 0.2025`` (alpha = 0.1); with it ``|x2| <= 0.1`` at every step.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from lmi import KothareProblem
from models import PolytopicModel
from rmpc import RMPC, simulate
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError, ToolkitError

DT = 0.1
SCS_OPTIONS = {"eps_abs": 1e-6, "eps_rel": 1e-6, "max_iters": 50_000}


def random_polytope(seed: int, n: int, m: int, n_vertices: int):
    """ZOH vertices of a random continuous system with per-vertex perturbations of A and B."""
    rng = np.random.default_rng(seed)
    ac = rng.normal(size=(n, n))
    ac -= (np.max(np.linalg.eigvals(ac).real) + rng.uniform(-0.3, 0.5)) * np.eye(n)
    bc = rng.normal(size=(n, m))
    a_list, b_list = [], []
    for _ in range(n_vertices):
        d, s = 0.3 * rng.normal(size=(n, n)), rng.uniform(0.6, 1.4)
        big = sla.expm(np.block([[ac + d, bc * s], [np.zeros((m, n + m))]]) * DT)
        a_list.append(big[:n, :n])
        b_list.append(big[:n, n:])
    x = rng.normal(size=n)
    q = np.diag(rng.uniform(0.5, 2.0, n))
    r = np.diag(rng.uniform(0.5, 2.0, m))
    return np.array(a_list), np.array(b_list), q, r, x / np.linalg.norm(x)


#: (seed, n, m, vertices)
POLYTOPES = [(10, 3, 1, 2), (11, 4, 2, 3), (12, 3, 2, 3), (16, 4, 1, 2)]
CONSTRAINTS = [("ellipsoid", 1.0), ("peak", 0.8), (None, None)]


def _kw(constraint, m):
    kind, bound = constraint
    if kind == "peak":
        bound = np.full(m, bound)
    return {"input_constraint": kind, "u_max": bound}


@pytest.fixture(scope="module", params=POLYTOPES, ids=lambda p: f"s{p[0]}-n{p[1]}m{p[2]}v{p[3]}")
def polytope(request):
    return random_polytope(*request.param)


@pytest.mark.parametrize("constraint", CONSTRAINTS, ids=lambda c: str(c[0]))
def test_backends_agree_on_gamma(polytope, constraint):
    a, b, q, r, x = polytope
    kw = _kw(constraint, b.shape[2])
    ref = KothareProblem(a, b, q, r, dt=DT, **kw).solve(x)
    assert ref.status == "optimal"
    cvx = KothareProblem(a, b, q, r, dt=DT, backend="cvxpy", solver="CLARABEL", **kw).solve(x)
    assert cvx.status == "optimal"
    assert cvx.backend == "cvxpy:CLARABEL" and ref.backend == "ipm"
    assert abs(cvx.gamma - ref.gamma) <= 1e-6 * ref.gamma  # measured <= 1.2e-7 (module docstring)
    direct = KothareProblem(a, b, q, r, dt=DT, backend="clarabel", **kw).solve(x)
    assert direct.status == "optimal" and direct.backend == "clarabel"
    assert abs(direct.gamma - ref.gamma) <= 1e-6 * ref.gamma  # measured <= 1.2e-7
    assert abs(cvx.gamma - direct.gamma) <= 3e-7 * direct.gamma  # measured <= 3.2e-8
    scs = KothareProblem(
        a, b, q, r, dt=DT, backend="cvxpy", solver="SCS", solver_options=SCS_OPTIONS, **kw
    ).solve(x)
    # SCS converged; at eps 1e-6 its LMI margins may miss the 1e-7 certificate tolerance
    assert scs.solver_status == "optimal", scs.solver_status
    assert scs.status in ("optimal", "uncertified")
    assert (scs.status == "optimal") == scs.certificate.ok
    assert scs.certificate.worst >= -1e-3
    assert abs(scs.gamma - ref.gamma) <= 1e-4 * ref.gamma  # measured <= 6.8e-6
    # the constraint costs something: gamma(none) <= gamma(ellipsoid) and gamma(peak)
    if constraint[0] is not None:
        free = KothareProblem(a, b, q, r, dt=DT, input_constraint=None).solve(x)
        assert free.gamma <= ref.gamma * (1 + 1e-6)


@pytest.mark.parametrize("constraint", CONSTRAINTS, ids=lambda c: str(c[0]))
def test_formulations_agree(polytope, constraint):
    a, b, q, r, x = polytope
    kw = _kw(constraint, b.shape[2])
    gammas = {}
    for formulation in ("delta", "delta_shared", "standard"):
        sol = KothareProblem(a, b, q, r, dt=DT, formulation=formulation, **kw).solve(x)
        assert sol.status == "optimal", (formulation, sol.status)
        gammas[formulation] = sol.gamma
    ref = gammas["standard"]
    for formulation, gamma in gammas.items():
        assert abs(gamma - ref) <= 2e-6 * ref, (formulation, gammas)  # measured <= 2.8e-7


def test_delta_scaling_is_exact_for_any_dt():
    """The delta formulation divides by dt internally; any positive dt gives the same optimum."""
    a, b, q, r, x = random_polytope(10, 3, 1, 2)
    gammas = [KothareProblem(a, b, q, r, dt=dt, u_max=1.0).solve(x).gamma for dt in (0.1, 1.0, 0.01)]
    # measured 8.8e-10 apart; asserted 1e-7, ten times the IPM's stopping gap (1e-8 relative)
    assert max(gammas) - min(gammas) <= 1e-7 * min(gammas)


# -- output constraints -----------------------------------------------------------------------


def _kothare(alpha: float):
    return np.array([[1.0, 0.1], [0.0, 1.0 - 0.1 * alpha]]), np.array([[0.0], [0.1 * 0.787]])


KOTHARE = PolytopicModel([_kothare(0.1), _kothare(10.0)], dt=DT)
K_WEIGHTS = {"Q": np.diag([1.0, 0.0]), "R": [[2e-5]], "u_max": 2.0, "input_constraint": "peak"}


@pytest.mark.parametrize("alpha", [0.1, 1.0])
def test_output_constraint_holds_on_closed_loop(alpha):
    x0 = np.array([0.05, 0.0])
    free = simulate(RMPC(KOTHARE, **K_WEIGHTS), KOTHARE, x0, n_steps=100, true_plant=_kothare(alpha))
    assert np.max(np.abs(free.x[:, 1])) > 0.17  # the constraint below is active
    ctrl = RMPC(KOTHARE, **K_WEIGHTS, output_matrix=[[0.0, 1.0]], y_max=0.1)
    traj = simulate(ctrl, KOTHARE, x0, n_steps=100, true_plant=_kothare(alpha))
    assert set(traj.status) <= {"optimal", "reused"}
    assert np.max(np.abs(traj.x[:, 1])) <= 0.1 * (1 + 1e-6)
    assert np.max(np.abs(traj.u_cmd)) <= 2.0 + 1e-6
    assert np.linalg.norm(traj.x[-1]) < 1e-10
    for info in traj.info:
        sol = info.extra.get("solution")
        if sol is not None:
            assert sol.margins["output_0"] >= -1e-7


def test_output_constraint_backends_agree():
    x0 = np.array([0.05, 0.0])
    kw = {"dt": DT, "input_constraint": "peak", "u_max": 2.0, "output_matrix": [[0.0, 1.0]], "y_max": 0.1}
    args = (KOTHARE.A, KOTHARE.B, np.diag([1.0, 0.0]), [[2e-5]])
    ref = KothareProblem(*args, **kw).solve(x0)
    cvx = KothareProblem(*args, backend="cvxpy", **kw).solve(x0)
    free = KothareProblem(*args, dt=DT, input_constraint="peak", u_max=2.0).solve(x0)
    assert ref.status == cvx.status == "optimal"
    assert ref.backend == "ipm" and cvx.backend == "cvxpy:CLARABEL"
    assert abs(cvx.gamma - ref.gamma) <= 1e-6 * ref.gamma  # measured 6.2e-8
    assert ref.gamma > 1.5 * free.gamma  # measured 1.974e-2 vs 9.716e-3


# -- options, back-ends, solvers --------------------------------------------------------------

A1 = np.array([[1.0, 0.1], [0.0, 0.9]])
B1 = np.array([[0.0], [0.1]])
GOOD = {"A": A1, "B": B1, "Q": np.eye(2), "R": np.eye(1), "dt": 0.1, "u_max": 1.0}


def _assert_names(err: pytest.ExceptionInfo, argument: str, base: type) -> None:
    assert isinstance(err.value, ToolkitError)
    assert isinstance(err.value, base)
    assert err.value.argument == argument
    assert str(err.value).startswith(f"{argument}:")
    assert "expected" in str(err.value) and "found" in str(err.value)


@pytest.mark.parametrize(
    "kw",
    [
        {"solver_options": {"bogus_setting": 1}},
        {"backend": "cvxpy", "solver_options": {"bogus_setting": 1}},
        {"backend": "cvxpy", "solver": "SCS", "solver_options": {"bogus_setting": 1}},
        {"backend": "cvxpy", "solver": "SCS", "solver_options": {"max_iter": 10}},  # Clarabel's name
        {"backend": "cvxpy", "solver": "OSQP", "solver_options": {"eps_abs": 1e-3}},
        {"solver_options": ["tol_feas", 1e-9]},
    ],
)
def test_unknown_solver_options_raise(kw):
    with pytest.raises(InvalidArgumentError) as err:
        KothareProblem(**{**GOOD, **kw})
    _assert_names(err, "solver_options", ValueError)
    if isinstance(kw["solver_options"], dict):
        assert repr(next(iter(kw["solver_options"]))) in str(err.value)  # names the bad key


def test_bad_solver_option_value_names_the_option():
    with pytest.raises(InvalidArgumentError) as err:
        KothareProblem(**GOOD, solver_options={"max_iter": "many"})
    assert err.value.argument.startswith("solver_options")
    assert "max_iter" in str(err.value)


@pytest.mark.parametrize("backend", ["clarabel", "ipm"])
def test_known_solver_options_are_applied(backend):
    # (the IPM's phase one, which would add its iterations after the failure, is off here)
    options = {"max_iter": 2} if backend == "clarabel" else {"max_iter": 2, "fallback": False,
                                                             "phase_one": False}
    prob = KothareProblem(**GOOD, backend=backend, solver_options=options)
    sol = prob.solve([1.0, 0.0])
    assert sol.status == "max_iterations" and sol.iterations == 2


def test_ipm_failure_is_resolved_by_the_clarabel_fallback():
    """With ``max_iter = 2`` the IPM stops early; phase one finds a strictly feasible point, so
    the default fallback hands the state to Clarabel.

    The fallback solves the IPM's conic data, which are in the coordinates of
    :func:`lmi.scaling.state_scaling`: the same problem as Clarabel's own back-end, so ``gamma``
    agrees to Clarabel's tolerance; without the scaling the data are identical, and so is
    ``gamma``."""
    ref = KothareProblem(**GOOD, backend="clarabel").solve([1.0, 0.0])
    for scaling, rel in ((True, 1e-7), (False, 1e-12)):
        opts = {"max_iter": 2, "state_scaling": scaling}
        sol = KothareProblem(**GOOD, solver_options=opts).solve([1.0, 0.0])
        assert sol.status == "optimal"
        assert sol.solver_status == "ipm max_iterations; phase one feasible; clarabel Solved"
        assert sol.gamma == pytest.approx(ref.gamma, rel=rel)


@pytest.mark.parametrize(
    ("kw", "argument"),
    [
        ({"backend": "mosek"}, "backend"),
        ({"backend": "CVXPY"}, "backend"),
        ({"backend": "cvxpy", "solver": "NO_SUCH_SOLVER"}, "solver"),
        ({"backend": "clarabel", "solver": "SCS"}, "solver"),
    ],
)
def test_unknown_backend_or_solver_raise(kw, argument):
    with pytest.raises(InvalidArgumentError) as err:
        KothareProblem(**{**GOOD, **kw})
    _assert_names(err, argument, ValueError)


def test_a_solver_without_sdp_support_is_a_status_not_a_crash():
    sol = KothareProblem(**GOOD, backend="cvxpy", solver="OSQP").solve([1.0, 0.0])
    assert sol.status == "solver_error"
    assert np.isnan(sol.gamma) and sol.F is None and not sol.ok


# -- bad inputs -------------------------------------------------------------------------------

BAD_PROBLEM = [
    ({"Q": np.diag([1.0, -1.0])}, "Q", ValueError),
    ({"Q": [[1.0, 0.5], [0.0, 1.0]]}, "Q", ValueError),
    ({"Q": np.eye(3)}, "Q", ValueError),
    ({"Q": [[np.nan, 0.0], [0.0, 1.0]]}, "Q", ValueError),
    ({"R": [[0.0]]}, "R", ValueError),
    ({"R": [[-1.0]]}, "R", ValueError),
    ({"R": np.eye(2)}, "R", ValueError),
    ({"A": np.ones((2, 3))}, "A", ValueError),
    ({"A": [[np.nan, 0.0], [0.0, 1.0]]}, "A", ValueError),
    ({"A": [[np.inf, 0.0], [0.0, 1.0]]}, "A", ValueError),
    ({"A": np.zeros((0, 2, 2)), "B": np.zeros((0, 2, 1))}, "A", ValueError),
    ({"B": np.ones((3, 1))}, "B", ValueError),
    ({"B": [[0.0], [np.nan]]}, "B", ValueError),
    ({"u_max": 0.0}, "u_max", ValueError),
    ({"u_max": -1.0}, "u_max", ValueError),
    ({"u_max": np.nan}, "u_max", ValueError),
    ({"u_max": [1.0, 2.0]}, "u_max", ValueError),  # the ellipsoid bound is a scalar
    ({"input_constraint": "peak", "u_max": [-1.0]}, "u_max", ValueError),
    ({"input_constraint": "peak", "u_max": [1.0, 1.0]}, "u_max", ValueError),
    ({"input_constraint": "box"}, "input_constraint", ValueError),
    ({"u_max": None}, "u_max", ValueError),
    ({"input_constraint": "peak", "u_max": None}, "u_max", ValueError),
    ({"input_constraint": None}, "u_max", ValueError),  # a bound without a constraint
    ({"dt": 0.0}, "dt", ValueError),
    ({"formulation": "lifted"}, "formulation", ValueError),
    ({"certificate_tol": -1.0}, "certificate_tol", ValueError),
    ({"output_matrix": np.eye(2)}, "output_matrix", ValueError),
    ({"output_matrix": np.eye(3), "y_max": 1.0}, "output_matrix", ValueError),
    ({"output_matrix": np.eye(2), "y_max": [1.0, -1.0]}, "y_max", ValueError),
    ({"Q": "identity"}, "Q", TypeError),
]


@pytest.mark.parametrize(("kw", "argument", "base"), BAD_PROBLEM, ids=lambda v: None)
def test_bad_problem_data_names_the_argument(kw, argument, base):
    with pytest.raises((InvalidArgumentError, ArgumentTypeError)) as err:
        KothareProblem(**{**GOOD, **kw})
    _assert_names(err, argument, base)


@pytest.mark.parametrize(
    "x", [[0.0, 0.0], [np.nan, 1.0], [np.inf, 1.0], [1.0, 0.0, 0.0], np.eye(2)],
)
def test_bad_state_names_x(x):
    prob = KothareProblem(**GOOD)
    with pytest.raises(InvalidArgumentError) as err:
        prob.solve(x)
    _assert_names(err, "x", ValueError)


PLANT = PolytopicModel([(A1, B1)], dt=0.1)
RMPC_GOOD = {"Q": np.eye(2), "R": np.eye(1), "u_max": 1.0}
BAD_RMPC = [
    ({"Q": np.diag([1.0, -1.0])}, "Q", ValueError),
    ({"R": [[0.0]]}, "R", ValueError),
    ({"Q": np.eye(3)}, "Q", ValueError),
    ({"u_max": -1.0}, "u_max", ValueError),
    ({"u_max": 0.0}, "u_max", ValueError),
    ({"input_constraint": "foo"}, "input_constraint", ValueError),
    ({"u_max": None, "input_constraint": "peak"}, "u_max", ValueError),
    ({"u_max": None, "input_constraint": "ellipsoid"}, "u_max", ValueError),
    ({"x_ref": [1.0, 1.0]}, "x_ref", ValueError),  # A x_ref != x_ref
    ({"x_ref": [1.0, 0.0, 0.0]}, "x_ref", ValueError),
    ({"x_ref": [np.nan, 0.0]}, "x_ref", ValueError),
    ({"on_failure": "ignore"}, "on_failure", ValueError),
    ({"resolve_threshold": 1.5}, "resolve_threshold", ValueError),
    ({"resolve_threshold": 0.0}, "resolve_threshold", ValueError),
    ({"hold_radius": -1.0}, "hold_radius", ValueError),
    ({"backend": "nope"}, "backend", ValueError),
    ({"solver_options": {"bogus": 1}}, "solver_options", ValueError),
]


@pytest.mark.parametrize(("kw", "argument", "base"), BAD_RMPC, ids=lambda v: None)
def test_bad_rmpc_arguments_name_the_argument(kw, argument, base):
    with pytest.raises((InvalidArgumentError, ArgumentTypeError)) as err:
        RMPC(PLANT, **{**RMPC_GOOD, **kw})
    _assert_names(err, argument, base)


def test_rmpc_needs_a_polytope():
    with pytest.raises(ArgumentTypeError) as err:
        RMPC((A1, B1), **RMPC_GOOD)
    _assert_names(err, "plant", TypeError)


@pytest.mark.parametrize("x", [[np.nan, 0.0], [np.inf, 0.0], [1.0]])
def test_rmpc_bad_state_names_x(x):
    ctrl = RMPC(PLANT, **RMPC_GOOD)
    for method in (ctrl.step, ctrl.solve):
        with pytest.raises(InvalidArgumentError) as err:
            method(x)
        _assert_names(err, "x", ValueError)


def test_rmpc_solve_at_the_reference_raises_but_step_holds():
    ctrl = RMPC(PLANT, **RMPC_GOOD, x_ref=[1.0, 0.0])  # an equilibrium: A [1, 0]' = [1, 0]'
    with pytest.raises(InvalidArgumentError) as err:
        ctrl.solve([1.0, 0.0])
    _assert_names(err, "x", ValueError)
    u = ctrl.step([1.0, 0.0])  # at the reference: nothing to do, no solve
    assert np.array_equal(u, [0.0]) and ctrl.last.status == "reused"
    u = ctrl.step([1.5, 0.0])  # regulates the deviation x - x_ref
    sol = ctrl.last.extra["solution"]
    assert sol.ok and np.allclose(sol.x, [0.5, 0.0])
    np.testing.assert_allclose(u, sol.F @ [0.5, 0.0], rtol=1e-12)
