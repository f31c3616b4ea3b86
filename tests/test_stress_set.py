"""The seeded stress set of Kothare problems (:mod:`dev.stress`): what each problem claims
about itself holds, independently of any solver.

* feasible problems: the witness ``(gamma, Q, Y)`` satisfies every LMI (:func:`lmi.certify`
  at the problem's state, all margins >= 0) and ``x`` is strictly inside its ellipsoid;
* infeasible problems: vertex 0 has the real eigenvalue ``lam > 1`` with the left eigenvector
  ``w`` of the construction, and ``|w'x| (lam - 1)`` exceeds the largest ``|w'B_0 u|`` an
  admissible input reaches, so ``|w'x(k)|`` grows along every admissible input sequence of
  the constant plant ``(A_0, B_0)`` (checked here by the bound itself and along 30 steps of a
  worst-case input);
* the set is deterministic in its seed, and bad arguments raise naming the argument.
"""

from __future__ import annotations

import numpy as np
import pytest

from dev.stress import make_problem, stress_set
from lmi import build_kothare_data, certify
from toolkit_common.errors import InvalidArgumentError

SMALL = [(n, v, seed) for n in (4, 8) for v in (2, 4) for seed in (0, 1)]


@pytest.mark.parametrize(("n", "n_vertices", "seed"), SMALL)
def test_feasible_witness_satisfies_every_lmi(n, n_vertices, seed):
    prob = make_problem(n, 2, n_vertices, "feasible", seed, "peak" if seed % 2 == 0 else "ellipsoid")
    gamma, q, y = prob.witness
    data = build_kothare_data(**prob.kothare_kwargs())
    cert = certify(data, prob.x, gamma, q, y)
    assert min(cert.margins.values()) >= 0.0, cert.margins
    assert prob.x @ np.linalg.solve(q, prob.x) <= 0.9 + 1e-12


@pytest.mark.parametrize(("n", "n_vertices", "seed"), SMALL)
def test_infeasible_problem_escapes_every_admissible_input(n, n_vertices, seed):
    constraint = "peak" if seed % 2 == 0 else "ellipsoid"
    prob = make_problem(n, 2, n_vertices, "infeasible", seed, constraint)
    a0, b0 = prob.A[0], prob.B[0]
    eig, left = np.linalg.eig(a0.T)
    k = int(np.argmax(eig.real))
    lam, w = float(eig[k].real), left[:, k].real
    assert abs(eig[k].imag) == 0.0 and lam > 1.0
    wb = w @ b0
    u_max = np.broadcast_to(np.asarray(prob.u_max, dtype=float), (b0.shape[1],))
    if constraint == "peak":
        reach = float(np.sum(np.abs(wb) * u_max))
    else:
        reach = float(np.linalg.norm(wb)) * u_max[0]
    assert abs(w @ prob.x) * (lam - 1.0) > 1.5 * reach
    # the best an admissible input can do: push w'x towards zero as hard as it may
    x = prob.x.copy()
    for _ in range(30):
        along = np.sign(w @ x)
        u = -along * (np.sign(wb) * u_max if constraint == "peak" else wb / np.linalg.norm(wb) * u_max[0])
        x_next = a0 @ x + b0 @ u
        assert abs(w @ x_next) > abs(w @ x)
        x = x_next


def test_stress_set_is_deterministic_and_covers_its_grid():
    first = list(stress_set(sizes=(4,), vertex_counts=(2,), seeds=(0, 1)))
    again = list(stress_set(sizes=(4,), vertex_counts=(2,), seeds=(0, 1)))
    assert [p.label for p in first] == ["n4-v2-feasible-s0", "n4-v2-feasible-s1", "n4-v2-infeasible-s0",
                                        "n4-v2-infeasible-s1"]
    for p, q in zip(first, again, strict=True):
        assert np.array_equal(p.A, q.A) and np.array_equal(p.x, q.x)


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"n": 1}, "n"), ({"m": 0}, "m"), ({"n_vertices": 0}, "n_vertices"), ({"kind": "maybe"}, "kind"),
    ({"input_constraint": "box"}, "input_constraint"), ({"distance": 1.0}, "distance"),
    ({"distance": np.inf}, "distance"), ({"distance": True}, "distance"),
])
def test_bad_arguments_name_the_argument(kwargs, name):
    args = {"n": 4, "m": 2, "n_vertices": 2, "kind": "feasible", "seed": 0, **kwargs}
    with pytest.raises(InvalidArgumentError, match=name):
        make_problem(**args)


def test_stress_benchmark_answers_never_contradict_the_construction():
    """The benchmark on one feasible and one infeasible 4-state problem (~1 s): no path says
    "optimal" on the infeasible one or "infeasible" on the feasible one, the IPM is optimal
    on the feasible one and agrees with cvxpy + Clarabel at 1e-9 within 1e-6."""
    from dev.stress import format_stress, run_stress

    records = run_stress([make_problem(4, 2, 2, "feasible", 0), make_problem(4, 2, 2, "infeasible", 0)])
    for rec in records:
        for path in ("ipm", "ipm-alone", "cvxpy:CLARABEL"):
            assert not rec[path]["contradiction"], rec
    assert records[0]["ipm"]["status"] == "optimal"
    assert records[0]["rel_diff_gamma_ipm"] < 1e-6
    assert records[1]["ipm"]["status"] != "optimal"
    assert "n4-v2-infeasible-s0" in format_stress(records)


def test_distance_moves_only_the_state_and_scales_it():
    """``distance`` changes neither the data nor the state's direction, only its length (in
    proportion: the state is placed on ``|w'x| (lam - 1) = distance * max |w' B_0 u|``)."""
    base = make_problem(4, 2, 2, "infeasible", 1, "ellipsoid")
    far = make_problem(4, 2, 2, "infeasible", 1, "ellipsoid", distance=2e3)
    assert np.array_equal(base.A, far.A) and np.array_equal(base.B, far.B) and base.u_max == far.u_max
    assert np.allclose(far.x, 1e3 * base.x, rtol=1e-14, atol=0.0)
