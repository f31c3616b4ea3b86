"""The forms with steps (``horizon``, ``step_gains``): Li, Shi, Sun & Wang's two-step gains (MUP's
``li``) and Shi, Su & Chu's N steps with chained Lyapunov matrices (MUP's ``shi``).

Checked against an independent cvxpy construction written after MUP's ``sdp_li.m`` and
``sdp_shi.m`` in MUP's own variables (:func:`reference_forms.reference_steps`): the toolkit's
answer, mapped to MUP's variables (Shi's ``Z`` is ``Y - H G``: MUP bounds ``Y - Z``), satisfies
every LMI of the reference (measured worst relative smallest eigenvalue -1.6e-12; bound -1e-8);
on MUP's demo, where Clarabel's answer is accurate, the two gammas agree (measured 1e-9
relative; bound 1e-5). On Kothare's example 2 Clarabel fails on li ("solver_error") and is
inaccurate on shi (residual -4e-6, gamma 2.6 % below the toolkit's certified one), so only the
first check applies there.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from reference_forms import reference_steps, steps_values
from test_rmpc_forms_reference import kothare_2, mup_demo

from lmi.forms import MAX_HORIZON, FormProblem
from models import PolytopicModel
from rmpc import RMPC, load
from toolkit_common.errors import ArgumentTypeError, InvalidArgumentError

AGREE_RTOL = 1e-5
CLARABEL_ACCURATE = -1e-9
#: gamma of a form that contains Kothare's answer may exceed Kothare's by the solvers' accuracy only
NOT_WORSE_RTOL = 1e-6

LI = {"horizon": 2, "step_gains": "vertex"}
SHI = {"horizon": 3, "lyapunov": "vertex_pairs", "saturation": "auxiliary"}
#: (MUP's method, options): the papers' forms, and the chain with the other Lyapunov forms
FORMS = [
    ("li", LI),
    ("shi", SHI),
    ("shi", {"horizon": 2, "lyapunov": "common"}),
    ("shi", {"horizon": 2, "lyapunov": "vertex"}),
    ("shi", {"horizon": 2, "lyapunov": "vertex_pairs"}),
]
PROBLEMS = {"kothare_2": kothare_2, "mup_demo": mup_demo}


def _plant(problem: dict) -> PolytopicModel:
    return PolytopicModel(list(zip(problem["A"], problem["B"], strict=True)), dt=0.1)


def _rmpc(problem: dict, **options) -> RMPC:
    return RMPC(_plant(problem), problem["Q1"], problem["R"], u_max=problem["u_max"], input_constraint="peak",
                **options, **problem["extra"])


def _reference(problem: dict, method: str, options: dict, at: dict | None = None):
    args = (problem["A"], problem["B"], problem["Q1"], problem["R"], problem["x"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return reference_steps(
            *args, u_max=problem["u_max"], method=method, horizon=options["horizon"],
            lyapunov=options.get("lyapunov", "common"), saturation=options.get("saturation"), at=at,
            **problem["extra"])


@pytest.mark.parametrize("method, options", FORMS, ids=lambda v: v if isinstance(v, str) else
                         "-".join(f"{k}={o}" for k, o in v.items()))
@pytest.mark.parametrize("name", list(PROBLEMS))
def test_optimal_certified_and_the_references_lmis_hold(name, method, options):
    problem = PROBLEMS[name]()
    sol = _rmpc(problem, **options).solve(problem["x"])
    assert sol.status == "optimal" and sol.certificate.ok
    values = steps_values(sol, method, options["horizon"], len(problem["A"]))
    _, _, at = _reference(problem, method, options, at=values)
    # the reference's LMIs hold at the answer to the tolerance the toolkit certified it with
    # (relative margins >= -certificate_tol): -1e-8 promised more than that and measured -2.0e-8 for
    # shi on example 2 with OPENBLAS_CORETYPE=SandyBridge (-1e-12 on this machine's default BLAS)
    assert at["residual"] >= -sol.certificate.tol, (at["residual"], sol.certificate.tol)
    status, gamma, var = _reference(problem, method, options)
    if status == "optimal" and var["residual"] >= CLARABEL_ACCURATE:
        assert sol.gamma == pytest.approx(gamma, rel=AGREE_RTOL)
    # otherwise Clarabel's minimum is not to be trusted (Kothare's example 2; on MUP's demo the
    # chain with one Lyapunov matrix, "optimal_inaccurate" at residual -3e-9): the check above


def test_mup_demo_clarabel_is_accurate_for_both_methods():
    """The agreement branch above is the one taken on MUP's demo (not the fallback)."""
    problem = mup_demo()
    for method, options in FORMS[:2]:
        status, _, var = _reference(problem, method, options)
        assert status == "optimal" and var["residual"] >= CLARABEL_ACCURATE


STATES = {
    # where Kothare's problem is feasible (x1 != x2 at rest is not, e.g. (1, 0.9, 0, 0))
    "kothare_2": [[1.0, 1.0, 0.0, 0.0], [0.5, 0.5, 0.0, 0.0], [1.0, 1.0, 0.1, -0.1], [-1.0, -1.0, 0.1, 0.0],
                  [1.0, 1.0, 0.0, 0.2]],
    "mup_demo": [[3.0, 0.0], [1.5, 0.0], [0.0, 3.0], [2.0, -2.0], [-3.0, 1.0]],
}


@pytest.mark.parametrize("key", ["li", "shi"])
@pytest.mark.parametrize("name", list(PROBLEMS))
def test_never_worse_than_kothare(name, key):
    """Kothare's answer is feasible for both (li: ``X = Q``, ``Y_v = F (A_v Q + B_v Y)``; shi:
    every step's variables Kothare's), so their gamma is never above Kothare's."""
    problem = PROBLEMS[name]()
    plant = _plant(problem)
    common = {"Q": problem["Q1"], "R": problem["R"], "u_max": problem["u_max"], **problem["extra"]}
    kothare = RMPC.from_method("kothare", plant, **common)
    method = RMPC.from_method(key, plant, **common)
    better = 0
    for x in np.array(STATES[name]):
        ref, sol = kothare.solve(x), method.solve(x)
        assert ref.status == sol.status == "optimal", (x, ref.status, sol.status)
        assert sol.gamma <= ref.gamma * (1.0 + NOT_WORSE_RTOL), (x, sol.gamma, ref.gamma)
        better += sol.gamma < ref.gamma * (1.0 - 1e-3)
    assert better >= 1  # and strictly better somewhere: the steps do something


def test_a_longer_horizon_is_never_worse_and_one_step_is_the_form_without_steps():
    """``horizon=N`` contains ``N - 1`` (the last two steps equal); ``horizon=1`` is the form of
    :mod:`lmi.forms.lmis` itself (the same variables and blocks)."""
    problem = kothare_2()
    gammas = []
    for horizon in (1, 2, 3):
        sol = _rmpc(problem, lyapunov="vertex_pairs", horizon=horizon).solve(problem["x"])
        assert sol.status == "optimal"
        gammas.append(sol.gamma)
    assert gammas[1] <= gammas[0] * (1 + NOT_WORSE_RTOL) and gammas[2] <= gammas[1] * (1 + NOT_WORSE_RTOL)
    assert gammas[2] < 0.9 * gammas[0]  # measured 189.5 (3 steps) against 258.1 (1)
    plain = _rmpc(problem, lyapunov="vertex_pairs").solve(problem["x"])
    assert gammas[0] == plain.gamma
    args = (problem["A"], problem["B"], problem["Q1"], problem["R"])
    one = FormProblem(*args, u_max=1.0, horizon=1, lyapunov="vertex_pairs")
    assert one.layout.names == FormProblem(*args, u_max=1.0, lyapunov="vertex_pairs").layout.names
    assert "Y@2" not in one.layout


def test_the_law_is_the_first_steps_gain_and_the_loop_keeps_the_bounds():
    """``F = Y X^-1`` of the first step (MUP's refo_li.m / refo_shi.m read ``X{1}, Y{1}``), and
    the closed loop on switching vertices converges within the input and output bounds."""
    problem = mup_demo()
    plant = _plant(problem)
    rng = np.random.default_rng(3)
    for key in ("li", "shi"):
        ctrl = RMPC.from_method(key, plant, Q=problem["Q1"], R=problem["R"], u_max=problem["u_max"],
                                **problem["extra"])
        sol = ctrl.solve(problem["x"])
        g_mat = sol.G if sol.G is not None else sol.Q
        np.testing.assert_allclose(sol.F, sol.Y @ np.linalg.inv(g_mat), rtol=1e-10)
        x = problem["x"].copy()
        for _ in range(25):
            u = ctrl.step(x)
            assert not ctrl.last.fallback and ctrl.last.status == "optimal"
            assert np.all(np.abs(u) <= problem["u_max"] * (1 + 1e-6))
            v = rng.integers(len(problem["A"]))
            x = problem["A"][v] @ x + problem["B"][v] @ u
            assert np.all(np.abs(x) <= 10.0 * (1 + 1e-6))  # MUP's demo bounds the states by 10
            if np.linalg.norm(x) < 1e-3:
                break
        assert np.linalg.norm(x) < 1e-2 * np.linalg.norm(problem["x"]), (key, x)


@pytest.mark.parametrize("options", [LI, SHI], ids=["li", "shi"])
def test_saved_and_loaded(tmp_path, options):
    problem = mup_demo()
    ctrl = _rmpc(problem, **options)
    ctrl.save(tmp_path / "c.rmpc")
    back = load(tmp_path / "c.rmpc")
    want = (options["horizon"], options.get("step_gains", "common"))
    assert (back.form.horizon, back.form.step_gains) == want
    assert back.solve(problem["x"]).gamma == pytest.approx(ctrl.solve(problem["x"]).gamma, rel=1e-9)


def test_a_design_without_steps_saves_as_before(tmp_path):
    problem = mup_demo()
    ctrl = _rmpc(problem, lyapunov="vertex")
    assert "horizon" not in ctrl._arguments and "step_gains" not in ctrl._arguments
    ctrl.save(tmp_path / "c.rmpc")
    assert load(tmp_path / "c.rmpc").form.horizon == 1


BAD = [
    ({"horizon": 0}, InvalidArgumentError, r"horizon: expected an integer from 1 to MAX_HORIZON"),
    ({"horizon": MAX_HORIZON + 1}, InvalidArgumentError, rf"horizon: .*found {MAX_HORIZON + 1}"),
    ({"horizon": 2.0}, ArgumentTypeError, r"horizon: expected an integer.*found float 2.0"),
    ({"horizon": True}, ArgumentTypeError, r"horizon: .*found bool True"),
    ({"step_gains": "per_vertex"}, InvalidArgumentError, r"step_gains: expected one of 'common', 'vertex'"),
    ({"step_gains": "vertex"}, InvalidArgumentError, r"step_gains, horizon: .*horizon=2"),
    ({"step_gains": "vertex", "horizon": 3}, InvalidArgumentError, r"step_gains, horizon"),
    ({**LI, "lyapunov": "vertex"}, InvalidArgumentError, r"step_gains, lyapunov: .*lyapunov='common'"),
    ({**LI, "saturation": "auxiliary"}, InvalidArgumentError, r"step_gains, saturation"),
    ({"horizon": 2, "cost": "nominal"}, InvalidArgumentError, r"horizon, cost: "),
    ({"horizon": 2, "free_moves": 1}, InvalidArgumentError, r"horizon, free_moves: "),
    ({"horizon": 2, "soft": {"u": 10.0}}, InvalidArgumentError, r"horizon, soft: "),
    ({"horizon": 2, "disturbance": (np.ones((2, 1)), 0.1)}, InvalidArgumentError, r"horizon, disturbance: "),
    ({"horizon": 2, "resolve_threshold": 0.5}, InvalidArgumentError, r"resolve_threshold, horizon: "),
]


@pytest.mark.parametrize("options, error, message", BAD, ids=[str(i) for i in range(len(BAD))])
def test_bad_input_names_the_argument(options, error, message):
    with pytest.raises(error, match=message):
        _rmpc(mup_demo(), **options)


def test_numpy_integers_are_horizons():
    ctrl = _rmpc(mup_demo(), horizon=np.int64(2))
    assert ctrl.form.horizon == 2 and type(ctrl.form.horizon) is int
    assert _rmpc(mup_demo(), horizon=MAX_HORIZON).form.horizon == MAX_HORIZON


def test_the_cvxpy_backend_solves_the_same_program():
    problem = mup_demo()
    for options in (LI, SHI):
        ipm = _rmpc(problem, **options).solve(problem["x"])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ref = _rmpc(problem, backend="cvxpy", **options).solve(problem["x"])
        assert ref.status in ("optimal", "inaccurate") and ref.certificate.ok
        assert ipm.gamma == pytest.approx(ref.gamma, rel=1e-5)


def test_a_form_too_large_for_memory_names_the_horizon():
    """The size check of :class:`lmi.forms.FormProblem` counts every step's blocks and variables
    and names ``horizon`` among the causes (14 states, 8 vertices, 8 steps: about 224 GB)."""
    rng = np.random.default_rng(0)
    n, m = 14, 3
    A = [np.eye(n) + 0.01 * rng.normal(size=(n, n)) for _ in range(8)]
    B = [0.01 * rng.normal(size=(n, m)) for _ in range(8)]
    message = r"plant, lyapunov, horizon: .*a shorter horizon.*horizon=8"
    with pytest.raises(InvalidArgumentError, match=message):
        FormProblem(A, B, np.eye(n), np.eye(m), u_max=[1.0] * m, input_constraint="peak",
                    lyapunov="vertex_pairs", horizon=8)
    FormProblem(A[:2], B[:2], np.eye(n), np.eye(m), u_max=[1.0] * m, input_constraint="peak", horizon=2)
