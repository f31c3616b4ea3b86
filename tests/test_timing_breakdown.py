"""The per-iteration breakdown of ``python -m benchmarks.timing.breakdown`` adds up.

No wall-clock assertion: the times are whatever the machine gives; what is checked is that the
parts are the solver's parts (their sum within the solver's time, every kernel called once per
iteration), that the wrappers are removed afterwards, and the flop count of the floor.
"""

from __future__ import annotations

import pytest

import lmi.ipm.solver as solver_module
from benchmarks.timing import breakdown as bd


@pytest.fixture(scope="module")
def result():
    return bd.breakdown(2, n_states=3)


def test_the_parts_are_one_call_per_iteration_and_sum_within_the_solver(result):
    iterations = result["iterations_per_solve"]
    assert iterations >= 1
    assert result["parts"]["rows_iteration"]["calls_per_solve"] == pytest.approx(iterations)
    assert result["parts"]["residuals"]["calls_per_solve"] == pytest.approx(iterations + 1)
    kernels = sum(part["per_solve_us"] for part in result["parts"].values())
    assert kernels <= result["solver_us"] <= result["kothare_solve_us"]
    assert result["python_around_kernels_us"] == pytest.approx(result["solver_us"] - kernels)


def test_the_wrappers_are_removed(result):
    assert solver_module._kernels.rows_iteration.__name__ == "rows_iteration"
    assert solver_module._kernels.residuals.__name__ == "residuals"
    assert solver_module.BlockLMISolver.solve.__name__ == "solve"


def test_every_replayed_iteration_has_a_scaling_a_factor_and_a_step(result):
    """Each iterate of the first solves is replayed part by part: the scaling and the step
    always, ``H`` and its Cholesky factor in the Cholesky phase, QR in the QR phase (both on
    the iterate where Cholesky fails), so the two phases' shares add up to at least one."""
    parts = result["iteration_parts"]
    assert result["replayed_iterations"] >= 1
    assert parts["NT scaling and P"]["share_of_iterations"] == 1.0
    assert parts["Newton step (2 solves, step lengths, update)"]["share_of_iterations"] == 1.0
    cholesky = parts.get("Cholesky of H (dpotrf)", {"share_of_iterations": 0.0})["share_of_iterations"]
    qr = parts.get("QR of P (dgeqrf), QR phase", {"share_of_iterations": 0.0})["share_of_iterations"]
    assert cholesky + qr >= 1.0
    assert all(part["per_iteration_us"] > 0.0 for part in parts.values())


def test_the_flop_count_of_the_floor():
    floor = bd.floor_per_iteration(4, 10, [2, 3], seed=1)
    n, m = 4, 10
    assert floor["flops"] == n * n * m + n**3 / 3 + 2 * (4 * n * m + 2 * n * n) + 13 * (8 + 27)
    assert floor["arithmetic"] == pytest.approx(floor["flops"] / floor["flops_per_s"])


def test_the_report_names_every_part(result):
    text = bd.format_breakdown([result], {"empty_cache_s": 12.0, "filled_cache_s": 0.5})
    for name in ("rows_iteration", "Python around the kernels", "Inside the iteration", "NT scaling and P",
                 "Floor, arithmetic", "12.0 s with an empty"):
        assert name in text


def test_rmpc_timing_runs_it_as_the_breakdown_problem(tmp_path):
    from benchmarks.cli import main

    args = ["--problems", "Breakdown", "--vertices", "2", "--steps", "2", "--no-progress"]
    assert main(["timing", "--out", str(tmp_path), *args]) == 0
    text = (tmp_path / "timing.md").read_text(encoding="utf-8")
    assert "Where an interior-point solve spends its time" in text and "Floor, arithmetic" in text
    import json

    report = json.loads((tmp_path / "timing.json").read_text(encoding="utf-8"))
    assert report["breakdown"][0]["vertices"] == 2 and report["breakdown"][0]["iterations_per_solve"] >= 1
