"""Save and load: every designed controller and estimator round-trips through its file and pickle.

A loaded controller must give the original's ``step(x)`` outputs along a closed loop from
``reset()``: bit for bit where nothing is solved (the off-line lookup, LQR, estimators), to
solver accuracy where a solve happens (measured bit for bit here too, the same LMIs being solved
from the same data). The problems are Kothare's examples 1 and 2 (Kothare, Balakrishnan and
Morari 1996) as the methods bench builds them, and paper P's satellite for the scheduled RMPC.
The bad files of :mod:`tests.test_save_load_files`.
"""

from __future__ import annotations

import pickle
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import rmpc
from benchmarks.suites.methods_problems import build_problem
from models import RigidSatellite
from rmpc import CRMPC, GIPC, LQR, RMPC, OfflineRMPC, ScheduledRMPC
from rmpc.controller import StepInputs
from rmpc.errors import InvalidArgumentError
from rmpc.estimators import KalmanFilter, Luenberger
from rmpc.mpc.adaptation import LyapunovRule, MITRule

EX1 = build_problem("kothare_ex1")
EX2 = build_problem("kothare_ex2")
SAT = RigidSatellite.paper_p()


def _rmpc(**options: Any) -> Callable[[], RMPC]:
    return lambda: RMPC(EX1.plant, Q=EX1.Q, R=EX1.R, u_max=EX1.u_max, input_constraint="peak", **options)


def _with_reference() -> RMPC:
    ctrl = RMPC(EX1.plant, Q=EX1.Q, R=EX1.R, u_max=EX1.u_max, input_constraint="peak")
    ctrl.set_reference([0.02], outputs=[[1.0, 0.0]])
    return ctrl


def _crmpc_mit() -> CRMPC:
    return CRMPC(EX1.plant, Q=EX1.Q, R=EX1.R, u_max=EX1.u_max, input_constraint="peak",
                 adaptation=MITRule(gain=5.0, reset_period=1.0), torque_budget="split",
                 rmpc_options={"resolve_threshold": 0.5, "x_ref": [0.0, 0.0]})


# name -> (builder, whether a step solves an LMI or QP); every form of the RMPC issue's list
SOLVING: dict[str, Callable[[], Any]] = {
    "rmpc_kothare": _rmpc(),
    "rmpc_ellipsoid_outputs": lambda: RMPC(EX1.plant, Q=EX1.Q, R=EX1.R, u_max=EX1.u_max,
                                           output_matrix=[[1.0, 0.0]], y_max=0.2, resolve_threshold=0.5),
    "rmpc_vertex": _rmpc(lyapunov="vertex"),
    "rmpc_nominal_cost": _rmpc(cost="nominal"),
    "rmpc_free_move": _rmpc(free_moves=1),
    "rmpc_saturation": _rmpc(saturation="auxiliary"),
    "rmpc_soft": _rmpc(soft={"u": 100.0}),
    "rmpc_disturbance": _rmpc(disturbance=(EX1.plant.nominal[1], 0.01, 0.95)),
    "rmpc_clarabel": _rmpc(backend="clarabel", solver_options={"max_iter": 150}),
    "rmpc_method_mao_cao": lambda: RMPC.from_method("mao_cao", EX1.plant, Q=EX1.Q, R=EX1.R, u_max=EX1.u_max),
    "rmpc_reference": _with_reference,
    "crmpc_lyapunov": lambda: CRMPC(EX2.plant, Q=EX2.Q, R=EX2.R, u_max=EX2.u_max, input_constraint="peak",
                                    adaptation=LyapunovRule(gain=50.0)),
    "crmpc_mit": _crmpc_mit,
    "gipc_proxqp": lambda: GIPC(EX2.plant, Np=12, Nc=3, C=np.eye(4)[:2], u_max=1.0, du_max=0.5),
    "gipc_osqp": lambda: GIPC(EX1.plant, Np=10, Nc=2, u_max=2.0, du_max=None, backend="osqp",
                              solver_options={"eps_abs": 1e-8, "eps_rel": 1e-8}, u0=[0.1]),
}
FIXED: dict[str, Callable[[], Any]] = {
    "lqr": lambda: LQR(EX2.plant, Q=EX2.Q, R=EX2.R, x_ref=np.zeros(4)),
    "lqr_vertex": lambda: LQR(EX1.plant, Q=np.eye(2), R=EX1.R, vertex=1),
}


def _problem(name: str) -> Any:
    return EX1 if any(name.startswith(p) for p in ("rmpc", "crmpc_mit", "gipc_osqp", "lqr_vertex")) else EX2


def _closed_loop(ctrl: Any, problem: Any, steps: int, inputs: StepInputs | None = None) -> list[Any]:
    """The inputs and statuses of ``steps`` samples from ``reset()`` on the problem's true plant."""
    a, b = problem.true_plant
    ctrl.reset()
    x, out = np.array(problem.x0, dtype=float), []
    for _ in range(steps):
        u = np.array(ctrl.step(x, inputs))
        out.append((u, ctrl.last.status))
        x = a @ x + b @ u
    return out


def _same(first: list[Any], second: list[Any], exact: bool) -> None:
    assert [s for _, s in first] == [s for _, s in second]
    for (u1, _), (u2, _) in zip(first, second, strict=True):
        if exact:
            assert np.array_equal(u1, u2)
        else:  # solver accuracy: the solvers' 1e-8 tolerances on inputs of order one
            np.testing.assert_allclose(u2, u1, rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("name", [*SOLVING, *FIXED])
def test_every_controller_round_trips_through_its_file_and_pickle(name: str, tmp_path: Path) -> None:
    build = SOLVING.get(name) or FIXED[name]
    ctrl, problem = build(), _problem(name)
    path = ctrl.save(tmp_path / "design.rmpc")
    assert path == tmp_path / "design.rmpc"
    loaded = rmpc.load(path)
    copied = pickle.loads(pickle.dumps(ctrl))
    assert type(loaded) is type(ctrl) is type(copied)
    inputs = None
    reference = _closed_loop(ctrl, problem, 20, inputs)
    exact = name in FIXED
    _same(reference, _closed_loop(loaded, problem, 20, inputs), exact)
    _same(reference, _closed_loop(copied, problem, 20, inputs), exact)
    # a loaded controller saves the same design again
    assert loaded.save(tmp_path / "again.rmpc").read_text() == path.read_text()


def test_offset_free_and_its_disturbance_estimate_round_trip(tmp_path: Path) -> None:
    ctrl = RMPC(EX1.plant, Q=EX1.Q, R=EX1.R, u_max=EX1.u_max, offset_free=True)
    loaded = rmpc.load(ctrl.save(tmp_path / "of.rmpc"))
    assert loaded.offset_free and loaded.accepts == ctrl.accepts
    inputs = StepInputs(d_hat=np.array([0.05]))
    _same(_closed_loop(ctrl, EX1, 15, inputs), _closed_loop(loaded, EX1, 15, inputs), exact=False)


def test_the_set_point_is_saved_without_solving_it_again(tmp_path: Path) -> None:
    ctrl = _with_reference()
    loaded = rmpc.load(ctrl.save(tmp_path / "ref.rmpc"))
    assert loaded.target is not None and ctrl.target is not None
    assert np.array_equal(loaded.x_ref, ctrl.x_ref) and np.array_equal(loaded.u_ref, ctrl.u_ref)
    assert np.array_equal(loaded.target.reference, [0.02])


def test_the_scheduled_rmpc_round_trips_on_paper_p_satellite(tmp_path: Path) -> None:
    ctrl = ScheduledRMPC.for_satellite(SAT, dt=0.01, spread=0.3, Q=np.diag([1, 1, 1, 0.1, 0.1, 0.1]),
                                       R=np.eye(3), u_max=1.0)
    loaded = rmpc.load(ctrl.save(tmp_path / "sched.rmpc"))
    copied = pickle.loads(pickle.dumps(ctrl))
    assert np.array_equal(loaded.polytope_at.satellite.inertia, SAT.inertia)
    x0 = SAT.initial_state()
    a, b = SAT.linear_model(x0, 0.01).nominal
    runs = []
    for c in (ctrl, loaded, copied):
        c.reset()
        x, out = x0.copy(), []
        for _ in range(8):
            u = c.step(x)
            out.append((u, c.last.status))
            x = a @ x + b @ u
        runs.append(out)
    _same(runs[0], runs[1], exact=False)
    _same(runs[0], runs[2], exact=False)


def _offline() -> OfflineRMPC:
    return OfflineRMPC(EX2.plant, Q=EX2.Q, R=EX2.R, u_max=EX2.u_max, input_constraint="peak",
                       x_design=EX2.x0, n_ellipsoids=6)


def test_a_loaded_offline_table_looks_up_bit_for_bit_on_10000_states(tmp_path: Path) -> None:
    ctrl = _offline()
    loaded = rmpc.load(ctrl.save(tmp_path / "offline.rmpc"))
    copied = pickle.loads(pickle.dumps(ctrl))
    q1_inv = np.linalg.inv(ctrl.table.ellipsoids[0].Q)
    rng = np.random.default_rng(20261129)
    directions = rng.standard_normal((10_000, 4))
    levels = np.einsum("ij,jk,ik->i", directions, q1_inv, directions)
    # radii so that the level x' Q_1^-1 x is uniform in [0, 4]: about half inside E_1, half outside
    states = directions * np.sqrt(rng.uniform(0.0, 4.0, 10_000) / levels)[:, None]
    seen = set()
    for x in states:
        for c in (ctrl, loaded, copied):
            c.reset()
        u = ctrl.step(x)
        assert np.array_equal(loaded.step(x), u) and np.array_equal(copied.step(x), u)
        assert loaded.last.status == ctrl.last.status
        assert loaded.last.extra["index"] == ctrl.last.extra["index"]
        seen.add(ctrl.last.status)
    assert seen == {"optimal", "outside"}


def test_loading_an_offline_table_designs_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    ctrl = _offline()
    path = ctrl.save(tmp_path / "offline.rmpc")
    from lmi.offline import NestedKothareProblem

    def refuse(*args: Any, **kwargs: Any) -> None:
        raise AssertionError("the design was solved again")

    for method in ("design", "design_ray", "design_trajectory", "solve"):
        monkeypatch.setattr(NestedKothareProblem, method, refuse)
    loaded = rmpc.load(path)
    assert loaded.table.n_ellipsoids == 6
    for got, want in zip(loaded.table.ellipsoids, ctrl.table.ellipsoids, strict=True):
        assert np.array_equal(got.Q, want.Q) and np.array_equal(got.F, want.F) and got.gamma == want.gamma
        assert got.certificate is not None and got.certificate.margins == want.certificate.margins
    assert np.array_equal(loaded.table.interpolable, ctrl.table.interpolable)
    loaded.step(EX2.x0 * 10.0)  # outside: a table given by x_design is not redesigned
    assert loaded.last.status == "outside"


def test_an_automatic_table_is_still_redesigned_outside_after_loading(tmp_path: Path) -> None:
    ctrl = OfflineRMPC(EX1.plant, Q=EX1.Q, R=EX1.R, u_max=EX1.u_max, input_constraint="peak", n_ellipsoids=3)
    with pytest.raises(InvalidArgumentError, match="no table yet"):
        ctrl.save(tmp_path / "nothing.rmpc")
    assert not (tmp_path / "nothing.rmpc").exists()
    ctrl.step(EX1.x0)
    loaded = rmpc.load(ctrl.save(tmp_path / "auto.rmpc"))
    far = EX1.x0 * 3.0
    for c in (ctrl, loaded):
        c.reset()
    np.testing.assert_allclose(loaded.step(far), ctrl.step(far), rtol=1e-7)
    assert loaded.last.status == ctrl.last.status == "optimal"
    assert loaded.last.extra["design_time"] > 0.0


def test_from_table_builds_the_controller_of_a_table_and_checks_its_sizes() -> None:
    ctrl = _offline()
    copy = OfflineRMPC.from_table(EX2.plant, ctrl.table, Q=EX2.Q, R=EX2.R, u_max=EX2.u_max,
                                  input_constraint="peak")
    x = EX2.x0 * 0.3
    assert np.array_equal(copy.step(x), ctrl.step(x))
    with pytest.raises(InvalidArgumentError, match=r"table.ellipsoids\[0\]"):
        OfflineRMPC.from_table(EX1.plant, ctrl.table, Q=EX1.Q, R=EX1.R, u_max=EX1.u_max)
    with pytest.raises(TypeError, match="table"):
        OfflineRMPC.from_table(EX2.plant, "table", Q=EX2.Q, R=EX2.R)


def test_crmpc_keeps_its_rule_and_settings_and_starts_from_a_reset_estimate(tmp_path: Path) -> None:
    ctrl = _crmpc_mit()
    _closed_loop(ctrl, EX1, 10)
    loaded = rmpc.load(ctrl.save(tmp_path / "crmpc.rmpc"))
    assert isinstance(loaded.adaptation, MITRule)
    assert loaded.adaptation.settings() == ctrl.adaptation.settings()
    assert loaded.torque_budget == "split" and np.array_equal(loaded.theta_bound, ctrl.theta_bound)
    assert loaded.rmpc.resolve_threshold == 0.5
    assert not np.any(loaded.theta)  # run-time state is not in the file


def test_a_pickle_taken_mid_run_continues_the_run(tmp_path: Path) -> None:
    for build in (SOLVING["rmpc_kothare"], SOLVING["crmpc_lyapunov"], SOLVING["gipc_osqp"]):
        ctrl = build()
        problem = EX2 if isinstance(ctrl, CRMPC) else EX1
        a, b = problem.true_plant
        ctrl.reset()
        x = np.array(problem.x0, dtype=float)
        for _ in range(5):
            x = a @ x + b @ ctrl.step(x)
        copied = pickle.loads(pickle.dumps(ctrl))
        for _ in range(5):
            u = ctrl.step(x)
            np.testing.assert_allclose(copied.step(x), u, rtol=1e-6, atol=1e-9)
            assert copied.last.status == ctrl.last.status
            x = a @ x + b @ u


@pytest.mark.parametrize("kind", ["luenberger", "kalman", "kalman_disturbance"])
def test_estimators_round_trip_with_their_gain_as_computed(kind: str, tmp_path: Path) -> None:
    if kind == "luenberger":
        est = Luenberger(EX1.plant, C=[[1.0, 0.0]], poles=[0.5, 0.6], x0=[0.01, 0.0])
    elif kind == "kalman":
        est = KalmanFilter(EX2.plant, C=np.eye(4)[:2], process_noise=1e-4, measurement_noise=1e-2)
    else:
        est = KalmanFilter(EX2.plant, C=np.eye(4)[:2], process_noise=1e-4, measurement_noise=1e-2,
                           disturbance_model="input")
    loaded = rmpc.load(est.save(tmp_path / "est.rmpc"))
    copied = pickle.loads(pickle.dumps(est))
    assert type(loaded) is type(est) and np.array_equal(loaded.M, est.M) and loaded.dt == est.dt
    if isinstance(est, KalmanFilter):
        assert all(np.array_equal(getattr(loaded, k), getattr(est, k)) for k in ("P", "W", "V"))
    rng = np.random.default_rng(7)
    ys, us = rng.standard_normal((30, est.n_outputs)), rng.standard_normal((30, est.n_inputs))
    for e in (est, loaded, copied):
        e.reset()
    for k in range(30):
        u_prev = us[k - 1] if k else None
        x = est.update(ys[k], u_prev)
        assert np.array_equal(loaded.update(ys[k], u_prev), x)
        assert np.array_equal(copied.update(ys[k], u_prev), x)
    assert np.array_equal(loaded.d_hat, est.d_hat)


class MyRule(LyapunovRule):
    """A rule of the user's own (the toolkit's rule, subclassed)."""


def test_a_crmpc_with_a_rule_of_the_users_own_is_refused_by_save(tmp_path: Path) -> None:
    ctrl = CRMPC(EX1.plant, Q=EX1.Q, R=EX1.R, u_max=EX1.u_max, adaptation=MyRule())
    with pytest.raises(InvalidArgumentError, match=r"^adaptation: .*RULES.*MyRule"):
        ctrl.save(tmp_path / "mine.rmpc")
    assert not (tmp_path / "mine.rmpc").exists()
    pickle.loads(pickle.dumps(ctrl))  # pickle keeps it
