"""The disturbance form's search for its contraction factor ``lam`` (:mod:`lmi.forms.problem`).

At a state after one with a certified answer, the warm search brackets the minimum around the
previous state's ``lam`` and refines it by parabolic steps (``solver_options={"lambda_search":
"warm"}``, the default); otherwise, or when its bracket holds no interior minimum or a solve in it
fails, the full search (the grid :data:`lmi.forms.problem.LAMBDA_GRID`, then golden section) runs,
as it does at every state with ``"lambda_search": "grid"``. The solves are counted by a spy on
``FormProblem._solve_at`` (one call per ``lam``), never timed.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from lmi.forms import FormProblem
from lmi.forms.problem import LAMBDA_FLAT, LAMBDA_GRID, LAMBDA_REFINE
from toolkit_common.errors import InvalidArgumentError

FULL = len(LAMBDA_GRID) + LAMBDA_REFINE  # the full search's solves when the grid certifies one


def kothare_ex1() -> tuple[dict, np.ndarray, np.ndarray]:
    """Kothare's example 1 (angular positioning) with an input-channel disturbance, ``w_max`` 5 % of
    the input bound (the methods bench's "disturbance" method); the nominal plant, its start state."""

    def a_of(alpha: float) -> list[list[float]]:
        return [[1.0, 0.1], [0.0, 1.0 - 0.1 * alpha]]

    b = [[0.0], [0.1 * 0.787]]
    kw = dict(A=[a_of(0.1), a_of(10.0)], B=[b, b], Q=np.diag([1.0, 0.0]), R=[[2e-5]], u_max=2.0,
              input_constraint="peak", disturbance=(np.array(b), 0.1))
    return kw, np.array(a_of(1.0)), np.array([0.05, 0.0])


def double_integrator() -> tuple[dict, np.ndarray, np.ndarray]:
    """The double integrator of the tube literature, ``|x_i| <= 10``, ``||w|| <= 0.1 sqrt(2)``."""
    a = [[1.0, 1.0], [0.0, 1.0]]
    kw = dict(A=[a], B=[[[0.5], [1.0]]], Q=np.eye(2), R=[[0.01]], u_max=1.0, input_constraint="peak",
              output_matrix=np.eye(2), y_max=[10.0, 10.0], disturbance=(np.eye(2), 0.1 * math.sqrt(2.0)))
    return kw, np.array(a), np.array([-5.0, -2.0])


def spy(prob: FormProblem) -> list[float]:
    """The ``lam`` of every ``_solve_at`` call of ``prob``, in order."""
    calls: list[float] = []
    inner = prob._solve_at

    def counted(x, scale, xs, us, ys, w_max, lam, **kwargs):
        calls.append(lam)
        return inner(x, scale, xs, us, ys, w_max, lam, **kwargs)

    prob._solve_at = counted  # type: ignore[method-assign]
    return calls


def closed_loop_states(kw: dict, a: np.ndarray, x0: np.ndarray, steps: int) -> list[np.ndarray]:
    """The states of the grid search's law on the plant ``a`` (input column of the first vertex)."""
    prob = FormProblem(**kw, solver_options={"lambda_search": "grid"})
    b = np.asarray(kw["B"][0], dtype=float)
    x, states = x0.copy(), []
    for _ in range(steps):
        states.append(x.copy())
        sol = prob.solve(x)
        assert sol.ok, sol.solver_status
        x = a @ x + b @ (sol.F @ x)
    return states


@pytest.fixture(scope="module", params=["kothare_ex1", "double_integrator"])
def searched(request):
    """Per problem: the states of a closed loop, each solved in order by the warm and the full search
    (the solves of each counted)."""
    kw, a, x0 = {"kothare_ex1": kothare_ex1, "double_integrator": double_integrator}[request.param]()
    states = closed_loop_states(kw, a, x0, 6)
    out: dict = {"kw": kw, "states": states}
    for how in ("warm", "grid"):
        prob = FormProblem(**kw, solver_options={"lambda_search": how})
        calls = spy(prob)
        sols, counts, records = [], [], []
        for x in states:
            before = len(calls)
            sols.append(prob.solve(x))
            counts.append(len(calls) - before)
            records.append(prob.last_lambda_search)
        out[how] = (sols, counts, records)
    return out


def test_the_warm_search_needs_far_fewer_solves_after_the_first_state(searched):
    warm_counts, grid_counts = searched["warm"][1], searched["grid"][1]
    assert grid_counts == [FULL] * len(grid_counts)
    assert warm_counts[0] == FULL  # no previous lam: the grid
    assert all(c <= 8 for c in warm_counts[1:]), warm_counts
    assert sum(warm_counts[1:]) <= 0.4 * sum(grid_counts[1:])
    records = searched["warm"][2]
    assert [r.how for r in records] == ["grid"] + ["warm"] * (len(records) - 1)
    assert [r.solves for r in records] == warm_counts  # the record counts what the spy counts


def test_the_warm_search_finds_the_full_searchs_gamma_and_every_answer_is_certified(searched):
    for warm, grid in zip(searched["warm"][0], searched["grid"][0], strict=True):
        assert warm.ok and grid.ok
        assert warm.certificate is not None and warm.certificate.ok
        assert abs(warm.gamma - grid.gamma) <= 1e-4 * grid.gamma, (warm.gamma, grid.gamma, warm.lam, grid.lam)
        assert 0.0 < warm.lam < 1.0


def test_the_retuned_solver_solves_the_lmis_of_its_lam(searched):
    """Each warm answer (its solver retuned from lam to lam) has the gamma a fresh problem with that
    lam given finds."""
    kw = searched["kw"]
    e_mat, w_max = kw["disturbance"]
    for x, warm, record in zip(searched["states"], searched["warm"][0], searched["warm"][2], strict=True):
        if record.how != "warm":
            continue
        fixed = FormProblem(**{**kw, "disturbance": (e_mat, w_max, warm.lam)}).solve(x)
        assert fixed.ok
        assert abs(warm.gamma - fixed.gamma) <= 1e-6 * fixed.gamma, (warm.gamma, fixed.gamma)


def test_the_warm_searchs_solver_holds_the_coefficients_of_the_lam_it_last_solved():
    """The one kept solver of the warm search, retuned from lam to lam: its blocks' coefficients are
    those a fresh symbolic program writes at its last lam (and differ from another lam's)."""
    kw, a, x0 = kothare_ex1()
    states = closed_loop_states(kw, a, x0, 4)
    prob = FormProblem(**kw)
    lams = []
    for x in states:
        prob.solve(x)
        lams.append(prob.last_lambda_search.lams[-1])
    solver = prob._solvers[("ipm", "warm", False)]
    assert solver.form_lam == lams[-1]

    def coefficients(lam: float) -> list[np.ndarray]:
        fd = prob._form_data(states[-1], prob.data.u_max, prob.data.y_max, 0.1, lam)
        return [coef for _, coef in prob._symbolic(fd).solver_blocks()]

    now, other = coefficients(solver.form_lam), coefficients(0.5 * solver.form_lam)
    assert all(np.allclose(solver._coef[j], now[j], rtol=0.0, atol=1e-12) for j in range(len(now)))
    assert not all(np.allclose(solver._coef[j], other[j], rtol=0.0, atol=1e-12) for j in range(len(now)))


def fake(prob: FormProblem, objective, infeasible=lambda lam: False, slopes: bool = False) -> list[float]:
    """Replace ``prob._solve_at`` by certified answers whose ``gamma`` is ``objective(lam)`` (one real
    certified answer, its gamma and lam rewritten), ``"infeasible"`` where ``infeasible(lam)``; with
    ``slopes``, each certified answer's ``d gamma / d lam`` too (central differences of ``objective``),
    as the ipm's dual gives it, else none (the search by values alone)."""
    kw, _, x0 = kothare_ex1()
    real = FormProblem(**{**kw, "disturbance": (kw["disturbance"][0], 0.1, 0.9)}).solve(x0)
    assert real.ok
    calls: list[float] = []

    def solve_at(x, scale, xs, us, ys, w_max, lam, **kwargs):
        calls.append(lam)
        prob._last_slope = None
        if infeasible(lam):
            return dataclasses.replace(real, status="infeasible", gamma=math.nan, lam=lam)
        if slopes:
            h = 1e-7
            prob._last_slope = (objective(lam + h) - objective(lam - h)) / (2.0 * h)
        return dataclasses.replace(real, gamma=objective(lam), lam=lam)

    prob._solve_at = solve_at  # type: ignore[method-assign]
    return calls


def logit(lam: float) -> float:
    return math.log(lam / (1.0 - lam))


@pytest.mark.parametrize("slopes", [False, True])
def test_a_minimum_near_the_previous_lam_is_found_by_the_bracket_and_refinement(slopes):
    kw, _, x0 = kothare_ex1()
    prob = FormProblem(**kw)
    calls = fake(prob, lambda lam: 1.0 + (logit(lam) - logit(0.62)) ** 2, slopes=slopes)
    prob._lam_prev = 0.6
    sol = prob.solve(x0)
    assert prob.last_lambda_search.how == "warm" and prob.last_lambda_search.fallback is None
    assert len(calls) <= (3 if slopes else 5)
    assert abs(logit(sol.lam) - logit(0.62)) < 1e-3
    assert prob._lam_prev == sol.lam  # the next state's bracket centre


def after_a_first_warm_search() -> tuple:
    """``(prob, calls, centre, first, x0)``: the objective ``1 + 2 (t - c)^2`` (``t`` the log-odds of
    lam, ``c = centre[0]``) searched warm from lam 0.6; the search finds ``c`` in three solves and
    keeps the curvature 4."""
    kw, _, x0 = kothare_ex1()
    prob = FormProblem(**kw)
    centre = [logit(0.62)]
    calls = fake(prob, lambda lam: 1.0 + 2.0 * (logit(lam) - centre[0]) ** 2, slopes=True)
    prob._lam_prev = 0.6
    first = prob.solve(x0)
    assert prob.last_lambda_search.how == "warm" and len(calls) == 3
    assert prob._lam_curvature == pytest.approx(4.0, rel=1e-4)
    return prob, calls, centre, first, x0


def test_the_next_state_starts_with_a_newton_step_on_the_kept_curvature():
    """After the first warm search (:func:`after_a_first_warm_search`), ``c`` moves by 5e-3: one
    Newton step from the previous lam lands where the slope is flat: two solves."""
    prob, calls, centre, first, x0 = after_a_first_warm_search()
    assert abs(logit(first.lam) - centre[0]) < 1e-5
    centre[0] += 5e-3
    second = prob.solve(x0)
    assert prob.last_lambda_search.how == "warm" and len(calls) == 3 + 2
    assert abs(logit(second.lam) - centre[0]) < 1e-5


def test_no_step_when_the_kept_curvature_predicts_a_gain_below_the_flat_tolerance():
    """After the first warm search (:func:`after_a_first_warm_search`), ``c`` moves by 4e-4; a
    Newton step would gain ``(4 * 4e-4)^2 / (2 * 4) = 3.2e-7`` relative, less than
    :data:`LAMBDA_FLAT`: the search ends after the solve at the previous lam, within that of the
    minimum. At 5e-3 (a gain of 5e-5) it steps (the test above)."""
    prob, calls, centre, first, x0 = after_a_first_warm_search()
    centre[0] += 4e-4
    second = prob.solve(x0)
    assert prob.last_lambda_search.how == "warm" and len(calls) == 3 + 1
    assert second.lam == first.lam
    assert 1.0 < second.gamma <= 1.0 + LAMBDA_FLAT
    # the next state starts at the Newton step's end, the moved minimum
    assert abs(logit(prob._lam_prev) - centre[0]) < 1e-9
    centre[0] += 4e-4  # the minimum drifts on by as much: again one solve
    third = prob.solve(x0)
    assert len(calls) == 3 + 2 and abs(logit(third.lam) - (centre[0] - 4e-4)) < 1e-9
    assert 1.0 < third.gamma <= 1.0 + LAMBDA_FLAT


@pytest.mark.parametrize("slopes", [False, True])
def test_no_interior_minimum_in_the_bracket_falls_back_to_the_full_grid(slopes):
    """The minimum (at lam = 0.97) lies beyond the bracket around lam = 0.2 and its three expansions:
    the full search runs, and finds it."""
    kw, _, x0 = kothare_ex1()
    prob = FormProblem(**kw)
    calls = fake(prob, lambda lam: 1.0 + (logit(lam) - logit(0.97)) ** 2, slopes=slopes)
    prob._lam_prev = 0.2
    sol = prob.solve(x0)
    rec = prob.last_lambda_search
    assert rec.how == "grid" and "no interior minimum" in rec.fallback
    assert set(LAMBDA_GRID) <= set(calls)
    # the previous lam, the first step or both sides, three expansions; then the full search
    assert len(calls) == rec.solves == (5 if slopes else 6) + FULL
    assert abs(sol.lam - 0.97) < 0.01


@pytest.mark.parametrize("slopes", [False, True])
def test_a_failed_solve_at_the_previous_lam_falls_back_to_the_full_grid(slopes):
    kw, _, x0 = kothare_ex1()
    prob = FormProblem(**kw)
    calls = fake(prob, lambda lam: 1.0 + (lam - 0.3) ** 2, infeasible=lambda lam: lam > 0.8, slopes=slopes)
    prob._lam_prev = 0.9
    sol = prob.solve(x0)
    assert prob.last_lambda_search.fallback == "no certified answer at the previous lam 0.9"
    assert calls[0] == pytest.approx(0.9) and set(LAMBDA_GRID) <= set(calls)
    assert sol.ok and abs(sol.lam - 0.3) < 0.01


@pytest.mark.parametrize("lam", [0.9, 0.95, 0.985])
def test_the_slope_from_the_dual_is_the_derivative_of_gamma_in_lam(lam):
    """The envelope theorem's ``d gamma / d lam`` at an optimum (the ipm's dual blocks against the
    blocks' derivative in lam) against central differences of gamma, lam given."""
    kw, _, x0 = kothare_ex1()
    e_mat, w_max = kw["disturbance"]

    def solve(value: float) -> tuple[float, float | None]:
        given = {**kw, "disturbance": (e_mat, w_max, value)}
        prob = FormProblem(**given, solver_options={"tol_gap_rel": 1e-12})
        sol = prob.solve(x0)
        assert sol.ok
        return sol.gamma, prob._last_slope

    h = 1e-4
    gamma, slope = solve(lam)
    central = (solve(lam + h)[0] - solve(lam - h)[0]) / (2.0 * h)
    assert slope is not None and abs(central) > 1e-3 * gamma  # a slope that could be told from zero
    assert abs(slope - central) <= 1e-3 * abs(central), (slope, central)


def test_a_failure_after_a_certified_state_is_a_status_from_the_full_search():
    """The double integrator beyond its output bounds: no invariant ellipsoid holds the state."""
    kw, _, x0 = double_integrator()
    prob = FormProblem(**kw)
    calls = spy(prob)
    assert prob.solve(x0).ok
    before = len(calls)
    sol = prob.solve(3.0 * x0)  # beyond the output bounds |x_i| <= 10
    assert sol.status == "infeasible" and math.isnan(sol.gamma)
    assert "at each of the" in sol.solver_status
    assert prob.last_lambda_search.how == "grid"
    assert prob.last_lambda_search.fallback.startswith("no certified answer at the previous lam")
    assert len(calls) - before == 1 + len(LAMBDA_GRID)  # the previous lam, then the grid
    assert prob._lam_prev is None  # the next state starts from the grid again


def test_reset_forgets_the_previous_lam():
    kw, _, x0 = kothare_ex1()
    prob = FormProblem(**kw)
    assert prob.solve(x0).ok and prob._lam_prev is not None
    prob.reset()
    prob.solve(0.9 * x0)
    assert prob.last_lambda_search.how == "grid" and prob.last_lambda_search.fallback is None


@pytest.mark.parametrize("value", ["fast", 1, None])
def test_an_unknown_search_is_refused_naming_the_setting(value):
    kw, _, _ = kothare_ex1()
    with pytest.raises(InvalidArgumentError, match=r"solver_options\['lambda_search'\].*'warm' or 'grid'"):
        FormProblem(**kw, solver_options={"lambda_search": value})


def test_retuning_writes_the_symbolic_programs_numbers_at_the_new_lam():
    """``_retune`` forms the lam blocks from their coefficients at lam = 0 and their slope, with
    no symbolic program: constants and coefficients bit for bit those of the symbolic program
    written at that lam (three lams, one of them not a short binary fraction)."""
    kw, a, x0 = kothare_ex1()
    prob = FormProblem(**kw)
    for x in closed_loop_states(kw, a, x0, 2):  # the warm search's kept solver from the second on
        prob.solve(x)
    solver = prob._solvers[("ipm", "warm", False)]
    lam_blocks = prob._lam_coefficients(prob._form_data(x0, prob.data.u_max, prob.data.y_max, 0.1, 0.5))
    assert lam_blocks  # the invariance blocks
    for lam in (0.3, 0.7071067811865476, 0.93):
        fd = prob._form_data(x0 / np.linalg.norm(x0), prob.data.u_max, prob.data.y_max, 0.1, lam)
        prob._retune(solver, fd)
        assert solver.form_lam == lam
        symbolic = prob._symbolic(fd)
        for name in lam_blocks:
            j = solver.form_blocks[name]
            coef = symbolic.solver_coef(name)
            assert np.array_equal(solver._coef[j], -coef[1:]), (lam, name)
            assert np.array_equal(solver._const[j], coef[0]), (lam, name)
