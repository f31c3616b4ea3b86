"""Every QP back-end on the same problems, checked by certificates and a high-accuracy reference.

The reference is :func:`rmpc.qp.reference.reference_solution`: cvxpy/Clarabel at 1e-10,
refined on its active set to an exact KKT point, whose certificate is checked first (an
interior-point answer alone was 6e-4 of the ``du`` bound away from the optimum on GIPC QPs).
The fast back-ends (OSQP, ProxQP, Clarabel) must agree with it (objective to 1e-6 relative on
well-conditioned problems), have small KKT residuals of their own, survive the
``setup -> update -> solve`` path, and report failures as statuses.

The GIPC-like problems have ``|du| <= 0.01`` boxes: an answer off by more than 1e-3 of that
bound fails. Measured while writing these tests, on the same QPs: OSQP at its default
``eps = 1e-3`` without polishing was off by up to 20 % of the bound and ProxQP at
``eps_abs = 1e-4`` without the duality-gap check by up to 100 %, both reporting success;
``test_loose_tolerances_are_caught`` keeps that sensitivity honest.
"""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from models import RigidSatellite
from rmpc import GIPC, StepDisturbance, simulate
from rmpc.qp import (
    BACKENDS,
    QP,
    STATUSES,
    QPBackend,
    kkt_residuals,
    make_backend,
)
from rmpc.qp.base import DEFAULT_TIME_LIMIT
from rmpc.qp.proxqp_backend import ProxQPBackend
from rmpc.qp.reference import reference_solution
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError, SolverError
from toolkit_common.status import describe

FAST = ("osqp", "proxqp", "clarabel")
ALL = (*FAST, "cvxpy")


def random_qp(seed: int, n: int = 10, m: int = 8, n_eq: int = 2) -> QP:
    """A strongly convex QP (condition number of H below ~10) with a known feasible point.

    Some bounds are infinite, ``n_eq`` rows are equalities, and bounds sit close to the
    feasible point so that several constraints are active at the optimum.
    """
    rng = np.random.default_rng(seed)
    m_h = rng.standard_normal((n, n))
    h = m_h @ m_h.T / n + np.eye(n)
    c = rng.standard_normal((m, n))
    x0 = rng.standard_normal(n)
    cx = c @ x0
    lo = cx - rng.uniform(0.1, 1.0, m)
    up = cx + rng.uniform(0.1, 1.0, m)
    lo[:n_eq] = up[:n_eq] = cx[:n_eq]
    lo[n_eq::3] = -np.inf
    lb = x0 - rng.uniform(0.1, 1.0, n)
    ub = x0 + rng.uniform(0.1, 1.0, n)
    ub[::4] = np.inf
    return QP(H=h, g=5.0 * rng.standard_normal(n), C=c, l=lo, u=up, lb=lb, ub=ub)


def solve_fresh(name: str, qp: QP, **settings: object):
    be = make_backend(name, **settings)
    be.setup(qp)
    return be.solve()


@pytest.fixture(scope="module")
def references() -> dict[int, object]:
    out = {}
    for seed in range(5):
        qp = random_qp(seed)
        res = reference_solution(qp)
        assert res.status == "optimal" and res.backend == "cvxpy+refined"
        assert kkt_residuals(qp, res).max() < 1e-10
        out[seed] = (qp, res)
    return out


# -- agreement on random well-conditioned problems -----------------------------------------
@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("name", FAST)
def test_random_qps_agree_with_the_reference(name: str, seed: int, references: dict) -> None:
    qp, ref = references[seed]
    res = solve_fresh(name, qp)
    assert res.status == "optimal" and res.ok
    assert res.backend == name
    assert abs(res.objective - ref.objective) <= 1e-6 * max(1.0, abs(ref.objective))
    np.testing.assert_allclose(res.x, ref.x, atol=1e-6 * max(1.0, np.abs(ref.x).max()))
    kkt = kkt_residuals(qp, res)
    scale = max(1.0, np.abs(qp.g).max())
    assert kkt.primal < 1e-7, kkt
    assert kkt.dual < 1e-6 * scale, kkt
    assert kkt.complementarity < 1e-6 * scale, kkt
    assert res.objective == pytest.approx(qp.objective(res.x))
    assert res.solve_time >= 0.0 and res.iterations >= 0


@pytest.mark.parametrize("name", ALL)
def test_update_path_matches_fresh_solves(name: str) -> None:
    """setup once, then only vectors change: each answer equals a fresh solve of that QP."""
    base = random_qp(11)
    be = make_backend(name)
    be.setup(base)
    rng = np.random.default_rng(5)
    for _ in range(6):
        shift = 0.2 * rng.standard_normal(base.n_cons)
        target = base.replace(g=base.g + rng.standard_normal(base.n_vars), l=base.l + shift, u=base.u + shift)
        be.update(g=target.g, l=target.l, u=target.u)
        res = be.solve()
        fresh = reference_solution(target)
        assert res.status == "optimal"
        assert abs(res.objective - fresh.objective) <= 1e-6 * max(1.0, abs(fresh.objective))
        assert kkt_residuals(target, res).max() < 1e-5
    # the problem the back-end holds is the updated one
    np.testing.assert_array_equal(be.problem.g, target.g)


@pytest.mark.parametrize("name", ALL)
def test_changing_which_bounds_are_finite(name: str) -> None:
    qp = QP(H=np.eye(2), g=[-2.0, 2.0], lb=[-np.inf, -np.inf], ub=[np.inf, np.inf])
    be = make_backend(name)
    be.setup(qp)
    np.testing.assert_allclose(be.solve().x, [2.0, -2.0], atol=1e-6)
    be.update(ub=[1.0, np.inf], lb=[-np.inf, -0.5])
    res = be.solve()
    assert res.status == "optimal"
    np.testing.assert_allclose(res.x, [1.0, -0.5], atol=1e-6)
    np.testing.assert_allclose(res.y_box, [1.0, -1.5], atol=1e-5)  # sign convention
    be.update(ub=[np.inf, np.inf], lb=[-np.inf, -np.inf])
    np.testing.assert_allclose(be.solve().x, [2.0, -2.0], atol=1e-6)


@pytest.mark.parametrize("name", ALL)
def test_unconstrained_qp(name: str) -> None:
    h = np.array([[2.0, 0.5], [0.5, 1.0]])
    g = np.array([-2.0, 2.0])
    res = solve_fresh(name, QP(H=h, g=g))
    assert res.status == "optimal"
    np.testing.assert_allclose(res.x, np.linalg.solve(h, -g), rtol=1e-6)
    assert res.y_C.shape == (0,)


@pytest.mark.parametrize("name", ALL)
def test_equality_constrained_qp_has_the_lagrange_solution(name: str) -> None:
    # min 1/2 |z|^2 s.t. z1 + z2 = 1  ->  z = (0.5, 0.5), multiplier -0.5
    qp = QP(H=np.eye(2), g=[0.0, 0.0], C=[[1.0, 1.0]], l=[1.0], u=[1.0])
    res = solve_fresh(name, qp)
    assert res.status == "optimal"
    np.testing.assert_allclose(res.x, [0.5, 0.5], atol=1e-7)
    np.testing.assert_allclose(res.y_C, [-0.5], atol=1e-6)


# -- failures are statuses -------------------------------------------------------------------
#: What each back-end reports for a primal infeasible QP. ProxQP 0.8 does not detect it and
#: runs to max_iter (documented in rmpc.qp.proxqp_backend).
INFEASIBLE = {"osqp": {"infeasible"}, "clarabel": {"infeasible"}, "cvxpy": {"infeasible"},
              "proxqp": {"infeasible", "max_iterations"}}


@pytest.mark.parametrize("name", ALL)
def test_infeasible_qp_comes_back_as_a_status(name: str) -> None:
    # z1 + z2 >= 3 with |z_i| <= 1
    qp = QP(H=np.eye(2), g=[1.0, 1.0], C=[[1.0, 1.0]], l=[3.0], u=[4.0], lb=[-1.0, -1.0], ub=[1.0, 1.0])
    kwargs = {"max_iter": 2000} if name == "proxqp" else {}
    res = solve_fresh(name, qp, **kwargs)
    assert res.status in INFEASIBLE[name]
    assert not res.ok
    assert np.all(np.isnan(res.x)) and np.isnan(res.objective)


@pytest.mark.parametrize("name", ALL)
def test_unbounded_qp_is_not_reported_optimal(name: str) -> None:
    # H = 0, g = -1, z unbounded above
    qp = QP(H=np.zeros((1, 1)), g=[-1.0], lb=[0.0])
    kwargs = {"max_iter": 2000} if name == "proxqp" else {}
    res = solve_fresh(name, qp, **kwargs)
    assert res.status != "optimal" and res.status in STATUSES
    assert np.all(np.isnan(res.x))


@pytest.mark.parametrize("name", ALL)
def test_status_map_uses_the_shared_vocabulary(name: str) -> None:
    cls = BACKENDS[name]
    assert set(cls.STATUS_MAP.values()) <= set(STATUSES)
    assert "optimal" in cls.STATUS_MAP.values()
    assert cls.map_status("something the solver never says") == "numerical_error"


# -- the GIPC-like problem: tight du bounds -----------------------------------------------
@pytest.fixture(scope="module")
def gipc_qps() -> tuple[list[QP], list[np.ndarray]]:
    """QPs of GIPC on paper P's satellite along a closed loop, and reference solutions."""
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    lin = sat.linear_model(x0, 0.01)
    ctrl = GIPC(lin)
    traj = simulate(ctrl, lin, x0, duration=15.0)
    # every 30th step: the warm start of one QP from the previous one is a real jump
    qps = [ctrl.qp_at(traj.x[k], traj.x[k - 1], traj.u_cmd[k - 1]) for k in range(1, traj.n_steps, 30)]
    refs = []
    for qp in qps:
        res = reference_solution(qp)
        assert res.backend == "cvxpy+refined" and kkt_residuals(qp, res).max() < 1e-9
        refs.append(res.x)
    # the du box is active in some of them, else the test would prove little
    assert any(np.isclose(np.abs(x).max(), 0.01, rtol=1e-6) for x in refs)
    return qps, refs


def _du_errors(
    name: str, qps: list[QP], refs: list[np.ndarray], warm: bool = True, **settings: object
) -> np.ndarray:
    """Largest error of each answer; ``warm``: one setup, then updates (the controller's path)."""
    be = make_backend(name, **settings)
    errs = []
    for i, qp in enumerate(qps):
        if i == 0 or not warm:
            be.setup(qp)
        else:
            be.update(g=qp.g, l=qp.l, u=qp.u, lb=qp.lb, ub=qp.ub)
        res = be.solve()
        assert res.status == "optimal", (name, i, res.status)
        errs.append(np.abs(res.x - refs[i]).max())
    return np.asarray(errs)


@pytest.mark.parametrize("name", FAST)
def test_gipc_qps_within_a_small_fraction_of_the_du_bound(name: str, gipc_qps: tuple) -> None:
    qps, refs = gipc_qps
    errs = _du_errors(name, qps, refs)
    assert errs.max() <= 1e-3 * 0.01, f"{name}: off by {errs.max() / 0.01:.2%} of the du bound"


def test_loose_tolerances_are_caught(gipc_qps: tuple) -> None:
    """The check above fails for the settings that gave wrong answers in exploration.

    Measured on these 50 QPs (each solved from scratch): OSQP at eps 1e-3 without polishing
    off by up to 20 % of the du bound, ProxQP at eps_abs 1e-4 without the duality-gap check
    by up to 100 %, both reporting success. If a solver upgrade makes these settings
    accurate here, this test fails: revisit the tolerances and the sensitivity of the
    comparison rather than deleting it.
    """
    qps, refs = gipc_qps
    loose_osqp = _du_errors("osqp", qps, refs, warm=False, eps_abs=1e-3, eps_rel=1e-3, polishing=False)
    loose_prox = _du_errors("proxqp", qps, refs, warm=False, eps_abs=1e-4, check_duality_gap=False)
    assert loose_osqp.max() > 1e-2 * 0.01
    assert loose_prox.max() > 1e-2 * 0.01


# -- settings and arguments ------------------------------------------------------------------
@pytest.mark.parametrize("name", ALL)
def test_unknown_setting_is_rejected_by_name(name: str) -> None:
    with pytest.raises(InvalidArgumentError, match="'not_a_setting'"):
        make_backend(name, not_a_setting=1.0)


@pytest.mark.parametrize(
    ("name", "setting", "value"),
    [("osqp", "eps_abs", -1.0), ("osqp", "max_iter", 0), ("osqp", "polishing", "yes"),
     ("proxqp", "eps_abs", 0.0), ("proxqp", "dense_backend", "sparse"), ("proxqp", "box", "both"),
     ("proxqp", "first_chunk", 0), ("proxqp", "first_chunk", 2.5),
     ("clarabel", "tol_feas", float("nan")), ("clarabel", "max_iter", 2.5),
     ("cvxpy", "solver", "GUROBI")],
)
def test_bad_setting_values_are_rejected(name: str, setting: str, value: object) -> None:
    with pytest.raises((InvalidArgumentError, ArgumentTypeError), match=setting):
        make_backend(name, **{setting: value})


def test_make_backend_names() -> None:
    assert set(BACKENDS) == {"osqp", "proxqp", "clarabel", "cvxpy"}
    for name in BACKENDS:
        assert isinstance(make_backend(name), QPBackend)
    with pytest.raises(InvalidArgumentError, match="name"):
        make_backend("gurobi")
    with pytest.raises(ArgumentTypeError, match="name"):
        make_backend(3)  # type: ignore[arg-type]


def test_settings_object_and_overrides() -> None:
    from rmpc.qp import OSQPBackend, OSQPSettings

    be = OSQPBackend(OSQPSettings(eps_abs=1e-7), eps_rel=1e-8)
    assert (be.settings.eps_abs, be.settings.eps_rel) == (1e-7, 1e-8)
    with pytest.raises(InvalidArgumentError, match="'bogus'"):
        OSQPBackend(OSQPSettings(), bogus=1)
    with pytest.raises(ArgumentTypeError, match="settings"):
        OSQPBackend(settings=[1, 2])  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "argument"),
    [
        ({"H": [[1.0, 2.0], [0.0, 1.0]], "g": [0.0, 0.0]}, "H"),           # not symmetric
        ({"H": [[1.0, 0.0], [0.0, -1.0]], "g": [0.0, 0.0]}, "H"),          # indefinite
        ({"H": np.eye(2), "g": [0.0, 0.0, 0.0]}, "g"),                     # wrong length
        ({"H": np.eye(2), "g": [0.0, np.nan]}, "g"),
        ({"H": np.eye(2), "g": [0.0, 0.0], "C": np.ones((1, 3))}, "C"),
        ({"H": np.eye(2), "g": [0.0, 0.0], "C": np.ones((1, 2)), "l": [2.0], "u": [1.0]}, "l, u"),
        ({"H": np.eye(2), "g": [0.0, 0.0], "lb": [0.0, np.inf]}, "lb"),    # +inf lower bound
        ({"H": np.eye(2), "g": [0.0, 0.0], "ub": [0.0, np.nan]}, "ub"),
        ({"H": np.eye(2), "g": [0.0, 0.0], "lb": [1.0, 0.0], "ub": [0.0, 1.0]}, "lb, ub"),
    ],
)
def test_qp_validation_names_the_argument(kwargs: dict, argument: str) -> None:
    with pytest.raises(InvalidArgumentError) as err:
        QP(**kwargs)
    assert str(err.value).startswith(f"{argument}:"), str(err.value)


@pytest.mark.parametrize("name", FAST)
def test_update_validation(name: str) -> None:
    be = make_backend(name)
    with pytest.raises(SolverError):
        be.update(g=[0.0])
    with pytest.raises(SolverError):
        be.solve()
    with pytest.raises(ArgumentTypeError, match="qp"):
        be.setup("not a qp")  # type: ignore[arg-type]
    be.setup(QP(H=np.eye(2), g=[0.0, 0.0], C=[[1.0, 1.0]], l=[-1.0], u=[1.0]))
    with pytest.raises(InvalidArgumentError, match=r"^g:"):
        be.update(g=[0.0, 0.0, 0.0])
    with pytest.raises(InvalidArgumentError, match=r"^g:"):
        be.update(g=[0.0, np.inf])
    with pytest.raises(InvalidArgumentError, match=r"^l, u:"):
        be.update(l=[2.0])
    with pytest.raises(InvalidArgumentError, match=r"^ub:"):
        be.update(ub=[0.0, np.nan])
    assert be.solve().status == "optimal"  # a rejected update left the problem unchanged


# -- bounds in time and iterations -----------------------------------------------------------
#: z1 + z2 >= 3 with |z_i| <= 1: OSQP, Clarabel and cvxpy prove it infeasible in a few iterations,
#: ProxQP (infeasibility detection nearly off) runs to its max_iter.
INFEASIBLE_QP = QP(
    H=np.eye(2), g=[1.0, 1.0], C=[[1.0, 1.0]], l=[3.0], u=[4.0], lb=[-1.0, -1.0], ub=[1.0, 1.0]
)
#: The same rows with a feasible range.
FEASIBLE_QP = INFEASIBLE_QP.replace(l=[-1.0], u=[1.0])
#: Every way a solve is bounded in time: each back-end, cvxpy through both of its solvers.
TIMED = [("osqp", {}), ("proxqp", {}), ("clarabel", {}), ("cvxpy", {}), ("cvxpy", {"solver": "OSQP"})]
INF = float("inf")


@pytest.mark.parametrize("name", ALL)
def test_every_backend_is_bounded_in_time_and_iterations_by_default(name: str) -> None:
    settings = make_backend(name).settings
    assert settings.time_limit == DEFAULT_TIME_LIMIT
    assert math.isfinite(DEFAULT_TIME_LIMIT) and DEFAULT_TIME_LIMIT > 0
    assert isinstance(settings.max_iter, int) and settings.max_iter >= 1


def test_the_default_time_limit_is_the_one_the_status_table_states() -> None:
    assert f"{DEFAULT_TIME_LIMIT:g} s by default" in describe("time_limit").meaning


@pytest.mark.parametrize("name", ALL)
@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), -INF])
def test_time_limit_must_be_a_positive_number_of_seconds(name: str, value: float) -> None:
    with pytest.raises(InvalidArgumentError, match=r"Settings\.time_limit: .*seconds > 0"):
        make_backend(name, time_limit=value)


@pytest.mark.parametrize("name", ALL)
@pytest.mark.parametrize("value", ["5", True, None, [1.0]])
def test_time_limit_of_another_type_is_refused(name: str, value: object) -> None:
    with pytest.raises(ArgumentTypeError, match=r"Settings\.time_limit: "):
        make_backend(name, time_limit=value)


@pytest.mark.parametrize("name", ALL)
def test_time_limit_inf_switches_the_bound_off_and_integers_are_seconds(name: str) -> None:
    assert make_backend(name, time_limit=INF).settings.time_limit == INF
    assert make_backend(name, time_limit=2).settings.time_limit == 2


@pytest.mark.filterwarnings("ignore:Solution may be inaccurate")  # cvxpy's word on a user limit
@pytest.mark.parametrize(("name", "extra"), TIMED)
def test_a_tiny_time_limit_stops_the_solve_with_time_limit(name: str, extra: dict) -> None:
    """Without the bound the same solve ends otherwise; with 1e-9 s it ends ``"time_limit"``.

    OSQP and Clarabel read the clock before their first iteration; ProxQP, between chunks of
    outer iterations, stops after its first chunk (the QP keeps it from converging).
    """
    free = solve_fresh(name, INFEASIBLE_QP, time_limit=INF, max_iter=2000, **extra)
    assert free.status in {"infeasible", "max_iterations"}
    res = solve_fresh(name, INFEASIBLE_QP, time_limit=1e-9, max_iter=2000, **extra)
    assert res.status == "time_limit" and not res.ok
    assert np.all(np.isnan(res.x)) and np.isnan(res.objective)
    if name == "proxqp":
        assert res.info["outer_iterations"] == ProxQPBackend().settings.first_chunk < 2000


@pytest.mark.filterwarnings("ignore:Solution may be inaccurate")
@pytest.mark.parametrize("solver", ["CLARABEL", "OSQP"])
def test_cvxpy_tells_the_iteration_limit_from_the_time_limit(solver: str) -> None:
    """cvxpy reports both as ``"user_limit"``; the back-end reads which one its solver met."""
    res = solve_fresh("cvxpy", random_qp(3), solver=solver, max_iter=1)
    assert res.raw_status == "user_limit" and res.status == "max_iterations"


@pytest.mark.parametrize("max_iter", [2000, 1234])
@pytest.mark.parametrize("limit", [DEFAULT_TIME_LIMIT, INF])
def test_proxqp_max_iter_bounds_the_chunks_together(max_iter: int, limit: float) -> None:
    res = solve_fresh("proxqp", INFEASIBLE_QP, max_iter=max_iter, time_limit=limit)
    assert res.status == "max_iterations"
    assert res.info["outer_iterations"] == max_iter


def test_proxqp_time_limit_counts_the_cold_solve_after_setup() -> None:
    """``setup`` only builds; the cold solve that must follow ``init`` runs inside ``solve``.

    On a QP it cannot solve, a 1e-9 s limit ends the call after that one attempt.
    """
    be = ProxQPBackend(time_limit=1e-9)
    be.setup(INFEASIBLE_QP)
    attempts = []
    run = be._run
    be._run = lambda *args: attempts.append(1) or run(*args)  # type: ignore[method-assign]
    res = be.solve()
    assert res.status == "time_limit" and len(attempts) == 1 and not res.info["retried_cold"]
    be.update(l=[-1.0], u=[1.0])  # after a failed solve the next one is cold, and it converges
    assert be.solve().status == "optimal" and len(attempts) == 2


def test_proxqp_first_solve_that_raises_is_a_status() -> None:
    """The cold solve after ``init`` moved from ``setup`` into ``solve``; a binding that raises
    there is still a ``"numerical_error"`` (as a failed ``setup`` was), not an exception."""

    class Raising:
        def __init__(self, solver: object) -> None:
            self._solver = solver

        def __getattr__(self, name: str) -> object:
            return getattr(self._solver, name)

        def solve(self) -> None:
            raise RuntimeError("the binding refused")

    be = ProxQPBackend()
    be.setup(FEASIBLE_QP)
    be._solver = Raising(be._solver)  # type: ignore[assignment]
    res = be.solve()
    assert res.status == "numerical_error" and "the binding refused" in res.raw_status
    assert np.all(np.isnan(res.x))


@pytest.mark.parametrize(("limit", "status", "retried"), [(1e-9, "time_limit", False),
                                                          (INF, "max_iterations", True)])
def test_proxqp_retry_cold_starts_only_within_the_time_limit(
    limit: float, status: str, retried: bool
) -> None:
    """A warm-started solve that fails is retried cold, unless the call's time is up."""
    be = ProxQPBackend(time_limit=limit, max_iter=2000)
    be.setup(FEASIBLE_QP)
    assert be.solve().status == "optimal"  # converges in its first chunk: the limit plays no part
    be.update(l=[3.0], u=[4.0])  # infeasible: the warm-started solve cannot converge
    res = be.solve()
    assert res.status == status and res.info["retried_cold"] is retried
    be.update(l=[-1.0], u=[1.0])
    assert be.solve().status == "optimal"


@pytest.fixture(scope="module")
def hard_gipc_qps() -> list[QP]:
    """GIPC's QPs at every step of paper P's E5 (true inertia 1.7 times the model's, 0.5 N m step
    disturbance), shortened: after the step, warm-started ProxQP solves need up to 155 outer
    iterations (the most of any GIPC solve in the paper suite)."""
    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    heavy = RigidSatellite(inertia=1.7 * np.asarray(sat.inertia))
    ctrl = GIPC(sat.linear_model(x0, 0.01))
    traj = simulate(ctrl, heavy, x0, duration=1.2, dt=0.01, disturbance=StepDisturbance([0.5] * 3, 0.75))
    return [ctrl.qp_at(traj.x[0])] + [
        ctrl.qp_at(traj.x[k], traj.x[k - 1], traj.u_cmd[k - 1]) for k in range(1, traj.n_steps)
    ]


def _proxqp_run(qps: list[QP], warm: bool, **settings: object) -> list:
    be = make_backend("proxqp", **settings)
    out = []
    for i, qp in enumerate(qps):
        if i == 0 or not warm:
            be.setup(qp)
        else:
            be.update(g=qp.g, l=qp.l, u=qp.u, lb=qp.lb, ub=qp.ub)
        out.append(be.solve())
    return out


@pytest.mark.parametrize("warm", [True, False])
def test_proxqp_chunked_solve_equals_the_unchunked_one_within_the_first_chunk(
    hard_gipc_qps: list, warm: bool
) -> None:
    """The time limit changes nothing in a solve that converges in the first chunk.

    GIPC's QPs along a closed loop (one setup and updates, or a setup for each: then the cold
    solve after ``init`` and the warm one after it), with the default time limit (chunks) and
    with none (one proxsuite solve each). The first chunk is set to the outer iterations of the
    longest unchunked solve on this machine (the cold solve after a setup included), so every
    solve ends inside it by construction and the longest at its last iteration; the counts
    themselves (38 to 155 outer iterations on the machines measured) are the machine's, not the
    test's premise. A first chunk of 5 (mutation) fails it. proxsuite's arithmetic is not
    reproducible to the bit from one run to the next even with the same settings (on these
    QPs: ``x`` to 2.75e-12, the multipliers to 3.9e-9 of about 1e3, iteration counts exactly,
    over 20 runs without a limit), so iterations and statuses must agree exactly and the
    vectors to 1e-10 of their scale, about 36 times that noise. A first chunk of 5 outer
    iterations moves ``x`` by 3.5e-8 and the iteration counts.
    """
    qps = hard_gipc_qps if warm else hard_gipc_qps[::10]
    whole = _proxqp_run(qps, warm, time_limit=INF)
    outer = [max(r.info["outer_iterations"], r.info["first_solve_outer_iterations"]) for r in whole]
    chunked = _proxqp_run(qps, warm, first_chunk=max(outer))
    assert ProxQPBackend().settings.time_limit < INF  # the default runs in chunks
    for a, b in zip(chunked, whole, strict=True):
        assert a.status == b.status == "optimal"
        assert (a.iterations, a.info, a.raw_status) == (b.iterations, b.info, b.raw_status)
        np.testing.assert_allclose(a.x, b.x, rtol=0, atol=1e-10 * max(1.0, np.abs(b.x).max()))
        y_scale = max(1.0, np.abs(b.y_C).max(initial=0.0), np.abs(b.y_box).max())
        np.testing.assert_allclose(a.y_C, b.y_C, rtol=0, atol=1e-10 * y_scale)
        np.testing.assert_allclose(a.y_box, b.y_box, rtol=0, atol=1e-10 * y_scale)


@pytest.mark.parametrize("warm", [True, False])
def test_proxqp_chunks_resume_where_the_previous_one_stopped(
    hard_gipc_qps: list, warm: bool
) -> None:
    """Cut into chunks shorter than the longest solve, every solve still converges to the same
    answer.

    Each chunk starts from the previous chunk's result (a cold restart would never get past the
    first chunk). The chunk is 5 outer iterations, or one less than the longest unchunked solve
    took on this machine where that is 5 or fewer, so the longest solve is cut by construction
    (it needs at least 2 outer iterations: these are the QPs after a step disturbance).
    Measured: the answers agree with the unchunked ones to 3.5e-8 (3.5e-6 of the du bound,
    within the solver's tolerance); 1e-6 leaves a margin of about 30.
    """
    qps = hard_gipc_qps if warm else hard_gipc_qps[::10]
    whole = _proxqp_run(qps, warm, time_limit=INF)
    longest = max(max(r.info["outer_iterations"], r.info["first_solve_outer_iterations"]) for r in whole)
    assert longest >= 2
    chunked = _proxqp_run(qps, warm, first_chunk=min(5, longest - 1))
    for a, b in zip(chunked, whole, strict=True):
        assert a.status == "optimal"
        np.testing.assert_allclose(a.x, b.x, rtol=0, atol=1e-6)


# -- back-end specific pitfalls ------------------------------------------------------------
def test_proxqp_update_before_any_solve_does_not_crash() -> None:
    """proxsuite 0.8.0's dense QP segfaults on init -> update -> warm-started solve.

    The first solve after ``init`` is cold; then the paths of the time limit: chunks each
    warm-started from the previous one, a stopped solve followed by update -> solve, a failed
    warm-started solve retried in a new solver. Run in a subprocess so a crash is a failure
    of this test, not of the whole run.
    """
    code = textwrap.dedent(
        """
        import numpy as np
        from rmpc.qp import QP, make_backend
        rng = np.random.default_rng(0)
        n = 12
        m = rng.standard_normal((n, n))
        qp = QP(H=m @ m.T + np.eye(n), g=rng.standard_normal(n), C=np.tril(np.ones((n, n))),
                l=-np.ones(n), u=np.ones(n), lb=-0.01 * np.ones(n), ub=0.01 * np.ones(n))
        for box in ("rows", "native"):
            be = make_backend("proxqp", box=box)
            be.setup(qp)
            be.update(g=rng.standard_normal(n))
            assert be.solve().status == "optimal"
        infeasible = QP(H=np.eye(2), g=[1.0, 1.0], C=[[1.0, 1.0]], l=[3.0], u=[4.0],
                        lb=[-1.0, -1.0], ub=[1.0, 1.0])
        for box in ("rows", "native"):
            for limit, stopped, retried in ((1e-9, "time_limit", False), (5.0, "max_iterations", True)):
                be = make_backend("proxqp", box=box, time_limit=limit, max_iter=1200)
                be.setup(infeasible)
                be.update(g=[0.5, 1.0])  # init -> update -> the cold solve, chunks after it
                assert be.solve().status == stopped
                be.update(l=[-1.0], u=[1.0])  # a stopped solve -> update -> solve
                assert be.solve().status == "optimal"
                be.update(l=[3.0], u=[4.0])  # a warm-started solve that fails (and a retry)
                res = be.solve()
                assert (res.status, res.info["retried_cold"]) == (stopped, retried), (box, limit, res)
        print("ok")
        """
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip() == "ok"


def test_osqp_prints_nothing_when_no_constraint_is_active(capsys: pytest.CaptureFixture[str]) -> None:
    be = make_backend("osqp")
    be.setup(QP(H=np.eye(2), g=[0.1, 0.1], lb=[-1.0, -1.0], ub=[1.0, 1.0]))
    res = be.solve()
    assert res.status == "optimal" and res.info["polish_status"] != 1
    assert capsys.readouterr().out == ""


def test_kkt_residuals_detect_a_wrong_point() -> None:
    qp = QP(H=np.eye(2), g=[-2.0, 0.0], ub=[1.0, 1.0])
    good = kkt_residuals(qp, [1.0, 0.0], y_box=[1.0, 0.0])
    assert good.max() == 0.0
    bad = kkt_residuals(qp, [1.2, 0.0], y_box=[0.8, 0.0])
    assert bad.primal == pytest.approx(0.2) and bad.dual == pytest.approx(0.0)
    wrong_sign = kkt_residuals(qp, [0.5, 0.0], y_box=[1.5, 0.0])
    assert wrong_sign.complementarity == pytest.approx(0.75)


@pytest.mark.parametrize("name", ALL)
def test_a_result_is_not_changed_by_later_solves(name: str) -> None:
    """proxsuite returns views of its own memory; a QPResult must hold copies."""
    be = make_backend(name)
    be.setup(QP(H=np.eye(2), g=[-1.0, -1.0], ub=[0.5, 2.0]))
    first = be.solve()
    x, y = first.x.copy(), first.y_box.copy()
    be.update(g=[3.0, 3.0])
    second = be.solve()
    np.testing.assert_array_equal(first.x, x)
    np.testing.assert_array_equal(first.y_box, y)
    np.testing.assert_allclose(second.x, [-3.0, -3.0], atol=1e-6)


def test_a_solver_that_refuses_the_data_is_a_status() -> None:
    """A binding that raises during setup: solve() reports numerical_error, nothing is raised."""
    from rmpc.qp import OSQPBackend

    class Refusing(OSQPBackend):
        def _setup(self) -> None:
            raise RuntimeError("factorisation failed")

    be = Refusing()
    be.setup(QP(H=np.eye(2), g=[0.0, 0.0]))
    res = be.solve()
    assert res.status == "numerical_error" and "factorisation failed" in res.raw_status
    assert np.all(np.isnan(res.x))
    be.update(g=[1.0, 1.0])  # tries to build again, fails again, still no exception
    assert be.solve().status == "numerical_error"
