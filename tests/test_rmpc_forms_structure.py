"""Structural inequalities between the robust MPC forms, closed-loop bounds and bad input.

On MUP's demo system (three vertices, the third the nominal model; ``|u| <= 10``, ``|x_i| <=
10``) at seeded states inside the feasible region. Each inequality follows from the forms'
definitions (``docs/rmpc_forms.rst``): the vertex forms contain Kothare's (``G = Q_j = Q``),
pairs ``(i, i)`` are a subset of all pairs, the nominal cost bounds fewer plants, a free move
contains ``u0 = F x``, the auxiliary gain contains ``Z = Y``. Tolerance 1e-7 relative (the
certificate's): measured worst violation 0 (the inequalities hold with margins above 1e-3 except
where two forms coincide, e.g. auxiliary saturation at states where the bound does not bind,
where they agree to 2e-10).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_rmpc_forms_reference import kothare_1, mup_demo

from models import PolytopicModel
from rmpc import RMPC
from toolkit_common.errors import InvalidArgumentError

RTOL = 1e-7
PROBLEM = mup_demo()
PLANT = PolytopicModel(list(zip(PROBLEM["A"], PROBLEM["B"], strict=True)), dt=0.1,
                       nominal=(PROBLEM["A"][-1], PROBLEM["B"][-1]))
STATES = [r * np.array([np.cos(t), np.sin(t)])
          for r, t in zip(np.random.default_rng(24).uniform(0.5, 2.5, 4),
                          np.random.default_rng(25).uniform(0, 2 * np.pi, 4), strict=True)]


def controller(**options) -> RMPC:
    extra = dict(PROBLEM["extra"])
    extra.update(options)
    return RMPC(PLANT, PROBLEM["Q1"], PROBLEM["R"], u_max=PROBLEM["u_max"], input_constraint="peak", **extra)


def gamma(ctrl: RMPC, x: np.ndarray) -> float:
    sol = ctrl.solve(x)
    assert sol.status == "optimal", sol.status
    assert sol.certificate.ok
    return sol.gamma


@pytest.fixture(scope="module")
def gammas():
    forms = {
        "common": {}, "vertex": {"lyapunov": "vertex"}, "vertex_pairs": {"lyapunov": "vertex_pairs"},
        "nominal": {"cost": "nominal"}, "free": {"free_moves": 1},
        "vertex_free": {"lyapunov": "vertex", "free_moves": 1}, "auxiliary": {"saturation": "auxiliary"},
        "w0": {"disturbance": (np.array([[0.1], [0.0]]), 0.0)},
        "w_small": {"disturbance": (np.array([[0.1], [0.0]]), 1e-3)},
    }
    return {name: [gamma(controller(**opts), x) for x in STATES] for name, opts in forms.items()}


def test_lyapunov_forms_are_ordered(gammas):
    for v, p, c in zip(gammas["vertex"], gammas["vertex_pairs"], gammas["common"], strict=True):
        assert v <= p * (1 + RTOL)
        assert p <= c * (1 + RTOL)
    # and the vertex form is strictly better somewhere (MUP's demo: about 20%)
    assert min(v / c for v, c in zip(gammas["vertex"], gammas["common"], strict=True)) < 0.99


def test_nominal_cost_and_free_move_never_worse(gammas):
    for name, base in (("nominal", "common"), ("free", "common"), ("vertex_free", "vertex")):
        for g, g0 in zip(gammas[name], gammas[base], strict=True):
            assert g <= g0 * (1 + RTOL), (name, g, g0)


def test_auxiliary_saturation_feasible_where_kothare_is(gammas):
    for g, g0 in zip(gammas["auxiliary"], gammas["common"], strict=True):
        assert g <= g0 * (1 + RTOL)


def test_zero_disturbance_is_kothare_and_a_small_one_close_above(gammas):
    for g, g0 in zip(gammas["w0"], gammas["common"], strict=True):
        assert g == pytest.approx(g0, rel=RTOL)
    # measured: w_max = 1e-3 gives gamma 1.8e-11 relative above Kothare's at x0
    for g, g0 in zip(gammas["w_small"], gammas["common"], strict=True):
        assert g0 * (1 - RTOL) <= g <= g0 * (1 + 1e-3)


def test_soft_equals_hard_where_hard_is_feasible():
    """Weights 1e3 (above the bounds' multipliers): slacks ~0 and the same gamma. Measured at x0:
    gamma 2.4e-6 relative above the hard one (vertex form), slacks -5e-7 (squared units, inside
    the certificate's tolerance); bounds 1e-5 and 1e-5."""
    for lyapunov in ("common", "vertex"):
        for x in STATES[:2]:
            hard = controller(lyapunov=lyapunov).solve(x)
            soft = controller(lyapunov=lyapunov, soft={"u": 1e3, "y": 1e3}).solve(x)
            assert soft.status == "optimal"
            assert soft.gamma == pytest.approx(hard.gamma, rel=1e-5)
            assert max(abs(v) for v in soft.slack.values()) <= 1e-5


def test_soft_feasible_where_hard_is_not():
    x = 4.0 * PROBLEM["x"]
    assert controller().solve(x).status == "infeasible"
    soft = controller(soft={"u": 1e3, "y": 1e3}).solve(x)
    assert soft.status == "optimal"
    assert max(soft.slack.values()) > 1.0  # measured: s_y = 113.8
    assert min(soft.slack.values()) >= -1e-6


def _realised(plant_seq, F, x0, Q1, R, u_max, u0=None, saturate=False):
    x = np.asarray(x0, float)
    cost, peak = 0.0, 0.0
    for k, (A, B) in enumerate(plant_seq):
        u = F @ x
        if saturate:
            u = np.clip(u, -u_max, u_max)
        if k == 0 and u0 is not None:
            u = u0
        cost += float(x @ Q1 @ x + u @ R @ u)
        peak = max(peak, float(np.max(np.abs(u))))
        x = A @ x + B @ u
    return cost, peak, x


@pytest.mark.parametrize("problem_of", [mup_demo, kothare_1], ids=["mup_demo", "kothare_1"])
@pytest.mark.parametrize("options", [
    {}, {"lyapunov": "vertex"}, {"lyapunov": "vertex_pairs"}, {"free_moves": 1},
    {"lyapunov": "vertex_pairs", "saturation": "auxiliary"},
], ids=lambda o: "-".join(f"{k}={v}" for k, v in o.items()) or "kothare")
def test_realised_cost_with_fixed_gain_below_gamma(problem_of, options):
    """F held fixed after one solve: the cost over 400 steps on each vertex (and on randomly
    switching plants for the forms made for them) is below gamma, the input inside its bound."""
    p = problem_of()
    plant = PolytopicModel(list(zip(p["A"], p["B"], strict=True)), dt=0.1)
    ctrl = RMPC(plant, p["Q1"], p["R"], u_max=p["u_max"], input_constraint="peak", **options, **p["extra"])
    sol = ctrl.solve(p["x"])
    assert sol.status == "optimal"
    vertices = list(zip(p["A"], p["B"], strict=True))
    sequences = [[v] * 400 for v in vertices]
    if options.get("lyapunov", "common") != "vertex":
        rng = np.random.default_rng(5)
        sequences += [[vertices[i] for i in rng.integers(len(vertices), size=400)] for _ in range(3)]
    saturate = options.get("saturation") == "auxiliary"
    for seq in sequences:
        cost, peak, x_end = _realised(seq, sol.F, p["x"], p["Q1"], p["R"], p["u_max"], sol.u0, saturate)
        assert cost <= sol.gamma * (1 + RTOL), (cost, sol.gamma)
        assert peak <= p["u_max"] * (1 + 1e-6)
        assert np.linalg.norm(x_end) < 1e-6 * np.linalg.norm(p["x"])


def test_applied_input_is_the_free_move_or_the_saturated_gain():
    x = PROBLEM["x"]
    ctrl = controller(free_moves=1)
    sol = ctrl.solve(x)
    np.testing.assert_allclose(ctrl.step(x), sol.u0, rtol=1e-6, atol=1e-9)
    ctrl = controller(saturation="auxiliary")
    sol = ctrl.solve(x)
    np.testing.assert_allclose(ctrl.step(x), np.clip(sol.F @ x, -10.0, 10.0), rtol=1e-6, atol=1e-9)
    assert sol.H is not None and sol.G is None and sol.u0 is None


E_OK = np.array([[0.1], [0.0]])


@pytest.mark.parametrize(("options", "names"), [
    ({"lyapunov": "pairs"}, ["lyapunov"]),
    ({"cost": "best"}, ["cost"]),
    ({"free_moves": 2}, ["free_moves"]),
    ({"saturation": "clip"}, ["saturation"]),
    ({"disturbance": (np.ones((3, 1)), 0.1)}, ["disturbance"]),
    ({"disturbance": (E_OK, -0.1)}, ["w_max"]),
    ({"disturbance": (E_OK, 0.1, 1.5)}, ["lam"]),
    ({"soft": {"u": -1.0}}, ["soft"]),
    ({"soft": {"x": 1.0}}, ["soft"]),
    ({"saturation": "auxiliary", "input_constraint": "ellipsoid"}, ["saturation", "input_constraint"]),
    ({"free_moves": 1, "disturbance": (E_OK, 0.1)}, ["free_moves", "disturbance"]),
    ({"soft": {"u": [1.0, 0.0]}}, ["soft['u']", "1 values", "2 values"]),
    ({"soft": {"u": [0.0]}}, ["soft['u']", "at least one weight > 0"]),
    ({"soft": {"u": [1e9]}}, ["soft['u'][0]", "MAX_SOFT_WEIGHT"]),
    ({"soft": {"u": [1.0], "u_limit": [0.0]}}, ["soft['u_limit'][0]", "finite soft limit > 0"]),
    ({"soft": {"u": 1.0, "u_limit": [0.5]}}, ["soft['u']", "a list of weights"]),
    ({"soft": {"u_limit": [0.5]}}, ["soft", "at least one weight"]),
    ({"soft": {"u": [1.0]}, "input_constraint": "ellipsoid"}, ["soft, input_constraint", "'peak'"]),
])
def test_bad_options_name_the_argument(options, names):
    kwargs = {"u_max": 10.0, "input_constraint": "peak", **options}
    with pytest.raises(InvalidArgumentError) as info:
        RMPC(PLANT, PROBLEM["Q1"], PROBLEM["R"], **kwargs)
    for name in names:
        assert name in str(info.value)
