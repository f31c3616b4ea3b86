"""TubeMPC: closed-loop constraints under seeded disturbances, the tube's own invariants, the QP
against an independent solve, failures as statuses, every back-end, save and load, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from models import PolytopicModel
from rmpc import StepInputs, TubeMPC, load
from rmpc.controller import Controller
from rmpc.mpc import tube as tube_module
from rmpc.mpc.tube_runs import disturbance_runs, double_integrator, feasible_initial_states
from rmpc.qp import reference_solution
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

P = double_integrator()
A, B = P["A"], P["B"]
KINDS = ("rigid", "tightening")


@pytest.fixture(scope="module", params=KINDS)
def tube(request) -> TubeMPC:
    return TubeMPC((A, B), **P["controller"], kind=request.param)


def test_protocol(tube: TubeMPC) -> None:
    assert isinstance(tube, Controller)
    assert tube.name == ("TubeMPC" if tube.kind == "rigid" else "TubeMPC-tightening")
    assert tube.accepts == frozenset()
    with pytest.raises(ValueError, match=r"inputs\.u_max"):
        tube.step([0.0, 0.0], StepInputs(u_max=0.5))


def test_zero_violations_over_seeded_sequences(tube: TubeMPC) -> None:
    """60 seeded 50-step runs from states where the first QP is feasible, the disturbances at
    W's vertices, inside W and held at one vertex: no state or input leaves its bounds, no step
    fails. (dev/tube_targets.py runs the 1,000 sequences of the target.)"""
    rng = np.random.default_rng(40)
    x0s, share = feasible_initial_states(tube, [10.0, 10.0], 60, rng)
    assert len(x0s) == 60 and 0.2 < share < 0.6
    runs = disturbance_runs(tube, x0s, steps=50, rng=rng)
    assert runs.violations == 0
    assert runs.failed_steps == 0
    assert runs.max_excess <= 1e-6
    # the runs do reach the bounds: the input saturates, the tube is not trivially loose
    assert runs.max_excess > -1e-3


@pytest.mark.slow
@pytest.mark.parametrize("kind", KINDS)
def test_the_target_zero_violations_over_1000_sequences(kind: str) -> None:
    """The double integrator's target: 1,000 seeded 50-step sequences, no violation, no failed
    step (the solve times are measured by ``python -m dev.tube_targets``, not asserted)."""
    tube = TubeMPC((A, B), **P["controller"], kind=kind)
    rng = np.random.default_rng(2005)
    x0s, _ = feasible_initial_states(tube, [10.0, 10.0], 1000, rng)
    runs = disturbance_runs(tube, x0s, steps=50, rng=rng)
    assert runs.runs == 1000
    assert runs.violations == 0 and runs.failed_steps == 0


def test_rigid_tube_holds_the_error_in_Z() -> None:
    """x - z0 in Z at every step, z0 the QP's nominal state (Mayne et al.'s tube)."""
    tube = TubeMPC((A, B), **P["controller"], kind="rigid")
    rng = np.random.default_rng(3)
    x = np.array([-5.0, -2.0])
    for _ in range(40):
        u = tube.step(x)
        z0 = tube.last.extra["z0"]
        assert tube.Z.contains(x - z0, tol=1e-7)
        x = A @ x + B @ u + rng.choice([-0.1, 0.1], size=2)


def test_tightening_predicts_from_the_state() -> None:
    tube = TubeMPC((A, B), **P["controller"], kind="tightening")
    x = np.array([-5.0, -2.0])
    tube.step(x)
    assert np.array_equal(tube.last.extra["z0"], x)


@pytest.mark.parametrize("kind", KINDS)
def test_qp_matches_an_independent_reference(kind: str) -> None:
    """The first input equals the certified reference solution of the same QP (interior point
    refined on its active set), and the QP's cost at a plan simulated step by step equals the
    tube's cost written out directly."""
    tube = TubeMPC((A, B), **P["controller"], kind=kind)
    x = np.array([-4.0, 1.5])
    u = tube.step(x)
    qp = tube.qp_at(x)
    ref = reference_solution(qp)
    n, m, N = 2, 1, tube.N
    K = tube.sets.K
    z0, c = (ref.x[:n], ref.x[n:]) if kind == "rigid" else (x, ref.x)
    assert np.allclose(u, K @ x + c[:m], atol=1e-6)
    # the cost written out: sum z'Qz + v'Rv + z_N' P z_N along the simulated nominal plan
    z, cost = z0.copy(), 0.0
    for i in range(N):
        v = K @ z + c[i * m:(i + 1) * m]
        cost += z @ tube.Q @ z + v @ tube.R @ v
        z = A @ z + B @ v
    cost += z @ tube.sets.P @ z
    const = 0.0 if kind == "rigid" else x @ tube._cost_xx @ x
    assert np.isclose(qp.objective(ref.x) + const, cost, rtol=1e-9)


@pytest.mark.parametrize("backend", ["clarabel", "proxqp", "osqp"])
def test_backends_agree_inside_the_feasible_set(backend: str) -> None:
    reference = TubeMPC((A, B), **P["controller"], kind="tightening", backend="clarabel")
    tube = TubeMPC((A, B), **P["controller"], kind="tightening", backend=backend)
    for x in ([-3.0, 1.0], [2.0, -1.0], [0.5, 0.5]):
        assert np.allclose(tube.step(x), reference.step(x), atol=1e-5)
        assert tube.last.status == "optimal"


def test_infeasible_state_is_a_status_and_the_shifted_plan_is_applied() -> None:
    tube = TubeMPC((A, B), **P["controller"], kind="rigid")
    far = np.array([9.9, 9.9])                       # outside the tube's feasible set
    u = tube.step(far)
    assert tube.last.status == "infeasible" and tube.last.fallback
    assert np.array_equal(u, np.zeros(1))            # no plan yet: zero, flagged
    x = np.array([-5.0, -2.0])
    tube.reset()
    tube.step(x)
    plan = tube._plan.copy()
    u = tube.step(far)
    assert tube.last.status == "infeasible" and tube.last.fallback
    assert np.allclose(u, tube.sets.K @ far + plan[1])


def test_save_and_load_design_nothing(tube: TubeMPC, tmp_path, monkeypatch) -> None:
    path = tube.save(tmp_path / "tube.rmpc")

    def no_design(*args, **kwargs):
        raise AssertionError("loading designed a set")

    for name in ("mrpi_outer", "mrpi_support_bound", "admissible_set", "reachable_tightening"):
        monkeypatch.setattr(tube_module, name, no_design)
    loaded = load(path)
    assert loaded.kind == tube.kind and loaded.name == tube.name
    tube.reset()
    for x in ([-5.0, -2.0], [3.0, -1.0]):
        assert np.allclose(loaded.step(x), tube.step(x), atol=1e-8)
    assert np.array_equal(loaded.sets.terminal_H, tube.sets.terminal_H)


# -- bad input -----------------------------------------------------------------------------------
def make(**changes):
    args = {**P["controller"], **changes}
    return TubeMPC((A, B), **args)


def test_disturbance_set_unbounded_or_without_origin() -> None:
    with pytest.raises(InvalidArgumentError, match="disturbance_set: expected a bounded polytope"):
        make(w_max=None, disturbance_set=(np.eye(2), [0.1, 0.1]))
    shifted = (np.vstack([np.eye(2), -np.eye(2)]), [0.3, 0.1, -0.1, 0.1])      # 0.1 <= w_1 <= 0.3
    with pytest.raises(InvalidArgumentError, match="disturbance_set: expected a disturbance set with the"):
        make(w_max=None, disturbance_set=shifted)
    with pytest.raises(InvalidArgumentError, match="w_max: expected finite bounds > 0"):
        make(w_max=[0.1, -0.1])
    with pytest.raises(InvalidArgumentError, match="w_max: expected the disturbance bound"):
        make(w_max=None)


def test_gain_that_does_not_stabilise() -> None:
    with pytest.raises(InvalidArgumentError, match="K: expected a gain with A \\+ B K Schur stable"):
        make(K=[[0.1, 0.1]])
    with pytest.raises(InvalidArgumentError, match="K: expected shape"):
        make(K=[[0.1, 0.1, 0.1]])


@pytest.mark.parametrize("kind", KINDS)
def test_tightening_that_empties_the_constraints(kind: str) -> None:
    with pytest.raises(InvalidArgumentError, match=r"u_max: expected constraints that survive the tube's"):
        make(w_max=[1.5, 1.5], kind=kind)
    with pytest.raises(InvalidArgumentError, match=r"x_max: expected constraints that survive the tube's"):
        make(x_max=[0.12, 10.0], u_max=100.0, kind=kind)
    general = (np.array([[1.0, 0.0], [-1.0, 0.0]]), np.array([0.12, 0.12]))
    with pytest.raises(InvalidArgumentError, match=r"x_max and state_constraints: expected constraints"):
        make(state_constraints=general, u_max=100.0, kind=kind)


def test_other_arguments() -> None:
    two = PolytopicModel([(A, B), (A, 1.1 * B)], dt=1.0)
    with pytest.raises(InvalidArgumentError, match="plant: expected one linear model"):
        TubeMPC(two, **P["controller"])
    with pytest.raises(ArgumentTypeError, match="plant"):
        TubeMPC(A, **P["controller"])
    with pytest.raises(InvalidArgumentError, match="kind: expected one of 'rigid', 'tightening'"):
        make(kind="homothetic")
    with pytest.raises(InvalidArgumentError, match="horizon: expected at most max_horizon = 200"):
        make(horizon=500)
    with pytest.raises(InvalidArgumentError, match="state_constraints\\[0\\]: expected shape"):
        make(state_constraints=(np.eye(3), np.ones(3)))
    with pytest.raises(InvalidArgumentError, match="epsilon"):
        make(epsilon=0.0)


# -- a flat disturbance on a six-state satellite -------------------------------------------------
@pytest.fixture(scope="module")
def satellite():
    """Paper P's satellite holding attitude under a gravity-gradient torque through B (the
    methods bench's ``paper_p_hold``): ``E W`` is flat (rank 3 in six states)."""
    from benchmarks.suites.methods_problems import build_problem

    p = build_problem("paper_p_hold")
    a, b = p.true_plant
    tube = TubeMPC((a, b), p.Q, p.R, horizon=9, kind="tightening", u_max=p.u_max, w_max=p.w_box,
                   E=p.w_matrix)
    return p, tube


def _lp_max(c: np.ndarray, H: np.ndarray, h: np.ndarray) -> float:
    from scipy.optimize import linprog

    res = linprog(-c, A_ub=H, b_ub=h, bounds=[(None, None)] * H.shape[1], method="highs")
    assert res.status == 0, res.message
    return float(-res.fun)


def test_satellite_terminal_set_is_robustly_invariant_and_admissible(satellite) -> None:
    """Checked by LPs row by row (no vertex of the 6-D set is enumerated): ``A_K X_f + A_K^N E W
    in X_f`` (the shifted plan's terminal state stays in it) and ``X_f`` inside the input bound
    tightened by ``F_N``, both with ``E W``'s support summed over the torque box's corners."""
    p, tube = satellite
    K, N, E = tube.sets.K, tube.N, tube.E
    A_K = tube.A + tube.B @ K
    H, h = tube.sets.terminal_H, tube.sets.terminal_h
    corners = np.array(list(__import__("itertools").product(*[[-w, w] for w in p.w_box])))
    push = corners @ E.T @ np.linalg.matrix_power(A_K, N).T          # A_K^N E w at the corners
    for i in range(h.size):
        assert _lp_max(A_K.T @ H[i], H, h) + (push @ H[i]).max() <= h[i] + 1e-9 * max(1.0, abs(h[i]))
    f_n = np.zeros(2 * K.shape[0])                                   # h_{F_N}(+-K rows)
    power = np.eye(6)
    rows = np.vstack([K, -K])
    for _ in range(N):
        f_n += (corners @ E.T @ power.T @ rows.T).max(axis=0)
        power = A_K @ power
    for r, row in enumerate(rows):
        assert _lp_max(row, H, h) <= p.u_max - f_n[r] + 1e-9


def test_satellite_tightening_has_no_violation_over_seeded_torque_sequences(satellite) -> None:
    p, tube = satellite
    rng = np.random.default_rng(41)
    starts = p.x0 * rng.uniform(0.2, 1.0, size=(6, 1))
    out = disturbance_runs(tube, starts, steps=60, rng=rng)
    assert out.failed_steps == 0 and out.violations == 0, out.statuses
    assert out.max_excess < 0.0


def test_the_rigid_tube_refuses_a_flat_disturbance_naming_E(satellite) -> None:
    p, tube = satellite
    with pytest.raises(InvalidArgumentError, match=r"^E: expected for kind='rigid'.*rank 3 for 6 states"):
        TubeMPC((tube.A, tube.B), p.Q, p.R, horizon=9, kind="rigid", u_max=p.u_max, w_max=p.w_box,
                E=p.w_matrix)
    with pytest.raises(InvalidArgumentError, match="E"):
        TubeMPC((tube.A, tube.B), p.Q, p.R, kind="tightening", u_max=p.u_max, w_max=p.w_box,
                E=np.ones((5, 3)))


def test_satellite_tube_saves_and_loads_its_disturbance_matrix(satellite, tmp_path) -> None:
    p, tube = satellite
    loaded = load(tube.save(tmp_path / "sat.rmpc"))
    assert np.array_equal(loaded.E, tube.E)
    tube.reset()
    assert np.allclose(loaded.step(p.x0), tube.step(p.x0), atol=1e-8)
