"""The machinery of :mod:`lmi.forms`: the variable layout, the certificate, the back-ends, proofs of
infeasibility, warm starts, and which problem :class:`rmpc.RMPC` builds.

The forms' values are checked against an independent cvxpy construction in
``test_rmpc_forms_reference.py`` and against each other in ``test_rmpc_forms_structure.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from lmi import KothareProblem
from lmi.forms import FormProblem
from lmi.forms.lmis import delta_congruence, write
from lmi.forms.program import Layout, Program
from models import PolytopicModel
from rmpc import RMPC


def two_masses(k: float) -> list[list[float]]:
    return [[1, 0, .1, 0], [0, 1, 0, .1], [-.1 * k, .1 * k, 1, 0], [.1 * k, -.1 * k, 0, 1]]


EX2 = dict(A=[two_masses(0.5), two_masses(10.0)], B=[[[0], [0], [.1], [0]]] * 2, Q=np.eye(4), R=[[1.0]],
           u_max=1.0)
X2 = np.array([1.0, 1.0, 0.0, 0.0])
MUP_A = [[[.93, .51], [.38, .83]], [[.06, .26], [1.8, .87]], [[.5, .39], [1.1, .85]]]
MUP = dict(A=MUP_A, B=[[[-1.45], [-.70]]] * 3, Q=np.eye(2), R=[[1.0]], u_max=10.0, input_constraint="peak",
           output_matrix=np.eye(2), y_max=[10.0, 10.0])


def test_layout_vector_and_values_are_inverse():
    lay = Layout()
    lay.full("gamma", 1, 1)
    lay.symmetric("Q", 3)
    lay.full("Y", 2, 3)
    rng = np.random.default_rng(0)
    sym = rng.normal(size=(3, 3))
    values = {"gamma": np.array([[2.5]]), "Q": sym + sym.T, "Y": rng.normal(size=(2, 3))}
    z = lay.vector(values)
    assert z.shape == (1 + 6 + 6,)
    back = lay.values(z)
    for name, value in values.items():
        np.testing.assert_array_equal(back[name], value)
    np.testing.assert_array_equal(lay.vector(back), z)


def test_delta_congruence_is_invertible_and_keeps_the_sign_of_a_block():
    rng = np.random.default_rng(1)
    lmat = delta_congruence(3, 2, 0.01, 0.1)
    assert abs(np.linalg.det(lmat)) > 0.0
    root = rng.normal(size=(8, 8))
    psd = root @ root.T
    indefinite = psd - 2.0 * np.linalg.eigvalsh(psd)[-1] * np.eye(8)[:, :1] @ np.eye(8)[:1]
    assert np.linalg.eigvalsh(lmat @ psd @ lmat.T)[0] > 0.0
    assert np.linalg.eigvalsh(lmat @ indefinite @ lmat.T)[0] < 0.0  # Sylvester's law of inertia


@pytest.mark.parametrize("lyapunov", ["common", "vertex", "vertex_pairs"])
def test_the_certificate_rejects_a_smaller_gamma(lyapunov):
    """Every block is recomputed at the answer: the same matrices with gamma 1 % lower violate a
    cost block, printed and after the delta congruence."""
    prob = FormProblem(**EX2, lyapunov=lyapunov)
    sol = prob.solve(X2)
    assert sol.status == "optimal" and sol.certificate.ok
    values = {"gamma": np.array([[sol.gamma]]), "Y": sol.Y}
    if lyapunov == "common":
        values["Q"] = sol.Q
    else:
        values["G"] = sol.G
        values.update({f"Q{j}": q for j, q in enumerate(sol.Q_vertices)})
    fd = prob._form_data(X2, prob.data.u_max, prob.data.y_max, 0.0, 1.0, t=np.ones(4))
    # the shared W at its best value for these matrices (Schur complement of the shared block)
    if "W0" in prob.layout:
        g_mat = values.get("G", values.get("Q"))
        values["W0"] = (g_mat.T @ prob.data.Q1 @ g_mat + sol.Y.T @ prob.data.R @ sol.Y) / (fd.dt * sol.gamma)
    margins = write(Program(prob.layout, values), prob.options, fd).margins()
    cost = {k: v for k, v in margins.items() if k.startswith("cost")}
    assert min(cost.values()) > -1e-6
    values["gamma"] = np.array([[0.99 * sol.gamma]])
    if "W0" in values:
        values["W0"] = values["W0"] / 0.99
    margins = write(Program(prob.layout, values), prob.options, fd).margins()
    assert min(v for k, v in margins.items() if k.startswith("cost")) < -1e-4
    assert any(k.endswith("_delta") for k in margins)


def test_an_infeasible_problem_is_proved_so_with_a_checked_farkas_certificate():
    """A disturbance the input bound cannot reject, contraction factor given: the ipm's ray is
    checked on the conic data and the status is "infeasible" (not a fallback's numerical error)."""
    prob = FormProblem(**EX2, lyapunov="vertex", disturbance=(0.1 * np.eye(4)[:, :1], 0.05, 0.9))
    sol = prob.solve(X2)
    assert sol.status == "infeasible"
    assert sol.infeasibility is not None and sol.infeasibility.ok
    assert sol.F is None and np.isnan(sol.gamma)


@pytest.mark.parametrize("options", [{"lyapunov": "vertex"}, {"free_moves": 1}, {"cost": "nominal"}])
def test_the_backends_agree_on_mup_demo(options):
    """ipm, Clarabel's API and cvxpy + Clarabel on the same LMIs: gamma to 1e-6 relative (measured:
    3e-9 or closer on these three)."""
    x = np.array([3.0, 0.0])
    extra = {"nominal": (MUP_A[2], MUP["B"][2])} if options.get("cost") == "nominal" else {}
    gammas = []
    for backend in ("ipm", "clarabel", "cvxpy"):
        sol = FormProblem(**MUP, **options, **extra, backend=backend).solve(x)
        assert sol.status == "optimal", (backend, sol.status, sol.solver_status)
        gammas.append(sol.gamma)
    assert max(gammas) - min(gammas) <= 1e-6 * max(gammas)


def test_warm_started_solves_give_the_cold_answers():
    prob = FormProblem(**EX2, lyapunov="vertex_pairs")
    states = [X2, 0.7 * X2 + np.array([0, 0, 0.1, 0]), 0.4 * X2]
    warm = [prob.solve(x) for x in states]
    for x, sol in zip(states, warm, strict=True):
        cold = FormProblem(**EX2, lyapunov="vertex_pairs").solve(x)
        assert sol.status == cold.status == "optimal"
        assert abs(sol.gamma - cold.gamma) <= 1e-7 * cold.gamma
    assert max(s.iterations for s in warm[1:]) < warm[0].iterations


def test_rmpc_keeps_kothares_problem_for_the_default_form():
    plant = PolytopicModel(list(zip(np.asarray(EX2["A"]), np.asarray(EX2["B"]), strict=True)), dt=0.1)
    default = RMPC(plant, EX2["Q"], EX2["R"], u_max=1.0)
    zero_w = RMPC(plant, EX2["Q"], EX2["R"], u_max=1.0, disturbance=(np.ones((4, 1)), 0.0))
    vertex = RMPC(plant, EX2["Q"], EX2["R"], u_max=1.0, lyapunov="vertex")
    assert type(default.problem) is KothareProblem and type(zero_w.problem) is KothareProblem
    assert type(vertex.problem) is FormProblem
    assert default.solve(X2).gamma == zero_w.solve(X2).gamma
    assert vertex.solve(X2).gamma < default.solve(X2).gamma


def test_a_disturbance_that_reaches_past_an_output_bound_is_refused():
    with pytest.raises(Exception, match="disturbance, y_max"):
        FormProblem(**MUP, disturbance=(np.array([[100.0], [0.0]]), 0.2))


def test_a_form_too_large_for_dense_coefficients_is_refused(monkeypatch):
    import lmi.forms.problem as problem

    # Kothare's example 2: "vertex" 7 blocks in 51 variables, about 0.39 MB; "vertex_pairs" 9, 0.55 MB
    monkeypatch.setattr(problem, "MAX_COEFFICIENT_BYTES", 4.5e5)
    FormProblem(**EX2, lyapunov="vertex", backend="ipm")
    expected = r"plant, lyapunov: .* 2 vertices, lyapunov='vertex_pairs': \d+ blocks of orders up to"
    with pytest.raises(Exception, match=expected) as err:
        FormProblem(**EX2, lyapunov="vertex_pairs", backend="ipm")
    assert "saturation" not in str(err.value)  # not set: the message names only what was given


def test_a_failed_solve_is_retried_in_coordinates_balanced_on_its_lyapunov_matrix():
    """Kothare's example 2 with the nominal cost, peak bound 1, at 64 x0: the first run stalls
    ("inaccurate", its certificate fails by 3e-4); balanced on its Q the retry ends "optimal" and
    certified (measured: gamma 8.962e6, below the worst case's 9.673e6). Without the retry (and
    without the fallback) the answer is not usable. reset() restores the first coordinates."""
    nominal = (np.mean(EX2["A"], axis=0), EX2["B"][0])
    base = dict(EX2, input_constraint="peak", nominal=nominal, cost="nominal")
    x = 64.0 * X2
    sol = FormProblem(**base).solve(x)
    assert sol.status == "optimal" and "rebalanced" in sol.solver_status
    worst = KothareProblem(EX2["A"], EX2["B"], EX2["Q"], EX2["R"], input_constraint="peak", u_max=1.0)
    worst = worst.solve(x)
    assert sol.gamma < worst.gamma
    off = FormProblem(**base, solver_options={"rebalance": False, "fallback": False}).solve(x)
    assert off.status != "optimal"
    prob = FormProblem(**base)
    prob.solve(x)
    prob.reset()
    again = prob.solve(x)
    assert again.solver_status == sol.solver_status and again.gamma == sol.gamma


def test_layout_values_are_the_affine_variables_values_bit_for_bit():
    """``Layout.values`` gathers the entries from ``z`` by index; each equals the value of the
    variable's affine matrix at ``z`` exactly (a symmetric variable's both triangles, a full
    variable row-major), also for a variable declared after a first call."""
    from lmi.forms.program import Layout

    lay = Layout()
    lay.full("gamma", 1, 1)
    lay.symmetric("Q0", 5)
    lay.full("Y", 2, 5)
    rng = np.random.default_rng(3)
    z = rng.normal(size=lay.size)
    got = lay.values(z)
    assert set(got) == {"gamma", "Q0", "Y"}
    for name in got:
        assert np.array_equal(got[name], lay.affine(name).value(z)), name
    assert np.array_equal(got["Q0"], got["Q0"].T)
    lay.symmetric("Q1", 3)
    z = np.concatenate([z, rng.normal(size=6)])
    assert np.array_equal(lay.values(z)["Q1"], lay.affine("Q1").value(z))
    assert np.array_equal(lay.vector(lay.values(z)), z)  # the inverse of Layout.vector
